"""The node-axes problem as a scipy user would solve it: the same objective as lamina's
(our own re-implementation, numpy, vectorised over edges and nodes), minimised by scipy's
L-BFGS-B with the same continuation in alpha (cut by 10 to 10,000 times, aiming at half the
tolerance, until every panel is within it).

    planarize_scipy.py JOB.json

JOB: positions, edges, reference (unit normals), heights, alpha, tolerance (as written by
`cargo bench --bench planarize_scale -- … --write`). Each axis is d = normalize(r + x0 t0 +
x1 t1) with (t0, t1) a tangent basis of its reference r; the objective is
sum over edges (e . (d_a x d_b))^2 + alpha * sum over nodes |d - r|^2.
Prints one JSON line: seconds of solving (reading excluded), iterations, rounds, alpha at the
end, the largest panel deviation in mm, and whether the tolerance was reached.
"""
import json
import sys
import time

import numpy as np
from scipy.optimize import minimize


def tangent_basis(r):
    # Any unit vector not parallel to r, then two cross products.
    pick = np.where(np.abs(r[:, 0:1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    t0 = np.cross(r, pick)
    t0 /= np.linalg.norm(t0, axis=1)[:, None]
    t1 = np.cross(r, t0)
    return t0, t1


def main():
    job = json.load(open(sys.argv[1]))
    p = np.array(job["positions"], dtype=np.float64)
    edges = np.array(job["edges"], dtype=np.int64)
    r = np.array(job["reference"], dtype=np.float64)
    r /= np.linalg.norm(r, axis=1)[:, None]
    h = np.array(job["heights"], dtype=np.float64)
    alpha = float(job.get("alpha", 0.01))
    alpha0 = alpha
    tol = float(job.get("tolerance", 0.01))
    a, b = edges[:, 0], edges[:, 1]
    e = p[b] - p[a]
    e /= np.linalg.norm(e, axis=1)[:, None]
    t0, t1 = tangent_basis(r)
    n = len(p)

    def axes(x):
        u = r + x[:n, None] * t0 + x[n:, None] * t1
        length = np.linalg.norm(u, axis=1)
        return u / length[:, None], length

    def cost_grad(x):
        d, length = axes(x)
        det = np.einsum("ij,ij->i", e, np.cross(d[a], d[b]))
        diff = d - r
        cost = np.dot(det, det) + alpha * np.einsum("ij,ij->", diff, diff)
        g = 2.0 * alpha * diff
        f = 2.0 * det
        np.add.at(g, a, np.cross(d[b], e) * f[:, None])
        np.add.at(g, b, np.cross(e, d[a]) * f[:, None])
        out = np.empty(2 * n)
        for k, t in enumerate((t0, t1)):
            dd = (t - d * np.einsum("ij,ij->i", d, t)[:, None]) / length[:, None]
            out[k * n:(k + 1) * n] = np.einsum("ij,ij->i", g, dd)
        return cost, out

    def max_dev(x):
        d, _ = axes(x)
        q0, q1 = p[a], p[b]
        q2 = p[b] + d[b] * h[b, None]
        q3 = p[a] + d[a] * h[a, None]
        nrm = np.cross(q1 - q0, q3 - q0)
        nrm /= np.linalg.norm(nrm, axis=1)[:, None]
        return float(np.max(np.abs(np.einsum("ij,ij->i", q2 - q0, nrm))))

    x = np.zeros(2 * n)
    start = time.perf_counter()
    iterations = 0
    rounds = 0
    budget = 10000
    while iterations < budget:
        rounds += 1
        res = minimize(cost_grad, x, jac=True, method="L-BFGS-B",
                       options={"maxiter": budget - iterations, "maxcor": 7,
                                "ftol": 1e-15, "gtol": 1e-12})
        x = res.x
        iterations += max(int(res.nit), 1)
        dev = max_dev(x)
        if dev <= tol or alpha <= alpha0 * 1e-10:
            break
        alpha *= min(max(0.5 * tol / dev, 1e-4), 0.1)
    seconds = time.perf_counter() - start
    dev = max_dev(x)
    print(json.dumps({"seconds": seconds, "iterations": iterations, "rounds": rounds,
                      "alpha": alpha, "max_deviation": dev, "converged": dev <= tol,
                      "nodes": n, "edges": len(edges)}))


if __name__ == "__main__":
    main()
