"""The one place that composes "a first estimate" and "refine it": :class:`Pipeline`.

``Pipeline(estimator, settings).run(sketch)`` reads the sketch (the one reader,
``render.reader``), prepares it as the renderer frames a tree, asks the estimator for a
first estimate (parameters, species scores, maybe a view), refines the species' free values
and the view yaw with ``refine.search`` until the tree's sketch matches the input, and
returns a :class:`Result`.  The CLI, the HTTP service, the evaluation report, the rotation
sweep, the benchmarks and the notebooks all run a ``Pipeline``;
:func:`predict_then_refine` is the one-line convenience over it.

A sketch that does not look like a tree is not an error of the program: a blank page
raises :class:`SketchError`; anything else (a circle, noise) gives a result whose
``confidence`` is low and whose ``warning`` says so.
"""

from __future__ import annotations

import dataclasses
import math
import os
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from refine.objective import OtherView, PreparedDrawing, framed
from refine.search import Cancelled, RefineResult, RefineSettings
from refine.search import refine as refine_search
from refine.shape import ShapeTarget, line_distance
from render.reader import DRAWING_SIDE, SketchError, normalise_drawing, read_sketch
from weberpenn import TreeParams, build_mesh, grow
from weberpenn import species as wp_species

from .estimate import Estimate, Estimator
from .estimators import load_estimator
from .species_choice import Candidate, describe, posterior
from .trees import sketch_renderer, tree_sketch
from .views import SketchView, ViewResult, as_views, fuse_estimates

__all__ = [
    "LOW_CONFIDENCE_INK",
    "LOW_CONFIDENCE_LOSS",
    "LOW_CONFIDENCE_LOSS_SHAPE",
    "MAX_HEIGHT",
    "Cancelled",
    "Pipeline",
    "Progress",
    "RefineSettings",
    "Result",
    "SketchError",
    "SketchView",
    "TREE_PROBABILITY_LIMIT",
    "ViewResult",
    "check_height",
    "load_sketch",
    "planned_evaluations",
    "predict_then_refine",
    "prepare_input",
    "rescale_height",
    "result_confidence",
    "tree_judgement",
    "tree_likeness",
    "tree_line_distance",
]

CANDIDATES = 3  # species a result lists (the page shows them to switch to)
THUMB_SIZE = 128  # pixels of a candidate's sketch
SKETCH_SIZE = DRAWING_SIDE  # the size sketches are prepared at (TSN crops and resizes from it)
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
MAX_HEIGHT = 200.0  # metres: taller than any tree that grows


@dataclass(frozen=True)
class Progress:
    """Where a run is: ``stage`` is "read", "estimate", "refine" or "render".

    ``evaluations`` counts the trees of every species tried and never passes ``budget``,
    the run's whole plan (the estimator's species' budget plus the other candidates');
    ``best_loss`` (the best tree's sketch distance, NaN before the refinement's first
    tree) only falls.  ``params`` is the current best tree (the first estimate from the
    "estimate" stage's end, then the refinement's best), of ``species`` seen from ``yaw``;
    ``version`` grows by one each time it changes (0: no tree yet)."""

    stage: str
    evaluations: int
    budget: int
    best_loss: float
    elapsed: float
    params: TreeParams | None = None
    species: str | None = None
    yaw: float = 0.0
    version: int = 0


class _CurrentBest:
    """The tree a run would return if it stopped now, by the rule the run picks its result
    with (the species of highest posterior, ``species_choice.posterior``, from the
    estimator's scores and each species' best distance so far; only the species the user
    means when there is one); the shown distance only falls."""

    def __init__(self, scores: dict[str, float]) -> None:
        self.scores = scores
        self.best: dict[str, tuple[TreeParams, float, float]] = {}  # species -> tree
        self.params: TreeParams | None = None
        self.species: str | None = None
        self.yaw = 0.0
        self.shown = math.nan
        self.version = 0

    def estimate(self, params: TreeParams, species: str, yaw: float) -> None:
        self.params, self.species, self.yaw = params, species, yaw
        self.version += 1

    def offer(self, params: TreeParams, yaw: float, loss: float, species: str) -> None:
        """A candidate's new best tree."""
        if species in self.best and not loss < self.best[species][2]:
            return
        self.best[species] = (params, yaw, loss)
        post = posterior(self.scores, {s: v[2] for s, v in self.best.items()})
        pick = max(self.best, key=lambda s: post.get(s, 0.0))
        p, y, d = self.best[pick]
        if p is self.params and pick == self.species:
            return
        self.params, self.species, self.yaw = p, pick, y
        self.shown = d if math.isnan(self.shown) else min(self.shown, d)
        self.version += 1


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
    input_sketch: np.ndarray | None = None  # uint8, prepared (SKETCH_SIZE square)
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


