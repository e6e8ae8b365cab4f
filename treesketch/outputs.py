"""What a :class:`treesketch.Result` becomes on disk or over HTTP, made in one place.

``result_files(result, kinds)`` gives the bytes of each requested artefact;
``write_outputs(result, {kind: path})`` writes them all or none
(``weberpenn.fileio.write_together``).  Kinds:

========== ==========================================================================
glb        the tree (branches and leaves), binary glTF, Y-up, textured
obj        the tree as Wavefront OBJ (+ its .mtl and textures beside it, written together)
json       the parameter dictionary (Sapling key names)
preset     a Blender Sapling preset (.py)
compare    PNG: input sketch | first estimate's sketch | refined sketch with the drawing's
           outline (red) over the tree's (blue) | colour render
sketch_before, sketch_after   PNG: the first estimate's and the result's sketches
outlines   PNG: the drawing's outline (red) over the tree's (blue), at the drawn view
           (``outlines_images``); the views side by side when the tree was drawn from
           several sides
summary    JSON: species and scores, losses, yaw, confidence, warning, timings
========== ==========================================================================
"""

from __future__ import annotations

import io
import json
import os
from collections.abc import Iterable, Mapping
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from weberpenn.fileio import check_targets, write_together

__all__ = [
    "KINDS",
    "ExportOptions",
    "compare_image",
    "outlines_images",
    "png_bytes",
    "result_files",
    "write_outputs",
]

KINDS = (
    "glb",
    "obj",
    "json",
    "preset",
    "compare",
    "outlines",
    "sketch_before",
    "sketch_after",
    "summary",
)


def png_bytes(img: np.ndarray) -> bytes:
    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(np.asarray(img, np.uint8)).save(buf, format="PNG")
    return buf.getvalue()


def outlines_images(result: Any) -> list[np.ndarray | None]:
    """One picture per drawn view (RGB uint8, the sketches' size): the drawing's outline
    (red) over the returned tree's (blue) seen from that view
    (``refine.envelope.outlines_rgb`` of the prepared drawing and the tree's sketch).
    None for a view whose drawing is not kept or differs in size (a result not made by
    the pipeline): nothing to lay over."""
    from refine.envelope import outlines_rgb

    return [
        None
        if v.input_sketch is None or np.shape(v.input_sketch) != np.shape(v.sketch_after)
        else outlines_rgb(v.input_sketch, v.sketch_after)
        for v in result.views or (result,)
    ]


def outlines_strip(result: Any) -> np.ndarray:
    """:func:`outlines_images` side by side (the tree's sketch alone for a view without
    its drawing): the ``outlines`` kind."""
    pictures = [
        np.repeat(np.asarray(v.sketch_after, np.uint8)[..., None], 3, axis=2)
        if pic is None
        else pic
        for pic, v in zip(outlines_images(result), result.views or (result,), strict=True)
    ]
    return np.concatenate(pictures, axis=1)


def compare_image(result: Any, size: int = 256) -> np.ndarray:
    """Side by side: input sketch | first estimate's sketch | refined sketch, with the
    drawing's outline (red) over the tree's (blue) | colour render (RGB uint8, captioned);
    one row per view when the tree was drawn from several sides."""
    from PIL import Image, ImageDraw, ImageFont

    from render.sketch import SketchRenderer

    def grey(img: np.ndarray) -> Image.Image:
        return Image.fromarray(np.asarray(img, np.uint8)).convert("RGB").resize((size, size))

    # the drawing's outline (red) over the tree's (blue): does the tree follow it?
    outlines = outlines_images(result)

    def outlined(i: int, tree: np.ndarray) -> Image.Image:
        pic = outlines[i]
        return grey(tree) if pic is None else Image.fromarray(pic).resize((size, size))

    renderer = SketchRenderer(result.tree_mesh, species=result.species)
    views = result.views or ()
    rows = []
    for i in range(max(1, len(views))):
        turn = views[i].yaw if views else 0.0
        yaw = (result.yaw + turn) % 360.0
        colour = renderer.colour(yaw, size, supersample=2)
        if i == 0:
            before, after = result.losses["before"], result.losses["after"]
            side = ""
        else:
            before, after = views[i].loss_before, views[i].loss_after
            side = f"view {i + 1} (+{turn:.0f}) "
        rows.append(
            [
                (
                    side + "input sketch",
                    grey(views[i].input_sketch if views else result.input_sketch),
                ),
                (
                    f"{result.estimator} ({before:.3f})",
                    grey(views[i].sketch_before if views else result.sketch_before),
                ),
                (
                    f"refined ({after:.3f}); outlines",
                    outlined(i, views[i].sketch_after if views else result.sketch_after),
                ),
                (f"{result.species}, yaw {yaw:.0f}", Image.fromarray(colour).convert("RGB")),
            ]
        )
    # captions in a scalable font, legible in a picture viewer at its size (PIL's bitmap
    # default ran words together)
    font = ImageFont.load_default(size=max(11, round(size / 20)))
    cap = round(font.size * 1.6)
    height = size + cap
    out = Image.new("RGB", (size * len(rows[0]), height * len(rows)), (255, 255, 255))
    draw = ImageDraw.Draw(out)
    for r, panels in enumerate(rows):
        top = r * height
        for i, (title, im) in enumerate(panels):
            out.paste(im, (i * size, top + cap))
            draw.text((i * size + 4, top + 3), title, fill=(0, 0, 0), font=font)
            if i:
                draw.line([(i * size, top), (i * size, top + height)], fill=(180, 180, 180))
        if r:
            draw.line([(0, top), (size * len(panels), top)], fill=(180, 180, 180))
    return np.asarray(out)


