"""Compares a network file's node and edge counts, computed here independently, with what
`lamina info --json` reports (shares no code with lamina).

    check_network.py FILE [--lamina PATH_TO_BINARY] [--weld-rel 1e-6]

JSON is read with the json module; OBJ `v`/`l` records by a few lines here; DXF with ezdxf
(LINE, LWPOLYLINE, POLYLINE, POINT). Polyline points closer than weld-rel x bbox diagonal are one
node, as the lamina format documentation specifies.
"""
import argparse
import json
import math
import os
import subprocess
import sys

import ezdxf
import numpy as np

from obj_records import read_obj


def polylines_from_obj(path):
    verts, lines = read_obj(path, "l")
    return verts, [[i, j] for l in lines for i, j in zip(l, l[1:])]


def polylines_from_dxf(path):
    doc = ezdxf.readfile(path)
    verts, segs = [], []

    def add(points, closed=False):
        points = [tuple(map(float, p)) for p in points]
        if closed and len(points) > 2:
            points.append(points[0])
        base = len(verts)
        verts.extend(points)
        segs.extend([base + k, base + k + 1] for k in range(len(points) - 1))

    for e in doc.modelspace():
        t = e.dxftype()
        if t == "LINE":
            add([e.dxf.start, e.dxf.end])
        elif t == "LWPOLYLINE":
            ocs = e.ocs()
            z = e.dxf.elevation
            add([ocs.to_wcs((x, y, z)) for x, y in e.get_points("xy")], e.closed)
        elif t == "POLYLINE" and not (e.is_poly_face_mesh or e.is_polygon_mesh):
            pts = list(e.points()) if e.is_3d_polyline else list(e.points_in_wcs())
            add(pts, e.is_closed)
        elif t == "POINT":
            add([e.dxf.location])
    return verts, segs


def weld(verts, segs, rel):
    pts = np.asarray(verts, dtype=float)
    diag = float(np.linalg.norm(pts.max(axis=0) - pts.min(axis=0))) if len(pts) else 0.0
    tol = rel * diag
    # Simple O(n log n) sweep on x, independent of lamina's grid.
    order = np.argsort(pts[:, 0], kind="stable")
    rep = list(range(len(pts)))
    for a_pos, a in enumerate(order):
        if rep[a] != a:
            continue
        for b in order[a_pos + 1:]:
            if pts[b, 0] - pts[a, 0] > tol:
                break
            if rep[b] == b and np.linalg.norm(pts[b] - pts[a]) <= tol:
                rep[b] = a
    nodes = len({rep[i] for i in range(len(pts))})
    edges = {tuple(sorted((rep[i], rep[j]))) for i, j in segs if rep[i] != rep[j]}
    return nodes, len(edges)


def count(path, rel):
    ext = os.path.splitext(path)[1].lower()
    if ext == ".json":
        data = json.load(open(path))
        assert data["format"] == "lamina-network", "not a lamina-network file"
        return len(data["nodes"]), len(data["edges"])
    if ext == ".obj":
        return weld(*polylines_from_obj(path), rel)
    if ext == ".dxf":
        return weld(*polylines_from_dxf(path), rel)
    raise SystemExit(f"unsupported extension {ext}")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("file")
    ap.add_argument("--lamina", default=os.environ.get("LAMINA", "lamina"))
    ap.add_argument("--weld-rel", type=float, default=1e-6)
    a = ap.parse_args()
    nodes, edges = count(a.file, a.weld_rel)
    out = subprocess.run([a.lamina, "info", "--json", a.file], capture_output=True, text=True)
    if out.returncode != 0:
        print(f"FAIL lamina info exited {out.returncode}: {out.stderr.strip()}")
        return 1
    info = json.loads(out.stdout)
    ok = (info["nodes"], info["edges"]) == (nodes, edges)
    verdict = "ok" if ok else "FAIL"
    print(f"{verdict} {a.file}: independent count {nodes} nodes, {edges} edges; "
          f"lamina {info['nodes']} nodes, {info['edges']} edges")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
