"""Hard bounds on what ``grow`` and ``build_mesh`` may build, checked before allocating.

Parameter validation accepts every value inside its own range, but products of values
(split probability × segments per stem, ``resU`` × ``bevelRes`` × points) can ask for
billions of vertices.  ``grow`` counts the stems and control points it has made after
every segment and the exact mesh the skeleton will give after every level;
``build_mesh`` checks the exact size before allocating.  Going over a limit raises
:class:`~weberpenn.params.ParamError` naming the keys responsible.

The limits sit far above every species' sampled trees and the 15 reference trees
(the biggest, cherry: about 10 k stems, 24 k control points, 40 k leaves,
0.54 M vertices and 0.72 M triangles).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from functools import lru_cache
from typing import Any

import numpy as np

from .params import MAX_LEAVES, MAX_STEMS, ParamError

__all__ = [
    "MAX_GROW_POINTS",
    "MAX_LEAVES",
    "MAX_MESH_FACES",
    "MAX_MESH_VERTICES",
    "MAX_STEMS",
    "check_grow",
    "check_leaves",
    "check_mesh",
    "mesh_size",
    "responsible",
]

# MAX_STEMS (stems, split clones included) and MAX_LEAVES come from the parameter table,
# whose validation estimates them from the dictionary alone.
MAX_GROW_POINTS = 2_000_000  # padded control-point slots of one level while it grows
MAX_MESH_VERTICES = 4_000_000  # branches + leaves
MAX_MESH_FACES = 6_000_000  # triangles, branches + leaves

# What multiplies each count (per-level keys are named with their level below).
_STEM_KEYS = ("levels", "baseSplits", "branches", "segSplits", "curveRes")
_LEAF_KEYS = ("leaves", "levels", "branches", "segSplits")
_MESH_KEYS = ("resU", "bevelRes", "curveRes", "segSplits", "branches", "baseSplits", "levels")


def mesh_size(
    counts: np.ndarray, res_u: int, bevel_res: int, n_leaves: int, leaf_shape: str
) -> tuple[int, int]:
    """Exact (vertices, triangles) ``build_mesh`` makes for stems with ``counts`` control
    points each (stems with fewer than two make no tube) and ``n_leaves`` leaves."""
    c = np.asarray(counts, dtype=np.int64)
    c = c[c >= 2]
    sides = 4 + 2 * int(bevel_res)
    res_u = max(int(res_u), 1)
    rings = (c - 1) * res_u + 1
    verts = int(sides * rings.sum())
    faces = int(2 * sides * (rings - 1).sum())
    per_v, per_f = (4, 2) if str(leaf_shape) == "rect" else (6, 4)
    return verts + per_v * int(n_leaves), faces + per_f * int(n_leaves)


@lru_cache(maxsize=1)
def _reference_max() -> dict[str, float]:
    """Largest value of every numeric key over the five species' base dictionaries."""
    from . import species  # species imports the table; import late to keep this light

    out: dict[str, float] = {}
    for name in species.SPECIES:
        for key, value in species.base(name).items():
            vals = value if isinstance(value, tuple) else (value,)
            for v in vals:
                if isinstance(v, bool) or not isinstance(v, int | float):
                    continue
                out[key] = max(out.get(key, float("-inf")), float(v))
    return out


def responsible(p: Mapping[str, Any], keys: Sequence[str], level: int | None = None) -> list[str]:
    """The keys among ``keys`` (those ``p`` has) whose value (at ``level`` for per-level keys, else any level)
    exceeds the largest any species uses, as ``'key[i]=value'``; all of them if none does."""
    ref = _reference_max()
    named: list[tuple[bool, str]] = []
    for key in keys:
        if key not in p:
            continue
        value = p[key]
        if isinstance(value, tuple):
            idx = [min(level, 3)] if level is not None else range(len(value))
            items = [(f"{key}[{i}]", value[i]) for i in idx]
        else:
            items = [(key, value)]
        for label, v in items:
            named.append((float(v) > ref.get(key, float("inf")), f"{label}={v!r}"))
    high = [s for big, s in named if big]
    return high or [s for _, s in named]


def _error(what: str, p: Mapping[str, Any], keys: Sequence[str], level: int | None) -> ParamError:
    blame = responsible(p, keys, level)
    first = blame[0].split("=", 1)[0].split("[", 1)[0]
    return ParamError(f"{what}; reduce {', '.join(blame)}", first)


def check_grow(p: Mapping[str, Any], level: int, stems: int, padded_points: int) -> None:
    """Raise if the stems grown so far (``stems`` in the tree) or the padded control-point
    slots of the growing ``level`` exceed the limits."""
    if stems > MAX_STEMS:
        raise _error(
            f"the tree grows more than {MAX_STEMS} stems (at least {stems} by level {level})",
            p,
            _STEM_KEYS,
            level,
        )
    if padded_points > MAX_GROW_POINTS:
        raise _error(
            f"level {level} grows more than {MAX_GROW_POINTS} control points "
            f"(at least {padded_points})",
            p,
            _STEM_KEYS,
            level,
        )


def check_leaves(p: Mapping[str, Any], leaves: int) -> None:
    if leaves > MAX_LEAVES:
        raise _error(
            f"the tree would have {leaves} leaves; the limit is {MAX_LEAVES}", p, _LEAF_KEYS, None
        )


def check_mesh(verts: int, faces: int, p: Mapping[str, Any]) -> None:
    """Raise if a mesh of ``verts`` vertices and ``faces`` triangles exceeds the limits.

    ``p`` holds the values known (the dictionary, or just ``resU`` and ``bevelRes`` for a
    bare skeleton): the error names those responsible."""
    if verts <= MAX_MESH_VERTICES and faces <= MAX_MESH_FACES:
        return
    what = (
        f"the tree mesh would have {verts:,} vertices and {faces:,} triangles; the limits "
        f"are {MAX_MESH_VERTICES:,} and {MAX_MESH_FACES:,}"
    )
    raise _error(what, p, _MESH_KEYS, None)
