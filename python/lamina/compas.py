"""COMPAS interop: lamina networks as COMPAS Graphs, lamina meshes as COMPAS Meshes.

COMPAS (https://compas.dev) is imported only when these functions are called. Node positions
are the Graph's ``x``, ``y``, ``z`` attributes; radii travel as the node and edge attribute
``radius``, normals as the node attribute ``normal`` (a list of three floats, left out when
the network has none), lamina's edge order as the edge attribute ``index``. Nodes of a Graph made elsewhere are numbered in the Graph's node order;
``from_network`` gives that order back as ``keys``.
"""

from __future__ import annotations

from typing import Any, Optional

import numpy as np

from ._errors import LaminaError


def _compas():
    try:
        from compas.datastructures import Graph, Mesh
    except ImportError as e:
        raise ImportError("lamina.compas needs COMPAS: pip install compas") from e
    return Graph, Mesh


def to_network(network: dict) -> Any:
    """A lamina network dict as a ``compas.datastructures.Graph`` (nodes 0..N-1 in order)."""
    Graph, _ = _compas()
    g = Graph()
    p = np.asarray(network["positions"], dtype=np.float64).reshape(-1, 3)
    n = len(p)
    nr = network.get("node_radius")
    radius = np.broadcast_to(np.asarray(0.0 if nr is None else nr, dtype=np.float64), (n,))
    normals = network.get("normals")
    for i in range(n):
        attr = {"x": float(p[i, 0]), "y": float(p[i, 1]), "z": float(p[i, 2]),
                "radius": float(radius[i])}
        if normals is not None:
            attr["normal"] = [float(c) for c in normals[i]]
        g.add_node(i, **attr)
    edges = np.asarray(network["edges"], dtype=np.int64).reshape(-1, 2)
    er = network.get("edge_radius")
    er = np.broadcast_to(np.asarray(0.0 if er is None else er, dtype=np.float64), (len(edges),))
    for k, ((a, b), r) in enumerate(zip(edges, er)):
        g.add_edge(int(a), int(b), radius=float(r), index=k)
    meta = network.get("meta")
    if meta:
        g.attributes["lamina_meta"] = meta
    # The unit the positions are in travels with the graph, and comes back from it.
    g.attributes["units"] = network.get("units", "mm")
    return g


def from_network(graph: Any, units: Optional[str] = None) -> dict:
    """A ``compas.datastructures.Graph`` as a lamina network dict; ``keys`` lists the Graph's
    node keys in the order of ``positions``. Nodes without a radius get 0, edges too; normals
    only when every node has one. ``units``: the unit the Graph's coordinates are in (the
    document's; default the Graph's ``units`` attribute, else mm): lamina's functions take the
    network in that unit."""
    keys = list(graph.nodes())
    index = {k: i for i, k in enumerate(keys)}
    positions = np.array([graph.node_attributes(k, "xyz") for k in keys], dtype=np.float64)
    positions = positions.reshape(-1, 3)
    node_radius = np.array([graph.node_attribute(k, "radius") or 0.0 for k in keys],
                           dtype=np.float64)
    normals = [graph.node_attribute(k, "normal") for k in keys]
    normals = (np.array(normals, dtype=np.float64).reshape(-1, 3)
               if keys and all(n is not None for n in normals) else None)
    pairs = list(graph.edges())
    order = [graph.edge_attribute(e, "index") for e in pairs]
    if all(isinstance(k, int) for k in order) and sorted(order) == list(range(len(pairs))):
        pairs = [p for _, p in sorted(zip(order, pairs))]
    edges, edge_radius = [], []
    for u, v in pairs:
        edges.append((index[u], index[v]))
        edge_radius.append(graph.edge_attribute((u, v), "radius") or 0.0)
    if not np.isfinite(positions).all():
        bad = keys[int(np.argwhere(~np.isfinite(positions))[0, 0])]
        raise LaminaError(f"graph node {bad!r}: position is not finite")
    return {"positions": positions, "edges": np.array(edges, dtype=np.int64).reshape(-1, 2),
            "node_radius": node_radius, "edge_radius": np.array(edge_radius, dtype=np.float64),
            "normals": normals, "meta": graph.attributes.get("lamina_meta", {}), "keys": keys,
            "units": units or graph.attributes.get("units", "mm")}


def to_mesh(mesh: dict) -> Any:
    """A lamina mesh dict as a ``compas.datastructures.Mesh`` (vertex colours as the vertex
    attribute ``color``, when the mesh has them)."""
    _, Mesh = _compas()
    v = np.asarray(mesh["vertices"], dtype=np.float64).reshape(-1, 3)
    f = np.asarray(mesh["faces"], dtype=np.int64).reshape(-1, 3)
    m = Mesh.from_vertices_and_faces(v.tolist(), f.tolist())
    colors = mesh.get("colors")
    if colors is not None:
        for key, c in zip(m.vertices(), np.asarray(colors, dtype=np.float64)):
            m.vertex_attribute(key, "color", [float(x) for x in c])
    m.attributes["units"] = mesh.get("units", "mm")
    return m


def from_mesh(mesh: Any, units: Optional[str] = None) -> dict:
    """A ``compas.datastructures.Mesh`` as a lamina mesh dict: polygons triangulated by COMPAS,
    vertices renumbered 0..V-1 in the Mesh's order (``keys`` gives the Mesh's keys); ``units``
    as for :func:`from_network`."""
    keys = list(mesh.vertices())
    vertices, faces = mesh.to_vertices_and_faces(triangulated=True)
    colors = [mesh.vertex_attribute(k, "color") for k in keys]
    colors = (np.array(colors, dtype=np.float64).reshape(-1, 3)
              if keys and all(c is not None for c in colors) else None)
    return {"vertices": np.array(vertices, dtype=np.float64).reshape(-1, 3),
            "faces": np.array(faces, dtype=np.int64).reshape(-1, 3), "colors": colors,
            "keys": keys, "units": units or mesh.attributes.get("units", "mm")}
