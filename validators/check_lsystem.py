"""Independent checks of `lamina lsystem` / `lamina bifurcate` output (no lamina code).

counts COUNTS.json N: rewrites the paper's grammar (Hanafin et al. 5.3: X -> F[-X]F[+X]-X,
    F -> FF) N times in memory and counts symbols, F's and maximal runs of F; the JSON lamina
    printed with --derive-only --json must match.
word WORD.txt N: the whole word lamina printed with --derive-only --string must equal ours.
facade NET.json (--rect W,H | --dxf FILE) [--root-on-boundary]: with shapely, every member lies
    inside the boundary (a W x H rectangle with its base centred on the origin, or the largest
    closed LWPOLYLINE of a DXF read by ezdxf) within 1e-6 mm, members meet only at their ends,
    the network is one connected piece holding meta.parameters.root_node.
tree NET.json --edges E: a tree (E edges, E + 1 nodes, connected, acyclic).
"""
import argparse
import json
import re
import sys

from shapely.geometry import LineString, Point, box
from shapely.strtree import STRtree

from graph_parts import component_count, component_labels


def derive(n):
    rules = str.maketrans({"X": "F[-X]F[+X]-X", "F": "FF"})
    word = "X"
    for _ in range(n):
        word = word.translate(rules)
    return word


def load(path):
    with open(path) as f:
        d = json.load(f)
    nodes = [tuple(n["p"]) for n in d["nodes"]]
    edges = [(e["a"], e["b"]) for e in d["edges"]]
    return d, nodes, edges


def check_counts(path, n):
    with open(path) as f:
        got = json.load(f)
    word = derive(n)
    want = {
        "symbols": len(word),
        "segments": word.count("F"),
        "simplified_segments": len(re.findall("F+", word)),
    }
    errors = [f"{k}: lamina {got.get(k)} != {v}" for k, v in want.items() if got.get(k) != v]
    return errors, f"n = {n}: {want}"


def check_word(path, n):
    with open(path) as f:
        got = f.read().strip()
    want = derive(n)
    return ([] if got == want else [f"word differs ({len(got)} vs {len(want)} symbols)"]), \
        f"n = {n}: {len(want)} symbols equal"


def dxf_polygon(path):
    import ezdxf
    from shapely.geometry import Polygon

    doc = ezdxf.readfile(path)
    loops = [Polygon([(x, y) for x, y, *_ in e.get_points()])
             for e in doc.modelspace().query("LWPOLYLINE") if e.closed]
    return max(loops, key=lambda p: p.area)


def check_facade(path, frame, root_on_boundary):
    d, nodes, edges = load(path)
    tol = 1e-6
    grown = frame.buffer(tol)
    errors = []
    lines = [LineString([nodes[a][:2], nodes[b][:2]]) for a, b in edges]
    for k, line in enumerate(lines):
        if not grown.covers(line):
            errors.append(f"edge {k} leaves the boundary")
    tree = STRtree(lines)
    crossings = 0
    for k, line in enumerate(lines):
        for j in tree.query(line):
            j = int(j)
            if j <= k:
                continue
            shared = set(edges[k]) & set(edges[j])
            inter = line.intersection(lines[j])
            if inter.is_empty:
                continue
            # Sharing a node, they may meet there only; otherwise they may not meet at all.
            if not shared or inter.geom_type != "Point":
                crossings += 1
    if crossings:
        errors.append(f"{crossings} pair(s) of members cross or touch away from a shared node")
    labels = component_labels(len(nodes), edges)
    parts = len(set(labels))
    if parts != 1:
        errors.append(f"{parts} connected pieces, expected 1")
    root = d["meta"]["parameters"].get("root_node")
    if root is None or not 0 <= root < len(nodes):
        errors.append(f"root_node {root} is not a node")
    elif root_on_boundary and frame.exterior.distance(Point(nodes[root][:2])) > tol:
        errors.append(f"root node {root} at {nodes[root][:2]} is not on the boundary")
    return errors, f"{len(nodes)} nodes, {len(edges)} members inside the boundary, {parts} piece(s)"


def check_tree(path, n_edges):
    _, nodes, edges = load(path)
    errors = []
    if len(edges) != n_edges:
        errors.append(f"{len(edges)} edges, expected {n_edges}")
    if len(nodes) != len(edges) + 1:
        errors.append(f"{len(nodes)} nodes for {len(edges)} edges: not a tree")
    if component_count(len(nodes), edges) != 1:
        errors.append("not connected")
    return errors, f"{len(nodes)} nodes, {len(edges)} edges"


def main():
    ap = argparse.ArgumentParser()
    sub = ap.add_subparsers(dest="cmd", required=True)
    c = sub.add_parser("counts")
    c.add_argument("file")
    c.add_argument("n", type=int)
    wd = sub.add_parser("word")
    wd.add_argument("file")
    wd.add_argument("n", type=int)
    f = sub.add_parser("facade")
    f.add_argument("file")
    f.add_argument("--rect", help="W,H: the rectangle with its base centred on the origin")
    f.add_argument("--dxf", help="the largest closed LWPOLYLINE of this DXF")
    f.add_argument("--root-on-boundary", action="store_true")
    t = sub.add_parser("tree")
    t.add_argument("file")
    t.add_argument("--edges", type=int, required=True)
    a = ap.parse_args()
    if a.cmd == "counts":
        errors, summary = check_counts(a.file, a.n)
    elif a.cmd == "word":
        errors, summary = check_word(a.file, a.n)
    elif a.cmd == "facade":
        if a.rect:
            w, h = (float(v) for v in a.rect.split(","))
            frame = box(-w / 2, 0, w / 2, h)
        else:
            frame = dxf_polygon(a.dxf)
        errors, summary = check_facade(a.file, frame, a.root_on_boundary)
    else:
        errors, summary = check_tree(a.file, a.edges)
    for e in errors[:20]:
        print(f"check_lsystem {a.cmd}: {a.file}: {e}", file=sys.stderr)
    print(f"check_lsystem {a.cmd}: {a.file}: {summary}: {'FAILED' if errors else 'ok'}")
    sys.exit(1 if errors else 0)


if __name__ == "__main__":
    main()
