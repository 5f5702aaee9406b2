"""Independent DXF check with ezdxf (shares no code with lamina).

    check_dxf.py FILE.dxf [FILE.dxf ...] [--min-version AC1015] [--expect LAYER:TYPE=N ...]

Fails if ezdxf cannot read a file, if its audit (on load by `recover`, and `doc.audit()` after a
plain `readfile`) has anything to fix or reports an error, if the DXF version is older than
R2000 (AC1015: older versions drop LWPOLYLINE), if $INSUNITS is not 4 (mm) or $MEASUREMENT not 1
(metric), or if $EXTMIN/$EXTMAX do not hold every entity's points. Prints entity counts by layer
and type.
"""
import argparse
import collections
import sys

import ezdxf
from ezdxf import recover


def points(e):
    t = e.dxftype()
    if t == "LINE":
        return [e.dxf.start, e.dxf.end]
    if t == "LWPOLYLINE":
        return [e.ocs().to_wcs((x, y, e.dxf.elevation)) for x, y in e.get_points("xy")]
    if t == "POLYLINE":
        return list(e.points())
    if t == "POINT":
        return [e.dxf.location]
    return []


def check(path, a):
    try:
        doc, auditor = recover.readfile(path)
        plain = ezdxf.readfile(path).audit()
    except (IOError, ezdxf.DXFStructureError) as e:
        print(f"FAIL {path}: ezdxf cannot read it: {e}")
        return False
    ok = True
    for what in (auditor, plain):
        for err in what.errors:
            print(f"FAIL {path}: audit error: {err.message}")
            ok = False
        for fix in what.fixes:
            print(f"FAIL {path}: audit had to fix: {fix.message}")
            ok = False
    if doc.header.get("$INSUNITS") != 4 or doc.header.get("$MEASUREMENT") != 1:
        print(f"FAIL {path}: $INSUNITS {doc.header.get('$INSUNITS')}, "
              f"$MEASUREMENT {doc.header.get('$MEASUREMENT')} (want 4 and 1: millimetres)")
        ok = False
    lo, hi = doc.header.get("$EXTMIN"), doc.header.get("$EXTMAX")
    pts = [p for e in doc.modelspace() for p in points(e)]
    if pts:
        for k in range(3):
            least, most = min(p[k] for p in pts), max(p[k] for p in pts)
            slack = 1e-9 * max(1.0, abs(least), abs(most))
            if abs(lo[k] - least) > slack or abs(hi[k] - most) > slack:
                print(f"FAIL {path}: extents {lo} .. {hi} are not the drawing's box")
                ok = False
                break
    if doc.dxfversion < a.min_version:
        print(f"FAIL version {doc.dxfversion} older than {a.min_version}")
        ok = False
    counts = collections.Counter((e.dxf.layer, e.dxftype()) for e in doc.modelspace())
    print(f"{path}: {doc.dxfversion}, audit fixes {len(auditor.fixes) + len(plain.fixes)}, "
          f"errors {len(auditor.errors) + len(plain.errors)}")
    for (layer, kind), n in sorted(counts.items()):
        print(f"  {layer:>12} {kind:<12} {n}")
    for spec in a.expect:
        key, n = spec.split("=")
        layer, kind = key.split(":")
        if counts[(layer, kind)] != int(n):
            print(f"FAIL expected {n} {kind} on {layer}, found {counts[(layer, kind)]}")
            ok = False
    return ok


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("files", nargs="+")
    ap.add_argument("--min-version", default="AC1015")
    ap.add_argument("--expect", nargs="*", default=[], help="LAYER:TYPE=N")
    a = ap.parse_args()
    if a.expect and len(a.files) > 1:
        ap.error("--expect applies to one file")
    results = [check(f, a) for f in a.files]
    return 0 if all(results) else 1


if __name__ == "__main__":
    sys.exit(main())
