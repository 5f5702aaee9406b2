"""Checks a nesting folder (`lamina nest ... -o DIR`) with ezdxf and shapely, sharing no code
with lamina.

- Every sheet DXF audits clean, is R2000 or later in mm ($INSUNITS = 4), has its sheet outline
  on SHEET, parts as closed counter-clockwise LWPOLYLINEs on CUT_OUTER, holes as closed
  clockwise ones on CUT_INNER, etching as LWPOLYLINEs on ETCH, lead lines only on LEAD,
  remnants on REMNANT, and no TEXT or MTEXT anywhere.
- File order: all etching first (tags and the sheet and remnant labels, while every part is held
  by the sheet), then per part its inner contours, then its outer contour (each inside the outer
  one that follows). Each etched polyline lies on one part, or is a label in the scrap: at
  least the spacing from every part.
- Micro-joints (`--micro-joints N`): the outer contour of every part whose bounding box's longer
  side is under `--micro-joint-below` is N open LWPOLYLINEs in a row, each starting the joint's
  width after the last one ended and the last ending where the first began; every gap lies on a
  straight side at least `clear_mm` (nest.json) from the part's corners, and is drawn across on
  JOINT; larger parts have one closed contour. Without the flag every contour is closed.
- Every placement's rotation is one of the allowed angles, bit for bit, and the part on the
  sheet is the plate's outline turned by it and moved by the offset (within 1e-6 mm).
- Remnants lie on their sheet, at least the spacing from every part, at least the minimum size.
  Where nest.json's first remnant runs right across the sheet, the rest of the sheet (the strip)
  holds every part and nest.json's `strip` gives its direction, length and utilisation; without
  such a remnant there is no `strip`.
- Every part lies inside its sheet less the margin; any two parts on a sheet are at least the
  spacing apart (shapely distances, an STRtree for neighbours), except the two parts of a
  common line (nest.json's `common_lines`, `--common-line`): those are at least the kerf apart,
  the line lies half the kerf off both parts at every point (sampled every 0.05 mm, within
  0.003 mm) and each of its ends half the kerf straight off a corner of each (a whole side
  shared), and
  the line is counted once in the cut length (the DXFs draw both sides).
- Parts in all sheets = BOM rows = plates in plates.json; the part areas match the plates'
  areas one to one; each BOM row's sheet and mass agree with the plate.
- nest.json's utilisation per sheet and in total is recomputed from the DXF polygons, and its
  cut and etched lengths (`cut_mm`, `etch_mm`) from the polylines drawn (contours as cut,
  holes as their polygons, micro-joint gaps left out, lead lines counted).
"""

import argparse
import csv
import json
import math
import sys
from pathlib import Path

import ezdxf
import numpy as np
import shapely
from ezdxf import recover
from shapely import STRtree
from shapely.geometry import LineString, Point, Polygon, box

# A common line's parts: half the kerf off the line within this, mm (lamina pairs sides whose
# ends meet within 0.002 mm).
COMMON_TOL = 0.003
STAINLESS = ("1.40", "1.41", "1.42", "1.43", "1.44", "1.45", "1.46")  # EN 10088 numbers


def header_comment(path):
    """The DXF's leading comments (group 999), joined."""
    lines = open(path, encoding="utf-8", newline="").read().splitlines()
    out = []
    for code, value in zip(lines[0::2], lines[1::2]):
        if code.strip() != "999":
            break
        out.append(value)
    return " ".join(out)


def fail(msg):
    print(f"check_nest: FAILED: {msg}", file=sys.stderr)
    sys.exit(1)


def flat(e):
    return [(v.x, v.y) for v in ezdxf.path.make_path(e).flattening(0.001)]


def signed_area(pts):
    return 0.5 * sum(x0 * y1 - x1 * y0 for (x0, y0), (x1, y1) in zip(pts, pts[1:] + pts[:1]))


