"""The controls a person edits a tree with, mapped onto Weber-Penn keys: ONE table.

Each :class:`Control` has a name, a label and a one-line help, a kind (``number``,
``integer``, ``choice``, ``toggle``), a range, and what it moves (the keys and how, in
words).  Two sorts:

- *relative* controls (crown width, branch count, branch angle, trunk lean and bend, leaf
  size, leaf density) change the tree they are given by a factor or an offset; their
  ``neutral`` value (1 or 0) leaves it as it is, whatever the species;
- *absolute* controls (height, crown shape, leafy, variant) set a value; a tree's own is
  read from it (:func:`current`), a species' default from its base dictionary
  (:func:`defaults`), so a species added to ``species.SPECIES`` needs no code here.

:func:`apply_controls` turns (parameters, {control: value}) into parameters, every value
checked first (a clear error naming the control, the value and its range);
:func:`grow_with_controls` also grows the tree, and makes it ``height`` metres tall: the
height is the grown tree's, so it is measured and the size values (``scale``,
``scaleV``, to which every length in Weber-Penn is proportional) rescaled.

The page's sliders, ``treesketch grow --set``, ``GET /controls`` / ``POST /trees`` and the
Blender add-on all read this table.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Collection, Mapping
from dataclasses import dataclass, field
from functools import cache
from typing import Any

from . import species
from .grow import grow
from .mesh import TreeMesh, build_mesh
from .params import SPECS, ParamError, TreeParams

__all__ = [
    "CONTROLS",
    "Control",
    "apply_controls",
    "check_controls",
    "current",
    "defaults",
    "fit_controls",
    "grow_with_controls",
    "table",
    "tree_height",
]

Values = dict[str, Any]

#: Sapling's names for its shape-ratio functions (the ``shape`` key's choices).
SHAPE_LABELS: dict[str, str] = {
    "0": "conical",
    "1": "spherical",
    "2": "hemispherical",
    "3": "cylindrical",
    "4": "tapered cylindrical",
    "5": "flame",
    "6": "inverse conical",
    "7": "tend flame",
    "8": "the species' own outline",
    "9": "custom peak",
    "10": "inverse tapered cylindrical",
}
MAX_SEED = 2**31 - 1  # Sapling's preset needs a 32-bit signed seed
HEIGHT_TOLERANCE = 0.005  # relative: nearer than this the tree is not regrown
HEIGHT_TRIES = 3  # regrowths at most to meet a height
TRUNK_CURVE_RES = 6  # segments the trunk needs before a lean or a bend can show


def _shown(value: Any) -> str:
    """``value`` for an error message, at most 40 characters (repr of an int of more than
    4,300 digits raises; one of 400 says nothing more)."""
    if isinstance(value, int) and not isinstance(value, bool) and value.bit_length() > 100:
        return f"a number of about {int(value.bit_length() * 0.30103) + 1} digits"
    return f"{value!r:.40}"


@dataclass(frozen=True)
class Control:
    """One control: see the module text.  ``neutral`` is None for absolute controls."""

    name: str
    label: str
    help: str
    kind: str  # number | integer | choice | toggle
    lo: float
    hi: float
    step: float
    unit: str
    moves: tuple[str, ...]  # "key: how", in words
    neutral: Any = None
    choices: tuple[tuple[str, str], ...] = ()  # (value, label) of a choice
    apply_fn: Callable[[Values, Any], None] | None = field(default=None, repr=False)
    read_fn: Callable[[TreeParams], Any] | None = field(default=None, repr=False)

    @property
    def relative(self) -> bool:
        return self.neutral is not None

    def check(self, value: Any) -> Any:
        """The value, normalised (int, float, bool, str); ValueError naming the control."""
        bad = f"control {self.name!r}"
        if self.kind == "toggle":
            if isinstance(value, bool):
                return value
            if isinstance(value, str) and value.lower() in ("true", "false", "1", "0"):
                return value.lower() in ("true", "1")
            raise ValueError(f"{bad} must be true or false, got {value!r}")
        if self.kind == "choice":
            text = str(value)
            allowed = [c for c, _ in self.choices]
            if text not in allowed:
                raise ValueError(f"{bad} must be one of {', '.join(allowed)}, got {value!r}")
            return text
        if isinstance(value, bool):
            raise ValueError(f"{bad} must be a number, got {value!r}")
        try:
            number = float(value)
        except (TypeError, ValueError):
            raise ValueError(f"{bad} must be a number, got {_shown(value)}") from None
        except OverflowError:  # an int of 309 digits or more: out of range, not a crash
            number = math.inf
        if not math.isfinite(number) or not self.lo <= number <= self.hi:
            raise ValueError(f"{bad} must be in [{self.lo:g}, {self.hi:g}], got {_shown(value)}")
        if self.kind == "integer":
            if number != int(number):
                raise ValueError(f"{bad} must be a whole number, got {value!r}")
            return int(number)
        return number

    def describe(self) -> dict[str, Any]:
        """The row as plain data (``GET /controls``)."""
        return {
            "name": self.name,
            "label": self.label,
            "help": self.help,
            "kind": self.kind,
            "min": self.lo,
            "max": self.hi,
            "step": self.step,
            "unit": self.unit,
            "moves": list(self.moves),
            "neutral": self.neutral,
            "choices": [{"value": v, "label": lab} for v, lab in self.choices],
        }


# -- how each control moves its keys -------------------------------------------------


def _scale_level(key: str, level: int, lo: float, hi: float, integer: bool = False):
    def apply(v: Values, f: float) -> None:
        vec = list(v[key])
        x = min(hi, max(lo, float(vec[level]) * f))
        vec[level] = max(1, round(x)) if integer else x
        v[key] = vec

    return apply


def _shift_level(key: str, level: int, lo: float, hi: float):
    def apply(v: Values, d: float) -> None:
        vec = list(v[key])
        vec[level] = min(hi, max(lo, float(vec[level]) + d))
        v[key] = vec

    return apply


def _turn_trunk(back: bool):
    """Lean the trunk by the value in degrees; ``back``: turn it back as much above its
    middle (a dog-leg whose top stands upright again: a bend)."""

    def apply(v: Values, d: float) -> None:
        if d == 0:
            return
        _shift_level("curve", 0, -360.0, 360.0)(v, d)
        if back:
            _shift_level("curveBack", 0, -360.0, 360.0)(v, -d)
        _trunk_segments(v, d)

    return apply


def _trunk_segments(v: Values, d: float) -> None:
    # a trunk needs segments to bend, and its upward attraction (the palm's 8.6) would
    # pull any bend straight again: it fades as the bend grows (gone at 90 degrees)
    res = list(v["curveRes"])
    res[0] = max(int(res[0]), TRUNK_CURVE_RES)
    v["curveRes"] = res
    up = list(v["attractUp"])
    up[0] = float(up[0]) * max(0.0, 1.0 - abs(d) / 90.0)
    v["attractUp"] = up


def _leaf_size(v: Values, f: float) -> None:
    v["leafScale"] = min(float(SPECS["leafScale"].hi), float(v["leafScale"]) * f)


def _leaf_density(v: Values, f: float) -> None:
    n = int(v["leaves"])
    if n == 0:
        return
    k = max(1, round(abs(n) * f))
    v["leaves"] = int(math.copysign(min(k, int(SPECS["leaves"].hi)), n))


def _leafy(v: Values, on: bool) -> None:
    if not on:
        v["leaves"] = 0


def _shape(v: Values, s: str) -> None:
    v["shape"] = s


def _seed(v: Values, s: int) -> None:
    v["seed"] = int(s)


def _size_keys(v: Values, f: float) -> None:
    v["scale"] = float(v["scale"]) * f
    v["scaleV"] = float(v["scaleV"]) * f


def _factor(
    name: str, label: str, help: str, lo: float, hi: float, moves: str, apply_fn: Callable
) -> Control:
    """A relative control that multiplies (``x``): 1 leaves the tree as it is."""
    return Control(
        name, label, help, "number", lo, hi, 0.05, "x", (moves,), neutral=1.0, apply_fn=apply_fn
    )


def _degrees(
    name: str, label: str, help: str, limit: float, moves: tuple[str, ...], apply_fn: Callable
) -> Control:
    """A relative control that adds degrees, up to ``limit`` either way: 0 leaves the
    tree as it is."""
    return Control(
        name, label, help, "number", -limit, limit, 1.0, "°", moves, neutral=0.0, apply_fn=apply_fn
    )


# what a lean or a bend does to the trunk besides turning it (``_trunk_segments``)
_TRUNK_MOVES = ("attractUp[0]: times 1 - |value| / 90", f"curveRes[0]: at least {TRUNK_CURVE_RES}")

CONTROLS: tuple[Control, ...] = (
    Control(
        "height",
        "Height",
        "How tall the tree stands, from the ground to its highest leaf.",
        "number",
        0.2,
        100.0,
        0.1,
        "m",
        ("scale, scaleV: both times (wanted height / grown height); every length follows",),
        read_fn=lambda p: tree_height(p),
    ),
    _factor(
        "crown_width",
        "Crown width",
        "How far the main branches reach out: a narrow or a spreading crown.",
        0.4,
        2.0,
        "length[1]: times the value (the main branches' length)",
        _scale_level("length", 1, 0.0, 1.0),
    ),
    Control(
        "crown_shape",
        "Crown shape",
        "The outline the main branches' lengths follow up the trunk.",
        "choice",
        0,
        10,
        1,
        "",
        ("shape: set to the chosen shape-ratio function",),
        choices=tuple((c, SHAPE_LABELS.get(c, c)) for c in SPECS["shape"].choices),
        apply_fn=_shape,
        read_fn=lambda p: str(p["shape"]),
    ),
    _factor(
        "branch_count",
        "Branch count",
        "How many main branches grow from the trunk.",
        0.25,
        2.5,
        "branches[1]: times the value, rounded, at least 1",
        _scale_level("branches", 1, 1.0, float(SPECS["branches"].hi), integer=True),
    ),
    _degrees(
        "branch_angle",
        "Branch angle",
        "Tilts the main branches away from the trunk (more: flatter) or up towards it.",
        45.0,
        ("downAngle[1]: plus the value, kept in 0..180 degrees",),
        _shift_level("downAngle", 1, 0.0, 180.0),
    ),
    _degrees(
        "trunk_lean",
        "Trunk lean",
        "Bends the trunk to one side so the tree leans (strongest on a single trunk; a "
        "trunk that forks low leans little).",
        90.0,
        ("curve[0]: plus the value", *_TRUNK_MOVES),
        _turn_trunk(back=False),
    ),
    _degrees(
        "trunk_bend",
        "Trunk bend",
        "An S-bend in the trunk: it turns one way, then back upright.",
        90.0,
        ("curve[0]: plus the value", "curveBack[0]: minus the value", *_TRUNK_MOVES),
        _turn_trunk(back=True),
    ),
    _factor(
        "leaf_size",
        "Leaf size",
        "How big each leaf is.",
        0.3,
        3.0,
        "leafScale: times the value",
        _leaf_size,
    ),
    _factor(
        "leaf_density",
        "Leaf density",
        "How many leaves each twig carries.",
        0.1,
        3.0,
        "leaves: its size times the value, rounded, at least 1 (the sign kept)",
        _leaf_density,
    ),
    Control(
        "leafy",
        "Leaves",
        "Leafy, or bare branches (winter).",
        "toggle",
        0,
        1,
        1,
        "",
        ("leaves: 0 when off",),
        apply_fn=_leafy,
        read_fn=lambda p: int(p["leaves"]) != 0,
    ),
    Control(
        "seed",
        "Variant",
        "Another tree of the same kind: where branches sit, which way they turn.",
        "integer",
        0,
        MAX_SEED,
        1,
        "",
        ("seed: set to the value",),
        apply_fn=_seed,
        read_fn=lambda p: int(p["seed"]),
    ),
)

_BY_NAME: dict[str, Control] = {c.name: c for c in CONTROLS}


def table() -> list[dict[str, Any]]:
    """Every control as plain data, in the table's order."""
    return [c.describe() for c in CONTROLS]


