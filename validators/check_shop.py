"""Checks what a steel shop needs of `lamina plates` output, with numpy and shapely, sharing no
code with lamina:

- every plate's thickness is on the gauge list given here;
- every bolted pair: the same number of holes, each hole's axis (its centre along the plate
  normal, in 3D) the same line in both plies within 0.01 mm; the hole diameter is the normal
  clearance hole of the bolt size (EN 1090-2 Table 11, ISO 273 below M12); every hole centre
  at least e1 = e2 = 1.2 d0 from every edge of the plate, at least two bolts a seam,
  neighbouring holes at least p1 = 2.2 d0 and at most min(14 t, 200 mm) apart for the thinner
  ply t (EN 1993-1-8 Table 3.3); the part DXF has the holes on CUT_INNER;
- at every node (positions and axes from axes.json): the plates (a bolted seam as its two
  plies together) projected along the node axis; side by side around the axis, every pair's
  root gap (shapely distance of the projections) is within the weld gap ± tolerance, unless
  welds.json reports the node (needing a core, or with one: then every plate is the gap from
  the core's tube); no other pair is closer than the gap less the tolerance;
- the dihedral angle of every pair welds.json lists equals the one computed here to 0.01°.

    check_shop.py PLATES_DIR AXES_JSON --gauges 1.5,2,3,4,5,6 --weld-gap 1 --tolerance 0.5
"""
import argparse
import json
import math
import sys
from collections import defaultdict
from pathlib import Path

import ezdxf
import numpy as np
from shapely.geometry import MultiPolygon, Point, Polygon
from shapely.ops import unary_union

# Bolt: (d, d0).
HOLES = {"M6": 6.6, "M8": 9.0, "M10": 11.0, "M12": 13.0, "M14": 15.0, "M16": 18.0,
         "M20": 22.0, "M22": 24.0, "M24": 26.0, "M27": 30.0, "M30": 33.0}


def fail(problems, msg):
    problems.append(msg)


def world(p, xy, z=0.0):
    m = np.array(p["matrix"], dtype=np.float64)
    return m[:3, :3] @ np.array([xy[0], xy[1], z]) + m[:3, 3]