def load_sketch(source: Any) -> np.ndarray:
    """A sketch from a path, bytes, a PIL image or an array -> (H, W) uint8, 255 = white
    (``render.reader.read_sketch``: size and bomb checks first, alpha on white)."""
    return read_sketch(source)


def prepare_input(img: np.ndarray) -> np.ndarray:
    """The sketch every stage sees (the estimator and the refinement alike):
    ``render.reader.normalise_drawing`` at :data:`SKETCH_SIZE` (paper flattened, ink
    found, re-framed as the renderer frames a tree); blank and dark pages are refused."""
    return normalise_drawing(img, SKETCH_SIZE)


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
    # leaf size and radii follow scale in Weber-Penn; one correction pass for any
    # non-linearity (e.g. a clipped value)
    again = tree_height(out)
    if again > 0 and abs(again - height) / height > 0.01:
        g = height / again
        out = out.replace(scale=float(out["scale"]) * g, scaleV=float(out["scaleV"]) * g)
    return out


def tree_line_distance(drawing: Any, tree_sketch: Any, size: int) -> float:
    """``refine.shape.line_distance`` of a drawing and a tree's sketch, both framed as the
    refinement frames them (a tree too small to draw anything is as far as can be)."""
    return _line_distance(ShapeTarget.from_image(framed(drawing, size), size), tree_sketch)


def _line_distance(drawing: ShapeTarget, tree_sketch: Any) -> float:
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


def tree_judgement(
    tree_probability: float | None, loss: float, ink: float, limit: float
) -> tuple[float, str | None]:
    """How much the drawing looks like a tree (0..1) and the warning when it may not be
    one: the estimator's probability when it gives one (warned below
    :data:`TREE_PROBABILITY_LIMIT`), else the distances' :func:`tree_likeness`."""
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


def planned_evaluations(cfg: RefineSettings, n: int) -> int:
    """The most trees a run refining ``n`` species evaluates (see :func:`_share`)."""
    return sum(_share(cfg, i, n).budget for i in range(n)) if cfg.refine else 0


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


