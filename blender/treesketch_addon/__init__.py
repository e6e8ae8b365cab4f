"""TreeSketch for Blender: draw a tree (an image file or a Grease Pencil drawing), get a
3D tree back, as a native Sapling tree (editable in Sapling's redo panel) or as the
imported GLB, then shape it with the project's controls (height, crown width, ..., another
variant: the table the zip carries as ``controls.json``).  The species may be left to
the drawing or picked (the list the zip carries as ``species.json``); the panel says the
result's species in words.  Install the zip (``make blender-addon``) in Edit > Preferences > Add-ons,
then set where the project's ``treesketch`` program lives (or the service's URL) in the
add-on's preferences.  Panel: 3D view > sidebar (N) > TreeSketch.
"""

from __future__ import annotations

import json
import math
import os
import queue
import random
import shutil
import tempfile
import threading
from pathlib import Path

import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty, StringProperty

from . import backend

bl_info = {
    "name": "TreeSketch",
    "author": "TreeSketch",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "View3D > Sidebar > TreeSketch",
    "description": "Sketch a tree, get a 3D Weber-Penn tree (Sapling or GLB)",
    "category": "Add Curve",
}

BUNDLED_DRAWING = Path(__file__).with_name("drawing_maple.png")
SAPLING = "add_curve_sapling"
COLLECTION = "TreeSketch"  # where every predicted tree goes
CONTROLS = backend.load_controls(Path(__file__).with_name("controls.json"))["controls"]
SPECIES = backend.load_species(Path(__file__).with_name("species.json"))
AUTO = "AUTO"  # the species enum's "Let it decide"
# the last prediction's drawing's outline (red) over its tree's (blue), seen from where
# it was drawn: an image datablock, shown in the panel and beside the tree
OUTLINES_IMAGE = "TreeSketch outlines"


def species_items() -> list[tuple[str, str, str]]:
    """The panel's species choices: Let it decide, then every species by its name."""
    items = [(AUTO, "Let it decide", "TreeSketch decides from the drawing")]
    items += [
        (s["name"], s["display"], f"Make a {s['display']} from the drawing")
        for s in sorted(SPECIES, key=lambda s: s["display"].lower())
    ]
    return items


def _prefs(context) -> bpy.types.AddonPreferences:
    return context.preferences.addons[__package__].preferences


class TREESKETCH_Preferences(bpy.types.AddonPreferences):
    bl_idname = __package__

    backend: EnumProperty(
        name="Run with",
        items=[
            ("CLI", "Project CLI", "Run 'treesketch predict' from the project's venv"),
            ("SERVICE", "Service URL", "POST the drawing to a running TreeSketch service"),
        ],
        default="CLI",
    )
    cli_path: StringProperty(
        name="treesketch program",
        description="The 'treesketch' program in the project's venv (.venv/bin/treesketch)",
        subtype="FILE_PATH",
        default=os.environ.get("TREESKETCH_CLI", ""),
    )
    service_url: StringProperty(
        name="Service URL",
        description="http:// or https:// address of a running 'treesketch serve'; the add-on "
        "fetches nothing from any other address",
        default=os.environ.get("TREESKETCH_URL", "http://127.0.0.1:8000"),
    )
    service_token: StringProperty(
        name="Service token",
        description="The service's --token, sent as an Authorization header (never in a URL); "
        "kept in Blender's preferences: set TREESKETCH_TOKEN instead to keep it out of them",
        subtype="PASSWORD",
        default="",
    )
    copy_presets: BoolProperty(
        name="Add presets to Sapling's menu",
        description="Also copy each predicted tree's preset into Sapling's Import Preset menu",
        default=True,
    )

    def draw(self, context):
        col = self.layout.column()
        col.prop(self, "backend")
        col.prop(self, "cli_path")
        col.prop(self, "service_url")
        col.prop(self, "service_token")
        col.prop(self, "copy_presets")


