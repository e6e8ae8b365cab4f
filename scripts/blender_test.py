"""Blender-side checks of our GLB and the add-on (run by ``make blender-test``).

    blender -b --factory-startup --python-exit-code 1 --python scripts/blender_test.py -- \
        ZIP GLB HEIGHT TREESKETCH_CLI

0. The add-on installs from its zip (it gives numpy back the ``bool`` alias that Debian
   Blender 3.4's glTF importer calls; this script patches nothing).
1. Blender's own glTF importer, called plainly, reads our GLB: the tree stands along +Z,
   base at z~0, height equal to ours within 1 %.
2. The add-on registers its panel, and the panel draws; its species picker holds Let it
   decide and every species the zip carries.
3. It adds a tree from the bundled drawing through the project's CLI, as a native
   Sapling tree (every level and the leaves: no Limit Import), and from a Grease Pencil
   drawing as the imported GLB, standing upright; each comes in as one hierarchy (an
   empty named after the species) in the ``TreeSketch`` collection, and each
   prediction's Sapling preset gets a name of its own; a species picked in the panel is
   the tree's, and the panel says the species in words; a broken preset is reported by
   the operator in plain words.  Each prediction's outlines picture (the drawing's outline
   over the tree's) is the image ``TreeSketch outlines``, shown beside the tree and in the
   panel.
4. The trees are dressed (issue 28, part 5): a Sapling tree gets bark and leaf materials
   with the GLB's textures (packed), the leaves alpha-clipped in Eevee, their shadows
   too; the imported GLB's leaves clip their shadows as well.  While the CLI refines,
   its current best tree shows in the scene (a preview, gone when the tree arrives,
   leaving no data behind).
"""

import json
import os
import sys
import time
import zipfile
from pathlib import Path

import numpy as _np

NUMPY_HAD_BOOL = "bool" in _np.__dict__  # numpy >= 1.24 has no np.bool

import bpy  # type: ignore[import-not-found]  # noqa: E402, I001 - bpy first (bpy module)
import addon_utils  # type: ignore[import-not-found]  # noqa: E402
from mathutils import Vector  # type: ignore[import-not-found]  # noqa: E402

ZIP, GLB, HEIGHT, CLI = sys.argv[sys.argv.index("--") + 1 :]
OBJ = GLB[: -len(".glb")] + ".obj"
PRESET = GLB[: -len(".glb")] + "_sapling.py"
HEIGHT = float(HEIGHT)
T0 = time.time()


def clear():
    for o in list(bpy.data.objects):
        bpy.data.objects.remove(o)


def world_z(objs):
    zs = [(o.matrix_world @ v.co).z for o in objs if o.type == "MESH" for v in o.data.vertices]
    return min(zs), max(zs)


def step(msg):
    print(f"BLENDER_TEST {time.time() - T0:6.1f}s {msg}", flush=True)


# 0. install the add-on from its zip and enable it
bpy.ops.preferences.addon_install(filepath=ZIP, overwrite=True)
addon_utils.enable("treesketch_addon", default_set=True)
assert "bool" in _np.__dict__, "the add-on did not give numpy its bool alias"
step(f"add-on on; numpy {_np.__version__} had np.bool: {NUMPY_HAD_BOOL}, now: True")

# 1. our GLB through Blender's own importer, called plainly
clear()
bpy.ops.import_scene.gltf(filepath=GLB)
meshes = [o for o in bpy.data.objects if o.type == "MESH"]
assert sorted(o.name for o in meshes) == ["branches", "leaves"], [o.name for o in meshes]
lo, hi = world_z(meshes)
assert abs(lo) < 0.01 * HEIGHT, f"base at z={lo}, expected ~0"
assert abs(hi - lo - HEIGHT) < 0.01 * HEIGHT, f"height {hi - lo} vs ours {HEIGHT}"
for o in meshes:
    dims = o.dimensions
    assert o.data.uv_layers, f"{o.name}: no UVs"
    assert o.data.materials[0].node_tree.nodes.get("Image Texture"), f"{o.name}: no texture"
step(f"GLB upright: z {lo:.3f}..{hi:.3f}, ours {HEIGHT:.3f} m; textured")

