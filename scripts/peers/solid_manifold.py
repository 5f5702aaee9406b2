"""Peer for `lamina solid`: manifold3d's batch_boolean union of the network's primitives, a
frustum per edge (the end radii lamina uses) and a ball per node (its widest end), 16 segments,
as in Peele's FreeCAD spheres-and-cylinders model. Prints the union's volume, triangles and the
seconds spent building and uniting (reading the JSON excluded).

    solid_manifold.py NET.json [--scale S] [--segments 16]
"""
import argparse
import json
import time

import manifold3d
import numpy as np

ap = argparse.ArgumentParser()
ap.add_argument("network")
ap.add_argument("--scale", type=float, default=1.0)
ap.add_argument("--segments", type=int, default=16)
a = ap.parse_args()
net = json.load(open(a.network))
t0 = time.perf_counter()
nodes, edges = net["nodes"], net["edges"]
P = np.array([n["p"] for n in nodes], dtype=float) * a.scale
radius = [e.get("radius") or max(nodes[e["a"]].get("radius", 0), nodes[e["b"]].get("radius", 0))
          for e in edges]
ends = [[r, r] for r in radius]
around = {}
for k, e in enumerate(edges):
    around.setdefault(e["a"], []).append(k)
    around.setdefault(e["b"], []).append(k)
for v, ks in around.items():
    rv = nodes[v].get("radius", 0)
    if rv > 0:
        for k in sorted(ks, key=lambda k: (-radius[k], k))[:2]:
            ends[k][0 if edges[k]["a"] == v else 1] = rv
ball = [0.0] * len(nodes)
pieces = []
for e, (ra, rb) in zip(edges, ends):
    a_, b_ = P[e["a"]], P[e["b"]]
    ball[e["a"]] = max(ball[e["a"]], ra)
    ball[e["b"]] = max(ball[e["b"]], rb)
    d = b_ - a_
    h = float(np.linalg.norm(d))
    if h <= 0:
        continue
    cyl = manifold3d.Manifold.cylinder(h, ra * a.scale, rb * a.scale, a.segments)
    # Turn +z onto d, then move to a.
    z = d / h
    axis = np.cross([0.0, 0.0, 1.0], z)
    s, c = np.linalg.norm(axis), z[2]
    if s < 1e-12:
        R = np.eye(3) if c > 0 else np.diag([1.0, -1.0, -1.0])
    else:
        k = axis / s
        K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
        R = np.eye(3) + s * K + (1 - c) * K @ K
    M = np.hstack([R, a_.reshape(3, 1)])
    pieces.append(cyl.transform(M.tolist()))
for v, r in enumerate(ball):
    if r > 0:
        pieces.append(manifold3d.Manifold.sphere(r * a.scale, a.segments).translate(tuple(P[v])))
union = manifold3d.Manifold.batch_boolean(pieces, manifold3d.OpType.Add)
tri = union.num_tri()
secs = time.perf_counter() - t0
print(json.dumps({"pieces": len(pieces), "triangles": tri, "volume_mm3": union.volume(),
                  "genus": union.genus(), "status": str(union.status()), "seconds": secs}))