def corners(p):
    """The plate's prism corners in 3D."""
    t = p["thickness"] / 2
    return [world(p, q, z) for q in p["outline"] for z in (-t, t)]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("plates_dir")
    ap.add_argument("axes")
    ap.add_argument("--gauges", required=True)
    ap.add_argument("--weld-gap", type=float, required=True)
    ap.add_argument("--tolerance", type=float, required=True)
    args = ap.parse_args()
    folder = Path(args.plates_dir)
    doc = json.load(open(folder / "plates.json"))
    welds = json.load(open(folder / "welds.json"))
    axes = json.load(open(args.axes))
    plates = doc["plates"]
    by_id = {p["id"]: p for p in plates}
    gauges = [float(g) for g in args.gauges.split(",")]
    problems = []

    # Gauges.
    for p in plates:
        if not any(abs(p["thickness"] - g) < 1e-9 for g in gauges):
            fail(problems, f"{p['id']}: thickness {p['thickness']} is not on the gauge list")

    # Bolts.
    holes_checked, worst_axis = 0, 0.0
    for p in plates:
        other = p.get("bolted_to")
        if not p["holes"] and not other:
            continue
        if other is None or not p["holes"]:
            fail(problems, f"{p['id']}: holes without a partner or a partner without holes")
            continue
        q = by_id[other]
        b = p["bolt"]
        d0 = b["hole_diameter"]
        if HOLES.get(b["size"]) != d0:
            fail(problems, f"{p['id']}: {b['size']} hole {d0} mm, the normal clearance is {HOLES.get(b['size'])}")
        if len(p["holes"]) != len(q["holes"]):
            fail(problems, f"{p['id']}/{other}: {len(p['holes'])} and {len(q['holes'])} holes")
            continue
        nz = np.array(p["matrix"])[:3, 2]
        for hp, hq in zip(p["holes"], q["holes"]):
            a, c = world(p, hp), world(q, hq)
            off = (c - a) - np.dot(c - a, nz) * nz
            worst_axis = max(worst_axis, np.linalg.norm(off))
            if np.linalg.norm(off) > 0.01:
                fail(problems, f"{p['id']}/{other}: hole axes {np.linalg.norm(off):.4f} mm apart")
        outline = Polygon(p["outline"])
        if len(p["holes"]) < 2:
            fail(problems, f"{p['id']}: {len(p['holes'])} bolt(s): the plies can turn about one")
        largest = min(14 * min(p["thickness"], q["thickness"]), 200.0)
        for k, h in enumerate(p["holes"]):
            holes_checked += 1
            pt = Point(h)
            edge = outline.exterior.distance(pt)
            if not outline.contains(pt) or edge < 1.2 * d0 - 1e-6:
                fail(problems, f"{p['id']}: hole {k} is {edge:.2f} mm from an edge (< 1.2 d0 = {1.2 * d0:.2f})")
            if k > 0:
                pitch = math.dist(h, p["holes"][k - 1])
                if pitch < 2.2 * d0 - 1e-6:
                    fail(problems, f"{p['id']}: holes {k - 1},{k} {pitch:.2f} mm apart (< 2.2 d0)")
                if pitch > largest + 1e-6:
                    fail(problems, f"{p['id']}: holes {k - 1},{k} {pitch:.2f} mm apart "
                                   f"(> min(14 t, 200) = {largest:.2f})")
        dxf = ezdxf.readfile(folder / "parts" / f"{p['id']}.dxf")
        inner = [e for e in dxf.modelspace() if e.dxf.layer == "CUT_INNER"]
        if len(inner) != len(p["holes"]):
            fail(problems, f"{p['id']}: {len(inner)} contours on CUT_INNER for {len(p['holes'])} holes")
        for e, h in zip(inner, p["holes"]):
            pts = np.array([(v.x, v.y) for v in ezdxf.path.make_path(e).flattening(0.001)])
            centre = (pts.min(axis=0) + pts.max(axis=0)) / 2
            r = np.linalg.norm(pts - centre, axis=1)
            if np.linalg.norm(centre - h) > 0.01 or abs(r.max() - d0 / 2) > 0.01:
                fail(problems, f"{p['id']}: a CUT_INNER circle is not the hole at {h}")

    # Welds at nodes.
    positions = np.array([n["p"] for n in axes["nodes"]], dtype=np.float64)
    node_axes = np.array([n["axis"] for n in axes["nodes"]], dtype=np.float64)
    by_edge = defaultdict(list)
    for p in plates:
        by_edge[p["edge"]].append(p)
    at = defaultdict(list)
    for k, ps in by_edge.items():
        for v in ps[0]["nodes"]:
            at[v].append(k)
    reported = {n["node"]: n for n in welds["nodes"]}
    cores = {c["node"]: c for c in doc.get("cores", [])}
    pairs_checked, worst_angle, worst_gap = 0, 0.0, 0.0
    for v, edges in at.items():
        if len(edges) < 2:
            continue
        d = node_axes[v] / np.linalg.norm(node_axes[v])
        e1 = np.cross(d, [1.0, 0.0, 0.0] if abs(d[0]) < 0.9 else [0.0, 1.0, 0.0])
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(d, e1)
        sections, angle = {}, {}
        for k in edges:
            polys = []
            for p in by_edge[k]:
                pts = [((c - positions[v]) @ e1, (c - positions[v]) @ e2) for c in corners(p)]
                polys.append(Polygon(pts).convex_hull)
            sec = unary_union(polys)
            sections[k] = sec.convex_hull if isinstance(sec, MultiPolygon) else sec
            # Direction: toward the plate's other node, across the axis.
            other = [n for n in by_edge[k][0]["nodes"] if n != v]
            w = positions[other[0] if other else v] - positions[v]
            angle[k] = math.atan2(w @ e2, w @ e1)
        order = sorted(edges, key=lambda k: angle[k])
        wedges = []
        for i, a in enumerate(order):
            b = order[(i + 1) % len(order)]
            wd = math.degrees((angle[b] - angle[a]) % (2 * math.pi))
            if wd == 0.0:
                wd = 360.0
            wedges.append((a, b, wd))
        node = reported.get(v)
        if node is None:
            fail(problems, f"node {v}: not in welds.json")
            continue
        adjacent = {frozenset((a, b)) for a, b, _ in wedges}
        for i, a in enumerate(edges):
            for b in edges[i + 1:]:
                g = sections[a].distance(sections[b])
                if frozenset((a, b)) in adjacent:
                    pairs_checked += 1
                    off = abs(g - args.weld_gap)
                    if node["status"] == "even":
                        worst_gap = max(worst_gap, off)
                        if off > args.tolerance + 1e-6:
                            fail(problems, f"node {v}: edges {a},{b} root gap {g:.3f} mm, not reported")
                if node["core"] is None and g < args.weld_gap - args.tolerance - 1e-6:
                    fail(problems, f"node {v}: edges {a},{b} only {g:.3f} mm apart")
        if node["core"] is not None:
            c = cores[v]
            for k in edges:
                g = sections[k].distance(Point(0, 0)) - c["outer_diameter"] / 2
                if abs(g - args.weld_gap) > args.tolerance + 1e-6:
                    fail(problems, f"node {v}: edge {k} is {g:.3f} mm from the core")
        listed = {(p["edges"][0], p["edges"][1]): p["dihedral_deg"] for p in node["pairs"]}
        for a, b, wd in wedges:
            got = listed.get((a, b))
            if got is None and len(edges) == 2:
                got = listed.get((b, a)) if (b, a) in listed and abs(listed[(b, a)] - wd) < 0.01 else None
            if got is None:
                fail(problems, f"node {v}: the pair {a}→{b} ({wd:.2f}°) is not in welds.json")
                continue
            worst_angle = max(worst_angle, abs(got - wd))
            if abs(got - wd) > 0.01:
                fail(problems, f"node {v}: dihedral {a}→{b} {got:.4f}° in welds.json, {wd:.4f}° here")
    if problems:
        for p in problems[:20]:
            print(f"check_shop: FAILED: {folder}: {p}", file=sys.stderr)
        sys.exit(1)
    uneven = sum(1 for n in welds["nodes"] if n["status"] != "even")
    print(f"{folder}: ok ({len(plates)} plates on the gauge list, {holes_checked} holes, hole axes "
          f"within {worst_axis:.1e} mm, {pairs_checked} adjacent pairs, even gaps within "
          f"{worst_gap:.3f} mm of {args.weld_gap}, {uneven} node(s) reported, dihedral angles "
          f"within {worst_angle:.1e}°)")


main()
