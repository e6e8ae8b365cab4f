"""The worker pool on Ray: N actors (``actor.JobActor``, one CPU each) fed from the job
store by one dispatcher thread, so one HTTP front serves workers on several machines.

It has the local pool's interface (``start``, ``stop``, ``wakeup``, ``cancel``, ``live``,
``status``, ``busy``, ``broken``, ``error``, ``replaced``) and keeps its rules: the
dispatcher is the only writer of job states once a job runs; progress is kept in memory
for the events stream and saved to the store at most once a second; retention sweeps run
from the same thread.  How things cross to an actor:

- the job: its options and the uploaded drawings' bytes go with the ``run`` call;
- progress: the dispatcher polls each busy actor (``poll``) every ``POLL_EVERY`` seconds;
  a newer current best tree comes with the poll's answer and is written into the job's
  results folder (``preview/``) before its version is shown, as a local worker writes it;
- cancel: ``cancel(job_id)`` raises the actor's flag for that job, seen at the next
  evaluation; an actor that has not stopped ``cancel_grace`` seconds later is killed;
- results: the actor returns the artefacts' bytes and the dispatcher writes them with the
  one atomic writer (``write_together``): the nodes need no disk shared with the front.

An actor lost mid-job (killed, out of memory, its node gone) costs one attempt: the job
goes back to the head of the queue and runs on another actor; lost a second time it is
failed with a message.  A job that fails for its own reason (a blank page) is reported,
never retried.  Lost actors are replaced; idle ones are probed every ``PROBE_EVERY``
seconds (and at once after a loss) so that a job is not sent to a dead one.  The
bookkeeping is ``poolbase.BasePool``'s, shared with the local pool.
"""

from __future__ import annotations

import contextlib
import shutil
import threading
import time
import traceback
from dataclasses import dataclass
from typing import Any

from .poolbase import RESPAWN_BACKOFF, BasePool, Slot
from .runner import JobOptions
from .store import Job, JobStore, is_full

__all__ = ["MAX_ATTEMPTS", "RayWorkerPool"]

POLL_EVERY = 0.25  # seconds between progress polls of a busy actor
PROBE_EVERY = 5.0  # seconds between liveness probes of an idle actor
TICK = 0.1  # longest wait of the dispatcher (a submitted job waits at most this)
MAX_ATTEMPTS = 2  # runs of one job on actors that were lost under it


@dataclass(kw_only=True)
class _Actor(Slot):
    handle: Any
    ready_ref: Any  # the pending ready() probe, or None
    loaded: bool = False  # answered a probe once: a later lost probe is no load failure
    node: str = ""
    actor: str = ""
    pid: int = 0
    probed_at: float = 0.0
    attempt: int = 0
    run_ref: Any = None
    poll_ref: Any = None
    polled_at: float = 0.0
    preview: int = 0  # the version of the running job's current best tree written here


