"""The running jobs' progress, shared by the local and the Ray worker pools.

Kept in memory for the events stream and ``/jobs/{id}`` (every update), saved to the job
store at most once every :data:`SAVE_PROGRESS_EVERY` seconds per job (the store is a
SQLite file: a write per evaluation would slow every reader).  :class:`ProgressRows`, the
latest row per job in memory, also keeps a Ray actor's jobs for the pool's polls.
"""

from __future__ import annotations

import threading
import time
from typing import Any

from .store import JobStore

__all__ = ["SAVE_PROGRESS_EVERY", "LiveProgress", "ProgressRows"]

SAVE_PROGRESS_EVERY = 1.0


class ProgressRows:
    """The latest progress row of each running job: ``put(job, row)``, ``get(job)`` (a
    copy, None when there is none), ``end(job)``; any thread."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._rows: dict[str, dict[str, Any]] = {}

    def put(self, job_id: str, row: dict[str, Any]) -> None:
        with self._lock:
            self._rows[job_id] = row

    def get(self, job_id: str) -> dict[str, Any] | None:
        with self._lock:
            row = self._rows.get(job_id)
            return None if row is None else dict(row)

    def end(self, job_id: str) -> None:
        with self._lock:
            self._rows.pop(job_id, None)


class LiveProgress(ProgressRows):
    """``begin(job, options)``, ``update(job, info)``, ``get(job)``, ``end(job)``; any
    thread."""

    def __init__(self, store: JobStore, save_every: float = SAVE_PROGRESS_EVERY) -> None:
        super().__init__()
        self.store = store
        self.save_every = float(save_every)
        self._saved: dict[str, float] = {}

    def begin(self, job_id: str, options: dict[str, Any]) -> None:
        """A job starts running: its row before the first report."""
        with self._lock:
            self._rows[job_id] = {
                "evaluations": 0,
                "budget": int(options.get("budget", 0)),
                "best_loss": None,
                "elapsed": 0.0,
                "stage": "start",
            }
            self._saved[job_id] = -float("inf")  # the first report is saved at once

    def update(self, job_id: str, info: dict[str, Any]) -> None:
        """A report from the worker running ``job_id`` (ignored once the job has ended)."""
        now = time.monotonic()
        with self._lock:
            row = self._rows.get(job_id)
            if row is None:
                return
            row.update(info)
            due = now - self._saved[job_id] > self.save_every
            if due:
                self._saved[job_id] = now
            snapshot = dict(row)
        if due:
            self.store.set_progress(job_id, snapshot)

    def end(self, job_id: str) -> None:
        with self._lock:
            self._rows.pop(job_id, None)
            self._saved.pop(job_id, None)
