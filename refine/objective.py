"""Sketch distance and the refinement objective.

``sketch_distance(a, b)`` compares two sketches (uint8, 255 = white, dark lines) at two or
three scales of an image pyramid.  At each scale it adds

- a symmetric chamfer distance between the dark-line masks (mean distance from each line
  pixel of one sketch to the nearest line pixel of the other, via Euclidean distance
  transforms), as a fraction of the image side, times ``chamfer_weight``;
- one minus the IoU of the filled silhouettes (the line mask closed and its holes filled:
  the crown outline and trunk as solid shapes), times ``silhouette_weight``.

It is zero for identical sketches, symmetric, deterministic, and grows smoothly as lines
move apart (the chamfer term falls off linearly with distance, unlike pixel overlap).

:class:`SearchSpace` maps the species' free continuous unfixed values (and the camera yaw)
to the unit cube; :class:`SketchObjective` turns a point of that cube into a tree, renders
its sketch at the input's framing and size and measures the distance to the input, caching
results by (rounded) point and reusing the last tree's scene when only the yaw moved.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy import ndimage

from render.distance import distance_to_background
from render.reader import SketchError, drop_specks, frame_ink, ink_mask, normalise_drawing
from weberpenn import TreeParams, build_mesh, grow, species
from weberpenn.params import SPECS

from .prepare import prepare_sketch
from .shape import ShapeTarget, outline_gap

__all__ = [
    "METRICS",
    "OtherView",
    "PreparedDrawing",
    "SearchSpace",
    "SketchObjective",
    "SketchTarget",
    "draw_side",
    "framed",
    "framed_sketch",
    "make_target",
    "metric_distance",
    "prepare_sketch",
    "search_distance",
    "sketch_distance",
]

# one unit of outline gap (``refine.shape.outline_gap``: the envelopes' overlap, the
# outline row by row and where the tree stands) weighs as this much shape distance in the
# search (issue 48: the silhouette in the search; RESULTS.md, "The tree follows the
# drawing")
ENVELOPE_WEIGHT = 2.0
_DARK = 0.5  # a pixel darker than this (fraction of white) is a line pixel
_EMPTY_PENALTY = 1.0
_FILL_DENSITY = 0.15


@dataclass(frozen=True)
class _Level:
    mask: np.ndarray  # bool, line pixels
    dist: np.ndarray  # float32, distance to the nearest line pixel (inf-free)
    filled: np.ndarray  # float32 0..1, soft filled silhouette
    n: int  # number of line pixels


def _fill(mask: np.ndarray) -> np.ndarray:
    """Soft filled silhouette (float 0..1): local ink density, saturated.

    A blur of the line mask (sigma = side / 32) divided by ``_FILL_DENSITY`` and clipped:
    the inside of a crown drawn with many strokes, or closed by its outline after the hole
    fill, reads as 1; open page as 0.  Smooth in the line positions, unlike a hard fill
    whose result flips when one gap in an outline opens.
    """
    side = mask.shape[0]
    soft = ndimage.gaussian_filter(mask.astype(np.float32), sigma=max(0.75, side / 32))
    soft = np.clip(soft / _FILL_DENSITY, 0.0, 1.0)
    hard = ndimage.binary_fill_holes(soft > 0.5)
    return np.maximum(soft, hard.astype(np.float32) * 0.5 + soft * 0.5).astype(np.float32)


def _levels(img: np.ndarray, scales: int) -> tuple[_Level, ...]:
    out = []
    dark = img < _DARK
    for _ in range(scales):
        n = int(dark.sum())
        if n:
            dist = distance_to_background(~dark).astype(np.float32)
        else:
            dist = np.zeros(dark.shape, np.float32)
        out.append(_Level(dark, dist, _fill(dark), n))
        s = dark.shape[0] // 2
        if s < 8:
            break
        dark = dark[: 2 * s, : 2 * s].reshape(s, 2, s, 2).any(axis=(1, 3))
    return tuple(out)


@dataclass(frozen=True)
class SketchTarget:
    """A sketch prepared for repeated comparison (pyramid, distance maps, silhouettes)."""

    image: np.ndarray  # float32 0..1
    levels: tuple[_Level, ...]

    @classmethod
    def from_image(cls, img: Any, size: int = 128, scales: int = 3) -> SketchTarget:
        f = prepare_sketch(img, size)
        return cls(f, _levels(f, scales))

    @property
    def size(self) -> int:
        return int(self.image.shape[0])

    @property
    def ink(self) -> float:
        """Fraction of line pixels at full resolution."""
        return self.levels[0].n / self.levels[0].mask.size

    def distance(self, other: SketchTarget) -> float:
        return target_distance(self, other)


def _level_distance(a: _Level, b: _Level, chamfer_weight: float, silhouette_weight: float) -> float:
    side = a.mask.shape[0]
    if a.n == 0 and b.n == 0:
        return 0.0
    if a.n == 0 or b.n == 0:
        return _EMPTY_PENALTY * (chamfer_weight + silhouette_weight)
    ab = float(b.dist[a.mask].mean())
    ba = float(a.dist[b.mask].mean())
    chamfer = 0.5 * (ab + ba) / side
    inter = float(np.minimum(a.filled, b.filled).sum())
    union = float(np.maximum(a.filled, b.filled).sum())
    iou = inter / union if union > 0 else 1.0
    return chamfer_weight * chamfer + silhouette_weight * (1.0 - iou)


def target_distance(
    a: SketchTarget,
    b: SketchTarget,
    chamfer_weight: float = 10.0,
    silhouette_weight: float = 1.0,
) -> float:
    """Distance between two prepared sketches (see the module text)."""
    if a.image.shape != b.image.shape:
        raise ValueError(f"sketch sizes differ: {a.image.shape} vs {b.image.shape}")
    terms = [
        _level_distance(x, y, chamfer_weight, silhouette_weight)
        for x, y in zip(a.levels, b.levels, strict=False)
    ]
    return float(np.mean(terms))


def sketch_distance(
    a: Any,
    b: Any,
    size: int = 128,
    scales: int = 3,
    chamfer_weight: float = 10.0,
    silhouette_weight: float = 1.0,
) -> float:
    """Distance between two sketch images (any size; both resized to ``size``)."""
    return target_distance(
        SketchTarget.from_image(a, size, scales),
        SketchTarget.from_image(b, size, scales),
        chamfer_weight,
        silhouette_weight,
    )


# --------------------------------------------------------------------------- metrics
METRICS = ("shape", "ink")


def framed(img: Any, size: int) -> np.ndarray:
    """A sketch as every comparison sees it: ``render.reader.normalise_drawing`` at ``size``
    (ink on white, framed by its own drawn extent, its axis where a grown tree's would
    stand: ``over_crown``).  The input and every candidate go
    through it, so both sides of the distance share one framing.  Framed at twice the size
    and pooled "any ink", so a thin pen line stays a whole line at the work size (a plain
    downscale and threshold breaks it into dashes, and an outline into pieces)."""
    a = img if isinstance(img, np.ndarray) and img.dtype == np.uint8 and img.ndim == 2 else None
    if a is None:
        a = np.round(prepare_sketch(img, max(8, min(np.shape(img)[:2]))) * 255).astype(np.uint8)
    return _pooled(normalise_drawing(a, 2 * size, over_crown=True))


def framed_sketch(sketch: np.ndarray, size: int) -> np.ndarray:
    """A sketch the renderer drew (uint8, a candidate tree's) framed as :func:`framed`
    frames a drawing, without the reader's cleaning of a page: a tree's sketch has no
    paper, frame, caption, ground line, ruling or marks beside the tree, so its ink less
    its specks is what the cleaning leaves, framed the same (the same picture, pixel for
    pixel, for 264 of 264 candidates of the eleven species, in half the time; the specks
    go, as a willow's stray leaf clumps above its crown would frame it smaller: RESULTS.md,
    "Candidates framed without the page's cleaning; the outline step's trees meshed
    lighter")."""
    if np.ndim(sketch) != 2:
        raise ValueError(f"a tree's sketch is a 2-D grey picture, got shape {np.shape(sketch)}")
    return _pooled(frame_ink(drop_specks(ink_mask(sketch)), 2 * size, over_crown=True))


def _pooled(big: np.ndarray) -> np.ndarray:
    """The darker of each 2 x 2 block, as four strided minima: numpy's min over the
    reshaped block axes gives the same values at about thirty times the cost."""
    return np.minimum(
        np.minimum(big[0::2, 0::2], big[0::2, 1::2]), np.minimum(big[1::2, 0::2], big[1::2, 1::2])
    )


def draw_side(size: int) -> int:
    """The side, in pixels, a candidate tree's sketch is drawn at to be compared at
    ``size`` (:func:`framed` frames at twice ``size`` and pools any ink).  The renderer
    draws a sketch smaller than its reference side at that side and box-averages it
    down, so a 128 px sketch's one-pixel lines come out grey; framing thresholds them,
    and its outline fell apart into dashes whose envelope misses whole bites of the
    crown (RESULTS.md, "The tree follows the drawing").  Drawn at twice the size, the
    lines are whole, as the drawing's are."""
    return 2 * int(size)


def make_target(img: Any, size: int, metric: str = "shape", embedder: Any = None) -> Any:
    """A prepared sketch for the chosen metric (``ShapeTarget`` or :class:`SketchTarget`);
    both compare with ``.distance(other)``.  ``embedder`` (``refine.embed.ShapeEmbedder``,
    shape metric only) adds the learned embedding's term."""
    if metric == "shape":
        return ShapeTarget.from_image(img, size, embedder=embedder)
    if metric == "ink":
        return SketchTarget.from_image(img, size)
    raise ValueError(f"unknown metric {metric!r}; choose one of {', '.join(METRICS)}")


def metric_distance(
    a: Any, b: Any, size: int = 128, metric: str = "shape", embedder: Any = None
) -> float:
    """The distance the refinement minimises, between two sketches framed alike."""
    return make_target(framed(a, size), size, metric, embedder).distance(
        make_target(framed(b, size), size, metric, embedder)
    )


def search_distance(target: Any, candidate: Any) -> float:
    """The distance the refinement minimises from a prepared drawing ``target`` to a
    prepared candidate (both from :func:`make_target` at one size): the metric's own
    distance, plus ``ENVELOPE_WEIGHT`` times their outline gap with the shape metric (the
    tree's outline follows the drawn one, not only its lines)."""
    d = target.distance(candidate)
    if isinstance(target, ShapeTarget) and isinstance(candidate, ShapeTarget):
        d += ENVELOPE_WEIGHT * outline_gap(target, candidate)
    return d


@dataclass(frozen=True)
class PreparedDrawing:
    """The input drawing as every comparison of one run sees it, built once.

    ``target`` is what the search minimises against (:func:`make_target` of the framed
    drawing, with the learned embedding's term when ``embedder`` is given); ``shape`` the
    drawing's shape features for the line distance (``refine.shape.line_distance``): the
    same object when the metric is ``"shape"`` (the embedding plays no part there).  The
    pipeline builds one per run and hands it to every species' refinement and to the
    confidence check, instead of each re-framing and re-preparing the same drawing.
    """

    size: int
    metric: str
    target: Any  # ShapeTarget or SketchTarget
    shape: ShapeTarget
    embedder: Any = None

    @classmethod
    def create(
        cls, img: Any, size: int = 128, metric: str = "shape", embedder: Any = None
    ) -> PreparedDrawing:
        if embedder is not None and metric != "shape":
            raise ValueError("a learned embedder works with the shape metric only")
        f = framed(img, size)
        target = make_target(f, size, metric, embedder)
        shape = target if metric == "shape" else ShapeTarget.from_image(f, size)
        return cls(size, metric, target, shape, embedder)

    def check(self, size: int, metric: str) -> PreparedDrawing:
        """Self, when built for comparisons at ``size`` with ``metric`` (ValueError else)."""
        if (self.size, self.metric) != (size, metric):
            raise ValueError(
                f"the drawing was prepared for size {self.size} and metric {self.metric!r}, "
                f"not {size} and {metric!r}"
            )
        return self

    def distance(self, sketch: Any) -> float:
        """The search's distance from this drawing to a tree's sketch (the renderer's,
        framed alike: :func:`framed_sketch`)."""
        return search_distance(
            self.target,
            make_target(framed_sketch(sketch, self.size), self.size, self.metric, self.embedder),
        )


@dataclass(frozen=True)
class OtherView:
    """Another drawing of the same tree: ``drawing`` prepared like the first, seen from
    ``yaw`` degrees about the trunk relative to the first view (the renderer's sense: the
    first view at yaw ``y`` and this one at ``y + yaw``); ``None``: not known, searched
    (``refine.search.refine`` picks it at the start)."""

    drawing: PreparedDrawing
    yaw: float | None = 90.0


# --------------------------------------------------------------------------- search space


@dataclass(frozen=True)
class SearchSpace:
    """The free continuous unfixed values of a species (and the yaw), as a unit cube.

    ``base`` supplies every value not searched (its discrete values, e.g. ``baseSplits``,
    are held).  ``to_params(x)`` applies ``species.project`` (clipping, mirrored
    ``curveBack``, the split height).
    """

    species: str
    base: TreeParams
    dims: tuple[species.Unfixed, ...]
    search_yaw: bool = True
    fixed_yaw: float = 0.0
    # keys held at ``base``'s values whatever the species' (``species.project``'s
    # ``keep``: the drawn outline of ``refine.start``)
    keep: tuple[str, ...] = ()

    @classmethod
    def create(
        cls,
        name: str,
        base: TreeParams,
        keys: Sequence[str] | None = None,
        search_yaw: bool = True,
        yaw: float = 0.0,
        keep: Sequence[str] = (),
    ) -> SearchSpace:
        name = species.canonical(name)
        levels = int(base["levels"])
        rows = [u for u in species.unfixed(name) if u.free and not u.discrete]
        rows = [u for u in rows if u.hi > u.lo and (u.index is None or u.index < levels)]
        rows += species.search_freedoms(name)  # level 0 values and a 4-value envelope
        if keys is not None:
            wanted = set(keys)
            unknown = wanted - {u.key for u in rows} - {u.label for u in rows}
            if unknown:
                raise ValueError(
                    f"not searchable for {name}: {', '.join(sorted(unknown))}; "
                    f"choose from {', '.join(u.label for u in rows)}"
                )
            rows = [u for u in rows if u.key in wanted or u.label in wanted]
        return cls(
            name,
            species.project(name, base, search=True, keep=keep),
            tuple(rows),
            search_yaw,
            float(yaw) % 360.0,
            tuple(keep),
        )

    @property
    def n(self) -> int:
        return len(self.dims) + (1 if self.search_yaw else 0)

    @property
    def labels(self) -> tuple[str, ...]:
        return tuple(u.label for u in self.dims) + (("yaw",) if self.search_yaw else ())

    def to_params(self, x: Sequence[float]) -> TreeParams:
        x = np.clip(np.asarray(x, dtype=np.float64), 0.0, 1.0)
        changes: dict[str, Any] = {}
        for u, t in zip(self.dims, x, strict=False):
            v: Any = u.lo + float(t) * (u.hi - u.lo)
            now = changes.get(u.key, self.base[u.key])
            here = now if u.index is None else now[u.index]
            if abs(float(here) - v) <= 1e-6 * (u.hi - u.lo):
                continue  # the base's own value: keep it exactly (no round-trip error)
            if SPECS[u.key].kind == "int":
                v = round(v)
            if u.index is None:
                changes[u.key] = v
            else:
                vec = list(now)
                vec[u.index] = v
                changes[u.key] = vec
        return species.project(
            self.species, self.base.replace(**changes), search=True, keep=self.keep
        )

    def yaw(self, x: Sequence[float]) -> float:
        if not self.search_yaw:
            return self.fixed_yaw
        return float(np.clip(x[len(self.dims)], 0.0, 1.0) * 360.0) % 360.0

    def from_params(self, params: TreeParams, yaw: float = 0.0) -> np.ndarray:
        p = species.project(self.species, params, search=True, keep=self.keep).to_dict()
        xs = []
        for u in self.dims:
            v = p[u.key] if u.index is None else p[u.key][u.index]
            xs.append((float(v) - u.lo) / (u.hi - u.lo))
        if self.search_yaw:
            xs.append((float(yaw) % 360.0) / 360.0)
        return np.clip(np.asarray(xs, dtype=np.float64), 0.0, 1.0)

    def without(self, keys: Sequence[str]) -> SearchSpace:
        """The same space minus the dimensions whose key (or label) is in ``keys``."""
        drop = set(keys)
        dims = tuple(u for u in self.dims if u.key not in drop and u.label not in drop)
        return dataclasses.replace(self, dims=dims)

    def live(self, probe: float = 0.25) -> SearchSpace:
        """The same space minus its dead dimensions: those that do not change the grown
        tree at all when moved by ``probe`` (unit cube) either way from the base point.

        Many unfixed values only act through a structure the base does not have (a
        trunk-split rotation with ``baseSplits`` 0, the last-angle memory of a level whose
        stems take another rule, a pine's whorl-placed branches); searching them costs
        the local search start evaluations and lets them drift without a signal.  Costs
        up to ``2 n`` skeleton grows (no mesh, no render), each stopped at the first
        level whose stems differ from the base tree's (``weberpenn.growing``): a value
        that moves the trunk is known live once the trunk is grown.
        """
        from weberpenn.grow import grow_levels, growing

        def close(a: np.ndarray, b: np.ndarray) -> bool:
            return a.shape == b.shape and np.allclose(a, b, rtol=0.0, atol=1e-9)

        def moves(params: TreeParams) -> bool:
            levels = growing(params)
            k = 0
            while True:
                try:
                    stems = next(levels)
                except StopIteration as done:
                    sk = done.value
                    break
                if k >= len(ref) or not all(map(close, stems, ref[k])):
                    levels.close()
                    return True
                k += 1
            return k != len(ref) or not close(
                np.asarray(sk.leaf_matrices), np.asarray(ref_sk.leaf_matrices)
            )

        x0 = self.from_params(self.base)
        ref, ref_sk = grow_levels(self.to_params(x0))
        keep = []
        for i, u in enumerate(self.dims):
            for t in (x0[i] + probe, x0[i] - probe):
                if not 0.0 <= t <= 1.0:
                    continue
                x = x0.copy()
                x[i] = t
                if moves(self.to_params(x)):
                    keep.append(u)
                    break
        return dataclasses.replace(self, dims=tuple(keep))


# --------------------------------------------------------------------------- objective


@dataclass
class SketchObjective:
    """``objective(x)`` -> sketch distance of the tree at ``x`` to the target (plus the
    view's :meth:`penalty`).

    Counts evaluations (cache hits excluded), keeps the best point seen, and caches losses
    by the point rounded to ``decimals``.  The last tree's renderer is kept so points that
    differ only in yaw re-render without regrowing.

    ``fast`` (default) draws each candidate the cheap way, the same sketch up to a few
    pixels (``render.sketch.sketch_mesh`` without the stems too thin to be drawn,
    rasterised by ``render.raster`` instead of a mitsuba scene built per tree:
    ``benchmarks/RESULTS.md``, "Faster evaluations"); ``fast=False`` renders the full
    mesh with mitsuba, as datasets and outputs are.
    """

    target: Any  # SketchTarget or refine.shape.ShapeTarget (``make_target``)
    space: SearchSpace
    metric: str = "shape"
    decimals: int = 6
    yaw_prior: float = 0.0  # degrees: the view assumed unless the sketch says otherwise
    yaw_weight: float = 0.0
    evaluations: int = 0
    best_loss: float = math.inf  # objective: sketch distance + view penalty
    best_sketch_loss: float = math.inf  # the sketch distance alone at the best point
    best_x: np.ndarray | None = None
    best_params: TreeParams | None = None
    best_yaw: float = 0.0
    trace: list[tuple[int, float, float]] = field(default_factory=list)  # (eval, loss, best)
    fast: bool = True
    embedder: Any = None  # refine.embed.ShapeEmbedder: the one that made the target's embedding
    # the other drawings of the tree: (target, yaw relative to the first view); the sketch
    # distance is the mean over every view, so one view and several share one scale
    others: tuple[tuple[Any, float], ...] = ()
    _cache: dict[tuple[float, ...], float] = field(default_factory=dict, repr=False)
    _sketch_losses: dict[tuple[float, ...], float] = field(default_factory=dict, repr=False)
    _view_losses: dict[tuple[float, ...], tuple[float, ...]] = field(
        default_factory=dict, repr=False
    )
    _scene_key: tuple[float, ...] | None = field(default=None, repr=False)
    _renderer: Any = field(default=None, repr=False)
    render_seconds: float = 0.0

    def key(self, x: Sequence[float]) -> tuple[float, ...]:
        return tuple(round(float(v), self.decimals) for v in np.clip(x, 0.0, 1.0))

    def sketch_at(self, x: Sequence[float], turn: float = 0.0) -> np.ndarray:
        """The uint8 sketch of the tree at ``x`` (drawn at :func:`draw_side` of the
        target's size), seen from the point's yaw turned by ``turn`` degrees (another
        view's)."""
        from render.sketch import SketchRenderer, sketch_mesh

        k = self.key(x)
        scene_key = k[: len(self.space.dims)]
        if self._scene_key != scene_key or self._renderer is None:
            skeleton = grow(self.space.to_params(x))
            name = self.space.species
            if self.fast:
                mesh = sketch_mesh(skeleton, self.target.size, name)
                self._renderer = SketchRenderer(mesh, engine="raster")
            else:
                self._renderer = SketchRenderer(build_mesh(skeleton, species=name))
            self._scene_key = scene_key
        yaw = (self.space.yaw(x) + turn) % 360.0
        return self._renderer.sketch(yaw, draw_side(self.target.size))

    def loss_of_sketch(self, img: np.ndarray, target: Any = None) -> float:
        """Distance of a candidate's rendered sketch to the target (or another view's
        ``target``), framed as the target was; a tree too small to draw anything gets
        the largest distance."""
        target = self.target if target is None else target
        size = target.size
        try:
            cand = make_target(framed_sketch(img, size), size, self.metric, self.embedder)
        except SketchError:
            blank = np.full((size, size), 255, np.uint8)
            return search_distance(target, make_target(blank, size, self.metric, self.embedder))
        return search_distance(target, cand)

    def view_losses_at(self, x: Sequence[float]) -> tuple[float, ...]:
        """The sketch distance of every view (the first, then the others) at ``x``."""
        first = self.loss_of_sketch(self.sketch_at(x))
        rest = [self.loss_of_sketch(self.sketch_at(x, turn), t) for t, turn in self.others]
        return (first, *rest)

    def view_losses(self, x: Sequence[float]) -> tuple[float, ...]:
        """Every view's sketch distance at ``x`` (remembered when it was evaluated)."""
        k = self.key(x)
        return self._view_losses[k] if k in self._view_losses else self.view_losses_at(k)

    def penalty(self, x: Sequence[float]) -> float:
        """``yaw_weight * (turn / 180)^2`` for a searched yaw ``turn`` degrees away from
        ``yaw_prior``: a view other than the assumed one must fit clearly better (many
        trees look alike from every side, and a noise-picked view turns the whole tree)."""
        if self.yaw_weight <= 0 or not self.space.search_yaw:
            return 0.0
        turn = abs((self.space.yaw(x) - self.yaw_prior + 180.0) % 360.0 - 180.0) / 180.0
        return self.yaw_weight * turn * turn

    def sketch_loss(self, x: Sequence[float]) -> float:
        """The sketch distance alone (no penalties) at a point evaluated in this space."""
        return self._sketch_losses[self.key(x)]

    def cached(self, x: Sequence[float]) -> float | None:
        """The loss already computed at ``x`` (same rounded point), or None."""
        return self._cache.get(self.key(x))

    @property
    def cache_size(self) -> int:
        return len(self._cache)

    def __call__(self, x: Sequence[float]) -> float:
        k = self.key(x)
        hit = self._cache.get(k)
        if hit is not None:
            return hit
        t0 = time.perf_counter()
        views = self.view_losses_at(k)
        sketch_loss = float(np.mean(views)) if len(views) > 1 else views[0]
        self.render_seconds += time.perf_counter() - t0
        loss = sketch_loss + self.penalty(k)
        self._cache[k] = loss
        self._sketch_losses[k] = sketch_loss
        self._view_losses[k] = views
        self.evaluations += 1
        if loss < self.best_loss:
            self.best_loss = loss
            self.best_sketch_loss = sketch_loss
            self.best_x = np.asarray(k, dtype=np.float64)
            self.best_params = self.space.to_params(k)
            self.best_yaw = self.space.yaw(k)
        self.trace.append((self.evaluations, loss, self.best_loss))
        return loss
