"""Networks, meshes and options between Python and the binding: numpy arrays checked for shape
and type (naming the argument), units to millimetres and back, keyword arguments checked against
the stage's option names, warnings at the caller's line."""

from __future__ import annotations

import difflib
import os
import sys
import warnings
from types import FrameType
from typing import Any, Callable, Optional

import numpy as np

from . import _lamina
from ._errors import LaminaError, LaminaWarning

Progress = Optional[Callable[[str, str, int, Optional[int]], Any]]

#: Millimetres in one of each unit ``units=`` takes.
UNITS = {"mm": 1.0, "cm": 10.0, "m": 1000.0, "in": 25.4, "ft": 304.8}

_PACKAGE = os.path.dirname(os.path.abspath(__file__))


def stacklevel() -> int:
    """The stack level of the first frame outside this package: warnings point at the caller's
    line, however deep in the package they are raised."""
    frame: Optional[FrameType] = sys._getframe(1)
    level = 1
    while frame is not None and os.path.abspath(frame.f_code.co_filename).startswith(_PACKAGE):
        frame = frame.f_back
        level += 1
    return level


def warn(notes: list) -> list:
    """A stage's notes as LaminaWarnings at the caller's line."""
    for n in notes:
        warnings.warn(n, LaminaWarning, stacklevel=stacklevel())
    return list(notes)


def scale_of(units: Any) -> float:
    """Millimetres per unit, or LaminaError naming ``units=``."""
    if not isinstance(units, str) or units.lower() not in UNITS:
        raise LaminaError(f"units= {units!r}: give one of {', '.join(UNITS)}")
    return UNITS[units.lower()]


def check_options(function: str, options: dict, also: tuple = ()) -> dict:
    """The keyword options without those left at None, or TypeError naming an unknown one and
    the closest valid name."""
    valid = list(_lamina.option_names(function)) + list(also)
    for name in options:
        if name not in valid:
            close = difflib.get_close_matches(name, valid, n=1)
            hint = f"; did you mean {close[0]!r}?" if close else ""
            raise TypeError(f"{function}() got an unexpected keyword argument {name!r}{hint}")
    return {k: v for k, v in options.items() if v is not None}


def scaled(options: dict, lengths: tuple, scale: float) -> dict:
    """`options` with the lengths named in `lengths` taken to millimetres (numbers, or
    sequences of numbers)."""
    if scale == 1.0:
        return options
    out = dict(options)
    for k in lengths:
        v = out.get(k)
        if v is None or isinstance(v, (bool, str)):
            continue
        if isinstance(v, (int, float, np.integer, np.floating)):
            out[k] = float(v) * scale
        else:
            out[k] = (np.asarray(v, dtype=np.float64) * scale).tolist()
    return out


