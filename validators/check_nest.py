"""Checks a nesting folder (`lamina nest ... -o DIR`) with ezdxf and shapely, sharing no code
with lamina.

- Every sheet DXF audits clean, is R2000 or later in mm ($INSUNITS = 4), has its sheet outline
  on SHEET, parts as closed LWPOLYLINEs on CUT, tag strokes as LINEs on ETCH, and no TEXT or
  MTEXT anywhere.
- Every part lies inside its sheet less the margin; any two parts on a sheet are at least the
  spacing apart (shapely distances, an STRtree for neighbours).
- Parts in all sheets = BOM rows = plates in plates.json; the part areas match the plates'
  areas one to one; each BOM row's sheet and mass agree with the plate.
- nest.json's utilisation per sheet and in total is recomputed from the DXF polygons.
"""

import argparse
import csv
import json
import math
import sys
from pathlib import Path

import ezdxf
from ezdxf import recover
from shapely import STRtree
from shapely.geometry import Polygon, box

DENSITY = 7.9  # g/cm³, stainless


def fail(msg):
    print(f"check_nest: FAILED: {msg}", file=sys.stderr)
    sys.exit(1)


def sheet_polygons(path, width, height):
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
    parts = []
    for e in msp:
        layer = e.dxf.layer
        if layer == "CUT":
            if e.dxftype() != "LWPOLYLINE" or not e.closed:
                fail(f"{path}: CUT holds a {e.dxftype()} that is not a closed LWPOLYLINE")
            p = Polygon([(x, y) for x, y, *_ in e.get_points()])
            if not p.is_valid or p.area <= 0:
                fail(f"{path}: a CUT outline is not a valid polygon")
            parts.append(p)
        elif layer == "ETCH":
            if e.dxftype() != "LINE":
                fail(f"{path}: ETCH holds a {e.dxftype()}, expected LINE strokes")
        elif layer != "SHEET":
            fail(f"{path}: unexpected layer {layer}")
    etched = len(msp.query("LINE"))
    return parts, etched


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("folder")
    ap.add_argument("plates", help="the plates.json that was nested")
    ap.add_argument("--sheet", required=True, help="WIDTHxHEIGHT, mm")
    ap.add_argument("--margin", type=float, required=True)
    ap.add_argument("--spacing", type=float, required=True)
    args = ap.parse_args()
    folder = Path(args.folder)
    width, height = (float(v) for v in args.sheet.lower().split("x"))

    plates = {p["id"]: p for p in json.load(open(args.plates))["plates"]}
    nest = json.load(open(folder / "nest.json"))
    with open(folder / "bom.csv", newline="") as f:
        bom = list(csv.DictReader(f))

    inner = box(args.margin, args.margin, width - args.margin, height - args.margin)
    all_areas = []
    worst_gap = math.inf
    strokes = 0
    sheet_area = width * height
    for s in nest["sheets"]:
        parts, etched = sheet_polygons(folder / s["file"], width, height)
        strokes += etched
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
                worst_gap = min(worst_gap, d)
                if d < args.spacing - 1e-9:
                    fail(f"{s['file']}: parts {k} and {j} are {d:.6f} mm apart (< {args.spacing})")
        used = sum(p.area for p in parts)
        if abs(used / sheet_area - s["utilisation"]) > 1e-9:
            fail(f"{s['file']}: utilisation {s['utilisation']} but the DXF gives {used / sheet_area}")
        all_areas.extend(p.area for p in parts)

    if not (len(all_areas) == len(bom) == len(plates)):
        fail(f"{len(all_areas)} parts on sheets, {len(bom)} BOM rows, {len(plates)} plates")
    want = sorted(Polygon(p["outline"]).area for p in plates.values())
    for a, b in zip(sorted(all_areas), want):
        if abs(a - b) > 1e-6 * max(b, 1.0):
            fail(f"part areas on the sheets do not match the plates' ({a} vs {b})")
    total = sum(all_areas) / (len(nest["sheets"]) * sheet_area)
    if abs(total - nest["total"]["utilisation"]) > 1e-9:
        fail(f"total utilisation {nest['total']['utilisation']}, recomputed {total}")

    sheet_of = {pid: s["file"] for s in nest["sheets"] for pid in s["parts"]}
    for row in bom:
        p = plates.get(row["id"])
        if p is None:
            fail(f"BOM row {row['id']} is not a plate")
        if sheet_of.get(row["id"]) != row["sheet"]:
            fail(f"BOM row {row['id']}: sheet {row['sheet']}, nest.json says {sheet_of.get(row['id'])}")
        if float(row["thickness_mm"]) != p["thickness"]:
            fail(f"BOM row {row['id']}: thickness {row['thickness_mm']} is not {p['thickness']}")
        mass = Polygon(p["outline"]).area * p["thickness"] * DENSITY * 1e-6
        if abs(float(row["mass_kg"]) - mass) > 1e-4 + 1e-4 * mass:
            fail(f"BOM row {row['id']}: mass {row['mass_kg']} kg, expected {mass:.4f}")
    if strokes == 0:
        fail("no tag strokes on ETCH in any sheet")
    print(
        f"{folder}: ok ({len(all_areas)} parts on {len(nest['sheets'])} sheets, "
        f"closest pair {worst_gap:.3f} mm (spacing {args.spacing}), "
        f"utilisation {100 * total:.1f} %, {strokes} tag strokes)"
    )


if __name__ == "__main__":
    main()
