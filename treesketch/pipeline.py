"""The main job: a sketch of a tree -> TSN estimate -> refinement -> parameters and mesh.

``predict_then_refine(sketch)`` prepares the sketch as TSN's ``predict`` does, asks the
network for a first estimate (parameters and species), then lets ``refine.refine`` move
the species' free values and the view yaw until the tree's sketch matches the input.

When no TSN checkpoint is available (``model=None`` and ``tsn.predict`` cannot load one)
the first estimate is a template match: three sampled trees per species are sketched
from four yaws and the closest one starts the search.  ``Result.estimator`` says which.

A sketch that does not look like a tree is not an error of the program: a blank page
raises :class:`SketchError`; anything else (a circle, noise) gives a result whose
``confidence`` is low and whose ``warning`` says so.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from refine.objective import SketchTarget, prepare_sketch, sketch_distance
from refine.search import START_YAWS, RefineResult
from refine.search import refine as refine_search
from weberpenn import TreeParams, build_mesh, grow, species

__all__ = [
    "DEFAULT_BUDGET",
    "DEFAULT_TIME_LIMIT",
    "LOW_CONFIDENCE_LOSS",
    "Result",
    "SketchError",
    "load_sketch",
    "predict_then_refine",
    "rescale_height",
]

DEFAULT_BUDGET = 100
DEFAULT_TIME_LIMIT = 50.0
SKETCH_SIZE = 256  # the size sketches are prepared and compared at (TSN's input size)
SEARCH_SIZE = 128  # the size the refinement loop renders at
LOW_CONFIDENCE_LOSS = 0.6  # sketch distance above which the result is flagged
_MIN_INK = 2e-4  # fraction of dark pixels below which the page counts as blank


class SketchError(ValueError):
    """The input is not a usable sketch (unreadable, blank, wrong shape)."""


@dataclass(frozen=True)
class Result:
    params: TreeParams
    species: str
    tree_mesh: Any
    sketch_before: np.ndarray  # uint8 sketch of the first estimate (TSN / template)
    sketch_after: np.ndarray  # uint8 sketch of the returned tree
    losses: dict[str, float]  # "before", "after"
    timings: dict[str, float]  # seconds per stage
    yaw: float = 0.0
    input_sketch: np.ndarray | None = None  # uint8, prepared (SKETCH_SIZE square)
    estimator: str = "tsn"
    refinement: RefineResult | None = None
    confidence: float = 1.0
    warning: str | None = None
    extras: dict[str, Any] = field(default_factory=dict)

    @property
    def low_confidence(self) -> bool:
        return self.warning is not None


def load_sketch(source: Any) -> np.ndarray:
    """A sketch from a path, bytes, a PIL image or an array -> (H, W) uint8, 255 = white."""
    from PIL import Image, UnidentifiedImageError

    try:
        if isinstance(source, str | Path):
            path = Path(source)
            if not path.is_file():
                raise SketchError(f"sketch file not found: {path}")
            with Image.open(path) as im:
                return _to_grey(im)
        if isinstance(source, bytes | bytearray):
            import io

            with Image.open(io.BytesIO(bytes(source))) as im:
                return _to_grey(im)
        if isinstance(source, Image.Image):
            return _to_grey(source)
    except (UnidentifiedImageError, OSError) as exc:
        raise SketchError(f"cannot read the sketch as an image: {exc}") from exc
    a = np.asarray(source)
    if a.dtype == object or a.ndim not in (2, 3):
        raise SketchError(f"a sketch must be a 2-D image, got shape {a.shape}")
    return np.round(_grey_float(a) * 255).astype(np.uint8)


def _grey_float(a: np.ndarray) -> np.ndarray:
    scale = 255.0 if a.dtype == np.uint8 else 1.0
    f = np.asarray(a, dtype=np.float32) / scale
    if f.ndim == 3:
        f = f[..., :3].mean(axis=2)
    if f.ndim != 2 or min(f.shape) < 8:
        raise SketchError(f"a sketch must be a 2-D image at least 8x8, got shape {a.shape}")
    if not np.all(np.isfinite(f)):
        raise SketchError("the sketch holds non-finite values")
    return np.clip(f, 0.0, 1.0)


def _to_grey(im: Any) -> np.ndarray:
    from PIL import Image

    im.load()
    if im.mode in ("RGBA", "LA", "PA") or (im.mode == "P" and "transparency" in im.info):
        bg = Image.new("RGBA", im.size, (255, 255, 255, 255))
        bg.alpha_composite(im.convert("RGBA"))
        im = bg
    return np.asarray(im.convert("L"), dtype=np.uint8)


def _prepare_input(img: np.ndarray) -> np.ndarray:
    """The refinement target: the sketch padded to a square (white) and area-resized to
    SKETCH_SIZE, in its own framing.  TSN's ``preprocess`` is not used here: it crops to
    the drawing (``tsn.predict.predict`` does that itself), while the refinement renders
    with the dataset's camera framing, which the target must keep."""
    h, w = img.shape
    n = max(h, w)
    sq = np.full((n, n), 255, np.uint8)
    sq[(n - h) // 2 : (n - h) // 2 + h, (n - w) // 2 : (n - w) // 2 + w] = img
    return prepare_uint8(sq)


def prepare_uint8(img: np.ndarray) -> np.ndarray:
    return np.round(prepare_sketch(img, SKETCH_SIZE) * 255).astype(np.uint8)


def _load_model(model: Any) -> Any:
    if model is not None:
        return model
    try:
        from tsn import predict as tsn_predict  # type: ignore[attr-defined]

        return tsn_predict.load_model()
    except Exception:  # noqa: BLE001 - no network yet: fall back to template matching
        return None


def _tsn_estimate(model: Any, img: np.ndarray) -> tuple[TreeParams, str]:
    """Ask TSN for (params, species); accepts the shapes tsn.predict may return."""
    import inspect

    if inspect.isfunction(model) or inspect.ismethod(model):  # a plain estimator function
        out = model(img)
    else:
        from tsn import predict as tsn_predict  # type: ignore[attr-defined]

        fn = getattr(tsn_predict, "predict", None)
        out = fn(model, img) if callable(fn) else model(img)
    if isinstance(out, tuple) and len(out) >= 2:
        params, name = out[0], out[1]
    elif hasattr(out, "params"):
        params, name = out.params, getattr(out, "species", None)
    else:
        params, name = out, None
    if not isinstance(params, TreeParams):
        params = TreeParams(params)
    if not name:
        from refine.search import guess_species

        name = guess_species(params)
    name = species.canonical(str(name))
    return species.project(name, params), name


def _template_estimate(img: np.ndarray, seeds: int = 3) -> tuple[TreeParams, str, float]:
    """Closest of ``seeds`` sampled trees per species, each seen from four yaws (no
    network needed; the species vary a lot within themselves, so one tree each is not
    enough)."""
    from refine.objective import target_distance
    from render.sketch import SketchRenderer

    target = SketchTarget.from_image(img, SEARCH_SIZE)
    best: tuple[float, str, int, float] = (math.inf, species.SPECIES[0], 0, 0.0)
    for name in species.SPECIES:
        for seed in range(seeds):
            r = SketchRenderer(build_mesh(grow(species.sample(name, seed)), species=name))
            for yaw in START_YAWS[:4]:
                cand = SketchTarget.from_image(r.sketch(yaw, SEARCH_SIZE), SEARCH_SIZE)
                d = target_distance(target, cand)
                if d < best[0]:
                    best = (d, name, seed, yaw)
    return species.sample(best[1], best[2]), best[1], best[3]


def tree_height(params: TreeParams) -> float:
    mesh = build_mesh(grow(params))
    lo, hi = mesh.bounds()
    return float(np.asarray(hi)[2] - np.asarray(lo)[2])


def rescale_height(params: TreeParams, height: float) -> TreeParams:
    """Scale ``scale`` and ``scaleV`` so the grown tree is ``height`` tall (metres)."""
    if not (isinstance(height, int | float) and math.isfinite(height) and height > 0):
        raise ValueError(f"height must be a positive number of metres, got {height!r}")
    current = tree_height(params)
    if current <= 0:
        raise ValueError("the tree has no height to rescale")
    f = float(height) / current
    out = params.replace(scale=float(params["scale"]) * f, scaleV=float(params["scaleV"]) * f)
    # leaf size and radii follow scale in Weber-Penn; one correction pass for any
    # non-linearity (e.g. a clipped value)
    again = tree_height(out)
    if again > 0 and abs(again - height) / height > 0.01:
        g = float(height) / again
        out = out.replace(scale=float(out["scale"]) * g, scaleV=float(out["scaleV"]) * g)
    return out


def predict_then_refine(
    sketch: Any,
    *,
    refine: bool = True,
    budget: int = DEFAULT_BUDGET,
    time_limit: float | None = DEFAULT_TIME_LIMIT,
    height: float | None = None,
    model: Any = None,
    progress: Callable[[int, float], None] | None = None,
    algorithm: str = "bobyqa",
    seed: int = 0,
) -> Result:
    """Sketch (path, bytes, image or array) -> :class:`Result` (see the module text).

    ``model``: a loaded TSN model, a function ``image -> (params, species)``, the string
    ``"template"`` (no network), or None to load the shipped checkpoint (falling back to
    the template match when there is none).
    """
    from render.sketch import SketchRenderer

    timings: dict[str, float] = {}
    t = time.perf_counter()
    img = _prepare_input(load_sketch(sketch))
    ink = float((img < 128).mean())
    if ink < _MIN_INK:
        raise SketchError("the sketch is blank: draw a tree (dark lines on a light page)")
    timings["prepare"] = time.perf_counter() - t

    t = time.perf_counter()
    net = None if isinstance(model, str) and model == "template" else _load_model(model)
    yaw0 = 0.0
    if net is not None:
        params0, name = _tsn_estimate(net, img)
        estimator = "tsn"
    else:
        params0, name, yaw0 = _template_estimate(img)
        estimator = "template"
    timings["estimate"] = time.perf_counter() - t

    t = time.perf_counter()
    result_refine: RefineResult | None = None
    if refine:
        result_refine = refine_search(
            img,
            params0,
            budget=budget,
            algorithm=algorithm,
            time_limit=time_limit,
            seed=seed,
            progress=progress,
            species=name,
            size=SEARCH_SIZE,
        )
        params1, yaw1 = result_refine.params, result_refine.yaw
        yaw0 = result_refine.start_yaw
    else:
        params1, yaw1 = params0, yaw0
    timings["refine"] = time.perf_counter() - t

    t = time.perf_counter()
    mesh0 = build_mesh(grow(params0), species=name)
    before = SketchRenderer(mesh0).sketch(yaw0, SKETCH_SIZE)
    if params1 is params0:
        mesh1, after = mesh0, before
    else:
        mesh1 = build_mesh(grow(params1), species=name)
        after = SketchRenderer(mesh1).sketch(yaw1, SKETCH_SIZE)
    loss_before = sketch_distance(img, before, SEARCH_SIZE)
    loss_after = sketch_distance(img, after, SEARCH_SIZE)
    if result_refine is not None:
        loss_before, loss_after = result_refine.loss_before, result_refine.loss_after
    timings["render"] = time.perf_counter() - t

    if height is not None:
        t = time.perf_counter()
        params1 = rescale_height(params1, float(height))
        mesh1 = build_mesh(grow(params1), species=name)
        timings["height"] = time.perf_counter() - t

    confidence = float(math.exp(-max(0.0, loss_after) / LOW_CONFIDENCE_LOSS))
    warning = None
    if loss_after > LOW_CONFIDENCE_LOSS:
        warning = (
            f"low confidence: the best tree's sketch is far from the input "
            f"(distance {loss_after:.3f} > {LOW_CONFIDENCE_LOSS}); is this a sketch of a tree?"
        )
    timings["total"] = sum(timings.values())
    return Result(
        params=params1,
        species=name,
        tree_mesh=mesh1,
        sketch_before=before,
        sketch_after=after,
        losses={"before": float(loss_before), "after": float(loss_after)},
        timings=timings,
        yaw=float(yaw1),
        input_sketch=img,
        estimator=estimator,
        refinement=result_refine,
        confidence=confidence,
        warning=warning,
        extras={"ink": ink},
    )
