"""lamina from Python: grow branching structures and turn networks into buildable, checked parts.

Each function calls a stage of the lamina library in memory: networks and meshes as numpy arrays
in and out, reports as dicts (numeric arrays as numpy arrays; large per-element tables, such as
a planarity report's panels, as a dict of columns: :func:`rows` turns one back into a list of
dicts). No file is read or written but those you name. Keyword options are the stage's options,
named as the command line's flags with ``_`` for ``-`` (``fix_normal=["z<1:0,0,1"]``); a name
the stage does not take is a TypeError naming the closest one.

``units=`` (mm, cm, m, in, ft) says what unit the geometry you pass is in, and the lengths among
the options (heights, tolerances, cells, steps, radii): they are taken to millimetres on the way
in and the geometry returned is in the same unit again. Reports stay in millimetres, as the
command line writes them; shop quantities (plate gauges, weld gaps, sheets, printer settings)
are always millimetres. A default length that is more than 100× off the usual scale for the
model warns (a model in metres passed as millimetres).

Errors raise :class:`LaminaError` naming the argument (``tolerance=``, ``positions[3]``);
notes (defaults taken, things read but not used) are :class:`LaminaWarning` at your line.

Long stages release the GIL and run on a thread pool of this process (a forked child makes its
own); ``progress(stage, message, done, total)`` is called about ten times a second (``total``
None when unknown). Ctrl-C, an exception raised by the callback, or the callback returning
False stop the stage at its next check (a brick of a mesh, a layer of a print, an iteration of
a solver, a part of a nest), raising KeyboardInterrupt, the callback's exception or
:class:`Cancelled`. Results are plain dicts and pickle.
"""

from __future__ import annotations

import os
from typing import Any, Optional, Union

import numpy as np

from . import _lamina
from ._arrays import (Progress, check_options, check_scale, indices, mesh_bytes, mesh_out,
                      network, network_bytes, network_out, points, scale_of, scaled, size_mm, warn)
from ._errors import Cancelled, LaminaError, LaminaWarning
from ._lamina import __version__

