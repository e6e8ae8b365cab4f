"""What a worker does with one job: the pipeline run and the artefact files.

This is the only module of the service that touches the pipeline.  ``load_runner(spec)``
loads the estimator once per worker process; ``Runner.run`` turns a stored sketch and the
job's options into artefact bytes and a JSON-able summary.

The estimator ``spec`` is ``"tsn"`` (the shipped checkpoint), ``"template"`` (no network),
a checkpoint path, or ``"package.module:name"`` naming a callable ``image -> (params,
species)`` (how tests and researchers plug in their own without touching the service).
"""

from __future__ import annotations

import importlib
import tempfile
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

__all__ = ["ARTEFACTS", "Cancelled", "JobOptions", "Runner", "load_runner"]

# file name -> media type, in the order the page offers them
ARTEFACTS: dict[str, str] = {
    "tree.glb": "model/gltf-binary",
    "tree.json": "application/json",
    "tree_sapling.py": "text/x-python",
    "compare.png": "image/png",
    "sketch_before.png": "image/png",
    "sketch_after.png": "image/png",
}


class Cancelled(Exception):
    """The job's cancel flag was raised; the run stopped."""


@dataclass(frozen=True)
class JobOptions:
    """A job's options, validated (see ``limits.parse_options``)."""

    refine: bool = True
    budget: int = 100
    time_limit: float | None = 50.0
    height: float | None = None
    estimator: str = "tsn"  # a spec the server allows (see ``Runner``)

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> JobOptions:
        return cls(**d)


def _import(spec: str) -> Any:
    module, _, name = spec.partition(":")
    obj: Any = importlib.import_module(module)
    for part in name.split("."):
        obj = getattr(obj, part)
    return obj


def _estimator(spec: str) -> Any:
    """The ``model`` argument of the pipeline for this spec, loaded once."""
    if spec == "template":
        return "template"
    if ":" in spec and not Path(spec).exists():
        return _import(spec)
    from tsn.predict import load_model

    return load_model(None if spec == "tsn" else spec)


def _png(img: Any) -> bytes:
    import io

    import numpy as np
    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(np.asarray(img, dtype=np.uint8)).save(buf, format="PNG")
    return buf.getvalue()


def artefact_bytes(result: Any) -> dict[str, bytes]:
    """Every artefact of a result, as bytes keyed by file name."""
    from treesketch.cli_predict import compare_image
    from weberpenn.export import export_mesh, save_sapling_preset
    from weberpenn.params import save_params

    with tempfile.TemporaryDirectory(prefix="treesketch-job-") as d:
        tmp = Path(d)
        export_mesh(result.tree_mesh, tmp / "tree.glb")
        save_params(result.params, tmp / "tree.json")
        save_sapling_preset(result.params, tmp / "tree_sapling.py")
        files = {name: (tmp / name).read_bytes() for name in ARTEFACTS if (tmp / name).exists()}
    files["compare.png"] = _png(compare_image(result))
    files["sketch_before.png"] = _png(result.sketch_before)
    files["sketch_after.png"] = _png(result.sketch_after)
    return files


def summary(result: Any) -> dict[str, Any]:
    """The JSON-able description of a result that ``GET /jobs/{id}`` shows."""
    r = result.refinement
    scores = getattr(result, "species_scores", None) or result.extras.get("species_scores", {})
    return {
        "species": result.species,
        "species_scores": {str(k): float(v) for k, v in dict(scores).items()},
        "estimator": result.estimator,
        "params": result.params.to_dict(),
        "losses": {k: float(v) for k, v in result.losses.items()},
        "yaw": float(result.yaw),
        "confidence": float(result.confidence),
        "warning": result.warning,
        "timings": {k: float(v) for k, v in result.timings.items()},
        "evaluations": 0 if r is None else int(r.evaluations),
    }


class Runner:
    """One worker's pipeline: the default estimator loaded once, at start; another that
    a job asks for (from the server's short allowed list) loaded on first use and kept."""

    def __init__(self, spec: str) -> None:
        self.spec = spec
        self.models: dict[str, Any] = {spec: _estimator(spec)}

    def model(self, spec: str) -> Any:
        if spec not in self.models:
            self.models[spec] = _estimator(spec)
        return self.models[spec]

    def run(
        self,
        sketch: bytes,
        options: JobOptions,
        progress: Callable[[int, float], None],
        cancel: Callable[[], bool],
    ) -> tuple[dict[str, bytes], dict[str, Any]]:
        """(artefacts, summary) of one job; raises ``Cancelled`` soon after ``cancel()``
        turns True, ``ValueError`` (``SketchError``) for a sketch or option the pipeline
        rejects."""
        from treesketch.pipeline import predict_then_refine

        def on_progress(evaluations: int, best: float) -> None:
            if cancel():
                raise Cancelled("cancelled")
            progress(evaluations, best)

        if cancel():
            raise Cancelled("cancelled")
        result = predict_then_refine(
            sketch,
            refine=options.refine,
            budget=options.budget,
            time_limit=options.time_limit,
            height=options.height,
            model=self.model(options.estimator),
            progress=on_progress,
        )
        if cancel():
            raise Cancelled("cancelled")
        return artefact_bytes(result), summary(result)


def load_runner(spec: str) -> Runner:
    return Runner(spec)
