"""The one parameter table, and everything derived from it.

Every key of the TreeSketchNet dictionary (the 70 keys of Blender Sapling's parameter
dictionary as TreeSketchNet uses it) is described exactly once, in :data:`PARAMS`.
Validation, the TSN target encoding (``tsn.encoding``), the refinement bounds
(``weberpenn.species``), the CLI help and the docs are all derived from this table.

Values on disk are JSON with the Sapling key names.  Sapling presets (a Python dict
literal on the first non-blank, non-comment line) are read with :func:`ast.literal_eval`,
never executed.
"""

from __future__ import annotations

import ast
import contextlib
import hashlib
import json
import math
import os
import re
from collections.abc import Collection, Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

from .fileio import atomic_write

Kind = Literal["float", "int", "bool", "sign", "enum"]

#: The six TSN output heads, in the paper's order (insertion order of the first
#: alphabetical key of each group in TreeSketchNet's ``get_subdivision_keys``).
HEADS: tuple[str, ...] = ("0_1", "-inf_inf", "0_inf", "min_max", "angle", "-1_1")

#: Allowed values of the shape-ratio enums (strings, as in Sapling presets).
SHAPE_CHOICES: tuple[str, ...] = ("0", "1", "2", "3", "4", "5", "6", "7", "8", "10")
SHAPES_CHOICES: tuple[str, ...] = ("0", "1", "2", "3", "4", "5", "6", "7", "10")
LEAF_SHAPE_CHOICES: tuple[str, ...] = ("hex", "rect")

#: Hard limits that keep any accepted dictionary from hanging the process or
#: exhausting memory (checked across keys by :func:`validate`).
MAX_STEMS = 60_000
MAX_LEAVES = 400_000
MAX_TUBE_VERTICES = 12_000_000


@dataclass(frozen=True)
class ParamSpec:
    """One row of the parameter table."""

    name: str
    size: int  # 1 = scalar, 4 = one value per level
    kind: Kind
    lo: float  # inclusive valid range (after any capping for safety)
    hi: float
    head: str | None  # TSN output head, None = not predicted
    default: Any
    meaning: str
    choices: tuple[str, ...] = ()

    @property
    def predicted(self) -> bool:
        return self.head is not None

    @property
    def is_vector(self) -> bool:
        return self.size == 4

    @property
    def discrete(self) -> bool:
        return self.kind in ("int", "bool", "sign", "enum")

    def range_text(self) -> str:
        if self.kind == "enum":
            return "one of " + ", ".join(repr(c) for c in self.choices)
        if self.kind == "bool":
            return "true or false"
        if self.kind == "sign":
            return "-1 or 1"
        return f"[{_fmt(self.lo)}, {_fmt(self.hi)}]"


def _fmt(x: float) -> str:
    return str(int(x)) if float(x).is_integer() else repr(float(x))


A = 360.0  # angles: degrees in [-360, 360]
F, I, B, S, E = "float", "int", "bool", "sign", "enum"  # noqa: E741

