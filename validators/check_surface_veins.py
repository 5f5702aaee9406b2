"""Checks veins grown on a surface, independently of lamina (numpy, scipy and trimesh).

    check_surface_veins.py MESH NETWORK.json [--report REPORT.json] [--max-degree 3]
                           [--mesh-edges] [--tree]

- every node lies on the mesh: its distance to the nearest triangle (exact, numpy: every triangle
  that can be nearest measured) is at most 1e-6 of the mesh's bounding-box diagonal;
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
from scipy.spatial import cKDTree

from graph_parts import component_count


def closest_distances(points, tris):
    """Distance from each point to the nearest triangle (n x 3 points, t x 3 x 3 triangles), the
    index of that triangle (the lowest of equally near ones), and the triangles' unit normals.
    Exact, as a brute force over all triangles would give: a triangle's distance is at least
    its centre's less its reach (centre to farthest corner), so once the nearest few centres'
    triangles bound a point's distance from above, only triangles whose centre lies within that
    bound plus their reach can be nearer (found in k-d trees of the centres, a tree for each
    size class of triangle), and only those are measured."""
    a, b, c = tris[:, 0], tris[:, 1], tris[:, 2]
    ab, ac = b - a, c - a
    normal = np.cross(ab, ac)
    nlen = np.linalg.norm(normal, axis=1)
    nlen[nlen == 0] = 1.0
    unit = normal / nlen[:, None]
    d00, d01, d11 = (ab * ab).sum(1), (ab * ac).sum(1), (ac * ac).sum(1)
    denom = d00 * d11 - d01 * d01
    denom[denom == 0] = 1.0

    def pair(p, t):
        """Distance from p[i] to triangle t[i]: its plane inside it, else its nearest side."""
        ap = p - a[t]
        h = (ap * unit[t]).sum(1)
        q = ap - h[:, None] * unit[t]
        d20, d21 = (q * ab[t]).sum(1), (q * ac[t]).sum(1)
        v = (d11[t] * d20 - d01[t] * d21) / denom[t]
        w = (d00[t] * d21 - d01[t] * d20) / denom[t]
        inside = (v >= 0) & (w >= 0) & (v + w <= 1)
        dist = np.where(inside, np.abs(h), np.inf)
        for s, e in ((a, b), (b, c), (c, a)):
            se = e[t] - s[t]
            ll = (se * se).sum(1)
            ll[ll == 0] = 1.0
            u = np.clip(((p - s[t]) * se).sum(1) / ll, 0.0, 1.0)
            foot = s[t] + u[:, None] * se
            dist = np.minimum(dist, np.linalg.norm(p - foot, axis=1))
        return dist

    if len(points) == 0:
        return np.zeros(0), np.zeros(0, dtype=int), unit
    centre = tris.mean(1)
    reach = np.linalg.norm(tris - centre[:, None], axis=2).max(1)
    slack = 1e-9 * (1.0 + np.abs(tris).max())
    _, near = cKDTree(centre).query(points, k=min(8, len(tris)))
    near = near.reshape(len(points), -1)
    upper = np.min([pair(points, near[:, j]) for j in range(near.shape[1])], axis=0)
    level = np.floor(np.log2(np.maximum(reach, 1e-300) / max(reach.max(), 1e-300)))
    level = np.maximum(level, -8)
    found_p, found_t = [], []
    for g in np.unique(level):
        group = np.flatnonzero(level == g)
        hits = cKDTree(centre[group]).query_ball_point(points, upper + reach[group].max() + slack)
        counts = np.fromiter((len(h) for h in hits), np.int64, len(hits))
        if counts.sum():
            found_p.append(np.repeat(np.arange(len(points)), counts))
            found_t.append(group[np.concatenate([np.asarray(h, np.int64) for h in hits if h])])
    pi, ti = np.concatenate(found_p), np.concatenate(found_t)
    d = np.concatenate([pair(points[pi[s:s + 1_000_000]], ti[s:s + 1_000_000])
                        for s in range(0, len(pi), 1_000_000)])
    # Per point: the least distance, the lowest triangle among equals.
    order = np.lexsort((ti, d, pi))
    pi, ti, d = pi[order], ti[order], d[order]
    first = np.ones(len(pi), bool)
    first[1:] = pi[1:] != pi[:-1]
    best = np.full(len(points), np.inf)
    arg = np.zeros(len(points), dtype=int)
    best[pi[first]] = d[first]
    arg[pi[first]] = ti[first]
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