class TREESKETCH_Settings(bpy.types.PropertyGroup):
    source: EnumProperty(
        name="Drawing",
        items=[
            ("IMAGE", "Image file", "A PNG/JPEG of a tree, dark lines on white"),
            (
                "GPENCIL",
                "Grease Pencil",
                "The active Grease Pencil object, seen from the front; layers named Front, "
                "Right, Back, Left are drawings of one tree from those views",
            ),
        ],
        default="IMAGE",
    )
    image_path: StringProperty(name="Image", subtype="FILE_PATH", default=str(BUNDLED_DRAWING))
    result: EnumProperty(
        name="Add as",
        items=[
            ("SAPLING", "Sapling tree", "A native Sapling tree built from the predicted preset"),
            ("GLB", "Mesh (GLB)", "The predicted mesh with bark and leaf textures"),
        ],
        default="SAPLING",
    )
    species: EnumProperty(
        name="Species",
        description="The kind of tree drawn: let TreeSketch decide, or pick the one you mean",
        items=species_items(),
        default=AUTO,
    )
    refine: BoolProperty(name="Refine", description="Refine the network's estimate", default=True)
    budget: IntProperty(
        name="Budget",
        description="Trees the refinement may try (0: TreeSketch's own default, the same "
        "as the page's and the CLI's; under 20 the outline step after it tries fewer too: "
        "a quick preview)",
        default=0,
        min=0,
    )
    status: StringProperty(name="Status", default="")
    species_text: StringProperty(default="")  # the last prediction's species, in words
    # the last prediction, which the controls edit (JSON parameters, species, view yaw)
    last_params: StringProperty(default="")
    last_species: StringProperty(default="")
    last_yaw: FloatProperty(default=0.0)
    last_tree: StringProperty(default="")  # the parent empty of the tree on show
    progress: FloatProperty(name="Progress", default=0.0, min=0.0, max=1.0, subtype="FACTOR")
    running: BoolProperty(default=False)
    previews: IntProperty(default=0)  # trees the running prediction has shown so far


def _control_group(rows: list) -> type:
    """A PropertyGroup with one property per control of the table; each starts at its
    keep value (``backend.keep_value``: the predicted tree as it is)."""
    ann = {}
    for r in rows:
        name, label, text = r["name"], r["label"], r["help"]
        keep = backend.keep_value(r)
        if r["kind"] == "toggle":
            ann[name] = BoolProperty(name=label, description=text, default=True)
        elif r["kind"] == "choice":
            items = [("KEEP", "as predicted", "The predicted tree's own")]
            items += [(c["value"], c["label"], "") for c in r["choices"]]
            ann[name] = EnumProperty(name=label, description=text, items=items, default="KEEP")
        elif r["kind"] == "integer":
            ann[name] = IntProperty(
                name=label,
                description=f"{text} (-1: as predicted)",
                default=-1,
                min=-1,
                max=int(r["max"]),
            )
        else:
            relative = r.get("neutral") is not None
            ann[name] = FloatProperty(
                name=label,
                description=text if relative else f"{text} (0: as predicted)",
                default=float(keep),
                min=float(r["min"]) if relative else 0.0,
                max=float(r["max"]),
                step=max(1, min(100, round(100 * float(r["step"])))),
            )
    return type("TREESKETCH_Controls", (bpy.types.PropertyGroup,), {"__annotations__": ann})


TREESKETCH_Controls = _control_group(CONTROLS)


def _reset_controls(context) -> None:
    ctl = context.scene.treesketch_controls
    for r in CONTROLS:
        setattr(ctl, r["name"], backend.keep_value(r))


def _remove_tree(name: str) -> None:
    """The tree on show (its parent empty and everything under it), and the meshes,
    curves, materials and images only it used (a preview replaced every 2 s must not
    pile up in the file)."""
    parent = bpy.data.objects.get(name)
    if parent is None:
        return
    objects = [parent, *parent.children_recursive]
    datas = {o.data for o in objects if o.data is not None}
    mats = {m for d in datas for m in getattr(d, "materials", []) if m is not None}
    images = {
        n.image
        for m in mats
        if m.node_tree
        for n in m.node_tree.nodes
        if n.type == "TEX_IMAGE" and n.image
    }
    for o in objects:
        bpy.data.objects.remove(o, do_unlink=True)
    for kind, blocks in (
        (bpy.data.meshes, [d for d in datas if isinstance(d, bpy.types.Mesh)]),
        (bpy.data.curves, [d for d in datas if isinstance(d, bpy.types.Curve)]),
        (bpy.data.materials, mats),
        (bpy.data.images, images),
    ):
        for block in blocks:
            if block.users == 0:
                kind.remove(block)


GPENCIL_TYPES = ("GPENCIL", "GREASEPENCIL")  # Blender < 4.3, Blender 4.3+ (GPv3)


def _gpencil_strokes(obj, layers=None, right=(1.0, 0.0)) -> list:
    """World-space strokes of a Grease Pencil object's visible layers (``layers``: only
    those names) as seen in a view whose screen right is the world axis ``right`` (x, y)
    and up +Z: the Front view's (x, z) by default."""
    mw = obj.matrix_world
    rx, ry = right
    out = []
    for layer in obj.data.layers:
        if layer.hide or (layers is not None and _layer_name(layer) not in layers):
            continue
        if obj.type == "GPENCIL":  # legacy Grease Pencil: frames hold strokes of points
            frame = layer.active_frame
            strokes = [[p.co for p in s.points] for s in frame.strokes] if frame else []
        else:  # Grease Pencil v3: frames hold a drawing of strokes of positions
            frame = layer.current_frame()
            drawing = frame.drawing if frame else None
            strokes = [[p.position for p in s.points] for s in drawing.strokes] if drawing else []
        for pts in strokes:
            world = [mw @ co for co in pts]
            out.append([(rx * p.x + ry * p.y, p.z) for p in world])
    return out