# name, size, kind, lo, hi, head, default, meaning[, choices]
# fmt: off
_ROWS: list[tuple] = [
    ("attractOut", 4, F, 0.0, 1.0, "0_1", (0.0, 0.0, 0.0, 0.0), "per level: bend of the stem's azimuth towards the radial outward direction"),
    ("attractUp", 4, F, -50.0, 50.0, "-inf_inf", (0.0, 0.0, 0.0, 0.0), "per level: vertical attraction applied per segment (negative droops)"),
    ("baseSize", 1, F, 0.0, 1.0, "0_1", 0.4, "fraction of the trunk with no branches"),
    ("baseSize_s", 1, F, 0.0, 1.0, "0_1", 0.25, "baseSize is multiplied by this at each level after the trunk"),
    ("baseSplits", 1, I, 0, 16, "0_inf", 0, "extra trunk clones made at the end of the trunk's first segment"),
    ("bevelRes", 1, I, 0, 32, "min_max", 0, "round cross-section has 4 + 2*bevelRes sides"),
    ("branchDist", 1, F, 0.1, 10.0, "min_max", 1.0, "remaps trunk child positions: <1 pushes branches up, >1 down"),
    ("branches", 4, I, 0, 500, "0_inf", (50, 30, 10, 10), "per level: children per stem of the level above ([0] unused: one trunk)"),
    ("choiceNegPos1", 1, S, -1, 1, "0_1", 1, "realised sign of the split angle (replaces Sapling's choice([-1,1]))"),
    ("choiceNegPos2", 1, S, -1, 1, "0_1", 1, "realised sign of the split spread angle (replaces choice([-1,1]))"),
    ("curve", 4, F, -A, A, "angle", (0.0, -40.0, -40.0, 0.0), "per level: total bend along the stem, degrees"),
    ("curveBack", 4, F, -A, A, "angle", (0.0, 0.0, 0.0, 0.0), "per level: bend added from the middle segment on, degrees"),
    ("curveRes", 4, I, 1, 64, "0_inf", (3, 5, 3, 1), "per level: Bezier segments per stem"),
    ("curveV1", 4, F, -A, A, "angle", (0.0, 0.0, 0.0, 0.0), "per level: realised per-segment random bend about the local X axis, degrees"),
    ("curveV2", 4, F, -A, A, "angle", (0.0, 0.0, 0.0, 0.0), "per level: realised per-segment random sideways bend about the local Y axis, degrees"),
    ("customShape", 4, F, 0.01, 1.0, "min_max", (0.5, 1.0, 0.3, 0.5), "custom shape (shape 8): length factor at base, middle, middle position, top"),
    ("downAngle", 4, F, -A, A, "angle", (90.0, 60.0, 45.0, 45.0), "per level: angle between a child and its parent's axis, degrees"),
    ("downAngleV", 4, F, -A, A, "angle", (0.0, 0.0, 0.0, 0.0), "per level: realised down-angle variation (sign semantics follow useOldDownAngle)"),
    ("horzLeaves", 1, B, 0, 1, "0_1", True, "leaves face upwards"),
    ("leafDist", 1, E, 0, 10, "min_max", "6", "shape-ratio function that distributes leaves along the stems", SHAPES_CHOICES),
    ("leafDownAngle", 1, F, -A, A, "angle", 45.0, "angle of a leaf to its stem, degrees"),
    ("leafDownAngleV", 1, F, -A, A, "angle", 0.0, "realised leaf down-angle variation, degrees"),
    ("leafRotate", 1, F, -A, A, "angle", 137.5, "azimuth step between successive leaves (negative alternates), degrees"),
    ("leafRotateV", 1, F, -A, A, "angle", 0.0, "realised offset of the leaf azimuth step, degrees"),
    ("leafScale", 1, F, 0.0, 20.0, "0_inf", 0.17, "leaf size (the template is one unit tall)"),
    ("leafScaleT", 1, F, -1.0, 1.0, "-1_1", 0.0, "leaf size taper along the parent stem (positive: smaller towards the tip)"),
    ("leafScaleV", 1, F, 0.0, 2.0, "0_1", 1.0, "realised leaf size multiplier (1 = no variation)"),
    ("leafScaleX", 1, F, 0.0, 20.0, "0_inf", 1.0, "leaf width factor"),
    ("leafShape", 1, E, 0, 1, "0_1", "hex", "leaf template: 'hex' (6 vertices) or 'rect' (a quad); encoded hex=0, rect=1", LEAF_SHAPE_CHOICES),
    ("leafangle", 1, F, -A, A, "angle", 0.0, "extra tilt of the leaf plane about its X axis, degrees"),
    ("leaves", 1, I, -100, 2000, "-inf_inf", 25, "leaves per last-level stem; negative: |leaves| fanned at each stem tip"),
    ("length", 4, F, 1e-6, 5.0, "min_max", (1.0, 0.3, 0.6, 0.45), "per level: [0] trunk length / scale, [n] child length relative to parent"),
    ("lengthV", 4, F, 0.0, 1.0, "0_1", (0.0, 0.0, 0.0, 0.0), "per level: length variation (TreeSketchNet forces 0)"),
    ("levels", 1, I, 1, 4, "min_max", 3, "number of stem levels (trunk = level 0; the last level carries the leaves)"),
    ("maxBaseSplits", 1, I, 0, 16, "0_inf", 0, "upper bound used when baseSplits is drawn at random"),
    ("minRadius", 1, F, 0.0, 10.0, "0_inf", 0.0, "smallest branch radius"),
    ("nrings", 1, I, 0, 64, "0_inf", 0, ">0: trunk children grouped into this many whorls"),
    ("prune", 1, B, 0, 1, None, False, "enable the pruning envelope"),
    ("pruneBase", 1, F, 0.0, 1.0, None, 0.3, "pruning envelope bottom, fraction of the tree height"),
    ("prunePowerHigh", 1, F, -100.0, 100.0, None, 0.5, "pruning envelope exponent, upper part"),
    ("prunePowerLow", 1, F, -100.0, 100.0, None, 0.001, "pruning envelope exponent, lower part"),
    ("pruneRatio", 1, F, 0.0, 1.0, None, 1.0, "blend between unpruned (0) and fully pruned (1) stem length"),
    ("pruneWidth", 1, F, 0.0, 100.0, None, 0.4, "pruning envelope radius relative to the tree size"),
    ("pruneWidthPeak", 1, F, 0.0, 100.0, None, 0.6, "height fraction of the envelope's widest point"),
    ("rLastAng", 4, F, -A, A, "-inf_inf", (0.0, 0.0, 0.0, 0.0), "per level: realised initial roll (replaces uniform(0, 360)), degrees"),
    ("rSplits2", 1, F, 0.0, 1.0, "0_1", 0.5, "realised random number used when a stem splits into two (replaces random())"),
    ("radiusTweak", 4, F, 0.0, 1.0, "0_1", (1.0, 1.0, 1.0, 1.0), "per level: multiplies the child start radius"),
    ("ratio", 1, F, 0.0, 1.0, "0_inf", 0.015, "trunk base radius relative to the tree size"),
    ("ratioPower", 1, F, 0.0, 5.0, "0_inf", 1.2, "how fast the radius falls from parent to child"),
    ("resU", 1, I, 1, 32, "min_max", 4, "samples per Bezier segment when the curve is turned into a tube"),
    ("rootFlare", 1, F, 1.0, 10.0, "min_max", 1.0, "radius multiplier at the trunk's base"),
    ("rotate", 4, F, -A, A, "angle", (137.5, 137.5, 137.5, 137.5), "per level: azimuth step between children ([0]: between trunk splits), degrees"),
    ("rotateV", 4, F, -A, A, "angle", (0.0, 0.0, 0.0, 0.0), "per level: realised offset of the azimuth step, degrees"),
    ("scale", 1, F, 1e-3, 200.0, "0_inf", 13.0, "tree size: the trunk is (scale + scaleV) * length[0] long"),
    ("scale0", 1, F, 0.0, 10.0, "0_inf", 1.0, "trunk radius multiplier"),
    ("scaleV", 1, F, -100.0, 100.0, "-inf_inf", 0.0, "realised offset added to scale"),
    ("scaleV0", 1, F, 0.0, 2.0, "0_1", 1.0, "realised trunk radius multiplier (1 = no variation)"),
    ("seed", 1, I, 0, 2**63 - 1, None, 0, "seed of any randomness left after the realised keys"),
    ("segSplits", 4, F, 0.0, 3.0, "min_max", (0.0, 0.0, 0.0, 0.0), "per level: probability that a segment splits"),
    ("shape", 1, E, 0, 10, "min_max", "7", "shape-ratio function of the first-level branch lengths", SHAPE_CHOICES),
    ("shapeS", 1, E, 0, 10, "min_max", "4", "shape-ratio function of the lengths at deeper levels", SHAPES_CHOICES),
    ("splitAngle", 4, F, -A, A, "angle", (0.0, 0.0, 0.0, 0.0), "per level: angle between a split clone and its stem, degrees"),
    ("splitAngleV1", 4, F, -A, A, "angle", (0.0, 0.0, 0.0, 0.0), "per level: realised split angle variation, degrees"),
    ("splitAngleV2", 4, F, -A, A, "angle", (0.0, 0.0, 0.0, 0.0), "per level: realised split spread variation, degrees"),
    ("splitBias", 1, F, -2.0, 2.0, "min_max", 0.0, "trunk: moves splits towards the top (>0) or the base (<0)"),
    ("splitHeight", 1, F, 0.0, 1.0, "0_1", 0.2, "trunk: no splits and no curvature below this fraction"),
    ("taper", 4, F, 0.0, 1.0, "0_1", (1.0, 1.0, 1.0, 1.0), "per level: how much a stem narrows towards its tip (1 = pointed)"),
    ("taperCrown", 1, F, 0.0, 1.0, "0_1", 0.0, "trunk: shortens leaning split segments"),
    ("useOldDownAngle", 1, B, 0, 1, "0_1", False, "paper-like down-angle variation semantics"),
    ("useParentAngle", 1, B, 0, 1, "0_1", True, "first-level children follow the parent's declination"),
]
# fmt: on

