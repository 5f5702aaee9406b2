"""Checks `lamina size` output against the axes it sized, sharing no code with lamina (numpy):

- every gauge is on the sizing's gauge list (a seam's two plies each), every utilisation at most 1;
- equilibrium: the reactions balance the applied loads, recomputed here from the axes file —
  self-weight as each panel's area (the quad from its node axes) × gauge × density × g, down
  (or, where sizing.json says `joints`, each member's `mass_kg` as cut — never more than the
  uncut panel — and its `bolts_kg`, and each node's `core_kg` at the node);
  point loads on the nodes given; wind as the pressure on each panel's area projected across
  the wind (area × |normal · direction|, the normal from the quad's diagonals), along it —
  in force and in moment about the origin, to 1e-9 of the load (plus 1e-6 of the wind: the
  panels are planar only to planarize's tolerance, and lamina takes the normal from the
  member's frame). The frame's self-weight acts along its members; shells' (sizing.json
  "analysis": {"shells": N}) at each panel's centroid, known to within the panel's warp, which
  the moment check allows;
- `--lower-thicker`: the mean gauge of the lowest third of the members (by mid-height) is above
  that of the highest third (Calyx's observation of its own structural analysis).

    check_sizing.py axes.json sizing.json [--self-weight] [--wind KPA:DX,DY,DZ]
                    [--point NODE:FX,FY,FZ]... [--lower-thicker]
"""
import argparse
import json
import sys

import numpy as np

G = 9.80665


