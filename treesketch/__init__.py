"""TreeSketch: draw a tree, get a 3D Weber-Penn tree.

The front door::

    from treesketch import predict_then_refine
    result = predict_then_refine("my_sketch.png", budget=40)
    result.species, result.params, result.tree_mesh

or, keeping the model loaded between sketches::

    from treesketch import Pipeline, RefineSettings
    pipeline = Pipeline("tsn", RefineSettings(budget=40))
    result = pipeline.run("my_sketch.png", height=8.0)
"""

from refine.search import Cancelled, RefineSettings
from render.reader import SketchError

from .estimate import Estimate, Estimator
from .estimators import load_estimator
from .outputs import result_files, write_outputs
from .pipeline import Pipeline, Progress, Result, load_sketch, predict_then_refine

__all__ = [
    "Cancelled",
    "Estimate",
    "Estimator",
    "Pipeline",
    "Progress",
    "RefineSettings",
    "Result",
    "SketchError",
    "load_estimator",
    "load_sketch",
    "predict_then_refine",
    "result_files",
    "write_outputs",
]
