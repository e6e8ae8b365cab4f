"""Derivative-free refinement: move a species' free values (and the view yaw) until the
tree's sketch matches the input sketch.

``refine(sketch, initial_params)`` evaluates the start point first (at 24 views
15 degrees apart, ``START_YAWS``, as many as a third of the budget allows; keeping the best
yaw), optionally the same values grown from a
few other tree seeds at the best two views (``RefineSettings.tree_seeds``: the seed draws
a tree's random details, which way a trunk leans, where the big branches sit, which no
continuous value reaches), optionally tries neighbouring values of
the discrete keys that matter most (``baseSplits``, ``nrings``), optionally runs a short
global stage (CRS2), then an nlopt local search (BOBYQA by default) in the unit cube.  It
stops on the evaluation budget, the time limit or nlopt's tolerances, and always returns
the best point seen, so the loss after is never above the loss before.
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

from weberpenn import TreeParams, grow, species
from weberpenn.params import SPECS

from .objective import (
    DISCRETE_NEIGHBOUR_KEYS,
    METRICS,
    SearchSpace,
    SketchObjective,
    framed,
    make_target,
    tree_points,
)

__all__ = [
    "ALGORITHMS",
    "DEFAULT_BUDGET",
    "DEFAULT_HOLD",
    "MAX_BUDGET",
    "MAX_TIME_LIMIT",
    "START_YAWS",
    "Cancelled",
    "RefineResult",
    "RefineSettings",
    "guess_species",
    "refine",
]

ALGORITHMS = {"bobyqa": "LN_BOBYQA", "sbplx": "LN_SBPLX", "cobyla": "LN_COBYLA"}
# the views the start is seen from, every 15 degrees: the axes first, then the diagonals,
# then the rest, so a start capped by a small budget still sees the whole circle coarsely.
# The estimate turned to the best of 24 views is nearer the drawn tree in 3D than turned
# to the best of 8 (benchmarks/RESULTS.md, "Where the mesh error comes from")
START_YAWS = (
    (0.0, 90.0, 180.0, 270.0, 45.0, 135.0, 225.0, 315.0)
    + (15.0, 105.0, 195.0, 285.0, 60.0, 150.0, 240.0, 330.0)
    + (30.0, 120.0, 210.0, 300.0, 75.0, 165.0, 255.0, 345.0)
)
# objective penalty for a view turned from the front: 0.015 at 90 degrees, 0.06 at 180
YAW_WEIGHT = 0.06
# objective penalty per (depth offset of the tree's mass / its height)^2 at the searched
# view (``SketchObjective.depth``): a lean the drawing cannot show stays out of the depth
DEPTH_WEIGHT = 0.0
# objective penalty per squared change of the tree's depth extent (its nearest and
# farthest reach along the line of sight, fractions of its height) from the first
# estimate's at the same view (``SketchObjective.extent_change``)
EXTENT_WEIGHT = 0.0
# held at the first estimate unless asked for: the tree's absolute size variation.  Every
# sketch is framed to its own tree, so a size change shows only as slightly thinner lines
# and smaller leaves; per unit of sketch distance it moves the mesh more than any other
# value in every species where it is free (benchmarks/key_sensitivity.py, RESULTS.md), so
# the search would trade the estimator's size for pixel noise.
DEFAULT_HOLD = ("scaleV",)
MAX_BUDGET = 10_000
# the one default refinement budget (tree evaluations of the estimator's species): the
# settings, the CLI, the service, the page and the Blender add-on all take it from here.
# 40 is the budget the refinement's quality is measured at (bench_drawings --part refine)
DEFAULT_BUDGET = 40
MAX_TREE_SEEDS = 16
MAX_TIME_LIMIT = 3600.0
EMBEDDINGS = ("shipped", "none")  # RefineSettings.embedding's names (else a checkpoint path)

Progress = Callable[[int, float], None]
# told of each new best point: (its parameters, its yaw, its sketch distance)
OnBest = Callable[[TreeParams, float, float], None]


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

    @property
    def improvement(self) -> float:
        return self.loss_before - self.loss_after


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


def _discrete_candidates(name: str, params: TreeParams) -> list[TreeParams]:
    out = []
    for u in species.unfixed(name):
        if u.key not in DISCRETE_NEIGHBOUR_KEYS or u.rule != "randint":
            continue
        v = int(params[u.key])
        for w in (v - 1, v + 1):
            if u.lo <= w <= u.hi:
                out.append(params.replace(**{u.key: w}))
    return out


@dataclass(frozen=True)
class RefineSettings:
    """Everything that steers a refinement, with the project's one set of defaults.

    ``refine`` False skips the search (the estimate is returned as it is); ``budget`` caps
    the tree evaluations (grow + mesh + sketch; the start views count) and ``time_limit``
    the seconds; ``search_yaw`` False keeps the estimator's view (or the front) instead of
    searching it; ``keys`` restricts the searched values and ``hold`` (default
    :data:`DEFAULT_HOLD`; ``()`` for none) keeps some at their first estimate;
    ``live_only`` drops the values that do not change this tree at all
    (``SearchSpace.live``); ``global_evals`` > 0 runs GN_CRS2_LM first; ``prior_weight`` > 0
    adds ``prior_weight * |x - x_start|^2`` (unit cube, yaw excluded) to what is minimised;
    ``yaw_weight`` (when the yaw is searched) adds ``yaw_weight * (turn from the front
    view / 180)^2``, so the front view is kept unless another fits clearly better;
    ``depth_weight`` (when the yaw is searched) adds ``depth_weight * (depth / height)^2``
    for the depth at which the tree's mass lies off its trunk base along the line of
    sight (``SketchObjective.depth``): of the views that match alike, the one that shows
    a lean across the picture, not towards the viewer;
    ``extent_weight`` adds ``extent_weight`` times the squared change of the tree's depth
    extent (its nearest and farthest reach along the line of sight, fractions of its
    height) from the first estimate's seen at the same view
    (``SketchObjective.extent_change``): the values the search moves to fit the outline
    must not, unpaid, move branches in the depth that no drawing shows;
    ``size`` is the side in pixels the search renders and compares at; ``metric`` is the
    sketch distance: ``"shape"`` (style-blind, ``refine.shape``) or ``"ink"`` (line
    pixels, ``refine.objective.sketch_distance``); ``fast_sketch`` (default) draws the
    candidates the cheap way, the same sketch up to a few pixels (``SketchObjective``'s
    ``fast``: thin stems left out, numpy rasteriser), False with mitsuba on the full mesh.
    ``embedding`` (shape metric): the learned style-blind embedding added to the shape
    distance (``refine.embed``): ``"shipped"`` (``checkpoints/shape_embed.pt``), a
    checkpoint's path, or ``"none"`` for the hand-made shape distance alone.
    ``tree_seeds``: how many tree seeds the start tries (the start's own, then the next
    ones), each at the two best views of the first; 1 (the default) keeps the start's
    seed.  Skipped when they would take the start past half the budget, or when every
    value is held.  It finds the seed of a drawing made from a generated tree, but on 100
    held-out-style drawings it did not lower the mesh error against the truth
    (``benchmarks/RESULTS.md``, "Tree seeds at the start"), so it is off by default.
    ``keep_height`` (``treesketch.Pipeline``, when no height is given; off by default): the
    refined tree is scaled to the height of the estimator's tree of its species.  Off, it
    keeps the size values the search does not move (the species' ``scale``, the
    estimator's ``scaleV``: :data:`DEFAULT_HOLD`) and the proportions it fitted, so its
    height follows the proportions: a taller trunk found in the drawing makes a taller
    tree, where the rule would shrink every branch to the estimate's height.  On the
    held-out-style drawings and the 15 published trees the rule raised the mean mesh
    error (``benchmarks/RESULTS.md``, "The search's own size").

    Species by synthesis (``treesketch.Pipeline``): up to ``species_tries`` species are
    refined, the estimator's best and any other whose score is at least ``species_ratio``
    times the best's (the others with half the budget; 60% of the time limit for the
    estimator's species and the rest shared by the others); the tree
    whose sketch matches best wins, but another species replaces the estimator's only when
    its distance is lower by more than ``species_margin`` (a fraction of the estimator's
    species' distance): the network names the species far more reliably than a sketch
    distance between two close species does.  ``species_tries`` 1 refines the estimator's
    species only.
    """

    refine: bool = True
    budget: int = DEFAULT_BUDGET
    time_limit: float | None = 50.0
    algorithm: str = "bobyqa"
    seed: int = 0
    size: int = 128
    search_yaw: bool = True
    keys: tuple[str, ...] | None = None
    hold: tuple[str, ...] = DEFAULT_HOLD
    live_only: bool = True
    global_evals: int = 0
    discrete_neighbours: bool = False
    initial_step: float = 0.12
    xtol: float = 1e-3
    prior_weight: float = 0.0
    yaw_weight: float = YAW_WEIGHT
    depth_weight: float = DEPTH_WEIGHT
    extent_weight: float = EXTENT_WEIGHT
    species_tries: int = 2
    species_ratio: float = 0.5
    species_margin: float = 0.2
    metric: str = "shape"
    fast_sketch: bool = True
    keep_height: bool = False
    embedding: str = "shipped"
    tree_seeds: int = 1

    def replace(self, **changes: Any) -> RefineSettings:
        return dataclasses.replace(self, **changes).validate()

    def validate(self) -> RefineSettings:
        """Check every option (before any work); returns self.  Raises ValueError naming
        the option and the value."""
        b = self.budget
        if isinstance(b, bool) or not isinstance(b, int | np.integer) or not 1 <= b <= MAX_BUDGET:
            raise ValueError(f"budget must be an integer in 1..{MAX_BUDGET}, got {b!r}")
        t = self.time_limit
        if t is not None and not (
            isinstance(t, int | float) and math.isfinite(t) and 0 < t <= MAX_TIME_LIMIT
        ):
            raise ValueError(f"time_limit must be seconds in (0, {MAX_TIME_LIMIT:g}], got {t!r}")
        if str(self.algorithm).lower() not in ALGORITHMS:
            raise ValueError(
                f"unknown algorithm {self.algorithm!r}; choose one of {', '.join(ALGORITHMS)}"
            )
        if (
            isinstance(self.size, bool)
            or not isinstance(self.size, int)
            or not 32 <= self.size <= 512
        ):
            raise ValueError(f"size must be an integer in 32..512 pixels, got {self.size!r}")
        if not isinstance(self.seed, int) or isinstance(self.seed, bool):
            raise ValueError(f"seed must be an integer, got {self.seed!r}")
        unknown = [k for k in self.hold if str(k).split("[")[0] not in SPECS]
        if unknown:
            raise ValueError(f"hold: not parameter names: {', '.join(map(str, unknown))}")
        for label in (
            "prior_weight",
            "yaw_weight",
            "depth_weight",
            "extent_weight",
            "initial_step",
            "xtol",
        ):
            w = getattr(self, label)
            if not (isinstance(w, int | float) and math.isfinite(w) and w >= 0):
                raise ValueError(f"{label} must be a number >= 0, got {w!r}")
        if not isinstance(self.species_tries, int) or not 1 <= self.species_tries <= 5:
            raise ValueError(
                f"species_tries must be an integer in 1..5, got {self.species_tries!r}"
            )
        if not (isinstance(self.species_ratio, int | float) and 0 <= self.species_ratio <= 1):
            raise ValueError(f"species_ratio must be in [0, 1], got {self.species_ratio!r}")
        m = self.species_margin
        if isinstance(m, bool) or not (isinstance(m, int | float) and 0 <= m < 1):
            raise ValueError(f"species_margin must be in [0, 1), got {m!r}")
        if self.metric not in METRICS:
            raise ValueError(f"metric must be one of {', '.join(METRICS)}, got {self.metric!r}")
        for flag in ("fast_sketch", "keep_height"):
            if not isinstance(getattr(self, flag), bool):
                raise ValueError(f"{flag} must be True or False, got {getattr(self, flag)!r}")
        n = self.tree_seeds
        if isinstance(n, bool) or not isinstance(n, int) or not 1 <= n <= MAX_TREE_SEEDS:
            raise ValueError(f"tree_seeds must be an integer in 1..{MAX_TREE_SEEDS}, got {n!r}")
        if not isinstance(self.global_evals, int) or self.global_evals < 0:
            raise ValueError(f"global_evals must be an integer >= 0, got {self.global_evals!r}")
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
) -> RefineResult:
    """Refine ``initial_params`` so its sketch matches ``sketch`` (see the module text and
    :class:`RefineSettings`).

    ``embedder``: the loaded ``refine.embed.ShapeEmbedder`` to use (a caller that refines
    many sketches loads it once, ``settings.load_embedder()``); by default the settings'
    own is loaded.

    ``yaw`` fixes the view (degrees) instead of searching it; ``progress(evaluations,
    best_loss)`` is called after each new evaluation; ``cancel()`` is asked before each
    one and raises :class:`Cancelled` when it returns True; ``on_best(params, yaw,
    sketch_distance)`` is called whenever an evaluation is the best so far (what a caller
    shows while the search runs).  ``loss_before`` /
    ``loss_after`` are the sketch distance; the start point is always evaluated, whatever
    the time limit, so both are finite.
    """
    import nlopt

    t0 = time.perf_counter()
    cfg = (settings or RefineSettings()).validate()
    budget = int(cfg.budget)
    alg_name = str(cfg.algorithm).lower()
    if not isinstance(initial_params, TreeParams):
        initial_params = TreeParams(initial_params)
    from weberpenn import species as _species

    name = _species.canonical(species) if species else guess_species(initial_params)
    if embedder is None:
        embedder = cfg.load_embedder()
    elif cfg.metric != "shape":
        raise ValueError("a learned embedder works with the shape metric only")
    target = make_target(framed(sketch, cfg.size), cfg.size, cfg.metric, embedder)
    deadline = None if cfg.time_limit is None else t0 + float(cfg.time_limit)
    if yaw is None and not cfg.search_yaw:
        yaw = 0.0

    space = SearchSpace.create(
        name, initial_params, cfg.keys, search_yaw=yaw is None, yaw=yaw or 0.0
    )
    space = space.without([str(k) for k in cfg.hold])
    # liveness is judged at the start's discrete values: their neighbours (baseSplits,
    # nrings) change no value's liveness (checked on a sampled tree of each species)
    if cfg.live_only:
        space = space.live()
    obj = SketchObjective(
        target,
        space,
        metric=cfg.metric,
        prior=space.from_params(initial_params, 0.0),
        prior_weight=float(cfg.prior_weight),
        yaw_prior=0.0,
        yaw_weight=float(cfg.yaw_weight),
        depth_weight=float(cfg.depth_weight) if space.search_yaw else 0.0,
        extent_weight=float(cfg.extent_weight),
        extent_reference=(
            tree_points(grow(space.to_params(space.from_params(initial_params))))
            if cfg.extent_weight > 0
            else None
        ),
        fast=cfg.fast_sketch,
        embedder=embedder,
    )
    stopped = ["tolerance"]

    def out_of_budget() -> str | None:
        if obj.evaluations >= budget:
            return "budget"
        if deadline is not None and time.perf_counter() >= deadline:
            return "time"
        return None

    def evaluate(x: Sequence[float]) -> float:
        hit = obj.cached(x)
        if hit is not None:  # free: no new tree
            return hit
        if cancel is not None and cancel():
            raise Cancelled("refinement cancelled")
        why = out_of_budget() if obj.evaluations > 0 else None  # the start is always seen
        if why is not None:
            stopped[0] = why
            raise _Stop(why)
        n_before, best_before = obj.evaluations, obj.best_loss
        loss = obj(x)
        if on_best is not None and obj.best_loss < best_before and obj.best_params is not None:
            on_best(obj.best_params, obj.best_yaw, obj.best_sketch_loss)
        if progress is not None and obj.evaluations != n_before:
            progress(obj.evaluations, obj.best_loss)
        return loss

    # 1. the start point, at several views
    x0 = space.from_params(initial_params, yaw or 0.0)
    loss_before = start_total = math.inf
    start_yaw = float(yaw or 0.0)
    yaws = START_YAWS if yaw is None else (float(yaw),)
    start_cap = max(1, budget // 3)
    # x0 stays the start (its own seed at its best view) in ``start_space``: what "before"
    # is and what the result falls back to; later stages begin from ``obj.best_x``
    start_space = space

    def at_view(y: float) -> np.ndarray:
        x = x0.copy()
        if space.search_yaw:
            x[-1] = (y % 360.0) / 360.0
        return x

    try:
        seen: list[tuple[float, float]] = []  # (loss, yaw) of the start's own seed
        for i, y in enumerate(yaws):
            if i > 0 and (obj.evaluations >= start_cap or out_of_budget()):
                break
            x = at_view(y)
            loss = evaluate(x)  # sketch distance + the view's penalty
            seen.append((loss, y))
            if loss < start_total:
                start_total, start_yaw = loss, y
                loss_before = obj.sketch_loss(x)  # the sketch distance alone
        x0 = at_view(start_yaw)
        # 1b. other tree seeds at the best views, while the start keeps within half the
        # budget and something is searched at all; "before" stays the start's own seed
        best_views = [y for _, y in sorted(seen)[:2]]
        seed0 = int(space.base["seed"])
        extra = (cfg.tree_seeds - 1) * len(best_views)
        if extra and space.n > 0 and obj.evaluations + extra <= budget // 2:
            for k in range(1, cfg.tree_seeds):
                obj.rebase(space.with_base(space.base.replace(seed=seed0 + k)))
                for y in best_views:
                    evaluate(at_view(y))
            space = obj.best_space or space
            obj.rebase(space)
        # 2. neighbouring discrete values
        if cfg.discrete_neighbours:
            best = obj.best_x if obj.best_x is not None else x0
            for cand in _discrete_candidates(name, space.base):
                alt = space.with_base(cand)
                obj.rebase(alt)
                if evaluate(best) <= obj.best_loss and obj.best_space is alt:
                    space = alt
            obj.rebase(obj.best_space or space)
            space = obj.space
        # 3. optional global stage, then 4. local search
        nlopt.srand(int(cfg.seed))
        stages: list[tuple[int, int]] = []
        if cfg.global_evals > 0 and space.n >= 2:
            stages.append((nlopt.GN_CRS2_LM, int(cfg.global_evals)))
        local = getattr(nlopt, ALGORITHMS[alg_name])
        if local == nlopt.LN_BOBYQA and space.n < 2:
            local = nlopt.LN_COBYLA
        if space.n > 0:  # nothing to search: the start point is the answer
            stages.append((local, budget))
        for alg, cap in stages:
            if out_of_budget() is not None:
                stopped[0] = out_of_budget() or stopped[0]
                break
            opt = nlopt.opt(alg, space.n)
            opt.set_lower_bounds(np.zeros(space.n))
            opt.set_upper_bounds(np.ones(space.n))
            opt.set_min_objective(lambda x, grad: evaluate(x))
            opt.set_maxeval(int(min(cap, budget - obj.evaluations) + obj.cache_size + 5))
            if deadline is not None:
                opt.set_maxtime(max(1e-3, deadline - time.perf_counter()))
            if alg != nlopt.GN_CRS2_LM:
                opt.set_initial_step(np.full(space.n, cfg.initial_step))
                opt.set_xtol_abs(np.full(space.n, cfg.xtol))
                opt.set_ftol_abs(1e-6)
            start = obj.best_x if obj.best_x is not None else x0
            try:
                opt.optimize(np.clip(np.asarray(start, dtype=np.float64), 0.0, 1.0))
                stopped[0] = _nlopt_reason(opt.last_optimize_result())
            except Cancelled:
                raise
            except _Stop:
                pass
            except (nlopt.ForcedStop, nlopt.RoundoffLimited):
                stopped[0] = "nlopt stopped"
            except RuntimeError as exc:  # nlopt's generic failure: keep the best seen
                stopped[0] = f"nlopt: {exc}"
            except ValueError as exc:
                if "_Stop" not in repr(exc) and not isinstance(exc.__cause__, _Stop):
                    stopped[0] = f"nlopt: {exc}"
    except _Stop:
        pass
    if cancel is not None and stopped[0].startswith("nlopt") and cancel():
        raise Cancelled("refinement cancelled")  # nlopt swallowed the exception

    if obj.best_params is None:  # not even the start point fitted the budget/time
        loss_after = loss_before
        best_params, best_yaw = start_space.to_params(x0), start_yaw
    else:
        loss_after = obj.best_sketch_loss  # <= best objective <= objective at the start
        best_params, best_yaw = obj.best_params, obj.best_yaw
    if loss_after > loss_before:  # the view penalty traded sketch match for the front view
        loss_after, best_params, best_yaw = loss_before, start_space.to_params(x0), start_yaw
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
        stopped_by=stopped[0],
    )


def _nlopt_reason(code: int) -> str:
    return {
        1: "converged",
        2: "stopval",
        3: "ftol",
        4: "xtol",
        5: "budget",
        6: "time",
    }.get(int(code), f"nlopt code {code}")
