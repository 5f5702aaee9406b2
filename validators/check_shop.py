"""Checks what a steel shop needs of `lamina plates` output, with numpy and shapely, sharing no
code with lamina:

- every plate's thickness is on the gauge list given here;
- every bolted pair: the same number of holes, each hole's axis (its centre along the plate
  normal, in 3D) the same line in both plies within 0.01 mm; the hole diameter is the normal
  clearance hole of the bolt size (EN 1090-2 Table 11, ISO 273 below M12); every hole centre
  at least e1 = e2 = 1.2 d0 from every edge of the plate, at least two bolts a seam,
  neighbouring holes at least p1 = 2.2 d0 and at most min(14 t, 200 mm) apart for the thinner
  ply t (EN 1993-1-8 Table 3.3); the part DXF has the holes on CUT_INNER;
- a node's assembly group is that of the unbolted plates there (of a node with seams only, the
  group every seam there has a ply in); a seam's plies are in two groups;
- every plate's weld partners (plates.json `welded_to`) at a node are exactly the other plates of
  the node's group there, and a ply has none at the other group's node (nor a core): no weld
  joins two groups; welds.json names at each node the plate of the node's group per edge;
- at every node (positions and axes from axes.json): the plates welded there (of a seam, its ply
  of the node's group) projected along the node axis; side by side around the axis, every
  pair's root gap (shapely distance of the projections) is within the weld gap ± tolerance,
  unless welds.json reports the node (needing a core, or with one: then every plate is the gap
  from the core's tube); no other pair is closer than the gap less the tolerance; a seam's
  other ply passes the node at least the weld gap plus the thickness of its partner ply (which
  welds there; less 0.01 mm for the panels' flattening) from every welded plate, the core and
  every other passing ply (room for the leg of that ply's fillet);
- each pair of plates side by side at a node is listed once (a two-plate node's pair too), its
  angle (between the two plates, 0–180°) equal to the one computed here to 0.01°, its access
  class that of this angle, and welds.json's counts by class those of the angles here;
- every bolt can be fitted and tightened: on the stack's face the nut is on (+z, or −z for the
  holes in `nut_below`) the washer, nut and two threads, and a socket over the nut (radius and
  reach from --bolt-clearance, else the nut's corners plus 3 mm and 40 mm), on the other face
  the washer and head (ISO 7089, 4032, 4017 sizes), as cylinders on the hole's axis, cross no
  other plate or core: each cylinder as the 128-gon inside it (so a crossing found is a true
  one, and the true cylinder is missed by at most 4e-4 of its radius) against each plate's
  prism, tested by a linear program (the deepest point inside both, scipy's HiGHS).

    check_shop.py PLATES_DIR AXES_JSON --gauges ... --weld-gap 1 --tolerance 0.5 [--bolt-clearance R:H]

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
from shapely.geometry import Point, Polygon

# Bolt: (d, d0).
HOLES = {"M6": 6.6, "M8": 9.0, "M10": 11.0, "M12": 13.0, "M14": 15.0, "M16": 18.0,
         "M20": 22.0, "M22": 24.0, "M24": 26.0, "M27": 30.0, "M30": 33.0}


# Weld access by the angle between two plates: below 60°, 60–120°, 120–135°, 135–180°.
CLASS_PREFIX = ["below 60°", "60–120°", "120–135°", "135–180°"]


def weld_class(angle):
    return 0 if angle < 60.0 else 1 if angle <= 120.0 else 2 if angle <= 135.0 else 3


def fail(problems, msg):
    problems.append(msg)


def world(p, xy, z=0.0):
    m = np.array(p["matrix"], dtype=np.float64)
    return m[:3, :3] @ np.array([xy[0], xy[1], z]) + m[:3, 3]


def corners(p):
    """The plate's prism corners in 3D."""
    t = p["thickness"] / 2
    return [world(p, q, z) for q in p["outline"] for z in (-t, t)]


# Bolt: thread pitch, washer OD and thickness (ISO 7089), nut height and width across flats
# (ISO 4032), head height (ISO 4017).
FASTENERS = {"M6": (1.0, 12, 1.6, 5.2, 10, 4.0), "M8": (1.25, 16, 1.6, 6.8, 13, 5.3),
             "M10": (1.5, 20, 2.0, 8.4, 16, 6.4), "M12": (1.75, 24, 2.5, 10.8, 18, 7.5),
             "M16": (2.0, 30, 3.0, 14.8, 24, 10.0), "M20": (2.5, 37, 3.0, 18.0, 30, 12.5),
             "M22": (2.5, 39, 3.0, 19.4, 34, 14.0), "M24": (3.0, 44, 4.0, 21.5, 36, 15.0),
             "M27": (3.0, 50, 4.0, 23.8, 41, 17.0), "M30": (3.5, 56, 4.0, 25.6, 46, 18.7)}


