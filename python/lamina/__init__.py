"""lamina from Python: grow branching structures and turn networks into buildable, checked parts.

Each function mirrors a command of the ``lamina`` binary on in-memory data: networks and meshes
as numpy arrays in and out, reports as the dicts the command writes as JSON (their exact text
too, under ``report_json`` and the like). Keyword options beyond the named ones are the
command's flags with ``_`` for ``-`` (``fix_normal=["z<1:0,0,1"]`` is ``--fix-normal
'z<1:0,0,1'``; ``True`` is a switch). Errors raise :class:`LaminaError` with the message the
binary prints; notes (defaults taken, things read but not used) are :class:`LaminaWarning`.

Long commands release the GIL and call ``progress(stage, message, done, total)`` about ten
times a second while they run (``total`` is None for a spinner).

A network is a dict: ``positions`` (N×3 float64, mm), ``edges`` (E×2 int), ``node_radius``
(N), ``edge_radius`` (E), ``normals`` (N×3 or None) and ``meta``. A mesh is a dict:
``vertices`` (V×3 float64), ``faces`` (F×3 int), ``colors`` (V×3 in 0..1 or None).
"""

from __future__ import annotations

import json
import os
import shutil
from typing import Any, Optional, Union

import numpy as np

from . import _lamina
from ._job import (Job, LaminaWarning, Progress, arrays_positions, as_indices, as_points,
                   check_progress, flag_value, flags, mesh_of, network_arrays, network_of, warn)
from ._lamina import LaminaError, __version__

__all__ = [
    "LaminaError",
    "LaminaWarning",
    "__version__",
    "audit",
    "cells",
    "command",
    "lsystem",
    "nest",
    "planarize",
    "plates",
    "read_mesh",
    "read_network",
    "size",
    "slice",
    "solid",
    "veins",
    "venation",
    "venation_on_surface",
    "write_mesh",
    "write_network",
]

PathLike = Union[str, "os.PathLike[str]"]


def command(*argv: Any, progress: Progress = None) -> str:
    """Runs ``lamina ARGV…`` in-process on files and returns what it printed. Raises
    LaminaError where the binary exits 2; a result beyond its tolerance (exit 1) is not an
    error here: pass ``--json`` and read the figures."""
    check_progress(progress)
    _within, out, notes = _lamina.run([flag_value(a) for a in argv], progress)
    warn(notes)
    return out


def read_network(path: PathLike) -> dict:
    """A network file (.json .obj .dxf) as a network dict (numpy arrays), read as the commands
    read it with their default flags."""
    d = _lamina.read_network(os.fspath(path))
    return network_of(d, d["meta"])


def write_network(path: PathLike, network: dict) -> None:
    """Writes a network dict as lamina JSON, OBJ, DXF or SVG (by extension)."""
    p = os.fspath(path)
    with Job() as job:
        job.write_network("network.json", network)
        if p.lower().endswith(".json"):
            shutil.copyfile(job.path("network.json"), p)
        else:
            command("convert", job.path("network.json"), p)


def read_mesh(path: PathLike) -> dict:
    """A triangle mesh file (.obj .stl) as a mesh dict (numpy arrays)."""
    return mesh_of(*_lamina.read_mesh(os.fspath(path)))


def write_mesh(path: PathLike, mesh: Any) -> None:
    """Writes a mesh (a dict or a (vertices, faces) pair) as OBJ or binary STL (by extension)."""
    p = os.fspath(path)
    with Job() as job:
        job.write_mesh("mesh.obj", *_mesh(mesh, "mesh"))
        command("convert", job.path("mesh.obj"), p)


# Arguments that are networks, meshes or documents.


def _network(positions: Any, edges: Any, normals: Any = None, node_radius: Any = None,
             edge_radius: Any = None) -> dict:
    """A network from arrays, or the network dict given as `positions`."""
    if isinstance(positions, dict):
        net = dict(positions)
        for k, v in (("normals", normals), ("node_radius", node_radius),
                     ("edge_radius", edge_radius)):
            if v is not None:
                net[k] = v
        return net
    if edges is None:
        raise LaminaError("edges: give the network's edges (an E×2 array of node indices)")
    return {"positions": positions, "edges": edges, "normals": normals,
            "node_radius": node_radius, "edge_radius": edge_radius}


def _mesh(mesh: Any, what: str) -> tuple:
    """(vertices, faces, colors) from a mesh dict or a (vertices, faces[, colors]) tuple."""
    if isinstance(mesh, dict):
        return mesh["vertices"], mesh["faces"], mesh.get("colors")
    if isinstance(mesh, (tuple, list)) and len(mesh) in (2, 3):
        return (mesh[0], mesh[1], mesh[2] if len(mesh) == 3 else None)
    raise LaminaError(f"{what}: give a mesh as a dict or a (vertices, faces) pair")