def sheet_polygons(path, width, height, joint_width=None):
    doc, auditor = recover.readfile(path)
    if auditor.has_errors:
        fail(f"{path}: ezdxf audit errors: {[str(e) for e in auditor.errors][:3]}")
    if doc.dxfversion < "AC1015":
        fail(f"{path}: DXF version {doc.dxfversion} is older than R2000")
    if doc.header.get("$INSUNITS") != 4:
        fail(f"{path}: $INSUNITS is {doc.header.get('$INSUNITS')}, not 4 (mm)")
    msp = doc.modelspace()
    if len(msp.query("TEXT MTEXT")):
        fail(f"{path}: live text found")
    sheet = [e for e in msp.query("LWPOLYLINE") if e.dxf.layer == "SHEET"]
    if len(sheet) != 1:
        fail(f"{path}: {len(sheet)} sheet outlines on SHEET, expected 1")
    s = Polygon([(x, y) for x, y, *_ in sheet[0].get_points()])
    if abs(s.area - width * height) > 1e-6 * width * height:
        fail(f"{path}: sheet outline area {s.area} is not {width} × {height}")
    parts, holes, remnants, gaps, joint_lines = [], [], [], [], []
    etch, inner, etched = [], [], 0
    pieces = []
    # Lengths as drawn: the cut (outer and inner contours, lead lines) and the etching, mm.
    lengths = {"cut": 0.0, "etch": 0.0}

    def close_part(pts, part_gaps):
        if signed_area(pts) <= 0:
            fail(f"{path}: an outer contour runs clockwise")
        p = Polygon(pts)
        if not p.is_valid or p.area <= 0:
            fail(f"{path}: a CUT_OUTER outline is not a valid polygon")
        for h in inner:
            if not p.contains(h):
                fail(f"{path}: an inner contour before part {len(parts)} is not inside it")
        holes.extend(inner)
        parts.append(Polygon(pts, [list(h.exterior.coords) for h in inner]))
        gaps.append(part_gaps)

    for e in msp:
        layer = e.dxf.layer
        if layer in ("CUT_OUTER", "CUT_INNER", "ETCH", "LEAD", "REMNANT") and e.dxftype() != "LWPOLYLINE":
            fail(f"{path}: {layer} holds a {e.dxftype()}")
        if layer in ("CUT_OUTER", "CUT_INNER", "LEAD", "ETCH"):
            pts = [(x, y) for x, y, *_ in e.get_points()]
            if any(b for *_, b in e.get_points("xyb")):
                fail(f"{path}: a {layer} polyline has bulges")
            run = sum(math.dist(a, b) for a, b in zip(pts, pts[1:]))
            if e.closed and len(pts) > 1:
                run += math.dist(pts[-1], pts[0])
            lengths["etch" if layer == "ETCH" else "cut"] += run
        if layer == "CUT_OUTER":
            pts = [(x, y) for x, y, *_ in e.get_points()]
            if e.closed:
                if pieces:
                    fail(f"{path}: a closed outer contour inside the open pieces of another")
                close_part(pts, [])
            else:
                if joint_width is None:
                    fail(f"{path}: an outer contour is not closed (no micro-joints were asked for)")
                if pieces:
                    gap = math.dist(pieces[-1][-1], pts[0])
                    if abs(gap - joint_width) > 1e-6:
                        fail(f"{path}: a micro-joint gap of {gap:.6f} mm, not {joint_width}")
                pieces.append(pts)
                if math.dist(pts[-1], pieces[0][0]) < 1e-6:
                    if len(pieces) < 2:
                        fail(f"{path}: an open outer contour that closes on itself")
                    ring = [q for piece in pieces for q in piece][:-1]
                    part_gaps = [(a[-1], b[0]) for a, b in zip(pieces, pieces[1:])]
                    close_part(ring, part_gaps)
                    pieces = []
            inner = []
            continue
        if pieces:
            fail(f"{path}: a {layer} entity between the open pieces of an outer contour")
        if layer == "JOINT":
            joint_lines.append(tuple((x, y) for x, y, *_ in e.get_points()))
        elif layer == "CUT_INNER":
            if not e.closed:
                fail(f"{path}: an inner contour is not closed")
            pts = flat(e)
            if signed_area(pts) >= 0:
                fail(f"{path}: an inner contour runs counter-clockwise")
            inner.append(Polygon(pts))
        elif layer == "ETCH":
            if inner or parts:
                fail(f"{path}: etching after cutting began (part {len(parts)}): all etching comes first")
            etch.append(LineString([(x, y) for x, y, *_ in e.get_points()]))
            etched += 1
        elif layer == "REMNANT":
            remnants.append(Polygon([(x, y) for x, y, *_ in e.get_points()]))
        elif layer not in ("SHEET", "LEAD", "JOINT"):
            fail(f"{path}: unexpected layer {layer}")
    if inner:
        fail(f"{path}: inner contours after the last outer contour")
    if pieces:
        fail(f"{path}: open outer pieces that never close")
    drawn_gaps = sorted(tuple(sorted(g)) for part in gaps for g in part)
    drawn_joints = sorted(tuple(sorted(j)) for j in joint_lines)
    if len(drawn_gaps) != len(drawn_joints) or any(
            math.dist(a[0], b[0]) > 1e-6 or math.dist(a[1], b[1]) > 1e-6
            for a, b in zip(drawn_gaps, drawn_joints)):
        fail(f"{path}: JOINT lines ({len(drawn_joints)}) are not the micro-joint gaps ({len(drawn_gaps)})")
    return parts, etched, remnants, gaps, lengths, etch


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("folder")
    ap.add_argument("plates", help="the plates.json that was nested")
    ap.add_argument("--sheet", required=True, help="WIDTHxHEIGHT, mm")
    ap.add_argument("--margin", type=float, required=True)
    ap.add_argument("--spacing", type=float, required=True)
    ap.add_argument("--rotations", default="0,90,180,270", help="allowed angles, or any")
    ap.add_argument("--remnant-min", default="300x300")
    ap.add_argument("--micro-joints", type=int, help="joints per small part, as nested")
    ap.add_argument("--micro-joint-below", type=float, default=200.0)
    ap.add_argument("--micro-joint-width", type=float, default=0.5)
    args = ap.parse_args()
    joint_width = args.micro_joint_width if args.micro_joints else None
    folder = Path(args.folder)
    width, height = (float(v) for v in args.sheet.lower().split("x"))

    plates_doc = json.load(open(args.plates))
    plates = {p["id"]: p for p in plates_doc["plates"]}
    # The steel travels: plates.json's grade and density into nest.json, the BOM's grade and
    # masses, every sheet DXF's header and the speed table's family.
    grade, density = plates_doc["material"]["grade"], plates_doc["material"]["density"]
    segments = plates_doc.get("hole_segments", 48)

    def plate_area(p):
        """The outline less its holes, each the file's hole_segments-gon."""
        if not p["holes"]:
            return Polygon(p["outline"]).area
        r = p["bolt"]["hole_diameter"] / 2
        gon = 0.5 * segments * r * r * math.sin(2 * math.pi / segments)
        return Polygon(p["outline"]).area - len(p["holes"]) * gon
    nest = json.load(open(folder / "nest.json"))
    placement_of = {pl["id"]: pl for pl in nest["placements"]}

    def placed_outline(pl):
        a = pl["rotation_deg"]
        c, sn = math.cos(math.radians(a)), math.sin(math.radians(a))
        return Polygon([(c * x - sn * y + pl["offset"][0], sn * x + c * y + pl["offset"][1])
                        for x, y in plates[pl["id"]]["outline"]])
    with open(folder / "bom.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    bom = [r for r in rows if r["kind"] == "plate"]

    allowed = None if args.rotations == "any" else [float(a) % 360.0 for a in args.rotations.split(",")]
    rmin = sorted(float(v) for v in args.remnant_min.lower().split("x"))
    all_areas = []
    n_remnants = 0
    total_used = total_stock = total_cut = 0.0
    worst_gap = math.inf
    strokes = 0
    sheet_area = width * height
    last_strip = None
    for s in nest["sheets"]:
        width, height = s["size"]
        sheet_area = width * height
        inner = box(args.margin, args.margin, width - args.margin, height - args.margin)
        parts, etched, remnants, _, lengths, etch = sheet_polygons(
            folder / s["file"], width, height, joint_width)
        etch_tree = STRtree(parts)
        labels = 0
        for line in etch:
            near = etch_tree.query(line.buffer(args.spacing))
            on = [j for j in near if parts[j].buffer(1e-6).contains(line)]
            if on:
                continue
            d = min((parts[j].distance(line) for j in near), default=math.inf)
            if d < args.spacing - 1e-6:
                fail(f"{s['file']}: an etched polyline is on no part and {d:.3f} mm from one "
                     f"(a label must keep the spacing)")
            labels += 1
        if s.get("label") and labels == 0:
            fail(f"{s['file']}: nest.json gives the label {s['label']!r}, none is etched in the scrap")
        strokes += etched
        # The cut and etched lengths nest.json gives (and times the machine by) are the ones
        # drawn: every contour as the polyline cut (holes as their polygons, micro-joint gaps
        # left out), and the lead lines.
        # Common lines: two parts set the kerf apart along a whole side, the side cut once.
        kerf = nest.get("kerf_mm", 0.0)
        common_pairs = set()
        common_cut = 0.0
        for c in s.get("common_lines", []):
            a_id, b_id = c["parts"]
            twin = []
            for pid in (a_id, b_id):
                pl = placement_of.get(pid)
                if pl is None or pl["sheet"] != s["file"]:
                    fail(f"{s['file']}: common line {c['parts']}: {pid} is not on this sheet")
                want = placed_outline(pl)
                hits = [k for k, p in enumerate(parts)
                        if p.exterior.hausdorff_distance(want.exterior) < 1e-6]
                if len(hits) != 1:
                    fail(f"{s['file']}: common line {c['parts']}: {pid} is not drawn once")
                twin.append(hits[0])
            line = LineString([c["from"], c["to"]])
            if abs(line.length - c["length_mm"]) > 1e-9 * max(line.length, 1.0) or line.length <= 0:
                fail(f"{s['file']}: common line {c['parts']}: length_mm {c['length_mm']}, "
                     f"the line is {line.length}")
            if not kerf > 0:
                fail(f"{s['file']}: a common line without a kerf")
            # Every point of the line (every 0.05 mm) lies half the kerf off both parts, and
            # each end of it half the kerf off a corner of each: a whole side shared.
            n = max(2, int(line.length / 0.05) + 1)
            pts = shapely.points([line.interpolate(t, normalized=True).coords[0]
                                  for t in np.linspace(0.0, 1.0, n)])
            for k in twin:
                d = shapely.distance(parts[k].exterior, pts)
                if np.abs(d - kerf / 2).max() > COMMON_TOL:
                    fail(f"{s['file']}: common line {c['parts']} runs {d.min():.4f}–{d.max():.4f} "
                         f"mm off a part, not half the kerf {kerf / 2} ± {COMMON_TOL}")
                corners = list(parts[k].exterior.coords)[:-1]
                tx, ty = ((c["to"][0] - c["from"][0]) / line.length,
                          (c["to"][1] - c["from"][1]) / line.length)
                for end in (c["from"], c["to"]):
                    q = min(corners, key=lambda q: math.dist(end, q))
                    dx, dy = q[0] - end[0], q[1] - end[1]
                    along, across = abs(dx * tx + dy * ty), abs(dx * ty - dy * tx)
                    if along > COMMON_TOL or abs(across - kerf / 2) > COMMON_TOL:
                        fail(f"{s['file']}: common line {c['parts']} ends {along:.4f} mm along "
                             f"and {across:.4f} mm across from a part's corner: not a whole side")
            common_pairs.add(frozenset(twin))
            common_cut += line.length
        for key in ("cut", "etch"):
            drawn_len = lengths[key] - (common_cut if key == "cut" else 0.0)
            if abs(drawn_len - s[f"{key}_mm"]) > 1e-9 * max(drawn_len, 1.0):
                fail(f"{s['file']}: nest.json's {key}_mm {s[f'{key}_mm']!r} but the DXF draws "
                     f"{drawn_len!r} mm" + (" less its common lines" if key == "cut" and common_cut else ""))
        total_cut += lengths["cut"] - common_cut
        sheet_box = box(0, 0, width, height).buffer(1e-9)
        if len(remnants) != len(s["remnants"]):
            fail(f"{s['file']}: {len(remnants)} remnants drawn, nest.json lists {len(s['remnants'])}")
        for r in remnants:
            n_remnants += 1
            x0, y0, x1, y1 = r.bounds
            if not sheet_box.contains(r) or sorted((x1 - x0, y1 - y0))[0] < rmin[0] - 1e-9 \
                    or sorted((x1 - x0, y1 - y0))[1] < rmin[1] - 1e-9:
                fail(f"{s['file']}: remnant {r.bounds} is off the sheet or under {args.remnant_min}")
            for p in parts:
                if p.distance(r) < args.spacing - 1e-6:
                    fail(f"{s['file']}: remnant {r.bounds} is {p.distance(r):.3f} mm from a part")
        if len(parts) != len(s["parts"]):
            fail(f"{s['file']}: {len(parts)} outlines on CUT, nest.json lists {len(s['parts'])}")
        for k, p in enumerate(parts):
            if not inner.buffer(1e-9).contains(p):
                fail(f"{s['file']}: part {k} leaves the sheet less the {args.margin} mm margin")
        tree = STRtree(parts)
        for k, p in enumerate(parts):
            for j in tree.query(p.buffer(args.spacing)):
                if j <= k:
                    continue
                d = p.distance(parts[j])
                if frozenset((k, j)) in common_pairs:
                    if d < kerf - 1e-6:
                        fail(f"{s['file']}: parts {k} and {j} on a common line are {d:.6f} mm "
                             f"apart (< the kerf {kerf})")
                    continue
                worst_gap = min(worst_gap, d)
                if d < args.spacing - 1e-9:
                    fail(f"{s['file']}: parts {k} and {j} are {d:.6f} mm apart (< {args.spacing})")
        used = sum(plate_area(plates[pid]) for pid in s["parts"])
        if abs(used / sheet_area - s["utilisation"]) > 1e-9:
            fail(f"{s['file']}: utilisation {s['utilisation']} but the plates give {used / sheet_area}")
        # The strip: the sheet less a first remnant that runs right across it holds every
        # part, and its utilisation is the plates' area over its area.
        strip = None
        if s["remnants"]:
            (x0, y0), (x1, y1) = s["remnants"][0]
            if not any(abs(r.bounds[0] - x0) < 1e-6 and abs(r.bounds[1] - y0) < 1e-6
                       and abs(r.bounds[2] - x1) < 1e-6 and abs(r.bounds[3] - y1) < 1e-6
                       for r in remnants):
                fail(f"{s['file']}: nest.json's first remnant {s['remnants'][0]} is not drawn")
            if x0 <= 0 and x1 >= width and y1 - y0 < height:
                strip = ("y", box(0, 0 if y0 > 0 else y1, width, y0 if y0 > 0 else height))
            elif y0 <= 0 and y1 >= height and x1 - x0 < width:
                strip = ("x", box(0 if x0 > 0 else x1, 0, x0 if x0 > 0 else width, height))
        got = s.get("strip")
        if (strip is None) != (got is None):
            fail(f"{s['file']}: nest.json's strip {got} but the first remnant gives "
                 f"{strip and strip[1].bounds}")
        if strip is not None:
            along, rect = strip
            length = rect.bounds[3] - rect.bounds[1] if along == "y" else rect.bounds[2] - rect.bounds[0]
            if got["along"] != along or abs(got["length_mm"] - length) > 1e-9 * length:
                fail(f"{s['file']}: strip {got}, the first remnant leaves {along} {length}")
            for p in parts:
                if not rect.buffer(1e-9).contains(p):
                    fail(f"{s['file']}: a part leaves the strip {rect.bounds}")
            if abs(used / rect.area - got["utilisation"]) > 1e-9:
                fail(f"{s['file']}: strip utilisation {got['utilisation']}, the plates give "
                     f"{used / rect.area}")
            last_strip = (s["file"], length, used / rect.area)
        total_used += used
        total_stock += sheet_area
        all_areas.extend(Polygon(p.exterior).area for p in parts)

    if not (len(all_areas) == len(bom) == len(plates)):
        fail(f"{len(all_areas)} parts on sheets, {len(bom)} BOM rows, {len(plates)} plates")
    want = sorted(Polygon(p["outline"]).area for p in plates.values())
    for a, b in zip(sorted(all_areas), want):
        if abs(a - b) > 1e-6 * max(b, 1.0):
            fail(f"part areas on the sheets do not match the plates' ({a} vs {b})")
    total = total_used / total_stock
    if abs(total - nest["total"]["utilisation"]) > 1e-9:
        fail(f"total utilisation {nest['total']['utilisation']}, recomputed {total}")
    if abs(total_cut - nest["total"]["cut_mm"]) > 1e-9 * max(total_cut, 1.0):
        fail(f"total cut_mm {nest['total']['cut_mm']!r}, the DXFs draw {total_cut!r} mm")

    sheet_of = {pid: s["file"] for s in nest["sheets"] for pid in s["parts"]}
    # Rotations: exactly an allowed angle, and the geometry on the sheet turned by it.
    drawn = {}
    for s in nest["sheets"]:
        width, height = s["size"]
        parts, _, _, gaps, _, _ = sheet_polygons(folder / s["file"], width, height, joint_width)
        drawn[s["file"]] = list(zip(parts, gaps))
    clear = nest["micro_joints"]["clear_mm"] if args.micro_joints else 0.0
    jointed = n_joints = 0
    for pl in nest["placements"]:
        a = pl["rotation_deg"]
        if allowed is not None and a not in allowed:
            fail(f"{pl['id']}: rotation {a!r}° is not one of {allowed}")
        c, sn = math.cos(math.radians(a)), math.sin(math.radians(a))
        pts = [(c * x - sn * y + pl["offset"][0], sn * x + c * y + pl["offset"][1])
               for x, y in plates[pl["id"]]["outline"]]
        want = Polygon(pts)
        match = [(p, g) for p, g in drawn[pl["sheet"]]
                 if p.exterior.hausdorff_distance(want.exterior) < 1e-6]
        if not match:
            fail(f"{pl['id']}: no part on {pl['sheet']} is its outline turned {a}° and moved by the offset")
        part_gaps = match[0][1]
        xs = [x for x, _ in plates[pl["id"]]["outline"]]
        ys = [y for _, y in plates[pl["id"]]["outline"]]
        small = max(max(xs) - min(xs), max(ys) - min(ys)) < args.micro_joint_below
        expect = args.micro_joints if args.micro_joints and small else 0
        if len(part_gaps) != expect or pl.get("micro_joints", 0) != expect:
            fail(f"{pl['id']}: {len(part_gaps)} micro-joints drawn, nest.json says "
                 f"{pl.get('micro_joints', 0)}, expected {expect}")
        if part_gaps:
            jointed += 1
            n_joints += len(part_gaps)
        for g in part_gaps:
            seg = LineString(g)
            for corner in pts:
                d = seg.distance(Point(corner))
                if d < clear - 1e-6:
                    fail(f"{pl['id']}: a micro-joint is {d:.3f} mm from a corner (< {clear})")
    for row in bom:
        p = plates.get(row["id"])
        if p is None:
            fail(f"BOM row {row['id']} is not a plate")
        if sheet_of.get(row["id"]) != row["sheet"]:
            fail(f"BOM row {row['id']}: sheet {row['sheet']}, nest.json says {sheet_of.get(row['id'])}")
        if float(row["thickness_mm"]) != p["thickness"]:
            fail(f"BOM row {row['id']}: thickness {row['thickness_mm']} is not {p['thickness']}")
        if row["grade"] != grade:
            fail(f"BOM row {row['id']}: grade {row['grade']!r}, plates.json says {grade!r}")
        mass = plate_area(p) * p["thickness"] * density * 1e-6
        if abs(float(row["mass_kg"]) - mass) > 1e-4 + 1e-4 * mass:
            fail(f"BOM row {row['id']}: mass {row['mass_kg']} kg, expected {mass:.4f}")
    if strokes == 0:
        fail("no etching on ETCH in any sheet")
    print(
        f"{folder}: ok ({len(all_areas)} parts on {len(nest['sheets'])} sheets, "
        f"rotations {'any' if allowed is None else 'exactly ' + args.rotations}, "
        f"closest pair {worst_gap:.3f} mm (spacing {args.spacing}), "
        f"utilisation {100 * total:.1f} %, {strokes} etched polylines, {n_remnants} remnants"
        + (f", {nest['total']['common_lines']} common lines" if nest["total"].get("common_lines") else "")
        + (f", {n_joints} micro-joints on {jointed} parts" if args.micro_joints else "")
        + (f", last strip {last_strip[1]:.0f} mm at {100 * last_strip[2]:.1f} % on {last_strip[0]}"
           if last_strip else "") + ")"
    )


if __name__ == "__main__":
    main()
