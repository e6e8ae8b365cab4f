"""Plain data between ``grow`` (the algorithm) and ``build_mesh`` (the geometry)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True, eq=False)
class Skeleton:
    """A grown tree: Bezier stems (splines) and leaf placements, all numpy arrays.

    Stem ``i`` owns control points ``points[offsets[i]:offsets[i+1]]`` with radii
    ``radii[...]`` (at least 2 points each).  Curves are cubic Beziers through their
    control points with Blender's AUTO handles, except that the first point of every
    spline uses VECTOR handles (as Sapling sets it); ``build_mesh`` evaluates them with
    ``res_u`` samples per segment and a round cross-section of ``4 + 2*bevel_res`` sides.
    Split clones are separate stems (``parents`` gives the stem they branch from, -1 for
    the trunk).  Leaf ``j`` is the leaf template (``leaf_shape``: 'hex' or 'rect', one
    unit tall along +Y, centred on X, base at the origin) transformed by
    ``leaf_matrices[j]`` (3x3, rotation times scale) and moved to ``leaf_positions[j]``.
    Z is up; the trunk starts at the origin.
    """

    points: np.ndarray  # (P, 3) float64
    radii: np.ndarray  # (P,) float64
    offsets: np.ndarray  # (S + 1,) int64
    levels: np.ndarray  # (S,) int64, 0 = trunk
    parents: np.ndarray  # (S,) int64, -1 = none
    leaf_positions: np.ndarray  # (L, 3) float64
    leaf_matrices: np.ndarray  # (L, 3, 3) float64
    leaf_shape: str
    res_u: int
    bevel_res: int

    @property
    def n_stems(self) -> int:
        return int(len(self.offsets) - 1)

    @property
    def n_leaves(self) -> int:
        return int(len(self.leaf_positions))

    def stem(self, i: int) -> tuple[np.ndarray, np.ndarray]:
        """Control points and radii of stem ``i``."""
        a, b = int(self.offsets[i]), int(self.offsets[i + 1])
        return self.points[a:b], self.radii[a:b]

    def stems_per_level(self) -> np.ndarray:
        """Number of stems (splines, split clones included) at each level."""
        if self.n_stems == 0:
            return np.zeros(0, dtype=np.int64)
        return np.bincount(self.levels, minlength=int(self.levels.max()) + 1)

    def bounds(self) -> np.ndarray:
        """(2, 3) axis-aligned bounds of the control points and leaf positions."""
        pts = self.points if self.n_leaves == 0 else np.vstack([self.points, self.leaf_positions])
        return np.array([pts.min(axis=0), pts.max(axis=0)])
