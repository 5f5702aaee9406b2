"""Recomputes the planarity of every panel in an OBJ of quads (numpy; shares no code with
lamina) and compares it with a lamina planarity report:

    check_panels.py panels.obj REPORT.json [--tolerance-mm 1e-9]

Deviation of a quad (q0, q1, q2, q3): the distance of q2 from the plane through q0, q1, q3.
Fails when any panel's deviation differs from the report's by more than the tolerance, when the
counts differ, or when the report's maximum is not the maximum recomputed here.
"""
import argparse
import json
import sys

import numpy as np

from obj_records import read_obj


def read_quads(path):
    verts, faces = read_obj(path, "f")
    v = np.array(verts, dtype=np.float64)
    return [v[f] for f in faces]


def deviation(q):
    n = np.cross(q[1] - q[0], q[3] - q[0])
    norm = np.linalg.norm(n)
    if norm == 0.0:
        return 0.0
    return abs(np.dot(q[2] - q[0], n / norm))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("panels")
    ap.add_argument("report")
    ap.add_argument("--tolerance-mm", type=float, default=1e-9)
    a = ap.parse_args()
    quads = read_quads(a.panels)
    report = json.load(open(a.report))
    rows = {r["index"]: r["deviation"] for r in report["panels"]}
    problems = []
    if any(len(q) != 4 for q in quads):
        problems.append("not every face is a quad")
    if len(quads) != len(rows):
        problems.append(f"{len(quads)} panels in the OBJ, {len(rows)} in the report")
    ours = [deviation(q) for q in quads]
    worst = 0.0
    for k, d in enumerate(ours):
        if k in rows:
            worst = max(worst, abs(d - rows[k]))
    if worst > a.tolerance_mm:
        problems.append(f"deviations differ from the report by up to {worst:.3e} mm")
    # The corner figure's maximum: max_corner since reports hold other metrics too; before,
    # max_deviation was it.
    summary = report["summary"]
    reported = summary.get("max_corner", summary["max_deviation"])
    if summary.get("metric", "corner") == "corner" and summary["max_deviation"] != reported:
        problems.append("the summary's max_deviation is not its max_corner under the corner metric")
    if abs(max(ours) - reported) > a.tolerance_mm:
        problems.append(f"max deviation {max(ours)!r} here, {reported!r} in the report")
    if problems:
        for p in problems:
            print(f"{a.panels}: {p}", file=sys.stderr)
        sys.exit(1)
    print(f"{a.panels}: ok ({len(quads)} panels, max deviation {max(ours):.9f} mm, "
          f"largest difference from the report {worst:.1e} mm)")


if __name__ == "__main__":
    main()
