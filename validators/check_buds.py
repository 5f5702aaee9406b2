"""Independent check of a growth form made by `lamina buds` (shares no code with lamina).

    check_buds.py FORM.stl --report buds.json [--obj FORM.obj] [--min-cells N]

- manifold3d: the STL (vertices merged by trimesh) is a valid manifold (status NoError) with
  genus equal to the holes the report says were grown, and the volume the report gives.
- No self-intersection: the volume of the mesh equals the volume of its union with itself
  (a boolean resolves overlaps, so a mesh that passes through itself loses volume).
- The report's growth is consistent: cells = V of the cell graph, genus = holes, every bud
  counted once (made = dead + frozen + live).
- --obj: the OBJ has a colour on every vertex and the same surface (vertex and triangle counts
  agree with the STL's merged mesh).
Exit 0 on pass, 1 on fail.
"""
import argparse
import json
import sys

import manifold3d
import numpy as np
import trimesh


def manifold_of(mesh):
    return manifold3d.Manifold(manifold3d.Mesh(
        vert_properties=np.asarray(mesh.vertices, dtype=np.float32),
        tri_verts=np.asarray(mesh.faces, dtype=np.uint32)))


def obj_counts(path):
    verts = coloured = faces = 0
    with open(path) as f:
        for line in f:
            parts = line.split()
            if not parts:
                continue
            if parts[0] == "v":
                verts += 1
                if len(parts) == 7 and all(0.0 <= float(c) <= 1.0 for c in parts[4:7]):
                    coloured += 1
            elif parts[0] == "f":
                faces += 1
    return verts, coloured, faces


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("stl")
    ap.add_argument("--report", required=True)
    ap.add_argument("--obj")
    ap.add_argument("--min-cells", type=int, default=0)
    a = ap.parse_args()
    report = json.load(open(a.report))
    growth = report["growth"]
    fails = []

    mesh = trimesh.load(a.stl, force="mesh", process=True)
    m = manifold_of(mesh)
    status = m.status()
    if status != manifold3d.Error.NoError:
        fails.append(f"manifold3d status {status}")
    genus = m.genus()
    if genus != growth["holes"]:
        fails.append(f"genus {genus}, but {growth['holes']} holes were grown")
    if growth["genus"] != growth["holes"]:
        fails.append(f"report: cell graph genus {growth['genus']} != holes {growth['holes']}")
    volume = m.volume()
    want = report["mesh"]["volume_mm3"]
    if not abs(volume - want) <= 1e-3 * abs(want):
        fails.append(f"volume {volume:.3f} mm3, report {want:.3f}")
    union = (m + m).volume()
    if not abs(union - volume) <= 1e-4 * abs(volume):
        fails.append(f"self-intersection: union with itself has volume {union:.3f}, "
                     f"the mesh {volume:.3f}")
    if not mesh.is_watertight:
        fails.append("trimesh: not watertight")
    made = growth["buds_made"]
    if made != growth["buds_dead"] + growth["buds_frozen"] + growth["buds_live"]:
        fails.append("report: buds made != dead + frozen + live")
    if sum(k for _, k in growth["buds_by_type"]) != made:
        fails.append("report: buds by type do not add up")
    cells = growth["cells"]
    if sum(n for _, n in growth["degrees"]) != cells:
        fails.append("report: degree histogram does not count every cell")
    if cells < a.min_cells:
        fails.append(f"{cells} cells, expected at least {a.min_cells}")
    if a.obj:
        verts, coloured, faces = obj_counts(a.obj)
        if coloured != verts:
            fails.append(f"OBJ: {verts - coloured} of {verts} vertices have no colour")
        if faces != len(mesh.faces):
            fails.append(f"OBJ: {faces} triangles, STL {len(mesh.faces)}")

    for f in fails:
        print(f"check_buds: {a.stl}: {f}", file=sys.stderr)
    if fails:
        return 1
    print(f"check_buds: {a.stl}: manifold, genus {genus} = holes, volume {volume:.1f} mm3 = "
          f"its union with itself, {cells} cells, {made} buds")
    return 0


if __name__ == "__main__":
    sys.exit(main())