def check_controls(controls: Mapping[str, Any]) -> dict[str, Any]:
    """Every value checked and normalised (before any work); ValueError naming what was
    wrong."""
    if not isinstance(controls, Mapping):
        raise ValueError(f"controls must be an object of name: value, got {controls!r}")
    unknown = [k for k in controls if k not in _BY_NAME]
    if unknown:
        raise ValueError(
            f"unknown control(s) {', '.join(map(repr, unknown))}; "
            f"the controls are {', '.join(_BY_NAME)}"
        )
    return {k: _BY_NAME[k].check(v) for k, v in controls.items()}


def apply_controls(params: TreeParams, controls: Mapping[str, Any]) -> TreeParams:
    """``params`` with every control but ``height`` applied (see the module text; height
    needs the grown tree: :func:`grow_with_controls`).  Raises ValueError (ParamError)
    for a bad value or a tree past the generator's limits."""
    checked = check_controls(controls)
    values = params.to_dict()
    for c in CONTROLS:  # the table's order: the same result whatever order they came in
        if c.name in checked and c.apply_fn is not None:
            c.apply_fn(values, checked[c.name])
    try:
        return TreeParams(values)
    except ParamError as exc:
        raise ParamError(f"these controls make a tree the generator refuses: {exc}") from exc


def tree_height(params: TreeParams) -> float:
    """The grown tree's height in metres (ground to its highest point, leaves included)."""
    return _mesh_height(build_mesh(grow(params)))