__all__ = [
    "Cancelled",
    "LaminaError",
    "LaminaWarning",
    "__version__",
    "audit",
    "bifurcate",
    "buds",
    "cells",
    "lsystem",
    "nest",
    "planarize",
    "plates",
    "print",
    "read_mesh",
    "read_network",
    "rows",
    "simplify",
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


def _units(units: Optional[str], *inputs: Any) -> str:
    """The unit of a call: as given, else the first input dict that says its own (a result of
    another function, a network from lamina.compas), else mm."""
    if units is not None:
        return units
    for x in inputs:
        if isinstance(x, dict) and isinstance(x.get("units"), str):
            return x["units"]
    return "mm"


def _done(result: dict, units: str) -> dict:
    """The result, its notes warned at the caller's line and its unit said."""
    result["notes"] = warn(result.get("notes", []))
    result["units"] = units
    return result


def rows(table: dict) -> list:
    """A table of columns (as reports hold large tables) as a list of dicts, one per row, with
    plain Python values (NaN as None, as the report file writes it)."""
    def plain(v: Any) -> Any:
        if isinstance(v, np.ndarray):
            return [plain(x) for x in v.tolist()]
        if isinstance(v, list):
            return [plain(x) for x in v]
        if isinstance(v, float) and v != v:
            return None
        if isinstance(v, dict):
            return {k: plain(x) for k, x in v.items()}
        return v

    if isinstance(table, list):
        return [plain(r) for r in table]
    columns = {k: plain(v) for k, v in table.items()}
    n = max((len(v) for v in columns.values()), default=0)
    return [{k: v[i] for k, v in columns.items()} for i in range(n)]


# Files.


def read_network(path: PathLike, units: Optional[str] = None,
                 hatch_boundaries: bool = False) -> dict:
    """A network file (.json .obj .dxf) as a network dict, read as the commands read it (a DXF
    in the unit its header states, an OBJ in mm unless `units` says otherwise): positions in
    mm. ``hatch_boundaries=True`` reads each boundary of a DXF's HATCH fills as a closed loop
    (else they are named in the notes as not read)."""
    return _done(_lamina.read_network(os.fspath(path), units, bool(hatch_boundaries)), "mm")


def write_network(path: PathLike, net: dict, units: Optional[str] = None) -> None:
    """Writes a network dict as lamina JSON, OBJ, DXF or SVG (by extension), in mm."""
    _lamina.write_network(os.fspath(path), network_bytes(net, scale_of(_units(units, net))))


def read_mesh(path: PathLike) -> dict:
    """A triangle mesh file (.obj .stl) as a mesh dict (vertices, faces, colors)."""
    return _lamina.read_mesh(os.fspath(path))


def write_mesh(path: PathLike, mesh: Any, units: Optional[str] = None) -> None:
    """Writes a mesh (a dict or a (vertices, faces) pair) as OBJ, binary STL or a PNG render,
    in mm."""
    _lamina.write_mesh(os.fspath(path), mesh_bytes(mesh, scale_of(_units(units, mesh))))


# Growing.

_VENATION_LENGTHS = ("step", "kill", "birth", "birth_min", "birth_max", "join_distance",
                     "min_member", "tip_radius", "reach", "edge_tolerance")


def venation(*, shape: str = "ovate", mode: str = "closed", outline: Any = None,
             root: Any = None, seed: int = 1, units: Optional[str] = None, progress: Progress = None,
             **options: Any) -> dict:
    """Leaf venation in a built-in blade (``shape``) or an ``outline`` (an N×2 or N×3 closed
    polygon, or a file path) by space colonisation (Runions et al. 2005), ``mode`` open or
    closed. ``root``: an (x, y) point or a list of them. Returns ``network`` and ``report``."""
    units = _units(units)
    k = scale_of(units)
    opts = scaled(check_options("venation", options), _VENATION_LENGTHS, k)
    opts.update(mode=mode, seed=seed)
    if root is not None:
        r = np.asarray(root, dtype=np.float64)
        opts["root"] = (r.reshape(-1, 2) * k).tolist()
    blade = None
    if isinstance(outline, (str, os.PathLike)):
        outline = read_network(outline, units=None if units == "mm" else units)["positions"]
        k_outline = 1.0
    else:
        k_outline = k
    if outline is not None:
        pts = np.asarray(outline, dtype=np.float64)
        if pts.ndim == 2 and pts.shape[1] == 2:
            pts = np.column_stack([pts, np.zeros(len(pts))])
        blade = (points(pts, "outline") * k_outline).tobytes()
    out = _lamina.venation(shape, blade, opts, progress)
    out["network"] = network_out(out["network"], k)
    return _done(out, units)


def _surface_roots(root: Any, k: float) -> list:
    if root is None:
        return []
    if isinstance(root, (int, np.integer, str)):
        return [root]
    arr = np.asarray(root)
    if arr.ndim == 1 and arr.dtype.kind == "f" and len(arr) == 3:
        return [tuple(float(x) * k for x in arr)]
    return [r for item in root for r in _surface_roots(item, k)]


def venation_on_surface(vertices: Any, faces: Any = None, *, colors: Any = None,
                        root: Any = None, seed: int = 1, units: Optional[str] = None,
                        progress: Progress = None, **options: Any) -> dict:
    """Closed or open venation grown on a triangle mesh (a dict, or vertices and faces), Gokmen
    §3.3. ``colors`` (V×3 in 0..1) with ``density_channel`` set the density; ``root``: a vertex
    index, ``"tK"`` for a triangle, or an (x, y, z) point (or a list). Returns ``network`` and
    ``report``."""
    units = _units(units, vertices)
    k = scale_of(units)
    opts = scaled(check_options("venation_on_surface", options), _VENATION_LENGTHS, k)
    opts["seed"] = seed
    mesh = mesh_bytes(vertices, k, "surface", faces, colors)
    out = _lamina.venation_on_surface(mesh, _surface_roots(root, k), opts, progress)
    out["network"] = network_out(out["network"], k)
    return _done(out, units)


def veins(vertices: Any, faces: Any = None, *, sources: Any = None, root: Optional[int] = None,
          colors: Any = None, seed: int = 1, units: Optional[str] = None, progress: Progress = None,
          **options: Any) -> dict:
    """Geodesic veins along the edges of a mesh from a root vertex to source vertices
    (Bachman). ``sources``: a count to sample, or a list of vertex indices. Returns ``network``
    and ``report``."""
    units = _units(units, vertices)
    k = scale_of(units)
    opts = scaled(check_options("veins", options), ("tip_radius",), k)
    opts.update(seed=seed, root=root)
    if isinstance(sources, (int, np.integer)):
        opts["sources"] = int(sources)
    elif sources is not None:
        opts["source"] = [int(s) for s in sources]
    opts = {key: v for key, v in opts.items() if v is not None}
    out = _lamina.veins(mesh_bytes(vertices, k, "surface", faces, colors), opts, progress)
    out["network"] = network_out(out["network"], k)
    return _done(out, units)


_TREE_LENGTHS = ("step", "length", "radius", "tip_radius", "frame_radius", "sag", "root_at")


def _tree_options(function: str, options: dict, k: float) -> dict:
    opts = scaled(check_options(function, options), _TREE_LENGTHS, k)
    b = opts.get("boundary")
    if b is not None and not (isinstance(b, (tuple, list)) and len(b) == 2
                              and all(isinstance(x, (int, float)) for x in b)):
        opts["boundary"] = (points(b, "boundary", 2) * k).tolist()
    elif b is not None:
        opts["boundary"] = (float(b[0]) * k, float(b[1]) * k)
    if opts.get("onto") is not None:
        v, f, _ = mesh_bytes(opts["onto"], k, "onto")
        opts["onto"] = (v, f)
    return opts


def lsystem(*, axiom: Optional[str] = None, rules: Any = (), iterations: Optional[int] = None,
            grammar: Optional[PathLike] = None, derive_only: bool = False, seed: int = 1,
            units: Optional[str] = None, progress: Progress = None, **options: Any) -> dict:
    """A bracketed L-system drawn with a 3D turtle: ``rules`` as ``["X=F[-X]F[+X]-X", ...]``
    or a dict ``{"X": "F[-X]F[+X]-X"}``; ``grammar`` a grammar file. With
    ``derive_only=True`` only ``report`` (the counts). Returns ``network`` and ``report``."""
    units = _units(units)
    k = scale_of(units)
    if isinstance(rules, dict):
        rules = [f"{a}={b}" for a, b in rules.items()]
    opts = _tree_options("lsystem", options, k)
    opts.update(axiom=axiom, rule=list(rules), iterations=iterations, seed=seed)
    if "angle" in opts:
        opts["angle"] = str(opts["angle"])
    opts = {key: v for key, v in opts.items() if v is not None}
    g = None
    if grammar is not None:
        with open(grammar, encoding="utf-8") as f:
            g = (f.read(), os.fspath(grammar))
    out = _lamina.lsystem(g, opts, bool(derive_only), progress)
    if "network" in out:
        out["network"] = network_out(out["network"], k)
    return _done(out, units)


def bifurcate(*, seed: int = 1, units: Optional[str] = None, **options: Any) -> dict:
    """A tree by recursive bifurcation (two scaled, turned copies at every branch end).
    Returns ``network`` and ``report``."""
    units = _units(units)
    k = scale_of(units)
    opts = _tree_options("bifurcate", options, k)
    for key in ("angle", "scale"):
        if key in opts:
            opts[key] = str(opts[key])
    opts["seed"] = seed
    out = _lamina.bifurcate(opts)
    out["network"] = network_out(out["network"], k)
    return _done(out, units)


def buds(program: str, *, progress: Progress = None, **options: Any) -> dict:
    """A bud program (Hart's Figure 8 language: its text, or a .bud file path) grown into a
    cellular form, skinned into a closed mesh. Returns ``mesh`` (mm) and ``report``."""
    opts = check_options("buds", options)
    name = "program"
    if "\n" not in program and os.path.exists(program):
        name = program
        with open(program, encoding="utf-8") as f:
            program = f.read()
    return _done(_lamina.buds(program, name, opts, progress), "mm")


# Rationalizing.


def cells(positions: Any, edges: Any = None, normals: Any = None, *, surface: Any = None,
          units: Optional[str] = None, **options: Any) -> dict:
    """The closed cells of a network on a surface, triangulated (constrained Delaunay), with
    per-node normals; V − E + F checked against the ``surface`` (a mesh) when given. Returns
    ``mesh`` (one vertex per node), ``normals`` (V×3) and ``table`` (cells and holes as
    columns)."""
    units = _units(units, positions)
    k = scale_of(units)
    opts = scaled(check_options("cells", options), ("point_tolerance",), k)
    net = network_bytes(network(positions, edges, normals), k)
    s = None if surface is None else mesh_bytes(surface, k, "surface")
    out = _lamina.cells(net, s, opts)
    out["mesh"] = mesh_out(out["mesh"], k)
    return _done(out, units)


def simplify(positions: Any, edges: Any = None, *, surface: Any = None, units: Optional[str] = None,
             **options: Any) -> dict:
    """Fewer, straighter members for fabrication within ``max_deviation``. Returns
    ``network`` and ``report``."""
    units = _units(units, positions)
    k = scale_of(units)
    opts = scaled(check_options("simplify", options),
                  ("max_deviation", "min_length", "merge_distance"), k)
    net = network_bytes(network(positions, edges), k)
    s = None if surface is None else mesh_bytes(surface, k, "surface")
    out = _lamina.simplify(net, s, opts)
    out["network"] = network_out(out["network"], k)
    return _done(out, units)


def planarize(positions: Any, edges: Any = None, normals: Any = None, *,
              height: Optional[float] = None, tolerance: Optional[float] = None,
              method: str = "newton", surface: Any = None, node_radius: Any = None,
              edge_radius: Any = None, units: Optional[str] = None, progress: Progress = None,
              **options: Any) -> dict:
    """Node axes that make every panel of the network planar (Gauss-Newton by default,
    ``lbfgs`` or ``projection``). ``normals`` (N×3) are the reference directions, or the normals of ``surface``
    (a mesh) at the nodes. Returns ``axes`` (N×3 unit axes), ``heights`` (N), ``panels``
    (P×4×3 quads), ``within`` (the tolerance was reached), ``summary``, ``report`` (the
    planarity report; its ``panels`` and ``worst`` as columns), and what :func:`size` and
    :func:`plates` take (``positions``, ``edges``, ``reference``, ``fixed_normals``,
    ``edge_radius``)."""
    units = _units(units, positions)
    k = scale_of(units)
    net = network(positions, edges, normals, node_radius, edge_radius)
    data = network_bytes(net, k)
    defaults = {}
    if height is None and "height_from_radius" not in options:
        defaults["height"] = 100.0
    if tolerance is None:
        defaults["tolerance"] = 0.01
    check_scale("planarize", size_mm(np.frombuffer(data[0], "<f8").reshape(-1, 3)), defaults,
                units)
    opts = scaled(check_options("planarize", options), ("height_from_radius",), 1.0)
    opts.update(method=method)
    if height is not None:
        opts["height"] = float(height) * k
    if tolerance is not None:
        opts["tolerance"] = float(tolerance) * k
    s = None if surface is None else mesh_bytes(surface, k, "surface")
    out = _lamina.planarize(data, s, opts, progress)
    for key in ("positions", "heights", "panels"):
        out[key] = out[key] / k if k != 1.0 else out[key]
    if k != 1.0:
        out["edge_radius"] = out["edge_radius"] / k
    return _done(out, units)


def _axes_bytes(axes: Any) -> tuple:
    """What the binding takes for axes: a :func:`planarize` result (or a dict like it, in mm)
    or an axes file path."""
    if isinstance(axes, (str, os.PathLike)):
        axes = _read_axes(os.fspath(axes))
    if not isinstance(axes, dict) or "axes" not in axes:
        raise LaminaError("axes: give the result of planarize() or an axes file path")
    k = scale_of(axes.get("units", "mm"))
    p = points(axes["positions"], "axes: positions") * k
    e = indices(axes["edges"], "axes: edges", 2)
    a = points(axes["axes"], "axes: axes")
    h = np.ascontiguousarray(np.asarray(axes["heights"], dtype=np.float64) * k, dtype="<f8")
    ref = points(axes.get("reference", axes["axes"]), "axes: reference")
    fixed = axes.get("fixed_normals")
    f = (np.full((len(e), 3), np.nan) if fixed is None else points(fixed, "axes: fixed_normals"))
    er = np.asarray(axes.get("edge_radius", np.zeros(len(e))), dtype=np.float64) * k
    f8 = [np.ascontiguousarray(x, dtype="<f8").tobytes() for x in (p, a, h, ref, f, er)]
    return (f8[0], e.tobytes(), f8[1], f8[2], f8[3], f8[4], f8[5])


def _read_axes(path: str) -> dict:
    """An axes file (lamina-axes JSON) as the dict :func:`planarize` returns."""
    import json

    try:
        with open(path, encoding="utf-8") as f:
            doc = json.load(f)
    except (OSError, ValueError) as e:
        raise LaminaError(f"{path}: cannot read the axes file: {e}") from None
    if doc.get("format") != "lamina-axes":
        raise LaminaError(f"{path}: not an axes file (format {doc.get('format')!r})")
    nodes, edges = doc["nodes"], doc["edges"]
    nan3 = [float("nan")] * 3
    return {
        "positions": np.array([n["p"] for n in nodes], dtype=float).reshape(-1, 3),
        "axes": np.array([n["axis"] for n in nodes], dtype=float).reshape(-1, 3),
        "heights": np.array([n["height"] for n in nodes], dtype=float),
        "reference": np.array([n["reference"] for n in nodes], dtype=float).reshape(-1, 3),
        "edges": np.array([[e["a"], e["b"]] for e in edges], dtype=np.int64).reshape(-1, 2),
        "fixed_normals": np.array([e.get("fixed_normal") or nan3 for e in edges],
                                  dtype=float).reshape(-1, 3),
        "edge_radius": np.array([e.get("radius", 0.0) for e in edges], dtype=float),
        "units": "mm",
    }


def audit(panels: Any, *, tolerance: Optional[float] = None, metric: str = "flatness",
          units: Optional[str] = None, **options: Any) -> dict:
    """The planarity audit of panels made anywhere: a P×K×3 array (quads from planarize), a
    list of polygons (each K×3), a (vertices, faces) pair with faces as lists of vertex
    indices, or a file (.obj .dxf .json).
    Returns ``report`` (the planarity report; ``panels`` and ``worst`` as columns) and
    ``within``."""
    units = _units(units)
    k = scale_of(units)
    opts = check_options("audit", options)
    opts["metric"] = metric
    if tolerance is not None:
        opts["tolerance"] = float(tolerance) * k
    if isinstance(panels, (str, os.PathLike)):
        return _done(_lamina.audit_file(os.fspath(panels), opts), units)
    if isinstance(panels, np.ndarray) and panels.ndim == 3 and panels.shape[2] == 3:
        # P×K×3: every panel K corners, passed whole.
        if panels.shape[1] < 3:
            raise LaminaError(f"panels: {panels.shape[1]} corners a panel; needs 3 or more")
        corners = np.ascontiguousarray(panels.reshape(-1, 3) * k, dtype="<f8")
        out = _lamina.audit(corners.tobytes(), [panels.shape[1]] * len(panels), None, opts)
        return _done(out, units)
    if isinstance(panels, tuple) and len(panels) == 2:
        vertices = points(panels[0], "vertices")
        polygons = []
        for n, face in enumerate(panels[1]):
            f = np.asarray(face)
            if f.ndim != 1 or not np.issubdtype(f.dtype, np.integer) or len(f) < 3:
                raise LaminaError(f"faces[{n}]: needs 3 or more vertex indices")
            if f.min() < 0 or f.max() >= len(vertices):
                raise LaminaError(f"faces[{n}]: index {int(f.max())} is not one of the "
                                  f"{len(vertices)} vertices")
            polygons.append(vertices[f])
    else:
        polygons = [points(p, f"panels[{n}]") for n, p in enumerate(panels)]
    for n, p in enumerate(polygons):
        if len(p) < 3:
            raise LaminaError(f"panels[{n}]: needs 3 or more corners")
    corners = (np.concatenate(polygons) * k if polygons else np.zeros((0, 3))).astype("<f8")
    out = _lamina.audit(corners.tobytes(), [len(p) for p in polygons], None, opts)
    return _done(out, units)


# Steel.


def size(axes: Any, *, support: Any = (), load: Any = (), progress: Progress = None,
         **options: Any) -> dict:
    """Frame analysis of the plate network and the gauges it needs. ``axes``: the result of
    :func:`planarize` (or an axes file path); ``support`` and ``load`` as the command takes
    them (``"z<1"``, ``"self-weight"``; lists for several). The self-weight is the plates as
    :func:`plates` cuts them with ``weld_gap``, ``weld_gap_tolerance``, ``node_core``, ``bolt``
    and ``bolt_clearance`` (give :func:`plates` the same), their bolts and node cores. Returns
    ``sizing`` (the sizing report; ``edges`` and ``nodes`` as columns), ``gauges`` (per edge),
    ``within``."""
    opts = check_options("size", options)
    opts["support"] = [support] if isinstance(support, str) else list(support)
    opts["load"] = [load] if isinstance(load, str) else list(load)
    return _done(_lamina.size(_axes_bytes(axes), opts, progress), "mm")


def plates(axes: Any, *, sizing: Any = None, out: Optional[PathLike] = None,
           **options: Any) -> dict:
    """Planar plates with torsion-free node axes, bolt holes, weld gaps and tags. ``axes``: the
    result of :func:`planarize` (or a path); ``sizing``: the result of :func:`size` for gauges
    from the analysis. With ``out``, the files the command writes go into that folder.
    Returns ``plates`` (plates.json as a dict), ``welds``, ``assembly`` (mesh, mm),
    ``files`` (written, by name) and ``within``."""
    opts = check_options("plates", options)
    gauges = None
    if sizing is not None:
        if not isinstance(sizing, dict) or "gauges" not in sizing:
            raise LaminaError("sizing: give the result of size()")
        per_edge = np.ascontiguousarray(sizing["gauges"], dtype="<f8").tobytes()
        listed = np.ascontiguousarray(sizing["gauge_list"], dtype="<f8").tobytes()
        import json

        report = sizing["sizing"]
        gauges = (per_edge, listed, json.dumps(report["material"]), report.get("seam_groups"),
                  json.dumps([e.get("seam_forces") for e in rows(report["edges"])]),
                  json.dumps(report.get("joints")))
    return _done(_lamina.plates(_axes_bytes(axes), gauges, opts,
                                None if out is None else os.fspath(out)), "mm")


def nest(plates: Any, *, sheet: Optional[str] = None, out: Optional[PathLike] = None,
         progress: Progress = None, **options: Any) -> dict:
    """Nest the plates on stock sheets (``sheet="3000x1500"``, or ``stock=`` with costs). With
    ``out``, the cut DXFs, bom.csv, nest.json, assembly.scad and sheets.svg go into that
    folder. With ``nc="gcode"`` or ``"essi"`` (``post=``, ``nc_on=``, ``nc_off=`` as the
    command's flags), every sheet's NC program too. Returns ``nest`` (nest.json; ``placements``
    as columns), ``bom`` (CSV text), ``svg``, ``outlines`` (each plate as cut on its sheet, by
    id), ``nc`` (program text by file name; empty without ``nc=``) and ``files``."""
    if isinstance(plates, dict) and "plates" in plates and isinstance(plates["plates"], dict):
        doc = plates["plates"]
    elif isinstance(plates, (str, os.PathLike)):
        import json

        with open(plates, encoding="utf-8") as f:
            doc = json.load(f)
    else:
        doc = plates
    opts = check_options("nest", options)
    if sheet is not None:
        opts["sheet"] = sheet
    return _done(_lamina.nest(doc, opts, None if out is None else os.fspath(out), progress),
                 "mm")


# Printing.

_SOLID_LENGTHS = ("cell", "tolerance", "lamina", "fit", "radius", "base")


def solid(positions: Any, edges: Any = None, node_radius: Any = None, edge_radius: Any = None,
          *, cell: Optional[float] = None, units: Optional[str] = None, progress: Progress = None,
          **options: Any) -> dict:
    """The closed, 2-manifold mesh of the network's veins (each edge a cone between its nodes'
    spheres), meshed on a grid of ``cell`` and simplified to within ``tolerance`` (default a
    quarter cell; ``tolerance=False`` keeps every marched triangle, as ``--full``). Returns
    ``mesh`` and ``report``."""
    units = _units(units, positions)
    k = scale_of(units)
    data = network_bytes(network(positions, edges, None, node_radius, edge_radius), k)
    if cell is None and options.get("fit") is None:
        check_scale("solid", size_mm(np.frombuffer(data[0], "<f8").reshape(-1, 3)),
                    {"cell": 0.035}, units)
    opts = dict(check_options("solid", options))
    if cell is not None:
        opts["cell"] = cell
    opts = scaled(opts, _SOLID_LENGTHS, k)
    out = _lamina.solid(data, opts, progress)
    out["mesh"] = mesh_out(out["mesh"], k)
    return _done(out, units)


def slice(models: Any, *, units: Optional[str] = None, progress: Progress = None,
          **options: Any) -> dict:
    """Slice closed meshes into a DMP-SL/MSLA print job. ``models``: a mesh (a dict or a
    (vertices, faces) pair) or a list of them. Returns ``sl1`` (the archive's bytes) and
    ``report`` (print.json: layers, islands, resin, time). ``supports=True`` (with the
    ``support_*`` options of ``print``, in mm) holds every island as ``slice --supports`` does."""
    units = _units(units, models)
    k = scale_of(units)
    if isinstance(models, dict) or (isinstance(models, tuple) and len(models) == 2
                                     and not isinstance(models[0], (dict, tuple))):
        models = [models]
    data = []
    for n, m in enumerate(models):
        v, f, _ = mesh_bytes(m, k, f"models[{n}]")
        data.append((f"model-{n}", v, f))
    return _done(_lamina.slice(data, check_options("slice", options), progress), units)


def _print(positions: Any, edges: Any = None, node_radius: Any = None,
           edge_radius: Any = None, *, units: Optional[str] = None, progress: Progress = None,
           **options: Any) -> dict:
    """The network's solid sliced straight from its signed distance into an SL1 archive, no
    mesh in between. Returns ``sl1`` (the archive's bytes) and ``report`` (print.json)."""
    units = _units(units, positions)
    k = scale_of(units)
    data = network_bytes(network(positions, edges, None, node_radius, edge_radius), k)
    opts = scaled(check_options("print", options), ("lamina", "fit", "radius", "base"), k)
    return _done(_lamina.print(data, opts, progress), units)


_print.__name__ = "print"
globals()["print"] = _print
