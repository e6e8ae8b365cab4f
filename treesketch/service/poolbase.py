"""The bookkeeping both worker pools share (``pool.WorkerPool``: local processes,
``ray_pool.RayWorkerPool``: Ray actors): which slot runs which job, cancels and their
grace, the jobs' end in the store, progress in memory, replacing a lost worker and
giving up after ``LOAD_ATTEMPTS`` failed loads, the retention sweep, and the dispatcher
thread's life.

A pool subclass says how its workers start (``_spawn``), take a job (``_run``), are
told to cancel (``_signal_cancel``), are killed (``_kill``) and let go of (``_retire``),
and what its dispatcher does each round (``_loop``).  The dispatcher thread is the only
writer of job states once a job runs; the HTTP side only reads (``live``, ``status``,
``busy``) and raises cancel flags (``cancel``).
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass
from typing import Any

from .progress import LiveProgress
from .store import Job, JobStore

__all__ = ["LOAD_ATTEMPTS", "RESPAWN_BACKOFF", "BasePool", "Slot"]

RESPAWN_BACKOFF = 5.0  # seconds before retrying a worker that could not load its model
LOAD_ATTEMPTS = 3  # failed loads in a row after which the pool gives up (``broken``)


@dataclass(kw_only=True)
class Slot:
    """One worker as the dispatcher sees it."""

    ready: bool = False  # loaded its model and free to take jobs
    job: str | None = None  # the job it runs
    cancel_at: float | None = None  # when that job was asked to stop
    killed: bool = False  # killed by the pool (a cancel past its grace, or given up)


class BasePool:
    """``start()``, ``stop()``, ``wakeup()``, ``cancel(job_id)``, ``live(job_id)``,
    ``busy()``, ``broken``, ``error`` (the last worker start-up failure) and ``replaced``
    (workers replaced after dying)."""

    thread_name = "treesketch-pool"

    def __init__(
        self,
        store: JobStore,
        workers: int,
        estimator: str,
        cancel_grace: float,
        retention: tuple[float | None, int | None],
        sweep_every: float,
        respawn_backoff: float,
    ) -> None:
        self.store = store
        self.n = workers
        self.estimator = estimator
        self.cancel_grace = cancel_grace
        self.retention = retention
        self.sweep_every = sweep_every
        self.respawn_backoff = respawn_backoff
        self.error: str | None = None
        self.replaced = 0
        self._load_failures = 0
        self._slots: list[Any] = []
        self._lock = threading.Lock()
        self._live = LiveProgress(store)
        self._stopping = threading.Event()
        self._thread: threading.Thread | None = None

    # -- what a pool says ---------------------------------------------------------------
    def _spawn(self) -> Slot:
        raise NotImplementedError

    def _run(self, slot: Any, job: Job) -> None:
        """Send ``job`` to ``slot`` (after ``_begin``)."""
        raise NotImplementedError

    def _signal_cancel(self, slot: Any, job_id: str) -> None:
        raise NotImplementedError

    def _kill(self, slot: Any) -> None:
        raise NotImplementedError

    def _retire(self, slot: Any) -> None:
        """Let go of a lost or failed worker before it is replaced."""

    def _loop(self) -> None:
        raise NotImplementedError

    def wakeup(self) -> None:
        """A job was queued: look now rather than at the next tick."""
        raise NotImplementedError

    # -- life --------------------------------------------------------------------------
    def start(self) -> None:
        self.store.recover()
        self._slots = [self._spawn() for _ in range(self.n)]
        self._thread = threading.Thread(target=self._loop, name=self.thread_name, daemon=True)
        self._thread.start()

    def _stop_thread(self, timeout: float) -> None:
        self._stopping.set()
        self.wakeup()
        if self._thread is not None:
            self._thread.join(timeout)

    # -- requests from the HTTP side (any thread) --------------------------------------
    def cancel(self, job_id: str) -> bool:
        """Ask the worker running ``job_id`` to stop; False if none runs it."""
        with self._lock:
            for s in self._slots:
                if s.job == job_id:
                    if s.cancel_at is None:
                        s.cancel_at = time.monotonic()
                        self._signal_cancel(s, job_id)
                    return True
        return False

    def live(self, job_id: str) -> dict[str, Any] | None:
        return self._live.get(job_id)

    @property
    def broken(self) -> bool:
        """True when workers failed to load the estimator LOAD_ATTEMPTS times in a row."""
        return self._load_failures >= LOAD_ATTEMPTS

    def busy(self) -> int:
        with self._lock:
            return sum(s.job is not None for s in self._slots)

    # -- the dispatcher thread ---------------------------------------------------------
    def _idle(self, slot: Any) -> bool:
        return slot.ready and slot.job is None

    def _assign(self) -> None:
        """The oldest queued jobs to the idle workers."""
        for s in self._slots:
            if self._idle(s):
                job = self.store.claim_next()
                if job is None:
                    return
                self._run(s, job)

    def _begin(self, slot: Any, job: Job) -> None:
        self._live.begin(job.id, job.options)
        with self._lock:
            slot.job, slot.cancel_at = job.id, None

    def _record(self, job_id: str, state: str, info: Any) -> None:
        """A job's end as its worker reported it: ``done`` (``info``: the summary),
        ``cancelled``, or failed (``info``: ``message`` and whether the input was at fault)."""
        if state == "done":
            self.store.finish(job_id, info)
        elif state == "cancelled":
            self.store.fail(job_id, "cancelled", state="cancelled")
        else:
            self.store.fail(job_id, str(info["message"]), input_error=bool(info["input"]))

    def _fail_lost(self, slot: Any, job_id: str, message: str) -> None:
        """The worker running ``job_id`` is gone: a job asked to stop was cancelled, any
        other fails with ``message``."""
        if slot.cancel_at is not None:
            self.store.fail(job_id, "cancelled", state="cancelled")
        else:
            self.store.fail(job_id, message)

    def _release(self, slot: Any, job_id: str) -> None:
        with self._lock:
            slot.job, slot.cancel_at = None, None
        self._live.end(job_id)

    def _renew(self, i: int, slow: bool = False) -> None:
        """A new worker for slot ``i``; ``slow``: after a failed load, wait first, and
        leave the slot dead once the pool is broken."""
        old = self._slots[i]
        self._retire(old)
        if slow:
            if self.broken:
                with self._lock:
                    old.killed, old.ready = True, False
                return
            self._stopping.wait(self.respawn_backoff)
        fresh = self._spawn()
        with self._lock:
            self._slots[i] = fresh
            self.replaced += 1

    def _enforce_cancels(self) -> None:
        """Kill the workers still running a job ``cancel_grace`` seconds after its cancel
        (the pool then records the job as cancelled)."""
        now = time.monotonic()
        for s in self._slots:
            if s.cancel_at is not None and not s.killed and now - s.cancel_at > self.cancel_grace:
                s.killed = True
                self._kill(s)

    def _sweep(self, last: float) -> float:
        """The retention sweep, when ``sweep_every`` seconds have passed since ``last``;
        returns when it last ran."""
        if time.monotonic() - last > self.sweep_every:
            last = time.monotonic()
            self.store.expire(*self.retention)
        return last
