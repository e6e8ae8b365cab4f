"""Refinement: the sketch distance and the nlopt search over a species' unfixed values."""

from .objective import (
    OtherView,
    PreparedDrawing,
    SearchSpace,
    SketchObjective,
    SketchTarget,
    sketch_distance,
)
from .search import Cancelled, RefineResult, RefineSettings, guess_species, refine

__all__ = [
    "Cancelled",
    "OtherView",
    "PreparedDrawing",
    "RefineResult",
    "RefineSettings",
    "SearchSpace",
    "SketchObjective",
    "SketchTarget",
    "guess_species",
    "refine",
    "sketch_distance",
]