def halfspaces_prism(corners2d, origin, ex, ey, ez, z0, z1):
    """A x <= b rows (unit normals) of a convex outline in a frame, between heights z0, z1."""
    rows, rhs = [], []
    pts = [origin + ex * p[0] + ey * p[1] for p in corners2d]
    area = sum(corners2d[i][0] * corners2d[(i + 1) % len(corners2d)][1] -
               corners2d[(i + 1) % len(corners2d)][0] * corners2d[i][1] for i in range(len(corners2d)))
    sign = 1.0 if area > 0 else -1.0
    for i in range(len(pts)):
        a, b = pts[i], pts[(i + 1) % len(pts)]
        out = np.cross(b - a, ez) * sign
        n = np.linalg.norm(out)
        if n < 1e-12:
            continue
        out /= n
        rows.append(out)
        rhs.append(out @ a)
    rows += [ez, -ez]
    rhs += [ez @ origin + z1, -(ez @ origin + z0)]
    return np.array(rows), np.array(rhs)


def deepest(shapes):
    """The largest t with a point t inside every shape's half-spaces (negative: apart)."""
    from scipy.optimize import linprog
    a = np.vstack([np.hstack([r, np.ones((len(r), 1))]) for r, _ in shapes])
    b = np.concatenate([h for _, h in shapes])
    res = linprog([0, 0, 0, -1], A_ub=a, b_ub=b, bounds=[(None, None)] * 3 + [(None, 1.0)],
                  method="highs")
    return -res.fun if res.status == 0 else -math.inf


