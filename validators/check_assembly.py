"""Compares the solid OpenSCAD rebuilds from assembly.scad (parts imported from their cut DXFs)
with lamina's assembly.stl (shares no code with lamina): volume within 1e-4 (relative),
bounding box within 0.1 mm.

The OpenSCAD solid must be a closed, consistently oriented surface: every directed edge is
matched by its reverse (a surface without boundary). Where parts only touch along a line
(plates meeting edge to edge), OpenSCAD's union has edges shared by four faces; such a surface
is not a 2-manifold and manifold3d cannot take it, but it still bounds a volume, computed here
by the divergence theorem (the sum of signed tetrahedra). When every edge has exactly two
faces, manifold3d must also accept the solid and agree on the volume.

    check_assembly.py openscad.stl assembly.stl [--tolerance R]
"""
import sys
from collections import Counter

# Relative volume difference allowed; `--tolerance R` as the last argument overrides.
TOLERANCE = 1e-4
if len(sys.argv) > 3 and sys.argv[-2] == "--tolerance":
    TOLERANCE = float(sys.argv[-1])
    del sys.argv[-2:]

import manifold3d as m3d
import numpy as np
import trimesh


def signed_volume(vertices, faces):
    a, b, c = (vertices[faces[:, k]] for k in range(3))
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


def main():
    scad_path, ours_path = sys.argv[1], sys.argv[2]
    # Vertices merged where they are equal (an STL repeats them per facet).
    scad = trimesh.load(scad_path, force="mesh", process=True)
    vertices = np.asarray(scad.vertices, dtype=np.float64)
    faces = np.asarray(scad.faces, dtype=np.int64)
    ours = trimesh.load(ours_path, force="mesh", process=False)
    problems = []

    directed = Counter(map(tuple, np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]],
                                                  faces[:, [2, 0]]]).tolist()))
    open_edges = sum(1 for (a, b), n in directed.items() if directed.get((b, a), 0) != n)
    if open_edges:
        problems.append(f"OpenSCAD's solid is not closed: {open_edges} directed edges "
                        "without their reverse")
    shared = Counter()
    for (a, b), n in directed.items():
        shared[(min(a, b), max(a, b))] += n
    touching = sum(1 for n in shared.values() if n > 2)

    volume = signed_volume(vertices, faces)
    if touching == 0:
        solid = m3d.Manifold(m3d.Mesh(vertices.astype(np.float32), faces.astype(np.uint32)))
        if solid.status() != m3d.Error.NoError:
            problems.append(f"manifold3d does not take OpenSCAD's solid: {solid.status()}")
        elif abs(solid.volume() - volume) > 1e-4 * abs(volume):
            problems.append(f"manifold3d's volume {solid.volume():.1f} mm³ differs from the "
                            f"surface's {volume:.1f} mm³")
    rel = abs(volume - ours.volume) / ours.volume
    if rel > TOLERANCE:
        problems.append(f"volume {volume:.1f} mm³ vs {ours.volume:.1f} mm³ ({rel:.2%})")
    gap = max(np.abs(vertices.min(axis=0) - ours.bounds[0]).max(),
              np.abs(vertices.max(axis=0) - ours.bounds[1]).max())
    if gap > 0.1:
        problems.append(f"bounding boxes differ by {gap:.3f} mm")
    if problems:
        for p in problems:
            print(f"{scad_path}: {p}", file=sys.stderr)
        sys.exit(1)
    where = (f"; {touching} edges where parts touch along a line" if touching
             else "; a manifold")
    print(f"{scad_path}: ok (volume {volume / 1e6:.4f} dm³, {rel:.1e} from assembly.stl; "
          f"bounding boxes within {gap:.4f} mm{where})")


main()