def _document(job: Job, value: Any, key: str, fmt: str, name: str, what: str) -> str:
    """The path of a lamina JSON document: a file path, a result holding its exact text under
    `key`, or the document itself (a dict whose format is `fmt`)."""
    if isinstance(value, (str, os.PathLike)):
        return os.fspath(value)
    if isinstance(value, dict) and key in value:
        text = value[key]
    elif isinstance(value, dict) and value.get("format") == fmt:
        text = json.dumps(value)
    else:
        raise LaminaError(f"{what}: give a path, the result of the command that makes it, or a "
                          f"{fmt} document")
    with open(job.path(name), "w", encoding="utf-8") as f:
        f.write(text)
    return name


def _report(job: Job, name: str) -> tuple:
    text = job.text(name)
    return json.loads(text), text


# Growing.


def venation(*, shape: str = "ovate", mode: str = "closed", outline: Any = None,
             root: Any = None, seed: int = 1, progress: Progress = None, **options: Any) -> dict:
    """Leaf venation in a built-in blade (``shape``) or an ``outline`` (an N×2 or N×3 closed
    polygon, or a file path) by space colonization (Runions et al. 2005), ``mode`` open or
    closed. ``root``: an (x, y) pair or a list of them. Returns ``network``, ``report`` (the
    command's ``--report``), ``report_json``."""
    with Job() as job:
        argv = ["venation", "-o", job.path("venation.json"), "--report", job.path("report.json"),
                "--mode", mode, "--seed", str(seed)]
        if outline is None:
            argv += ["--shape", shape]
        elif isinstance(outline, (str, os.PathLike)):
            argv += ["--outline", os.fspath(outline)]
        else:
            pts = np.asarray(outline, dtype=np.float64)
            if pts.ndim == 2 and pts.shape[1] == 2:
                pts = np.column_stack([pts, np.zeros(len(pts))])
            pts = as_points(pts, "outline")
            n = len(pts)
            ring = np.column_stack([np.arange(n), (np.arange(n) + 1) % n])
            job.write_network("outline.json", {"positions": pts, "edges": ring})
            argv += ["--outline", job.path("outline.json")]
        argv += _roots(root)
        argv += flags(options)
        job.run(argv, progress)
        report, text = _report(job, "report.json")
        return {"network": job.read_network("venation.json"), "report": report,
                "report_json": text, "notes": job.notes}


def _roots(root: Any) -> list:
    if root is None:
        return []
    if isinstance(root, (int, np.integer, str)):
        return [f"--root={flag_value(root)}"]
    arr = np.asarray(root)
    if arr.ndim == 1 and arr.dtype.kind == "f":
        return ["--root=" + ",".join(repr(float(v)) for v in arr)]
    return [a for r in root for a in _roots(r)]


def venation_on_surface(vertices: Any, faces: Any, *, colors: Any = None, root: Any = None,
                        seed: int = 1, progress: Progress = None, **options: Any) -> dict:
    """Closed or open venation grown on a triangle mesh (Gokmen §3.3). ``colors`` (V×3 in 0..1)
    with ``density_channel`` set the density; ``root``: a vertex index, ``"tT"`` for a triangle,
    or an (x, y, z) point. Returns ``network``, ``report``, ``report_json``."""
    with Job() as job:
        job.write_mesh("surface.obj", vertices, faces, colors)
        argv = ["venation", "--surface", job.path("surface.obj"), "-o",
                job.path("venation.json"), "--report", job.path("report.json"),
                "--seed", str(seed)] + _roots(root) + flags(options)
        job.run(argv, progress)
        report, text = _report(job, "report.json")
        return {"network": job.read_network("venation.json"), "report": report,
                "report_json": text, "notes": job.notes}


def veins(vertices: Any, faces: Any, *, sources: Any = None, root: Optional[int] = None,
          colors: Any = None, seed: int = 1, progress: Progress = None,
          **options: Any) -> dict:
    """Geodesic veins along the edges of a mesh from a root vertex to source vertices
    (Bachman). ``sources``: a count to sample, or a list of vertex indices. Returns
    ``network``, ``report``, ``report_json``."""
    with Job() as job:
        job.write_mesh("surface.obj", vertices, faces, colors)
        argv = ["veins", "--surface", job.path("surface.obj"), "-o", job.path("veins.json"),
                "--report", job.path("report.json"), "--seed", str(seed)]
        if isinstance(sources, (int, np.integer)):
            argv.append(f"--sources={int(sources)}")
        elif sources is not None:
            argv += [f"--source={int(s)}" for s in sources]
        if root is not None:
            argv.append(f"--root={int(root)}")
        job.run(argv + flags(options), progress)
        report, text = _report(job, "report.json")
        return {"network": job.read_network("veins.json"), "report": report,
                "report_json": text, "notes": job.notes}


