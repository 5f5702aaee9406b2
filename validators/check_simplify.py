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
- cycles: the same number of independent cycles, E - V + C (scipy's connected components);
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
    return p, e


def cycles(p, e):
    used = np.unique(e)
    n = len(p)
    g = coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n, n))
    _, labels = connected_components(g, directed=False)
    comps = len(np.unique(labels[used]))
    return len(e) - len(used) + comps


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


def distances(points, p, e, block=2048):
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
    p0, e0 = load(args.original)
    if args.simple is None:
        angle, node = smallest_joint(p0, e0)
        print(f"{args.original}: {len(e0)} edges, smallest joint {angle:.3f} deg at node {node}")
        if angle < args.min_angle - 1e-9:
            failures.append(f"joint of {angle:.3f} deg at node {node} < {args.min_angle}")
    else:
        p1, e1 = load(args.simple)
        cut = 1.0 - len(e1) / len(e0)
        angle, node = smallest_joint(p1, e1)
        dev = distances(p0, p1, e1)
        c0, c1 = cycles(p0, e0), cycles(p1, e1)
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
        if args.flat:
            x = crossings(p1, e1)
            f0, f1 = faces(p0, e0), faces(p1, e1)
            print(f"  flat: {x} crossings; bounded faces {f0} -> {f1}")
            if x:
                failures.append(f"{x} pairs of simplified edges cross")
            if f0 != f1:
                failures.append(f"bounded faces {f0} -> {f1}")
        if args.report:
            with open(args.report) as f:
                r = json.load(f)
            checks = [
                ("members before", r["before"]["members"], len(e0)),
                ("members after", r["after"]["members"], len(e1)),
                ("cycles before", r["before"]["cycles"], c0),
                ("cycles after", r["after"]["cycles"], c1),
            ]
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
