"""The worker pool: N spawned worker processes fed from the job store by one thread.

The dispatcher thread is the only writer of job states once a job runs: it claims the
oldest queued job for each idle worker, relays progress (kept in memory for the events
stream and saved to the store at most once a second), records results, and watches the
processes.  A worker that dies (kill -9, out of memory) fails its job with a message and
is replaced; a worker that has not stopped ``cancel_grace`` seconds after a cancel is
killed and replaced.  The HTTP front never waits on any of this.
"""

from __future__ import annotations

import contextlib
import multiprocessing as mp
import os
import threading
import time
from dataclasses import dataclass, field
from multiprocessing.connection import Connection, wait
from typing import Any

from .store import JobStore

__all__ = ["WorkerPool"]

SAVE_PROGRESS_EVERY = 1.0
RESPAWN_BACKOFF = 5.0  # seconds before retrying a worker that could not load its model


@dataclass
class _Worker:
    process: Any
    conn: Connection
    cancel: Any  # multiprocessing.Value('b')
    ready: bool = False
    job: str | None = None
    job_started: float = 0.0
    cancel_at: float | None = None
    saved_at: float = 0.0
    pending: dict[str, Any] = field(default_factory=dict)


class WorkerPool:
    """``start()``, ``submit_wakeup()``, ``cancel(job_id)``, ``live(job_id)``, ``stop()``."""

    def __init__(
        self,
        store: JobStore,
        workers: int,
        estimator: str,
        cancel_grace: float = 3.0,
        retention: tuple[float | None, int | None] = (None, None),
        sweep_every: float = 60.0,
    ) -> None:
        if workers < 1:
            raise ValueError(f"workers must be at least 1, got {workers}")
        self.store = store
        self.n = workers
        self.estimator = estimator
        self.cancel_grace = cancel_grace
        self.retention = retention
        self.sweep_every = sweep_every
        self._ctx = mp.get_context("spawn")
        self._workers: list[_Worker] = []
        self._lock = threading.Lock()
        self._live: dict[str, dict[str, Any]] = {}
        self._wake_r, self._wake_w = self._ctx.Pipe(duplex=False)
        self._stopping = threading.Event()
        self._thread: threading.Thread | None = None
        self.error: str | None = None  # the last worker start-up failure
        self.replaced = 0  # workers replaced after dying

    # -- life --------------------------------------------------------------------------
    def start(self) -> None:
        self.store.recover()
        self._workers = [self._spawn() for _ in range(self.n)]
        self._thread = threading.Thread(target=self._loop, name="treesketch-pool", daemon=True)
        self._thread.start()

    def stop(self, timeout: float = 5.0) -> None:
        self._stopping.set()
        self.wakeup()
        if self._thread is not None:
            self._thread.join(timeout)
        for w in self._workers:
            w.cancel.value = 1  # a running job stops at its next evaluation
            with contextlib.suppress(OSError):
                w.conn.send(None)
        deadline = time.monotonic() + timeout
        for w in self._workers:
            w.process.join(max(0.0, deadline - time.monotonic()))
            if w.process.is_alive():
                w.process.kill()
                w.process.join(1.0)
        self._workers = []

    def _spawn(self) -> _Worker:
        from .worker import worker_main

        parent, child = self._ctx.Pipe(duplex=True)
        flag = self._ctx.Value("b", 0, lock=False)
        proc = self._ctx.Process(
            target=worker_main,
            args=(self.estimator, child, flag, str(self.store.root)),
            name="treesketch-worker",
            daemon=True,
        )
        proc.start()
        child.close()
        return _Worker(process=proc, conn=parent, cancel=flag)

    # -- requests from the HTTP side (any thread) --------------------------------------
    def wakeup(self) -> None:
        """A job was queued: look now rather than at the next tick."""
        with contextlib.suppress(OSError):
            self._wake_w.send_bytes(b".")

    def cancel(self, job_id: str) -> bool:
        """Raise the cancel flag of the worker running ``job_id``; False if none runs it."""
        with self._lock:
            for w in self._workers:
                if w.job == job_id:
                    w.cancel.value = 1
                    if w.cancel_at is None:
                        w.cancel_at = time.monotonic()
                    return True
        return False

    def live(self, job_id: str) -> dict[str, Any] | None:
        with self._lock:
            p = self._live.get(job_id)
            return None if p is None else dict(p)

    def status(self) -> list[dict[str, Any]]:
        with self._lock:
            return [
                {
                    "pid": w.process.pid,
                    "alive": w.process.is_alive(),
                    "ready": w.ready,
                    "job": w.job,
                }
                for w in self._workers
            ]

    def busy(self) -> int:
        with self._lock:
            return sum(w.job is not None for w in self._workers)

    # -- the dispatcher thread ---------------------------------------------------------
    def _loop(self) -> None:
        last_sweep = 0.0
        while not self._stopping.is_set():
            self._assign()
            waitables: list[Any] = [self._wake_r]
            with self._lock:
                for w in self._workers:
                    waitables += [w.conn, w.process.sentinel]
            ready = wait(waitables, timeout=0.2)
            if self._wake_r in ready:
                while self._wake_r.poll():
                    self._wake_r.recv_bytes()
            for i in range(len(self._workers)):
                self._drain(self._workers[i])
                if not self._workers[i].process.is_alive():
                    self._replace(i)
            self._enforce_cancels()
            if time.monotonic() - last_sweep > self.sweep_every:
                last_sweep = time.monotonic()
                self.store.expire(*self.retention)

    def _assign(self) -> None:
        for w in self._workers:
            if w.ready and w.job is None and w.process.is_alive():
                job = self.store.claim_next()
                if job is None:
                    return
                with self._lock:
                    w.cancel.value = 0
                    w.job, w.job_started, w.cancel_at = job.id, time.monotonic(), None
                    self._live[job.id] = {
                        "evaluations": 0,
                        "budget": int(job.options.get("budget", 0)),
                        "best_loss": None,
                        "elapsed": 0.0,
                        "stage": "start",
                    }
                # a dying process fails the send; _replace then fails the job
                with contextlib.suppress(OSError):
                    w.conn.send((job.id, job.options))

    def _drain(self, w: _Worker) -> None:
        try:
            while w.conn.poll():
                kind, job_id, payload = w.conn.recv()
                self._handle(w, kind, job_id, payload)
        except (EOFError, OSError):
            pass

    def _handle(self, w: _Worker, kind: str, job_id: Any, payload: Any) -> None:
        if kind == "ready":
            w.ready = True
            return
        if kind == "broken":
            self.error = str(payload)
            return
        if kind == "progress":
            with self._lock:
                live = self._live.get(job_id)
                if live is not None:
                    live.update(payload)
            if time.monotonic() - w.saved_at > SAVE_PROGRESS_EVERY:
                w.saved_at = time.monotonic()
                budget = live["budget"] if live else None
                self.store.set_progress(job_id, {**payload, "budget": budget})
            return
        if kind == "done":
            self.store.finish(job_id, payload)
        elif kind == "cancelled":
            self.store.fail(job_id, "cancelled", state="cancelled")
        elif kind == "failed":
            self.store.fail(job_id, str(payload["message"]), input_error=bool(payload["input"]))
        with self._lock:
            w.job, w.cancel_at = None, None
            self._live.pop(job_id, None)

    def _replace(self, i: int) -> None:
        w = self._workers[i]
        code = w.process.exitcode
        if w.job is not None:
            if w.cancel_at is not None:
                self.store.fail(w.job, "cancelled", state="cancelled")
            else:
                self.store.fail(
                    w.job,
                    f"the worker process died while running this job (exit code {code}); "
                    "submit it again",
                )
            with self._lock:
                self._live.pop(w.job, None)
        if not w.ready:  # died while loading: do not spin
            self.error = self.error or f"a worker exited while loading (exit code {code})"
            self._stopping.wait(RESPAWN_BACKOFF)
        w.conn.close()
        fresh = self._spawn()
        with self._lock:
            self._workers[i] = fresh
            self.replaced += 1

    def _enforce_cancels(self) -> None:
        now = time.monotonic()
        for w in self._workers:
            if w.cancel_at is not None and now - w.cancel_at > self.cancel_grace:
                w.process.kill()  # _replace records the job as cancelled
                w.process.join(1.0)


def default_workers() -> int:
    """One worker per core, at least one."""
    return max(1, len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else 1)