def _layer_name(layer) -> str:
    return layer.info if hasattr(layer, "info") else layer.name  # legacy GP: .info


def drawing_files(context, folder: Path) -> list[tuple[Path, float]]:
    """The drawings to send, each with its yaw relative to the first: the image file; or
    the Grease Pencil drawing rendered to PNG, one per layer named after a view (Front,
    Right, Back, Left: ``backend.VIEWS``), else all its layers as one Front view."""
    settings = context.scene.treesketch
    if settings.source == "IMAGE":
        path = Path(bpy.path.abspath(settings.image_path))
        if not path.is_file():
            raise backend.PredictError(f"no image file at {path}")
        return [(path, 0.0)]
    obj = context.active_object
    if obj is None or obj.type not in GPENCIL_TYPES:
        raise backend.PredictError("make a Grease Pencil drawing the active object first")
    named = backend.view_layers(_layer_name(layer) for layer in obj.data.layers)
    if not named:
        path = folder / "drawing.png"
        path.write_bytes(backend.strokes_png(_gpencil_strokes(obj)))
        return [(path, 0.0)]
    out = []
    for layer, view in named:
        yaw, right = backend.VIEWS[view]
        strokes = _gpencil_strokes(obj, {layer}, right)
        if not strokes:
            raise backend.PredictError(
                f"the Grease Pencil layer {layer!r} (the {view.title()} view) is empty or hidden"
            )
        path = folder / f"{view}.png"
        path.write_bytes(backend.strokes_png(strokes))
        out.append((path, yaw))
    return out


def prediction_job(context, drawings: list[tuple[Path, float]], out: backend.Outputs):
    """A function ``job(on_line, cancel) -> (species, species in words)`` that runs the
    prediction with the backend chosen in the preferences; it reads every setting now, so
    it can run in a thread without touching Blender's data.  ``drawings``: the views of
    the tree, (file, yaw relative to the first)."""
    prefs, settings = _prefs(context), context.scene.treesketch
    image = drawings[0][0]
    if len(drawings) > 1 and prefs.backend != "CLI":
        raise backend.PredictError(
            f"{len(drawings)} views drawn, and the service takes one drawing: hide all but "
            "the Front layer, or run with the project CLI (add-on preferences)"
        )
    refine = bool(settings.refine)
    budget = int(settings.budget) or None  # 0: the project's one default
    species = None if settings.species == AUTO else str(settings.species)
    if prefs.backend == "CLI":
        cmd = backend.cli_command(
            bpy.path.abspath(prefs.cli_path) or "treesketch",
            image,
            out,
            refine=refine,
            budget=budget,
            species=species,
            views=drawings[1:],
        )

        def run(on_line=None, cancel=None):
            lines: list[str] = []

            def seen(line: str) -> None:
                lines.append(line)
                if on_line is not None:
                    on_line(line)

            backend.run_cli(cmd, seen, cancel)
            return backend.species_of(lines), backend.species_text_of(lines)

        return run
    url = str(prefs.service_url)
    token = str(prefs.service_token) or os.environ.get("TREESKETCH_TOKEN") or None

    def ask(on_line=None, cancel=None):
        reply = backend.post_predict(
            url,
            image,
            out.glb,
            refine=refine,
            budget=budget,
            token=token,
            species=species,
            outlines_path=out.outlines,
        )
        out.params.write_text(json.dumps(reply.get("params", {})), encoding="utf-8")
        return reply.get("species"), reply.get("species_text")

    return ask


