"""Recomputes Peele's Figure 1 measures from the networks a `lamina venation --sweep-r` folder
holds, and checks sweep.json against them (shares no code with lamina; plain Python):

    check_peele_sweep.py DIR [--verdict]
    check_peele_sweep.py --network NET.json --report REPORT.json   (one leaf's --report)

Per leaf (its network JSON, named in sweep.json):
- veins: the edges split into maximal chains through nodes of degree 2, between junctions
  and tips (a loop of degree-2 nodes is one vein); a vein's radius is its thickest edge's;
- the petiole's radius: the thickest edge at a root (meta.parameters.roots first nodes);
- dominant veins: radius >= half the petiole's; their count, mean radius over the petiole's,
  length, and turning per mm (the angle between the edges in and out at each inner node, a
  loop's start included, summed and divided by their length);
- the zigzag index: the mean turning angle at the nodes of degree 2.
Counts must be equal, real numbers equal to 1e-9 (relative). Per r, sweep.json's table (mean,
sample standard deviation, min and max over the seeds) must equal the same from these numbers.
With --verdict, prints whether the dominant-vein count falls and their radius rises as r falls,
beyond the spread: the lowest r's mean + sd under (over, for the radius) the highest r's
mean - sd (mean + sd).
"""
import argparse
import json
import math
import os
import sys


def measures(path):
    data = json.load(open(path))
    pts = [n["p"] for n in data["nodes"]]
    edges = [(e["a"], e["b"], e.get("radius", 0.0)) for e in data["edges"]]
    roots = int(data["meta"]["parameters"].get("roots", 0))
    inc = [[] for _ in pts]
    for k, (a, b, _) in enumerate(edges):
        inc[a].append(k)
        inc[b].append(k)
    deg = [len(x) for x in inc]

    def sub(p, q):
        return [p[0] - q[0], p[1] - q[1], p[2] - q[2]]

    def unit(v):
        n = math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
        return None if n == 0.0 else [c / n for c in v]

    def angle(u, v):
        # atan2 of the cross product's length and the dot product: well conditioned for the
        # nearly straight turns veins make (an arc cosine of the dot is not).
        c = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
        d = u[0] * v[0] + u[1] * v[1] + u[2] * v[2]
        return math.degrees(math.atan2(math.sqrt(c[0] ** 2 + c[1] ** 2 + c[2] ** 2), d))

    # Zigzag index: at each node of degree 2, the angle between the legs' reversed directions.
    turns = []
    for v in range(len(pts)):
        if deg[v] != 2:
            continue
        legs = []
        for k in inc[v]:
            a, b, _ = edges[k]
            w = b if a == v else a
            u = unit(sub(pts[w], pts[v]))
            if u is not None:
                legs.append(u)
        if len(legs) == 2:
            turns.append(angle([-c for c in legs[0]], legs[1]))
    zigzag = sum(turns) / len(turns) if turns else 0.0

    used = [False] * len(edges)

    def walk(start, k):
        nodes, ks = [start], []
        at = start
        while True:
            used[k] = True
            ks.append(k)
            a, b, _ = edges[k]
            at = b if a == at else a
            nodes.append(at)
            if deg[at] != 2 or at == start:
                return nodes, ks
            nxt = [j for j in inc[at] if not used[j]]
            if not nxt:
                return nodes, ks
            k = nxt[0]

    veins = []
    for v in range(len(pts)):
        if deg[v] != 2:
            for k in inc[v]:
                if not used[k]:
                    veins.append(walk(v, k))
    for v in range(len(pts)):
        for k in inc[v]:
            if not used[k]:
                veins.append(walk(v, k))
    assert all(used), "every edge in one vein"

    petiole = max((r for a, b, r in edges if roots == 0 or a < roots or b < roots), default=0.0)
    dominant, rsum, length, turning = 0, 0.0, 0.0, 0.0
    if petiole > 0.0:
        for nodes, ks in veins:
            r = max(edges[k][2] for k in ks)
            if r < 0.5 * petiole:
                continue
            dominant += 1
            rsum += r
            p = [pts[v] for v in nodes]
            length += sum(math.dist(p[i], p[i + 1]) for i in range(len(p) - 1))
            corners = [(p[i - 1], p[i], p[i + 1]) for i in range(1, len(p) - 1)]
            if len(nodes) > 2 and nodes[0] == nodes[-1]:
                corners.append((p[-2], p[0], p[1]))
            for a, b, c in corners:
                turning += angle(sub(b, a), sub(c, b))
    return {
        "count": len(veins),
        "petiole_radius": petiole,
        "dominant": dominant,
        "dominant_radius_ratio": rsum / dominant / petiole if dominant else 0.0,
        "dominant_length": length,
        "dominant_turning_deg_per_mm": turning / length if length > 0 else 0.0,
        "zigzag_deg": zigzag,
    }


