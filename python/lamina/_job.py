"""Running one lamina command on in-memory data: a private folder, the inputs written into it
exactly (shortest round-trip numbers), the command run in-process, the outputs read back.

Paths in what a command writes (a report's "output", a title naming its input) are given
relative to that folder, so a report names its files as the command line would when run in a
folder holding them (``network.json``, ``axes.json``, ...)."""

from __future__ import annotations

import json
import os
import shutil
import tempfile
import warnings
from typing import Any, Callable, Optional

import numpy as np

from . import _lamina

Progress = Optional[Callable[[str, str, int, Optional[int]], Any]]


class LaminaWarning(UserWarning):
    """A note of a lamina command: a default it took, something it read but did not use."""


def flag_value(value: Any) -> str:
    """A flag's value as the command line takes it: floats in their shortest exact form."""
    if isinstance(value, bool):
        raise TypeError("a boolean is a switch, not a value")
    if isinstance(value, (float, np.floating)):
        return repr(float(value))
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, os.PathLike):
        return os.fspath(value)
    if isinstance(value, str):
        return value
    raise TypeError(f"{value!r} is not a number, a string or a path")


def flags(options: dict) -> list:
    """Keyword options as flags: ``fix_normal=[...]`` repeats ``--fix-normal``, ``True`` is a
    switch, ``None`` and ``False`` leave the flag out."""
    out = []
    for name, value in options.items():
        flag = "--" + name.replace("_", "-")
        if value is None or value is False:
            continue
        if value is True:
            out.append(flag)
        elif isinstance(value, (list, tuple)):
            out.extend(f"{flag}={flag_value(v)}" for v in value)
        else:
            out.append(f"{flag}={flag_value(value)}")
    return out


