"""Checks one node-axes file against another solve of the same network (numpy; shares no code
with lamina):

    check_axes.py CANDIDATE.json BASELINE.json [--tolerance 0.01] [--fixed-normal 'Z:nx,ny,nz']

From the two lamina-axes files alone: the same nodes, edges and references; every panel of the
candidate (v_a, v_b, v_b + h_b d_b, v_a + h_a d_a) within the tolerance (distance of the third
corner from the plane of the other three); with --fixed-normal, every panel whose two ends lie
below z = Z has that normal (within 0.01 degrees); and the candidate's axes no farther from
their references than the baseline's, mean and largest angle, within 0.01 degrees.
"""
import argparse
import json
import sys

import numpy as np


def load(path):
    d = json.load(open(path))
    if d.get("format") != "lamina-axes":
        sys.exit(f"{path}: not a lamina-axes file")
    nodes = d["nodes"]
    p = np.array([n["p"] for n in nodes], dtype=np.float64)
    axis = np.array([n["axis"] for n in nodes], dtype=np.float64)
    ref = np.array([n["reference"] for n in nodes], dtype=np.float64)
    h = np.array([n["height"] for n in nodes], dtype=np.float64)
    e = np.array([[x["a"], x["b"]] for x in d["edges"]], dtype=np.int64)
    return p, axis, ref, h, e


def unit(v):
    return v / np.linalg.norm(v, axis=1)[:, None]


def angles(axis, ref):
    c = np.clip(np.einsum("ij,ij->i", unit(axis), unit(ref)), -1.0, 1.0)
    return np.degrees(np.arccos(c))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("candidate")
    ap.add_argument("baseline")
    ap.add_argument("--tolerance", type=float, default=0.01)
    ap.add_argument("--fixed-normal")
    a = ap.parse_args()
    p, axis, ref, h, e = load(a.candidate)
    p0, axis0, ref0, h0, e0 = load(a.baseline)
    problems = []
    if p.shape != p0.shape or not np.array_equal(e, e0):
        sys.exit(f"{a.candidate}: not the same network as {a.baseline}")
    if np.abs(p - p0).max() > 0 or np.abs(unit(ref) - unit(ref0)).max() > 1e-12:
        problems.append("positions or references differ from the baseline's")
    ia, ib = e[:, 0], e[:, 1]
    q0, q1 = p[ia], p[ib]
    q2 = p[ib] + axis[ib] * h[ib, None]
    q3 = p[ia] + axis[ia] * h[ia, None]
    n = unit(np.cross(q1 - q0, q3 - q0))
    dev = np.abs(np.einsum("ij,ij->i", q2 - q0, n))
    if dev.max() > a.tolerance:
        k = int(dev.argmax())
        problems.append(f"panel {k} deviates {dev[k]:.5f} mm, over {a.tolerance} mm")
    if a.fixed_normal:
        z, v = a.fixed_normal.split(":")
        want = np.array([float(c) for c in v.split(",")])
        want /= np.linalg.norm(want)
        base = (p[ia, 2] < float(z)) & (p[ib, 2] < float(z))
        off = np.degrees(np.arccos(np.clip(np.abs(n[base] @ want), -1.0, 1.0)))
        if base.any() and off.max() > 0.01:
            problems.append(f"a base panel is {off.max():.4f} degrees off its fixed normal")
        print(f"{a.candidate}: {int(base.sum())} base panels, at most {off.max() if base.any() else 0:.2e} degrees off")
    c, b = angles(axis, ref), angles(axis0, ref0)
    if c.mean() > b.mean() + 0.01 or c.max() > b.max() + 0.01:
        problems.append(f"axes {c.mean():.4f} degrees from their references on average, "
                        f"{c.max():.4f} at most; the baseline {b.mean():.4f}, {b.max():.4f}")
    if problems:
        for m in problems:
            print(f"{a.candidate}: {m}", file=sys.stderr)
        sys.exit(1)
    print(f"{a.candidate}: ok ({len(e)} panels, max deviation {dev.max():.5f} mm; axes "
          f"{c.mean():.4f} / {c.max():.4f} degrees from their references, baseline "
          f"{b.mean():.4f} / {b.max():.4f})")


if __name__ == "__main__":
    main()