def add_result(
    context, out: backend.Outputs, yaw: float | None = None, species: str | None = None
) -> list:
    """Add the predicted tree to the scene, as one hierarchy (an empty named after the
    species, the tree's objects under it) in the ``TreeSketch`` collection; returns the
    new objects, the parent first."""
    settings = context.scene.treesketch
    before = set(bpy.data.objects)
    use_sapling = settings.result == "SAPLING" and out.preset.is_file()
    if use_sapling:
        _enable_sapling()
        kwargs, preset_yaw = backend.read_preset(out.preset)
        # as keyword arguments limitImport would be applied last and switch the build off
        kwargs.pop("limitImport", None)
        if bpy.ops.curve.tree_add(do_update=True, **kwargs) != {"FINISHED"}:
            raise backend.PredictError("Sapling did not build the tree from the preset")
        turn = preset_yaw if yaw is None else yaw
        if _prefs(context).copy_presets:
            _copy_to_sapling_menu(out.preset, species)
        new = [o for o in bpy.data.objects if o not in before]
        if out.glb.is_file():  # the same textures as the GLB's (Sapling makes no material)
            _sapling_materials(new, backend.glb_textures(out.glb), species, out.glb.parent)
    else:
        _import_glb(out.glb)
        # a predicted GLB already faces the drawn view; an edit's from the service does not
        turn = 0.0 if yaw is None else yaw
    new = [o for o in bpy.data.objects if o not in before]
    parent = _collect(context, new, species or "tree")
    parent.rotation_euler.z -= math.radians(turn)
    reference = _place_outlines(context, parent, new)
    return [parent, *new, *([reference] if reference else [])]


def load_outlines(path: Path):
    """The prediction's outlines picture as the image ``TreeSketch outlines`` (packed: the
    prediction's folder goes); None when the prediction made none (an older service).
    The last prediction's picture keeps its place under another name where a tree still
    shows it, and is dropped otherwise, so the name is never an older tree's."""
    old = bpy.data.images.get(OUTLINES_IMAGE)
    if old is not None:
        if old.users:
            old.name = f"{OUTLINES_IMAGE} (earlier)"  # Blender numbers it: .001, ...
        else:
            bpy.data.images.remove(old)
    if not path.is_file():
        return None
    img = bpy.data.images.load(str(path))
    img.name = OUTLINES_IMAGE
    img.pack()
    return img


def _place_outlines(context, parent, objects: list):
    """The outlines picture as a reference image empty standing beside the tree, facing
    Blender's Front view (the drawn view, which the tree was turned to face), under the
    tree's parent so it goes with the tree; None without a picture.  An edited tree gets
    the prediction's picture again: an edit has no sketch of its own to outline."""
    img = bpy.data.images.get(OUTLINES_IMAGE)
    if img is None:
        return None
    from mathutils import Matrix, Vector

    context.view_layer.update()  # the parent's turn in the children's world matrices
    corners = [
        o.matrix_world @ Vector(c)
        for o in objects
        if o.type in ("MESH", "CURVE")
        for c in o.bound_box
    ]
    height = max((c.z for c in corners), default=1.0) - min((c.z for c in corners), default=0.0)
    right = max((c.x for c in corners), default=0.5)
    ref = bpy.data.objects.new(OUTLINES_IMAGE, None)
    ref.empty_display_type = "IMAGE"
    ref.data = img
    ref.empty_display_size = max(height, 0.1) * 1.1
    ref.empty_image_offset = (0.0, 0.0)  # its lower left corner at the empty
    ref.show_empty_image_orthographic = ref.show_empty_image_perspective = True
    for c in list(ref.users_collection):
        c.objects.unlink(ref)
    for c in parent.users_collection:
        c.objects.link(ref)
    ref.parent = parent
    # world-aligned whatever the parent's turn: upright in the XZ plane, seen from the
    # front (-Y), to the right of the tree
    ref.matrix_world = Matrix.Translation((right + 0.1 * height, 0.0, 0.0)) @ Matrix.Rotation(
        math.pi / 2, 4, "X"
    )
    return ref


LEAF_ALPHA_THRESHOLD = 0.5  # as the GLB's alphaCutoff


def _import_glb(path: Path) -> None:
    """Blender's glTF importer on our GLB; its images packed (the prediction's folder is
    removed afterwards) and its alpha-masked leaves made to cast clipped shadows."""
    images, materials = set(bpy.data.images), set(bpy.data.materials)
    backend.numpy_bool_alias()  # Blender 3.4's importer calls np.bool
    try:
        bpy.ops.import_scene.gltf(filepath=str(path))
    except RuntimeError as exc:
        raise backend.PredictError(
            f"Blender's glTF importer could not read the tree: {backend.plain_error(exc)}"
        ) from None
    for img in set(bpy.data.images) - images:
        if img.source == "FILE" and not img.packed_file:
            img.pack()
    for mat in set(bpy.data.materials) - materials:
        # the importer clips the leaves' alpha (glTF MASK) but leaves their shadows
        # opaque: a crown of dark squares in Eevee
        if mat.blend_method == "CLIP":
            _alpha_clip(mat, mat.alpha_threshold)