def spread(values):
    n = len(values)
    mean = sum(values) / n
    sd = math.sqrt(sum((x - mean) ** 2 for x in values) / (n - 1)) if n > 1 else 0.0
    return {"mean": mean, "sd": sd, "min": min(values), "max": max(values)}


def close(a, b):
    return a == b or abs(a - b) <= 1e-9 * max(abs(a), abs(b))


def compare(name, ours, report):
    """What differs between our measures and a report's (quality.veins, quality.zigzag_deg)."""
    theirs = dict(report["quality"]["veins"])
    theirs["zigzag_deg"] = report["quality"]["zigzag_deg"]
    out = []
    for key, value in ours.items():
        same = value == theirs[key] if isinstance(value, int) else close(value, theirs[key])
        if not same:
            out.append(f"{name}: {key} is {value!r} here, {theirs[key]!r} in the report")
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("dir", nargs="?")
    ap.add_argument("--verdict", action="store_true")
    ap.add_argument("--network")
    ap.add_argument("--report")
    args = ap.parse_args()
    if args.network:
        report = json.load(open(args.report))
        problems = compare(os.path.basename(args.network), measures(args.network), report)
        for p in problems:
            print("FAIL", p)
        if problems:
            sys.exit(1)
        print(f"ok: {args.network}: the report's veins and zigzag index recomputed")
        return
    sweep = json.load(open(os.path.join(args.dir, "sweep.json")))
    problems = []
    by_r = {}
    for leaf in sweep["leaves"]:
        name = os.path.basename(leaf["output"])
        ours = measures(os.path.join(args.dir, name))
        problems += compare(name, ours, leaf)
        by_r.setdefault(leaf["r"], []).append(ours)
    table = sweep["table"]
    if [row["r"] for row in table] != list(by_r):
        problems.append(f"table rows {[row['r'] for row in table]}, leaves at r {list(by_r)}")
    columns = {
        "dominant": "dominant",
        "dominant_radius_ratio": "dominant_radius_ratio",
        "zigzag_deg": "zigzag_deg",
        "turning_deg_per_mm": "dominant_turning_deg_per_mm",
    }
    for row in table:
        leaves = by_r.get(row["r"], [])
        if row["seeds"] != len(leaves):
            problems.append(f"r = {row['r']}: {row['seeds']} seeds in the table, {len(leaves)} leaves")
            continue
        for column, key in columns.items():
            ours = spread([float(m[key]) for m in leaves])
            for stat, value in ours.items():
                if not close(value, row[column][stat]):
                    problems.append(
                        f"r = {row['r']}: {column} {stat} is {value!r} here, "
                        f"{row[column][stat]!r} in sweep.json"
                    )
    for p in problems[:20]:
        print("FAIL", p)
    if problems:
        sys.exit(1)
    print(f"ok: {len(sweep['leaves'])} leaves at r = {', '.join(str(r) for r in by_r)}: veins, "
          "dominant veins, their radius and turning, zigzag index and the table recomputed")
    if args.verdict:
        lo, hi = table[0], table[-1]
        fewer = lo["dominant"]["mean"] + lo["dominant"]["sd"] < hi["dominant"]["mean"] - hi["dominant"]["sd"]
        thicker = (lo["dominant_radius_ratio"]["mean"] - lo["dominant_radius_ratio"]["sd"]
                   > hi["dominant_radius_ratio"]["mean"] + hi["dominant_radius_ratio"]["sd"])
        print(f"r = {lo['r']} against r = {hi['r']}: fewer dominant veins beyond the spread: "
              f"{fewer}; thicker beyond the spread: {thicker}")


if __name__ == "__main__":
    main()
