"""Peer for the planarize benchmark: the paper's iterative method (Gokmen §4.4.1) as a Python
user would write it with numpy, vectorised over edges: estimate each panel's normal as the
mean of d_i x e and d_j x e (base panels keep +Z), project every axis onto the planes of its
panels, move it half way to the mean of its projections, renormalise, repeat until the largest
panel deviation is within the tolerance. Our own plain re-implementation, not the paper's code.

usage: python planarize_iterative.py job.json   (written by benches/planarize.rs)
prints iterations, max deviation (mm) and the solve time (s, without reading the job)
"""
import json
import sys
import time

import numpy as np


def deviation(p, d, h, a, b):
    # Distance of the fourth corner (b + h_b d_b) from the plane of a, b, a + h_a d_a.
    e = p[b] - p[a]
    n = np.cross(e, d[a])
    n /= np.linalg.norm(n, axis=1)[:, None]
    return np.abs(np.einsum("ij,ij->i", n, h[b][:, None] * d[b]))


def main():
    job = json.load(open(sys.argv[1]))
    p = np.array(job["positions"], float)
    edges = np.array(job["edges"], int)
    d = np.array(job["reference"], float)
    d /= np.linalg.norm(d, axis=1)[:, None]
    h = np.array(job["heights"], float)
    tol = job["tolerance"]
    step = job["step"]
    a, b = edges[:, 0], edges[:, 1]
    below = job["fixed_normal"]["below_z"]
    fixed = (p[a, 2] < below) & (p[b, 2] < below)
    fixed_n = np.array(job["fixed_normal"]["normal"], float)
    e = p[b] - p[a]
    e /= np.linalg.norm(e, axis=1)[:, None]
    count = np.bincount(a, minlength=len(p)) + np.bincount(b, minlength=len(p))
    start = time.perf_counter()
    it = 0
    dev = deviation(p, d, h, a, b).max()
    while dev > tol and it < 100000:
        n = np.cross(d[a], e) + np.cross(d[b], e)
        n /= np.linalg.norm(n, axis=1)[:, None]
        n[fixed] = fixed_n
        acc = np.zeros_like(d)
        for ends in (a, b):
            proj = d[ends] - n * np.einsum("ij,ij->i", d[ends], n)[:, None]
            np.add.at(acc, ends, proj)
        mean = acc / np.maximum(count, 1)[:, None]
        d = d + step * (mean - d)
        d /= np.linalg.norm(d, axis=1)[:, None]
        dev = deviation(p, d, h, a, b).max()
        it += 1
    seconds = time.perf_counter() - start
    print(json.dumps({"iterations": it, "max_deviation": float(dev), "seconds": seconds}))


main()
