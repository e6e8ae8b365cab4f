"""Derivative-free refinement: move a species' free values (and the view yaw) until the
tree's sketch matches the input sketch.

``refine(sketch, initial_params)`` evaluates the start point first (at 24 views
15 degrees apart, ``START_YAWS``, as many as a third of the budget allows; keeping the best
yaw), then, for a species whose trunk bends freely (palm, bonsai), the start with its bend
at a few values either way (``BEND_FRACTIONS``) from that view and, when the budget leaves
room (``MIRROR_RESERVE``), from the opposite one, then runs an nlopt local search (COBYLA
by default) from the best point seen, in the unit cube.  It stops on the evaluation budget,
the time limit or nlopt's tolerances, and returns the best point seen, so the search's
loss after is never above the loss before.  When the search started from the drawn outline
(``refine.start.choose_start``, whose values it holds), or its tree grows from a custom
shape and still misses the drawn outline, those values are then searched for the drawn
outlines alone, every view's (``refine.start.polish``, up to ``POLISH_EVALS`` more trees;
for a drawing of outlines first the tree's own random draws and a turn of the view,
``refine.start.reseed``, up to ``RESEED_TREES``; both together fewer under half the
default budget: :func:`outline_allowance`; then the polished tree's draws again, from
more of them with drawings from other sides, up to ``RESEED_VIEWS_TREES``), and that tree kept
when its outlines are nearer the drawn ones, as tall as the searched tree
(``refine.start.same_size``: a drawing shows no size): there the drawn outline wins over
the distance's other terms, and ``loss_after`` is that tree's.

Studies measured to give nothing and removed (their numbers stay in
``docs/history/results-2026-12-05.md``, "Options measured and removed"; the code last lived at commit
548efa3): a global CRS2 stage, neighbouring discrete values, a prior towards the start, a
depth and a depth-extent term, other tree seeds at the start, and scaling the refined tree
to the estimate's height.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from weberpenn import TreeParams, species
from weberpenn.params import SPECS

from .objective import METRICS, OtherView, PreparedDrawing, SearchSpace, SketchObjective
from .start import (
    FIT_BELOW,
    LINES_INSIDE,
    POLISH_AGAIN_EVALS,
    POLISH_BELOW,
    POLISH_EVALS,
    RESEED_SEEDS,
    RESEED_TREES,
    RESEED_VIEWS_SEEDS,
    RESEED_VIEWS_TREES,
    cheap_sketches,
    choose_start,
    fit_start,
    grown_height,
    polish,
    reseed,
    same_size,
)

__all__ = [
    "ALGORITHMS",
    "BEND_FRACTIONS",
    "DEFAULT_BUDGET",
    "DEFAULT_HOLD",
    "MAX_BUDGET",
    "MAX_TIME_LIMIT",
    "OUTLINE_FULL_BUDGET",
    "OUTLINE_TREES",
    "START_YAWS",
    "Cancelled",
    "RefineResult",
    "RefineSettings",
    "bend_starts",
    "guess_species",
    "outline_allowance",
    "outline_searched",
    "refine",
]

ALGORITHMS = {"bobyqa": "LN_BOBYQA", "sbplx": "LN_SBPLX", "cobyla": "LN_COBYLA"}
# the views the start is seen from, every 15 degrees: the axes first, then the diagonals,
# then the rest, so a start capped by a small budget still sees the whole circle coarsely.
# The estimate turned to the best of 24 views is nearer the drawn tree in 3D than turned
# to the best of 8 (docs/history/results-2026-12-05.md, "Where the mesh error comes from")
START_YAWS = (
    (0.0, 90.0, 180.0, 270.0, 45.0, 135.0, 225.0, 315.0)
    + (15.0, 105.0, 195.0, 285.0, 60.0, 150.0, 240.0, 330.0)
    + (30.0, 120.0, 210.0, 300.0, 75.0, 165.0, 255.0, 345.0)
)
# the trunk's bend (``weberpenn.species.TRUNK_BEND``): the network reads it worst from
# between the axes (benchmarks/probes/bend_gap.py: the estimate with the truth's bend set
# halves its error there), and a local search does not cross from one sign to the other
# (through a straight trunk, a worse fit), so after the start view is chosen the start is
# also tried with the bend at these fractions of its range either way
# (docs/history/results-2026-12-05.md, "The start tried with the trunk bent either way")
BEND_FRACTIONS = (-1.0, -0.5, 0.5, 1.0)
# the bends are also tried from the opposite view only when the local search keeps at
# least this many times their number of evaluations after them: with less, the local
# search gains more (a second species' half budget: RESULTS.md, "The trunk's bends tried
# from the opposite side too")
MIRROR_RESERVE = 2
# objective penalty for a view turned from the front: 0.015 at 90 degrees, 0.06 at 180
# (a view other than the front must fit clearly better; RESULTS.md, "Refinement")
YAW_WEIGHT = 0.06
# the local search's first step and its tolerance, in the unit cube
INITIAL_STEP = 0.12
XTOL = 1e-3
# held at the first estimate unless asked for: the tree's absolute size variation.  Every
# sketch is framed to its own tree, so a size change shows only as slightly thinner lines
# and smaller leaves; per unit of sketch distance it moves the mesh more than any other
# value in every species where it is free (benchmarks/probes/key_sensitivity.py,
# RESULTS.md), so the search would trade the estimator's size for pixel noise.
DEFAULT_HOLD = ("scaleV",)
MAX_BUDGET = 10_000
# the one default refinement budget (tree evaluations of the estimator's species): the
# settings, the CLI, the service, the page and the Blender add-on all take it from here.
# 40 is the budget the refinement's quality is measured at (bench_drawings --part refine)
DEFAULT_BUDGET = 40
# the outline step's trees (:func:`outline_allowance`) at a budget of OUTLINE_FULL_BUDGET
# or more: half the default, what a second species gets in a default run and about what
# the report's rotation sweep gives each angle; a share under it
# the draws, the polish, the draws again, the polish again
OUTLINE_TREES = RESEED_TREES + POLISH_EVALS + RESEED_TREES + POLISH_AGAIN_EVALS
OUTLINE_FULL_BUDGET = DEFAULT_BUDGET // 2
MAX_TIME_LIMIT = 3600.0
EMBEDDINGS = ("shipped", "none")  # RefineSettings.embedding's names (else a checkpoint path)

Progress = Callable[[int, float], None]
# told of each new best point: (its parameters, its yaw, its sketch distance, the distance
# its species is weighed by: ``RefineResult.evidence``)
OnBest = Callable[[TreeParams, float, float, float], None]


@dataclass(frozen=True)
class RefineResult:
    params: TreeParams
    yaw: float
    loss_before: float
    loss_after: float
    evaluations: int
    seconds: float
    trace: tuple[tuple[int, float, float], ...]  # (evaluation, loss, best loss so far)
    species: str = ""
    start_yaw: float = 0.0
    stopped_by: str = ""
    # the other views (``refine(views=...)``): their yaws relative to the first, as given
    # or as searched, and every view's sketch distance (the first's first) at the start
    # and at the result; ``loss_before``/``loss_after`` are the means
    view_yaws: tuple[float, ...] = ()
    view_losses_before: tuple[float, ...] = ()
    view_losses_after: tuple[float, ...] = ()
    # trees drawn after the search for a fitted start's outline (``refine.start.polish``;
    # not in ``evaluations``, which the budget bounds)
    outline_evaluations: int = 0
    # the search's best distance, before the outline step moved the tree (NaN: as
    # ``loss_after``)
    search_loss: float = math.nan

    @property
    def improvement(self) -> float:
        return self.loss_before - self.loss_after

    @property
    def evidence(self) -> float:
        """The distance that weighs one species against another: the search's best.  The
        outline step after it makes any species' tree follow the drawn outline, as far
        as its form grows one (a maple takes a palm's outline), so its tree's distance
        tells how far the outline was followed, not which species the drawing shows."""
        return self.loss_after if math.isnan(self.search_loss) else self.search_loss


class _Stop(Exception):
    """Raised inside the objective wrapper when the budget or time runs out."""


def guess_species(params: TreeParams) -> str:
    """The species whose fixed values ``params`` is closest to (range-normalised)."""
    src = params.to_dict()
    best, best_d = species.SPECIES[0], math.inf
    for name in species.SPECIES:
        proj = species.project(name, params).to_dict()
        d = 0.0
        for k, v in proj.items():
            if k == "seed":
                continue
            spec = SPECS[k]
            try:
                a = np.asarray(src[k], dtype=np.float64)
                b = np.asarray(v, dtype=np.float64)
            except (TypeError, ValueError):
                d += float(src[k] != v)
                continue
            width = float(spec.hi) - float(spec.lo)
            if not math.isfinite(width) or width <= 0:
                width = max(1.0, float(np.max(np.abs(b))))
            d += float(np.sum(np.abs(a - b))) / width
        if d < best_d:
            best, best_d = name, d
    return best


def _shown(value: Any) -> str:
    """A value for a message: its repr, cut short (a number may have 400 digits)."""
    text = repr(value)
    return text if len(text) <= 60 else f"{text[:40]}... ({len(text)} characters)"


def _finite(value: Any) -> bool:
    """A real number (not a bool) that is a finite float (an int of 309 digits is not:
    ``math.isfinite`` and ``float()`` raise OverflowError on it)."""
    if isinstance(value, bool) or not isinstance(value, int | float | np.integer | np.floating):
        return False
    try:
        return math.isfinite(float(value))
    except OverflowError:
        return False


def _int_in(name: str, value: Any, lo: int, hi: int, unit: str = "") -> None:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or not lo <= value <= hi:
        raise ValueError(f"{name} must be an integer in {lo}..{hi}{unit}, got {_shown(value)}")


@dataclass(frozen=True)
class RefineSettings:
    """Everything that steers a refinement, with the project's one set of defaults.

    ``refine`` False skips the search (the estimate is returned as it is); ``budget`` caps
    the tree evaluations (grow + mesh + sketch; the start views count) and ``time_limit``
    the seconds; ``algorithm`` is the nlopt local search (``ALGORITHMS``);
    ``search_yaw`` False keeps the estimator's view (or the front) instead of searching it
    (a searched view turned from the front pays :data:`YAW_WEIGHT`); ``keys`` restricts the
    searched values and ``hold`` (default :data:`DEFAULT_HOLD`; ``()`` for none) keeps some
    at their first estimate; values that do not change the tree at all are never searched
    (``SearchSpace.live``).

    ``size`` is the side in pixels the search renders and compares at; ``metric`` is the
    sketch distance: ``"shape"`` (style-blind, ``refine.shape``) or ``"ink"`` (line
    pixels, ``refine.objective.sketch_distance``); ``fast_sketch`` (default) draws the
    candidates the cheap way, the same sketch up to a few pixels (``SketchObjective``'s
    ``fast``: thin stems left out, numpy rasteriser), False with mitsuba on the full mesh.
    ``embedding`` (shape metric): the learned style-blind embedding added to the shape
    distance (``refine.embed``): ``"shipped"`` (``checkpoints/shape_embed.pt``), a
    checkpoint's path, or ``"none"`` for the hand-made shape distance alone.

    Species by synthesis (``treesketch.Pipeline``): up to ``species_tries`` species are
    refined, the estimator's best and any other whose score is at least ``species_ratio``
    times the best's (the others with half the budget; 60% of the time limit for the
    estimator's species and the rest shared by the others); the estimator's scores and the
    refined trees' distances decide together (``treesketch.species_choice``).
    ``species_tries`` 1 refines the estimator's species only.
    The outline step after the search grows its trees on top of the budget, all of
    them from half the default budget up and a share under it (:func:`outline_allowance`),
    so a small budget asks for a quick refinement as a whole.
    The refined tree keeps the size values the search does not move (the species'
    ``scale``, the estimator's ``scaleV``) and the proportions it fitted; a height given to
    ``Pipeline.run`` rescales it.
    """

    refine: bool = True
    budget: int = DEFAULT_BUDGET
    time_limit: float | None = 50.0
    # COBYLA: it builds its first model from n + 1 points where BOBYQA needs 2n + 1; with
    # 9-22 free values and about 27 evaluations left after the start views, BOBYQA spends
    # the whole default budget on its first model (RESULTS, "The local search at the
    # default budget")
    algorithm: str = "cobyla"
    size: int = 128
    search_yaw: bool = True
    keys: tuple[str, ...] | None = None
    hold: tuple[str, ...] = DEFAULT_HOLD
    species_tries: int = 2
    species_ratio: float = 0.5
    metric: str = "shape"
    fast_sketch: bool = True
    embedding: str = "shipped"

    def replace(self, **changes: Any) -> RefineSettings:
        return dataclasses.replace(self, **changes).validate()

    def validate(self) -> RefineSettings:
        """Check every option (before any work); returns self.  Raises ValueError naming
        the option and the value.  Every integer has bounds (a seed of 400 digits would
        overflow nlopt's ``srand`` once the model is loaded and the search starts) and a
        number of any size is refused plainly (``math.isfinite`` overflows on a huge int)."""
        _int_in("budget", self.budget, 1, MAX_BUDGET)
        t = self.time_limit
        if t is not None and not (_finite(t) and 0 < t <= MAX_TIME_LIMIT):
            raise ValueError(
                f"time_limit must be seconds in (0, {MAX_TIME_LIMIT:g}], got {_shown(t)}"
            )
        if str(self.algorithm).lower() not in ALGORITHMS:
            raise ValueError(
                f"unknown algorithm {_shown(self.algorithm)}; choose one of {', '.join(ALGORITHMS)}"
            )
        _int_in("size", self.size, 32, 512, " pixels")
        unknown = [k for k in self.hold if str(k).split("[")[0] not in SPECS]
        if unknown:
            raise ValueError(f"hold: not parameter names: {', '.join(map(str, unknown))}")
        _int_in("species_tries", self.species_tries, 1, 5)
        r = self.species_ratio
        if not (_finite(r) and 0 <= r <= 1):
            raise ValueError(f"species_ratio must be in [0, 1], got {_shown(r)}")
        if self.metric not in METRICS:
            raise ValueError(
                f"metric must be one of {', '.join(METRICS)}, got {_shown(self.metric)}"
            )
        if not isinstance(self.fast_sketch, bool):
            raise ValueError(f"fast_sketch must be True or False, got {self.fast_sketch!r}")
        e = self.embedding
        if not isinstance(e, str) or not (e in EMBEDDINGS or Path(e).is_file()):
            raise ValueError(
                f"embedding must be {' or '.join(map(repr, EMBEDDINGS))} or a checkpoint "
                f"file, got {e!r}"
            )
        return self

    def load_embedder(self) -> Any:
        """The ``refine.embed.ShapeEmbedder`` these settings ask for, or None (the ink
        metric, or ``embedding="none"``)."""
        if self.metric != "shape" or self.embedding == "none":
            return None
        from .embed import load_embedder

        return load_embedder(None if self.embedding == "shipped" else self.embedding)


def outline_allowance(budget: int) -> int:
    """The most trees the outline step after a search of ``budget`` trees grows: all
    :data:`OUTLINE_TREES` from :data:`OUTLINE_FULL_BUDGET` up, a share in proportion
    under it (30 at a budget of 6, 10 at 2; RESULTS.md, "The tree follows the drawing")."""
    return round(OUTLINE_TREES * min(1.0, budget / OUTLINE_FULL_BUDGET))


class Cancelled(Exception):
    """The caller's ``cancel()`` said stop; raised between two tree evaluations."""


def refine(
    sketch: Any,
    initial_params: TreeParams,
    settings: RefineSettings | None = None,
    *,
    species: str | None = None,  # noqa: A002 - the issue's name
    yaw: float | None = None,
    progress: Progress | None = None,
    cancel: Callable[[], bool] | None = None,
    embedder: Any = None,
    on_best: OnBest | None = None,
    views: Sequence[OtherView] = (),
) -> RefineResult:
    """Refine ``initial_params`` so its sketch matches ``sketch`` (see the module text and
    :class:`RefineSettings`).

    ``sketch``: an image, or a ``refine.objective.PreparedDrawing`` built for these
    settings' size and metric (a caller that refines one drawing several times, e.g. for
    several species, prepares it once; its embedder is then the one used).
    ``embedder``: the loaded ``refine.embed.ShapeEmbedder`` to use (a caller that refines
    many sketches loads it once, ``settings.load_embedder()``); by default the settings'
    own is loaded.

    ``yaw`` fixes the view (degrees) instead of searching it; ``progress(evaluations,
    best_loss)`` is called after each new evaluation; ``cancel()`` is asked before each
    one and raises :class:`Cancelled` when it returns True; ``on_best(params, yaw,
    sketch_distance, weight)`` is called whenever an evaluation is the best so far, and for
    the outline step's tree (what a caller shows while the search runs; ``weight`` the
    distance the species is weighed by, ``RefineResult.evidence``: the search's).  ``loss_before`` /
    ``loss_after`` are the sketch distance; the start point is always evaluated, whatever
    the time limit, so both are finite.

    ``views``: other drawings of the same tree (``refine.objective.OtherView``, prepared
    like ``sketch``), each at its yaw relative to the first; the distance minimised is the
    mean over all views.  A view whose yaw is None gets the turn (every 15 degrees) at
    which the start tree fits it best, before the search starts.
    """
    t0 = time.perf_counter()
    cfg = (settings or RefineSettings()).validate()
    budget = int(cfg.budget)
    if not isinstance(initial_params, TreeParams):
        initial_params = TreeParams(initial_params)
    from weberpenn import species as _species

    name = _species.canonical(species) if species else guess_species(initial_params)
    drawing = _checked_drawing(sketch, cfg, embedder, views)
    deadline = None if cfg.time_limit is None else t0 + float(cfg.time_limit)
    if yaw is None and not cfg.search_yaw:
        yaw = 0.0

    keep: tuple[str, ...] = ()
    # the drawn outline, when it fits better than the estimate's; not for a species whose
    # trunk bends freely (palm, bonsai): there the bends tried at the start find the
    # drawn trunk, and a start fitted to a bent trunk's outline leads them astray
    # (tests/test_refine_search.py, the trunk bent the other way)
    bending = _species.TRUNK_BEND[0][0] in _bending_keys(name)
    if not bending:
        initial_params, keep = choose_start(drawing, initial_params, name, yaw or 0.0)
    space = SearchSpace.create(
        name, initial_params, cfg.keys, search_yaw=yaw is None, yaw=yaw or 0.0, keep=keep
    )
    space = space.without([str(k) for k in cfg.hold])
    # liveness is judged at the start's values: a value that does not change this tree
    # costs the local search evaluations of its first model and drifts without a signal
    space = space.live()
    obj = SketchObjective(
        drawing.target,
        space,
        metric=cfg.metric,
        yaw_prior=0.0,
        yaw_weight=YAW_WEIGHT,
        fast=cfg.fast_sketch,
        embedder=drawing.embedder,
    )
    if views:
        turns = _view_turns(obj, space.from_params(initial_params, yaw or 0.0), views)
        obj.others = tuple((v.drawing.target, t) for v, t in zip(views, turns, strict=True))
    run = _Run(obj, budget, deadline, cancel, progress, on_best)
    start = _Start(space.from_params(initial_params, yaw or 0.0), float(yaw or 0.0))
    try:
        _find_start(run, space, start, yaw)  # 1. the start point, at several views
        _local_search(run, space, str(cfg.algorithm).lower(), start.x)  # 2. from the best
    except _Stop:
        pass
    if cancel is not None and run.stopped.startswith("nlopt") and cancel():
        raise Cancelled("refinement cancelled")  # nlopt swallowed the exception
    result = _result(run, space, start, views, name, t0)
    # 3. the drawn values searched for the drawn outlines from the best (every view's):
    # a fitted start's, which the search held; or any other tree whose outlines still
    # miss the drawn ones (under POLISH_BELOW; under FIT_BELOW where the trunk bends
    # freely: there the bends the search found set the outline, and the step cost the
    # held-out-style bonsai mesh error).  Its trees come on top of the budget (a share of
    # it cost the search what the outline gained: RESULTS.md, "The tree follows the
    # drawing")
    trees = outline_allowance(budget)
    if trees and keep:
        result = outline_searched(result, drawing, views, run, t0, trees)
    elif trees:
        below = FIT_BELOW if bending else POLISH_BELOW
        result = outline_searched(result, drawing, views, run, t0, trees, below=below)
    return result


def outline_searched(
    result: RefineResult,
    drawing: PreparedDrawing,
    views: Sequence[OtherView],
    run: _Run,
    t0: float,
    trees: int,
    below: float | None = None,
) -> RefineResult:
    """``result`` with its drawn values searched for the drawn outlines, every view's
    (``refine.start.polish``, up to ``POLISH_EVALS`` trees, after ``refine.start.reseed``
    for a drawing of outlines, up to ``RESEED_TREES``; told in ``outline_evaluations``),
    kept when its outlines are nearer the drawn ones (its
    ``loss_after`` then the search's distance of that tree, the mean over the views, which
    may be above the search's best).  ``below``: only when the tree's outlines overlap the
    drawn ones less than this (one tree to see).  ``trees``: the most trees grown here
    (:func:`outline_allowance`); under the full step's the reseed tries fewer
    other draws and the polish stops where they run out.  For a drawing of outlines the
    polished tree's draws are then chosen again (``RESEED_SEEDS`` other draws; with other
    ``views``, ``RESEED_VIEWS_SEEDS``, up to ``RESEED_VIEWS_TREES`` less ``RESEED_TREES``
    more trees than ``trees``, the same share of them) and its drawn values polished
    once more (up to ``POLISH_AGAIN_EVALS`` trees)."""
    used = 0

    def upto(limit: int) -> Callable[[], bool]:
        """Whether another tree may be grown: under ``limit`` in all, the caller's time
        and cancel allowing."""

        def going() -> bool:
            nonlocal used
            if used >= limit:
                return False
            if run.cancel is not None and run.cancel():
                return False
            if run.deadline is not None and time.perf_counter() >= run.deadline:
                return False
            used += 1
            return True

        return going

    share = min(1.0, trees / OUTLINE_TREES)
    going = upto(round((RESEED_TREES + POLISH_EVALS) * share))  # the draws, then the polish
    drawings = [drawing, *(v.drawing for v in views)]
    turns = [0.0, *result.view_yaws]
    inside = float(np.mean([d.shape.inside_ink for d in drawings]))
    wants = [(d.shape.envelope, result.yaw + t) for d, t in zip(drawings, turns, strict=True)]
    seeded = None
    if inside < LINES_INSIDE:
        # a drawing of outlines: the outline is all it shows, so the tree's own draws are
        # chosen for it too (``refine.start.reseed``)
        seeds = round(RESEED_SEEDS * share)
        seeded = reseed(result.params, wants, result.species, drawing.size, going, below, seeds)
    if seeded is not None:
        result = dataclasses.replace(result, params=seeded[0], yaw=(result.yaw + seeded[1]) % 360.0)
        wants = [(w, yaw + seeded[1]) for w, yaw in wants]
    tree, sketches = polish(
        result.params,
        wants,
        result.species,
        drawing.size,
        going=going,
        below=below,
        # a tree grown from one of the species' shapes: searched from the custom shape
        # fitted to the first drawing
        refit=lambda p: fit_start(
            drawing.target.image, p, result.species, drawing.size, result.yaw
        ),
    )
    if run.cancel is not None and run.cancel():
        raise Cancelled("refinement cancelled")
    # the drawn outline wins over the search's other terms (its lines, the learned
    # embedding): kept by the outline alone (kept only where the search's distance fell
    # too, people's outlines 0.723 against 0.740: RESULTS.md, "The tree follows the
    # drawing")
    if sketches is None and seeded is not None:
        tree, sketches = result.params, seeded[2]
    if sketches is None:
        return dataclasses.replace(
            result, outline_evaluations=used, seconds=time.perf_counter() - t0
        )
    height = grown_height(result.params)

    def sized(tree: TreeParams, sketches: list[np.ndarray]) -> tuple[TreeParams, list]:
        """As tall as the searched tree: the step moves proportions, not the tree's size."""
        q = same_size(tree, height)
        if q is tree:
            return tree, sketches
        return q, cheap_sketches(q, result.species, drawing.size, [yaw for _, yaw in wants])

    tree, sketches = sized(tree, sketches)
    if inside < LINES_INSIDE:
        # the polish moved the outline away from what the draws chosen before it bought:
        # they are chosen again for the polished tree; drawn from other sides too, from
        # more of them, as where the branches leave the trunk sets how the outlines differ
        # from side to side, which the polish cannot move
        extra = round((RESEED_VIEWS_TREES - RESEED_TREES) * share) if views else 0
        going = upto(trees + extra)  # the draws again, then the polish again
        again = reseed(
            tree,
            wants,
            result.species,
            drawing.size,
            going,
            None,
            round((RESEED_VIEWS_SEEDS if views else RESEED_SEEDS) * share),
        )
        if again is not None:
            tree, sketches = again[0], again[2]
            result = dataclasses.replace(result, yaw=(result.yaw + again[1]) % 360.0)
            wants = [(w, yaw + again[1]) for w, yaw in wants]
        # the new draws moved the outline the polish fitted, or the polish stopped short
        # of its best: fitted once more, from a fresh start of its search
        polished, seen = polish(
            tree,
            wants,
            result.species,
            drawing.size,
            evals=round(POLISH_AGAIN_EVALS * share),
            going=going,
        )
        if seen is not None:
            tree, sketches = sized(polished, seen)
    # the step's sketches were drawn for their envelopes (``outline=True``); the search's
    # distance reads the whole sketch, so the kept tree is drawn as the search draws it
    sketches = cheap_sketches(tree, result.species, drawing.size, [yaw for _, yaw in wants])
    targets = [d.target for d in drawings]
    losses = tuple(run.obj.loss_of_sketch(s, t) for s, t in zip(sketches, targets, strict=True))
    loss = float(np.mean(losses))
    if inside >= LINES_INSIDE and loss > result.loss_after:
        # the drawing shows its inside (branches, leaves within the crown): those lines
        # are drawn as much as the outline, and the search's distance weighs them; an
        # outline bought with them fitted the renderer's drawings' outlines past their
        # own trees' (RESULTS.md, "The tree follows the drawing")
        return dataclasses.replace(
            result, outline_evaluations=used, seconds=time.perf_counter() - t0
        )
    if run.on_best is not None:
        run.on_best(tree, result.yaw, loss, result.loss_after)
    return dataclasses.replace(
        result,
        params=tree,
        loss_after=loss,
        search_loss=result.loss_after,
        view_losses_after=losses if len(losses) > 1 else result.view_losses_after,
        outline_evaluations=used,
        seconds=time.perf_counter() - t0,
    )


def _checked_drawing(
    sketch: Any, cfg: RefineSettings, embedder: Any, views: Sequence[OtherView]
) -> PreparedDrawing:
    """The drawing as the search compares with it (prepared here unless the caller did,
    for these settings), and every other view checked against it."""
    if isinstance(sketch, PreparedDrawing):  # prepared once by the caller (the pipeline)
        drawing = sketch.check(cfg.size, cfg.metric)
        if embedder is not None and embedder is not drawing.embedder:
            raise ValueError("the drawing was prepared with another embedder")
    else:
        if embedder is None:
            embedder = cfg.load_embedder()
        drawing = PreparedDrawing.create(sketch, cfg.size, cfg.metric, embedder)
    for v in views:
        v.drawing.check(cfg.size, cfg.metric)
        if v.drawing.embedder is not drawing.embedder:
            raise ValueError("every view must be prepared with the same embedder")
        if v.yaw is not None and not _finite(v.yaw):
            raise ValueError(f"a view's yaw must be a finite number of degrees, got {v.yaw!r}")
    return drawing


class _Run:
    """One search's evaluations within its budget and time: each new tree asks
    ``cancel`` first, and tells ``on_best`` (a better tree) and ``progress`` after;
    ``stopped`` says what ended the search."""

    def __init__(
        self,
        obj: SketchObjective,
        budget: int,
        deadline: float | None,
        cancel: Callable[[], bool] | None,
        progress: Progress | None,
        on_best: OnBest | None,
    ) -> None:
        self.obj, self.budget, self.deadline = obj, budget, deadline
        self.cancel, self.progress, self.on_best = cancel, progress, on_best
        self.stopped = "tolerance"

    def out_of_budget(self) -> str | None:
        if self.obj.evaluations >= self.budget:
            return "budget"
        if self.deadline is not None and time.perf_counter() >= self.deadline:
            return "time"
        return None

    def evaluate(self, x: Sequence[float]) -> float:
        obj = self.obj
        hit = obj.cached(x)
        if hit is not None:  # free: no new tree
            return hit
        if self.cancel is not None and self.cancel():
            raise Cancelled("refinement cancelled")
        why = self.out_of_budget() if obj.evaluations > 0 else None  # the start is always seen
        if why is not None:
            self.stopped = why
            raise _Stop(why)
        n_before, best_before = obj.evaluations, obj.best_loss
        loss = obj(x)
        if self.on_best is not None and obj.best_loss < best_before and obj.best_params is not None:
            d = obj.best_sketch_loss
            self.on_best(obj.best_params, obj.best_yaw, d, d)
        if self.progress is not None and obj.evaluations != n_before:
            self.progress(obj.evaluations, obj.best_loss)
        return loss


@dataclass
class _Start:
    """The search's start point (search coordinates), seen from ``yaw``, and its sketch
    distance (inf until evaluated); filled in as the start is found."""

    x: np.ndarray
    yaw: float
    loss: float = math.inf


def _find_start(run: _Run, space: SearchSpace, start: _Start, yaw: float | None) -> None:
    """The start tree at several views (the given one alone when ``yaw`` is), the best
    kept in ``start``; then the trunk's bends tried from there (and from the opposite
    side when the budget keeps enough after them)."""
    obj, budget = run.obj, run.budget
    start_total = math.inf
    yaws = START_YAWS if yaw is None else (float(yaw),)
    start_cap = max(1, budget // 3)

    def at_view(y: float) -> np.ndarray:
        x = start.x.copy()
        if space.search_yaw:
            x[-1] = (y % 360.0) / 360.0
        return x

    for i, y in enumerate(yaws):
        if i > 0 and (obj.evaluations >= start_cap or run.out_of_budget()):
            break
        x = at_view(y)
        loss = run.evaluate(x)  # sketch distance + the view's penalty
        if loss < start_total:
            start_total, start.yaw = loss, y
            start.loss = obj.sketch_loss(x)  # the sketch distance alone
    start.x = at_view(start.yaw)
    bent = bend_starts(space, start.x)
    if bent and space.search_yaw:
        # the start view was chosen with the estimate's bend, whose sign the network
        # often reads wrongly; a trunk bent the other way fits best from the opposite
        # side, so the bends are tried there too, when the local search keeps enough
        # of the budget after them (a small budget does better spent on it)
        mirrored = bend_starts(space, at_view(start.yaw + 180.0))
        left = budget - obj.evaluations - len(bent) - len(mirrored)
        if left >= MIRROR_RESERVE * len(mirrored):
            bent += mirrored
    for x in bent:  # the best point seen is the local search's start
        if run.out_of_budget():
            break
        run.evaluate(x)


def _local_search(run: _Run, space: SearchSpace, alg_name: str, x0: np.ndarray) -> None:
    """nlopt's local search from the best point seen (``x0`` when none), within what is
    left of the budget and the time."""
    import nlopt

    obj = run.obj
    local = getattr(nlopt, ALGORITHMS[alg_name])
    if local == nlopt.LN_BOBYQA and space.n < 2:
        local = nlopt.LN_COBYLA
    if space.n == 0:  # nothing to search: the start point is the answer
        return
    if run.out_of_budget() is not None:
        run.stopped = run.out_of_budget() or run.stopped
        return
    nlopt.srand(0)  # the local algorithms draw nothing at random; kept reproducible
    opt = nlopt.opt(local, space.n)
    opt.set_lower_bounds(np.zeros(space.n))
    opt.set_upper_bounds(np.ones(space.n))
    opt.set_min_objective(lambda x, grad: run.evaluate(x))
    opt.set_maxeval(int(run.budget - obj.evaluations + obj.cache_size + 5))
    if run.deadline is not None:
        opt.set_maxtime(max(1e-3, run.deadline - time.perf_counter()))
    opt.set_initial_step(np.full(space.n, INITIAL_STEP))
    opt.set_xtol_abs(np.full(space.n, XTOL))
    opt.set_ftol_abs(1e-6)
    start = obj.best_x if obj.best_x is not None else x0
    try:
        opt.optimize(np.clip(np.asarray(start, dtype=np.float64), 0.0, 1.0))
        run.stopped = _nlopt_reason(opt.last_optimize_result())
    except Cancelled:
        raise
    except _Stop:
        pass
    except (nlopt.ForcedStop, nlopt.RoundoffLimited):
        run.stopped = "nlopt stopped"
    except RuntimeError as exc:  # nlopt's generic failure: keep the best seen
        run.stopped = f"nlopt: {exc}"
    except ValueError as exc:
        if "_Stop" not in repr(exc) and not isinstance(exc.__cause__, _Stop):
            run.stopped = f"nlopt: {exc}"


def _result(
    run: _Run,
    space: SearchSpace,
    start: _Start,
    views: Sequence[OtherView],
    name: str,
    t0: float,
) -> RefineResult:
    """The best tree seen (the start's when the view penalty made the best a worse
    sketch match, or nothing fitted the budget) and its distances."""
    obj, x0 = run.obj, start.x
    loss_before, start_yaw = start.loss, start.yaw
    if obj.best_params is None:  # not even the start point fitted the budget/time
        loss_after = loss_before
        best_params, best_yaw = space.to_params(x0), start_yaw
    else:
        loss_after = obj.best_sketch_loss  # <= best objective <= objective at the start
        best_params, best_yaw = obj.best_params, obj.best_yaw
    best_key = x0 if obj.best_x is None else obj.best_x
    if loss_after > loss_before:  # the view penalty traded sketch match for the front view
        loss_after, best_params, best_yaw = loss_before, space.to_params(x0), start_yaw
        best_key = x0
    view_before = view_after = ()
    if views:
        view_before = tuple(obj.view_losses(x0))
        view_after = tuple(obj.view_losses(best_key))
    return RefineResult(
        params=best_params,
        yaw=float(best_yaw),
        loss_before=float(loss_before),
        loss_after=float(loss_after),
        evaluations=int(obj.evaluations),
        seconds=time.perf_counter() - t0,
        trace=tuple(obj.trace),
        species=name,
        start_yaw=float(start_yaw),
        stopped_by=run.stopped,
        view_yaws=tuple(float(t) for _, t in obj.others),
        view_losses_before=view_before,
        view_losses_after=view_after,
    )


def _bending_keys(name: str) -> set[str]:
    """The keys of the species' free values that bend the trunk (``species.TRUNK_BEND``)."""
    rows = list(species.unfixed(name)) + list(species.search_freedoms(name))
    return {u.key for u in rows if (u.key, u.index) in species.TRUNK_BEND and u.free}


def bend_starts(space: SearchSpace, x: np.ndarray) -> list[np.ndarray]:
    """``x`` with the trunk's bend at each of :data:`BEND_FRACTIONS` of its range and the
    bend back mirrored, when the space searches the bend (else none)."""
    where = {(u.key, u.index): i for i, u in enumerate(space.dims)}
    bend = where.get(species.TRUNK_BEND[0])
    if bend is None:
        return []
    back = where.get(species.TRUNK_BEND[1])
    u = space.dims[bend]
    out = []
    for f in BEND_FRACTIONS:
        v = f * max(abs(u.lo), abs(u.hi))
        y = x.copy()
        y[bend] = np.clip((v - u.lo) / (u.hi - u.lo), 0.0, 1.0)
        if back is not None:
            b = space.dims[back]
            y[back] = np.clip((-v - b.lo) / (b.hi - b.lo), 0.0, 1.0)
        out.append(y)
    return out


def _view_turns(obj: SketchObjective, x: np.ndarray, views: Sequence[OtherView]) -> list[float]:
    """Each view's yaw relative to the first: as given, or (None) the turn of the start
    tree, every 15 degrees, whose sketch is nearest that drawing (one tree grown, only
    re-drawn; no evaluation of the budget)."""
    turns = []
    for v in views:
        if v.yaw is not None:
            turns.append(float(v.yaw) % 360.0)
            continue
        losses = [obj.loss_of_sketch(obj.sketch_at(x, t), v.drawing.target) for t in START_YAWS]
        turns.append(START_YAWS[int(np.argmin(losses))])
    return turns


def _nlopt_reason(code: int) -> str:
    return {
        1: "converged",
        2: "stopval",
        3: "ftol",
        4: "xtol",
        5: "budget",
        6: "time",
    }.get(int(code), f"nlopt code {code}")