# 1b. the OBJ through Blender's default OBJ importer (its default axes: up +Y, forward -Z)
clear()
bpy.ops.wm.obj_import(filepath=OBJ)
meshes = [o for o in bpy.data.objects if o.type == "MESH"]
lo, hi = world_z(meshes)
assert abs(lo) < 0.01 * HEIGHT and abs(hi - lo - HEIGHT) < 0.01 * HEIGHT, (lo, hi, HEIGHT)
step(f"OBJ upright: z {lo:.3f}..{hi:.3f}")

# 1c. our preset through Sapling's own Import Preset: every level and the leaves.
# Sapling is bundled up to Blender 4.1 (an online extension from 4.2): required there.
addon_utils.enable("add_curve_sapling", default_set=True)
SAPLING = "add_curve_sapling" in bpy.context.preferences.addons
assert SAPLING or bpy.app.version >= (4, 2), "Sapling Tree Gen missing from this Blender"
if not SAPLING:
    step("Sapling not bundled in this Blender (an extension since 4.2): Sapling checks skipped")
folder = bpy.utils.user_resource("SCRIPTS", path="presets/operator/add_curve_sapling", create=True)
with open(PRESET, encoding="utf-8") as src, open(f"{folder}/ts_test.py", "w") as dst:
    dst.write(src.read())
# ours (limitImport off inside), then Sapling's default Limit Import forced on
levels = {}
for limit in (False, True) if SAPLING else ():
    clear()
    bpy.ops.sapling.importdata(filename="ts_test.py")
    if limit:  # what a preset without our key gets
        import add_curve_sapling  # type: ignore[import-not-found]

        add_curve_sapling.settings["limitImport"] = True
    assert bpy.ops.curve.tree_add() == {"FINISHED"}
    leaf_objs = [o for o in bpy.data.objects if o.type == "MESH"]
    levels[limit] = (
        sum(len(o.data.splines) for o in bpy.data.objects if o.type == "CURVE"),
        sum(len(o.data.polygons) for o in leaf_objs),
    )
if SAPLING:
    assert levels[False][1] > 0, f"Import Preset dropped the leaves: {levels}"
    assert levels[True][1] == 0  # the check is live: Limit Import on drops them
    step(
        f"Sapling Import Preset (splines, leaf faces): ours {levels[False]}, Limit on {levels[True]}"
    )

# 2. the add-on's panel
assert hasattr(bpy.types, "VIEW3D_PT_treesketch"), "panel not registered"
prefs = bpy.context.preferences.addons["treesketch_addon"].preferences
prefs.cli_path, prefs.copy_presets = CLI, True


class Layout:  # records what the panel draws (there is no screen in background mode)
    def __init__(self, log):
        self.log, self.enabled = log, True

    def prop(self, data, name, **kw):
        self.log.append(("prop", name))

    def operator(self, idname, **kw):
        self.log.append(("operator", idname))

    def label(self, **kw):
        self.log.append(("label", kw.get("text")))

    def row(self, **kw):
        return self

    def column(self, **kw):
        return self

    def box(self, **kw):
        return self

    def template_icon(self, **kw):
        self.log.append(("template_icon", kw.get("icon_value")))


log = []
panel = bpy.types.VIEW3D_PT_treesketch
panel.draw(type("P", (), {"layout": Layout(log)})(), bpy.context)
assert ("operator", "treesketch.predict") in log and ("prop", "image_path") in log, log
assert ("prop", "species") in log, log
# the species picker: Let it decide, then the project's species (the zip's species.json)
items = bpy.context.scene.treesketch.bl_rna.properties["species"].enum_items
assert items[0].identifier == "AUTO" and bpy.context.scene.treesketch.species == "AUTO"
with zipfile.ZipFile(ZIP) as zf:
    shipped = json.loads(zf.read("treesketch_addon/species.json"))["species"]
assert sorted(i.identifier for i in items[1:]) == sorted(s["name"] for s in shipped), items
step(f"add-on installed, panel draws {len(log)} items; species: {[i.name for i in items]}")


def texture_of(mat):
    """The image node feeding the material's Principled BSDF's base colour."""
    bsdf = next(n for n in mat.node_tree.nodes if n.type == "BSDF_PRINCIPLED")
    links = bsdf.inputs["Base Color"].links
    assert links and links[0].from_node.type == "TEX_IMAGE", f"{mat.name}: no texture"
    return links[0].from_node, bsdf


