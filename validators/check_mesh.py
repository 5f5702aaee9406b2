"""Independent mesh check with manifold3d (shares no code with lamina).

    check_mesh.py FILE.stl [--expect-volume V] [--expect-genus G] [--same-volume-as REF.stl]
                           [--rel-tol 1e-6]

Loads the STL with trimesh (vertices merged), builds a manifold3d Manifold, and fails unless it
is a valid manifold. Prints volume and genus; compares them when asked. Exit 0 on pass, 1 on fail.
"""
import argparse
import sys

import manifold3d
import numpy as np
import trimesh


def load_manifold(path):
    mesh = trimesh.load(path, force="mesh", process=True)
    m = manifold3d.Manifold(manifold3d.Mesh(
        vert_properties=np.asarray(mesh.vertices, dtype=np.float32),
        tri_verts=np.asarray(mesh.faces, dtype=np.uint32)))
    return mesh, m


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("file")
    ap.add_argument("--expect-volume", type=float)
    ap.add_argument("--expect-genus", type=int)
    ap.add_argument("--same-volume-as")
    ap.add_argument("--rel-tol", type=float, default=1e-6)
    a = ap.parse_args()
    mesh, m = load_manifold(a.file)
    status = m.status()
    if status != manifold3d.Error.NoError:
        print(f"FAIL {a.file}: not a manifold ({status})")
        return 1
    volume, genus = m.volume(), m.genus()
    print(f"{a.file}: manifold, {len(mesh.faces)} triangles, volume {volume:.6f}, genus {genus}")
    ok = True
    expect = a.expect_volume
    if a.same_volume_as:
        _, ref = load_manifold(a.same_volume_as)
        expect = ref.volume()
        print(f"  reference {a.same_volume_as}: volume {expect:.6f}")
    if expect is not None and abs(volume - expect) > a.rel_tol * abs(expect):
        print(f"FAIL volume {volume} differs from {expect} by more than {a.rel_tol} relative")
        ok = False
    if a.expect_genus is not None and genus != a.expect_genus:
        print(f"FAIL genus {genus}, expected {a.expect_genus}")
        ok = False
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
