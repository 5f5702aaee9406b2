"""Independent DXF check with ezdxf (shares no code with lamina).

    check_dxf.py FILE.dxf [--min-version AC1015] [--expect LAYER:TYPE=N ...]

Fails if ezdxf cannot read the file, its audit reports errors, or the DXF version is older than
R2000 (AC1015: older versions drop LWPOLYLINE). Prints entity counts by layer and type.
"""
import argparse
import collections
import sys

import ezdxf
from ezdxf import recover


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("file")
    ap.add_argument("--min-version", default="AC1015")
    ap.add_argument("--expect", nargs="*", default=[], help="LAYER:TYPE=N")
    a = ap.parse_args()
    try:
        doc, auditor = recover.readfile(a.file)
    except (IOError, ezdxf.DXFStructureError) as e:
        print(f"FAIL {a.file}: ezdxf cannot read it: {e}")
        return 1
    ok = True
    if auditor.has_errors:
        ok = False
        for err in auditor.errors:
            print(f"FAIL audit: {err.message}")
    if doc.dxfversion < a.min_version:
        print(f"FAIL version {doc.dxfversion} older than {a.min_version}")
        ok = False
    counts = collections.Counter((e.dxf.layer, e.dxftype()) for e in doc.modelspace())
    print(f"{a.file}: {doc.dxfversion}, audit fixes {len(auditor.fixes)}, errors {len(auditor.errors)}")
    for (layer, kind), n in sorted(counts.items()):
        print(f"  {layer:>12} {kind:<12} {n}")
    for spec in a.expect:
        key, n = spec.split("=")
        layer, kind = key.split(":")
        if counts[(layer, kind)] != int(n):
            print(f"FAIL expected {n} {kind} on {layer}, found {counts[(layer, kind)]}")
            ok = False
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