PARAMS: tuple[ParamSpec, ...] = tuple(ParamSpec(*row) for row in _ROWS)
SPECS: dict[str, ParamSpec] = {p.name: p for p in PARAMS}
KEYS: tuple[str, ...] = tuple(p.name for p in PARAMS)
PREDICTED_KEYS: tuple[str, ...] = tuple(p.name for p in PARAMS if p.predicted)
HEAD_KEYS: dict[str, tuple[str, ...]] = {
    h: tuple(p.name for p in PARAMS if p.head == h) for h in HEADS
}

#: Keys that exist only in TreeSketchNet's dictionary (realised random draws), with the
#: value that means "no variation".  Filled when a Sapling preset is imported.
TSN_ONLY_NEUTRAL: dict[str, Any] = {
    "curveV1": (0.0, 0.0, 0.0, 0.0),
    "curveV2": (0.0, 0.0, 0.0, 0.0),
    "splitAngleV1": (0.0, 0.0, 0.0, 0.0),
    "splitAngleV2": (0.0, 0.0, 0.0, 0.0),
    "choiceNegPos1": 1,
    "choiceNegPos2": 1,
    "rLastAng": (0.0, 0.0, 0.0, 0.0),
    "rSplits2": 0.5,
}

#: Sapling keys whose meaning differs: Sapling stores a variation amplitude, TreeSketchNet
#: the realised value.  On preset import they take their "no variation" value.
REALISED_NEUTRAL: dict[str, Any] = {
    "scaleV": 0.0,
    "scaleV0": 1.0,
    "leafScaleV": 1.0,
    "rotateV": (0.0, 0.0, 0.0, 0.0),
    "downAngleV": (0.0, 0.0, 0.0, 0.0),
    "leafRotateV": 0.0,
    "leafDownAngleV": 0.0,
}

