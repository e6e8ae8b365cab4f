"""Write trees out: GLB / OBJ meshes and Sapling presets that Blender's Sapling can import.

- :func:`export_mesh` writes ``.glb`` (two named meshes, ``branches`` and ``leaves``, with a
  bark and a leaf PBR material coloured per species) or ``.obj`` (two named objects and a
  ``.mtl`` beside it).  Empty meshes are left out of the file.
- :func:`save_sapling_preset` writes the ONE-line dict literal that Sapling's "Import
  Preset" reads, holding only Sapling's own keys (TreeSketchNet's realised keys folded
  into their Sapling counterparts, see :func:`to_sapling`).
- JSON parameter files: :func:`weberpenn.params.save_params`.

All files are written to a temporary name in the target folder and then renamed.
"""

from __future__ import annotations

import io
import math
import os
import tempfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import trimesh
from trimesh.visual import TextureVisuals
from trimesh.visual.material import PBRMaterial

from .fileio import atomic_write
from .params import ParamError, TreeParams, atomic_write_text, validate
from .treemesh import TreeMesh

__all__ = [
    "COLOURS",
    "SAPLING_KEYS",
    "colours",
    "export_mesh",
    "save_sapling_preset",
    "to_sapling",
]

# (bark RGB, leaf RGB) in 0..1, per species; None = default.
COLOURS: dict[str | None, tuple[tuple[float, float, float], tuple[float, float, float]]] = {
    None: ((0.36, 0.27, 0.20), (0.25, 0.50, 0.18)),
    "maple": ((0.38, 0.30, 0.24), (0.72, 0.30, 0.10)),
    "pine": ((0.33, 0.22, 0.15), (0.13, 0.33, 0.16)),
    "bonsai": ((0.42, 0.34, 0.26), (0.22, 0.46, 0.16)),
    "palm": ((0.55, 0.45, 0.32), (0.30, 0.55, 0.20)),
    "cherry": ((0.30, 0.20, 0.18), (0.95, 0.72, 0.80)),
}

# Sapling's own operator keys that change geometry (the preset holds these and no others).
SAPLING_KEYS: tuple[str, ...] = (
    "seed", "levels", "scale", "scaleV", "shape", "shapeS", "customShape", "branchDist",
    "nrings", "baseSize", "baseSize_s", "bevel", "bevelRes", "resU", "handleType", "prune",
    "ratio", "scale0", "scaleV0", "ratioPower", "minRadius", "closeTip", "rootFlare",
    "autoTaper", "taper", "radiusTweak", "baseSplits", "segSplits", "splitByLen",
    "splitHeight", "splitBias", "splitAngle", "splitAngleV", "rotate", "rotateV", "rMode",
    "attractOut", "curveRes", "branches", "length", "lengthV", "taperCrown", "downAngle",
    "downAngleV", "useOldDownAngle", "useParentAngle", "curve", "curveBack", "curveV",
    "attractUp", "pruneRatio", "pruneWidth", "pruneBase", "pruneWidthPeak", "prunePowerHigh",
    "prunePowerLow", "showLeaves", "leaves", "leafShape", "leafDist", "leafScale",
    "leafScaleX", "leafScaleT", "leafScaleV", "leafDownAngle", "leafDownAngleV", "leafRotate",
    "leafRotateV", "horzLeaves", "leafangle", "bend", "useArm",
)  # fmt: skip

# Sapling keys our dictionary lacks, at the values our generator assumes.
_SAPLING_EXTRA: dict[str, Any] = {
    "bevel": True,
    "handleType": "0",
    "rMode": "rotate",
    "autoTaper": True,
    "closeTip": False,
    "splitByLen": False,
    "bend": 0.0,
    "useArm": False,
}


def colours(species: str | None) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """(bark, leaf) RGB for a species name (the default pair for None or an unknown name)."""
    return COLOURS.get(species, COLOURS[None])


