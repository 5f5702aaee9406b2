"""Writes the quads of an OBJ as a DXF with ezdxf (shares no code with lamina), so that
`lamina audit` can be checked on DXF panels made by another program: even panels as 3DFACE,
odd panels as closed 3D POLYLINE, in the OBJ's order.

    panels_dxf.py panels.obj panels.dxf
"""
import sys

import ezdxf


def main():
    src, dst = sys.argv[1], sys.argv[2]
    verts, faces = [], []
    with open(src) as f:
        for raw in f:
            w = raw.split()
            if not w:
                continue
            if w[0] == "v":
                verts.append(tuple(float(x) for x in w[1:4]))
            elif w[0] == "f":
                faces.append([int(t.split("/")[0]) - 1 for t in w[1:]])
    doc = ezdxf.new("R2000")
    msp = doc.modelspace()
    for k, face in enumerate(faces):
        corners = [verts[i] for i in face]
        if k % 2 == 0:
            msp.add_3dface(corners)
        else:
            msp.add_polyline3d(corners, close=True)
    doc.saveas(dst)
    print(f"{dst}: {len(faces)} panels")


main()
