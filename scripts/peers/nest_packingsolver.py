"""The nesting peer: PackingSolver (irregular, bin packing) on the job `benches/nest.rs` wrote.

Same plates, sheet, margin (the bin is the sheet less the margin), item-to-item spacing and
rotations. Its time limit is the time lamina took on the job (or --time-limit), so the two are
compared at equal time; it prints sheets, utilisation and its own wall time as JSON.
"""

import argparse
import json
import time

import packingsolver.irregular as psi


def area(p):
    return 0.5 * sum(p[k][0] * p[(k + 1) % len(p)][1] - p[(k + 1) % len(p)][0] * p[k][1]
                     for k in range(len(p)))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("job")
    ap.add_argument("--time-limit", type=float, help="seconds (default: lamina's time)")
    args = ap.parse_args()
    job = json.load(open(args.job))
    w, h = job["sheet"]
    m = job["margin"]
    limit = args.time_limit if args.time_limit is not None else job["lamina"]["seconds"]

    b = psi.InstanceBuilder()
    b.set_objective(psi.Objective.BinPacking)
    b.set_item_item_minimum_spacing(job["spacing"])
    b.add_bin_type(psi.build_rectangle(0, w - 2 * m, 0, h - 2 * m), copies=len(job["parts"]))
    rotations = [(a, a, False) for a in job["rotations"]]
    total = 0.0
    for p in job["parts"]:
        pts = [tuple(q) for q in p]
        if area(pts) < 0:
            pts.reverse()
        total += abs(area(pts))
        b.add_item_type(psi.build_shape(pts), copies=1, allowed_rotations=rotations)
    instance = b.build()
    params = psi.OptimizeParameters()
    params.time_limit = limit
    params.verbosity_level = 0
    t = time.perf_counter()
    out = psi.optimize(instance, params)
    seconds = time.perf_counter() - t
    sol = out.solution
    bins = sol.number_of_bins()
    placed = sol.number_of_items()
    print(json.dumps({
        "peer": "packingsolver",
        "parts": len(job["parts"]),
        "placed": placed,
        "sheets": bins,
        "utilisation": total / (bins * w * h) if bins else None,
        "seconds": seconds,
        "time_limit": limit,
        "feasible": sol.feasible(),
    }))


if __name__ == "__main__":
    main()