def _mesh_height(mesh: TreeMesh) -> float:
    lo, hi = mesh.bounds()
    return float(hi[2] - lo[2])


def grow_with_controls(
    params: TreeParams, controls: Mapping[str, Any], species_name: str | None = None
) -> tuple[TreeParams, TreeMesh]:
    """(parameters, mesh) of ``params`` edited by ``controls``, ``height`` included: the
    tree is grown, and when its height is not the one asked for, its size values are
    rescaled and it is grown again (Weber-Penn lengths are proportional to them)."""
    checked = check_controls(controls)
    out = apply_controls(params, {k: v for k, v in checked.items() if k != "height"})
    mesh = build_mesh(grow(out), species=species_name)
    want = checked.get("height")
    if want is None:
        return out, mesh
    h0 = _mesh_height(mesh)
    if h0 <= 0:
        raise ValueError("the tree has no height to rescale")
    base = out
    # the height is nearly proportional to the size values (the leaves' own size is not):
    # the first try scales by want / height, the next ones follow the line through the
    # last two trees grown (secant steps)
    tried = [(1.0, h0)]
    for _ in range(HEIGHT_TRIES):
        f1, h1 = tried[-1]
        if abs(h1 - want) <= HEIGHT_TOLERANCE * want:
            break
        if len(tried) == 1:
            f = want / h0
        else:
            f0, h_0 = tried[-2]
            slope = (h1 - h_0) / (f1 - f0) if f1 != f0 else 0.0
            f = f1 + (want - h1) / slope if slope > 0 else f1 * want / h1
        values = base.to_dict()
        _size_keys(values, max(f, 1e-3))
        out = TreeParams(values)
        mesh = build_mesh(grow(out), species=species_name)
        tried.append((f, _mesh_height(mesh)))
    return out, mesh


