"""The one place that composes "a first estimate" and "refine it": :class:`Pipeline`.

``Pipeline(estimator, settings).run(sketch)`` reads the sketch (the one reader,
``render.reader``), prepares it as the renderer frames a tree, asks the estimator for a
first estimate (parameters, species scores, maybe a view), refines the species' free values
and the view yaw with ``refine.search`` until the tree's sketch matches the input, judges
whether the drawing is a tree, and returns a :class:`Result`; the steps are
:mod:`treesketch.steps`.  The CLI, the HTTP service, the evaluation report, the rotation
sweep, the benchmarks and the notebooks all run a ``Pipeline``;
:func:`predict_then_refine` is the one-line convenience over it.

A sketch that does not look like a tree is not an error of the program: a blank page
raises :class:`SketchError`; anything else (a circle, noise) gives a result whose
``confidence`` is low and whose ``warning`` says so.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from refine.objective import framed
from refine.search import Cancelled, RefineResult, RefineSettings
from refine.shape import ShapeTarget, line_distance
from render.reader import SketchError, ink_mask, line_spread, straight_share
from weberpenn import TreeMesh, TreeParams, build_mesh, grow
from weberpenn import species as wp_species

from .estimate import Estimate, Estimator
from .estimators import load_estimator
from .species_choice import Candidate, describe
from .steps import (
    DrawnViews,
    FirstEstimate,
    Progress,
    ReadDrawings,
    Reporter,
    SpeciesSearch,
    draw_views,
    first_estimate,
    list_candidates,
    load_sketch,
    planned_evaluations,
    prepare_input,
    read_drawings,
    read_views,
    refine_species,
    species_to_try,
    timed,
)
from .views import SketchView, ViewResult, as_views, fuse_estimates

__all__ = [
    "LOW_CONFIDENCE_INK",
    "LOW_CONFIDENCE_LOSS",
    "LOW_CONFIDENCE_LOSS_SHAPE",
    "MAX_HEIGHT",
    "Cancelled",
    "Judgement",
    "Pipeline",
    "Progress",
    "RefineSettings",
    "Result",
    "SketchError",
    "SketchView",
    "TREE_PROBABILITY_LIMIT",
    "ViewResult",
    "check_height",
    "fit_height",
    "has_height",
    "judge_views",
    "load_sketch",
    "planned_evaluations",
    "predict_then_refine",
    "prepare_input",
    "rescale_height",
    "result_confidence",
    "straight_lines",
    "tree_judgement",
    "tree_likeness",
    "tree_line_distance",
]

# the result is flagged when the best tree's sketch is this far from the input, by the
# style-blind shape distance the refinement minimises (with the learned embedding's term
# when it is on; a circle can pass for a crown) or by the line distance
# (``refine.shape.line_distance``: ink the tree's shape does not explain, a trunk where
# nothing is drawn); recalibrated with doodles and code-made non-tree doodles
# (``benchmarks/bench_species.py``; RESULTS.md, "The species people draw": at 1.75 and
# 0.035 a third of SG drawings and nearly half the doodles of trees were warned)
LOW_CONFIDENCE_LOSS = 2.25
# the same limit for the hand-made shape distance alone (``RefineSettings(embedding="none")``
# or the ink metric), calibrated before the embedding existed (RESULTS.md, "Style-blind
# distance and warning, recalibrated")
LOW_CONFIDENCE_LOSS_SHAPE = 0.7
LOW_CONFIDENCE_INK = 0.06
# an estimator that can tell whether a drawing is a tree at all (TSN's tree detector,
# ``tsn.tree_detect``) decides the warning instead of the distances: below this
# probability the drawing is asked "is this a tree?".  The distances cannot tell a quick
# doodle of a tree from a house (RESULTS.md, "Is it a tree?")
TREE_PROBABILITY_LIMIT = 0.5
# one straight line (a stick, a stick with a dot on it, a line across the page) shows no
# crown, and the network reads a lone upright line as a fir's trunk (P(tree) 0.997): a
# drawing whose ink spreads across its longest axis no more than this share of its reach
# (``render.reader.line_spread``; a hand-drawn line about 0.005, the thinnest of people's
# 648 held-out trees 0.079) is asked "is this a tree?" whatever the estimator says, and
# is a tree as often as people's held-out drawings that thin are (LINE_TREES: 1 of 11,
# a single stroke labelled a tree; `benchmarks/probes/one_line.py`)
LINE_SPREAD = 0.03
LINE_TREES = 1 / 11
# two straight strokes (a cross, a plus, an X, a T, a V) show no crown either, and the
# network reads a cross as a palm or a pine at P(tree) 0.99: a drawing whose ink's centre
# line lies this much within reach of its two strongest straight lines
# (``render.reader.straight_share``; people's held-out trees at most 0.78 but for one
# single stroke, `examples/hand` at most 0.44) is asked too, and is a tree as often as
# people's held-out drawings of at most two straight lines are (STRAIGHT_TREES: 1 of 7,
# that single stroke; `benchmarks/probes/two_lines.py`)
STRAIGHT_SHARE = 0.95
STRAIGHT_TREES = 1 / 7
MAX_HEIGHT = 200.0  # metres: taller than any tree that grows


@dataclass(frozen=True)
class Result:
    params: TreeParams
    species: str
    tree_mesh: Any
    sketch_before: np.ndarray  # uint8 sketch of the first estimate
    sketch_after: np.ndarray  # uint8 sketch of the returned tree
    losses: dict[str, float]  # "before", "after": sketch distance to the input
    timings: dict[str, float]  # seconds per stage
    yaw: float = 0.0
    input_sketch: np.ndarray | None = None  # uint8, prepared, framed as compared (as_drawn)
    estimator: str = "tsn"
    estimate: Estimate | None = None
    refinement: RefineResult | None = None
    confidence: float = 1.0
    warning: str | None = None
    extras: dict[str, Any] = field(default_factory=dict)
    candidates: tuple[Candidate, ...] = ()  # best first: the species it could be
    # every drawing of the tree (the first is the fields above); one for one drawing
    views: tuple[ViewResult, ...] = ()

    @property
    def species_text(self) -> str:
        """The species in words, with the others it could be ("a palm; could also be...")."""
        return describe(list(self.candidates))

    @property
    def low_confidence(self) -> bool:
        return self.warning is not None

    @property
    def species_scores(self) -> dict[str, float]:
        return {} if self.estimate is None else dict(self.estimate.species_scores)

    def summary(self) -> dict[str, Any]:
        """Everything but the arrays and the mesh, as JSON-able plain data."""
        r = self.refinement
        return {
            "species": self.species,
            "species_scores": self.species_scores,
            "estimator": self.estimator,
            "params": self.params.to_dict(),
            "losses": dict(self.losses),
            "yaw": float(self.yaw),
            "confidence": float(self.confidence),
            "species_text": self.species_text,
            "candidates": [c.summary() for c in self.candidates],
            "warning": self.warning,
            "timings": dict(self.timings),
            "evaluations": 0 if r is None else int(r.evaluations),
            "stopped_by": None if r is None else r.stopped_by,
            **({"views": [v.summary() for v in self.views]} if len(self.views) > 1 else {}),
            **{k: v for k, v in self.extras.items() if isinstance(v, int | float | str | dict)},
        }


def check_height(height: float | None) -> float | None:
    """None, or a finite height in (0, MAX_HEIGHT] metres (ValueError otherwise)."""
    if height is None:
        return None
    if (
        isinstance(height, bool)
        or not isinstance(height, int | float | np.floating | np.integer)
        or not math.isfinite(height)
        or not 0 < height <= MAX_HEIGHT
    ):
        raise ValueError(f"height must be metres in (0, {MAX_HEIGHT:g}], got {height!r}")
    return float(height)


def mesh_height(mesh: Any) -> float:
    lo, hi = mesh.bounds()
    return float(np.asarray(hi)[2] - np.asarray(lo)[2])


def tree_height(params: TreeParams) -> float:
    return mesh_height(build_mesh(grow(params)))


def rescale_height(params: TreeParams, height: float, current: float | None = None) -> TreeParams:
    """Scale ``scale`` and ``scaleV`` so the grown tree is ``height`` tall (metres);
    ``current``: the tree's height when already known (saves growing it once)."""
    height = check_height(height)
    if height is None:
        raise ValueError("height must be given")
    current = tree_height(params) if current is None else float(current)
    if current <= 0:
        raise ValueError("the tree has no height to rescale")
    f = height / current
    out = params.replace(scale=float(params["scale"]) * f, scaleV=float(params["scaleV"]) * f)
    # radii follow scale in Weber-Penn, leaves keep their size (``leafScale`` is in
    # metres: a taller tree of one kind has the same leaves); one correction pass for any
    # non-linearity (e.g. a clipped value)
    again = tree_height(out)
    if again > 0 and abs(again - height) / height > 0.01:
        g = height / again
        out = out.replace(scale=float(out["scale"]) * g, scaleV=float(out["scaleV"]) * g)
    return out


