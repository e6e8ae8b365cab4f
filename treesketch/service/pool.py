"""The worker pool: N spawned worker processes fed from the job store by one thread.

The dispatcher thread is the only writer of job states once a job runs: it claims the
oldest queued job for each idle worker, relays progress (kept in memory for the events
stream and saved to the store at most once a second), records results, and watches the
processes.  A worker that dies (kill -9, out of memory) fails its job with a message and
is replaced; a worker that has not stopped ``cancel_grace`` seconds after a cancel is
killed and replaced.  The HTTP front never waits on any of this.  The bookkeeping is
``poolbase.BasePool``'s, shared with the Ray pool.
"""

from __future__ import annotations

import contextlib
import multiprocessing as mp
import os
import sqlite3
import sys
import time
from collections import deque
from dataclasses import dataclass
from multiprocessing.connection import Connection, wait
from typing import Any

from .poolbase import RESPAWN_BACKOFF, BasePool, Slot
from .store import Job, JobStore, is_full

__all__ = ["WorkerPool", "default_workers"]


@dataclass(kw_only=True)
class _Worker(Slot):
    process: Any
    conn: Connection
    cancel: Any  # multiprocessing.Value('b')


class WorkerPool(BasePool):
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
        super().__init__(
            store, workers, estimator, cancel_grace, retention, sweep_every, respawn_backoff
        )
        self._ctx = mp.get_context("spawn")
        self._inbox: deque[tuple[_Worker, tuple[str, Any, Any]]] = deque()
        self._wake_r, self._wake_w = self._ctx.Pipe(duplex=False)

    # -- life --------------------------------------------------------------------------
    def stop(self, timeout: float = 5.0) -> None:
        self._stop_thread(timeout)
        for w in self._slots:
            w.cancel.value = 1  # a running job stops at its next evaluation
            with contextlib.suppress(OSError):
                w.conn.send(None)
        deadline = time.monotonic() + timeout
        for w in self._slots:
            w.process.join(max(0.0, deadline - time.monotonic()))
            if w.process.is_alive():
                w.process.kill()
                w.process.join(1.0)
        self._slots = []

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

    def _retire(self, w: _Worker) -> None:
        w.conn.close()

    # -- requests from the HTTP side (any thread) --------------------------------------
    def wakeup(self) -> None:
        """A job was queued: look now rather than at the next tick."""
        with contextlib.suppress(OSError):
            self._wake_w.send_bytes(b".")

    def _signal_cancel(self, w: _Worker, job_id: str) -> None:
        w.cancel.value = 1  # seen by the worker at its next evaluation

    def status(self) -> list[dict[str, Any]]:
        with self._lock:
            return [
                {
                    "pid": w.process.pid,
                    "alive": w.process.is_alive(),
                    "ready": w.ready,
                    "job": w.job,
                }
                for w in self._slots
            ]

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
            for w in self._slots:
                if w.process.is_alive():  # a dead one's sentinel would never block
                    waitables += [w.conn, w.process.sentinel]
        ready = wait(waitables, timeout=0.2)
        if self._wake_r in ready:
            while self._wake_r.poll():
                self._wake_r.recv_bytes()
        for i in range(len(self._slots)):
            self._drain(self._slots[i])
            self._deliver()  # a worker's last answer before its death is seen
            if not self._slots[i].process.is_alive() and not self.broken:
                self._replace(i)
        self._enforce_cancels()
        return self._sweep(last_sweep)

    def _idle(self, w: _Worker) -> bool:
        return super()._idle(w) and w.process.is_alive()

    def _run(self, w: _Worker, job: Job) -> None:
        w.cancel.value = 0  # (no cancel can name this job before _begin gives it to w)
        self._begin(w, job)
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
        elif kind == "broken":
            self.error = str(payload)
        elif kind == "progress":
            self._live.update(job_id, payload)
        else:  # done, cancelled or failed
            self._record(job_id, kind, payload)
            self._release(w, job_id)

    def _replace(self, i: int) -> None:
        w = self._slots[i]
        code = w.process.exitcode
        if w.job is not None:
            self._fail_lost(
                w,
                w.job,
                f"the worker process died while running this job (exit code {code}); "
                "submit it again",
            )
            self._release(w, w.job)
        if not w.ready:  # died while loading: retry a few times, slowly, then give up
            self.error = self.error or f"a worker exited while loading (exit code {code})"
            self._load_failures += 1
        self._renew(i, slow=not w.ready)

    def _kill(self, w: _Worker) -> None:
        w.process.kill()  # _replace records the job as cancelled
        w.process.join(1.0)


def default_workers() -> int:
    """One worker per core, at least one."""
    return max(1, len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else 1)
