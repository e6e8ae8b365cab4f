"""Evaluation: 1-RMSE per head, Hausdorff distance, the rotation sweep, the report."""

from .hausdorff import Distance, tree_hausdorff
from .metrics import Scores, one_minus_rmse
from .rotation import rotation_sweep
from .scoring import Scorer, tsn_scorer

__all__ = [
    "Distance",
    "Scorer",
    "Scores",
    "one_minus_rmse",
    "rotation_sweep",
    "tree_hausdorff",
    "tsn_scorer",
]