def check_leaf_clip(mat):
    """Leaves clipped by their texture's alpha, in the render and in Eevee's shadows."""
    tex, bsdf = texture_of(mat)
    alpha = bsdf.inputs["Alpha"].links
    assert alpha and alpha[0].from_node == tex and alpha[0].from_socket.name == "Alpha", mat.name
    assert mat.blend_method == "CLIP", (mat.name, mat.blend_method)
    assert abs(mat.alpha_threshold - 0.5) < 1e-6, mat.alpha_threshold
    if hasattr(mat, "shadow_method"):  # up to Blender 4.1
        assert mat.shadow_method == "CLIP", (mat.name, mat.shadow_method)
    else:  # Eevee Next
        assert mat.use_transparent_shadow, mat.name
    return tex


def check_sapling_materials(parent):
    """A Sapling tree's bark and leaf materials: the GLB's textures, packed."""
    curves = [o for o in parent.children_recursive if o.type == "CURVE"]
    leaves = [o for o in parent.children_recursive if o.type == "MESH"]
    assert curves and leaves, parent.name
    bark = curves[0].data.materials[0]
    tex, _ = texture_of(bark)
    assert tex.image.packed_file and tex.image.size[0] == 256, tex.image
    assert all(o.data.materials[0] == bark for o in curves)
    leaf = leaves[0].data.materials[0]
    img = check_leaf_clip(leaf).image
    assert img.packed_file and img.channels == 4, img
    px = _np.array(img.pixels[:]).reshape(-1, 4)
    assert px[:, 3].min() == 0.0 and px[:, 3].max() == 1.0, "the leaf has no alpha mask"
    step(f"{parent.name}: materials {bark.name!r} and {leaf.name!r} (clip, shadow clip)")


def check_hierarchy(kind):
    """The last prediction: one empty named after its species (not the fallback "tree"),
    the tree's objects under it, everything in the TreeSketch collection."""
    coll = bpy.data.collections["TreeSketch"]
    assert coll.name in bpy.context.scene.collection.children
    parent = [o for o in coll.objects if o.parent is None][-1]
    assert parent.type == "EMPTY" and parent.name.split(".")[0] != "tree", parent.name
    tree = [o for o in coll.objects if o.parent is parent]
    assert tree, f"{kind}: nothing under {parent.name}"
    stray = [
        o.name
        for o in bpy.data.objects
        if o.type in ("MESH", "CURVE") and coll not in o.users_collection
    ]
    assert not stray, f"{kind}: objects outside the TreeSketch collection: {stray}"
    step(f"{kind}: {parent.name} holds {[o.name for o in tree]} in collection TreeSketch")
    return parent


def check_outlines(parent, kind):
    """The prediction's outlines picture (issue 48): the image ``TreeSketch outlines``,
    packed, the drawing's outline red and the tree's blue; a reference image empty under
    the tree showing it, upright and facing the Front view; the panel shows it."""
    img = bpy.data.images.get("TreeSketch outlines")
    assert img is not None and img.packed_file, f"{kind}: no outlines image"
    w, h = img.size
    px = _np.array(img.pixels[:]).reshape(h, w, -1)[..., :3]
    red = (px[..., 0] > 0.7) & (px[..., 1] < 0.3) & (px[..., 2] < 0.3)
    blue = (px[..., 2] > 0.7) & (px[..., 0] < 0.3)
    assert (w, h) == (256, 256) and red.sum() > 200 and blue.sum() > 200, (w, h, red.sum())
    refs = [o for o in parent.children if o.type == "EMPTY" and o.data == img]
    assert len(refs) == 1 and refs[0].empty_display_type == "IMAGE", [
        o.name for o in parent.children
    ]
    normal = refs[0].matrix_world.to_3x3() @ Vector((0.0, 0.0, 1.0))
    assert normal.y < -0.99, normal  # faces the Front view (it looks along +Y)
    log = []
    panel.draw(type("P", (), {"layout": Layout(log)})(), bpy.context)
    assert ("label", "Your drawing's outline (red) over the tree's (blue)") in log, log
    assert any(k == "template_icon" for k, _ in log), log
    step(f"{kind}: outlines image {w}x{h} ({red.sum()} red, {blue.sum()} blue px) beside the tree")