def lsystem(*, axiom: Optional[str] = None, rules: Any = (), iterations: Optional[int] = None,
            seed: int = 1, progress: Progress = None, **options: Any) -> dict:
    """A bracketed L-system drawn with a 3D turtle: ``rules`` as ``["X=F[-X]F[+X]-X", ...]``
    or a dict ``{"X": "F[-X]F[+X]-X"}``. With ``derive_only=True`` only ``report`` (the
    counts). Returns ``network``, ``report``, ``report_json``."""
    if isinstance(rules, dict):
        rules = [f"{k}={v}" for k, v in rules.items()]
    with Job() as job:
        argv = ["lsystem", "--seed", str(seed)]
        if axiom is not None:
            argv.append(f"--axiom={axiom}")
        argv += [f"--rule={r}" for r in rules]
        if iterations is not None:
            argv.append(f"--iterations={int(iterations)}")
        if options.get("derive_only"):
            options.pop("json", None)
            _, out, notes = _lamina.run(argv + flags(options) + ["--json"], progress)
            return {"report": json.loads(out), "report_json": out, "notes": notes}
        argv += ["-o", job.path("lsystem.json"), "--report", job.path("report.json")]
        job.run(argv + flags(options), progress)
        report, text = _report(job, "report.json")
        return {"network": job.read_network("lsystem.json"), "report": report,
                "report_json": text, "notes": job.notes}


# Rationalizing.


def cells(positions: Any, edges: Any = None, normals: Any = None, *, surface: Any = None,
          progress: Progress = None, **options: Any) -> dict:
    """The closed cells of a network on a surface, triangulated (constrained Delaunay), with
    per-node normals; V − E + F checked against the ``surface`` (a mesh) when given. Returns
    ``mesh`` (one vertex per node), ``normals`` (V×3), ``table`` (the command's ``--table``),
    ``table_json``."""
    with Job() as job:
        job.write_network("network.json", _network(positions, edges, normals))
        argv = ["cells", job.path("network.json"), "-o", job.path("cells.obj"), "--table",
                job.path("table.json")]
        if surface is not None:
            job.write_mesh("surface.obj", *_mesh(surface, "surface"))
            argv += ["--surface", job.path("surface.obj")]
        job.run(argv + flags(options), progress)
        table, text = _report(job, "table.json")
        rows = {"v": [], "vn": [], "f": []}
        for line in job.text("cells.obj").splitlines():
            kind, _, rest = line.partition(" ")
            if kind in rows:
                rows[kind].append(rest.split())
        faces = [[int(t.split("/")[0]) - 1 for t in f] for f in rows["f"]]
        mesh = {"vertices": np.asarray(rows["v"], dtype=np.float64).reshape(-1, 3),
                "faces": np.asarray(faces, dtype=np.int64).reshape(-1, 3), "colors": None}
        return {"mesh": mesh, "normals": np.asarray(rows["vn"], dtype=np.float64).reshape(-1, 3),
                "table": table, "table_json": text, "notes": job.notes}


