"""Writes the quads of an OBJ as a DXF with ezdxf (shares no code with lamina), so that
`lamina audit` can be checked on DXF panels made by another program: even panels as 3DFACE,
odd panels as closed 3D POLYLINE, in the OBJ's order.

    panels_dxf.py panels.obj panels.dxf
"""
import sys

import ezdxf

from obj_records import read_obj


def main():
    src, dst = sys.argv[1], sys.argv[2]
    verts, faces = read_obj(src, "f")
    doc = ezdxf.new("R2000", units=4)
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
