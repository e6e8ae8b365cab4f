"""The species: the paper's five and the trees people draw, as data.

``species_data.json`` is made by ``scripts/make_species_data.py``.  The paper's five
(:data:`PAPER_SPECIES`) come from the 15 published TreeSketchNet ground-truth files: a key
(or one level of a per-level key) is *fixed* when it is equal in a species' three files;
otherwise it is *unfixed* and drawn by the rule of TreeSketchNet's ``set_variation`` with
an amplitude covering every observed value.  The species people draw (a conical fir, a
weeping willow, a round-crowned oak, a slender birch, a columnar poplar and a bare winter
tree) start from Blender's bundled Sapling presets; their unfixed values are the presets'
own variation amplitudes, realised the same way.

``sample(species, seed)`` draws a dictionary with a numpy ``Generator``;
``unfixed(species)`` lists exactly what varies (what the refinement searches).
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cache
from importlib import resources
from typing import Any

import numpy as np

from .params import SPECS, ParamError, TreeParams

#: The paper's five species, in the project's order (its benchmarks compare on these).
PAPER_SPECIES: tuple[str, ...] = ("maple", "pine", "bonsai", "palm", "cherry")

#: The species people draw most that the paper's five cannot be.
PEOPLE_SPECIES: tuple[str, ...] = ("fir", "willow", "oak", "birch", "poplar", "winter")

#: Every species, in the project's order (the paper's five first, so their dataset seeds
#: and indices never move).
SPECIES: tuple[str, ...] = PAPER_SPECIES + PEOPLE_SPECIES

#: Name of each species in the TreeSketchNet files.
PAPER_NAMES: dict[str, str] = {
    "maple": "acer_2",
    "pine": "pine",
    "bonsai": "bonsai",
    "palm": "palm_3",
    "cherry": "cherry_blossom_3",
}

_ALIASES: dict[str, str] = {v: k for k, v in PAPER_NAMES.items()} | {
    "acer": "maple",
    "cherry_blossom": "cherry",
    "spruce": "fir",
    "conifer": "fir",
    "christmas_tree": "fir",
    "weeping_willow": "willow",
    "aspen": "birch",
    "bare": "winter",
    "winter_tree": "winter",
}


@dataclass(frozen=True)
class Unfixed:
    """One unfixed value: a key (and level ``index`` for per-level keys) and its range.

    ``rule`` is how ``sample`` draws it: ``uniform`` (lo..hi), ``sign`` (-1/1),
    ``randint`` (lo..hi inclusive), ``mirror`` (minus another key's value: not free),
    ``split_height`` (0.6 when the trunk splits at its base, else a fixed value).
    """

    key: str
    index: int | None
    lo: float
    hi: float
    rule: str

    @property
    def discrete(self) -> bool:
        return self.rule in ("sign", "randint") or SPECS[self.key].discrete

    @property
    def free(self) -> bool:
        """Whether a search may move this value independently."""
        return self.rule not in ("mirror", "split_height")

    @property
    def label(self) -> str:
        return self.key if self.index is None else f"{self.key}[{self.index}]"


def canonical(name: str) -> str:
    """The species' canonical name (accepts the paper's names); raises for unknown ones."""
    key = str(name).strip().lower().replace(" ", "_").replace("-", "_")
    key = _ALIASES.get(key, key)
    if key not in SPECIES:
        raise ParamError(f"unknown species {name!r}; choose one of {', '.join(SPECIES)}")
    return key


@cache
def _data() -> dict[str, Any]:
    text = resources.files("weberpenn").joinpath("species_data.json").read_text("utf-8")
    return json.loads(text)["species"]


def display_name(name: str) -> str:
    """What a person calls the species ("fir (conical conifer)")."""
    return str(_data()[canonical(name)].get("display", canonical(name)))


def common_name(name: str) -> str:
    """The display name without its gloss: "oak" for "oak (round crown)"."""
    return display_name(name).split(" (")[0]


def doodle_foliage(name: str) -> bool:
    """Whether people draw the species' foliage as single strokes (palm fronds, a weeping
    willow's hanging twigs) rather than as a crown outline."""
    return bool(_data()[canonical(name)].get("foliage_strokes", False))


