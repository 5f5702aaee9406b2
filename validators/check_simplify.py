"""Checks a simplified network against the network it came from (shares no code with lamina).

    check_simplify.py ORIGINAL.json SIMPLE.json [--min-reduction 0.4] [--min-angle 30]
        [--max-deviation MM] [--report REPORT.json] [--flat]

Each figure is computed here from the two network JSON files alone (json, numpy, scipy,
shapely):
- members: the simplified network has at least `--min-reduction` fewer edges;
- joints: no two edges at a node meet at less than `--min-angle` degrees (3D angle between the
  edges' directions);
- deviation: every node of the original lies within `--max-deviation` of some edge of the
  simplified network (exact point-to-segment distance, all pairs, in blocks);
- cycles: the same number of components and independent cycles, E - V + C (scipy's
  connected components);
- faces: where every node stores a normal, the faces of the rotation system (edges ordered
  by angle about each node's normal; a face leaves each node by the edge just clockwise of the
  one it came in on), so V - E + F on the surface, the same before and after;
- with `--flat` (a 2D network): no two simplified edges cross (shapely, STRtree), and the
  bounded faces of both networks (shapely.polygonize) match in count.
With `--report`, lamina's own report must agree with these figures (members, cycles, the
largest deviation within 1e-6 mm, the smallest joint angle within 1e-6 degrees).
With only ORIGINAL.json (and `--min-angle`), checks just its joints: for grown networks.
Exit 0 when every check holds, 1 otherwise.
"""
import argparse
import json
import sys

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
import shapely
from shapely.geometry import LineString


def load(path):
    with open(path) as f:
        d = json.load(f)
    p = np.array([n["p"] for n in d["nodes"]], dtype=float).reshape(-1, 3)
    e = np.array([[x["a"], x["b"]] for x in d["edges"]], dtype=np.int64).reshape(-1, 2)
    normals = [n.get("normal") for n in d["nodes"]]
    normals = None if any(n is None for n in normals) else np.array(normals, dtype=float)
    return p, e, normals


def components_and_cycles(p, e):
    used = np.unique(e)
    n = len(p)
    g = coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n, n))
    _, labels = connected_components(g, directed=False)
    comps = len(np.unique(labels[used]))
    return comps, len(e) - len(used) + comps


