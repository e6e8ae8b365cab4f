"""Render our tree beside Blender Sapling's tree from the same dictionary (docs/species.png).

    blender --background --factory-startup --python scripts/blender_species.py -- JOBS.json

JOBS.json is a list of ``{"mesh": ours.npz, "presets": [tree.py, ...], "bark": [r, g, b],
"leaf": [r, g, b], "out": tile.png, "width": px, "height": px}``; ``ours.npz`` holds our
mesh as ``branch_v``, ``branch_f``, ``leaf_v``, ``leaf_f`` (Z up, trunk base at the
origin, as ``weberpenn.build_mesh`` makes it).  For each job: our mesh in the left slot,
then Sapling's tree (``tree_add`` with the keys of each one-line preset) in the next
slots, the tile's width shared equally, all at one scale, seen from the front
(orthographic, along +Y), Workbench with flat light and cavity, one flat colour for bark
and one for leaves on every tree.  ``scripts/make_species_png.py`` writes the jobs and
labels the tiles.  Runs only inside Blender; not part of the test suite.
"""

import ast
import json
import os
import sys

import bpy  # type: ignore[import-not-found]
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))  # Blender adds no script folder
from blender_scene import clear, enable_sapling  # noqa: E402

with open(sys.argv[sys.argv.index("--") + 1], encoding="utf-8") as _fh:
    jobs = json.load(_fh)
enable_sapling()
GAP = 0.08  # of the widest tree's width, between two slots


def linear(srgb: list) -> tuple:
    """Scene-linear RGBA of a display (sRGB) colour: Workbench shows an object colour
    through the view transform, so the picture then shows the species' own colour."""
    return (*(c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4 for c in srgb), 1.0)


def mesh_object(name: str, v: np.ndarray, f: np.ndarray, colour: list) -> None:
    """A mesh object of triangles ``f`` over vertices ``v`` (filled by foreach_set: fast
    for the 700k triangles of a cherry)."""
    if len(f) == 0:
        return
    me = bpy.data.meshes.new(name)
    me.vertices.add(len(v))
    me.vertices.foreach_set("co", v.astype(np.float32).ravel())
    me.loops.add(3 * len(f))
    me.loops.foreach_set("vertex_index", f.astype(np.int32).ravel())
    me.polygons.add(len(f))
    me.polygons.foreach_set("loop_start", np.arange(0, 3 * len(f), 3, dtype=np.int32))
    me.polygons.foreach_set("loop_total", np.full(len(f), 3, dtype=np.int32))
    me.update()
    ob = bpy.data.objects.new(name, me)
    ob.color = linear(colour)
    bpy.context.scene.collection.objects.link(ob)


def world_points(objs: list) -> np.ndarray:
    """World-space vertices of the objects as evaluated (a curve's bevelled surface)."""
    deps = bpy.context.evaluated_depsgraph_get()
    pts = []
    for o in objs:
        ev = o.evaluated_get(deps)
        me = ev.to_mesh()
        co = np.empty(3 * len(me.vertices), dtype=np.float64)
        me.vertices.foreach_get("co", co)
        ev.to_mesh_clear()
        co = co.reshape(-1, 3)
        m = np.array(o.matrix_world)
        pts.append(co @ m[:3, :3].T + m[:3, 3])
    return np.vstack(pts) if pts else np.zeros((0, 3))


def sapling_tree(path: str, bark: list, leaf: list) -> list:
    """Grow Sapling's tree from a one-line preset; its new objects, coloured."""
    before = set(bpy.data.objects)
    with open(path, encoding="utf-8") as fh:
        line = next(t for t in fh if t.strip() and not t.lstrip().startswith("#"))
    d = ast.literal_eval(line)
    d.pop("limitImport", None)  # as a keyword it is applied last and turns the build off
    res = bpy.ops.curve.tree_add(do_update=True, **d)
    if "FINISHED" not in res:
        raise SystemExit(f"Sapling refused {path}: {res}")
    new = [o for o in bpy.data.objects if o not in before]
    for o in new:
        o.color = linear(bark if o.type == "CURVE" else leaf)
    return new


def render(job: dict) -> None:
    clear()
    scene = bpy.context.scene
    data = np.load(job["mesh"])
    mesh_object("ours_branches", data["branch_v"], data["branch_f"], job["bark"])
    mesh_object("ours_leaves", data["leaf_v"], data["leaf_f"], job["leaf"])
    groups = [list(bpy.data.objects)]
    for preset in job["presets"]:
        groups.append(sapling_tree(preset, job["bark"], job["leaf"]))
    pts = [world_points(g) for g in groups]
    w = max(np.ptp(p[:, 0]) for p in pts)
    slot = w * (1.0 + GAP)
    n = len(groups)
    # tree k's box centred in slot k of n: each tree fills its share of the tile's width
    for k, (objs, p) in enumerate(zip(groups, pts, strict=True)):
        dx = (k - (n - 1) / 2.0) * slot - (p[:, 0].min() + p[:, 0].max()) / 2.0
        for o in objs:
            if o.parent is None:
                o.location.x += dx
    zlo = min(p[:, 2].min() for p in pts)
    zhi = max(p[:, 2].max() for p in pts)
    rx, ry = int(job["width"]), int(job["height"])
    span_x, span_z = n * slot, zhi - zlo
    scale = 1.08 * max(span_x, span_z * rx / ry)
    cam_data = bpy.data.cameras.new("front")
    cam_data.type = "ORTHO"
    cam_data.ortho_scale = scale
    cam = bpy.data.objects.new("front", cam_data)
    scene.collection.objects.link(cam)
    cam.location = (0.0, -10.0 * max(span_x, span_z), (zlo + zhi) / 2.0)
    cam.rotation_euler = (1.5708, 0.0, 0.0)  # looking along +Y: Blender's Front view
    cam_data.clip_end = 40.0 * max(span_x, span_z)
    scene.camera = cam
    scene.render.resolution_x, scene.render.resolution_y = rx, ry
    scene.render.resolution_percentage = 100
    scene.render.engine = "BLENDER_WORKBENCH"
    shading = scene.display.shading
    shading.light = "FLAT"  # flat colours; the cavity gives the crown its depth
    shading.color_type = "OBJECT"
    shading.show_cavity = True
    shading.cavity_type = "BOTH"
    shading.show_shadows = False
    shading.show_object_outline = False
    scene.display.render_aa = "8"
    scene.view_settings.view_transform = "Standard"
    scene.world = scene.world or bpy.data.worlds.new("w")
    scene.world.color = (0.8, 0.8, 0.8)
    scene.render.film_transparent = False
    scene.render.filepath = job["out"]
    bpy.ops.render.render(write_still=True)
    print(f"wrote {job['out']}")


for job in jobs:
    render(job)