def points(a: Any, what: str, dim: int = 3) -> np.ndarray:
    """An N×dim float64 array, or LaminaError naming the argument."""
    try:
        arr = np.asarray(a, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise LaminaError(f"{what}: not an array of numbers ({e})") from None
    if arr.ndim != 2 or arr.shape[1] != dim:
        raise LaminaError(f"{what}: expected an N×{dim} array, got shape {arr.shape}")
    return np.ascontiguousarray(arr, dtype="<f8")


def indices(a: Any, what: str, width: int) -> np.ndarray:
    """An M×width array of indices ≥ 0 (uint32), or LaminaError naming the argument and the
    first bad row. Whether they are in range is the stage's check."""
    arr = np.asarray(a)
    if arr.size == 0:
        arr = arr.reshape(0, width)
    if arr.ndim != 2 or arr.shape[1] != width:
        raise LaminaError(f"{what}: expected an M×{width} array, got shape {arr.shape}")
    if not np.issubdtype(arr.dtype, np.integer):
        raise LaminaError(f"{what}: expected integer indices, got {arr.dtype}")
    bad = np.flatnonzero((arr < 0).any(axis=1) | (arr >= 2**32).any(axis=1))
    if bad.size:
        k = int(bad[0])
        raise LaminaError(f"{what}[{k}]: index {arr[k].tolist()} is not a node number")
    return np.ascontiguousarray(arr, dtype="<u4")


def values(a: Any, what: str, count: int, default: float) -> np.ndarray:
    """`count` float64 values: a scalar, an array, or `default` for None."""
    if a is None:
        a = default
    try:
        arr = np.asarray(a, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise LaminaError(f"{what}: not numbers ({e})") from None
    if arr.ndim == 0:
        arr = np.full(count, float(arr))
    if arr.shape != (count,):
        raise LaminaError(f"{what}: expected {count} values, got shape {arr.shape}")
    return np.ascontiguousarray(arr, dtype="<f8")


def network(positions: Any, edges: Any = None, normals: Any = None, node_radius: Any = None,
            edge_radius: Any = None) -> dict:
    """A network dict from arrays, or the network dict given as `positions` (arrays given
    beside it replace its own)."""
    if isinstance(positions, dict):
        net = dict(positions)
        for k, v in (("edges", edges), ("normals", normals), ("node_radius", node_radius),
                     ("edge_radius", edge_radius)):
            if v is not None:
                net[k] = v
        return net
    if edges is None:
        raise LaminaError("edges: give the network's edges (an E×2 array of node indices)")
    return {"positions": positions, "edges": edges, "normals": normals,
            "node_radius": node_radius, "edge_radius": edge_radius}


def network_bytes(net: dict, scale: float) -> tuple:
    """A network dict as the binding takes it (lengths taken to mm by `scale`)."""
    for key in ("positions", "edges"):
        if key not in net:
            raise LaminaError(f"{key}: the network dict has no {key!r}")
    p = points(net["positions"], "positions") * scale
    e = indices(net["edges"], "edges", 2)
    nr = values(net.get("node_radius"), "node_radius", len(p), 0.0) * scale
    er = values(net.get("edge_radius"), "edge_radius", len(e), 0.0) * scale
    normals = net.get("normals")
    n = b"" if normals is None else points(normals, "normals").tobytes()
    if normals is not None and len(n) != len(p) * 24:
        raise LaminaError(f"normals: {len(n) // 24} rows for {len(p)} nodes (one per node)")
    return (p.tobytes(), e.tobytes(), nr.tobytes(), er.tobytes(), n, net.get("meta"))


def network_out(d: dict, scale: float) -> dict:
    """A network from the binding, its lengths in the caller's unit."""
    if scale != 1.0:
        for k in ("positions", "node_radius", "edge_radius"):
            d[k] = d[k] / scale
    return d


def mesh_parts(mesh: Any, faces: Any = None, colors: Any = None, what: str = "mesh") -> tuple:
    """(vertices, faces, colors) from a mesh dict, a (vertices, faces[, colors]) pair, or
    vertices with `faces` beside them."""
    if isinstance(mesh, dict):
        return mesh["vertices"], mesh["faces"], mesh.get("colors") if colors is None else colors
    if faces is not None:
        return mesh, faces, colors
    if isinstance(mesh, (tuple, list)) and len(mesh) in (2, 3):
        return mesh[0], mesh[1], mesh[2] if len(mesh) == 3 else colors
    raise LaminaError(f"{what}: give a mesh as a dict or a (vertices, faces) pair")


def mesh_bytes(mesh: Any, scale: float, what: str = "mesh", faces: Any = None,
               colors: Any = None) -> tuple:
    """A mesh as the binding takes it: vertices (taken to mm), faces, colours."""
    v, f, c = mesh_parts(mesh, faces, colors, what)
    v = points(v, f"{what}: vertices") * scale
    f = indices(f, f"{what}: faces", 3)
    cb = b""
    if c is not None:
        rgb = points(c, f"{what}: colors")
        if len(rgb) != len(v):
            raise LaminaError(f"{what}: colors: {len(rgb)} rows for {len(v)} vertices")
        cb = rgb.tobytes()
    return v.tobytes(), f.tobytes(), cb


def mesh_out(d: dict, scale: float) -> dict:
    """A mesh from the binding, its vertices in the caller's unit."""
    if scale != 1.0:
        d["vertices"] = d["vertices"] / scale
    return d


def size_mm(p: np.ndarray) -> float:
    """A model's size: its bounding box's diagonal, mm."""
    if len(p) == 0:
        return 0.0
    return float(np.linalg.norm(p.max(axis=0) - p.min(axis=0)))


#: The usual ratio of each default length to a model's size (its bounding-box diagonal): a
#: panel about a twentieth of the model high, a planarity tolerance of 5 µm a metre, a mesher
#: cell of a two-thousandth of a leaf.
TYPICAL = {"height": 0.05, "tolerance": 5e-6, "cell": 5e-4}


def check_scale(function: str, size: float, defaults: dict, units: str) -> None:
    """Warns when a default length and the model's size differ by more than 100× from their
    usual ratio: a model in metres read as millimetres, say."""
    if not (0 < size < float("inf")):
        return  # the stage refuses such a model, in its own words
    for name, value in defaults.items():
        ratio = value / (size * TYPICAL[name])
        if ratio > 100 or ratio < 0.01:
            warnings.warn(
                f"{function}: the default {name}={value:g} mm against a model {size:g} mm across "
                f"is {max(ratio, 1 / ratio):.0f}× off the usual scale: is the model in another "
                f"unit than {units}? give units= (mm, cm, m, in, ft) or {name}=",
                LaminaWarning, stacklevel=stacklevel())