# 3a. the bundled drawing -> native Sapling tree (the GLB where Sapling is missing)
clear()
settings = bpy.context.scene.treesketch
settings.source, settings.refine = "IMAGE", False
settings.result = "SAPLING" if SAPLING else "GLB"
assert bpy.ops.treesketch.predict(wait=True) == {"FINISHED"}, settings.status
check_outlines(check_hierarchy("bundled drawing"), "bundled drawing")
if SAPLING:
    curves = [o for o in bpy.data.objects if o.type == "CURVE"]
    leaves = [o for o in bpy.data.objects if o.type == "MESH"]
    assert curves, "no Sapling tree added"
    splines = sum(len(o.data.splines) for o in curves)
    assert leaves and len(leaves[0].data.polygons) > 0, "Sapling made no leaves (Limit Import?)"
    n_leaves = len(leaves[0].data.polygons)
    step(f"Sapling tree from the bundled drawing: {splines} splines, {n_leaves} leaves")
    first = check_hierarchy("Sapling tree")
    check_sapling_materials(first)
    assert settings.species_text, "the panel does not say the species in words"
    # a second prediction, of the species picked: its own preset in Sapling's menu, its
    # own parent, named after that species; the panel says it in words
    # refined this time: the CLI's current best tree shows while it refines
    settings.species, settings.refine, settings.budget = "oak", True, 6
    meshes_before = set(bpy.data.meshes)
    assert bpy.ops.treesketch.predict(wait=True) == {"FINISHED"}, settings.status
    settings.refine, settings.budget = False, 0
    assert settings.previews >= 1, "no preview shown while refining"
    assert not [o for o in bpy.data.objects if o.name.startswith("TreeSketch preview")]
    used = {o.data for o in bpy.data.objects if o.data is not None}
    orphans = [m.name for m in set(bpy.data.meshes) - meshes_before if m not in used]
    assert not orphans, f"the previews left meshes behind: {orphans}"
    step(f"refined: {settings.previews} preview(s) shown, gone when the tree arrived")
    second = check_hierarchy("second Sapling tree")
    check_sapling_materials(second)
    assert second.name != first.name
    assert second.name.split(".")[0] == "oak", second.name
    assert settings.species_text.startswith("an oak"), settings.species_text
    log = []
    panel.draw(type("P", (), {"layout": Layout(log)})(), bpy.context)
    assert ("label", f"It is {settings.species_text}") in log, log
    step(f"species picked: {second.name}, the panel says 'It is {settings.species_text}'")
    settings.species = "AUTO"
    presets = sorted(p for p in os.listdir(folder) if p.startswith("treesketch_"))
    assert len(presets) == 2, f"each prediction's preset needs a name of its own: {presets}"
    step(f"two predictions, two presets: {presets}")
    # 3a'. the panel's controls edit it: more branches, a new tree in the old one's place
    log = []
    panel.draw(type("P", (), {"layout": Layout(log)})(), bpy.context)
    assert ("prop", "crown_width") in log and ("operator", "treesketch.variant") in log, log
    ctl = bpy.context.scene.treesketch_controls
    assert ctl.crown_width == 1.0 and ctl.seed == -1 and ctl.crown_shape == "KEEP"
    ctl.branch_count = 2.0
    coll = bpy.data.collections["TreeSketch"]

    marks = iter(range(1, 1_000_000))

    def roots():
        """Each tree's mark (a new tree gets one now): Blender may give a new object a
        removed one's name, and its memory too."""
        out = []
        for o in coll.objects:
            if o.parent is None:
                if "ts_test" not in o:
                    o["ts_test"] = next(marks)
                out.append(o["ts_test"])
        return out

    def shown():
        roots()
        return bpy.data.objects[settings.last_tree]["ts_test"]

    before, old = roots(), shown()
    assert bpy.ops.treesketch.apply_controls() == {"FINISHED"}, settings.status
    edited = check_hierarchy("edited Sapling tree")
    check_sapling_materials(edited)
    check_outlines(edited, "edited Sapling tree")  # the prediction's picture, kept
    after = roots()  # the edited tree took the old one's place
    assert len(after) == len(before) and old not in after and shown() != old, (before, after)
    more = sum(len(o.data.splines) for o in bpy.data.objects if o.type == "CURVE")
    assert more > splines, (more, splines)
    old = shown()
    assert bpy.ops.treesketch.variant() == {"FINISHED"}, settings.status
    assert ctl.seed >= 0 and len(roots()) == len(before) and old not in roots()
    step(f"controls: branch count x2 gives {more} splines (was {splines}); variant {ctl.seed}")