def _alpha_clip(mat, threshold: float = LEAF_ALPHA_THRESHOLD) -> None:
    """Alpha-clipped surface and shadows in Eevee (Cycles reads the BSDF's Alpha)."""
    mat.blend_method = "CLIP"  # deprecated from 4.2, where it still sets the render method
    mat.alpha_threshold = threshold
    if hasattr(mat, "shadow_method"):  # up to Blender 4.1
        mat.shadow_method = "CLIP"
    if hasattr(mat, "use_transparent_shadow"):  # Eevee Next, 4.2+
        mat.use_transparent_shadow = True


def _load_png(data: bytes, name: str, folder: Path):
    """A packed Blender image from PNG bytes (written to ``folder`` to be read)."""
    path = folder / f"{bpy.path.clean_name(name)}.png"
    path.write_bytes(data)
    img = bpy.data.images.load(str(path))
    img.name = name
    img.pack()
    return img


def _textured_material(name: str, image, roughness: float):
    """A Principled material whose base colour is ``image``; returns the material, its
    nodes and links, the image node, the BSDF and a Texture Coordinate node (unlinked:
    the caller says how the UVs reach the image)."""
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    bsdf = nodes["Principled BSDF"]
    bsdf.inputs["Roughness"].default_value = roughness
    tex = nodes.new("ShaderNodeTexImage")
    tex.image = image
    links.new(tex.outputs["Color"], bsdf.inputs["Base Color"])
    uv = nodes.new("ShaderNodeTexCoord")
    return mat, nodes, links, tex, bsdf, uv


def _sapling_materials(objects: list, textures: dict, species, folder: Path) -> None:
    """Bark and leaf materials with the GLB's textures on a new Sapling tree: the bark
    on its curves (Sapling's curve UVs run along each branch in u, 0..1, and around it in
    v: turned to our bark's u around, v along, repeated along the trunk's length by its
    length over girth), the leaves alpha-clipped, shadows too (Sapling's ``leafUV`` is
    our leaf texture's square)."""
    label = species or "tree"
    curves = [o for o in objects if o.type == "CURVE"]
    leaves = [o for o in objects if o.type == "MESH"]
    if "bark" in textures and curves:
        img = _load_png(textures["bark"], f"TreeSketch bark ({label})", folder)
        mat, nodes, links, tex, bsdf, uv = _textured_material(img.name, img, 0.9)
        split = nodes.new("ShaderNodeSeparateXYZ")
        turn = nodes.new("ShaderNodeCombineXYZ")
        along = nodes.new("ShaderNodeMath")
        along.operation = "MULTIPLY"
        along.inputs[1].default_value = _bark_repeats(curves[0])
        links.new(uv.outputs["UV"], split.inputs[0])
        links.new(split.outputs["Y"], turn.inputs["X"])
        links.new(split.outputs["X"], along.inputs[0])
        links.new(along.outputs[0], turn.inputs["Y"])
        links.new(turn.outputs[0], tex.inputs["Vector"])
        # the bark's cracks as a little relief
        bump = nodes.new("ShaderNodeBump")
        bump.inputs["Strength"].default_value = 0.4
        links.new(tex.outputs["Color"], bump.inputs["Height"])
        links.new(bump.outputs["Normal"], bsdf.inputs["Normal"])
        for o in curves:
            o.data.materials.clear()
            o.data.materials.append(mat)
    if "leaf" in textures and leaves:
        img = _load_png(textures["leaf"], f"TreeSketch leaf ({label})", folder)
        mat, nodes, links, tex, bsdf, uv = _textured_material(img.name, img, 0.6)
        links.new(uv.outputs["UV"], tex.inputs["Vector"])
        links.new(tex.outputs["Alpha"], bsdf.inputs["Alpha"])
        _alpha_clip(mat)
        mat.use_backface_culling = False  # one quad per leaf, seen from both sides
        for o in leaves:
            o.data.materials.clear()
            o.data.materials.append(mat)


def _bark_repeats(curve) -> float:
    """How many times the bark repeats along a branch: the trunk's (the first spline's)
    length over its girth, so its bark is not stretched (1..64)."""
    spline = curve.data.splines[0]
    pts = [p.co.xyz for p in spline.bezier_points] or [p.co.xyz for p in spline.points]
    radii = [p.radius for p in spline.bezier_points] or [p.radius for p in spline.points]
    length = sum((b - a).length for a, b in zip(pts[:-1], pts[1:], strict=True))
    girth = 2.0 * math.pi * max(radii[0] * max(curve.data.bevel_depth, 1e-6), 1e-6)
    return float(min(max(round(length / girth), 1), 64))


