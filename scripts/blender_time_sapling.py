"""Time Blender's Sapling (``bpy.ops.curve.tree_add``) on one-line Sapling presets.

    blender --background --factory-startup --python scripts/blender_time_sapling.py -- \
        OUT.json REPEATS preset1.py [preset2.py ...]

For each preset: clears the scene, runs ``tree_add(**preset)`` REPEATS times and records
every run's seconds, plus the branch spline count and leaf face count of the last run.
Writes a JSON list to OUT.json.  Runs only inside Blender (``benchmarks/bench_grow.py
--blender`` calls it); not part of the test suite.
"""

import ast
import json
import sys
import time

import addon_utils  # type: ignore[import-not-found]
import bpy  # type: ignore[import-not-found]

argv = sys.argv[sys.argv.index("--") + 1 :]
out, repeats, presets = argv[0], int(argv[1]), argv[2:]
addon_utils.enable("add_curve_sapling", default_set=True)


def clear() -> None:
    for o in list(bpy.data.objects):
        bpy.data.objects.remove(o)
    for c in list(bpy.data.curves):
        bpy.data.curves.remove(c)
    for m in list(bpy.data.meshes):
        bpy.data.meshes.remove(m)


rows = []
for path in presets:
    with open(path, encoding="utf-8") as fh:
        line = next(t for t in fh if t.strip() and not t.lstrip().startswith("#"))
    d = ast.literal_eval(line)
    d.pop("limitImport", None)  # as a keyword it is applied last and turns the build off
    secs = []
    for _ in range(repeats):
        clear()
        t0 = time.perf_counter()
        res = bpy.ops.curve.tree_add(do_update=True, **d)
        secs.append(time.perf_counter() - t0)
        if "FINISHED" not in res:
            raise SystemExit(f"Sapling refused {path}: {res}")
    splines = sum(len(o.data.splines) for o in bpy.data.objects if o.type == "CURVE")
    leaf_faces = sum(len(o.data.polygons) for o in bpy.data.objects if o.type == "MESH")
    rows.append({"preset": path, "seconds": secs, "splines": splines, "leaf_faces": leaf_faces})
with open(out, "w", encoding="utf-8") as fh:
    json.dump(rows, fh)
