"""Counts the faces of a flat DXF line drawing with shapely (noded by union_all on a 1e-6 mm
grid, so strokes drawn over each other a few ulps apart are one line, then polygonized) and compares them with lamina's cells: the count in the cells table and the total
area of the cells OBJ's triangles.

    check_cells_faces.py DRAWING.dxf CELLS.json CELLS.obj

Shares no code with lamina.
"""
import json
import sys

import ezdxf
import numpy as np
import shapely
from shapely.geometry import LineString
from shapely.ops import polygonize

from obj_records import read_obj


def main():
    dxf, table, obj = sys.argv[1:4]
    doc = ezdxf.readfile(dxf)
    lines = []
    for e in doc.modelspace():
        if e.dxftype() == "LINE":
            lines.append(LineString([tuple(e.dxf.start)[:2], tuple(e.dxf.end)[:2]]))
        elif e.dxftype() == "LWPOLYLINE":
            pts = [tuple(p) for p in e.get_points("xy")]
            if e.closed:
                pts.append(pts[0])
            lines.append(LineString(pts))
    faces = list(polygonize(shapely.union_all(lines, grid_size=1e-6).geoms))
    area = sum(f.area for f in faces)
    with open(table) as f:
        cells = json.load(f)["cells"]
    verts, tris = read_obj(obj, "f")
    v = np.asarray(verts, float)
    t = np.asarray([tri[:3] for tri in tris], int)
    ours = 0.5 * np.linalg.norm(np.cross(v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]]), axis=1).sum()
    ok = len(cells) == len(faces) and abs(ours - area) <= 1e-6 * max(area, 1.0)
    print(f"{dxf}: shapely finds {len(faces)} faces of {area:.6g} mm², lamina {len(cells)} cells "
          f"of {ours:.6g} mm²")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
