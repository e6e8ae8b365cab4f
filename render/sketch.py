"""Tree mesh -> synthetic sketch (the paper's "SG sketch"), and colour previews.

``sketch(tree_mesh, yaw=0.0, size=256)`` is the one-shot function.  For many views of the
same tree (dataset builder, refinement loop, rotation sweep) use
:class:`SketchRenderer`, which builds the mitsuba scenes once::

    r = SketchRenderer(tree_mesh)
    for yaw in range(0, 360, 5):
        img = r.sketch(yaw, size=256)   # (256, 256) uint8, 255 = white

An empty tree (no faces at all) gives an all-white image.  The same mesh and arguments
give identical pixels.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .camera import VIEWS, Framing, _check_size, resolve_yaw
from .edges import EdgeConfig, branch_sketch, combine, foliage_sketch, thin_mask

__all__ = ["VIEWS", "EdgeConfig", "SketchParts", "SketchRenderer", "sketch"]


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
    ) -> None:
        from .silhouette import TreeScene  # mitsuba is imported only when rendering

        if not (hasattr(tree_mesh, "branches") and hasattr(tree_mesh, "leaves")):
            raise TypeError(
                f"expected a TreeMesh (with .branches and .leaves), got {type(tree_mesh).__name__}"
            )
        self.config = config or EdgeConfig()
        self.scene = TreeScene(tree_mesh, framing)

    @property
    def framing(self) -> Framing:
        return self.scene.framing

    @property
    def variant(self) -> str:
        return self.scene.backend.variant

    def parts(self, yaw: float | str = 0.0, size: int = 256, pitch: float = 0.0) -> SketchParts:
        size = _check_size(size)
        cfg = self.config
        ss = int(cfg.supersample)
        cov = self.scene.coverage(
            resolve_yaw(yaw), size, ss, pitch, keep_hr=True, leaf_supersample=cfg.leaf_supersample
        )
        thin = cfg.px(cfg.branch_thin_px, size)
        assert cov.branches_hr is not None
        branch_sil = 1.0 - thin_mask(cov.branches_hr, ss, thin)
        leaf_sil = 1.0 - cov.leaves
        if self.scene.is_empty:
            white = np.ones((size, size), dtype=np.float32)
            return SketchParts(np.full((size, size), 255, np.uint8), white, white, white, white)
        b = branch_sketch(branch_sil, cfg)
        f = foliage_sketch(leaf_sil, cfg)
        return SketchParts(combine(b, f), branch_sil, leaf_sil, b, f)

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
        size = _check_size(size)
        ss = int(self.config.supersample if supersample is None else supersample)
        if not 1 <= ss <= 8:
            raise ValueError(f"supersample must be in 1..8, got {supersample!r}")
        return self.scene.colour(resolve_yaw(yaw), size, ss, pitch)


def sketch(
    tree_mesh: Any,
    yaw: float | str = 0.0,
    size: int = 256,
    config: EdgeConfig | None = None,
    pitch: float = 0.0,
) -> np.ndarray:
    """One sketch of ``tree_mesh`` seen from ``yaw`` degrees (or a view name)."""
    return SketchRenderer(tree_mesh, config).sketch(yaw, size, pitch)
