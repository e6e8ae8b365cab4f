"""The steps :meth:`treesketch.Pipeline.run` is made of, each over plain data.

read the drawing(s) -> first estimate -> the species to try -> refine each -> draw the
result from every view (judging and building the :class:`~treesketch.Result` stay in
``pipeline``).  :class:`Reporter` tells a watcher where the run is and asks whether to
stop; the current best tree it shows is picked by the rule the run picks its result with.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

import numpy as np

from refine.objective import OtherView, PreparedDrawing, draw_side
from refine.search import Cancelled, RefineResult, RefineSettings
from refine.search import refine as refine_search
from render.reader import DRAWING_SIDE, SketchError, normalise_drawing, read_sketch
from weberpenn import TreeMesh, TreeParams, build_mesh, grow
from weberpenn import species as wp_species

from .estimate import Estimate, Estimator
from .species_choice import Candidate, posterior
from .trees import sketch_renderer, tree_sketch
from .views import SketchView, ViewResult, as_views, fuse_estimates

__all__ = [
    "CANDIDATES",
    "SKETCH_SIZE",
    "THUMB_SIZE",
    "DrawnViews",
    "FirstEstimate",
    "Progress",
    "ReadDrawings",
    "Reporter",
    "SpeciesSearch",
    "draw_views",
    "first_estimate",
    "list_candidates",
    "load_sketch",
    "planned_evaluations",
    "prepare_input",
    "read_drawings",
    "read_views",
    "refine_species",
    "share",
    "species_to_try",
    "timed",
    "view_turns",
]

CANDIDATES = 3  # species a result lists (the page shows them to switch to)
THUMB_SIZE = 128  # pixels of a candidate's sketch
SKETCH_SIZE = DRAWING_SIDE  # the size sketches are prepared at (TSN crops and resizes from it)


@contextmanager
def timed(timings: dict[str, float], key: str) -> Iterator[None]:
    """Seconds the block takes, into ``timings[key]``."""
    t = time.perf_counter()
    yield
    timings[key] = time.perf_counter() - t


# -- telling the watcher ---------------------------------------------------------------


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


class CurrentBest:
    """The tree a run would return if it stopped now, by the rule the run picks its result
    with (the species of highest posterior, ``species_choice.posterior``, from the
    estimator's scores and each species' best distance so far; only the species the user
    means when there is one); the shown distance only falls."""

    def __init__(self, scores: dict[str, float]) -> None:
        self.scores = scores
        # species -> its tree, yaw, distance and the distance it is weighed by
        self.best: dict[str, tuple[TreeParams, float, float, float]] = {}
        self.params: TreeParams | None = None
        self.species: str | None = None
        self.yaw = 0.0
        self.shown = math.nan
        self.version = 0

    def estimate(self, params: TreeParams, species: str, yaw: float) -> None:
        self.params, self.species, self.yaw = params, species, yaw
        self.version += 1

    def offer(
        self, params: TreeParams, yaw: float, loss: float, species: str, weight: float
    ) -> None:
        """A candidate's new best tree: ``loss`` its distance, ``weight`` the distance its
        species is weighed by (the search's, as ``RefineResult.evidence``; the outline
        step's tree comes with its search's and replaces the searched tree)."""
        if species in self.best and weight > self.best[species][3]:
            return
        self.best[species] = (params, yaw, loss, weight)
        post = posterior(self.scores, {s: v[3] for s, v in self.best.items()})
        pick = max(self.best, key=lambda s: post.get(s, 0.0))
        p, y, d, _ = self.best[pick]
        if p is self.params and pick == self.species:
            return
        self.params, self.species, self.yaw = p, pick, y
        self.shown = d if math.isnan(self.shown) else min(self.shown, d)
        self.version += 1


class Reporter:
    """Tells ``progress`` where the run is (with the current best tree once there is one)
    and raises :class:`Cancelled` at the next stage or tree when ``cancel()`` says so."""

    def __init__(
        self,
        budget: int,
        progress: Callable[[Progress], None] | None = None,
        cancel: Callable[[], bool] | None = None,
    ) -> None:
        self.progress, self.cancel = progress, cancel
        self.plan = budget  # until the species to try are known
        self.best: CurrentBest | None = None
        self.start = time.perf_counter()

    def tell(self, stage: str, evaluations: int = 0) -> None:
        if self.cancel is not None and self.cancel():
            raise Cancelled(f"cancelled during {stage}")
        if self.progress is None:
            return
        elapsed = time.perf_counter() - self.start
        best = self.best
        if best is None:
            self.progress(Progress(stage, 0, self.plan, math.nan, elapsed))
            return
        self.progress(
            Progress(
                stage,
                min(evaluations, self.plan),
                self.plan,
                best.shown,
                elapsed,
                best.params,
                best.species,
                best.yaw,
                best.version,
            )
        )

    def first_tree(self, first: FirstEstimate, plan: int) -> CurrentBest:
        """The first estimate's tree is the current best; ``plan`` trees are to come."""
        self.best = CurrentBest(first.scores)
        self.best.estimate(first.params, first.species, first.yaw)
        self.plan = plan
        self.tell("estimate")
        return self.best


