"""Checks veins grown on a surface, independently of lamina (numpy and trimesh only).

    check_surface_veins.py MESH NETWORK.json [--report REPORT.json] [--max-degree 3]
                           [--mesh-edges] [--tree]

- every node lies on the mesh: its distance to the nearest triangle (brute force over all
  triangles, numpy) is at most 1e-6 of the mesh's bounding-box diagonal;
- every node's stored normal is a unit vector on the same side as the nearest face's normal;
- no node has more than --max-degree edges;
- --mesh-edges: every edge joins two mesh vertices that share a triangle side (geodesic veins);
- --tree: the network is one tree (E = V - 1, connected);
- --report: the report's node, edge and loop counts, and its nodes-off-surface figure, match.
Exit 0 when all hold; otherwise prints each failure and exits 1.
"""
import argparse
import json
import sys

import numpy as np
import trimesh

from graph_parts import component_count


def closest_distances(points, tris):
    """Distance from each point to the nearest triangle (n x 3 points, t x 3 x 3 triangles), and
    the index of that triangle."""
    a, b, c = tris[:, 0], tris[:, 1], tris[:, 2]
    ab, ac = b - a, c - a
    normal = np.cross(ab, ac)
    nlen = np.linalg.norm(normal, axis=1)
    nlen[nlen == 0] = 1.0
    unit = normal / nlen[:, None]
    d00, d01, d11 = (ab * ab).sum(1), (ab * ac).sum(1), (ac * ac).sum(1)
    denom = d00 * d11 - d01 * d01
    denom[denom == 0] = 1.0
    best = np.full(len(points), np.inf)
    arg = np.zeros(len(points), dtype=int)
    for start in range(0, len(points), 32):
        p = points[start:start + 32][:, None, :]  # m x 1 x 3
        ap = p - a[None]
        h = (ap * unit[None]).sum(2)  # signed plane distance, m x t
        q = ap - h[..., None] * unit[None]
        d20, d21 = (q * ab[None]).sum(2), (q * ac[None]).sum(2)
        v = (d11 * d20 - d01 * d21) / denom
        w = (d00 * d21 - d01 * d20) / denom
        inside = (v >= 0) & (w >= 0) & (v + w <= 1)
        dist = np.where(inside, np.abs(h), np.inf)
        for s, e in ((a, b), (b, c), (c, a)):
            se = e - s
            ll = (se * se).sum(1)
            ll[ll == 0] = 1.0
            t = np.clip(((p - s[None]) * se[None]).sum(2) / ll, 0.0, 1.0)
            foot = s[None] + t[..., None] * se[None]
            dist = np.minimum(dist, np.linalg.norm(p - foot, axis=2))
        best[start:start + 32] = dist.min(1)
        arg[start:start + 32] = dist.argmin(1)
    return best, arg, unit


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("mesh")
    ap.add_argument("network")
    ap.add_argument("--report")
    ap.add_argument("--max-degree", type=int, default=3)
    ap.add_argument("--mesh-edges", action="store_true")
    ap.add_argument("--tree", action="store_true")
    args = ap.parse_args()
    mesh = trimesh.load(args.mesh, force="mesh", process=False)
    net = json.load(open(args.network))
    nodes = net["nodes"]
    edges = [(e["a"], e["b"]) for e in net["edges"]]
    pts = np.array([n["p"] for n in nodes], dtype=float)
    verts = np.asarray(mesh.vertices, dtype=float)
    tris = verts[np.asarray(mesh.faces)]
    size = float(np.linalg.norm(verts.max(0) - verts.min(0)))
    failures = []

    dist, nearest, unit = closest_distances(pts, tris)
    off = int((dist > 1e-6 * size).sum())
    if off:
        failures.append(f"{off} nodes off the surface (farthest {dist.max():.3e} mm)")
    normals = np.array([n.get("normal") or [0, 0, 0] for n in nodes], dtype=float)
    lengths = np.linalg.norm(normals, axis=1)
    if np.any(np.abs(lengths - 1) > 1e-6):
        failures.append(f"{int((np.abs(lengths - 1) > 1e-6).sum())} nodes without a unit normal")
    side = (normals * unit[nearest]).sum(1)
    if np.any(side <= 0):
        failures.append(f"{int((side <= 0).sum())} normals on the wrong side of their face")

    degree = np.zeros(len(nodes), dtype=int)
    for a, b in edges:
        degree[a] += 1
        degree[b] += 1
    if degree.max(initial=0) > args.max_degree:
        failures.append(f"a node of degree {degree.max()} (at most {args.max_degree})")

    if args.mesh_edges:
        index = {tuple(v): i for i, v in enumerate(verts.tolist())}
        sides = set()
        for f in np.asarray(mesh.faces).tolist():
            for k in range(3):
                x, y = f[k], f[(k + 1) % 3]
                sides.add((min(x, y), max(x, y)))
        bad = 0
        for a, b in edges:
            va, vb = index.get(tuple(nodes[a]["p"])), index.get(tuple(nodes[b]["p"]))
            if va is None or vb is None or (min(va, vb), max(va, vb)) not in sides:
                bad += 1
        if bad:
            failures.append(f"{bad} edges are not mesh edges")

    if args.tree:
        components = component_count(len(nodes), edges)
        if len(edges) != len(nodes) - 1 or components != 1:
            failures.append(f"not a tree: {len(nodes)} nodes, {len(edges)} edges, "
                            f"{components} components")

    if args.report:
        rep = json.load(open(args.report))
        q = rep.get("quality", rep)
        components = q.get("components", 1)
        loops = len(edges) + components - len(nodes)
        for key, value in (("nodes", len(nodes)), ("edges", len(edges)), ("loops", loops),
                           ("nodes_off_surface", off)):
            if key in q and q[key] != value:
                failures.append(f"report says {key} = {q[key]}, counted {value}")

    for f in failures:
        print(f"{args.network}: {f}")
    if not failures:
        print(f"{args.network}: {len(nodes)} nodes on the surface (farthest {dist.max():.2e} mm), "
              f"max degree {degree.max(initial=0)}")
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