@dataclass(frozen=True)
class ExportOptions:
    """How the tree is exported: ``face_view`` turns it so Blender's (and any glTF
    viewer's) front view shows it as it was drawn (the yaw the refinement found);
    ``max_faces`` keeps it under that many triangles (``weberpenn.lod``); ``textures``
    embeds the species' bark and leaf textures (else flat colours)."""

    face_view: bool = True
    max_faces: int | None = None
    textures: bool = True

    def validate(self) -> ExportOptions:
        if self.max_faces is not None:
            from weberpenn.lod import check_budget

            check_budget(self.max_faces)
        return self

    def mesh_kwargs(self, result: Any) -> dict[str, Any]:
        yaw = float(result.yaw) if self.face_view else 0.0
        return {"yaw": yaw, "max_faces": self.max_faces, "textures": self.textures}


def result_files(
    result: Any, kinds: Iterable[str], options: ExportOptions | None = None
) -> dict[str, bytes]:
    """The bytes of each artefact kind asked for (see the module text); an OBJ comes with
    its material library and texture pictures, named ``tree.obj``, ``tree.mtl``, ...."""
    from weberpenn.export import glb_bytes, obj_files
    from weberpenn.params import params_text
    from weberpenn.preset import preset_text

    opts = (options or ExportOptions()).validate()
    wanted = list(dict.fromkeys(kinds))
    unknown = [k for k in wanted if k not in KINDS]
    if unknown:
        raise ValueError(f"unknown output kind(s) {', '.join(unknown)}; choose from {KINDS}")
    out: dict[str, bytes] = {}
    for kind in wanted:
        if kind == "glb":
            out[kind] = glb_bytes(result.tree_mesh, **opts.mesh_kwargs(result))
        elif kind == "obj":
            files = obj_files(result.tree_mesh, Path("tree.obj"), **opts.mesh_kwargs(result))
            for path, content in files.items():
                key = "obj" if path.suffix == ".obj" else path.name
                out[key] = content.encode() if isinstance(content, str) else content
        elif kind == "json":
            out[kind] = params_text(result.params).encode()
        elif kind == "preset":
            yaw = float(result.yaw) if opts.face_view else None
            out[kind] = preset_text(result.params, yaw=yaw).encode()
        elif kind == "compare":
            out[kind] = png_bytes(compare_image(result))
        elif kind == "outlines":
            out[kind] = png_bytes(outlines_strip(result))
        elif kind in ("sketch_before", "sketch_after"):
            out[kind] = png_bytes(getattr(result, kind))
        elif kind == "summary":
            summary = {**result.summary(), "export": asdict(opts)}
            out[kind] = (json.dumps(summary, indent=1, default=float) + "\n").encode()
    return out


def write_outputs(
    result: Any,
    outputs: Mapping[str, str | os.PathLike[str] | None],
    options: ExportOptions | None = None,
) -> list[Path]:
    """Write the requested outputs ``{kind: path}`` (None entries skipped) all or nothing.

    ``kind`` "mesh" picks GLB or OBJ from the path's suffix; an OBJ's material library and
    texture pictures are written beside it, in the same all-or-nothing set."""
    from weberpenn.export import mesh_files, mesh_paths

    opts = (options or ExportOptions()).validate()
    paths: dict[str, Path] = {}
    for kind, p in outputs.items():
        if p is None:
            continue
        path = Path(p)
        if kind == "mesh":
            kind = path.suffix.lower().lstrip(".")
            if kind not in ("glb", "obj"):
                raise ValueError(f"{path}: unknown mesh format; use .glb or .obj")
        paths[kind] = path
    # before any bytes are made: a folder, two outputs on one file, a folder that takes
    # no file (an OutputError, a ValueError)
    check_targets(
        {
            f"the {kind} output": mesh_paths(path, textures=opts.textures)
            if kind in ("glb", "obj")
            else [path]
            for kind, path in paths.items()
        }
    )
    files: dict[Path, Any] = {}
    for kind in ("glb", "obj"):
        if kind in paths:
            files.update(mesh_files(result.tree_mesh, paths[kind], **opts.mesh_kwargs(result)))
    rest = [k for k in paths if k not in ("glb", "obj")]
    data = result_files(result, rest, opts)
    files.update({paths[k]: v for k, v in data.items() if k in paths})
    return write_together(files)