def _tmp_path(path: Path) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    return Path(tmp)


def _atomic_bytes(path: Path, data: bytes) -> None:
    tmp = _tmp_path(path)
    try:
        tmp.write_bytes(data)
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def _material(name: str, rgb: tuple[float, float, float], rough: float) -> PBRMaterial:
    rgba = [int(round(255 * c)) for c in rgb] + [255]
    return PBRMaterial(
        name=name, baseColorFactor=rgba, metallicFactor=0.0, roughnessFactor=rough, doubleSided=True
    )


def _glb(tm: TreeMesh) -> bytes:
    bark, leaf = colours(tm.species)
    scene = trimesh.Scene()
    for name, mesh, mat in (
        ("branches", tm.branches, _material("bark", bark, 0.9)),
        ("leaves", tm.leaves, _material("leaf", leaf, 0.6)),
    ):
        if len(mesh.faces) == 0:
            continue
        uv = getattr(mesh.visual, "uv", None)
        m = trimesh.Trimesh(vertices=mesh.vertices, faces=mesh.faces, process=False)
        m.visual = TextureVisuals(uv=uv, material=mat)
        scene.add_geometry(m, node_name=name, geom_name=name)
    if not scene.geometry:
        raise ValueError("cannot export an empty tree (no branch or leaf faces)")
    return scene.export(file_type="glb")


def _fmt_rows(prefix: str, arr: np.ndarray, fmt: str) -> str:
    buf = io.StringIO()
    np.savetxt(buf, arr, fmt=fmt, delimiter=" ")
    text = buf.getvalue()
    return "".join(f"{prefix} {line}\n" for line in text.splitlines())


def _obj(tm: TreeMesh, mtl_name: str) -> str:
    parts = [f"# TreeSketch tree ({tm.species or 'custom'})\n", f"mtllib {mtl_name}\n"]
    base_v, base_t = 1, 1
    for name, mesh, mat in (("branches", tm.branches, "bark"), ("leaves", tm.leaves, "leaf")):
        if len(mesh.faces) == 0:
            continue
        parts.append(f"o {name}\ng {name}\nusemtl {mat}\n")
        parts.append(_fmt_rows("v", np.asarray(mesh.vertices), "%.6f"))
        uv = getattr(mesh.visual, "uv", None)
        f = np.asarray(mesh.faces, dtype=np.int64) + base_v
        if uv is not None and len(uv) == len(mesh.vertices):
            parts.append(_fmt_rows("vt", np.asarray(uv), "%.5f"))
            ft = np.asarray(mesh.faces, dtype=np.int64) + base_t
            cols = np.stack([f, ft], axis=-1).reshape(len(f), 6)
            parts.append(_fmt_rows("f", cols, "%d/%d %d/%d %d/%d"))
            base_t += len(uv)
        else:
            parts.append(_fmt_rows("f", f, "%d"))
        base_v += len(mesh.vertices)
    return "".join(parts)


def _mtl(tm: TreeMesh) -> str:
    bark, leaf = colours(tm.species)
    out = []
    for name, rgb in (("bark", bark), ("leaf", leaf)):
        out.append(f"newmtl {name}\nKd {rgb[0]:.4f} {rgb[1]:.4f} {rgb[2]:.4f}\nKa 0 0 0\nd 1\n")
    return "\n".join(out)