def as_points(a: Any, what: str, dim: int = 3) -> np.ndarray:
    """An N×dim float64 array, or LaminaError naming the argument."""
    try:
        arr = np.asarray(a, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise _lamina.LaminaError(f"{what}: not an array of numbers ({e})") from None
    if arr.ndim != 2 or arr.shape[1] != dim:
        raise _lamina.LaminaError(f"{what}: expected an N×{dim} array, got shape {arr.shape}")
    return np.ascontiguousarray(arr, dtype="<f8")


def as_indices(a: Any, what: str, width: int, count: int) -> np.ndarray:
    """An M×width array of indices below `count`, or LaminaError naming the argument."""
    arr = np.asarray(a)
    if arr.size == 0:
        arr = arr.reshape(0, width)
    if arr.ndim != 2 or arr.shape[1] != width:
        raise _lamina.LaminaError(f"{what}: expected an M×{width} array, got shape {arr.shape}")
    if not np.issubdtype(arr.dtype, np.integer):
        raise _lamina.LaminaError(f"{what}: expected integer indices, got {arr.dtype}")
    if arr.size and (arr.min() < 0 or arr.max() >= count):
        bad = int(arr.min()) if arr.min() < 0 else int(arr.max())
        raise _lamina.LaminaError(f"{what}: index {bad} is not one of the {count} points")
    return np.ascontiguousarray(arr, dtype="<u4")


def as_values(a: Any, what: str, count: int, default: float) -> np.ndarray:
    """`count` float64 values: a scalar, an array, or `default` for None."""
    if a is None:
        a = default
    arr = np.asarray(a, dtype=np.float64)
    if arr.ndim == 0:
        arr = np.full(count, float(arr))
    if arr.shape != (count,):
        raise _lamina.LaminaError(f"{what}: expected {count} values, got shape {arr.shape}")
    return np.ascontiguousarray(arr, dtype="<f8")


def check_progress(progress: Progress) -> None:
    if progress is not None and not callable(progress):
        raise TypeError("progress must be callable as progress(stage, message, done, total)")


def warn(notes: list, stacklevel: int = 3) -> list:
    """A command's notes as LaminaWarnings (pointing at the caller of the package's function
    that calls this with the default stacklevel)."""
    for n in notes:
        warnings.warn(n, LaminaWarning, stacklevel=stacklevel)
    return list(notes)


class Job:
    """One command's private folder; removed when the job ends."""

    def __init__(self) -> None:
        self.dir = tempfile.mkdtemp(prefix="lamina-")
        self.notes: list = []

    def __enter__(self) -> "Job":
        return self

    def __exit__(self, *exc) -> None:
        shutil.rmtree(self.dir, ignore_errors=True)

    def path(self, name: str) -> str:
        return os.path.join(self.dir, name)

    def relative(self, text: str) -> str:
        """`text` with this folder's paths made relative (also as JSON escapes them)."""
        prefix = self.dir + os.sep
        text = text.replace(json.dumps(prefix)[1:-1], "")
        return text.replace(prefix, "")

    def run(self, argv: list, progress: Progress = None) -> bool:
        """Runs ``lamina ARGV…``; its notes become LaminaWarnings (and ``self.notes``). False
        when the command's result missed its tolerance (exit 1 on the command line)."""
        check_progress(progress)
        try:
            within, _out, notes = _lamina.run([str(a) for a in argv], progress)
        except _lamina.LaminaError as e:
            raise _lamina.LaminaError(self.relative(str(e))) from None
        self.note(notes)
        return within

    def note(self, notes: list) -> None:
        """A command's notes, as LaminaWarnings and in ``self.notes``."""
        self.notes.extend(warn([self.relative(n) for n in notes], stacklevel=4))

    def text(self, name: str) -> str:
        with open(self.path(name), encoding="utf-8") as f:
            return self.relative(f.read())

    def json(self, name: str) -> Any:
        return json.loads(self.text(name))

    def bytes(self, name: str) -> bytes:
        with open(self.path(name), "rb") as f:
            return f.read()

    def files(self, folder: str) -> dict:
        """Every file under `folder`, by its path relative to it (``/`` separated)."""
        root = self.path(folder)
        out = {}
        for base, dirs, names in os.walk(root):
            dirs.sort()
            for n in sorted(names):
                p = os.path.join(base, n)
                out[os.path.relpath(p, root).replace(os.sep, "/")] = open(p, "rb").read()
        return out

    # Networks and meshes in and out.

    def write_network(self, name: str, net: dict) -> str:
        _lamina.write_network(self.path(name), network_arrays(net))
        return self.path(name)

    def read_network(self, name: str) -> dict:
        d = _lamina.read_network(self.path(name))
        return network_of(d, self.relative(d["meta"]))

    def write_mesh(self, name: str, vertices: Any, faces: Any, colors: Any = None) -> str:
        v = as_points(vertices, "vertices")
        f = as_indices(faces, "faces", 3, len(v))
        c = b""
        if colors is not None:
            rgb = as_points(colors, "colors")
            if len(rgb) != len(v):
                raise _lamina.LaminaError(f"colors: expected {len(v)} rows, got {len(rgb)}")
            c = rgb.tobytes()
        _lamina.write_mesh(self.path(name), v.tobytes(), f.tobytes(), c)
        return self.path(name)

    def read_mesh(self, name: str) -> dict:
        v, f, c = _lamina.read_mesh(self.path(name))
        return mesh_of(v, f, c)


def network_arrays(net: dict) -> tuple:
    """A network dict's arrays as the binding takes them: positions, edges, node and edge radii,
    normals (empty for none), each little-endian bytes, checked for shape and index range; and
    its meta as JSON text (empty for none)."""
    p = as_points(net["positions"], "positions")
    e = as_indices(net["edges"], "edges", 2, len(p))
    nr = as_values(net.get("node_radius"), "node_radius", len(p), 0.0)
    er = as_values(net.get("edge_radius"), "edge_radius", len(e), 0.0)
    normals = net.get("normals")
    n = b"" if normals is None else as_points(normals, "normals").tobytes()
    if normals is not None and len(n) != len(p) * 24:
        raise _lamina.LaminaError(f"normals: expected {len(p)} rows, got {len(n) // 24}")
    meta = net.get("meta")
    return p.tobytes(), e.tobytes(), nr.tobytes(), er.tobytes(), n, json.dumps(meta) if meta else ""


def arrays_positions(arrays: tuple) -> np.ndarray:
    """The N×3 positions of `network_arrays`' result."""
    return np.frombuffer(arrays[0], "<f8").reshape(-1, 3)


def network_of(d: dict, meta: str) -> dict:
    """A network dict (numpy arrays) from the binding's bytes."""
    n = d["normals"]
    return {
        "positions": np.frombuffer(d["positions"], "<f8").reshape(-1, 3).copy(),
        "edges": np.frombuffer(d["edges"], "<u4").reshape(-1, 2).astype(np.int64),
        "node_radius": np.frombuffer(d["node_radius"], "<f8").copy(),
        "edge_radius": np.frombuffer(d["edge_radius"], "<f8").copy(),
        "normals": None if n is None else np.frombuffer(n, "<f8").reshape(-1, 3).copy(),
        "meta": json.loads(meta),
    }


def mesh_of(v: bytes, f: bytes, c: Optional[bytes]) -> dict:
    """A mesh dict (numpy arrays) from the binding's bytes."""
    return {
        "vertices": np.frombuffer(v, "<f8").reshape(-1, 3).copy(),
        "faces": np.frombuffer(f, "<u4").reshape(-1, 3).astype(np.int64),
        "colors": None if c is None else np.frombuffer(c, "<f8").reshape(-1, 3).copy(),
    }
