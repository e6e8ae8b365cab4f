"""Check exported Sapling presets and GLBs inside Blender (Debian's blender 3.4 + Sapling).

    treesketch grow --species maple --seed 3 --out /tmp/m.glb --preset /tmp/m.py
    blender --background --factory-startup --python scripts/blender_check.py -- /tmp/m.py /tmp/m.glb

Runs Sapling (``bpy.ops.curve.tree_add``) with every key of the one-line preset (an
unknown key, wrong type or bad enum value fails here), prints its spline count and
dimensions, then imports the GLB and prints its objects and materials.  Runs only inside
Blender; not part of the test suite.
"""

import ast
import sys

import addon_utils  # type: ignore[import-not-found]
import bpy  # type: ignore[import-not-found]
import numpy as _np

if not hasattr(_np, "bool"):
    _np.bool = bool  # Debian blender 3.4 glTF importer vs numpy 2
argv = sys.argv[sys.argv.index("--") + 1 :]
preset, glb = argv
addon_utils.enable("add_curve_sapling", default_set=True)
with open(preset, encoding="utf-8") as fh:
    line = next(t for t in fh if t.strip() and not t.lstrip().startswith("#"))
d = ast.literal_eval(line)
d.pop("limitImport", None)  # as a keyword it is applied last and turns the build off
for o in list(bpy.data.objects):
    bpy.data.objects.remove(o)
res = bpy.ops.curve.tree_add(do_update=True, **d)
print("TREE_ADD", res, [(o.name, o.type) for o in bpy.data.objects])
for o in bpy.data.objects:
    if o.type == "CURVE":
        print("SPLINES", len(o.data.splines), "DIMS", tuple(round(x, 2) for x in o.dimensions))
    if o.type == "MESH":
        print("MESH", o.name, len(o.data.polygons), tuple(round(x, 2) for x in o.dimensions))
for o in list(bpy.data.objects):
    bpy.data.objects.remove(o)
bpy.ops.import_scene.gltf(filepath=glb)
print(
    "GLB",
    sorted(
        (o.name, o.type, len(o.data.polygons) if o.type == "MESH" else 0) for o in bpy.data.objects
    ),
)
print("MATS", sorted(m.name for m in bpy.data.materials))
