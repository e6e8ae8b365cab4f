"""The worker pool on Ray: N actors (``actor.JobActor``, one CPU each) fed from the job
store by one dispatcher thread, so one HTTP front serves workers on several machines.

It has the local pool's interface (``start``, ``stop``, ``wakeup``, ``cancel``, ``live``,
``status``, ``busy``, ``broken``, ``error``, ``replaced``) and keeps its rules: the
dispatcher is the only writer of job states once a job runs; progress is kept in memory
for the events stream and saved to the store at most once a second; retention sweeps run
from the same thread.  How things cross to an actor:

- the job: its options and the uploaded drawings' bytes go with the ``run`` call;
- progress: the dispatcher polls each busy actor (``poll``) every ``POLL_EVERY`` seconds;
- cancel: ``cancel(job_id)`` raises the actor's flag for that job, seen at the next
  evaluation; an actor that has not stopped ``cancel_grace`` seconds later is killed;
- results: the actor returns the artefacts' bytes and the dispatcher writes them with the
  one atomic writer (``write_together``): the nodes need no disk shared with the front.

An actor lost mid-job (killed, out of memory, its node gone) costs one attempt: the job
goes back to the head of the queue and runs on another actor; lost a second time it is
failed with a message.  A job that fails for its own reason (a blank page) is reported,
never retried.  Lost actors are replaced; idle ones are probed every ``PROBE_EVERY``
seconds (and at once after a loss) so that a job is not sent to a dead one.
"""

from __future__ import annotations

import contextlib
import shutil
import threading
import time
import traceback
from dataclasses import dataclass
from typing import Any

from .pool import LOAD_ATTEMPTS, RESPAWN_BACKOFF
from .progress import LiveProgress
from .runner import JobOptions
from .store import JobStore, is_full

__all__ = ["MAX_ATTEMPTS", "RayWorkerPool"]

POLL_EVERY = 0.25  # seconds between progress polls of a busy actor
PROBE_EVERY = 5.0  # seconds between liveness probes of an idle actor
TICK = 0.1  # longest wait of the dispatcher (a submitted job waits at most this)
MAX_ATTEMPTS = 2  # runs of one job on actors that were lost under it


@dataclass
class _Actor:
    handle: Any
    ready_ref: Any  # the pending ready() probe, or None
    loaded: bool = False  # answered a probe once: a later lost probe is no load failure
    ready: bool = False
    node: str = ""
    actor: str = ""
    pid: int = 0
    probed_at: float = 0.0
    job: str | None = None
    attempt: int = 0
    run_ref: Any = None
    poll_ref: Any = None
    polled_at: float = 0.0
    cancel_at: float | None = None
    killed: bool = False