def sketch_stem_cut(name: str) -> float:
    """Stems thinner than this fraction of a sketch's sample width may be left out of the
    fast sketch's mesh without changing the sketch (``render.sketch.sketch_mesh``)."""
    return float(_data()[canonical(name)].get("sketch_stem_cut", 0.5))


def outline_stem_cut(name: str) -> float:
    """Stems thinner than this fraction of a sketch's sample width may be left out of the
    mesh of a sketch read for its envelope alone (``refine.start``'s outline step): more
    than :func:`sketch_stem_cut` where the foliage draws the crown's outline."""
    return float(_data()[canonical(name)].get("outline_stem_cut", sketch_stem_cut(name)))


def source(name: str) -> str:
    """Where the species' numbers come from (the paper's files or a Sapling preset)."""
    return str(_data()[canonical(name)].get("source", ""))


def sapling_preset(name: str) -> str | None:
    """Stem of the Blender Sapling preset the species starts from (``douglas_fir``), or
    None for the paper's five (they come from its published files)."""
    return _data()[canonical(name)].get("sapling_preset")


def reference_files(name: str) -> tuple[str, ...]:
    """File names of the species' three published ground-truth dictionaries."""
    return tuple(_data()[canonical(name)]["reference_files"])


def base(name: str) -> TreeParams:
    """The species' base dictionary (its first published ground truth, seed 0)."""
    return _base(canonical(name))


@cache
def _base(name: str) -> TreeParams:
    """Validated once: a TreeParams never changes, and the search asks for it per tree."""
    return TreeParams(_data()[name]["base"])


def _to_unfixed(row: dict[str, Any]) -> Unfixed:
    rule = row["rule"]
    if rule in ("uniform", "randint"):
        lo, hi = float(row["lo"]), float(row["hi"])
    elif rule == "uniform_sym":
        lo, hi, rule = -float(row["amp"]), float(row["amp"]), "uniform"
    elif rule == "uniform_around_one":
        lo, hi, rule = 1.0 - float(row["amp"]), 1.0 + float(row["amp"]), "uniform"
    elif rule == "sign":
        lo, hi = -1.0, 1.0
    elif rule == "split_height":
        lo, hi = float(row["without"]), float(row["with_splits"])
    elif rule == "mirror":
        lo, hi = -360.0, 360.0
    else:  # pragma: no cover - guarded by the data generator
        raise ValueError(f"unknown rule {rule!r}")
    return Unfixed(row["key"], row["index"], lo, hi, rule)


@cache
def unfixed(name: str) -> tuple[Unfixed, ...]:
    """Every unfixed value of the species, with its range and draw rule."""
    return tuple(_to_unfixed(r) for r in _data()[canonical(name)]["unfixed"])


def unfixed_keys(name: str) -> tuple[str, ...]:
    """Names of the keys with at least one unfixed value."""
    return tuple(dict.fromkeys(u.key for u in unfixed(name)))


def _set(values: dict[str, Any], key: str, index: int | None, value: Any) -> None:
    if index is None:
        values[key] = value
    else:
        vec = list(values[key])
        vec[index] = value
        values[key] = vec


def _get(values: dict[str, Any], key: str, index: int | None) -> Any:
    return values[key] if index is None else values[key][index]


def sample(name: str, seed: int = 0) -> TreeParams:
    """Draw one tree of the species: base values plus freshly drawn unfixed values."""
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        raise ParamError(f"seed must be a non-negative integer, got {seed!r}")
    rng = np.random.default_rng(int(seed))
    values = base(name).to_dict()
    rows = unfixed(name)
    for u in rows:
        spec = SPECS[u.key]
        if u.rule == "uniform":
            v: Any = float(rng.uniform(u.lo, u.hi))
            if spec.kind == "int":
                v = round(v)
        elif u.rule == "sign":
            v = int(rng.choice([-1, 1]))
        elif u.rule == "randint":
            v = int(rng.integers(int(u.lo), int(u.hi) + 1))
        else:
            continue  # derived below
        _set(values, u.key, u.index, v)
    for u in rows:
        if u.rule == "mirror":
            _set(values, u.key, u.index, -float(_get(values, "curve", u.index)))
        elif u.rule == "split_height":
            values[u.key] = u.hi if values["baseSplits"] > 0 else u.lo
    values["seed"] = int(seed)
    return TreeParams(values)


