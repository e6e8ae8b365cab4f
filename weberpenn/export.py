"""Write trees out as GLB or OBJ meshes that stand up in Blender and every glTF viewer.

- :func:`glb_bytes` / :func:`export_mesh` (``.glb``): two named meshes, ``branches`` and
  ``leaves``, Y-up in metres with the trunk base at the origin (``weberpenn.orient``),
  each with a PBR material; with ``textures`` (the default) the bark and the leaves carry
  the project's per-species textures (``weberpenn.textures``) embedded in the file, the
  leaves alpha-masked, else flat species colours.
- :func:`obj_files` / :func:`export_mesh` (``.obj``): the same as an OBJ in Blender's
  default OBJ axes (up +Y, forward -Z), a ``.mtl`` beside it and, with textures, the two
  PNGs it names; all files land together or none.
- Options shared by both: ``yaw`` (degrees) turns the tree so the view it was drawn from
  faces the front view; ``max_faces`` keeps it under that many triangles
  (``weberpenn.lod``).  Empty meshes are left out of the file.
- Sapling presets live in ``weberpenn.preset`` (re-exported here).
"""

from __future__ import annotations

import io
import os
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np
import trimesh
from PIL import Image
from trimesh.visual import TextureVisuals
from trimesh.visual.material import PBRMaterial

from .fileio import write_together
from .lod import lod
from .orient import to_export_frame
from .preset import (
    SAPLING_KEYS,
    preset_text,
    sapling_preset_text,
    save_sapling_preset,
    to_sapling,
)
from .textures import COLOURS, bark_texture, colours, leaf_texture
from .treemesh import TreeMesh
from .uv import close_seams

__all__ = [
    "COLOURS",
    "SAPLING_KEYS",
    "TEXTURE_SIZE",
    "colours",
    "export_mesh",
    "glb_bytes",
    "mesh_files",
    "mesh_paths",
    "obj_files",
    "preset_text",
    "sapling_preset_text",
    "save_sapling_preset",
    "to_sapling",
]

#: Pixel size of the embedded textures (square).
TEXTURE_SIZE = 256


@dataclass(frozen=True)
class _Part:
    name: str
    material: str
    vertices: np.ndarray  # (V, 3) export frame
    faces: np.ndarray  # (F, 3)
    uv: np.ndarray | None  # (V, 2), OBJ/trimesh convention (v up)


def _parts(tm: TreeMesh, yaw: float, max_faces: int | None) -> list[_Part]:
    if not isinstance(tm, TreeMesh):
        raise TypeError(f"expected a weberpenn TreeMesh, got {type(tm).__name__}")
    if tm.is_empty:
        raise ValueError("cannot export an empty tree (no branch or leaf faces)")
    if max_faces is not None:
        tm = lod(tm, max_faces)
    out = []
    for name, mesh, mat in (("branches", tm.branches, "bark"), ("leaves", tm.leaves, "leaf")):
        if len(mesh.faces) == 0:
            continue
        v, f = np.asarray(mesh.vertices), np.asarray(mesh.faces, dtype=np.int64)
        uv = getattr(mesh.visual, "uv", None)
        uv = None if uv is None or len(uv) != len(v) else np.asarray(uv, dtype=np.float64)
        if uv is not None and name == "branches":
            f, src, uv = close_seams(f, uv)
            v = v[src]
        out.append(_Part(name, mat, to_export_frame(v, yaw), f, uv))
    return out


class _EncodedTexture(Image.Image):
    """A texture that saves as PNG from bytes encoded once.  trimesh PNG-encodes every
    material image on every GLB export: half of a slider edit's time (issue 49).  The
    bytes are those of a plain ``save(f, format="png")``, so the file is unchanged; any
    other save encodes as usual."""

    png: bytes = b""

    def save(self, fp: Any, format: str | None = None, **params: Any) -> None:  # noqa: A002
        if self.png and str(format).lower() == "png" and not params and hasattr(fp, "write"):
            fp.write(self.png)
            return
        super().save(fp, format, **params)


def _encoded(image: Image.Image) -> Image.Image:
    buf = io.BytesIO()
    image.save(buf, format="png")  # as trimesh saves it
    out = image.copy()
    out.__class__ = _EncodedTexture  # a subclass adding only a method and a field
    out.png = buf.getvalue()
    return out


@lru_cache(maxsize=32)
def _textures(species: str | None) -> dict[str, Image.Image]:
    # a pure function of the species, made per export before: an edit's light GLB paid
    # for drawing both pictures every time (read-only for the callers)
    return {
        "bark": _encoded(bark_texture(species, TEXTURE_SIZE)),
        "leaf": _encoded(leaf_texture(species, TEXTURE_SIZE)),
    }


def _material(name: str, species: str | None, image: Image.Image | None) -> PBRMaterial:
    bark, leaf = colours(species)
    rgb, rough = (bark, 0.9) if name == "bark" else (leaf, 0.6)
    if image is None:
        factor = [int(round(255 * c)) for c in rgb] + [255]
        return PBRMaterial(
            name=name,
            baseColorFactor=factor,
            metallicFactor=0.0,
            roughnessFactor=rough,
            doubleSided=True,
        )
    return PBRMaterial(
        name=name,
        baseColorTexture=image,
        baseColorFactor=[255, 255, 255, 255],
        metallicFactor=0.0,
        roughnessFactor=rough,
        doubleSided=True,
        alphaMode="MASK" if name == "leaf" else "OPAQUE",
        alphaCutoff=0.5 if name == "leaf" else None,
    )


