"""Render a tree the add-on makes from a drawing, in a lit scene (docs/blender.png).

    blender -b --factory-startup --python scripts/blender_render.py -- \
        ZIP TREESKETCH_CLI SKETCH.png OUT.png INFO.json [SPECIES] [BUDGET]

Inside Blender: the add-on is installed from its zip and makes the tree the way a person
would (the drawing as the image file, *Sapling tree*, refined with BUDGET trees, the
SPECIES picked or ``AUTO``): a native Sapling tree with the add-on's bark and leaf
materials.  The scene around it is this script's: a ground that takes the shadows, a sun,
a sky, a camera a little above eye height in front (Blender's Front view is the drawn
view), rendered with Eevee (the leaves alpha-clipped, their shadows too).  INFO.json gets
what the caption needs (species in words, height, Blender's version, render time).
"""

import json
import math
import sys
import time

import addon_utils  # type: ignore[import-not-found]
import bpy  # type: ignore[import-not-found]
from mathutils import Vector  # type: ignore[import-not-found]

args = sys.argv[sys.argv.index("--") + 1 :]
ZIP, CLI, SKETCH, OUT, INFO = args[:5]
SPECIES = args[5] if len(args) > 5 else "AUTO"
BUDGET = int(args[6]) if len(args) > 6 else 40

for o in list(bpy.data.objects):
    bpy.data.objects.remove(o)
scene = bpy.context.scene

# the tree, made by the add-on as a person would make it
bpy.ops.preferences.addon_install(filepath=ZIP, overwrite=True)
addon_utils.enable("treesketch_addon", default_set=True)
prefs = bpy.context.preferences.addons["treesketch_addon"].preferences
prefs.backend, prefs.cli_path, prefs.copy_presets = "CLI", CLI, False
settings = scene.treesketch
settings.source, settings.image_path, settings.result = "IMAGE", SKETCH, "SAPLING"
settings.species, settings.refine, settings.budget = SPECIES, True, BUDGET
assert bpy.ops.treesketch.predict(wait=True) == {"FINISHED"}, settings.status
tree = bpy.data.objects[settings.last_tree]
parts = [o for o in tree.children_recursive if o.type in ("CURVE", "MESH")]

depsgraph = bpy.context.evaluated_depsgraph_get()
corners = [o.matrix_world @ Vector(c) for o in parts for c in o.evaluated_get(depsgraph).bound_box]
lo = Vector([min(c[i] for c in corners) for i in range(3)])
hi = Vector([max(c[i] for c in corners) for i in range(3)])
height = hi.z - lo.z
width = max(hi.x - lo.x, hi.y - lo.y)
print(f"tree: z {lo.z:.2f}..{hi.z:.2f}, width {width:.2f}")

# ground: a wide disc of grass-coloured ground that takes the shadows
bpy.ops.mesh.primitive_circle_add(vertices=96, radius=12 * height, fill_type="NGON")
ground = bpy.context.active_object
mat = bpy.data.materials.new("ground")
mat.use_nodes = True
bsdf = mat.node_tree.nodes["Principled BSDF"]
bsdf.inputs["Base Color"].default_value = (0.15, 0.22, 0.08, 1.0)
bsdf.inputs["Roughness"].default_value = 1.0
bsdf.inputs["Specular"].default_value = 0.1
ground.data.materials.append(mat)

# sky: pale at the horizon, blue above, lighting the shade; a sun from the front left
world = bpy.data.worlds.new("sky")
world.use_nodes = True
nodes, links = world.node_tree.nodes, world.node_tree.links
bg = nodes["Background"]
coords = nodes.new("ShaderNodeTexCoord")
split = nodes.new("ShaderNodeSeparateXYZ")
ramp = nodes.new("ShaderNodeValToRGB")
ramp.color_ramp.elements[0].position = 0.0
ramp.color_ramp.elements[0].color = (0.75, 0.84, 0.95, 1.0)
ramp.color_ramp.elements[1].position = 0.3
ramp.color_ramp.elements[1].color = (0.28, 0.48, 0.85, 1.0)
links.new(coords.outputs["Generated"], split.inputs[0])  # a world's: the view direction
links.new(split.outputs["Z"], ramp.inputs["Fac"])
links.new(ramp.outputs["Color"], bg.inputs["Color"])
bg.inputs["Strength"].default_value = 1.0
scene.world = world
sun_data = bpy.data.lights.new("sun", "SUN")
sun_data.energy = 4.0
sun_data.color = (1.0, 0.95, 0.87)  # late morning
sun_data.angle = math.radians(1.5)
sun_data.shadow_cascade_max_distance = 6 * height
sun_data.shadow_cascade_count = 4
sun = bpy.data.objects.new("sun", sun_data)
sun.rotation_euler = (math.radians(48), 0.0, math.radians(-35))  # from the front left
scene.collection.objects.link(sun)

# camera: in front (-Y, Blender's Front view), a little above eye height, the whole tree
# and its shadow in frame
cam_data = bpy.data.cameras.new("camera")
cam_data.lens = 50
cam = bpy.data.objects.new("camera", cam_data)
scene.collection.objects.link(cam)
scene.camera = cam
target = Vector((0.5 * (lo.x + hi.x), 0.5 * (lo.y + hi.y), lo.z + 0.42 * height))
fov = 2 * math.atan(cam_data.sensor_width / (2 * cam_data.lens))
distance = max(height, width) / (2 * math.tan(fov / 2)) + 0.5 * width
tilt = math.radians(6)  # looking slightly down
cam.location = target + Vector((0.0, -distance * math.cos(tilt), distance * math.sin(tilt)))
cam.rotation_euler = (target - cam.location).to_track_quat("-Z", "Y").to_euler()

eevee = scene.eevee
eevee.taa_render_samples = 32
eevee.use_gtao = True
eevee.gtao_distance = 0.5
eevee.use_soft_shadows = True
eevee.shadow_cascade_size = "4096"
eevee.shadow_cube_size = "2048"
scene.render.engine = "BLENDER_EEVEE"
scene.render.resolution_x = scene.render.resolution_y = 900
scene.render.resolution_percentage = 100
scene.view_settings.view_transform = "Filmic"
scene.view_settings.look = "Medium High Contrast"
scene.render.filepath = OUT
t0 = time.time()
bpy.ops.render.render(write_still=True)
seconds = time.time() - t0
leaf = next(o for o in parts if o.type == "MESH").data.materials[0]
info = {
    "blender": bpy.app.version_string,
    "engine": "Eevee",
    "species": settings.last_species,
    "species_text": settings.species_text,
    "height": round(height, 2),
    "render_seconds": round(seconds, 1),
    "leaf_material": leaf.name,
    "leaf_blend": leaf.blend_method,
    "leaf_shadow": getattr(leaf, "shadow_method", "transparent shadow"),
}
with open(INFO, "w", encoding="utf-8") as fh:
    json.dump(info, fh)
print("RENDER", json.dumps(info))
