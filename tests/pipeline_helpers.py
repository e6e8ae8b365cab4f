"""Stand-ins the pipeline tests share: a tree's own sketch and a fixed estimator."""

from __future__ import annotations

import numpy as np

from treesketch import Estimate
from weberpenn import build_mesh, grow, species


def gt_sketch(name: str = "palm", seed: int = 3, yaw: float = 0.0) -> np.ndarray:
    from render.sketch import SketchRenderer

    return SketchRenderer(build_mesh(grow(species.sample(name, seed)), species=name)).sketch(
        yaw, 256
    )


class Fixed:
    """A stand-in estimator: always the same sampled tree."""

    def __init__(self, name: str, seed: int) -> None:
        self.name = "fixed"
        self.tree = species.sample(name, seed)
        self.species = name
        self.calls = 0

    def estimate(self, sketch: np.ndarray) -> Estimate:
        self.calls += 1
        assert sketch.dtype == np.uint8 and sketch.shape == (256, 256)
        return Estimate(self.tree, self.species, {self.species: 1.0})
