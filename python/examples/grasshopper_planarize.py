# The body of a Grasshopper "Python 3 Script" component (Rhino 8): node axes that make every
# panel of a line network planar, as lamina planarize does.
#
# Inputs:  lines (list access, Line or Curve: each one member), guide (item, Mesh or None: its
#          normals are the reference directions; without one the network must be flat),
#          height (float, or None: 100 mm), tolerance (float, or None: 0.01 mm), both in the
#          document's units like the geometry (lamina is told them: a model in metres works)
# Outputs: panels (list of Mesh quads), axes (list of Line), report (str)
#
# Install once, from a checkout of lamina with Rust installed, into Rhino's Python:
#   ~/.rhinocode/py39-rh8/python3.9 -m pip install /path/to/lamina
# (on Windows %USERPROFILE%\.rhinocode\py39-rh8\python.exe).
import json

import numpy as np
import Rhino
import Rhino.Geometry as rg

import lamina

# The document's unit system, as lamina names units (others: convert the model first).
UNITS = {"Millimeters": "mm", "Centimeters": "cm", "Meters": "m", "Inches": "in", "Feet": "ft"}
system = str(Rhino.RhinoDoc.ActiveDoc.ModelUnitSystem).split(".")[-1]
if system not in UNITS:
    raise ValueError(f"lamina takes mm, cm, m, in or ft; this document is in {system}")
units = UNITS[system]

# Members' ends become nodes: points closer than 1e-6 of the model size are one node.
ends = []
for ln in lines:
    if isinstance(ln, rg.Curve):
        ln = rg.Line(ln.PointAtStart, ln.PointAtEnd)
    ends.append([(ln.From.X, ln.From.Y, ln.From.Z), (ln.To.X, ln.To.Y, ln.To.Z)])
ends = np.asarray(ends, dtype=float).reshape(-1, 3)
size = float(np.ptp(ends, axis=0).max()) or 1.0
keys = np.round(ends / (1e-6 * size)).astype(np.int64)
_, first, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
positions = ends[first]
edges = inverse.reshape(-1, 2)
edges = edges[edges[:, 0] != edges[:, 1]]

surface = None
if guide is not None:
    guide.Faces.ConvertQuadsToTriangles()
    v = [(p.X, p.Y, p.Z) for p in guide.Vertices]
    f = [(t.A, t.B, t.C) for t in guide.Faces]
    surface = (v, f)

result = lamina.planarize(positions, edges, surface=surface, height=height,
                          tolerance=tolerance, units=units)

panels = []
for quad in result["panels"]:
    m = rg.Mesh()
    for x, y, z in quad:
        m.Vertices.Add(x, y, z)
    m.Faces.AddFace(0, 1, 2, 3)
    m.Normals.ComputeNormals()
    panels.append(m)
axes = [rg.Line(rg.Point3d(*p), rg.Point3d(*(p + a * h)))
        for p, a, h in zip(positions, result["axes"], result["heights"])]
report = json.dumps(result["summary"], indent=2)