def _collect(context, objects: list, name: str):
    """Move ``objects`` into the ``TreeSketch`` collection under a new empty ``name``
    (Blender makes the name unique: maple, maple.001, ...); returns the empty."""
    coll = bpy.data.collections.get(COLLECTION)
    if coll is None:
        coll = bpy.data.collections.new(COLLECTION)
    if coll.name not in context.scene.collection.children:
        context.scene.collection.children.link(coll)
    parent = bpy.data.objects.new(name, None)
    parent.empty_display_type = "PLAIN_AXES"
    coll.objects.link(parent)
    for o in objects:
        for c in list(o.users_collection):
            c.objects.unlink(o)
        coll.objects.link(o)
        if o.parent is None:
            o.parent = parent
    return parent


def _enable_sapling() -> None:
    """Turn Sapling Tree Gen on (bundled up to Blender 4.1; an extension from 4.2)."""
    import addon_utils

    addons = bpy.context.preferences.addons
    names = [SAPLING] + [
        m.__name__
        for m in addon_utils.modules()
        if m.__name__.endswith((".sapling_tree_gen", "." + SAPLING))
    ]
    for name in names:
        if name not in addons:
            addon_utils.enable(name, default_set=True)
        if name in addons:
            return
    raise backend.PredictError(
        "Sapling Tree Gen is not installed in this Blender (from 4.2 it is an extension: "
        "Edit > Preferences > Get Extensions); or add the tree as Mesh (GLB)"
    )


def _copy_to_sapling_menu(preset: Path, species: str | None) -> Path:
    """The preset in Sapling's Import Preset menu, under a name of its own (an earlier
    prediction's is never overwritten)."""
    folder = Path(
        bpy.utils.user_resource("SCRIPTS", path=f"presets/operator/{SAPLING}", create=True)
    )
    target = folder / backend.preset_name(species, (p.name for p in folder.iterdir()))
    target.write_bytes(preset.read_bytes())
    return target


class TREESKETCH_OT_predict(bpy.types.Operator):
    """Predict a 3D tree from the drawing and add it to the scene"""

    bl_idname = "treesketch.predict"
    bl_label = "Sketch to Tree"
    # not REGISTER: Sapling's tree_add, run inside, stays the last operator, so the
    # redo panel edits the Sapling tree (ours would re-run the whole prediction)
    bl_options = {"UNDO"}

    wait: BoolProperty(
        name="Wait", description="Run in the foreground (scripts, background mode)", default=False
    )

    _timer = None
    _thread = None
    _lines: queue.Queue
    _cancel = False
    _species = None
    _species_text = None
    _preview = ""  # the parent empty of the tree shown while it refines

    def execute(self, context):
        settings = context.scene.treesketch
        settings.species_text = ""  # an earlier prediction's words would mislead
        folder = Path(tempfile.mkdtemp(prefix="treesketch-"))
        self._folder, self._out = folder, backend.Outputs.in_folder(folder)
        try:
            if settings.result == "SAPLING" and _prefs(context).backend == "CLI":
                _enable_sapling()  # before the prediction, not after a minute of it
            job = prediction_job(context, drawing_files(context, folder), self._out)
        except backend.PredictError as exc:
            shutil.rmtree(folder, ignore_errors=True)
            settings.status = str(exc)
            self.report({"ERROR"}, str(exc))
            return {"CANCELLED"}
        # the CLI keeps the current best tree there while it refines (the service's
        # one-request path has none)
        self._watch = backend.PreviewWatch(self._out.preview)
        self._lines = queue.Queue()
        self._error = None

        def work():
            try:
                self._species, self._species_text = job(
                    on_line=self._lines.put, cancel=lambda: self._cancel
                )
            except Exception as exc:  # shown in the panel, never lost in a thread
                self._error = exc

        settings.running, settings.progress, settings.status = True, 0.0, "starting..."
        settings.previews = 0
        # the prediction runs in a thread; Blender's data is touched only here, on the
        # main thread: by the modal timer, or by the loop below in the foreground
        self._thread = threading.Thread(target=work, daemon=True)
        self._thread.start()
        if self.wait or bpy.app.background:
            while self._thread.is_alive():
                self._thread.join(0.25)
                self._update(context, echo=True)
            return self._done(context)
        wm = context.window_manager
        self._timer = wm.event_timer_add(0.25, window=context.window)
        wm.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        if event.type == "ESC":
            self._cancel = True
        if event.type != "TIMER":
            return {"PASS_THROUGH"}
        self._update(context)
        for area in context.screen.areas if context.screen else []:
            area.tag_redraw()
        if self._thread.is_alive():
            return {"RUNNING_MODAL"}
        context.window_manager.event_timer_remove(self._timer)
        return self._done(context)

    def _update(self, context, echo: bool = False) -> None:
        """The CLI's new lines into the panel, and its newest tree into the scene."""
        settings = context.scene.treesketch
        while not self._lines.empty():
            line = self._lines.get()
            if echo:
                print("treesketch:", line)
            settings.status = line[:80]
            frac = backend.progress_fraction(line)
            if frac is not None:
                settings.progress = frac
        path = self._watch.poll()
        if path is None:
            return
        try:
            self._show_preview(context, path)
        except (backend.PredictError, RuntimeError, OSError) as exc:
            # a preview that cannot be shown is no reason to stop the prediction
            print("treesketch: preview not shown:", backend.plain_error(exc))

    def _show_preview(self, context, path: Path) -> None:
        """The refinement's current best tree in place of the last one shown (a light
        GLB, also when the result is to be a Sapling tree: Sapling builds slower)."""
        _remove_tree(self._preview)
        before = set(bpy.data.objects)
        _import_glb(path)
        new = [o for o in bpy.data.objects if o not in before]
        self._preview = _collect(context, new, "TreeSketch preview").name
        context.scene.treesketch.previews = self._watch.shown

    def _done(self, context) -> set:
        settings = context.scene.treesketch
        settings.running = False
        _remove_tree(self._preview)
        self._preview = ""
        if self._error is not None:
            shutil.rmtree(self._folder, ignore_errors=True)
            return self._failed(settings, self._error)
        return self._finish(context)

    def _failed(self, settings, exc: BaseException) -> set:
        # plain words, never Blender's "Error: Python: Traceback ..." (a failing CLI's
        # message keeps its last lines below the first)
        text = backend.plain_error(exc)
        settings.status = text[:120]
        self.report({"ERROR"}, text if "Traceback" in str(exc) else str(exc))
        return {"CANCELLED"}

    def _finish(self, context) -> set:
        """Add the tree, then drop the prediction's files (the GLB's images are packed
        into the .blend by the importer; the preset was copied to Sapling's menu)."""
        settings = context.scene.treesketch
        try:
            try:
                load_outlines(self._out.outlines)
            except (RuntimeError, OSError) as exc:  # a picture Blender cannot read
                print("treesketch: outlines not shown:", backend.plain_error(exc))
            new = add_result(context, self._out, species=self._species)
            _remember(context, self._out, self._species, new[0].name)  # before the files go
        except (backend.PredictError, RuntimeError, OSError) as exc:
            return self._failed(settings, exc)
        finally:
            shutil.rmtree(self._folder, ignore_errors=True)
        settings.progress, settings.status = 1.0, f"added {new[0].name} ({len(new) - 1} object(s))"
        settings.species_text = self._species_text or ""
        return {"FINISHED"}


