"""Time Blender's Sapling (``bpy.ops.curve.tree_add``) on one-line Sapling presets and
measure the trees it makes.

    blender --background --factory-startup --python scripts/blender_time_sapling.py -- \
        OUT.json REPEATS preset1.py [preset2.py ...]

For each preset: clears the scene, runs ``tree_add(**preset)`` REPEATS times and records
every run's seconds; of the last run it records the branch spline count, the branch faces
(the bevelled curve as Blender evaluates it into a mesh, quads), the leaf faces, and the
world-space bounding boxes (``[[x, y, z] lo, [x, y, z] hi]``, Z up) of the branches and of
the leaves.  Writes a JSON list to OUT.json.  Runs only inside Blender
(``benchmarks/lib/sapling_run.py`` calls it for ``bench_grow.py --blender`` and
``compare_sapling.py --blender``); not part of the test suite.
"""

import ast
import json
import os
import sys
import time

import bpy  # type: ignore[import-not-found]

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))  # Blender adds no script folder
from blender_scene import clear, enable_sapling  # noqa: E402

argv = sys.argv[sys.argv.index("--") + 1 :]
out, repeats, presets = argv[0], int(argv[1]), argv[2:]
enable_sapling()


def box(points: list) -> list | None:
    """[[lo x, y, z], [hi x, y, z]] of world-space points, None when there are none."""
    if not points:
        return None
    return [
        [min(p[i] for p in points) for i in range(3)],
        [max(p[i] for p in points) for i in range(3)],
    ]


def measure() -> dict:
    """Faces and bounding boxes of the tree now in the scene (branches evaluated to a mesh,
    so the bevel's thickness counts, as in our tube mesh)."""
    deps = bpy.context.evaluated_depsgraph_get()
    splines = branch_faces = leaf_faces = 0
    branch_pts, leaf_pts = [], []
    for o in bpy.data.objects:
        if o.type == "CURVE":
            splines += len(o.data.splines)
            ev = o.evaluated_get(deps)
            mesh = ev.to_mesh()
            branch_faces += len(mesh.polygons)
            branch_pts += [tuple(o.matrix_world @ v.co) for v in mesh.vertices]
            ev.to_mesh_clear()
        elif o.type == "MESH":
            leaf_faces += len(o.data.polygons)
            leaf_pts += [tuple(o.matrix_world @ v.co) for v in o.data.vertices]
    return {
        "splines": splines,
        "branch_faces": branch_faces,
        "leaf_faces": leaf_faces,
        "branch_bbox": box(branch_pts),
        "leaf_bbox": box(leaf_pts),
    }


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
    rows.append({"preset": path, "seconds": secs, **measure()})
with open(out, "w", encoding="utf-8") as fh:
    json.dump(rows, fh)
