"""Checks a venation network written by `lamina venation` against the rules of the venation
issue, computing everything here (shares no code with lamina):

    check_venation.py NET.json [--report REPORT.json] [--expect-loops]

- no node of degree > 3 (Y and I joints only);
- every node inside the blade outline stored in meta.parameters.outline, and every edge too
  (shapely);
- no two edges cross or touch except at a shared node (shapely STRtree);
- without blade growth, every growth-tree edge (all but the last `loop_edges`) is `step` long;
- Murray's law r_parent^n = sum r_child^n at every node with children, to 1e-9;
- with --expect-loops, at least one loop (E - V + C > 0); without, a single tree;
- with --report, the report's loops, open tips, nodes by degree and crossings match ours.
"""
import argparse
import json
import math
import sys
from collections import Counter

from shapely.geometry import LineString, Point, Polygon
from shapely.strtree import STRtree

from graph_parts import component_count


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("network")
    ap.add_argument("--report")
    ap.add_argument("--expect-loops", action="store_true")
    args = ap.parse_args()
    data = json.load(open(args.network))
    params = data["meta"]["parameters"]
    nodes = [(n["p"][0], n["p"][1]) for n in data["nodes"]]
    radius = [n.get("radius", 0.0) for n in data["nodes"]]
    edges = [(e["a"], e["b"]) for e in data["edges"]]
    roots = int(params["roots"])
    loops_closing = int(params["loop_edges"])
    problems = []

    degree = Counter()
    for a, b in edges:
        degree[a] += 1
        degree[b] += 1
    if any(d > 3 for d in degree.values()):
        problems.append(f"nodes of degree > 3: {sum(d > 3 for d in degree.values())}")

    blade = Polygon(params["outline"])
    if not blade.is_valid:
        problems.append("the stored outline is not a valid polygon")
    grown = blade.buffer(1e-9)
    outside = sum(not grown.contains(Point(p)) for p in nodes)
    if outside:
        problems.append(f"{outside} nodes outside the blade")
    segs = [LineString([nodes[a], nodes[b]]) for a, b in edges]
    leaving = sum(not grown.contains(s) for s in segs)
    if leaving:
        problems.append(f"{leaving} edges leave the blade")

    tree = STRtree(segs)
    crossings = 0
    for i, s in enumerate(segs):
        for j in tree.query(s):
            j = int(j)
            if j <= i:
                continue
            if set(edges[i]) & set(edges[j]):
                continue
            if s.intersects(segs[j]):
                crossings += 1
    if crossings:
        problems.append(f"{crossings} pairs of edges cross")

    tree_edges = edges[: len(edges) - loops_closing]
    if params.get("blade") == "none":
        d = float(params["step"])
        bad = [
            (a, b)
            for a, b in tree_edges
            if abs(math.dist(nodes[a], nodes[b]) - d) > 1e-9
        ]
        if bad:
            problems.append(f"{len(bad)} growth edges are not {d} mm long")

    n = float(params["murray"])
    child_sum = Counter()
    for a, b in tree_edges:
        child_sum[a] += radius[b] ** n
    for v, s in child_sum.items():
        if abs(radius[v] ** n - s) > 1e-9 * max(1.0, s):
            problems.append(f"Murray's law fails at node {v}")
            break

    c = component_count(len(nodes), edges)
    loops = len(edges) - len(nodes) + c
    if args.expect_loops and loops < 1:
        problems.append("no loop in a closed venation")
    if not args.expect_loops and (loops != 0 or c != 1):
        problems.append(f"not one tree: {c} components, {loops} loops")

    if args.report:
        q = json.load(open(args.report))["quality"]
        open_tips = sum(1 for v in range(roots, len(nodes)) if degree[v] == 1)
        by_degree = Counter(degree[v] for v in range(len(nodes)))
        ours = {
            "loops": loops,
            "open_tips": open_tips,
            "crossings": crossings,
            "nodes_by_degree": {str(k): v for k, v in sorted(by_degree.items())},
        }
        for k, v in ours.items():
            if q[k] != v:
                problems.append(f"report {k} = {q[k]}, counted here {v}")

    if problems:
        for p in problems:
            print(f"{args.network}: {p}", file=sys.stderr)
        sys.exit(1)
    print(
        f"{args.network}: ok ({len(nodes)} nodes, {len(edges)} edges, {loops} loops, "
        f"degree <= 3, inside the blade, no crossings, Murray holds)"
    )


if __name__ == "__main__":
    main()
