"""Sapling presets: the one-line dict literal that Blender's Sapling "Import Preset" reads.

Sapling reads the first line that does not start with ``#`` (so no blank line may come
first) as one dict literal and sets every key on its operator, in order, before it looks
at its own *Limit Import* switch; the preset therefore carries ``limitImport: False`` and
Sapling builds every level and the leaves without the user unticking anything.  The key
comes FIRST: setting it also clears Sapling's "rebuild" flag (its update callback), and
the geometry keys after it set the flag again (placed last, Sapling builds nothing).
Callers of ``bpy.ops.curve.tree_add(**preset)`` must drop the key (keyword arguments are
applied in Sapling's property order, so it would come last).

Sapling's dictionary cannot hold all of ours (TreeSketchNet's realised draws are folded
into Sapling's keys, see :func:`to_sapling`), so the preset also carries the full
dictionary as JSON on a comment line, sealed with the SHA-256 of the Sapling line:
``weberpenn.params.load_params`` uses it while the Sapling line is untouched (growing
from the preset gives exactly the tree grown from the JSON) and falls back to mapping
Sapling's keys once someone edits the line.  The drawn view's yaw, when given, is
recorded in the header comment.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from .fileio import atomic_write
from .params import EMBEDDED_PREFIX, ParamError, TreeParams, validate

__all__ = [
    "SAPLING_KEYS",
    "preset_text",
    "sapling_preset_text",
    "save_sapling_preset",
    "to_sapling",
]

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


def preset_text(params: TreeParams | Mapping[str, Any], *, yaw: float | None = None) -> str:
    """The preset file's text: header comment, the Sapling line, the sealed full
    dictionary."""
    p = validate(params)
    sapling = {"limitImport": False, **to_sapling(p)}
    line = repr(sapling)
    if "\n" in line:  # pragma: no cover - repr of plain values never breaks lines
        raise ParamError("preset literal spans lines")
    head = "# TreeSketch tree for Blender's Sapling Tree Gen (Import Preset reads the next line)"
    if yaw is not None:
        yaw = float(yaw)
        if not math.isfinite(yaw):
            raise ParamError(f"yaw={yaw!r}: must be a finite number of degrees")
        head += (
            f"\n# view yaw: {yaw:.2f} degrees (the drawing was seen from this yaw; turn the"
            f" tree by {-yaw:.2f} degrees about Z to face the front view as drawn)"
        )
    seal = hashlib.sha256(line.encode()).hexdigest()
    full = json.dumps(p.to_dict(), separators=(",", ":"))
    return f"{head}\n{line}\n{EMBEDDED_PREFIX}sha256={seal} {full}\n"


#: The name ``treesketch.outputs`` calls it by.
sapling_preset_text = preset_text


def save_sapling_preset(
    params: TreeParams | Mapping[str, Any],
    path: str | os.PathLike[str],
    *,
    yaw: float | None = None,
) -> Path:
    """Write a Sapling preset (``.py``, see :func:`preset_text`); returns the path."""
    return atomic_write(Path(path), preset_text(params, yaw=yaw))
