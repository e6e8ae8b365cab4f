"""Tree mesh -> synthetic sketch (the paper's "SG sketch"), and colour previews.

``sketch(tree_mesh, yaw=0.0, size=256)`` is the one-shot function.  For many views of the
same tree (dataset builder, refinement loop, rotation sweep) use
:class:`SketchRenderer`, which builds the mitsuba scenes once::

    r = SketchRenderer(tree_mesh)
    for yaw in range(0, 360, 5):
        img = r.sketch(yaw, size=256)   # (256, 256) uint8, 255 = white

An empty tree (no faces at all) gives an all-white image.  The same mesh and arguments
give identical pixels.

``engine="raster"`` draws the silhouettes with :mod:`render.raster` (numpy, no
acceleration structure to build) instead of mitsuba: the same sample grid, so the same
sketch up to samples that lie exactly on a triangle edge, at a fraction of the cost of a
tree drawn once or twice (the refinement loop).  Datasets and outputs use mitsuba.
:func:`sample_width` is the world width of one silhouette sample: stems thinner than it
cannot survive the branch thinning (``weberpenn.lod.drop_thin_stems``).
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from typing import Any

import numpy as np

from .camera import VIEWS, Framing, check_size, resolve_yaw
from .edges import EdgeConfig, branch_sketch, combine, foliage_sketch, thin_mask

__all__ = [
    "ENGINES",
    "VIEWS",
    "EdgeConfig",
    "SketchParts",
    "SketchRenderer",
    "sample_width",
    "sketch",
    "sketch_mesh",
]

ENGINES = ("mitsuba", "raster")


@dataclass(frozen=True)
class SketchParts:
    """A sketch and the intermediate images it came from (all float 0..1, 1 = white)."""

    sketch: np.ndarray  # uint8
    branch_silhouette: np.ndarray
    leaf_silhouette: np.ndarray
    branch_edges: np.ndarray
    foliage_edges: np.ndarray


class SketchRenderer:
    """Keeps a tree's mitsuba scenes; renders sketches and colour pictures for any yaw."""

    def __init__(
        self,
        tree_mesh: Any,
        config: EdgeConfig | None = None,
        framing: Framing | None = None,
        species: str | None = None,
        engine: str = "mitsuba",
    ) -> None:
        """``framing`` overrides the tree's own framing; ``species`` (for the colour
        render's bark and leaf colours) overrides ``tree_mesh.species``; ``engine`` is
        one of :data:`ENGINES` (``"raster"`` draws sketches only, no colour)."""
        if engine not in ENGINES:
            raise ValueError(f"unknown engine {engine!r}; choose one of {', '.join(ENGINES)}")
        if not (hasattr(tree_mesh, "branches") and hasattr(tree_mesh, "leaves")):
            raise TypeError(
                f"expected a TreeMesh (with .branches and .leaves), got {type(tree_mesh).__name__}"
            )
        self.config = config or EdgeConfig()
        self.engine = engine
        if engine == "raster":
            from .raster import RasterScene

            self.scene: Any = RasterScene(tree_mesh, framing)
        else:
            from .silhouette import TreeScene  # mitsuba is imported only when rendering

            self.scene = TreeScene(tree_mesh, framing, species)

    @property
    def framing(self) -> Framing:
        return self.scene.framing

    @property
    def variant(self) -> str:
        """The mitsuba variant drawing the silhouettes, or ``"raster"``."""
        return "raster" if self.engine == "raster" else self.scene.backend.variant

    def parts(self, yaw: float | str = 0.0, size: int = 256, pitch: float = 0.0) -> SketchParts:
        """The sketch and its intermediate images.

        Sketches smaller than ``config.reference_size`` are drawn at the reference size
        and area-averaged down (the intermediate images stay at the reference size), so a
        128-pixel sketch is exactly a downsized 256-pixel one; larger ones are drawn at
        their own size with the pixel constants scaled up.
        """
        size = check_size(size)
        cfg = self.config
        work = max(size, int(cfg.reference_size))
        ss = int(cfg.supersample)
        yaw_deg = resolve_yaw(yaw)
        if self.scene.is_empty:
            self.scene.coverage(yaw_deg, size, ss, pitch)  # validates the arguments
            white = np.ones((work, work), dtype=np.float32)
            return SketchParts(np.full((size, size), 255, np.uint8), white, white, white, white)
        cov = self.scene.coverage(
            yaw_deg, work, ss, pitch, keep_hr=True, leaf_supersample=cfg.leaf_supersample
        )
        assert cov.branches_hr is not None
        leaf_sil = 1.0 - cov.leaves
        # the two chains side by side (scipy's filters let go of the GIL): a refinement
        # draws a hundred sketches per drawing, each chain a few milliseconds
        with ThreadPoolExecutor(1) as pool:
            foliage = pool.submit(foliage_sketch, leaf_sil, cfg)
            branch_sil = 1.0 - thin_mask(cov.branches_hr, ss, cfg.px(cfg.branch_thin_px, work))
            b = branch_sketch(branch_sil, cfg)
            f = foliage.result()
        out = b * f
        if work != size:
            out = _area_resize(out, size)
        return SketchParts(combine(out, np.float32(1.0)), branch_sil, leaf_sil, b, f)

    def sketch(self, yaw: float | str = 0.0, size: int = 256, pitch: float = 0.0) -> np.ndarray:
        """(size, size) uint8 sketch, 255 = white background, dark lines."""
        return self.parts(yaw, size, pitch).sketch

    def colour(
        self,
        yaw: float | str = 0.0,
        size: int = 256,
        pitch: float = 0.0,
        supersample: int | None = None,
    ) -> np.ndarray:
        """(size, size, 3) uint8 shaded picture with the species' bark and leaf colours
        (``supersample``^2 rays per pixel; default ``config.supersample``)."""
        if self.engine != "mitsuba":
            raise ValueError(f"colour pictures need engine='mitsuba', not {self.engine!r}")
        size = check_size(size)
        ss = int(self.config.supersample if supersample is None else supersample)
        if not 1 <= ss <= 8:
            raise ValueError(f"supersample must be in 1..8, got {supersample!r}")
        return self.scene.colour(resolve_yaw(yaw), size, ss, pitch)