def glb_bytes(
    tree_mesh: TreeMesh,
    *,
    yaw: float = 0.0,
    max_faces: int | None = None,
    textures: bool = True,
) -> bytes:
    """The tree as a binary glTF (see the module docstring for the options)."""
    parts = _parts(tree_mesh, yaw, max_faces)
    images = _textures(tree_mesh.species) if textures else {}
    scene = trimesh.Scene()
    for part in parts:
        m = trimesh.Trimesh(vertices=part.vertices, faces=part.faces, process=False)
        mat = _material(part.material, tree_mesh.species, images.get(part.material))
        m.visual = TextureVisuals(uv=part.uv if textures else None, material=mat)
        scene.add_geometry(m, node_name=part.name, geom_name=part.name)
    return scene.export(file_type="glb")


def _fmt_rows(prefix: str, arr: np.ndarray, fmt: str) -> str:
    buf = io.StringIO()
    np.savetxt(buf, arr, fmt=fmt, delimiter=" ")
    return "".join(f"{prefix} {line}\n" for line in buf.getvalue().splitlines())


def _png(image: Image.Image) -> bytes:
    buf = io.BytesIO()
    image.save(buf, format="PNG", optimize=True)
    return buf.getvalue()


def obj_files(
    tree_mesh: TreeMesh,
    path: str | os.PathLike[str],
    *,
    yaw: float = 0.0,
    max_faces: int | None = None,
    textures: bool = True,
) -> dict[Path, bytes | str]:
    """``{path: content}`` of an OBJ export: the ``.obj``, its ``.mtl`` and, with
    textures, ``<stem>_bark.png`` and ``<stem>_leaf.png`` beside it."""
    path = Path(path)
    parts = _parts(tree_mesh, yaw, max_faces)
    mtl_path = path.with_suffix(".mtl")
    lines = [f"# TreeSketch tree ({tree_mesh.species or 'custom'}), Y up, metres\n"]
    lines.append(f"mtllib {mtl_path.name}\n")
    base_v = base_t = 1
    for part in parts:
        lines.append(f"o {part.name}\ng {part.name}\nusemtl {part.material}\n")
        lines.append(_fmt_rows("v", part.vertices, "%.6f"))
        f = part.faces + base_v
        if part.uv is not None and textures:
            lines.append(_fmt_rows("vt", part.uv, "%.5f"))
            ft = part.faces + base_t
            cols = np.stack([f, ft], axis=-1).reshape(len(f), 6)
            lines.append(_fmt_rows("f", cols, "%d/%d %d/%d %d/%d"))
            base_t += len(part.uv)
        else:
            lines.append(_fmt_rows("f", f, "%d"))
        base_v += len(part.vertices)
    files: dict[Path, bytes | str] = {path: "".join(lines)}
    bark, leaf = colours(tree_mesh.species)
    mtl = []
    images = _textures(tree_mesh.species) if textures else {}
    for name, rgb in (("bark", bark), ("leaf", leaf)):
        block = f"newmtl {name}\nKd {rgb[0]:.4f} {rgb[1]:.4f} {rgb[2]:.4f}\nKa 0 0 0\nd 1\n"
        if name in images:
            png = _texture_path(path, name)
            files[png] = _png(images[name])
            block = f"newmtl {name}\nKd 1 1 1\nKa 0 0 0\nd 1\nmap_Kd {png.name}\n"
            if name == "leaf":
                block += f"map_d {png.name}\n"
        mtl.append(block)
    files[mtl_path] = "\n".join(mtl)
    return files


def _mesh_format(path: Path) -> str:
    """``glb`` or ``obj``, by the path's suffix (``.gltf`` is written as ``.glb``)."""
    suffix = path.suffix.lower()
    if suffix in (".glb", ".gltf"):
        return "glb"
    if suffix == ".obj":
        return "obj"
    raise ValueError(f"{path}: unknown mesh format {suffix!r} (use .glb or .obj)")


def mesh_paths(path: str | os.PathLike[str], *, textures: bool = True) -> list[Path]:
    """The files a mesh export to ``path`` writes (:func:`mesh_files`), known before the
    tree is grown: for checking outputs first (``weberpenn.fileio.check_targets``)."""
    path = Path(path)
    if _mesh_format(path) == "glb":
        return [path.with_suffix(".glb")]
    extra = [_texture_path(path, name) for name in ("bark", "leaf")] if textures else []
    return [path, path.with_suffix(".mtl"), *extra]


def _texture_path(obj: Path, name: str) -> Path:
    return obj.with_name(f"{obj.stem}_{name}.png")


def mesh_files(
    tree_mesh: TreeMesh, path: str | os.PathLike[str], **options: Any
) -> dict[Path, bytes | str]:
    """``{path: content}`` of a mesh export by the path's suffix (``.glb``: one file, see
    :func:`glb_bytes`; ``.obj``: see :func:`obj_files`; ``options``: theirs, ``yaw``,
    ``max_faces``, ``textures``), for ``weberpenn.fileio.write_together`` beside other
    outputs."""
    path = Path(path)
    if _mesh_format(path) == "glb":
        return {path.with_suffix(".glb"): glb_bytes(tree_mesh, **options)}
    return obj_files(tree_mesh, path, **options)


def export_mesh(tree_mesh: TreeMesh, path: str | os.PathLike[str], **options: Any) -> Path:
    """Write the tree as ``.glb`` (``.gltf`` is written as ``.glb``) or ``.obj`` (+ ``.mtl``
    and textures), all files or none (``options`` as for :func:`mesh_files`); returns the
    mesh file's path."""
    files = mesh_files(tree_mesh, path, **options)
    write_together(files)
    return next(iter(files))
