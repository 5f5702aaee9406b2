"""Rebuilds every plate of a lamina plates.json with manifold3d (outline extruded by its
thickness about the mid-plane, placed by its matrix; shares no code with lamina) and checks:

- each plate's volume is its outline area, less its bolt holes (as the file's hole_segments-gons),
  times its thickness;
- node cores are tubes (core_segments-gons), not overlapping any plate;
- plates meeting at a node do not interpenetrate: the intersection volume of any two is below
  1e-3 of the smaller one's volume;
- the plates' total volume matches assembly.stl (read by trimesh) to 1e-6;
- assembly.obj has one object per plate, named by its tag, each closed (every edge used once in
  each direction) with the plate's volume.

    check_plates.py plates.json assembly.stl assembly.obj
"""
import json
import sys
from collections import defaultdict

import manifold3d as m3d
import numpy as np
import trimesh


def circle(c, r, n):
    return [(c[0] + r * np.cos(2 * np.pi * k / n), c[1] + r * np.sin(2 * np.pi * k / n))
            for k in range(n)]


def plate_solid(p, segments):
    t = p["thickness"]
    section = m3d.CrossSection([[tuple(q) for q in p["outline"]]])
    if p.get("holes"):
        d0 = p["bolt"]["hole_diameter"]
        holes = m3d.CrossSection([circle(c, d0 / 2, segments) for c in p["holes"]])
        section = section - holes
    solid = m3d.Manifold.extrude(section, t).translate((0.0, 0.0, -t / 2))
    rows = np.array(p["matrix"], dtype=np.float64)[:3, :]
    return solid.transform(rows)


def core_solid(c, segments):
    ro, ri = c["outer_diameter"] / 2, c["outer_diameter"] / 2 - c["wall"]
    ring = m3d.CrossSection([circle((0, 0), ro, segments)]) - m3d.CrossSection(
        [circle((0, 0), ri, segments)])
    solid = m3d.Manifold.extrude(ring, c["length"])
    z = np.array(c["axis"], dtype=np.float64)
    z /= np.linalg.norm(z)
    x = np.cross(z, [1.0, 0.0, 0.0] if abs(z[0]) < 0.9 else [0.0, 1.0, 0.0])
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    rows = np.column_stack([x, y, z, np.array(c["base"], dtype=np.float64)])
    return solid.transform(rows)


def read_objects(path):
    """(name, vertices, triangles with object-local indices) per `o` record."""
    objects, verts, offset = [], [], 0
    for raw in open(path):
        w = raw.split()
        if not w:
            continue
        if w[0] == "o":
            objects.append((w[1], [], []))
            offset = len(verts)
        elif w[0] == "v":
            verts.append(np.array([float(x) for x in w[1:4]]))
            objects[-1][1].append(verts[-1])
        elif w[0] == "f":
            objects[-1][2].append([int(x) - 1 - offset for x in w[1:4]])
    return objects


def main():
    plates_path, stl_path, obj_path = sys.argv[1], sys.argv[2], sys.argv[3]
    doc = json.load(open(plates_path))
    plates = doc["plates"]
    segments = doc.get("hole_segments", 48)
    problems = []
    solids = []
    for k, p in enumerate(plates):
        s = plate_solid(p, segments)
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
    cores = [core_solid(c, doc.get("core_segments", 48)) for c in doc.get("cores", [])]
    for c, cs in zip(doc.get("cores", []), cores):
        for k in at[c["node"]]:
            inter = (cs ^ solids[k]).volume()
            if inter > 1e-3 * solids[k].volume():
                problems.append(f"core {c['id']} overlaps plate {plates[k]['id']} by {inter:.3f} mm³")
    mesh = trimesh.load(stl_path, force="mesh", process=False)
    total = sum(s.volume() for s in solids) + sum(c.volume() for c in cores)
    if abs(mesh.volume - total) > 1e-6 * total:
        problems.append(f"STL volume {mesh.volume} vs plates {total}")
    objects = read_objects(obj_path)
    want_names = [p["id"] for p in plates] + [c["id"] for c in doc.get("cores", [])]
    if [name for name, _, _ in objects] != want_names:
        problems.append("the OBJ's objects are not the plates and cores, by tag, in order")
    for (name, v, f), s in zip(objects, solids + cores):
        directed = {(a, b) for t in f for a, b in zip(t, t[1:] + t[:1])}
        if len(directed) != 3 * len(f) or any((b, a) not in directed for a, b in directed):
            problems.append(f"OBJ object {name} is not closed")
        vol = sum(np.dot(v[a], np.cross(v[b], v[c])) for a, b, c in f) / 6.0
        if abs(vol - s.volume()) > 1e-6 * s.volume():
            problems.append(f"OBJ object {name}: volume {vol} vs {s.volume()}")
    if problems:
        for p in problems[:20]:
            print(f"{plates_path}: {p}", file=sys.stderr)
        sys.exit(1)
    print(f"{plates_path}: ok ({len(plates)} plates, {len(cores)} cores, {total / 1e6:.4f} dm³, {pairs} pairs at nodes, "
          f"largest overlap {worst:.1e} of the smaller plate)")


main()
