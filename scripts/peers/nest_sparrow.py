"""The density peer: sparrow (Gardeyn & Vanden Berghe 2025, irregular strip packing, MIT).

sparrow is not on crates.io or PyPI: build it from a checkout of
https://github.com/JeroenGar/sparrow (`cargo build --release --features only_final_svg`), then
run `sparrow -i INPUT -t SECONDS -s SEED`; it writes `output/final_<name>.json`. This script turns a lamina
plates.json (one thickness) into sparrow's input (jagua-rs's strip packing JSON) the way lamina's
nester sees the job: each plate's convex hull grown by half the spacing (an outer polygon of the
round offset), the strip's height the sheet less the margins grown by half the spacing, the
listed rotations. `--solution FILE` reads sparrow's final JSON back and prints the strip's
length and density (true plate areas over length × the sheet's height less the margins).
"""

import argparse
import json
import math


def hull(pts):
    pts = sorted(set(map(tuple, pts)))
    if len(pts) < 3:
        return pts

    def half(seq):
        out = []
        for p in seq:
            while len(out) >= 2 and ((out[-1][0] - out[-2][0]) * (p[1] - out[-2][1])
                                     - (out[-1][1] - out[-2][1]) * (p[0] - out[-2][0])) <= 0:
                out.pop()
            out.append(p)
        return out

    lo, up = half(pts), half(reversed(pts))
    return lo[:-1] + up[:-1]


def area(p):
    return 0.5 * abs(sum(p[k][0] * p[(k + 1) % len(p)][1] - p[(k + 1) % len(p)][0] * p[k][1]
                         for k in range(len(p))))


def grow(h, r, step=math.radians(20)):
    """Counter-clockwise convex polygon grown by r: the round offset's circumscribed polygon."""
    out = []
    n = len(h)
    for k in range(n):
        p, a, b = h[k], h[k - 1], h[(k + 1) % n]
        t0 = math.atan2(p[1] - a[1], p[0] - a[0]) - math.pi / 2
        t1 = math.atan2(b[1] - p[1], b[0] - p[0]) - math.pi / 2
        while t1 < t0:
            t1 += 2 * math.pi
        m = max(1, math.ceil((t1 - t0) / step))
        d = (t1 - t0) / m
        rr = r / math.cos(d / 2)
        out.append((p[0] + r * math.cos(t0), p[1] + r * math.sin(t0)))
        for i in range(m):
            t = t0 + (i + 0.5) * d
            out.append((p[0] + rr * math.cos(t), p[1] + rr * math.sin(t)))
        out.append((p[0] + r * math.cos(t1), p[1] + r * math.sin(t1)))
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("plates")
    ap.add_argument("--out", help="sparrow input to write")
    ap.add_argument("--sheet", default="3000x1500")
    ap.add_argument("--margin", type=float, default=10.0)
    ap.add_argument("--spacing", type=float, default=5.0)
    ap.add_argument("--rotations", default="0,90,180,270")
    ap.add_argument("--solution", help="sparrow's final JSON: print length and density")
    args = ap.parse_args()
    w, h = (float(v) for v in args.sheet.split("x"))
    plates = json.load(open(args.plates))["plates"]
    total = sum(p["area_mm2"] for p in plates)
    height = h - 2 * args.margin
    if args.out:
        items = []
        for i, p in enumerate(plates):
            g = grow(hull(p["outline"]), args.spacing / 2 + 0.01)
            items.append({"id": i, "demand": 1,
                          "allowed_orientations": [float(a) for a in args.rotations.split(",")],
                          "shape": {"type": "simple_polygon", "data": [list(q) for q in g]}})
        json.dump({"name": "lamina", "items": items, "strip_height": height + args.spacing},
                  open(args.out, "w"))
    if args.solution:
        sol = json.load(open(args.solution))
        length = sol["solution"]["strip_width"] - args.spacing
        print(json.dumps({"peer": "sparrow", "plates": len(plates), "strip_mm": round(length, 1),
                          "density": round(total / (length * height), 4),
                          "sheets_of_length": round(length / (w - 2 * args.margin), 3)}))


if __name__ == "__main__":
    main()