def sample_width(framing: Framing, size: int, config: EdgeConfig | None = None) -> float:
    """World width of one branch-silhouette sample of a ``size`` px sketch in ``framing``,
    or 0.0 when the chain does not thin the branches.

    The branch thinning erodes the sample mask by a square of ``k + 1`` samples (k >= 1),
    so a sample survives only inside a 2 x 2 block of covered samples, which no stem
    narrower than one sample spacing can hold on its own: such stems leave no trace in
    the sketch except where they touch other branches.
    """
    cfg = config or EdgeConfig()
    work = max(check_size(size), int(cfg.reference_size))
    ss = int(cfg.supersample)
    if int(round(2.0 * cfg.px(cfg.branch_thin_px, work) * ss)) < 1:
        return 0.0
    return framing.span / (work * ss)


def sketch_mesh(
    skeleton: Any,
    size: int,
    species: str | None = None,
    config: EdgeConfig | None = None,
    cut: float | None = None,
) -> Any:
    """The lightest TreeMesh of a grown ``skeleton`` that draws the same ``size`` px
    sketch: its stems thinner than half a :func:`sample_width` are left out
    (``weberpenn.lod.drop_thin_stems``; less for the species whose twigs darken the
    silhouette together, ``weberpenn.species.sketch_stem_cut``); every kept stem and every leaf is meshed as
    ``build_mesh`` meshes them.

    The sample width comes from a framing of the skeleton's control points and leaf
    positions, which lie inside the full mesh, so it is never wider than the full
    tree's own: the cut errs on the side of keeping stems.  ``cut``: another share of
    the sample width to cut at (``refine.start``'s outlines cut more).
    """
    from weberpenn import build_mesh
    from weberpenn import species as wp_species
    from weberpenn.lod import drop_thin_stems

    framing = Framing.from_parts([skeleton.points, skeleton.leaf_positions])
    width = sample_width(framing, size, config)
    # a species whose sub-pixel twigs darken its silhouette together keeps more of them
    if cut is None:
        cut = 0.5 if species is None else wp_species.sketch_stem_cut(species)
    return build_mesh(drop_thin_stems(skeleton, cut * width), species=species)


def _area_resize(img: np.ndarray, size: int) -> np.ndarray:
    """Area-average (box filter) resize of a float image to ``size`` x ``size``."""
    n = img.shape[0]
    if n % size == 0:
        k = n // size
        return img.reshape(size, k, size, k).mean(axis=(1, 3), dtype=np.float32)
    from PIL import Image

    im = Image.fromarray(np.ascontiguousarray(img, dtype=np.float32), mode="F")
    return np.asarray(im.resize((size, size), Image.Resampling.BOX), dtype=np.float32)


def sketch(
    tree_mesh: Any,
    yaw: float | str = 0.0,
    size: int = 256,
    config: EdgeConfig | None = None,
    pitch: float = 0.0,
) -> np.ndarray:
    """One sketch of ``tree_mesh`` seen from ``yaw`` degrees (or a view name)."""
    return SketchRenderer(tree_mesh, config).sketch(yaw, size, pitch)
