"""HTTP service: ``create_app()`` -> FastAPI app.

- ``GET /health``: ``{"status": "ok", "estimator": "tsn" | "template"}``.
- ``POST /predict`` (multipart: ``sketch`` image file; form fields ``refine``, ``budget``,
  ``time_limit``, ``height``): JSON with ``species``, ``params`` (the 70-key dictionary),
  ``losses``, ``confidence``, ``warning``, ``yaw``, ``timings`` and ``glb`` (the URL of
  the tree's GLB).
- ``GET /trees/{tree_id}.glb``: the GLB of a recent prediction (the last ``keep`` trees are
  kept in memory).

The TSN model is loaded once, when the app is made.  Requests are served one at a time
(the renderer and the generator are CPU-bound).  Bad uploads are answered 400 (not an
image) or 422 (blank page, bad options) with a message, never a traceback.
"""

import tempfile
import threading
import uuid
from collections import OrderedDict
from pathlib import Path
from typing import Any

from fastapi import FastAPI, File, Form, HTTPException, UploadFile
from fastapi.responses import Response

__all__ = ["MAX_BUDGET", "MAX_UPLOAD_BYTES", "create_app"]

MAX_UPLOAD_BYTES = 10 * 1024 * 1024
MAX_BUDGET = 1000
MAX_TIME_LIMIT = 600.0


def _glb_bytes(tree_mesh: Any) -> bytes:
    from weberpenn.export import export_mesh

    with tempfile.TemporaryDirectory(prefix="treesketch-") as d:
        path = export_mesh(tree_mesh, Path(d) / "tree.glb")
        return path.read_bytes()


def create_app(model: Any = None, keep: int = 16, default_budget: int | None = None) -> FastAPI:
    """The FastAPI app.  ``model``: an estimator or its name (``load_estimator``), or None
    for the shipped TSN checkpoint."""
    from .estimators import load_estimator
    from .pipeline import Pipeline, RefineSettings, SketchError

    estimator = load_estimator("tsn" if model is None else model)
    defaults = RefineSettings()
    budget_default = int(default_budget or defaults.budget)
    trees: OrderedDict[str, bytes] = OrderedDict()
    lock = threading.Lock()

    app = FastAPI(title="TreeSketch", description="A sketch of a tree -> a 3D Weber-Penn tree.")
    app.state.model = estimator
    app.state.trees = trees

    @app.get("/health")
    def health() -> dict[str, str]:
        return {
            "status": "ok",
            "estimator": estimator.name,
        }

    @app.post("/predict")
    def predict(
        sketch: UploadFile = File(..., description="The sketch image (PNG/JPEG)."),
        refine: bool = Form(True),
        budget: int | None = Form(None),
        time_limit: float | None = Form(None),
        height: float | None = Form(None),
    ) -> dict[str, Any]:
        data = sketch.file.read(MAX_UPLOAD_BYTES + 1)
        if len(data) > MAX_UPLOAD_BYTES:
            raise HTTPException(413, f"the sketch is over {MAX_UPLOAD_BYTES} bytes")
        if not data:
            raise HTTPException(400, "the uploaded sketch is empty")
        n = budget_default if budget is None else int(budget)
        if not 1 <= n <= MAX_BUDGET:
            raise HTTPException(422, f"budget must be in 1..{MAX_BUDGET}, got {n}")
        seconds = defaults.time_limit if time_limit is None else float(time_limit)
        if not 0 < seconds <= MAX_TIME_LIMIT:
            raise HTTPException(422, f"time_limit must be in (0, {MAX_TIME_LIMIT}], got {seconds}")
        if height is not None and not height > 0:
            raise HTTPException(422, f"height must be positive metres, got {height}")
        with lock:
            try:
                settings = defaults.replace(refine=refine, budget=n, time_limit=seconds)
                result = Pipeline(estimator, settings).run(data, height=height)
            except SketchError as exc:
                status = 400 if "not an image" in str(exc) or "damaged" in str(exc) else 422
                raise HTTPException(status, str(exc)) from exc
            except ValueError as exc:
                raise HTTPException(422, str(exc)) from exc
            tree_id = uuid.uuid4().hex
            trees[tree_id] = _glb_bytes(result.tree_mesh)
            while len(trees) > keep:
                trees.popitem(last=False)
        r = result.refinement
        return {
            "tree_id": tree_id,
            "species": result.species,
            "estimator": result.estimator,
            "params": result.params.to_dict(),
            "losses": result.losses,
            "confidence": result.confidence,
            "warning": result.warning,
            "yaw": result.yaw,
            "evaluations": 0 if r is None else r.evaluations,
            "timings": result.timings,
            "glb": f"/trees/{tree_id}.glb",
        }

    @app.get("/trees/{tree_id}.glb")
    def tree_glb(tree_id: str) -> Response:
        data = trees.get(tree_id)
        if data is None:
            raise HTTPException(404, f"no tree {tree_id!r} (only the last {keep} are kept)")
        return Response(
            data,
            media_type="model/gltf-binary",
            headers={"Content-Disposition": f'attachment; filename="tree_{tree_id[:8]}.glb"'},
        )

    return app
