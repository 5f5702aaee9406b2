"""Compares the solid OpenSCAD rebuilds from assembly.scad (parts imported from their cut DXFs)
with lamina's assembly.stl (shares no code with lamina): volume within 0.5 %, bounding box
within 0.1 mm. The OpenSCAD solid must be a manifold (manifold3d).

    check_assembly.py openscad.stl assembly.stl
"""
import sys

# Relative volume difference allowed; `--tolerance R` as the last argument overrides.
TOLERANCE = 1e-4
if len(sys.argv) > 3 and sys.argv[-2] == "--tolerance":
    TOLERANCE = float(sys.argv[-1])
    del sys.argv[-2:]

import manifold3d as m3d
import numpy as np
import trimesh


def main():
    scad_path, ours_path = sys.argv[1], sys.argv[2]
    scad = trimesh.load(scad_path, force="mesh")
    solid = m3d.Manifold(m3d.Mesh(np.asarray(scad.vertices, dtype=np.float32),
                                  np.asarray(scad.faces, dtype=np.uint32)))
    ours = trimesh.load(ours_path, force="mesh", process=False)
    problems = []
    if solid.status() != m3d.Error.NoError:
        problems.append(f"OpenSCAD's solid is not a manifold: {solid.status()}")
    rel = abs(solid.volume() - ours.volume) / ours.volume
    if rel > TOLERANCE:
        problems.append(f"volume {solid.volume():.1f} mm³ vs {ours.volume:.1f} mm³ ({rel:.2%})")
    lo, hi = solid.bounding_box()[:3], solid.bounding_box()[3:]
    gap = max(np.abs(np.array(lo) - ours.bounds[0]).max(), np.abs(np.array(hi) - ours.bounds[1]).max())
    if gap > 0.1:
        problems.append(f"bounding boxes differ by {gap:.3f} mm")
    if problems:
        for p in problems:
            print(f"{scad_path}: {p}", file=sys.stderr)
        sys.exit(1)
    print(f"{scad_path}: ok (volume {solid.volume() / 1e6:.4f} dm³, {rel:.1e} from assembly.stl; "
          f"bounding boxes within {gap:.4f} mm)")


main()
