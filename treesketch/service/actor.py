"""A service worker as a Ray actor: loads the estimator once, then runs the jobs it is given.

The Ray pool (``ray_pool``) calls, from its dispatcher thread:

- ``ready()`` -> ``{"node", "actor", "pid", "error"}``, answered once the estimator is loaded
  (``error``: why it could not be; None when it is);
- ``run(job_id, options, drawings)`` (the job's drawings' bytes, in order) ->
  ``{"state": "done", "summary", "files"}``,
  ``{"state": "cancelled"}`` or ``{"state": "failed", "message", "input"}`` (``input``: the
  sketch or an option was at fault, not the program);
- ``poll(job_id, seen)`` -> the job's latest progress (the dict the API shows) or None;
  when the job's current best tree (``preview.PreviewWriter``, made here in memory) is
  newer than the version ``seen`` by the front, the row carries its version
  (``preview``) and files (``preview_files``), which the front writes for the page;
- ``cancel(job_id)``: the run stops at its next evaluation.

The actor is threaded (``max_concurrency`` > 1) so that ``poll`` and ``cancel`` are
answered while ``run`` works.  It returns the artefacts' bytes rather than writing them:
a cluster's nodes share no disk with the HTTP front, which writes them into its data
folder.  Nothing here imports Ray; the pool makes the class remote.
"""

from __future__ import annotations

import gc
import json
import os
import threading
import time
import traceback
from typing import Any

from .preview import PreviewWriter
from .progress import ProgressRows
from .worker import WORKER_NICE, progress_info

__all__ = ["JobActor"]


class JobActor:
    """One warm worker: a :class:`~treesketch.service.runner.Runner` for ``spec``."""

    def __init__(self, spec: str) -> None:
        from .runner import Runner

        # below the HTTP front when they share a machine
        os.nice(WORKER_NICE)
        self.error: str | None = None
        try:
            self.runner: Runner | None = Runner(spec)
        except Exception as exc:  # noqa: BLE001 - told to the pool by ready()
            self.runner = None
            self.error = f"cannot load the estimator {spec!r}: {exc}"
        self._progress = ProgressRows()
        self._lock = threading.Lock()  # of _cancelled
        self._cancelled: set[str] = set()  # by job id: a cancel may overtake its run
        self._previews: dict[str, tuple[int, dict[str, bytes]]] = {}  # job id -> the latest

    def ready(self) -> dict[str, Any]:
        import ray

        ctx = ray.get_runtime_context()
        return {
            "node": ctx.get_node_id(),
            "actor": ctx.get_actor_id(),
            "pid": os.getpid(),
            "error": self.error,
        }

    def poll(self, job_id: str, seen: int = 0) -> dict[str, Any] | None:
        row = self._progress.get(job_id)
        if row is None:
            return None
        with self._lock:
            made = self._previews.get(job_id)
        if made is not None and made[0] > seen:
            row["preview"], row["preview_files"] = made
        return row

    def cancel(self, job_id: str) -> None:
        with self._lock:
            self._cancelled.add(job_id)

    def run(self, job_id: str, options: dict[str, Any], drawings: list[bytes]) -> dict[str, Any]:
        from treesketch import Cancelled

        from .runner import JobOptions

        if self.runner is None:
            return {"state": "failed", "message": self.error, "input": False}
        t0 = time.perf_counter()
        preview = PreviewWriter(None)

        def progress(p: Any) -> None:
            shown = preview.offer(p)
            if shown is not None:
                with self._lock:
                    self._previews[job_id] = (shown, preview.files)
            self._progress.put(job_id, progress_info(p, time.perf_counter() - t0))

        def cancelled() -> bool:
            with self._lock:
                return job_id in self._cancelled

        try:
            opts = JobOptions.from_dict(options)
            files, summary = self.runner.run(drawings, opts, progress, cancelled)
            summary = json.loads(json.dumps(summary, default=float))  # plain JSON types
            summary["timings"]["job"] = time.perf_counter() - t0
            return {"state": "done", "summary": summary, "files": files}
        except Cancelled:
            return {"state": "cancelled"}
        except ValueError as exc:  # SketchError and option errors: the input's fault
            return {"state": "failed", "message": str(exc), "input": True}
        except Exception as exc:  # noqa: BLE001 - one bad job must not end the worker
            traceback.print_exc()
            return {"state": "failed", "message": f"{type(exc).__name__}: {exc}", "input": False}
        finally:
            self._progress.end(job_id)
            with self._lock:
                self._cancelled.discard(job_id)
                self._previews.pop(job_id, None)
            gc.collect()