def planarize(positions: Any, edges: Any = None, normals: Any = None, *,
              height: float = 100.0, tolerance: float = 0.01, method: str = "lbfgs",
              surface: Any = None, node_radius: Any = None, edge_radius: Any = None,
              progress: Progress = None, **options: Any) -> dict:
    """Node axes that make every panel of the network planar (L-BFGS, ``projection`` or
    ``newton``). ``normals`` (N×3) are the reference directions, or the normals of ``surface``
    (a mesh) at the nodes. Returns ``axes`` (N×3 unit axes), ``heights`` (N), ``panels``
    (P×4×3 quads), ``within`` (the tolerance was reached), ``summary`` (the axes file's),
    ``report`` (the planarity report, ``--report``), ``report_json``, and ``axes_json`` (the
    axes file's text, for :func:`size` and :func:`plates`)."""
    arrays = network_arrays(_network(positions, edges, normals, node_radius, edge_radius))
    with Job() as job:
        # The network stays in memory; the report names it network.json, as the command line
        # run on a file of that name would.
        argv = ["network.json", "-o", "axes.json", f"--height={flag_value(float(height))}",
                f"--tolerance={flag_value(float(tolerance))}", f"--method={method}"]
        if surface is not None:
            job.write_mesh("surface.obj", *_mesh(surface, "surface"))
            argv += ["--surface", job.path("surface.obj")]
        check_progress(progress)
        try:
            within, axes_text, text, summary, axes, heights, notes = _lamina.planarize(
                argv + flags(options), arrays, progress)
        except LaminaError as e:
            raise LaminaError(job.relative(str(e))) from None
        job.note(notes)
        axes = np.frombuffer(axes, "<f8").reshape(-1, 3).copy()
        heights = np.frombuffer(heights, "<f8").copy()
        p = arrays_positions(arrays)
        e = np.frombuffer(arrays[1], "<u4").reshape(-1, 2).astype(np.int64)
        a, b = e[:, 0], e[:, 1]
        panels = np.stack([p[a], p[b], p[b] + axes[b] * heights[b, None],
                           p[a] + axes[a] * heights[a, None]], axis=1)
        return {"axes": axes, "heights": heights, "panels": panels, "within": within,
                "summary": json.loads(summary), "report": json.loads(text), "report_json": text,
                "axes_json": axes_text, "notes": job.notes}


def audit(panels: Any, *, tolerance: Optional[float] = None, metric: str = "flatness",
          progress: Progress = None, **options: Any) -> dict:
    """The planarity audit of panels made anywhere: a list of polygons (each K×3), a
    (vertices, faces) pair with faces as lists of vertex indices, or a file (.obj .dxf .json).
    Returns ``report`` (the planarity report), ``report_json``, ``within``."""
    with Job() as job:
        if isinstance(panels, (str, os.PathLike)):
            source = os.fspath(panels)
        else:
            _write_polygons(job.path("panels.obj"), panels)
            source = job.path("panels.obj")
        argv = ["audit", source, "--report", job.path("report.json"), f"--metric={metric}"]
        if tolerance is not None:
            argv.append(f"--tolerance={flag_value(float(tolerance))}")
        within = job.run(argv + flags(options), progress)
        report, text = _report(job, "report.json")
        return {"report": report, "report_json": text, "within": within, "notes": job.notes}


def _write_polygons(path: str, panels: Any) -> None:
    """Polygons as OBJ n-gons (shortest exact numbers)."""
    if isinstance(panels, tuple) and len(panels) == 2:
        vertices = as_points(panels[0], "vertices")
        faces = [list(map(int, f)) for f in panels[1]]
    else:
        vertices, faces = [], []
        for k, poly in enumerate(panels):
            pts = as_points(poly, f"panel {k}")
            faces.append(list(range(len(vertices), len(vertices) + len(pts))))
            vertices.extend(pts)
        vertices = np.asarray(vertices, dtype=np.float64).reshape(-1, 3)
    n = len(vertices)
    lines = ["v " + " ".join(repr(float(c)) for c in v) for v in vertices]
    for k, f in enumerate(faces):
        if len(f) < 3 or min(f) < 0 or max(f) >= n:
            raise LaminaError(f"panel {k}: needs 3 or more corners among the {n} vertices")
        lines.append("f " + " ".join(str(i + 1) for i in f))
    with open(path, "w", encoding="utf-8") as out:
        out.write("\n".join(lines) + "\n")


# Steel.


def size(axes: Any, *, support: Any = (), load: Any = (), progress: Progress = None,
         **options: Any) -> dict:
    """Frame analysis of the plate network and the gauges it needs. ``axes``: the result of
    :func:`planarize` (or an axes file path); ``support`` and ``load`` as the command takes
    them (``"z<1"``, ``"self-weight"``; lists repeat). Returns ``sizing`` (sizing.json),
    ``sizing_json``, ``within`` (utilisation, weld utilisation and deflection within limits)."""
    with Job() as job:
        source = _document(job, axes, "axes_json", "lamina-axes", "axes.json", "axes")
        support = [support] if isinstance(support, str) else list(support)
        load = [load] if isinstance(load, str) else list(load)
        argv = ["size", _in(job, source), "-o", job.path("sizing.json")]
        argv += [f"--support={s}" for s in support] + [f"--load={s}" for s in load]
        within = job.run(argv + flags(options), progress)
        sizing, text = _report(job, "sizing.json")
        return {"sizing": sizing, "sizing_json": text, "within": within, "notes": job.notes}


def _in(job: Job, source: str) -> str:
    """A document the job wrote (by its name) or the caller's path."""
    return job.path(source) if os.path.exists(job.path(source)) else source