#: The trunk's bend: ``curve[0]`` and the ``curveBack[0]`` that bends it back (minus it,
#: the ``mirror`` rule).  Where a species leaves it free (the palm, the bonsai) it moves the
#: tree more than any other value; it shows only in a view across the plane it bends in,
#: and its sign names a side of the tree that no single drawing fixes (the same trunk seen
#: from the other side bends the other way).
TRUNK_BEND = (("curve", 0), ("curveBack", 0))


#: Shapes people draw that the published variation cannot reach, opened to the
#: refinement's search only (``sample`` never draws them, so datasets are unchanged, and
#: every base value lies inside its range).  A trunk that leans or bends: the published
#: palm and bonsai trunks curve by ``curve[0]`` and curve straight back by the mirrored
#: ``curveBack[0]`` (and the palm's ``attractUp[0]`` of 8.6 pulls it upright), so the
#: trunk always ends above its base.  A conical conifer: the pine's envelope
#: (``customShape``: length factor at the base, the widest point, its height, the top) is
#: fixed at a tiered shape.  Ranges stay inside what Sapling accepts.
SEARCH_FREEDOMS: dict[str, tuple[Unfixed, ...]] = {
    "palm": (
        Unfixed("curveBack", 0, -90.0, 90.0, "search"),
        Unfixed("attractUp", 0, 0.0, 8.57, "search"),
    ),
    "bonsai": (
        Unfixed("curveBack", 0, -150.0, 150.0, "search"),
        Unfixed("attractUp", 0, 0.0, 0.81, "search"),
    ),
    "pine": tuple(Unfixed("customShape", i, 0.05, 1.0, "search") for i in range(4)),
}


#: The outline a drawing sets over the species' habit (issue 48, ``refine.start``): the
#: crown's width profile (``shape`` 8 and its ``customShape``), the crown base, the
#: trunk's thickness and the branches' reach.  ``project(..., keep=DRAWN_KEYS)`` keeps
#: them as given (the parameter table has checked their ranges): where a person draws
#: what the species' ranges do not allow, the tree follows the drawing as far as it grows.
DRAWN_KEYS = ("shape", "customShape", "baseSize", "ratio", "length")


def search_freedoms(name: str) -> tuple[Unfixed, ...]:
    """The species' search-only freedoms (see :data:`SEARCH_FREEDOMS`)."""
    return SEARCH_FREEDOMS.get(canonical(name), ())


def project(
    name: str, params: TreeParams, search: bool = False, keep: Sequence[str] = ()
) -> TreeParams:
    """Force a dictionary onto a species: its fixed values, keeping the unfixed ones.

    Unfixed values are clipped into the species' ranges; derived values (mirrors, the
    split height) are recomputed.  Used after prediction so a tree is a valid member.
    With ``search`` the species' search-only freedoms (:data:`SEARCH_FREEDOMS`) keep the
    given values too, clipped into their ranges (what the refinement moves); the keys in
    ``keep`` (e.g. :data:`DRAWN_KEYS`) keep the given values whatever the species'.
    """
    start = base(name)
    values = start.to_dict()
    src = params.to_dict()
    for u in unfixed(name):
        v = _get(src, u.key, u.index)
        if u.rule in ("uniform", "randint"):
            v = float(np.clip(v, u.lo, u.hi))
            if SPECS[u.key].kind == "int":
                v = round(v)
        _set(values, u.key, u.index, v)
    for u in unfixed(name):
        if u.rule == "mirror":
            _set(values, u.key, u.index, -float(_get(values, "curve", u.index)))
        elif u.rule == "split_height":
            values[u.key] = u.hi if values["baseSplits"] > 0 else u.lo
    if search:
        for u in search_freedoms(name):
            _set(values, u.key, u.index, float(np.clip(_get(src, u.key, u.index), u.lo, u.hi)))
    for key in keep:  # a start fitted to a drawing: its outline wins
        values[key] = src[key]
    values["seed"] = params["seed"]
    first = start.to_dict()
    return start.replace(**{k: v for k, v in values.items() if v != first[k]})
