"""What a :class:`treesketch.Result` becomes on disk or over HTTP, made in one place.

``result_files(result, kinds)`` gives the bytes of each requested artefact;
``write_outputs(result, {kind: path})`` writes them all or none
(``weberpenn.fileio.write_together``).  Kinds:

========== ==========================================================================
glb        the tree (branches and leaves), binary glTF
obj        the tree as Wavefront OBJ (+ its .mtl beside it, written together)
json       the parameter dictionary (Sapling key names)
preset     a Blender Sapling preset (.py)
compare    PNG: input sketch | first estimate's sketch | refined sketch | colour render
sketch_before, sketch_after   PNG: the first estimate's and the result's sketches
summary    JSON: species and scores, losses, yaw, confidence, warning, timings
========== ==========================================================================
"""

from __future__ import annotations

import io
import json
import os
import tempfile
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from weberpenn.fileio import write_together

__all__ = ["KINDS", "compare_image", "png_bytes", "result_files", "write_outputs"]

KINDS = (
    "glb",
    "obj",
    "json",
    "preset",
    "compare",
    "sketch_before",
    "sketch_after",
    "summary",
)


def png_bytes(img: np.ndarray) -> bytes:
    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(np.asarray(img, np.uint8)).save(buf, format="PNG")
    return buf.getvalue()


def compare_image(result: Any, size: int = 256) -> np.ndarray:
    """Side by side: input sketch | first estimate's sketch | refined sketch | colour render
    (RGB uint8, captioned)."""
    from PIL import Image, ImageDraw

    from render.sketch import SketchRenderer

    def grey(img: np.ndarray) -> Image.Image:
        return Image.fromarray(np.asarray(img, np.uint8)).convert("RGB").resize((size, size))

    colour = SketchRenderer(result.tree_mesh, species=result.species).colour(
        result.yaw, size, supersample=2
    )
    panels = [
        ("input sketch", grey(result.input_sketch)),
        (f"{result.estimator} ({result.losses['before']:.3f})", grey(result.sketch_before)),
        (f"refined ({result.losses['after']:.3f})", grey(result.sketch_after)),
        (f"{result.species}, yaw {result.yaw:.0f}", Image.fromarray(colour).convert("RGB")),
    ]
    cap = 18
    out = Image.new("RGB", (size * len(panels), size + cap), (255, 255, 255))
    draw = ImageDraw.Draw(out)
    for i, (title, im) in enumerate(panels):
        out.paste(im, (i * size, cap))
        draw.text((i * size + 4, 3), title, fill=(0, 0, 0))
        if i:
            draw.line([(i * size, 0), (i * size, size + cap)], fill=(180, 180, 180))
    return np.asarray(out)


def _mesh_bytes(tree_mesh: Any, suffix: str) -> dict[str, bytes]:
    """The mesh file (and for OBJ its material library) as bytes, keyed by suffix."""
    from weberpenn.export import export_mesh

    with tempfile.TemporaryDirectory(prefix="treesketch-") as d:
        path = export_mesh(tree_mesh, Path(d) / f"tree{suffix}")
        return {p.suffix: p.read_bytes() for p in Path(d).iterdir() if p.stem == path.stem}


def result_files(result: Any, kinds: Iterable[str]) -> dict[str, bytes]:
    """The bytes of each artefact kind asked for (see the module text)."""
    from weberpenn.export import sapling_preset_text

    wanted = list(dict.fromkeys(kinds))
    unknown = [k for k in wanted if k not in KINDS]
    if unknown:
        raise ValueError(f"unknown output kind(s) {', '.join(unknown)}; choose from {KINDS}")
    out: dict[str, bytes] = {}
    for kind in wanted:
        if kind == "glb":
            out[kind] = _mesh_bytes(result.tree_mesh, ".glb")[".glb"]
        elif kind == "obj":
            files = _mesh_bytes(result.tree_mesh, ".obj")
            out["obj"] = files[".obj"]
            if ".mtl" in files:
                out["mtl"] = files[".mtl"]
        elif kind == "json":
            out[kind] = (json.dumps(result.params.to_dict(), indent=1) + "\n").encode()
        elif kind == "preset":
            out[kind] = sapling_preset_text(result.params).encode()
        elif kind == "compare":
            out[kind] = png_bytes(compare_image(result))
        elif kind in ("sketch_before", "sketch_after"):
            out[kind] = png_bytes(getattr(result, kind))
        elif kind == "summary":
            out[kind] = (json.dumps(result.summary(), indent=1, default=float) + "\n").encode()
    return out


def write_outputs(result: Any, outputs: Mapping[str, str | os.PathLike[str] | None]) -> list[Path]:
    """Write the requested outputs ``{kind: path}`` (None entries skipped) all or nothing.

    ``kind`` "mesh" picks GLB or OBJ from the path's suffix; an OBJ's material library is
    written beside it, in the same all-or-nothing set."""
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
    for kind, path in paths.items():
        if path.is_dir():
            raise ValueError(f"{path} is a folder; give a file name for the {kind} output")
    data = result_files(result, paths)
    files: dict[Path, bytes] = {paths[k]: v for k, v in data.items() if k in paths}
    if "mtl" in data:
        files[paths["obj"].with_suffix(".mtl")] = data["mtl"]
    return write_together(files)
