"""Peer for `lamina simplify` on a flat network: the same chains (maximal runs of degree-2
nodes between other nodes, and closed rings) simplified by shapely's Douglas-Peucker (GEOS,
`shapely.simplify`, preserve_topology=False) at half the mean edge length, as benches/simplify.rs
asks lamina. Only the Douglas-Peucker step: no crossings, no joint angles, no report.

    simplify_shapely.py NETWORK.json

Prints one JSON line: the tolerance, members after, seconds to read, to find chains, to simplify.
"""
import json
import sys
import time

import numpy as np
import shapely


def main():
    t0 = time.perf_counter()
    with open(sys.argv[1]) as f:
        d = json.load(f)
    p = np.array([n["p"] for n in d["nodes"]], dtype=float)[:, :2]
    e = np.array([[x["a"], x["b"]] for x in d["edges"]], dtype=np.int64)
    t1 = time.perf_counter()
    n = len(p)
    adj = [[] for _ in range(n)]
    for k, (a, b) in enumerate(e):
        adj[a].append((b, k))
        adj[b].append((a, k))
    used = np.zeros(len(e), bool)
    chains = []

    def walk(start, k):
        chain = [start]
        at = start
        while True:
            used[k] = True
            a, b = e[k]
            at = b if a == at else a
            chain.append(at)
            if len(adj[at]) != 2 or at == start:
                return chain
            nxt = [kk for _, kk in adj[at] if not used[kk]]
            if not nxt:
                return chain
            k = nxt[0]

    for v in range(n):
        if len(adj[v]) != 2:
            for _, k in adj[v]:
                if not used[k]:
                    chains.append(walk(v, k))
    for v in range(n):
        for _, k in adj[v]:
            if not used[k]:
                chains.append(walk(v, k))
    t2 = time.perf_counter()
    tol = 0.5 * np.linalg.norm(p[e[:, 0]] - p[e[:, 1]], axis=1).mean()
    lines = [shapely.LineString(p[c]) for c in chains]
    t3 = time.perf_counter()
    simple = shapely.simplify(np.array(lines, dtype=object), tol, preserve_topology=False)
    members = int(sum(shapely.get_num_coordinates(simple) - 1))
    t4 = time.perf_counter()
    print(json.dumps({
        "tolerance": tol, "chains": len(chains), "members": members,
        "read_s": round(t1 - t0, 3), "chains_s": round(t2 - t1, 3),
        "geometry_s": round(t3 - t2, 3), "simplify_s": round(t4 - t3, 3),
    }))


if __name__ == "__main__":
    main()
