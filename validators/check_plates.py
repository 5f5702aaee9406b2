"""Rebuilds every plate of a lamina plates.json with manifold3d (outline extruded by its
thickness about the mid-plane, placed by its matrix; shares no code with lamina) and checks:

- each plate's volume is its outline area times its thickness;
- plates meeting at a node do not interpenetrate: the intersection volume of any two is below
  1e-3 of the smaller one's volume;
- the plates' total volume matches assembly.stl (read by trimesh) to 1e-6, and the STL has one
  closed shell per plate.

    check_plates.py plates.json assembly.stl
"""
import json
import sys
from collections import defaultdict

import manifold3d as m3d
import numpy as np
import trimesh


def plate_solid(p):
    t = p["thickness"]
    section = m3d.CrossSection([[tuple(q) for q in p["outline"]]])
    solid = m3d.Manifold.extrude(section, t).translate((0.0, 0.0, -t / 2))
    rows = np.array(p["matrix"], dtype=np.float64)[:3, :]
    return solid.transform(rows)


def main():
    plates_path, stl_path = sys.argv[1], sys.argv[2]
    doc = json.load(open(plates_path))
    plates = doc["plates"]
    problems = []
    solids = []
    for k, p in enumerate(plates):
        s = plate_solid(p)
        solids.append(s)
        want = abs(p["area_mm2"]) * p["thickness"]
        if abs(s.volume() - want) > 1e-6 * max(want, 1.0):
            problems.append(f"plate {k}: volume {s.volume()} but area × thickness = {want}")
    at = defaultdict(list)
    for k, p in enumerate(plates):
        for v in p["nodes"]:
            at[v].append(k)
    worst, pairs = 0.0, 0
    for v, ks in at.items():
        for i in range(len(ks)):
            for j in range(i + 1, len(ks)):
                a, b = solids[ks[i]], solids[ks[j]]
                inter = (a ^ b).volume()
                ratio = inter / min(a.volume(), b.volume())
                worst = max(worst, ratio)
                pairs += 1
                if ratio > 1e-3:
                    problems.append(f"node {v}: plates {ks[i]} and {ks[j]} overlap by {inter:.3f} mm³")
    mesh = trimesh.load(stl_path, force="mesh")
    total = sum(s.volume() for s in solids)
    stl = m3d.Manifold(m3d.Mesh(np.asarray(mesh.vertices, dtype=np.float32),
                                np.asarray(mesh.faces, dtype=np.uint32)))
    shells = len(stl.decompose())
    if shells != len(plates):
        problems.append(f"{shells} shells in the STL for {len(plates)} plates")
    if not mesh.is_watertight:
        problems.append("the STL is not watertight")
    if abs(mesh.volume - total) > 1e-6 * total:
        problems.append(f"STL volume {mesh.volume} vs plates {total}")
    if problems:
        for p in problems[:20]:
            print(f"{plates_path}: {p}", file=sys.stderr)
        sys.exit(1)
    print(f"{plates_path}: ok ({len(plates)} plates, {total / 1e6:.4f} dm³, {pairs} pairs at nodes, "
          f"largest overlap {worst:.1e} of the smaller plate)")


main()