def _remember(context, out: backend.Outputs, species, tree: str) -> None:
    """Keep what the controls edit: the prediction's parameters, species and view."""
    settings = context.scene.treesketch
    if not out.params.is_file():
        return
    settings.last_params = out.params.read_text(encoding="utf-8")
    settings.last_species = species or ""
    settings.last_yaw = backend.read_preset(out.preset)[1] if out.preset.is_file() else 0.0
    settings.last_tree = tree
    _reset_controls(context)


class TREESKETCH_OT_apply_controls(bpy.types.Operator):
    """Grow the predicted tree again with the panel's controls (it replaces the tree on
    show)"""

    bl_idname = "treesketch.apply_controls"
    bl_label = "Apply"
    bl_options = {"UNDO"}

    def execute(self, context):
        settings, prefs = context.scene.treesketch, _prefs(context)
        if not settings.last_params:
            return self._failed(settings, "make a tree first (Sketch to Tree)")
        ctl = context.scene.treesketch_controls
        changed = backend.changed_controls(
            CONTROLS, {r["name"]: getattr(ctl, r["name"]) for r in CONTROLS}
        )
        species = settings.last_species or None
        folder = Path(tempfile.mkdtemp(prefix="treesketch-edit-"))
        out = backend.Outputs.in_folder(folder)
        try:
            if prefs.backend == "CLI":
                params = folder / "predicted.json"
                params.write_text(settings.last_params, encoding="utf-8")
                cmd = backend.grow_command(
                    bpy.path.abspath(prefs.cli_path) or "treesketch", params, out, changed
                )
                cmd += ["--yaw", f"{settings.last_yaw:g}"]
                backend.run_cli(cmd, lambda s: print("treesketch:", s))
                yaw = None  # the GLB and the preset carry the view
            else:
                backend.post_trees(
                    str(prefs.service_url),
                    json.loads(settings.last_params),
                    changed,
                    species,
                    out,
                )
                out.preset.unlink(missing_ok=True)  # (none: the service makes no preset)
                yaw = settings.last_yaw
            _remove_tree(settings.last_tree)
            new = add_result(context, out, yaw=yaw, species=species)
        except (backend.PredictError, RuntimeError, OSError, ValueError) as exc:
            return self._failed(settings, backend.plain_error(exc))
        finally:
            shutil.rmtree(folder, ignore_errors=True)
        settings.last_tree = new[0].name
        what = ", ".join(f"{k}={v}" for k, v in changed.items()) or "as predicted"
        settings.status = f"{new[0].name}: {what}"[:120]
        return {"FINISHED"}

    def _failed(self, settings, text: str) -> set:
        settings.status = text[:120]
        self.report({"ERROR"}, text)
        return {"CANCELLED"}