#: Keys of Sapling's operator that have no effect on geometry here (or no TreeSketchNet
#: counterpart); accepted in presets and dropped.
SAPLING_IGNORED_KEYS: frozenset[str] = frozenset(
    """bevel showLeaves useArm armAnim leafAnim previewArm frameRate loopFrames wind gust gustF
    af1 af2 af3 af4 makeMesh armLevels boneStep do_update chooseSet presetName limitImport overwrite
    windSpeed windGust startCurv handleType splitByLen rMode closeTip autoTaper leafDupliObj bend
    curveV splitAngleV""".split()  # noqa: SIM905
)

assert len(PARAMS) == 70, len(PARAMS)
assert len(PREDICTED_KEYS) == 62
assert [len(HEAD_KEYS[h]) for h in HEADS] == [17, 4, 12, 12, 16, 1]


class ParamError(ValueError):
    """A parameter dictionary is invalid; the message names the key, value and range.

    ``key`` is the offending parameter's name when one key is to blame (else ``None``).
    """

    def __init__(self, message: str, key: str | None = None) -> None:
        super().__init__(message)
        self.key = key


def _bad(key: str, value: Any, why: str) -> ParamError:
    spec = SPECS.get(key.split("[", 1)[0])  # per-level values are named like 'taper[2]'
    allowed = f" (allowed: {spec.range_text()})" if spec else ""
    shown = repr(value)
    if len(shown) > 60:  # a number of 400 digits or a long string: its start says enough
        shown = f"{shown[:40]}... ({len(shown)} characters)"
    return ParamError(f"parameter {key!r}: {why}, got {shown}{allowed}", key.split("[", 1)[0])