else:
    lo, hi = world_z([o for o in bpy.data.objects if o.type == "MESH"])
    step(f"GLB from the bundled drawing: z {lo:.2f}..{hi:.2f}")
    settings.result = "SAPLING"  # without Sapling: a plain message before any work
    try:  # an operator that reports an error raises it when called from Python
        bpy.ops.treesketch.predict(wait=True)
        raise AssertionError("a Sapling tree was asked for without Sapling and not refused")
    except RuntimeError as exc:
        assert "Sapling Tree Gen is not installed" in str(exc), exc
    step("asking for a Sapling tree without Sapling: refused up front with a plain message")

# 3c. the prediction leaves a preset that is not a literal (cut short): the operator
# reports it plainly, no Python error escapes it (issue 30, item 7)
if SAPLING:
    broken_cli = Path(GLB).with_name("broken_treesketch")
    broken_cli.write_text(
        "#!/bin/sh\n"
        'while [ $# -gt 0 ]; do case "$1" in --out) out=$2;; --preset) preset=$2;; esac; '
        "shift; done\n"
        'printf glTF > "$out"; printf "{\'levels\': 3,\\n" > "$preset"\n'
    )
    broken_cli.chmod(0o755)
    prefs.cli_path = str(broken_cli)
    clear()
    try:  # an operator that reports an error raises it when called from Python
        bpy.ops.treesketch.predict(wait=True)
        raise AssertionError("a broken preset was not refused")
    except RuntimeError as exc:
        assert "not a Sapling preset TreeSketch can read" in str(exc), exc
        assert "Traceback" not in str(exc), exc
    assert not bpy.data.objects, "a broken preset added objects"
    prefs.cli_path = CLI
    step("a broken preset: the operator reports it plainly")


# 3b. a Grease Pencil drawing -> the GLB
def new_gpencil():
    if bpy.app.version >= (4, 3, 0):  # Grease Pencil v3
        bpy.ops.object.grease_pencil_add(type="EMPTY")
    else:  # Blender up to 4.2: legacy Grease Pencil
        bpy.ops.object.gpencil_add(type="EMPTY")
    return bpy.context.active_object


def gpencil_layer(gp, name=None):
    """A function adding a stroke of world points (x, y, z) to the Grease Pencil object's
    layer ``name`` (made now), or to its active layer."""
    if bpy.app.version >= (4, 3, 0):
        layer = gp.data.layers.new(name) if name else gp.data.layers.active
        layer = layer or gp.data.layers.new("ink")
        drawing = (layer.current_frame() or layer.frames.new(1)).drawing

        def stroke(points):
            drawing.add_strokes([len(points)])
            for p, co in zip(drawing.strokes[-1].points, points, strict=True):
                p.position = co

    else:
        layer = gp.data.layers.new(name) if name else gp.data.layers.active
        frame = layer.frames[0] if len(layer.frames) else layer.frames.new(1)

        def stroke(points):
            s = frame.strokes.new()
            s.points.add(len(points))
            for p, co in zip(s.points, points, strict=True):
                p.co = co

    return stroke


def ring(cx, cz, rx, rz):
    return [(cx + rx * _np.cos(a), cz + rz * _np.sin(a)) for a in _np.linspace(0, 2 * _np.pi, 60)]


clear()
ink = gpencil_layer(new_gpencil())


def stroke(points):  # seen from the front: (x, z) on the plane y = 0
    ink([(x, 0.0, z) for x, z in points])


stroke([(-0.15, 0.0), (-0.1, 1.5)])  # trunk, two lines
stroke([(0.15, 0.0), (0.1, 1.5)])
stroke(ring(0.0, 2.6, 1.3, 1.2))  # crown outline
settings.source, settings.result = "GPENCIL", "GLB"
assert bpy.ops.treesketch.predict(wait=True) == {"FINISHED"}, settings.status
meshes = [o for o in bpy.data.objects if o.type == "MESH"]
assert meshes, "no GLB imported"
lo, hi = world_z(meshes)
assert abs(lo) < 0.02 * (hi - lo) and hi - lo > 0.5, (lo, hi)
check_hierarchy("GLB")
images = {
    n.image
    for o in meshes
    for m in o.data.materials
    for n in m.node_tree.nodes
    if n.type == "TEX_IMAGE" and n.image
}
assert len(images) == 2 and all(i.packed_file for i in images), "textures not packed"
check_leaf_clip(next(o for o in meshes if o.name.startswith("leaves")).data.materials[0])
step(f"GLB from a Grease Pencil drawing: z {lo:.2f}..{hi:.2f}; {len(images)} textures packed")
# 3b'. the height control: the GLB tree grown again, 7 m tall
bpy.context.scene.treesketch_controls.height = 7.0
assert bpy.ops.treesketch.apply_controls() == {"FINISHED"}, settings.status
glb_tree = check_hierarchy("edited GLB")
lo7, hi7 = world_z([o for o in glb_tree.children_recursive if o.type == "MESH"])
assert abs(hi7 - lo7 - 7.0) < 0.03 * 7.0, (lo7, hi7)
step(f"controls: height 7 m -> {hi7 - lo7:.2f} m")

