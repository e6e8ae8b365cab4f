"""The worker process: loads the estimator once, then runs the jobs it is sent.

It talks to the pool over one duplex pipe.  In: ``(job_id, options dict)`` or ``None``
(stop).  Out: ``("ready", pid)`` once loaded, then per job any number of
``("progress", job_id, {...})`` and one of ``("done", job_id, summary)``,
``("cancelled", job_id, "")`` or ``("failed", job_id, {"message", "input"})`` (``input``:
the sketch or an option was at fault, not the program).

Cancelling: the pool sets the shared ``cancel`` value to 1; the pipeline's progress
callback sees it at the next evaluation and the run stops.  The worker writes the job's
artefacts itself (``results/<id>/``, all or nothing) so that no big bytes cross the pipe.
"""

from __future__ import annotations

import contextlib
import gc
import json
import math
import shutil
import time
import traceback
from multiprocessing.connection import Connection
from pathlib import Path
from typing import Any

from .preview import PreviewWriter

__all__ = ["progress_info", "worker_main"]

WORKER_NICE = 5
PROGRESS_EVERY = 0.1  # seconds between progress messages (the pipe is cheap, the DB is not)


class _Reporter:
    """The progress callback of one job: at most one message per PROGRESS_EVERY, and the
    current best tree written for the page (``preview.PreviewWriter``)."""

    def __init__(
        self, conn: Connection, job_id: str, t0: float, preview: PreviewWriter | None = None
    ) -> None:
        self.conn, self.job_id, self.t0, self.preview = conn, job_id, t0, preview
        self.last, self.stage = 0.0, ""

    def __call__(self, p: Any) -> None:
        """``p``: a ``treesketch.Progress``; a new stage and a new preview are always
        told."""
        shown = None if self.preview is None else self.preview.offer(p)
        now = time.perf_counter()
        if shown is not None or p.stage != self.stage or now - self.last >= PROGRESS_EVERY:
            self.last, self.stage = now, p.stage
            info = progress_info(p, now - self.t0)
            if shown is not None:
                info["preview"] = shown
            self.conn.send(("progress", self.job_id, info))


def progress_info(p: Any, elapsed: float) -> dict[str, Any]:
    """A ``treesketch.Progress`` as the plain dict the pool keeps and the API shows
    (``budget``: the run's whole plan, which ``evaluations`` never passes)."""
    best = p.best_loss if math.isfinite(p.best_loss) else None
    return {
        "stage": p.stage,
        "evaluations": p.evaluations,
        "budget": p.budget,
        "best_loss": best,
        "elapsed": elapsed,
    }


def worker_main(spec: str, conn: Connection, cancel: Any, root: str) -> None:
    """Entry point of a spawned worker (``cancel``: a shared ``multiprocessing.Value``)."""
    import os

    from treesketch import Cancelled
    from weberpenn.fileio import write_together

    from .runner import JobOptions, Runner
    from .store import is_full, upload_name

    # below the HTTP front: a status poll must not wait behind a refinement for a core
    os.nice(WORKER_NICE)
    try:
        runner = Runner(spec)
    except Exception as exc:  # noqa: BLE001 - reported to the pool, which shows it
        conn.send(("broken", 0, f"cannot load the estimator {spec!r}: {exc}"))
        return
    conn.send(("ready", os.getpid(), ""))
    results = Path(root) / "results"
    uploads = Path(root) / "uploads"
    while True:
        try:
            msg = conn.recv()
        except (EOFError, OSError):  # the pool went away
            return
        if msg is None:
            return
        job_id, options = msg
        t0 = time.perf_counter()
        out = results / job_id
        progress = _Reporter(conn, job_id, t0, PreviewWriter(out / "preview"))
        reply: tuple[str, str, Any]
        full = False
        try:
            opts = JobOptions.from_dict(options)
            drawings = [
                (uploads / upload_name(job_id, v)).read_bytes() for v in range(1, opts.views + 1)
            ]
            files, summary = runner.run(drawings, opts, progress, lambda: bool(cancel.value))
            summary = json.loads(json.dumps(summary, default=float))  # plain JSON types
            write_together({out / name: data for name, data in files.items()})
            summary["timings"]["job"] = time.perf_counter() - t0
            reply = ("done", job_id, summary)
        except Cancelled:
            reply = ("cancelled", job_id, "")
        except ValueError as exc:  # SketchError and option errors: the input's fault
            reply = ("failed", job_id, {"message": str(exc), "input": True})
        except Exception as exc:  # noqa: BLE001 - one bad job must not end the worker
            full = is_full(exc)
            if full:
                message = f"storage full: the results could not be saved ({exc})"
            else:
                traceback.print_exc()
                message = f"{type(exc).__name__}: {exc}"
            reply = ("failed", job_id, {"message": message, "input": False})
        if full:  # the disk is full: its previews go too
            shutil.rmtree(out, ignore_errors=True)
        elif reply[0] != "done":  # no empty folder left (its previews stay on show)
            for folder in (out / "preview", out):
                with contextlib.suppress(OSError):
                    folder.rmdir()
        conn.send(reply)
        gc.collect()