FIT_STEPS = 7  # halvings of the move when controls are brought back within the limits


def fit_controls(
    params: TreeParams,
    controls: Mapping[str, Any],
    species_name: str | None = None,
    only: Collection[str] | None = None,
) -> tuple[dict[str, Any], dict[str, Any]]:
    """``(controls, adjusted)``: the controls as asked when the tree they make is within
    the generator's limits (``adjusted`` empty), else with the relative number controls
    moved back from the asked values towards their neutral ones, all by one fraction, the
    largest that grows (halved ``FIT_STEPS`` times, then snapped to each control's step
    towards neutral), ``adjusted`` naming the new values. A slider pushed past what the
    generator can grow (a fir's leaf density and branch count together make more leaves
    than it grows) so gives the nearest tree it can grow instead of a refusal. ``only``
    names the controls that may move (the slider being dragged; default: every one).
    Raises ValueError for a bad value, or ParamError when even the others alone make a
    tree past the limits."""
    checked = check_controls(controls)
    unknown = sorted(set(only or ()) - set(_BY_NAME))
    if unknown:
        raise ValueError(f"unknown control(s) to fit: {', '.join(map(repr, unknown))}")
    movable = {
        k: v
        for k, v in checked.items()
        if _BY_NAME[k].relative
        and _BY_NAME[k].kind == "number"
        and v != _BY_NAME[k].neutral
        and (only is None or k in only)
    }

    def at(t: float) -> dict[str, Any]:
        out = dict(checked)
        for k, v in movable.items():
            c = _BY_NAME[k]
            x = c.neutral + t * (v - c.neutral)
            # the step towards neutral, so a snapped value never moves past the fitted one
            n = math.floor(abs(x - c.neutral) / c.step + 1e-9) * c.step
            out[k] = round(c.neutral + math.copysign(n, x - c.neutral), 6)
        return out

    def grown(values: Mapping[str, Any]) -> None:
        grow(apply_controls(params, {k: v for k, v in values.items() if k != "height"}))

    def grows(values: Mapping[str, Any]) -> bool:
        try:
            grown(values)
        except ParamError:
            return False
        return True

    if grows(checked):
        return dict(checked), {}
    if not movable or not grows(at(0.0)):
        try:
            grown(checked)  # not a matter of how far these sliders went
        except ParamError as exc:
            if not movable:
                raise
            names = ", ".join(_BY_NAME[k].label.lower() for k in movable)
            raise ParamError(f"{exc} (even with {names} back where the tree had it)") from None
    lo, hi = 0.0, 1.0
    for _ in range(FIT_STEPS):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if grows(at(mid)) else (lo, mid)
    fitted = at(lo)
    return fitted, {k: fitted[k] for k in movable if fitted[k] != checked[k]}


def current(params: TreeParams, height: float | None = None) -> dict[str, Any]:
    """The control values that leave ``params`` as it is (the neutral ones for relative
    controls, the tree's own for absolute ones); ``height``: the tree's when already
    known (else it is grown once to measure it)."""
    out: dict[str, Any] = {}
    for c in CONTROLS:
        if c.relative:
            out[c.name] = c.neutral
        elif c.name == "height" and height is not None:
            out[c.name] = float(height)
        else:
            assert c.read_fn is not None
            out[c.name] = c.read_fn(params)
    return out


def defaults(name: str) -> dict[str, Any]:
    """The controls' defaults for a species: :func:`current` of its base dictionary."""
    return dict(_defaults(species.canonical(name)))


@cache
def _defaults(name: str) -> dict[str, Any]:
    return current(species.base(name))