def fail(msg):
    print(f"check_sizing: FAILED: {msg}", file=sys.stderr)
    sys.exit(1)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("axes")
    ap.add_argument("sizing")
    ap.add_argument("--self-weight", action="store_true", help="the only load was self-weight")
    ap.add_argument("--wind", help="KPA:DX,DY,DZ, as given to lamina size")
    ap.add_argument("--point", action="append", default=[], help="NODE:FX,FY,FZ (one node)")
    ap.add_argument("--lower-thicker", action="store_true")
    args = ap.parse_args()
    axes = json.load(open(args.axes))
    s = json.load(open(args.sizing))
    nodes = axes["nodes"]
    edges = axes["edges"]
    if len(s["edges"]) != len(edges):
        fail(f"{len(s['edges'])} sized edges for {len(edges)} axes edges")
    gauges = set(s["gauges"])
    for k, e in enumerate(s["edges"]):
        # A bolted seam (sized for plates' groups) is two plies on the list adding up to it.
        plies = e.get("plies") or [e["gauge"]]
        if any(t not in gauges for t in plies) or abs(sum(plies) - e["gauge"]) > 1e-9:
            fail(f"edge {k}: gauge {e['gauge']} (plies {plies}) is not on the list {sorted(gauges)}")
        if (e["a"], e["b"]) != (edges[k]["a"], edges[k]["b"]):
            fail(f"edge {k}: nodes {e['a']}-{e['b']}, the axes say {edges[k]['a']}-{edges[k]['b']}")
    worst = max(e["utilisation"] for e in s["edges"])
    if worst > 1.0:
        fail(f"a member is utilised {worst:.3f} > 1")

    # Applied loads and where they act, from the axes alone.
    p = np.array([n["p"] for n in nodes], dtype=float)
    d = np.array([n["axis"] for n in nodes], dtype=float)
    h = np.array([n["height"] for n in nodes], dtype=float)
    mid = p + d * (h[:, None] / 2.0)
    # The panels as shells carry their weight where it is; the frame along its members.
    shells = isinstance(s.get("analysis"), dict) and "shells" in s["analysis"]
    force = np.zeros(3)
    moment = np.zeros(3)
    warp_moment = 0.0
    if args.self_weight:
        rho = s["material"]["density"] * 1e-6  # kg/mm³
        # Weighed as cut (`joints` given): each member's plates, its bolt sets along it, node
        # cores at their nodes.
        as_cut = s.get("joints") is not None
        for i, n in enumerate(s["nodes"]):
            if as_cut and n.get("core_kg"):
                f = np.array([0.0, 0.0, -n["core_kg"] * G])
                force += f
                moment += np.cross(mid[i], f)
        for k, e in enumerate(edges):
            a, b = e["a"], e["b"]
            quad = [p[a], p[b], p[b] + d[b] * h[b], p[a] + d[a] * h[a]]
            area = 0.5 * np.linalg.norm(np.cross(quad[2] - quad[0], quad[3] - quad[1]))
            uncut = area * s["edges"][k]["gauge"] * rho
            if as_cut:
                # The plates as cut (check_opensees --plates checks them against plates.json):
                # never more steel than the uncut panel, then the seam's bolt sets.
                steel = s["edges"][k]["mass_kg"]
                if not 0.0 < steel <= uncut * (1.0 + 1e-9):
                    fail(f"edge {k}: {steel} kg as cut, the uncut panel {uncut} kg")
                weight = (steel + (s["edges"][k].get("bolts_kg") or 0.0)) * G
            else:
                weight = uncut * G
            f = np.array([0.0, 0.0, -weight])
            if shells:
                # The panel's own weight: its resultant at the quad's centroid (two triangles).
                t1 = 0.5 * np.linalg.norm(np.cross(quad[1] - quad[0], quad[2] - quad[0]))
                t2 = 0.5 * np.linalg.norm(np.cross(quad[2] - quad[0], quad[3] - quad[0]))
                centre = (t1 * (quad[0] + quad[1] + quad[2]) + t2 * (quad[0] + quad[2] + quad[3])) \
                    / (3 * (t1 + t2))
                # A warped quad has no one centroid: its weight acts somewhere within its warp
                # (the fourth corner's distance from the plane of the other three).
                n3 = np.cross(quad[1] - quad[0], quad[3] - quad[0])
                warp_moment += weight * abs((quad[2] - quad[0]) @ n3) / np.linalg.norm(n3)
            else:
                # A uniform load along the member: its resultant at the member's middle.
                centre = 0.5 * (mid[a] + mid[b])
            force += f
            moment += np.cross(centre, f)
    wind_size = 0.0
    if args.wind:
        kpa, direction = args.wind.split(":")
        d_w = np.array([float(v) for v in direction.split(",")])
        d_w /= np.linalg.norm(d_w)
        for k, e in enumerate(edges):
            a, b = e["a"], e["b"]
            quad = [p[a], p[b], p[b] + d[b] * h[b], p[a] + d[a] * h[a]]
            cross = np.cross(quad[2] - quad[0], quad[3] - quad[1])
            area = 0.5 * np.linalg.norm(cross)
            normal = cross / np.linalg.norm(cross)
            f = float(kpa) * 1e-3 * area * abs(normal @ d_w) * d_w
            force += f
            moment += np.cross(0.5 * (mid[e["a"]] + mid[e["b"]]), f)
            wind_size += np.linalg.norm(f)
    for spec in args.point:
        node, values = spec.split(":")
        f = np.array([float(v) for v in values.split(",")])
        force += f
        moment += np.cross(mid[int(node)], f)
    scale = max(np.linalg.norm(force), 1e-300)
    rf = np.zeros(3)
    rm = np.zeros(3)
    for r in s["reactions"]:
        f = np.array(r["force"])
        rf += f
        rm += np.array(r["moment"]) + np.cross(mid[r["node"]], f)
    size = np.ptp(mid, axis=0).max()
    allowed = 1e-9 * scale + 1e-6 * wind_size
    if np.linalg.norm(rf + force) > allowed:
        fail(f"reactions {rf} do not balance the loads {force}")
    if np.linalg.norm(rm + moment) > allowed * size + warp_moment:
        fail(f"reaction moments {rm} do not balance the loads' {moment}")
    line = (f"{args.sizing}: ok ({len(edges)} members, gauges on the list, utilisation at most "
            f"{worst:.3f}, reactions balance {np.linalg.norm(force):.2f} N to "
            f"{np.linalg.norm(rf + force) / scale:.1e}")
    if args.lower_thicker:
        z = np.array([0.5 * (mid[e["a"]][2] + mid[e["b"]][2]) for e in edges])
        order = np.argsort(z, kind="stable")
        third = len(order) // 3
        g = np.array([e["gauge"] for e in s["edges"]])
        low, high = g[order[:third]].mean(), g[order[-third:]].mean()
        if not low > high:
            fail(f"the lowest third's mean gauge {low:.3f} mm is not above the highest's {high:.3f}")
        line += f"; mean gauge lowest third {low:.3f} mm, highest {high:.3f} mm"
    print(line + ")")


main()