def tree_line_distance(drawing: Any, tree_sketch: Any, size: int) -> float:
    """``refine.shape.line_distance`` of a drawing and a tree's sketch, both framed as the
    refinement frames them (a tree too small to draw anything is as far as can be)."""
    return drawing_line_distance(ShapeTarget.from_image(framed(drawing, size), size), tree_sketch)


def drawing_line_distance(drawing: ShapeTarget, tree_sketch: Any) -> float:
    """:func:`tree_line_distance` from the drawing's shape features, already prepared."""
    size = drawing.size
    try:
        tree = ShapeTarget.from_image(framed(tree_sketch, size), size)
    except SketchError:
        return 1.0
    return line_distance(drawing, tree)


def tree_likeness(loss: float, ink: float, limit: float) -> tuple[float, str | None]:
    """Confidence in 0..1 (1 at a perfect match, exp(-1) at either threshold) and the
    warning when either distance passes its threshold (``limit`` for the shape distance:
    the one calibrated for the distance in use)."""
    worst = max(max(0.0, loss) / limit, max(0.0, ink) / LOW_CONFIDENCE_INK)
    confidence = float(math.exp(-worst))
    if worst <= 1.0:
        return confidence, None
    return confidence, (
        f"low confidence: the best tree's sketch is far from the input (shape distance "
        f"{loss:.3f}, limit {limit}; line distance {ink:.3f}, limit "
        f"{LOW_CONFIDENCE_INK}); is this a sketch of a tree?"
    )


