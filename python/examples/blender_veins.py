# Blender (Text Editor, Run Script): geodesic veins along the edges of the active mesh object
# (lamina veins), added as a new object of edges with the veins' radii as a vertex attribute,
# and optionally made solid (lamina solid) as a second object.
#
# Install once, from a checkout of lamina with Rust installed, into Blender's Python:
#   /path/to/blender/4.x/python/bin/python3.11 -m pip install /path/to/lamina
import bpy
import numpy as np

import lamina

SOURCES = 200  # about this many source vertices, Poisson-disk on the surface
SOLID = False  # also mesh the veins as a closed solid (slow on large objects)

obj = bpy.context.active_object
me = obj.data
me.calc_loop_triangles()
vertices = np.empty(len(me.vertices) * 3)
me.vertices.foreach_get("co", vertices)
faces = np.empty(len(me.loop_triangles) * 3, dtype=np.int32)
me.loop_triangles.foreach_get("vertices", faces)

grown = lamina.veins(vertices.reshape(-1, 3), faces.reshape(-1, 3), sources=SOURCES,
                     progress=lambda stage, msg, done, total: print(stage, done, total))
net = grown["network"]
print(grown["report"])

veins = bpy.data.meshes.new(obj.name + " veins")
veins.from_pydata(net["positions"].tolist(), net["edges"].tolist(), [])
radius = veins.attributes.new("radius", "FLOAT", "POINT")
radius.data.foreach_set("value", net["node_radius"])
new = bpy.data.objects.new(veins.name, veins)
new.matrix_world = obj.matrix_world
bpy.context.collection.objects.link(new)

if SOLID:
    solid = lamina.solid(net, cell=float(net["edge_radius"].mean()) / 2)["mesh"]
    body = bpy.data.meshes.new(obj.name + " solid")
    body.from_pydata(solid["vertices"].tolist(), [], solid["faces"].tolist())
    new = bpy.data.objects.new(body.name, body)
    new.matrix_world = obj.matrix_world
    bpy.context.collection.objects.link(new)
