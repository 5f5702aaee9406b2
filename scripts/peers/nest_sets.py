#!/usr/bin/env python3
"""Plate sets for nesting benchmarks (issue 54): a plates.json's plates, all at one thickness,
plus copies stretched in their own frame (x by 0.85-1.15, y by 0.9-1.1), drawn with a seed.

    nest_sets.py PLATES.json --count 434 --seed 7 -o p434.json

The copies get ids `<id>-s<k>`; their weld references are dropped (nesting ignores them)."""
import argparse
import copy
import json
import random


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("plates")
    ap.add_argument("--count", type=int, required=True, help="plates in the set (at least the input's)")
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--thickness", type=float, default=5.0)
    ap.add_argument("-o", "--out", required=True)
    a = ap.parse_args()
    doc = json.load(open(a.plates))
    base = doc["plates"]
    if a.count < len(base):
        ap.error(f"--count must be at least the input's {len(base)} plates")
    rng = random.Random(a.seed)
    out = []
    for p in base:
        q = copy.deepcopy(p)
        q["thickness"] = a.thickness
        out.append(q)
    for k in range(a.count - len(base)):
        p = copy.deepcopy(base[rng.randrange(len(base))])
        sx, sy = rng.uniform(0.85, 1.15), rng.uniform(0.9, 1.1)
        p["id"] = f"{p['id']}-s{k}"
        p["outline"] = [[x * sx, y * sy] for x, y in p["outline"]]
        p["holes"] = [[x * sx, y * sy] for x, y in p.get("holes", [])]
        p["area_mm2"] = p["area_mm2"] * sx * sy
        p["thickness"] = a.thickness
        for e in p.get("ends", []):
            e["welded_to"] = []
        out.append(p)
    doc["plates"] = out
    json.dump(doc, open(a.out, "w"))


if __name__ == "__main__":
    main()