class RayWorkerPool(BasePool):
    """``workers`` actors of ``cpus_per_worker`` CPUs (a job runs on one thread; 0: Ray
    reserves none; None workers: one per CPU of the cluster).  ``address``: an existing
    cluster; None uses the Ray this process already runs, or starts a local one with
    ``workers`` CPUs and stops it at :meth:`stop`."""

    thread_name = "treesketch-ray-pool"

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
        super().__init__(
            store, workers or 0, estimator, cancel_grace, retention, sweep_every, respawn_backoff
        )
        self.cpus_per_worker = cpus_per_worker
        self.address = address
        self._attempts: dict[str, int] = {}  # job id -> runs lost with their actor
        self._wake = threading.Event()
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
        super().start()

    def stop(self, timeout: float = 5.0) -> None:
        self._stop_thread(timeout)
        for a in self._slots:
            self._retire(a)
        self._slots = []
        if self._owns_ray and self._ray.is_initialized():
            self._ray.shutdown()
        self._owns_ray = False

    def _spawn(self) -> _Actor:
        handle = self._cls.remote(self.estimator)
        return _Actor(handle=handle, ready_ref=handle.ready.remote(), probed_at=time.monotonic())

    def _retire(self, a: _Actor) -> None:
        with contextlib.suppress(Exception):  # a dead actor or a Ray going away
            self._ray.kill(a.handle, no_restart=True)

    # -- requests from the HTTP side (any thread) --------------------------------------
    def wakeup(self) -> None:
        self._wake.set()

    def _signal_cancel(self, a: _Actor, job_id: str) -> None:
        a.handle.cancel.remote(job_id)  # seen by the actor at its next evaluation

    def actor_of(self, job_id: str) -> Any | None:
        """The Ray actor handle running ``job_id`` (None if none runs it): for operators'
        tools and fault tests, e.g. ``ray.kill(pool.actor_of(job_id))``."""
        with self._lock:
            return next((a.handle for a in self._slots if a.job == job_id), None)

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
                for a in self._slots
            ]

    # -- the dispatcher thread ---------------------------------------------------------
    def _loop(self) -> None:
        last_sweep = 0.0
        while not self._stopping.is_set():
            try:
                self._step()
                last_sweep = self._sweep(last_sweep)
            except Exception as exc:  # noqa: BLE001 - e.g. the cluster unreachable for a while
                # the dispatcher must outlive it, or every running job would hang
                traceback.print_exc()
                self.error = f"the dispatcher hit {type(exc).__name__}: {exc}"
                self._stopping.wait(1.0)

    def _step(self) -> None:
        self._assign()
        refs = [
            r for a in self._slots for r in (a.ready_ref, a.run_ref, a.poll_ref) if r is not None
        ]
        if refs:
            self._ray.wait(refs, num_returns=1, timeout=TICK)
        else:
            self._wake.wait(TICK)
        self._wake.clear()
        for i in range(len(self._slots)):
            self._check(i)
        self._probe_and_poll()
        self._enforce_cancels()

    def _done(self, ref: Any) -> bool:
        return ref is not None and bool(self._ray.wait([ref], timeout=0)[0])

    def _run(self, a: _Actor, job: Job) -> None:
        try:
            views = JobOptions.from_dict(job.options).views
            drawings = self.store.read_uploads(job.id, views)
        except OSError as exc:
            self.store.fail(job.id, f"the uploaded sketch is gone: {exc}")
            return
        # (read with the job only: status shows an attempt once _begin gives the job)
        a.attempt, a.polled_at = self._attempts.get(job.id, 0) + 1, time.monotonic()
        a.preview = 0
        self._begin(a, job)
        a.run_ref = a.handle.run.remote(job.id, job.options, drawings)

    def _check(self, i: int) -> None:
        a = self._slots[i]
        if self._done(a.ready_ref):
            self._on_ready(i)
            return
        if self._done(a.poll_ref):
            with contextlib.suppress(self._ray.exceptions.RayError):  # run_ref tells why
                info = self._ray.get(a.poll_ref)
                if info is not None and a.job is not None:
                    self._live.update(a.job, self._take_preview(a, a.job, info))
            a.poll_ref = None
        if self._done(a.run_ref):
            self._on_result(i)

    def _take_preview(self, a: _Actor, job_id: str, info: dict[str, Any]) -> dict[str, Any]:
        """The progress row to show: a current best tree that came with it is written
        first (a full disk only costs the preview: the row then does not name it)."""
        from weberpenn.fileio import write_together

        files = info.pop("preview_files", None)
        if files is None:
            info.pop("preview", None)
            return info
        folder = self.store.result_dir(job_id) / "preview"
        try:
            folder.mkdir(parents=True, exist_ok=True)
            write_together({folder / name: data for name, data in files.items()})
        except OSError:
            info.pop("preview", None)
            return info
        a.preview = int(info["preview"])
        return info

    def _on_ready(self, i: int) -> None:
        a = self._slots[i]
        ref, a.ready_ref = a.ready_ref, None
        try:
            info = self._ray.get(ref)
        except self._ray.exceptions.RayError as exc:  # the actor died (or never started)
            if not a.loaded:
                self.error = self.error or f"a worker actor died while loading: {_first(exc)}"
                self._load_failures += 1
            self._renew(i, slow=not a.loaded)
            return
        if info["error"]:
            self.error = str(info["error"])
            self._load_failures += 1
            self._renew(i, slow=True)
            return
        with self._lock:
            a.ready, a.loaded, a.node, a.pid = True, True, info["node"], int(info["pid"])
            a.actor = info["actor"]
        self._load_failures = 0

    def _on_result(self, i: int) -> None:
        from weberpenn.fileio import write_together

        ray = self._ray
        a = self._slots[i]
        job_id, ref = a.job, a.run_ref
        assert job_id is not None
        a.run_ref = a.poll_ref = None
        try:
            out = ray.get(ref)
        except ray.exceptions.RayActorError as exc:  # the actor (or its node) is gone
            self._lost(i, job_id, _first(exc))
            return
        except ray.exceptions.RayError as exc:  # e.g. a result that could not travel
            self._drop_preview(job_id)
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
                    self._record(job_id, "done", summary)
            else:
                self._drop_preview(job_id)
                self._record(job_id, out["state"], out)
        self._release(a, job_id)

    def _drop_preview(self, job_id: str) -> None:
        """A job that ends without results leaves no preview and no empty folder."""
        folder = self.store.result_dir(job_id)
        shutil.rmtree(folder / "preview", ignore_errors=True)
        with contextlib.suppress(OSError):
            folder.rmdir()  # only when empty

    def _lost(self, i: int, job_id: str, why: str) -> None:
        """The actor running ``job_id`` died: retry the job once elsewhere, replace it."""
        a = self._slots[i]
        lost = self._attempts.get(job_id, 0) + 1
        retried = a.cancel_at is None and lost < MAX_ATTEMPTS and self.store.requeue(job_id)
        if retried:
            self._attempts[job_id] = lost
        else:
            self._fail_lost(
                a,
                job_id,
                f"the worker running this job was lost {lost} times (last: {why}); submit it again",
            )
        self._release(a, job_id, keep_attempts=retried)
        # its node may have taken others with it: check the idle ones before sending work
        for other in self._slots:
            if other is not a and other.ready and other.job is None:
                self._probe(other)
        self._renew(i)
        self._wake.set()

    def _release(self, a: _Actor, job_id: str, keep_attempts: bool = False) -> None:
        super()._release(a, job_id)
        if not keep_attempts:
            self._attempts.pop(job_id, None)

    def _probe(self, a: _Actor) -> None:
        with self._lock:
            a.ready = False
        a.ready_ref, a.probed_at = a.handle.ready.remote(), time.monotonic()

    def _probe_and_poll(self) -> None:
        now = time.monotonic()
        for a in self._slots:
            if a.ready and a.job is None and now - a.probed_at > PROBE_EVERY:
                self._probe(a)
            elif a.job is not None and a.poll_ref is None and now - a.polled_at > POLL_EVERY:
                a.polled_at = now
                a.poll_ref = a.handle.poll.remote(a.job, a.preview)

    def _kill(self, a: _Actor) -> None:
        self._retire(a)  # _on_result sees the actor lost and records the cancel


def _first(exc: BaseException) -> str:
    """The first line of an exception, named by its type (Ray's are long)."""
    text = str(exc).strip()
    return f"{type(exc).__name__}: {text.splitlines()[0] if text else ''}".rstrip(": ")