def _share(cfg: RefineSettings, i: int, n: int) -> RefineSettings:
    """Candidate ``i`` of ``n`` species' settings: the estimator's species (``i`` 0) the
    whole budget and, when others are tried, 60% of the time; the others half the budget
    and an equal part of the remaining 40%, so the whole run keeps to ``time_limit``."""
    if n == 1:
        return cfg
    share = 0.6 if i == 0 else 0.4 / (n - 1)
    limit = None if cfg.time_limit is None else cfg.time_limit * share
    return cfg.replace(budget=cfg.budget if i == 0 else max(8, cfg.budget // 2), time_limit=limit)


def _read_views(views: list[SketchView]) -> list[np.ndarray]:
    """Every view read and prepared (all before any estimate: a bad second drawing is
    refused before the first is worked on); an error names the view when there are
    several."""
    imgs = []
    for i, v in enumerate(views):
        try:
            imgs.append(prepare_input(load_sketch(v.source)))
        except SketchError as exc:
            if len(views) == 1:
                raise
            raise SketchError(f"view {i + 1} of {len(views)}: {exc}") from None
    return imgs


def _view_turns(
    views: list[SketchView],
    refined: RefineResult | None,
    drawings: list[PreparedDrawing],
    r: Any,
    yaw: float,
) -> list[float]:
    """The other views' yaws relative to the first: as the refinement used them, else as
    given; a view of unknown yaw and no refinement: the turn of the first estimate's
    tree (drawn by the renderer ``r``) whose sketch is nearest that drawing (every 15
    degrees)."""
    if refined is not None and refined.view_yaws:
        return list(refined.view_yaws)
    from refine.search import START_YAWS

    out = []
    for v, d in zip(views[1:], drawings[1:], strict=True):
        if v.yaw is not None:
            out.append(float(v.yaw))
            continue
        dist = [d.distance(r.sketch((yaw + t) % 360.0, d.size)) for t in START_YAWS]
        out.append(START_YAWS[int(np.argmin(dist))])
    return out


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
        imgs = _read_views(as_views(sketch))
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
        t_start = time.perf_counter()
        plan = cfg.budget if cfg.refine else 0  # until the candidates are known
        best: _CurrentBest | None = None

        def tell(stage: str, evaluations: int = 0) -> None:
            if cancel is not None and cancel():
                raise Cancelled(f"cancelled during {stage}")
            if progress is not None:
                elapsed = time.perf_counter() - t_start
                if best is None:
                    progress(Progress(stage, 0, plan, math.nan, elapsed))
                    return
                progress(
                    Progress(
                        stage,
                        min(evaluations, plan),
                        plan,
                        best.shown,
                        elapsed,
                        best.params,
                        best.species,
                        best.yaw,
                        best.version,
                    )
                )

        timings: dict[str, float] = {}
        t = time.perf_counter()
        tell("read")
        views = as_views(sketch)
        imgs = _read_views(views)
        img = imgs[0]
        # each drawing as every comparison of this run sees it (each species' search, the
        # first estimate's distance, the line distance): framed and prepared once
        drawings = [PreparedDrawing.create(im, cfg.size, cfg.metric, self.embedder) for im in imgs]
        drawing = drawings[0]
        others = [OtherView(d, v.yaw) for d, v in zip(drawings[1:], views[1:], strict=True)]
        timings["prepare"] = time.perf_counter() - t

        t = time.perf_counter()
        tell("estimate")
        est = fuse_estimates([self.estimator.estimate(im) for im in imgs])
        yaw0 = 0.0 if est.yaw is None else float(est.yaw)
        timings["estimate"] = time.perf_counter() - t
        best = _CurrentBest(est.species_scores or {est.species: 1.0})
        if chosen is None:
            best.estimate(est.params, est.species, yaw0)
        else:
            best.estimate(est.params_for(chosen), chosen, yaw0)
        names = ([chosen] if chosen is not None else self.candidates(est)) if cfg.refine else []
        plan = planned_evaluations(cfg, len(names))
        tell("estimate")  # the first tree, at once

        t = time.perf_counter()
        result_refine: RefineResult | None = None
        tried: dict[str, float] = {}
        name = est.species
        done = 0  # evaluations of all candidates so far, so progress only grows
        refined: dict[str, RefineResult] = {}
        if chosen is not None:
            name = chosen
        if cfg.refine:
            for i, candidate in enumerate(names):
                run_cfg = _share(cfg, i, len(names))
                tell("refine", done)
                rr = refine_search(
                    drawing,
                    est.params_for(candidate),
                    run_cfg,
                    species=candidate,
                    yaw=None if cfg.search_yaw else yaw0,
                    progress=lambda n, _loss, done=done: tell("refine", done + n),
                    cancel=cancel,
                    embedder=self.embedder,
                    on_best=lambda p, y, loss, c=candidate: best.offer(p, y, loss, c),
                    views=others,
                )
                done += rr.evaluations
                tried[candidate] = rr.loss_after
                refined[candidate] = rr
                if i == 0:
                    yaw0, loss0 = rr.start_yaw, rr.loss_before
                    views0 = rr.view_losses_before or (loss0,)
            # the network's scores and the synthesis distances decide together
            post = posterior(est.species_scores or {est.species: 1.0}, tried)
            if chosen is None:
                name = max(tried, key=lambda s: post.get(s, 0.0))
            result_refine = refined[name]
            params1, yaw1 = result_refine.params, result_refine.yaw
        else:
            post = posterior(est.species_scores or {est.species: 1.0}, {})
            params1 = est.params if chosen is None else est.params_for(chosen)
            yaw1 = yaw0
        timings["refine"] = time.perf_counter() - t

        t = time.perf_counter()
        tell("render", done)
        from render.sketch import SketchRenderer

        start = est.params if chosen is None else est.params_for(chosen)
        start_species = est.species if chosen is None else chosen
        mesh1 = build_mesh(grow(params1), species=name)
        draw1 = SketchRenderer(mesh1)  # the result's scene built once for all its views
        after = draw1.sketch(yaw1, SKETCH_SIZE)
        if result_refine is None:  # nothing refined: the estimate is the result
            draw0, before = draw1, after
        else:
            # the estimate's tree is only shown: drawn the cheap way, as the search drew it
            draw0 = sketch_renderer(start, start_species, SKETCH_SIZE)
            before = draw0.sketch(yaw0, SKETCH_SIZE)
        turns = _view_turns(views, result_refine, drawings, draw0, yaw0)
        view_results = [ViewResult(0.0, img, before, after, math.nan, math.nan)]
        for i, turn in enumerate(turns, start=1):
            b = draw0.sketch((yaw0 + turn) % 360.0, SKETCH_SIZE)
            a = b if draw1 is draw0 else draw1.sketch((yaw1 + turn) % 360.0, SKETCH_SIZE)
            view_results.append(
                ViewResult(turn, imgs[i], b, a, math.nan, math.nan, views[i].yaw is None)
            )
        if result_refine is not None:
            loss_before, loss_after = loss0, result_refine.loss_after
            per_before = views0
            per_after = result_refine.view_losses_after or (loss_after,)
        else:
            per_before = tuple(
                d.distance(v.sketch_before) for d, v in zip(drawings, view_results, strict=True)
            )
            per_after = per_before
            loss_before = loss_after = float(np.mean(per_before))
        view_results = [
            dataclasses.replace(v, loss_before=float(lb), loss_after=float(la))
            for v, lb, la in zip(view_results, per_before, per_after, strict=True)
        ]
        timings["render"] = time.perf_counter() - t

        current = mesh_height(mesh1)
        if height is not None and abs(current - height) > 1e-6 * height:
            t = time.perf_counter()
            params1 = rescale_height(params1, height, current=current)
            mesh1 = build_mesh(grow(params1), species=name)
            timings["height"] = time.perf_counter() - t

        # every view's unexplained ink, averaged as the shape distance is
        ink_after = float(
            np.mean(
                [
                    _line_distance(d.shape, v.sketch_after)
                    for d, v in zip(drawings, view_results, strict=True)
                ]
            )
        )
        limit = LOW_CONFIDENCE_LOSS if self.embedder is not None else LOW_CONFIDENCE_LOSS_SHAPE
        tree_like, warning = tree_judgement(est.tree_probability, loss_after, ink_after, limit)
        t = time.perf_counter()
        candidates = self._candidates(est, name, params1, after, refined, post, chosen)
        timings["candidates"] = time.perf_counter() - t
        confidence = result_confidence(
            candidates[0].probability if candidates else tree_like,
            tree_like,
            warning,
            est.tree_probability,
        )
        timings["total"] = sum(timings.values())
        return Result(
            params=params1,
            species=name,
            tree_mesh=mesh1,
            sketch_before=before,
            sketch_after=after,
            losses={
                "before": float(loss_before),
                "after": float(loss_after),
                "ink_after": float(ink_after),
            },
            timings=timings,
            yaw=float(yaw1),
            input_sketch=img,
            estimator=self.estimator.name,
            estimate=est,
            refinement=result_refine,
            confidence=confidence,
            warning=warning,
            extras={"tried": tried} if tried else {},
            candidates=tuple(candidates),
            views=tuple(view_results),
        )

    def _candidates(
        self,
        est: Estimate,
        name: str,
        params: TreeParams,
        sketch: np.ndarray,
        refined: dict[str, RefineResult],
        post: dict[str, float],
        chosen: str | None,
    ) -> list[Candidate]:
        """The result's species and the next most probable, at least ``CANDIDATES`` in
        all: each with its tree (refined, else the estimate for it), its distance (refined
        ones), its probability and a small sketch to pick it by."""
        # by probability, then (an estimator that scores few species) the species' order
        ranked = sorted(wp_species.SPECIES, key=lambda s: -post.get(s, 0.0))
        names = [name, *[s for s in ranked if s != name]][: max(CANDIDATES, len(refined))]
        scores = est.species_scores or {est.species: 1.0}
        out = []
        for s in names:
            if s == name:
                p, img = params, sketch
            else:
                rr = refined.get(s)
                p = rr.params if rr is not None else est.params_for(s)
                img = tree_sketch(p, s, rr.yaw if rr is not None else 0.0, THUMB_SIZE)
            rr = refined.get(s)
            prob = 1.0 if chosen is not None and s == chosen else post.get(s, 0.0)
            out.append(
                Candidate(
                    s,
                    p,
                    float(scores.get(s, 0.0)),
                    None if rr is None else float(rr.loss_after),
                    0.0 if chosen is not None and s != chosen else float(prob),
                    img,
                )
            )
        return out

    def candidates(self, est: Estimate) -> list[str]:
        """The species to refine: the estimator's, then up to ``species_tries - 1`` others
        scoring at least ``species_ratio`` times the best score."""
        ranked = est.ranked()
        top = max(ranked[0][1], 1e-12)
        others = [
            s for s, sc in ranked if s != est.species and sc >= self.settings.species_ratio * top
        ]
        return [est.species, *others[: self.settings.species_tries - 1]]


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