def export_mesh(tree_mesh: TreeMesh, path: str | os.PathLike[str]) -> Path:
    """Write a TreeMesh as ``.glb`` or ``.obj`` (+ ``.mtl``), atomically; returns the path."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix in (".glb", ".gltf"):
        if suffix == ".gltf":
            path = path.with_suffix(".glb")
        _atomic_bytes(path, _glb(tree_mesh))
    elif suffix == ".obj":
        mtl = path.with_suffix(".mtl")
        atomic_write_text(mtl, _mtl(tree_mesh))
        atomic_write_text(path, _obj(tree_mesh, mtl.name))
        os.chmod(mtl, 0o644)
        os.chmod(path, 0o644)
    else:
        raise ValueError(f"{path}: unknown mesh format {suffix!r} (use .glb or .obj)")
    return path


def _vec(v: Any) -> list[float]:
    return [float(x) for x in v]


def to_sapling(params: TreeParams | Mapping[str, Any]) -> dict[str, Any]:
    """Map a TreeSketchNet dictionary onto Sapling's operator keys (only those).

    curveV = (|curveV1|+|curveV2|)*curveRes; splitAngle += mean(splitAngleV1, V2) and
    splitAngleV = |V1-V2|/2; realised scaleV/scaleV0/leafScaleV are folded into
    scale/scale0/leafScale (Sapling's variations set to 0), rotateV[0] into rotate[0],
    leafRotateV into leafRotate; rLastAng, rSplits2, choiceNegPos1/2, maxBaseSplits dropped;
    seed reduced to a 32-bit signed int; Sapling-only keys get the values our generator uses.
    """
    p = validate(params).to_dict()
    out: dict[str, Any] = {}
    res = [int(x) for x in p["curveRes"]]
    v1, v2 = _vec(p["curveV1"]), _vec(p["curveV2"])
    a1, a2 = _vec(p["splitAngleV1"]), _vec(p["splitAngleV2"])
    rotate = _vec(p["rotate"])
    rotate_v = _vec(p["rotateV"])
    rotate[0] += rotate_v[0]
    rotate_v[0] = 0.0
    mapped: dict[str, Any] = {
        "curveV": [(abs(a) + abs(b)) * r for a, b, r in zip(v1, v2, res, strict=True)],
        "splitAngle": [
            s + (a + b) / 2.0 for s, a, b in zip(_vec(p["splitAngle"]), a1, a2, strict=True)
        ],
        "splitAngleV": [abs(a - b) / 2.0 for a, b in zip(a1, a2, strict=True)],
        "scale": max(float(p["scale"]) + float(p["scaleV"]), 1e-6),
        "scaleV": 0.0,
        "scale0": float(p["scale0"]) * float(p["scaleV0"]),
        "scaleV0": 0.0,
        "leafScale": float(p["leafScale"]) * float(p["leafScaleV"]),
        "leafScaleV": 0.0,
        "rotate": rotate,
        "rotateV": rotate_v,
        "leafRotate": float(p["leafRotate"]) + float(p["leafRotateV"]),
        "leafRotateV": 0.0,
        "seed": int(p["seed"]) % (2**31),
        "showLeaves": int(p["leaves"]) != 0,
    }
    for key in SAPLING_KEYS:
        if key in mapped:
            out[key] = mapped[key]
        elif key in _SAPLING_EXTRA:
            out[key] = _SAPLING_EXTRA[key]
        elif key in p:
            out[key] = p[key]
        else:  # pragma: no cover - table and key list disagree
            raise ParamError(f"Sapling key {key!r} has no value")
    for key in ("shape", "shapeS", "leafDist", "leafShape", "handleType"):
        out[key] = str(out[key])
    for key, value in out.items():
        if isinstance(value, float) and not math.isfinite(value):
            raise ParamError(f"{key}={value!r}: not finite after mapping to Sapling keys")
    return out


def sapling_preset_text(params: TreeParams | Mapping[str, Any]) -> str:
    """A Sapling preset's text: one line holding the whole dict literal."""
    text = repr(to_sapling(params))
    if "\n" in text:  # pragma: no cover - repr of plain values never breaks lines
        raise ParamError("preset literal spans lines")
    return text + "\n"


def save_sapling_preset(
    params: TreeParams | Mapping[str, Any], path: str | os.PathLike[str]
) -> Path:
    """Write a Sapling preset (``.py``) atomically."""
    return atomic_write(path, sapling_preset_text(params))