def rotation_faces(p, e, normals):
    """Faces traced through the rotation system about the nodes' normals."""
    out = {}
    for k, (a, b) in enumerate(e):
        out.setdefault(a, []).append((b, 2 * k))      # half-edge 2k: a -> b
        out.setdefault(b, []).append((a, 2 * k + 1))  # 2k + 1: b -> a
    pos = {}
    order = {}
    for v, hs in out.items():
        n = normals[v] / np.linalg.norm(normals[v])
        t0 = np.cross(n, [1.0, 0.0, 0.0] if abs(n[0]) < 0.9 else [0.0, 1.0, 0.0])
        t0 /= np.linalg.norm(t0)
        t1 = np.cross(n, t0)
        ang = [np.arctan2((p[w] - p[v]) @ t1, (p[w] - p[v]) @ t0) for w, _ in hs]
        ring = [h for _, h in sorted(zip(ang, [h for _, h in hs]))]
        order[v] = ring
        for i, h in enumerate(ring):
            pos[h] = i
    head = lambda h: e[h // 2][1] if h % 2 == 0 else e[h // 2][0]
    seen = np.zeros(2 * len(e), bool)
    faces = 0
    for start in range(2 * len(e)):
        if seen[start]:
            continue
        faces += 1
        h = start
        while not seen[h]:
            seen[h] = True
            v = head(h)
            ring = order[v]
            h = ring[(pos[h ^ 1] - 1) % len(ring)]
    return faces


def smallest_joint(p, e):
    """Per node, the smallest angle between two of its edges; returns (angle, node)."""
    legs = {}
    for a, b in e:
        legs.setdefault(a, []).append(b)
        legs.setdefault(b, []).append(a)
    best = (180.0, -1)
    for v, ws in legs.items():
        if len(ws) < 2:
            continue
        d = p[ws] - p[v]
        d /= np.linalg.norm(d, axis=1)[:, None]
        c = np.clip(d @ d.T, -1.0, 1.0)
        iu = np.triu_indices(len(ws), 1)
        a = np.degrees(np.arccos(c[iu])).min()
        if a < best[0]:
            best = (float(a), int(v))
    return best


def distances(points, p, e, block=512):
    a, b = p[e[:, 0]], p[e[:, 1]]
    ab = b - a
    l2 = np.maximum((ab * ab).sum(1), 1e-300)
    out = np.empty(len(points))
    for s in range(0, len(points), block):
        q = points[s:s + block][:, None, :]
        t = np.clip(((q - a) * ab).sum(2) / l2, 0.0, 1.0)
        near = a + t[..., None] * ab
        out[s:s + block] = np.sqrt(((q - near) ** 2).sum(2)).min(1)
    return out


def crossings(p, e):
    lines = [LineString([p[a, :2], p[b, :2]]) for a, b in e]
    tree = shapely.STRtree(lines)
    bad = 0
    for i, (a, b) in enumerate(e):
        for j in tree.query(lines[i], predicate="intersects"):
            if j <= i:
                continue
            c, d = e[j]
            if len({a, b, c, d}) < 4:
                # Edges sharing a node may only meet there.
                inter = lines[i].intersection(lines[j])
                if inter.geom_type != "Point":
                    bad += 1
                continue
            bad += 1
    return bad


def faces(p, e):
    lines = [LineString([p[a, :2], p[b, :2]]) for a, b in e]
    return len(list(shapely.polygonize(lines).geoms))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("original")
    ap.add_argument("simple", nargs="?")
    ap.add_argument("--min-reduction", type=float, default=0.4)
    ap.add_argument("--min-angle", type=float, default=30.0)
    ap.add_argument("--max-deviation", type=float)
    ap.add_argument("--report")
    ap.add_argument("--flat", action="store_true")
    args = ap.parse_args()
    failures = []
    p0, e0, n0 = load(args.original)
    if args.simple is None:
        angle, node = smallest_joint(p0, e0)
        print(f"{args.original}: {len(e0)} edges, smallest joint {angle:.3f} deg at node {node}")
        if angle < args.min_angle - 1e-9:
            failures.append(f"joint of {angle:.3f} deg at node {node} < {args.min_angle}")
    else:
        p1, e1, n1 = load(args.simple)
        cut = 1.0 - len(e1) / len(e0)
        angle, node = smallest_joint(p1, e1)
        dev = distances(p0, p1, e1)
        (k0, c0), (k1, c1) = components_and_cycles(p0, e0), components_and_cycles(p1, e1)
        print(
            f"{args.simple}: {len(e0)} -> {len(e1)} members ({100 * cut:.1f} % fewer), "
            f"smallest joint {angle:.3f} deg, largest deviation {dev.max():.4f} mm "
            f"(mean {dev.mean():.4f}), cycles {c0} -> {c1}"
        )
        if cut < args.min_reduction:
            failures.append(f"only {100 * cut:.1f} % fewer members (< {100 * args.min_reduction:.0f} %)")
        if angle < args.min_angle - 1e-9:
            failures.append(f"joint of {angle:.3f} deg at node {node} < {args.min_angle}")
        if args.max_deviation is not None and dev.max() > args.max_deviation * (1 + 1e-9):
            k = int(dev.argmax())
            failures.append(f"original node {k} is {dev.max():.4f} mm from the network (> {args.max_deviation})")
        if c0 != c1:
            failures.append(f"independent cycles {c0} -> {c1}")
        if k0 != k1:
            failures.append(f"components {k0} -> {k1}")
        if n0 is not None and n1 is not None:
            f0, f1 = rotation_faces(p0, e0, n0), rotation_faces(p1, e1, n1)
            chi0 = len(np.unique(e0)) - len(e0) + f0
            chi1 = len(np.unique(e1)) - len(e1) + f1
            print(f"  on the surface: faces {f0} -> {f1}, V - E + F {chi0} -> {chi1}")
            if (f0, chi0) != (f1, chi1):
                failures.append(f"faces {f0} -> {f1}, V - E + F {chi0} -> {chi1}")
        if args.flat:
            x = crossings(p1, e1)
            b0, b1 = faces(p0, e0), faces(p1, e1)
            print(f"  flat: {x} crossings; bounded faces {b0} -> {b1}")
            if x:
                failures.append(f"{x} pairs of simplified edges cross")
            if b0 != b1:
                failures.append(f"bounded faces {b0} -> {b1}")
        if args.report:
            with open(args.report) as f:
                r = json.load(f)
            checks = [
                ("members before", r["before"]["members"], len(e0)),
                ("members after", r["after"]["members"], len(e1)),
                ("cycles before", r["before"]["cycles"], c0),
                ("cycles after", r["after"]["cycles"], c1),
                ("components after", r["after"]["components"], k1),
            ]
            if n0 is not None and n1 is not None:
                checks += [("faces before", r["before"]["faces"], f0), ("faces after", r["after"]["faces"], f1)]
            for name, theirs, ours in checks:
                if theirs != ours:
                    failures.append(f"report {name} {theirs}, measured {ours}")
            if abs(r["max_distance"] - dev.max()) > 1e-6:
                failures.append(f"report max_distance {r['max_distance']}, measured {dev.max()}")
            if abs(r["after"]["smallest_joint_angle"] - angle) > 1e-6:
                failures.append(f"report smallest joint {r['after']['smallest_joint_angle']}, measured {angle}")
    for f in failures:
        print("FAIL:", f)
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