def bolt_room(plates, by_id, cores, clearance, problems):
    """Every bolt's washer, head, nut and socket clear of every other plate and core."""
    n = 128
    circle = [(math.cos(2 * math.pi * i / n), math.sin(2 * math.pi * i / n)) for i in range(n)]

    def cylinder(base, axis, r, length):
        u = np.cross(axis, [1.0, 0, 0] if abs(axis[0]) < 0.9 else [0, 1.0, 0])
        u /= np.linalg.norm(u)
        v = np.cross(axis, u)
        shape = halfspaces_prism([(r * c, r * s) for c, s in circle], base, u, v, axis, 0.0, length)
        return shape, base + axis * length / 2, math.hypot(r, length / 2)

    solids = []
    for p in plates:
        m = np.array(p["matrix"], dtype=float)
        ex, ey, ez, o = m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3]
        t = p["thickness"] / 2
        shape = halfspaces_prism(p["outline"], o, ex, ey, ez, -t, t)
        pts = [o + ex * q[0] + ey * q[1] for q in p["outline"]]
        c = np.mean(pts, axis=0)
        solids.append((p["id"], shape, c, max(np.linalg.norm(q - c) for q in pts) + t))
    for c in cores:
        axis = np.array(c["axis"], dtype=float)
        solids.append((c["id"],) + cylinder(np.array(c["base"], dtype=float), axis,
                                            c["outer_diameter"] / 2, c["length"]))
    fitted = 0
    for p in plates:
        other = p.get("bolted_to")
        if not other or p["id"] > other:
            continue
        q = by_id[other]
        m = np.array(p["matrix"], dtype=float)
        ez = m[:3, 2]
        faces = [np.array(x["matrix"], dtype=float)[:3, 3] @ ez + sgn * x["thickness"] / 2
                 for x in (p, q) for sgn in (-1, 1)]
        low, high = min(faces), max(faces)
        b = p["bolt"]
        pitch, w_od, w_h, nut_h, flats, head_h = FASTENERS[b["size"]]
        corners = flats / math.sqrt(3)
        fit_r = max(w_od / 2, corners)
        if clearance:
            r_s, h_s = (float(v) for v in clearance.split(":"))
        else:
            r_s, h_s = corners + 3.0, 40.0
        below = set(b.get("nut_below", []))
        for k, h in enumerate(p["holes"]):
            centre = m[:3, :3] @ np.array([h[0], h[1], 0.0]) + m[:3, 3]
            on_axis = centre - (centre @ ez) * ez
            if k in below:
                head_at, nut_at, out = high, low, -ez
            else:
                head_at, nut_at, out = low, high, ez
            envelopes = [
                ("head and washer", cylinder(on_axis + ez * head_at, -out, fit_r, w_h + head_h)),
                ("nut and washer", cylinder(on_axis + ez * nut_at, out, fit_r, w_h + nut_h + 2 * pitch)),
                ("socket", cylinder(on_axis + ez * nut_at + out * w_h, out, r_s, h_s)),
            ]
            hit = None
            for name, (shape, c, rad) in envelopes:
                for sid, sshape, sc, srad in solids:
                    if sid in (p["id"], other) or np.linalg.norm(c - sc) > rad + srad:
                        continue
                    depth = deepest([shape, sshape])
                    if depth > 1e-6:
                        hit = f"{name} {depth:.3f} mm into {sid}"
                        break
                if hit:
                    break
            listed = b.get("clashes", [])
            if hit:
                fail(problems, f"{p['id']}/{other} hole {k}: the {hit}" +
                     (" (reported)" if any(c.startswith(f"hole {k}:") for c in listed) else
                      ", not reported"))
            else:
                fitted += 1
    return fitted, None


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("plates_dir")
    ap.add_argument("axes")
    ap.add_argument("--gauges", required=True)
    ap.add_argument("--weld-gap", type=float, required=True)
    ap.add_argument("--tolerance", type=float, required=True)
    ap.add_argument("--bolt-clearance", help="RADIUS:REACH of the socket, mm")
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

    # Groups of the nodes, and weld partners only within them.
    node_group, seam_groups = {}, defaultdict(list)
    for p in plates:
        if p.get("bolted_to") is None:
            for v in p["nodes"]:
                if node_group.setdefault(v, p["group"]) != p["group"]:
                    fail(problems, f"node {v}: plates of groups {node_group[v]} and {p['group']} meet unbolted")
    for p in plates:
        if p.get("bolted_to") is not None:
            q = by_id[p["bolted_to"]]
            if q["group"] == p["group"] or q.get("bolted_to") != p["id"]:
                fail(problems, f"{p['id']}/{q['id']}: a seam's plies are not a pair in two groups")
            for v in p["nodes"]:
                seam_groups[v].append({p["group"], q["group"]})
    for v, sets in seam_groups.items():
        if v not in node_group:
            common = set.intersection(*sets)
            if len(common) != 1:
                fail(problems, f"node {v}: only seams meet there and their groups {sets} leave its group open")
                continue
            node_group[v] = common.pop()
    at_node = defaultdict(list)
    for p in plates:
        for v in p["nodes"]:
            at_node[v].append(p)
    cross = 0
    for p in plates:
        for end in p["ends"]:
            v, g = end["node"], node_group.get(end["node"])
            want = set() if p["group"] != g else \
                {q["id"] for q in at_node[v] if q["id"] != p["id"] and q["group"] == g}
            got = set(end["welded_to"])
            cross += sum(1 for i in got if i not in by_id or by_id[i]["group"] != p["group"])
            if end.get("core") is not None:
                if p["group"] != g:
                    fail(problems, f"{p['id']}: welded to the core at node {v}, of another group")
                continue
            if got != want:
                fail(problems, f"{p['id']} at node {v} (group {g}): welded to {sorted(got)}, "
                               f"the group's plates there are {sorted(want)}")

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
    class_counts = [0, 0, 0, 0]
    passes_checked, worst_pass = 0, math.inf
    for v, edges in at.items():
        if len(edges) < 2:
            continue
        d = node_axes[v] / np.linalg.norm(node_axes[v])
        e1 = np.cross(d, [1.0, 0.0, 0.0] if abs(d[0]) < 0.9 else [0.0, 1.0, 0.0])
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(d, e1)
        sections, angle, passing = {}, {}, {}

        def section(p):
            pts = [((c - positions[v]) @ e1, (c - positions[v]) @ e2) for c in corners(p)]
            return Polygon(pts).convex_hull

        g = node_group.get(v)
        for k in edges:
            mine = [p for p in by_edge[k] if p["group"] == g]
            if len(mine) != 1:
                fail(problems, f"node {v}: edge {k} has {len(mine)} plates of the node's group {g}")
                mine = by_edge[k][:1]
            sections[k] = section(mine[0])
            for p in by_edge[k]:
                if p is not mine[0]:
                    passing[k] = (p["id"], section(p), mine[0]["thickness"])
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
                gap = sections[a].distance(sections[b])
                if frozenset((a, b)) in adjacent:
                    pairs_checked += 1
                    off = abs(gap - args.weld_gap)
                    if node["status"] == "even":
                        worst_gap = max(worst_gap, off)
                        if off > args.tolerance + 1e-6:
                            fail(problems, f"node {v}: edges {a},{b} root gap {gap:.3f} mm, not reported")
                if node["core"] is None and gap < args.weld_gap - args.tolerance - 1e-6:
                    fail(problems, f"node {v}: edges {a},{b} only {gap:.3f} mm apart")
        if node["core"] is not None:
            c = cores[v]
            for k in edges:
                gc = sections[k].distance(Point(0, 0)) - c["outer_diameter"] / 2
                if abs(gc - args.weld_gap) > args.tolerance + 1e-6:
                    fail(problems, f"node {v}: edge {k} is {gc:.3f} mm from the core")
        # The plies passing unwelded: clear of every weld here.
        seen = []
        for k, (pid, sec, t_welded) in passing.items():
            clear = args.weld_gap + t_welded
            passes_checked += 1
            near = [sections[j].distance(sec) for j in edges if j != k] + [o.distance(sec) for o in seen]
            if node["core"] is not None:
                near.append(sec.distance(Point(0, 0)) - cores[v]["outer_diameter"] / 2)
            seen.append(sec)
            worst_pass = min(worst_pass, min(near) - clear)
            # Within the panels' flattening (the plate's plane holds its second node's axis to
            # the flattening plates.json reports, some micrometres).
            if min(near) < clear - 0.01:
                fail(problems, f"node {v}: {pid} passes {min(near):.3f} mm from a plate welded there "
                               f"(< gap + its welded partner's thickness = {clear:.3f})")
        names = [next((p["id"] for p in by_edge[k] if p["group"] == g), "?") for k in node["edges"]] \
            if "edges" in node else None
        if names is not None and names != node["plates"]:
            fail(problems, f"node {v}: welds.json names {node['plates']}, the plates of its group are {names}")
        # One angle per pair of neighbours, between the two plates (0–180°): a wedge wider than
        # 180° is the outside of a corner, measured the other way round.
        mine = {}
        for a, b, wd in wedges:
            mine.setdefault(frozenset((a, b)), min(wd, 360.0 - wd))
        listed = {}
        for p in node["pairs"]:
            key = frozenset(p["edges"])
            if key in listed:
                fail(problems, f"node {v}: the pair {sorted(key)} is listed twice in welds.json")
            listed[key] = p
        for key in listed:
            if key not in mine:
                fail(problems, f"node {v}: welds.json lists the pair {sorted(key)}, not neighbours here")
        for key, angle in sorted(mine.items(), key=lambda t: sorted(t[0])):
            p = listed.get(key)
            if p is None:
                fail(problems, f"node {v}: the pair {sorted(key)} ({angle:.2f}°) is not in welds.json")
                continue
            got = p["dihedral_deg"]
            worst_angle = max(worst_angle, abs(got - angle))
            if abs(got - angle) > 0.01:
                fail(problems, f"node {v}: pair {sorted(key)} at {got:.4f}° in welds.json, {angle:.4f}° here")
            cls = weld_class(angle)
            class_counts[cls] += 1
            if not p["access"].startswith(CLASS_PREFIX[cls]):
                fail(problems, f"node {v}: pair {sorted(key)} at {angle:.2f}° is '{p['access']}' in welds.json")
    summary = welds["summary"]
    said = [summary["pairs_below_60"], summary["pairs_60_120"], summary["pairs_120_135"],
            summary["pairs_over_135"]]
    if said != class_counts:
        fail(problems, f"welds.json counts {said} pairs by class (below 60°, 60–120°, 120–135°, "
                       f"135–180°), the pairs here give {class_counts}")
    fitted, clear_by = bolt_room(plates, by_id, doc.get("cores", []), args.bolt_clearance, problems)
    if problems:
        for p in problems[:20]:
            print(f"check_shop: FAILED: {folder}: {p}", file=sys.stderr)
        sys.exit(1)
    uneven = sum(1 for n in welds["nodes"] if n["status"] != "even")
    print(f"{folder}: ok ({len(plates)} plates on the gauge list, {holes_checked} holes, hole axes "
          f"within {worst_axis:.1e} mm, {pairs_checked} adjacent pairs, even gaps within "
          f"{worst_gap:.3f} mm of {args.weld_gap}, {uneven} node(s) reported, dihedral angles "
          f"within {worst_angle:.1e}°, by class {class_counts}; weld partners within their group, {cross} across; "
          f"{passes_checked} plies passing the other group's node, clear by "
          f"{'—' if passes_checked == 0 else f'{worst_pass:+.3f} mm over the gap + the welded ply'}; "
          f"{fitted} bolts with room for washer, head, nut and socket)")


main()
