"""Render a predicted tree in Blender next to the drawing it came from (docs/blender.png).

    blender -b --factory-startup --python scripts/blender_render.py -- SKETCH.png TREE.glb OUT.png [CAPTION]

Inside Blender: the GLB comes in through Blender's own glTF importer (no fix-ups: it must
stand on +Z by itself), the drawing is an image plane to its left, both seen from the
front (Blender's Front view = the drawn view), labelled with text objects, rendered with
Workbench in texture colours (the bark and leaf textures embedded in the GLB, leaves
alpha-clipped).
"""

import sys

import numpy as _np

if not hasattr(_np, "bool"):
    _np.bool = bool  # Debian Blender 3.4's glTF importer calls np.bool (gone in numpy 2)

import bpy  # type: ignore[import-not-found]  # noqa: E402
from mathutils import Vector  # type: ignore[import-not-found]  # noqa: E402

args = sys.argv[sys.argv.index("--") + 1 :]
SKETCH, GLB, OUT = args[:3]
CAPTION = args[3] if len(args) > 3 else "imported GLB"

for o in list(bpy.data.objects):
    bpy.data.objects.remove(o)
scene = bpy.context.scene
bpy.ops.import_scene.gltf(filepath=GLB)
tree = [o for o in bpy.data.objects if o.type == "MESH"]
pts = [o.matrix_world @ v.co for o in tree for v in o.data.vertices]
lo = Vector((min(p.x for p in pts), min(p.y for p in pts), min(p.z for p in pts)))
hi = Vector((max(p.x for p in pts), max(p.y for p in pts), max(p.z for p in pts)))
height = hi.z - lo.z
print(f"tree: z {lo.z:.3f}..{hi.z:.3f}, x {lo.x:.2f}..{hi.x:.2f}")

# the drawing as an image plane, as tall as the tree, to its left
img = bpy.data.images.load(SKETCH)
mat = bpy.data.materials.new("drawing")
mat.use_nodes = True
tex = mat.node_tree.nodes.new("ShaderNodeTexImage")
tex.image = img
tex.interpolation = "Closest"
bsdf = mat.node_tree.nodes["Principled BSDF"]
mat.node_tree.links.new(tex.outputs["Color"], bsdf.inputs["Base Color"])
side = height * 1.1
gap = 0.15 * side
cx = lo.x - gap - side / 2
bpy.ops.mesh.primitive_plane_add(size=side, location=(cx, 0.0, lo.z + side / 2 - 0.05 * side))
plane = bpy.context.active_object
plane.rotation_euler = (1.5708, 0.0, 0.0)  # face the front camera (-Y)
plane.data.materials.append(mat)


def label(text, x, z, size):
    bpy.ops.object.text_add(location=(x, -side, z), rotation=(1.5708, 0.0, 0.0))
    t = bpy.context.active_object
    t.data.body = text
    t.data.size = size
    t.data.align_x = "CENTER"
    m = bpy.data.materials.new("label")
    m.diffuse_color = (0.0, 0.0, 0.0, 1.0)
    t.data.materials.append(m)


top = lo.z + side + 0.02 * side
label("the drawing", cx, top, 0.06 * side)
label(CAPTION, (lo.x + hi.x) / 2, top, 0.06 * side)
label(
    f"Blender {bpy.app.version_string}: glTF import, Workbench, texture colours;"
    f" +Z up, base z = {round(lo.z, 2) + 0.0:.2f} m, height {height:.2f} m",
    (cx - side / 2 + hi.x) / 2,
    lo.z - 0.1 * side,
    0.035 * side,
)

# front orthographic camera framing both
left, right = cx - side / 2 - 0.05 * side, max(hi.x, lo.x + 0.9 * side) + 0.05 * side
bottom, top2 = lo.z - 0.15 * side, top + 0.12 * side
cam_data = bpy.data.cameras.new("front")
cam_data.type = "ORTHO"
cam_data.ortho_scale = max(right - left, top2 - bottom)
cam = bpy.data.objects.new("front", cam_data)
scene.collection.objects.link(cam)
cam.location = ((left + right) / 2, -10 * side, (bottom + top2) / 2)
cam.rotation_euler = (1.5708, 0.0, 0.0)  # looking along +Y: Blender's Front view
scene.camera = cam
aspect = (right - left) / (top2 - bottom)
scene.render.resolution_x = 1200
scene.render.resolution_y = int(round(1200 / aspect))
scene.render.engine = "BLENDER_WORKBENCH"
shading = scene.display.shading
shading.light = "FLAT"  # the drawing stays white; cavity gives the tree depth
shading.show_cavity = True
shading.cavity_type = "BOTH"
shading.show_shadows = False
shading.color_type = "TEXTURE"
shading.show_object_outline = False
scene.display.render_aa = "8"
scene.view_settings.view_transform = "Standard"
scene.world = scene.world or bpy.data.worlds.new("w")
scene.render.film_transparent = False
scene.world.color = (1.0, 1.0, 1.0)
scene.render.filepath = OUT
bpy.ops.render.render(write_still=True)
print(f"wrote {OUT}")