# 3d. two views (issue 29): Grease Pencil layers Front and Right are drawings of one tree
# from Blender's Front and Right views, sent as two views (Right: yaw 90, the camera at
# +X looking along -X, +Y to the right on screen).  A stand-in CLI keeps what it was given.
spy_dir = Path(GLB).with_name("spy")
spy_dir.mkdir()
spy = Path(GLB).with_name("spy_treesketch")
spy.write_text(
    "#!/bin/sh\n"
    f'printf "%s\\n" "$@" > {spy_dir}/args\n'
    f'for a in "$@"; do case "$a" in *.png|*.png@*) cp "${{a%@*}}" {spy_dir}/;; esac; done\n'
    f'exec {CLI} "$@"\n'
)
spy.chmod(0o755)
prefs.cli_path = str(spy)
clear()
gp = new_gpencil()
front, right = gpencil_layer(gp, "Front"), gpencil_layer(gp, "Right")
front([(x, 0.0, z) for x, z in [(-0.15, 0.0), (-0.1, 1.5)]])
front([(x, 0.0, z) for x, z in [(0.15, 0.0), (0.1, 1.5)]])
front([(x, 0.0, z) for x, z in ring(0.0, 2.6, 1.3, 1.2)])
# from the right the crown leans to +Y: right of the trunk on that screen
right([(0.0, y, z) for y, z in [(-0.1, 0.0), (-0.1, 1.5)]])
right([(0.0, y, z) for y, z in [(0.1, 0.0), (0.1, 1.5)]])
right([(0.0, y, z) for y, z in ring(1.0, 2.6, 1.0, 1.2)])
log = []
panel.draw(type("P", (), {"layout": Layout(log)})(), bpy.context)
assert ("label", "views: Front, Right") in log, log
assert bpy.ops.treesketch.predict(wait=True) == {"FINISHED"}, settings.status
args = (spy_dir / "args").read_text().splitlines()
assert Path(args[1]).name == "front.png", args  # (the program is not in "$@")
assert Path(args[args.index("--view") + 1]).name == "right.png@90", args
assert args.count("--view") == 1, args
check_hierarchy("two views")


def ink_columns(path, rows):
    """Mean column of the ink in the given fraction of rows from the bottom (0..1)."""
    img = bpy.data.images.load(str(path))
    w, h = img.size
    px = _np.array(img.pixels[:]).reshape(h, w, -1)[..., 0]  # Blender: bottom row first
    ys, xs = _np.nonzero(px[int(rows[0] * h) : int(rows[1] * h)] < 0.5)
    bpy.data.images.remove(img)
    return xs.mean() / w


trunk_front = ink_columns(spy_dir / "front.png", (0.05, 0.3))
trunk_right = ink_columns(spy_dir / "right.png", (0.05, 0.3))
assert abs(trunk_front - 0.5) < 0.02, trunk_front  # symmetric: the trunk in the middle
assert trunk_right < 0.4, trunk_right  # the crown to the right (+Y): the trunk left of middle
step(f"two views sent: front.png and right.png@90 (trunk at {trunk_right:.2f} of the width)")
# views named without a Front: refused before any work, in plain words
clear()
gpencil_layer(new_gpencil(), "Right")([(0.0, 0.0, 0.0), (0.0, 0.1, 1.0)])
(spy_dir / "args").unlink()
try:
    bpy.ops.treesketch.predict(wait=True)
    raise AssertionError("views without a Front were not refused")
except RuntimeError as exc:
    assert "no Front" in str(exc) and "Traceback" not in str(exc), exc
assert not (spy_dir / "args").exists(), "the CLI ran"
prefs.cli_path = CLI
step("views without a Front: refused before any work")
step(f"ALL OK (Blender {bpy.app.version_string})")