def plates(axes: Any, *, sizing: Any = None, progress: Progress = None,
           **options: Any) -> dict:
    """Planar plates with torsion-free node axes, bolt holes, weld gaps and tags. ``axes``: the
    result of :func:`planarize` (or a path); ``sizing``: the result of :func:`size` (or a
    path) for gauges from the analysis. Returns ``plates`` (plates.json), ``plates_json``,
    ``welds`` (welds.json), ``assembly`` (the mesh of every plate), ``files`` (every file the
    command writes, by name: part DXFs, assembly.obj, welds.html...), ``within``."""
    with Job() as job:
        source = _document(job, axes, "axes_json", "lamina-axes", "axes.json", "axes")
        argv = ["plates", _in(job, source), "-o", job.path("plates")]
        if sizing is not None:
            s = _document(job, sizing, "sizing_json", "lamina-sizing", "sizing.json", "sizing")
            argv += ["--sizing", _in(job, s)]
        within = job.run(argv + flags(options), progress)
        text = job.text("plates/plates.json")
        welds = job.text("plates/welds.json") if os.path.exists(job.path("plates/welds.json")) \
            else None
        return {"plates": json.loads(text), "plates_json": text,
                "welds": None if welds is None else json.loads(welds),
                "assembly": job.read_mesh("plates/assembly.stl"), "files": job.files("plates"),
                "within": within, "notes": job.notes}


def nest(plates: Any, *, sheet: Optional[str] = None, progress: Progress = None,
         **options: Any) -> dict:
    """Nest the plates onto stock sheets and write the cut DXFs. ``plates``: the result of
    :func:`plates` (or a plates.json path); ``sheet``: ``"3000x1500"``. Returns ``nest``
    (nest.json), ``nest_json``, ``files`` (every file written: the sheet DXFs, cut plan)."""
    with Job() as job:
        source = _document(job, plates, "plates_json", "lamina-plates", "plates.json", "plates")
        argv = ["nest", _in(job, source), "-o", job.path("cut")]
        if sheet is not None:
            argv.append(f"--sheet={sheet}")
        job.run(argv + flags(options), progress)
        text = job.text("cut/nest.json")
        return {"nest": json.loads(text), "nest_json": text, "files": job.files("cut"),
                "notes": job.notes}


# Printing.


def solid(positions: Any, edges: Any = None, node_radius: Any = None, edge_radius: Any = None,
          *, cell: Optional[float] = None, progress: Progress = None, **options: Any) -> dict:
    """The closed, 2-manifold mesh of the network's veins (each edge a cone between its nodes'
    spheres), meshed on a grid of ``cell`` mm. Returns ``mesh``, ``report``, ``report_json``."""
    arrays = network_arrays(_network(positions, edges, None, node_radius, edge_radius))
    check_progress(progress)
    # In memory, as planarize (no folder): the report names the network network.json.
    argv = ["network.json", "-o", "solid.obj"]
    if cell is not None:
        argv.append(f"--cell={flag_value(float(cell))}")
    text, v, f, notes = _lamina.solid(argv + flags(options), arrays, progress)
    return {"mesh": mesh_of(v, f, None), "report": json.loads(text), "report_json": text,
            "notes": warn(notes)}


def slice(models: Any, *, progress: Progress = None, **options: Any) -> dict:
    """Slice closed meshes into a DMP-SL/MSLA print job. ``models``: a mesh (a dict or a
    (vertices, faces) pair) or a list of them. Returns ``sl1`` (the archive's bytes),
    ``report`` (print.json: layers, islands, resin, time), ``report_json``."""
    if isinstance(models, dict) or (isinstance(models, tuple) and len(models) == 2
                                     and not isinstance(models[0], (dict, tuple))):
        models = [models]
    data = []
    for k, m in enumerate(models):
        vertices, faces, _colors = _mesh(m, f"model {k}")
        v = as_points(vertices, f"model {k}: vertices")
        f = as_indices(faces, f"model {k}: faces", 3, len(v))
        # In memory; the report names the models model-0.obj, model-1.obj, ...
        data.append((f"model-{k}.obj", v.tobytes(), f.tobytes()))
    with Job() as job:
        argv = ["-o", job.path("print.sl1")] + flags(options)
        check_progress(progress)
        try:
            text, notes = _lamina.slice(argv, data, progress)
        except LaminaError as e:
            raise LaminaError(job.relative(str(e))) from None
        job.note(notes)
        text = job.relative(text)
        report = json.loads(text)
        return {"sl1": job.bytes("print.sl1"), "report": report, "report_json": text,
                "notes": job.notes}
