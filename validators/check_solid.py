"""Independent check of a solid made by `lamina solid` (shares no code with lamina).

    check_solid.py SOLID.stl --report solid.json [--network NET.json] [--expect-genus-from-network]
                   [--reference] [--segments 64] [--volume-tol 0.01] [--parts 1]

- manifold3d: the STL (vertices merged by trimesh) is a valid manifold (status NoError); its
  volume matches the report's.
- --expect-genus-from-network: genus = independent cycles of the network (E - V + components),
  counted here from the network file.
- --reference: rebuilds the veins with manifold3d as the exact union (batch_boolean) of the hulls
  of two spheres per edge, with the end radii lamina's documented rule gives (at a node, the two
  thickest edges take the node's radius; other edges keep their own), scaled by the report's
  scale. The volume must agree within --volume-tol, and the symmetric difference (after lining
  up the bounding boxes) must be under 2 x that tolerance of the volume.
Exit 0 on pass, 1 on fail.
"""
import argparse
import json
import sys

import manifold3d
import numpy as np
import trimesh

from graph_parts import component_labels


def load(path):
    mesh = trimesh.load(path, force="mesh", process=True)
    m = manifold3d.Manifold(manifold3d.Mesh(
        vert_properties=np.asarray(mesh.vertices, dtype=np.float32),
        tri_verts=np.asarray(mesh.faces, dtype=np.uint32)))
    return mesh, m


def network_cycles(net):
    n = len(net["nodes"])
    edges = [(e["a"], e["b"]) for e in net["edges"]]
    used = {v for e in edges for v in e}
    labels = component_labels(n, edges)
    parts = len({labels[v] for v in used})
    return len(net["edges"]) - len(used) + parts


def end_radii(net):
    nodes, edges = net["nodes"], net["edges"]
    radius = []
    for e in edges:
        r = e.get("radius", 0.0)
        if not r > 0:
            r = max(nodes[e["a"]].get("radius", 0.0), nodes[e["b"]].get("radius", 0.0))
        radius.append(r)
    ends = [[r, r] for r in radius]
    around = {}
    for k, e in enumerate(edges):
        around.setdefault(e["a"], []).append(k)
        around.setdefault(e["b"], []).append(k)
    for v, ks in around.items():
        rv = nodes[v].get("radius", 0.0)
        if not rv > 0:
            continue
        for k in sorted(ks, key=lambda k: (-radius[k], k))[:2]:
            ends[k][0 if edges[k]["a"] == v else 1] = rv
    return ends


def reference(net, scale, segments):
    pieces = []
    ends = end_radii(net)
    for e, (ra, rb) in zip(net["edges"], ends):
        pa = np.array(net["nodes"][e["a"]]["p"], dtype=float) * scale
        pb = np.array(net["nodes"][e["b"]]["p"], dtype=float) * scale
        balls = [manifold3d.Manifold.sphere(r * scale, segments).translate(tuple(p))
                 for p, r in ((pa, ra), (pb, rb))]
        pieces.append(manifold3d.Manifold.batch_hull(balls))
    return manifold3d.Manifold.batch_boolean(pieces, manifold3d.OpType.Add)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("file")
    ap.add_argument("--report", required=True)
    ap.add_argument("--network")
    ap.add_argument("--expect-genus-from-network", action="store_true")
    ap.add_argument("--reference", action="store_true")
    ap.add_argument("--segments", type=int, default=64)
    ap.add_argument("--volume-tol", type=float, default=0.01)
    ap.add_argument("--parts", type=int)
    a = ap.parse_args()
    report = json.load(open(a.report))
    mesh, m = load(a.file)
    ok = True

    def fail(msg):
        nonlocal ok
        print(f"FAIL {a.file}: {msg}")
        ok = False

    if m.status() != manifold3d.Error.NoError:
        fail(f"not a manifold ({m.status()})")
        return 1
    volume, genus = m.volume(), m.genus()
    parts = len(m.decompose())
    print(f"{a.file}: manifold, {len(mesh.faces)} triangles, volume {volume:.4f} mm3, genus {genus}, "
          f"{parts} part(s)")
    if abs(volume - report["volume_mm3"]) > 1e-4 * volume:
        fail(f"volume {volume} but the report says {report['volume_mm3']}")
    if len(mesh.faces) != report["triangles"]:
        fail(f"{len(mesh.faces)} triangles but the report says {report['triangles']}")
    if a.parts is not None and parts != a.parts:
        fail(f"{parts} parts, expected {a.parts}")
    if a.network:
        net = json.load(open(a.network))
        cycles = network_cycles(net)
        print(f"  network: {cycles} independent cycle(s)")
        if a.expect_genus_from_network and genus != cycles:
            fail(f"genus {genus}, but the network has {cycles} independent cycles")
        if a.reference:
            ref = reference(net, report["scale"], a.segments)
            rv = ref.volume()
            rel = abs(volume - rv) / rv
            # Line the two up by their bounding boxes (lamina centres the solid on z = 0).
            lo, hi = np.array(m.bounding_box()[:3]), np.array(m.bounding_box()[3:])
            rlo, rhi = np.array(ref.bounding_box()[:3]), np.array(ref.bounding_box()[3:])
            moved = ref.translate(tuple((lo + hi) / 2 - (rlo + rhi) / 2))
            diff = (m - moved).volume() + (moved - m).volume()
            print(f"  reference union of {len(net['edges'])} sphere hulls: volume {rv:.4f} mm3 "
                  f"({rel * 100:.3f} % apart), symmetric difference {diff / rv * 100:.3f} %")
            if rel > a.volume_tol:
                fail(f"volume {volume} is {rel * 100:.2f} % from the reference {rv}")
            if diff > 2 * a.volume_tol * rv:
                fail(f"symmetric difference {diff} is over {2 * a.volume_tol * 100:.1f} % of the volume")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