# -- reading ---------------------------------------------------------------------------


def load_sketch(source: Any) -> np.ndarray:
    """A sketch from a path, bytes, a PIL image or an array -> (H, W) uint8, 255 = white
    (``render.reader.read_sketch``: size and bomb checks first, alpha on white)."""
    return read_sketch(source)


def prepare_input(img: np.ndarray) -> np.ndarray:
    """The sketch every stage sees (the estimator and the refinement alike):
    ``render.reader.normalise_drawing`` at :data:`SKETCH_SIZE` (paper flattened, ink
    found, re-framed as the renderer frames a tree); blank and dark pages are refused."""
    return normalise_drawing(img, SKETCH_SIZE)


def read_views(views: list[SketchView]) -> list[np.ndarray]:
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


@dataclass(frozen=True)
class ReadDrawings:
    """The drawings of one run: the views as given, each prepared (``images``, what the
    estimator reads) and each as every comparison of the run sees it (``drawings``: framed
    and prepared once for each species' search, the distances and the line distance)."""

    views: list[SketchView]
    images: list[np.ndarray]
    drawings: list[PreparedDrawing]

    @property
    def others(self) -> list[OtherView]:
        """The views after the first, as the refinement's objective adds them."""
        pairs = zip(self.drawings[1:], self.views[1:], strict=True)
        return [OtherView(d, v.yaw) for d, v in pairs]


def read_drawings(sketch: Any, cfg: RefineSettings, embedder: Any = None) -> ReadDrawings:
    """One drawing or several (``treesketch.views.as_views``) read and prepared."""
    views = as_views(sketch)
    images = read_views(views)
    drawings = [PreparedDrawing.create(im, cfg.size, cfg.metric, embedder) for im in images]
    return ReadDrawings(views, images, drawings)


# -- the first estimate and the species to try -------------------------------------------


@dataclass(frozen=True)
class FirstEstimate:
    """The estimator's reading of every view, fused, and the tree it starts from: of the
    species the user means (``chosen``) when there is one, else the estimator's."""

    estimate: Estimate
    chosen: str | None = None

    @property
    def species(self) -> str:
        return self.estimate.species if self.chosen is None else self.chosen

    @property
    def params(self) -> TreeParams:
        return self.estimate.params_for(self.species)

    @property
    def yaw(self) -> float:
        return 0.0 if self.estimate.yaw is None else float(self.estimate.yaw)

    @property
    def scores(self) -> dict[str, float]:
        """The estimator's species scores (its own species alone when it gives none)."""
        return self.estimate.species_scores or {self.estimate.species: 1.0}


def first_estimate(
    estimator: Estimator, images: list[np.ndarray], chosen: str | None = None
) -> FirstEstimate:
    """Every prepared view estimated, the estimates fused into one."""
    return FirstEstimate(fuse_estimates([estimator.estimate(im) for im in images]), chosen)


def species_to_try(first: FirstEstimate, cfg: RefineSettings) -> list[str]:
    """The species to refine: none when nothing is refined; the user's when given; else
    the estimator's, then up to ``species_tries - 1`` others scoring at least
    ``species_ratio`` times the best score."""
    if not cfg.refine:
        return []
    if first.chosen is not None:
        return [first.chosen]
    est = first.estimate
    ranked = est.ranked()
    top = max(ranked[0][1], 1e-12)
    others = [s for s, sc in ranked if s != est.species and sc >= cfg.species_ratio * top]
    return [est.species, *others[: cfg.species_tries - 1]]


