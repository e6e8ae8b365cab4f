"""Several drawings of one tree: the views a :class:`treesketch.Pipeline` run reads.

A run's input is a list of views: a drawing and its yaw in degrees about the trunk,
relative to the first view (the first is 0 by definition; 90 is the side the renderer
shows when the camera turns 90 degrees, ``render.sketch.SketchRenderer.sketch(90)``), or
``None`` when the angle is not known (the refinement picks it).  One drawing is the list
of one.  :func:`as_views` turns what a caller hands over (one source, a list of sources or
``(source, yaw)`` pairs, :class:`SketchView` objects) into that list and checks it before
anything is read; :func:`parse_view` reads the CLI's ``side.png@90`` / ``side.png@?``;
:func:`fuse_estimates` merges the estimator's reading of every view into one estimate.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from weberpenn import TreeParams
from weberpenn import species as wp_species
from weberpenn.params import SPECS

from .estimate import Estimate

__all__ = [
    "MAX_VIEWS",
    "SketchView",
    "ViewResult",
    "as_views",
    "fuse_estimates",
    "parse_view",
    "parse_yaw",
]

# more drawings than this add little (front, side, back, other side) and each costs a
# render per evaluation
MAX_VIEWS = 4


@dataclass(frozen=True)
class SketchView:
    """One drawing of the tree (a path, bytes, an image or an array) and its yaw in
    degrees relative to the first view; ``None``: not known, searched."""

    source: Any
    yaw: float | None = 0.0


@dataclass(frozen=True)
class ViewResult:
    """One view of a result: its yaw relative to the first view (as given or as found),
    the prepared drawing, the first estimate's and the result's sketches from that side,
    and the sketch distance of each to the drawing."""

    yaw: float
    input_sketch: np.ndarray
    sketch_before: np.ndarray
    sketch_after: np.ndarray
    loss_before: float
    loss_after: float
    searched: bool = False  # the yaw was not given: the refinement found it

    def summary(self) -> dict[str, Any]:
        return {
            "yaw": float(self.yaw),
            "searched": self.searched,
            "loss_before": float(self.loss_before),
            "loss_after": float(self.loss_after),
        }


def parse_yaw(text: Any) -> float | None:
    """A view's yaw from text or a number: degrees (finite), or ``"?"`` / ``None`` /
    ``""`` for an angle to search.  ValueError names what was given."""
    if text is None:
        return None
    if isinstance(text, bool):
        raise ValueError(f"a view's yaw must be degrees or '?', got {text!r}")
    if isinstance(text, int | float | np.integer | np.floating):
        value = float(text)
    else:
        s = str(text).strip()
        if s in ("", "?"):
            return None
        try:
            value = float(s.removesuffix("°").removesuffix("deg"))
        except ValueError:
            raise ValueError(f"a view's yaw must be degrees or '?', got {str(text)!r}") from None
    if not math.isfinite(value) or abs(value) > 3600:
        raise ValueError(f"a view's yaw must be degrees in [-3600, 3600] or '?', got {text!r}")
    return value % 360.0


def parse_view(text: str) -> SketchView:
    """``"side.png@90"`` -> the file and yaw 90; ``"side.png@?"``: the yaw is searched;
    a name without ``@`` is the side view (90)."""
    path, sep, yaw = str(text).rpartition("@")
    if not sep:
        return SketchView(text, 90.0)
    if not path:
        raise ValueError(f"--view {text!r}: expected FILE@DEGREES or FILE@?")
    try:
        return SketchView(path, parse_yaw(yaw))
    except ValueError as exc:
        raise ValueError(f"--view {text!r}: {exc}") from None


def _one(item: Any, first: bool) -> SketchView:
    if isinstance(item, SketchView):
        view = SketchView(item.source, parse_yaw(item.yaw))
    elif isinstance(item, tuple) and len(item) == 2:
        view = SketchView(item[0], parse_yaw(item[1]))
    else:
        view = SketchView(item, 0.0)
    if first:
        if view.yaw not in (0.0, None):
            raise ValueError(
                f"the first view defines yaw 0 (the others are relative to it), got {view.yaw}"
            )
        return SketchView(view.source, 0.0)
    return view


def as_views(sketch: Any) -> list[SketchView]:
    """One source, or a list of views (sources, ``(source, yaw)`` pairs or
    :class:`SketchView`), as a checked list of :class:`SketchView`, the first at yaw 0."""
    items = list(sketch) if isinstance(sketch, list | tuple) else [sketch]
    if not items:
        raise ValueError("no drawing given")
    if len(items) > MAX_VIEWS:
        raise ValueError(f"at most {MAX_VIEWS} views of one tree, got {len(items)}")
    return [_one(item, i == 0) for i, item in enumerate(items)]


def _mean_params(params: Sequence[TreeParams], name: str) -> TreeParams:
    """The continuous values averaged over the views' estimates (discrete ones: the first
    view's), fitted to species ``name``; the trunk's bend is the reading of the view that
    sees the most of it (``weberpenn.species.TRUNK_BEND``): the views' readings of it are
    not noisy copies of one value, a view along the plane it bends in reads a nearly
    straight trunk and two views can read opposite signs, so their mean would straighten a
    bent trunk."""
    if len(params) == 1:
        return params[0]
    values = params[0].to_dict()
    for key, spec in SPECS.items():
        if spec.discrete or key not in values or key == "seed":
            continue
        stack = np.asarray([p[key] for p in params], dtype=np.float64)
        mean = stack.mean(axis=0)
        values[key] = [float(v) for v in mean] if spec.is_vector else float(mean)
    bend_key, bend_index = wp_species.TRUNK_BEND[0]
    bent = max(params, key=lambda p: abs(float(p[bend_key][bend_index])))
    for key, index in wp_species.TRUNK_BEND:
        vector = list(values[key])
        vector[index] = float(bent[key][index])
        values[key] = vector
    return wp_species.project(name, TreeParams(values))


def fuse_estimates(estimates: Sequence[Estimate]) -> Estimate:
    """One estimate from the estimator's reading of every view: the species scores are
    averaged; the parameters, for the best species and for every other, are the views'
    continuous values averaged (a tree's values do not depend on the side it is drawn
    from, so each view is another noisy reading of them) but for the trunk's bend, which
    is the reading of the view that shows it most (``weberpenn.species.TRUNK_BEND``);
    the yaw is the first view's."""
    if not estimates:
        raise ValueError("no estimate to fuse")
    if len(estimates) == 1:
        return estimates[0]
    names = sorted({s for e in estimates for s in (e.species_scores or {e.species: 1.0})})
    scores = {
        s: float(np.mean([(e.species_scores or {e.species: 1.0}).get(s, 0.0) for e in estimates]))
        for s in names
    }
    first = estimates[0]
    best = max(names, key=lambda s: (scores[s], s == first.species))
    alternatives = {
        s: _mean_params([e.params_for(s) for e in estimates], s)
        for s in wp_species.SPECIES
        if s != best
    }
    return Estimate(
        params=_mean_params([e.params_for(best) for e in estimates], best),
        species=best,
        species_scores=scores,
        yaw=first.yaw,
        decoded=None,
        alternatives=alternatives,
        tree_probability=_mean_or_none([e.tree_probability for e in estimates]),
    )


def _mean_or_none(values: Sequence[float | None]) -> float | None:
    known = [v for v in values if v is not None]
    return float(np.mean(known)) if known else None