class RayWorkerPool:
    """``workers`` actors of ``cpus_per_worker`` CPUs (a job runs on one thread; 0: Ray
    reserves none; None workers: one per CPU of the cluster).  ``address``: an existing
    cluster; None uses the Ray this process already runs, or starts a local one with
    ``workers`` CPUs and stops it at :meth:`stop`."""

    def __init__(
        self,
        store: JobStore,
        workers: int | None,
        estimator: str,
        address: str | None = None,
        cancel_grace: float = 3.0,
        retention: tuple[float | None, int | None] = (None, None),
        sweep_every: float = 60.0,
        respawn_backoff: float = RESPAWN_BACKOFF,
        cpus_per_worker: float = 1.0,
    ) -> None:
        if workers is not None and workers < 1:
            raise ValueError(f"workers must be at least 1, got {workers}")
        if not 0 <= cpus_per_worker <= 1024:
            raise ValueError(f"cpus_per_worker must be in [0, 1024], got {cpus_per_worker}")
        self.cpus_per_worker = cpus_per_worker
        self.store = store
        self.n = workers or 0
        self.estimator = estimator
        self.address = address
        self.cancel_grace = cancel_grace
        self.retention = retention
        self.sweep_every = sweep_every
        self.respawn_backoff = respawn_backoff
        self.error: str | None = None
        self.replaced = 0
        self._load_failures = 0
        self._actors: list[_Actor] = []
        self._lock = threading.Lock()
        self._live = LiveProgress(store)
        self._attempts: dict[str, int] = {}  # job id -> runs lost with their actor
        self._wake = threading.Event()
        self._stopping = threading.Event()
        self._thread: threading.Thread | None = None
        self._owns_ray = False
        self._ray: Any = None
        self._cls: Any = None

    # -- life --------------------------------------------------------------------------
    def start(self) -> None:
        from treesketch.executor import start_ray

        from .actor import JobActor

        # a local Ray of our own gets as many CPUs as there are workers
        local_cpus = (self.n or None) if self.address is None else None
        self._owns_ray = start_ray(self.address, local_cpus)  # says so when Ray is missing
        import ray

        self._ray = ray
        if not self.n:
            cpus = ray.cluster_resources().get("CPU", 1)
            self.n = max(1, int(cpus / (self.cpus_per_worker or 1.0)))
        # SPREAD: a cluster's actors land on as many nodes as there are
        self._cls = ray.remote(JobActor).options(
            num_cpus=self.cpus_per_worker,
            max_restarts=0,
            max_concurrency=4,
            scheduling_strategy="SPREAD",
        )
        self.store.recover()
        self._actors = [self._spawn() for _ in range(self.n)]
        self._thread = threading.Thread(target=self._loop, name="treesketch-ray-pool", daemon=True)
        self._thread.start()

    def stop(self, timeout: float = 5.0) -> None:
        self._stopping.set()
        self._wake.set()
        if self._thread is not None:
            self._thread.join(timeout)
        for a in self._actors:
            with contextlib.suppress(Exception):  # a dead actor or a Ray going away
                self._ray.kill(a.handle, no_restart=True)
        self._actors = []
        if self._owns_ray and self._ray.is_initialized():
            self._ray.shutdown()
        self._owns_ray = False

    def _spawn(self) -> _Actor:
        handle = self._cls.remote(self.estimator)
        return _Actor(handle=handle, ready_ref=handle.ready.remote(), probed_at=time.monotonic())

    # -- requests from the HTTP side (any thread) --------------------------------------
    def wakeup(self) -> None:
        self._wake.set()

    def cancel(self, job_id: str) -> bool:
        """Ask the actor running ``job_id`` to stop; False if none runs it."""
        with self._lock:
            for a in self._actors:
                if a.job == job_id:
                    if a.cancel_at is None:
                        a.cancel_at = time.monotonic()
                        a.handle.cancel.remote(job_id)
                    return True
        return False

    def actor_of(self, job_id: str) -> Any | None:
        """The Ray actor handle running ``job_id`` (None if none runs it): for operators'
        tools and fault tests, e.g. ``ray.kill(pool.actor_of(job_id))``."""
        with self._lock:
            return next((a.handle for a in self._actors if a.job == job_id), None)

    def live(self, job_id: str) -> dict[str, Any] | None:
        return self._live.get(job_id)

    def status(self) -> list[dict[str, Any]]:
        with self._lock:
            return [
                {
                    "actor": a.actor,
                    "node": a.node,
                    "pid": a.pid,
                    "alive": not a.killed,
                    "ready": a.ready,
                    "job": a.job,
                    "attempt": a.attempt if a.job else None,  # 2: a lost actor's job again
                }
                for a in self._actors
            ]

    @property
    def broken(self) -> bool:
        """True when actors failed to load the estimator LOAD_ATTEMPTS times in a row."""
        return self._load_failures >= LOAD_ATTEMPTS

    def busy(self) -> int:
        with self._lock:
            return sum(a.job is not None for a in self._actors)

    # -- the dispatcher thread ---------------------------------------------------------
    def _loop(self) -> None:
        last_sweep = 0.0
        while not self._stopping.is_set():
            try:
                self._step()
                if time.monotonic() - last_sweep > self.sweep_every:
                    last_sweep = time.monotonic()
                    self.store.expire(*self.retention)
            except Exception as exc:  # noqa: BLE001 - e.g. the cluster unreachable for a while
                # the dispatcher must outlive it, or every running job would hang
                traceback.print_exc()
                self.error = f"the dispatcher hit {type(exc).__name__}: {exc}"
                self._stopping.wait(1.0)

    def _step(self) -> None:
        self._assign()
        refs = [
            r for a in self._actors for r in (a.ready_ref, a.run_ref, a.poll_ref) if r is not None
        ]
        if refs:
            self._ray.wait(refs, num_returns=1, timeout=TICK)
        else:
            self._wake.wait(TICK)
        self._wake.clear()
        for i in range(len(self._actors)):
            self._check(i)
        self._probe_and_poll()
        self._enforce_cancels()

    def _done(self, ref: Any) -> bool:
        return ref is not None and bool(self._ray.wait([ref], timeout=0)[0])

    def _assign(self) -> None:
        for a in self._actors:
            if not (a.ready and a.job is None):
                continue
            job = self.store.claim_next()
            if job is None:
                return
            try:
                views = JobOptions.from_dict(job.options).views
                drawings = self.store.read_uploads(job.id, views)
            except OSError as exc:
                self.store.fail(job.id, f"the uploaded sketch is gone: {exc}")
                continue
            attempt = self._attempts.get(job.id, 0) + 1
            self._live.begin(job.id, job.options)
            with self._lock:
                a.job, a.attempt, a.cancel_at = job.id, attempt, None
                a.polled_at = time.monotonic()
            a.run_ref = a.handle.run.remote(job.id, job.options, drawings)

    def _check(self, i: int) -> None:
        a = self._actors[i]
        if self._done(a.ready_ref):
            self._on_ready(i)
            return
        if self._done(a.poll_ref):
            with contextlib.suppress(self._ray.exceptions.RayError):  # run_ref tells why
                info = self._ray.get(a.poll_ref)
                if info is not None and a.job is not None:
                    self._live.update(a.job, info)
            a.poll_ref = None
        if self._done(a.run_ref):
            self._on_result(i)

    def _on_ready(self, i: int) -> None:
        a = self._actors[i]
        ref, a.ready_ref = a.ready_ref, None
        try:
            info = self._ray.get(ref)
        except self._ray.exceptions.RayError as exc:  # the actor died (or never started)
            if not a.loaded:
                self.error = self.error or f"a worker actor died while loading: {_first(exc)}"
                self._load_failures += 1
            self._replace(i, slow=not a.loaded)
            return
        if info["error"]:
            self.error = str(info["error"])
            self._load_failures += 1
            self._replace(i, slow=True)
            return
        with self._lock:
            a.ready, a.loaded, a.node, a.pid = True, True, info["node"], int(info["pid"])
            a.actor = info["actor"]
        self._load_failures = 0

    def _on_result(self, i: int) -> None:
        from weberpenn.fileio import write_together

        ray = self._ray
        a = self._actors[i]
        job_id, ref = a.job, a.run_ref
        assert job_id is not None
        a.run_ref = a.poll_ref = None
        try:
            out = ray.get(ref)
        except ray.exceptions.RayActorError as exc:  # the actor (or its node) is gone
            self._lost(i, job_id, _first(exc))
            return
        except ray.exceptions.RayError as exc:  # e.g. a result that could not travel
            self.store.fail(job_id, f"the worker's answer was lost: {_first(exc)}")
        else:
            if out["state"] == "done":
                summary = out["summary"]
                summary["worker"] = {"node": a.node, "pid": a.pid, "attempt": a.attempt}
                folder = self.store.result_dir(job_id)
                try:
                    write_together({folder / name: data for name, data in out["files"].items()})
                except OSError as exc:  # a full disk: the job fails, the pool goes on
                    shutil.rmtree(folder, ignore_errors=True)  # no empty folder left
                    what = "storage full: " if is_full(exc) else ""
                    self.store.fail(job_id, f"{what}the results could not be saved: {exc}")
                else:
                    self.store.finish(job_id, summary)
            elif out["state"] == "cancelled":
                self.store.fail(job_id, "cancelled", state="cancelled")
            else:
                self.store.fail(job_id, str(out["message"]), input_error=bool(out["input"]))
        self._release(a, job_id)

    def _lost(self, i: int, job_id: str, why: str) -> None:
        """The actor running ``job_id`` died: retry the job once elsewhere, replace it."""
        a = self._actors[i]
        lost = self._attempts.get(job_id, 0) + 1
        retried = False
        if a.cancel_at is not None:
            self.store.fail(job_id, "cancelled", state="cancelled")
        elif lost < MAX_ATTEMPTS and self.store.requeue(job_id):
            self._attempts[job_id], retried = lost, True
        else:
            self.store.fail(
                job_id,
                f"the worker running this job was lost {lost} times (last: {why}); submit it again",
            )
        self._release(a, job_id, keep_attempts=retried)
        # its node may have taken others with it: check the idle ones before sending work
        for other in self._actors:
            if other is not a and other.ready and other.job is None:
                self._probe(other)
        self._replace(i)
        self._wake.set()

    def _release(self, a: _Actor, job_id: str, keep_attempts: bool = False) -> None:
        with self._lock:
            a.job, a.cancel_at = None, None
        self._live.end(job_id)
        if not keep_attempts:
            self._attempts.pop(job_id, None)

    def _replace(self, i: int, slow: bool = False) -> None:
        """A new actor for slot ``i``; ``slow``: after a failed load, wait first, and give
        up once the pool is broken."""
        a = self._actors[i]
        with contextlib.suppress(Exception):
            self._ray.kill(a.handle, no_restart=True)
        if slow:
            if self.broken:
                with self._lock:
                    a.killed, a.ready = True, False
                return
            self._stopping.wait(self.respawn_backoff)
        fresh = self._spawn()
        with self._lock:
            self._actors[i] = fresh
            self.replaced += 1

    def _probe(self, a: _Actor) -> None:
        with self._lock:
            a.ready = False
        a.ready_ref, a.probed_at = a.handle.ready.remote(), time.monotonic()

    def _probe_and_poll(self) -> None:
        now = time.monotonic()
        for a in self._actors:
            if a.ready and a.job is None and now - a.probed_at > PROBE_EVERY:
                self._probe(a)
            elif a.job is not None and a.poll_ref is None and now - a.polled_at > POLL_EVERY:
                a.polled_at = now
                a.poll_ref = a.handle.poll.remote(a.job)

    def _enforce_cancels(self) -> None:
        now = time.monotonic()
        for a in self._actors:
            if a.cancel_at is not None and not a.killed and now - a.cancel_at > self.cancel_grace:
                a.killed = True  # _on_result sees the actor lost and records the cancel
                with contextlib.suppress(Exception):
                    self._ray.kill(a.handle, no_restart=True)


def _first(exc: BaseException) -> str:
    """The first line of an exception, named by its type (Ray's are long)."""
    text = str(exc).strip()
    return f"{type(exc).__name__}: {text.splitlines()[0] if text else ''}".rstrip(": ")