def share(cfg: RefineSettings, i: int, n: int) -> RefineSettings:
    """Candidate ``i`` of ``n`` species' settings: the estimator's species (``i`` 0) the
    whole budget and, when others are tried, 60% of the time; the others half the budget
    and an equal part of the remaining 40%, so the whole run keeps to ``time_limit``."""
    if n == 1:
        return cfg
    part = 0.6 if i == 0 else 0.4 / (n - 1)
    limit = None if cfg.time_limit is None else cfg.time_limit * part
    return cfg.replace(budget=cfg.budget if i == 0 else max(8, cfg.budget // 2), time_limit=limit)


def planned_evaluations(cfg: RefineSettings, n: int) -> int:
    """The most trees a run refining ``n`` species evaluates (see :func:`share`)."""
    return sum(share(cfg, i, n).budget for i in range(n)) if cfg.refine else 0


# -- refining --------------------------------------------------------------------------


@dataclass(frozen=True)
class SpeciesSearch:
    """What refining the species to try gave: the result's ``species``, tree and view yaw;
    ``start_yaw``, the yaw its first estimate is seen from (the first search's start);
    each species' search (``refined``, in the order tried; empty when nothing was
    refined) and the species' probabilities from the scores and those distances."""

    species: str
    params: TreeParams
    yaw: float
    start_yaw: float
    posterior: dict[str, float]
    refined: dict[str, RefineResult] = dataclasses.field(default_factory=dict)
    evaluations: int = 0  # trees of every species

    @property
    def result(self) -> RefineResult | None:
        """The result's species' search (None: nothing refined)."""
        return self.refined.get(self.species) if self.refined else None

    @property
    def opening(self) -> RefineResult | None:
        """The first species' search (the estimator's or the user's; None: nothing
        refined): the result's "before" is its start."""
        return next(iter(self.refined.values()), None)

    @property
    def tried(self) -> dict[str, float]:
        """Each species tried and its search's best distance (``RefineResult.evidence``)."""
        return {s: rr.evidence for s, rr in self.refined.items()}


def refine_species(
    read: ReadDrawings,
    first: FirstEstimate,
    names: list[str],
    cfg: RefineSettings,
    report: Reporter,
    embedder: Any = None,
) -> SpeciesSearch:
    """Each species of ``names`` refined in turn (its share of the budget and time, see
    :func:`share`); the network's scores and the distances found pick the result's
    species together (``species_choice.posterior``), unless the user chose it."""
    if not names:
        post = posterior(first.scores, {})
        return SpeciesSearch(first.species, first.params, first.yaw, first.yaw, post)
    refined: dict[str, RefineResult] = {}
    done = 0  # evaluations of all species so far, so progress only grows
    for i, name in enumerate(names):
        report.tell("refine", done)
        rr = _refine_one(read, first, name, share(cfg, i, len(names)), report, embedder, done)
        done += rr.evaluations
        refined[name] = rr
    post = posterior(first.scores, {s: rr.evidence for s, rr in refined.items()})
    pick = first.chosen or max(refined, key=lambda s: post.get(s, 0.0))
    rr = refined[pick]
    start_yaw = refined[names[0]].start_yaw
    return SpeciesSearch(pick, rr.params, rr.yaw, start_yaw, post, refined, done)


def _refine_one(
    read: ReadDrawings,
    first: FirstEstimate,
    name: str,
    cfg: RefineSettings,
    report: Reporter,
    embedder: Any,
    done: int,
) -> RefineResult:
    """One species' search from the first estimate's tree for it, each better tree
    offered to the reporter's current best."""
    best = report.best
    return refine_search(
        read.drawings[0],
        first.estimate.params_for(name),
        cfg,
        species=name,
        yaw=None if cfg.search_yaw else first.yaw,
        progress=lambda n, _loss: report.tell("refine", done + n),
        cancel=report.cancel,
        embedder=embedder,
        on_best=None if best is None else lambda p, y, d, w: best.offer(p, y, d, name, w),
        views=read.others,
    )


# -- drawing the result ----------------------------------------------------------------


@dataclass(frozen=True)
class DrawnViews:
    """The result's tree (``mesh``) and, for every view, the first estimate's and the
    result's sketches and their distances to the drawing; ``loss_before`` and
    ``loss_after``: the distances over all views (as the refinement measured them)."""

    mesh: TreeMesh
    views: tuple[ViewResult, ...]
    loss_before: float
    loss_after: float

    @property
    def before(self) -> np.ndarray:
        return self.views[0].sketch_before

    @property
    def after(self) -> np.ndarray:
        return self.views[0].sketch_after


def view_turns(
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
        dist = [d.distance(r.sketch((yaw + t) % 360.0, draw_side(d.size))) for t in START_YAWS]
        out.append(START_YAWS[int(np.argmin(dist))])
    return out


def draw_views(read: ReadDrawings, first: FirstEstimate, search: SpeciesSearch) -> DrawnViews:
    """The result's tree grown and drawn from every view, beside the first estimate's."""
    from render.sketch import SketchRenderer

    mesh = build_mesh(grow(search.params), species=search.species)
    draw1 = SketchRenderer(mesh)  # the result's scene built once for all its views
    if search.result is None:  # nothing refined: the estimate is the result
        draw0 = draw1
    else:
        # the estimate's tree is only shown: drawn the cheap way, as the search drew it
        draw0 = sketch_renderer(first.params, first.species, SKETCH_SIZE)
    views = _sketch_views(read, search, draw0, draw1)
    return _with_losses(mesh, views, read.drawings, search)


def as_drawn(sketch: np.ndarray) -> np.ndarray:
    """A sketch (a tree's, or the prepared drawing) framed as the refinement compares the
    drawing and the tree (``render.reader.normalise_drawing`` ``over_crown``: base on the
    bottom margin, the axis a grown tree would stand on at the centre line, as large as
    the frame allows).  The renderer's own frame fits the tree's width over all sides, so
    beside the drawing a tree wider from another side looked smaller than drawn (issue
    48)."""
    try:
        return normalise_drawing(sketch, SKETCH_SIZE, over_crown=True)
    except SketchError:  # nothing drawn (a bare tree seen edge on): the frame as rendered
        return sketch


def _sketch_views(
    read: ReadDrawings, search: SpeciesSearch, draw0: Any, draw1: Any
) -> list[ViewResult]:
    """Every view's sketches of the first estimate (``draw0``, seen from the search's
    start yaw) and of the result (``draw1``), each framed as the drawings are
    (:func:`as_drawn`); the distances are left NaN."""
    yaw0, yaw1 = search.start_yaw, search.yaw

    def sketch(draw: Any, yaw: float) -> np.ndarray:
        return as_drawn(draw.sketch(yaw % 360.0, SKETCH_SIZE))

    after = sketch(draw1, yaw1)
    before = after if draw0 is draw1 else sketch(draw0, yaw0)
    out = [ViewResult(0.0, as_drawn(read.images[0]), before, after, math.nan, math.nan)]
    turns = view_turns(read.views, search.result, read.drawings, draw0, yaw0)
    for i, turn in enumerate(turns, start=1):
        b = sketch(draw0, yaw0 + turn)
        a = b if draw1 is draw0 else sketch(draw1, yaw1 + turn)
        searched = read.views[i].yaw is None
        out.append(ViewResult(turn, as_drawn(read.images[i]), b, a, math.nan, math.nan, searched))
    return out


def _with_losses(
    mesh: TreeMesh,
    views: list[ViewResult],
    drawings: list[PreparedDrawing],
    search: SpeciesSearch,
) -> DrawnViews:
    """Each view's distances: the refinement's (the first species' start, the result's
    best); with nothing refined, the estimate's sketch measured against each drawing."""
    start, result = search.opening, search.result
    if start is not None and result is not None:
        loss_before, loss_after = start.loss_before, result.loss_after
        per_before = start.view_losses_before or (loss_before,)
        per_after = result.view_losses_after or (loss_after,)
    else:
        pairs = zip(drawings, views, strict=True)
        per_before = per_after = tuple(d.distance(v.sketch_before) for d, v in pairs)
        loss_before = loss_after = float(np.mean(per_before))
    measured = tuple(
        dataclasses.replace(v, loss_before=float(lb), loss_after=float(la))
        for v, lb, la in zip(views, per_before, per_after, strict=True)
    )
    return DrawnViews(mesh, measured, float(loss_before), float(loss_after))


# -- the species a result offers -------------------------------------------------------


def list_candidates(
    first: FirstEstimate, search: SpeciesSearch, params: TreeParams, sketch: np.ndarray
) -> list[Candidate]:
    """The result's species (its tree ``params``, drawn as ``sketch``) and the next most
    probable, at least :data:`CANDIDATES` in all: each with its tree (refined, else the
    estimate for it), its distance (refined ones), its probability and a small sketch to
    pick it by."""
    name, refined, chosen = search.species, search.refined, first.chosen
    # by probability, then (an estimator that scores few species) the species' order
    ranked = sorted(wp_species.SPECIES, key=lambda s: -search.posterior.get(s, 0.0))
    names = [name, *[s for s in ranked if s != name]][: max(CANDIDATES, len(refined))]
    out = []
    for s in names:
        rr = refined.get(s)
        if s == name:
            p, img = params, sketch
        else:
            p = rr.params if rr is not None else first.estimate.params_for(s)
            img = tree_sketch(p, s, rr.yaw if rr is not None else 0.0, THUMB_SIZE)
        prob = 1.0 if chosen is not None and s == chosen else search.posterior.get(s, 0.0)
        out.append(
            Candidate(
                s,
                p,
                float(first.scores.get(s, 0.0)),
                None if rr is None else float(rr.loss_after),
                0.0 if chosen is not None and s != chosen else float(prob),
                img,
            )
        )
    return out