def straight_lines(images: Sequence[np.ndarray]) -> int:
    """1 when every drawing (prepared, paper light) is one straight line
    (:data:`LINE_SPREAD`), 2 when every one is at most two (:data:`STRAIGHT_SHARE`: a
    cross, a plus, an X, a T, a V), else 0."""
    inks = [ink_mask(img) for img in images]
    if all(line_spread(ink) <= LINE_SPREAD for ink in inks):
        return 1
    if all(straight_share(ink) >= STRAIGHT_SHARE for ink in inks):
        return 2
    return 0


def tree_judgement(
    tree_probability: float | None,
    loss: float,
    ink: float,
    limit: float,
    lines: int = 0,
) -> tuple[float, str | None]:
    """How much the drawing looks like a tree (0..1) and the warning when it may not be
    one: the estimator's probability when it gives one (warned below
    :data:`TREE_PROBABILITY_LIMIT`), else the distances' :func:`tree_likeness`; a drawing
    of one or two straight ``lines`` (:func:`straight_lines`) is warned, at most
    :data:`LINE_TREES` or :data:`STRAIGHT_TREES`."""
    if lines:
        cap = LINE_TREES if lines == 1 else STRAIGHT_TREES
        p = cap if tree_probability is None else min(cap, tree_probability)
        what = "one straight line" if lines == 1 else "two straight lines"
        return float(max(0.0, p)), (
            f"low confidence: this is {what}, not a drawing of a tree (draw its crown "
            f"too); is this a sketch of a tree?"
        )
    if tree_probability is None:
        return tree_likeness(loss, ink, limit)
    p = float(min(1.0, max(0.0, tree_probability)))
    if p >= TREE_PROBABILITY_LIMIT:
        return p, None
    return p, (
        f"low confidence: this does not look like a drawing of a tree (probability "
        f"{p:.0%}; shape distance {loss:.3f}, line distance {ink:.3f}); is this a sketch "
        f"of a tree?"
    )