class TREESKETCH_OT_variant(bpy.types.Operator):
    """Another tree of the same kind (a new seed), then apply"""

    bl_idname = "treesketch.variant"
    bl_label = "Another variant"
    bl_options = {"UNDO"}

    def execute(self, context):
        seed = next((r for r in CONTROLS if r["name"] == "seed"), None)
        if seed is not None:
            context.scene.treesketch_controls.seed = random.randrange(int(seed["max"]))
        return bpy.ops.treesketch.apply_controls()


class TREESKETCH_OT_reset_controls(bpy.types.Operator):
    """Every control back to the predicted tree's own, then apply"""

    bl_idname = "treesketch.reset_controls"
    bl_label = "Reset"
    bl_options = {"UNDO"}

    def execute(self, context):
        _reset_controls(context)
        return bpy.ops.treesketch.apply_controls()


class TREESKETCH_PT_panel(bpy.types.Panel):
    bl_label = "TreeSketch"
    bl_idname = "VIEW3D_PT_treesketch"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "TreeSketch"

    def draw(self, context):
        settings = context.scene.treesketch
        layout = self.layout
        layout.prop(settings, "source", expand=True)
        if settings.source == "IMAGE":
            layout.prop(settings, "image_path")
        else:
            obj = context.active_object
            ok = obj is not None and obj.type in GPENCIL_TYPES
            layout.label(
                text=obj.name if ok else "select a Grease Pencil drawing", icon="GREASEPENCIL"
            )
            if ok:
                try:
                    named = backend.view_layers(_layer_name(la) for la in obj.data.layers)
                    text = "views: " + ", ".join(v.title() for _, v in named) if named else ""
                except backend.PredictError as exc:
                    text = str(exc)[:80]
                if text:
                    layout.label(text=text)
        layout.prop(settings, "species")
        layout.prop(settings, "result", expand=True)
        row = layout.row()
        row.prop(settings, "refine")
        sub = row.row()
        sub.enabled = settings.refine
        sub.prop(settings, "budget")
        col = layout.column()
        col.enabled = not settings.running
        col.operator(TREESKETCH_OT_predict.bl_idname, icon="OUTLINER_OB_CURVE")
        if settings.running:
            layout.prop(settings, "progress", text="Progress (Esc cancels)")
        if settings.status:
            layout.label(text=settings.status)
        if settings.species_text and not settings.running:
            layout.label(text=f"It is {settings.species_text}", icon="INFO")
        outlines = bpy.data.images.get(OUTLINES_IMAGE)
        if outlines is not None and settings.last_params and not settings.running:
            box = layout.box()
            box.label(text="Your drawing's outline (red) over the tree's (blue)")
            outlines.preview_ensure()
            box.template_icon(icon_value=outlines.preview.icon_id, scale=8.0)
        if settings.last_params and CONTROLS:
            box = layout.box()
            box.label(text=f"Shape the {settings.last_species or 'tree'}")
            ctl = context.scene.treesketch_controls
            for r in CONTROLS:
                box.prop(ctl, r["name"])
            row = box.row()
            row.operator(TREESKETCH_OT_apply_controls.bl_idname)
            row.operator(TREESKETCH_OT_variant.bl_idname)
            row.operator(TREESKETCH_OT_reset_controls.bl_idname)


CLASSES = (
    TREESKETCH_Preferences,
    TREESKETCH_Settings,
    TREESKETCH_Controls,
    TREESKETCH_OT_predict,
    TREESKETCH_OT_apply_controls,
    TREESKETCH_OT_variant,
    TREESKETCH_OT_reset_controls,
    TREESKETCH_PT_panel,
)


def register() -> None:
    # while the add-on is on, Blender 3.4's own glTF import works too (it calls np.bool)
    backend.numpy_bool_alias()
    for cls in CLASSES:
        bpy.utils.register_class(cls)
    bpy.types.Scene.treesketch = bpy.props.PointerProperty(type=TREESKETCH_Settings)
    bpy.types.Scene.treesketch_controls = bpy.props.PointerProperty(type=TREESKETCH_Controls)


def unregister() -> None:
    del bpy.types.Scene.treesketch_controls
    del bpy.types.Scene.treesketch
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