def _coerce_scalar(spec: ParamSpec, value: Any, key: str) -> Any:
    if spec.kind == "enum":
        if isinstance(value, bool):
            raise _bad(key, value, "expected one of the allowed names")
        if isinstance(value, int | float) and not isinstance(value, bool):
            # an int is exact however large; math.isfinite and float() overflow on it
            if isinstance(value, float) and not (math.isfinite(value) and value.is_integer()):
                raise _bad(key, value, "not an allowed value")
            value = str(int(value))
        if not isinstance(value, str) or value not in spec.choices:
            raise _bad(key, value, "not an allowed value")
        return value
    if spec.kind == "bool":
        if isinstance(value, bool):
            return value
        if isinstance(value, int | float) and value in (0, 1):
            return bool(value)
        raise _bad(key, value, "expected a boolean")
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise _bad(key, value, f"expected a number ({spec.kind})")
    # an int is compared as it is, however large (math.isfinite and float() overflow on
    # one of 309 digits or more); a float must be finite
    if isinstance(value, float) and not math.isfinite(value):
        raise _bad(key, value, "not a finite number")
    if spec.kind == "sign":
        if value not in (-1, 1):
            raise _bad(key, value, "expected -1 or 1")
        return int(value)
    if not spec.lo <= value <= spec.hi:
        raise _bad(key, value, "out of range")
    if spec.kind == "int":
        if isinstance(value, float) and not value.is_integer():
            raise _bad(key, value, "expected an integer")
        value = int(value)
    else:
        value = float(value)
    if not spec.lo <= value <= spec.hi:  # again: a float rounded onto a bound's far side
        raise _bad(key, value, "out of range")
    return value


def _coerce(key: str, value: Any) -> Any:
    spec = SPECS[key]
    if spec.is_vector:
        if isinstance(value, str | bytes) or not hasattr(value, "__len__"):
            raise _bad(key, value, "expected a list of 4 values (one per level)")
        items = list(value)
        if len(items) != 4:
            raise _bad(key, value, f"expected 4 values (one per level), got {len(items)}")
        out = []
        for i, v in enumerate(items):
            if hasattr(v, "item"):
                v = v.item()
            out.append(_coerce_scalar(spec, v, f"{key}[{i}]"))
        return tuple(out)
    if hasattr(value, "item") and not isinstance(value, str):
        value = value.item()
    return _coerce_scalar(spec, value, key)


def estimate_load(v: Mapping[str, Any]) -> tuple[float, float, float]:
    """Upper-bound-ish estimate of (stems, leaves, tube vertices) a dictionary grows, from
    the dictionary alone (no growing): validation bounds it, and a caller can tell a
    cheap tree from an expensive one before paying for it."""
    levels = int(v["levels"])
    stems_at = [1.0 + float(v["baseSplits"])]
    for n in range(1, levels):
        stems_at.append(stems_at[-1] * max(1, int(v["branches"][min(n, 3)])))
    # splitting multiplies stems; each segment may split at most once
    total_stems = 0.0
    verts = 0.0
    sides = 4 + 2 * int(v["bevelRes"])
    for n, count in enumerate(stems_at):
        res = int(v["curveRes"][min(n, 3)])
        split = min(1.0, float(v["segSplits"][min(n, 3)]))
        factor = min(1.0 + split * res, 64.0)
        total_stems += count * factor
        verts += count * factor * (res * int(v["resU"]) + 1) * sides
    leaves_per = abs(int(v["leaves"]))
    leaves = stems_at[-1] * leaves_per
    return total_stems, leaves, verts