def result_confidence(
    species_probability: float,
    tree_like: float,
    warning: str | None,
    tree_probability: float | None = None,
) -> float:
    """How sure a result is the kind of tree drawn: with a calibrated probability that the
    drawing is a tree, the product (a tree, and of this species); else its species'
    probability, and a drawing warned as maybe no tree cannot be surer of its kind than of
    being a tree."""
    if tree_probability is not None:
        return float(species_probability * min(1.0, max(0.0, tree_probability)))
    return species_probability if warning is None else min(species_probability, tree_like)


def has_height(mesh: TreeMesh, height: float | None) -> bool:
    """Whether the tree is ``height`` metres tall (to a millionth; any height when None)."""
    return height is None or abs(mesh_height(mesh) - height) <= 1e-6 * height


def fit_height(
    params: TreeParams, mesh: TreeMesh, species: str, height: float
) -> tuple[TreeParams, TreeMesh]:
    """The tree (``params``, grown as ``mesh``) rescaled to ``height`` metres and grown
    again."""
    params = rescale_height(params, height, current=mesh_height(mesh))
    return params, build_mesh(grow(params), species=species)


@dataclass(frozen=True)
class Judgement:
    """Whether the drawing looks like a tree: the line distance over the views
    (``ink_after``), how much it looks like one (0..1) and the warning when it may not."""

    ink_after: float
    tree_like: float
    warning: str | None
    tree_probability: float | None = None

    def confidence(self, candidates: list[Candidate]) -> float:
        """How sure the result is (:func:`result_confidence`), its species' probability
        being the first candidate's."""
        p = candidates[0].probability if candidates else self.tree_like
        return result_confidence(p, self.tree_like, self.warning, self.tree_probability)


def judge_views(
    read: ReadDrawings, drawn: DrawnViews, first: FirstEstimate, embedded: bool
) -> Judgement:
    """:func:`tree_judgement` of the result: every view's unexplained ink, averaged as the
    shape distance is; ``embedded``: the shape distance has the learned embedding's term
    (its own calibrated limit)."""
    pairs = zip(read.drawings, drawn.views, strict=True)
    ink = float(np.mean([drawing_line_distance(d.shape, v.sketch_after) for d, v in pairs]))
    limit = LOW_CONFIDENCE_LOSS if embedded else LOW_CONFIDENCE_LOSS_SHAPE
    p = first.estimate.tree_probability
    lines = straight_lines(read.images)
    tree_like, warning = tree_judgement(p, drawn.loss_after, ink, limit, lines)
    if lines and p is not None:
        p = tree_like
    return Judgement(ink, tree_like, warning, p)


