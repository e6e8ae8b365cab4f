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
import sqlite3
import sys
import threading
import time
from collections import deque
from dataclasses import dataclass
from multiprocessing.connection import Connection, wait
from typing import Any

from .progress import LiveProgress
from .store import JobStore, is_full

__all__ = ["WorkerPool"]

RESPAWN_BACKOFF = 5.0  # seconds before retrying a worker that could not load its model
LOAD_ATTEMPTS = 3  # failed loads in a row after which the pool gives up (``broken``)


@dataclass
class _Worker:
    process: Any
    conn: Connection
    cancel: Any  # multiprocessing.Value('b')
    ready: bool = False
    job: str | None = None
    job_started: float = 0.0
    cancel_at: float | None = None


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
        respawn_backoff: float = RESPAWN_BACKOFF,
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
        self._live = LiveProgress(store)
        self._inbox: deque[tuple[_Worker, tuple[str, Any, Any]]] = deque()
        self._wake_r, self._wake_w = self._ctx.Pipe(duplex=False)
        self._stopping = threading.Event()
        self._thread: threading.Thread | None = None
        self.respawn_backoff = respawn_backoff
        self.error: str | None = None  # the last worker start-up failure
        self._load_failures = 0
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
        return self._live.get(job_id)

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

    @property
    def broken(self) -> bool:
        """True when workers failed to load the estimator LOAD_ATTEMPTS times in a row."""
        return self._load_failures >= LOAD_ATTEMPTS

    def busy(self) -> int:
        with self._lock:
            return sum(w.job is not None for w in self._workers)

    # -- the dispatcher thread ---------------------------------------------------------
    def _loop(self) -> None:
        last_sweep = 0.0
        while not self._stopping.is_set():
            try:
                last_sweep = self._tick(last_sweep)
            except sqlite3.Error as exc:
                # the job database could not be written (a full disk): the thread must
                # live on; what was not saved waits in the inbox and is tried again
                if is_full(exc):
                    self.store.mark_full()
                print(f"treesketch: the job database cannot be written: {exc}", file=sys.stderr)
                self._stopping.wait(1.0)

    def _tick(self, last_sweep: float) -> float:
        """One round of the dispatcher; returns when it last swept."""
        if self._inbox:  # left from a round whose database write failed
            self._deliver()
        self._assign()
        waitables: list[Any] = [self._wake_r]
        with self._lock:
            for w in self._workers:
                if w.process.is_alive():  # a dead one's sentinel would never block
                    waitables += [w.conn, w.process.sentinel]
        ready = wait(waitables, timeout=0.2)
        if self._wake_r in ready:
            while self._wake_r.poll():
                self._wake_r.recv_bytes()
        for i in range(len(self._workers)):
            self._drain(self._workers[i])
            self._deliver()  # a worker's last answer before its death is seen
            if not self._workers[i].process.is_alive() and not self.broken:
                self._replace(i)
        self._enforce_cancels()
        if time.monotonic() - last_sweep > self.sweep_every:
            last_sweep = time.monotonic()
            self.store.expire(*self.retention)
        return last_sweep

    def _assign(self) -> None:
        for w in self._workers:
            if w.ready and w.job is None and w.process.is_alive():
                job = self.store.claim_next()
                if job is None:
                    return
                self._live.begin(job.id, job.options)
                with self._lock:
                    w.cancel.value = 0
                    w.job, w.job_started, w.cancel_at = job.id, time.monotonic(), None
                # a dying process fails the send; _replace then fails the job
                with contextlib.suppress(OSError):
                    w.conn.send((job.id, job.options))

    def _drain(self, w: _Worker) -> None:
        """Move what the worker sent into the inbox."""
        try:
            while w.conn.poll():
                self._inbox.append((w, w.conn.recv()))
        except (EOFError, OSError):
            pass

    def _deliver(self) -> None:
        """Handle the inbox in order; a message leaves it only once handled (saved)."""
        while self._inbox:
            w, (kind, job_id, payload) = self._inbox[0]
            self._handle(w, kind, job_id, payload)
            self._inbox.popleft()

    def _handle(self, w: _Worker, kind: str, job_id: Any, payload: Any) -> None:
        if kind == "ready":
            w.ready = True
            self._load_failures = 0
            return
        if kind == "broken":
            self.error = str(payload)
            return
        if kind == "progress":
            self._live.update(job_id, payload)
            return
        if kind == "done":
            self.store.finish(job_id, payload)
        elif kind == "cancelled":
            self.store.fail(job_id, "cancelled", state="cancelled")
        elif kind == "failed":
            self.store.fail(job_id, str(payload["message"]), input_error=bool(payload["input"]))
        with self._lock:
            w.job, w.cancel_at = None, None
        self._live.end(job_id)

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
            self._live.end(w.job)
        if not w.ready:  # died while loading: retry a few times, slowly, then give up
            self.error = self.error or f"a worker exited while loading (exit code {code})"
            self._load_failures += 1
            if self.broken:
                return
            self._stopping.wait(self.respawn_backoff)
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