class TreeParams(Mapping[str, Any]):
    """A validated, immutable TreeSketchNet parameter dictionary (all 70 keys).

    Values: floats, ints, bools, signs (-1/1) and enum strings; per-level keys are
    4-tuples.  Read with ``p["levels"]`` or ``p.levels``; change with ``p.replace(...)``.
    """

    __slots__ = ("_values",)

    def __init__(self, values: Mapping[str, Any]):
        object.__setattr__(self, "_values", _validate_dict(values))

    # Mapping protocol -------------------------------------------------------------
    def __getitem__(self, key: str) -> Any:
        return self._values[key]

    def __iter__(self) -> Iterator[str]:
        return iter(KEYS)

    def __len__(self) -> int:
        return len(KEYS)

    def __getattr__(self, key: str) -> Any:
        try:
            return self._values[key]
        except KeyError:
            raise AttributeError(key) from None

    def __setattr__(self, key: str, value: Any) -> None:
        raise AttributeError("TreeParams is immutable: use .replace(key=value)")

    def __reduce__(self) -> tuple[Any, ...]:
        # pickle through the constructor (executors ship parameters to worker processes);
        # the default path would call __getattr__ before _values exists
        return (TreeParams, (dict(self._values),))

    def __eq__(self, other: object) -> bool:
        if isinstance(other, TreeParams):
            return self._values == other._values
        return NotImplemented

    def __hash__(self) -> int:
        return hash(tuple(self._values[k] for k in KEYS))

    def __repr__(self) -> str:
        return f"TreeParams(levels={self.levels}, scale={self.scale}, leaves={self.leaves}, ...)"

    def replace(self, **changes: Any) -> TreeParams:
        """A new TreeParams with some keys changed (validated: the changed keys one by
        one, then the whole tree's limits; the others are this one's, valid already)."""
        values = dict(self._values)
        values.update(changes)
        new = object.__new__(TreeParams)
        object.__setattr__(new, "_values", _validate_dict(values, self._values, changes))
        return new

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready plain dict (lists for per-level keys), keys in table order."""
        return {k: list(v) if isinstance(v, tuple) else v for k, v in self._values.items()}


def _validate_dict(
    values: Mapping[str, Any],
    valid: Mapping[str, Any] | None = None,
    changed: Collection[str] = (),
) -> dict[str, Any]:
    """``values`` checked and coerced; ``valid``: a dictionary this one checked before,
    whose values stand for ``values``' own but for the ``changed`` keys (a search's
    candidates change a few of the 70 keys, and each is checked many times a second)."""
    if not isinstance(values, Mapping):
        raise ParamError(f"a parameter dictionary must be a mapping, got {type(values).__name__}")
    unknown = sorted(set(values) - set(KEYS))
    if unknown:
        raise ParamError(
            f"unknown parameter(s) {', '.join(map(repr, unknown))}; "
            f"the dictionary has exactly these {len(KEYS)} keys: {', '.join(KEYS)}"
        )
    missing = [k for k in KEYS if k not in values]
    if missing:
        raise ParamError(f"missing parameter(s): {', '.join(map(repr, missing))}")
    if valid is None:
        out = {k: _coerce(k, values[k]) for k in KEYS}
    else:
        out = {k: _coerce(k, values[k]) if k in changed else valid[k] for k in KEYS}
    if out["scale"] + out["scaleV"] <= 0:
        raise ParamError(
            f"parameter 'scaleV': scale + scaleV must be positive (the tree's size), got "
            f"scale={out['scale']!r}, scaleV={out['scaleV']!r}",
            "scaleV",
        )
    stems, leaves, verts = estimate_load(out)
    if stems > MAX_STEMS:
        raise ParamError(
            f"parameter 'branches': the tree would have about {stems:.3g} stems "
            f"(levels={out['levels']}, branches={list(out['branches'])}, baseSplits={out['baseSplits']}); "
            f"the limit is {MAX_STEMS}",
            "branches",
        )
    if leaves > MAX_LEAVES:
        raise ParamError(
            f"parameter 'leaves': the tree would have about {leaves:.3g} leaves "
            f"(leaves={out['leaves']}, branches={list(out['branches'])}); the limit is {MAX_LEAVES}",
            "leaves",
        )
    if verts > MAX_TUBE_VERTICES:
        raise ParamError(
            f"parameter 'curveRes': the branch mesh would have about {verts:.3g} vertices "
            f"(curveRes={list(out['curveRes'])}, resU={out['resU']}, bevelRes={out['bevelRes']}); "
            f"the limit is {MAX_TUBE_VERTICES}",
            "curveRes",
        )
    return out


def validate(values: Mapping[str, Any]) -> TreeParams:
    """Validate a dictionary and return :class:`TreeParams` (raises :class:`ParamError`)."""
    if isinstance(values, TreeParams):
        return values
    return TreeParams(values)


def default_params() -> TreeParams:
    """The table's defaults (Sapling's defaults with no realised variation)."""
    return TreeParams({p.name: p.default for p in PARAMS})


def fill_from_sapling(values: Mapping[str, Any]) -> dict[str, Any]:
    """Map a Sapling operator/preset dictionary onto the TreeSketchNet keys.

    Mirrors Sapling's own preset loader: a scalar ``attractUp`` becomes ``[0, 0, a, a]``;
    missing leaf angles are copied from downAngle/downAngleV/rotate/rotateV at level
    ``min(levels, 3)``; Sapling-only keys that do not change geometry are dropped;
    TreeSketchNet's realised keys take their "no variation" value; anything else missing
    takes the table default.  Unknown keys are still rejected later by validation.
    """
    src = {k: v for k, v in values.items() if k not in SAPLING_IGNORED_KEYS}
    if "attractUp" in src and isinstance(src["attractUp"], int | float):
        a = float(src["attractUp"])
        src["attractUp"] = [0.0, 0.0, a, a]
    for key, value in REALISED_NEUTRAL.items():
        src[key] = value
    for key, value in TSN_ONLY_NEUTRAL.items():
        src.setdefault(key, value)
    levels = src.get("levels", SPECS["levels"].default)
    try:
        idx = min(int(levels), 3)
    except (TypeError, ValueError):
        idx = 3
    for leaf_key, stem_key in (("leafDownAngle", "downAngle"), ("leafRotate", "rotate")):
        if leaf_key not in src and stem_key in src:
            with contextlib.suppress(TypeError, IndexError, KeyError):
                src[leaf_key] = src[stem_key][idx]
    for spec in PARAMS:
        src.setdefault(spec.name, spec.default)
    if "seed" in src and isinstance(src["seed"], int) and not 0 <= src["seed"] < 2**63:
        src["seed"] = abs(src["seed"]) % (2**31)
    return src


#: Comment prefix of the full dictionary that ``weberpenn.preset`` seals into a preset.
EMBEDDED_PREFIX = "# treesketch-params "


def _embedded_params(text: str) -> dict | None:
    """The full dictionary sealed into a TreeSketch preset, if the Sapling line (the
    first line not starting with '#', as Sapling reads it) still has the sealed hash."""
    lines = text.splitlines()
    sapling = next((t.strip() for t in lines if t.strip() and not t.startswith("#")), None)
    for t in lines:
        if not t.startswith(EMBEDDED_PREFIX) or sapling is None:
            continue
        seal, _, body = t[len(EMBEDDED_PREFIX) :].partition(" ")
        if seal != "sha256=" + hashlib.sha256(sapling.encode()).hexdigest():
            return None  # the Sapling line was edited: it wins
        try:
            data = json.loads(body)
        except json.JSONDecodeError:
            return None
        return data if isinstance(data, dict) else None
    return None


# what Python's parser raises for a literal: SyntaxError and ValueError for a bad one;
# MemoryError ("parser stack overflow") and RecursionError for one nested or chained too
# deep (200,000 unary minus signs: a preset is one dict literal, nothing like that)
_LITERAL_ERRORS = (ValueError, SyntaxError, MemoryError, RecursionError)


def _why(exc: BaseException) -> str:
    if isinstance(exc, MemoryError | RecursionError):
        return "its expression is nested too deep for a dict literal"
    return str(exc)


def _read_preset_literal(text: str, path: Path) -> Any:
    for line in text.splitlines():
        stripped = line.strip()
        if not stripped or stripped.startswith("#"):
            continue
        try:
            return ast.literal_eval(stripped)
        except _LITERAL_ERRORS as exc:
            break_exc = exc
            break
    else:
        raise ParamError(f"{path}: no dictionary found (expected a Python dict literal)")
    if isinstance(break_exc, MemoryError | RecursionError):
        # the whole file holds the same line: parsing it again fails the same way
        raise ParamError(f"{path}: not a valid Sapling preset: {_why(break_exc)}")
    # Not a one-line dict: try the whole file (a multi-line dict literal).
    try:
        return ast.literal_eval(text.strip())
    except _LITERAL_ERRORS as exc:
        why = _why(exc) if isinstance(exc, MemoryError | RecursionError) else _why(break_exc)
        raise ParamError(
            f"{path}: not a valid Sapling preset (a Python dict literal): {why}"
        ) from None


MAX_PARAM_FILE_BYTES = 1_000_000
MAX_NESTING = 8  # {"key": [v, ...]} nests 2 deep; anything far deeper is not parameters


# A string is a quote, then characters that are not that quote nor a backslash or a
# backslash and any character but a newline; the closing quote follows (as a preset or
# JSON writes it).  Matched from a given position only: see _max_nesting.
_STRING_BODY = {q: re.compile(q + r"(?:[^" + q + r"\\]|\\.)*") for q in "\"'"}
_TOKEN = re.compile(r"[\"'\[\]{}()]")


def _max_nesting(text: str) -> int:
    """Deepest bracket nesting in ``text`` (strings ignored), without recursion: parsers
    recurse per level and a file of 100000 '[' would blow the interpreter's stack.

    Linear in the text's length: a quote that opens no string (it is never closed) is
    skipped, and so is every later quote of its kind up to where its string stopped,
    since each of those would be read as the same unclosed string (``findall`` over one
    pattern of strings and brackets tried again from every such quote: quadratic, 50
    minutes for 1 MB of ``"\\"``)."""
    depth = best = pos = 0
    dead = {'"': 0, "'": 0}  # a quote of this kind before this position opens no string
    while (m := _TOKEN.search(text, pos)) is not None:
        ch, at = m.group(), m.start()
        pos = at + 1
        if ch in dead:
            if at < dead[ch]:
                continue
            end = _STRING_BODY[ch].match(text, at).end()  # type: ignore[union-attr]
            if end < len(text) and text[end] == ch:
                pos = end + 1  # a whole string: its brackets do not count
            else:
                dead[ch] = end
        elif ch in "[{(":
            depth += 1
            best = max(best, depth)
        else:
            depth -= 1
    return best


def load_params(path: str | os.PathLike[str]) -> TreeParams:
    """Load a parameter dictionary from JSON, or from a Sapling preset (``.py``).

    JSON files must hold exactly the 70 TreeSketchNet keys.  Sapling presets are parsed
    with :func:`ast.literal_eval` (never executed) and mapped by :func:`fill_from_sapling`
    when they lack TreeSketchNet's realised keys; a preset written by
    ``weberpenn.preset`` gives back its sealed full dictionary while its Sapling line is
    unedited (a lossless round trip).
    """
    path = Path(path)
    if not path.is_file():
        raise ParamError(f"{path}: no such parameter file")
    size = path.stat().st_size
    if size > MAX_PARAM_FILE_BYTES:
        raise ParamError(
            f"{path}: {size:,} bytes is too large for a parameter file "
            f"(at most {MAX_PARAM_FILE_BYTES:,})"
        )
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise ParamError(f"{path}: cannot read parameter file: {exc}") from None
    depth = _max_nesting(text)
    if depth > MAX_NESTING:
        raise ParamError(
            f"{path}: brackets nested {depth} deep; a parameter file nests at most {MAX_NESTING}"
        )
    if path.suffix.lower() == ".py":
        embedded = _embedded_params(text)
        data = embedded if embedded is not None else _read_preset_literal(text, path)
        if not isinstance(data, dict):
            raise ParamError(f"{path}: a Sapling preset must be a dict literal")
        if not all(k in data for k in TSN_ONLY_NEUTRAL):
            data = fill_from_sapling(data)
    else:
        try:
            data = json.loads(text)
        except json.JSONDecodeError as exc:
            raise ParamError(f"{path}: not valid JSON: {exc}") from None
        if not isinstance(data, dict):
            raise ParamError(f"{path}: the JSON must be an object of parameters")
    try:
        return TreeParams(data)
    except ParamError as exc:
        raise ParamError(f"{path}: {exc}") from None


def params_text(params: TreeParams | Mapping[str, Any]) -> str:
    """The JSON text of a parameter file (validated), as :func:`save_params` writes it."""
    return json.dumps(validate(params).to_dict(), indent=1) + "\n"


def save_params(params: TreeParams | Mapping[str, Any], path: str | os.PathLike[str]) -> Path:
    """Save as JSON (atomically).  Use ``weberpenn.export.save_sapling_preset`` for Sapling."""
    path = Path(path)
    atomic_write(path, params_text(params))
    return path


def describe() -> str:
    """A plain-text table of every parameter (used by the CLI help and the docs)."""
    lines = [f"{'key':<16} {'shape':<6} {'type':<6} {'head':<9} {'range':<28} meaning"]
    for p in PARAMS:
        shape = "4v" if p.is_vector else "scalar"
        lines.append(
            f"{p.name:<16} {shape:<6} {p.kind:<6} {p.head or '-':<9} {p.range_text():<28} {p.meaning}"
        )
    return "\n".join(lines)