class Pipeline:
    """An estimator and the refinement settings; :meth:`run` turns a sketch into a tree."""

    def __init__(
        self,
        estimator: Estimator | str | os.PathLike[str] = "tsn",
        settings: RefineSettings | None = None,
    ) -> None:
        self.estimator = load_estimator(estimator)
        self.settings = (settings or RefineSettings()).validate()
        # the learned shape embedding the distance adds (None: not used), loaded once
        self.embedder = self.settings.load_embedder()

    def __repr__(self) -> str:
        return f"Pipeline({self.estimator.name!r}, {self.settings!r})"

    def with_settings(self, **changes: Any) -> Pipeline:
        """The same estimator (not reloaded) with some settings changed."""
        return Pipeline(self.estimator, self.settings.replace(**changes))

    def estimate(self, sketch: Any) -> Estimate:
        """The first estimate alone (read, prepared, estimated; nothing refined); several
        views (as :meth:`run` takes them) give the estimate fused over all."""
        imgs = read_views(as_views(sketch))
        return fuse_estimates([self.estimator.estimate(img) for img in imgs])

    def run(
        self,
        sketch: Any,
        height: float | None = None,
        progress: Callable[[Progress], None] | None = None,
        cancel: Callable[[], bool] | None = None,
        species: str | None = None,
    ) -> Result:
        """Sketch (path, bytes, image or array) -> :class:`Result` (see the module text).

        ``sketch`` may also be several drawings of the tree: a list whose first item is
        the first view (a source) and whose others are ``(source, yaw)`` pairs or
        :class:`SketchView` (yaw in degrees about the trunk relative to the first view;
        None: not known, found by the refinement).  The estimator reads every view (its
        outputs fused, ``treesketch.views.fuse_estimates``), the refinement minimises the
        mean distance over all views, and ``Result.views`` keeps each view's sketches.

        ``height`` (metres) rescales the tree; ``progress`` is told of each stage and each
        refinement evaluation, with the current best tree (:class:`Progress`: the first
        estimate as soon as it exists, then the refinement's best); ``cancel()``
        returning True stops the run with :class:`Cancelled` within one tree
        evaluation; ``species`` (a name of ``weberpenn.species.SPECIES`` or one people
        use, "christmas tree") is the species the user means: only it is refined, and
        the result is of it."""
        height = check_height(height)
        chosen = None if species is None else wp_species.canonical(species)
        cfg = self.settings
        report = Reporter(cfg.budget if cfg.refine else 0, progress, cancel)
        timings: dict[str, float] = {}
        with timed(timings, "prepare"):
            report.tell("read")
            read = read_drawings(sketch, cfg, self.embedder)
        with timed(timings, "estimate"):
            report.tell("estimate")
            first = first_estimate(self.estimator, read.images, chosen)
        names = species_to_try(first, cfg)
        report.first_tree(first, planned_evaluations(cfg, len(names)))
        with timed(timings, "refine"):
            search = refine_species(read, first, names, cfg, report, self.embedder)
        with timed(timings, "render"):
            report.tell("render", search.evaluations)
            drawn = draw_views(read, first, search)
        params, mesh = search.params, drawn.mesh
        if not has_height(mesh, height):
            with timed(timings, "height"):
                params, mesh = fit_height(params, mesh, search.species, height)
        judged = judge_views(read, drawn, first, self.embedder is not None)
        with timed(timings, "candidates"):
            candidates = list_candidates(first, search, params, drawn.after)
        timings["total"] = sum(timings.values())
        return build_result(
            first, search, drawn, params, mesh, judged, candidates, timings, self.estimator.name
        )

    def candidates(self, est: Estimate) -> list[str]:
        """The species to refine: the estimator's, then up to ``species_tries - 1`` others
        scoring at least ``species_ratio`` times the best score."""
        return species_to_try(FirstEstimate(est), self.settings.replace(refine=True))


def build_result(
    first: FirstEstimate,
    search: SpeciesSearch,
    drawn: DrawnViews,
    params: TreeParams,
    mesh: TreeMesh,
    judged: Judgement,
    candidates: list[Candidate],
    timings: dict[str, float],
    estimator: str,
) -> Result:
    """The :class:`Result` of a run from its steps' outcomes (``params`` and ``mesh``: the
    result's tree at the height asked for)."""
    return Result(
        params=params,
        species=search.species,
        tree_mesh=mesh,
        sketch_before=drawn.before,
        sketch_after=drawn.after,
        losses={
            "before": drawn.loss_before,
            "after": drawn.loss_after,
            "ink_after": judged.ink_after,
        },
        timings=timings,
        yaw=float(search.yaw),
        input_sketch=drawn.views[0].input_sketch,
        estimator=estimator,
        estimate=first.estimate,
        refinement=search.result,
        confidence=judged.confidence(candidates),
        warning=judged.warning,
        extras={"tried": search.tried} if search.refined else {},
        candidates=tuple(candidates),
        views=drawn.views,
    )


def predict_then_refine(
    sketch: Any,
    *,
    estimator: Estimator | str = "tsn",
    height: float | None = None,
    progress: Callable[[Progress], None] | None = None,
    cancel: Callable[[], bool] | None = None,
    species: str | None = None,
    **settings: Any,
) -> Result:
    """``Pipeline(estimator, RefineSettings(**settings)).run(sketch, height, ...)``.

    Example: ``predict_then_refine("sketch.png", budget=40).params``.
    """
    cfg = RefineSettings(**settings)
    return Pipeline(estimator, cfg).run(
        sketch, height=height, progress=progress, cancel=cancel, species=species
    )
