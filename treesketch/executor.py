"""One executor for independent, deterministic pieces of work (a tree of a dataset, a view
of a rotation sweep, one refinement of a benchmark): in this process, a local process pool,
or a Ray cluster.  Same pieces, same factory, same results whichever runs them.

The caller hands over a *worker factory* and the pieces.  The factory is a picklable
zero-argument callable that returns the function doing one piece; it is called once per
worker process (in-process: once), so whatever it loads (a TSN model, a mitsuba scene of the
ground-truth tree) stays warm across that worker's pieces::

    with make_executor("ray", address="auto") as ex:
        for out in ex.run(MyFactory(settings), pieces):   # completion order
            out.index, out.value, out.error, out.node

A piece that raises is *reported* (``Outcome.error``), never retried: its inputs are bad
and another try gives the same answer.  A piece whose worker or node is lost (a crash, a
killed process, a node that left the cluster) is retried elsewhere by Ray's task retries,
``max_retries`` times, and only then reported.

Ray is optional (``pip install .[cluster]``); nothing here imports it until a
:class:`RayExecutor` is made.  Ray runs pieces as *tasks*, not actors: a task lost with its
node is re-scheduled wherever there is room, whereas an actor pool would have to restart
an actor that may not fit anywhere.  Ray reuses worker processes for tasks, and each
process builds the factory's worker once (kept by the factory's object id), so tasks keep
their models and scenes warm the way actors would.
"""

from __future__ import annotations

import os
import socket
import threading
import time
import traceback
from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass
from typing import Any, Generic, Protocol, Self, TypeVar

__all__ = [
    "EXECUTORS",
    "Executor",
    "ExecutorError",
    "InlineExecutor",
    "LocalExecutor",
    "Outcome",
    "RayExecutor",
    "from_options",
    "make_executor",
    "run_ordered",
    "start_ray",
]

EXECUTORS = ("local", "ray")

P = TypeVar("P")
R = TypeVar("R")

WorkerFactory = Callable[[], Callable[[Any], Any]]


class ExecutorError(ValueError):
    """A bad executor option, or a cluster that cannot be reached."""


@dataclass(frozen=True)
class Outcome(Generic[R]):
    """What became of one piece: its value, or the error it raised (``"Type: message"``)."""

    index: int
    value: R | None = None
    error: str | None = None
    node: str = ""  # where it ran: "<host>" locally, the Ray node id on a cluster
    worker: int = 0  # the process id that ran it
    seconds: float = 0.0

    @property
    def ok(self) -> bool:
        return self.error is None


class Executor(Protocol):
    name: str

    def run(self, factory: WorkerFactory, pieces: Sequence[Any]) -> Iterator[Outcome[Any]]:
        """Run every piece; yield each outcome as it completes (any order)."""
        ...

    def close(self) -> None: ...


def run_ordered(
    executor: Executor,
    factory: WorkerFactory,
    pieces: Sequence[Any],
    on_outcome: Callable[[Outcome[Any]], None] | None = None,
) -> list[Outcome[Any]]:
    """Every outcome, in the order of ``pieces`` (``on_outcome`` sees them as they land)."""
    out: list[Outcome[Any] | None] = [None] * len(pieces)
    for o in executor.run(factory, pieces):
        out[o.index] = o
        if on_outcome is not None:
            on_outcome(o)
    missing = [i for i, o in enumerate(out) if o is None]
    if missing:  # an executor bug, never the pieces' fault
        raise RuntimeError(f"{executor.name} executor lost pieces {missing[:10]}")
    return out  # type: ignore[return-value]


def _call(fn: Callable[[Any], Any], index: int, piece: Any, node: str) -> Outcome[Any]:
    t0 = time.perf_counter()
    try:
        value = fn(piece)
    except Exception as exc:  # the piece's own failure: report it, the run goes on
        err = f"{type(exc).__name__}: {exc}"
        tb = traceback.format_exc(limit=-3)
        return Outcome(index, None, f"{err}\n{tb}", node, os.getpid(), time.perf_counter() - t0)
    return Outcome(index, value, None, node, os.getpid(), time.perf_counter() - t0)


class _Closing:
    """``with executor:`` closes it at the end; :meth:`close` frees nothing by default."""

    def close(self) -> None:
        pass

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class _Window:
    """Pieces started a few at a time (a bounded queue keeps memory flat on long runs):
    ``submit(k)`` starts the next ``k`` with ``start(index, piece)``; ``pending`` maps what
    ``start`` returned (a future, a Ray reference) to the piece's index."""

    def __init__(self, pieces: Sequence[Any], start: Callable[[int, Any], Any]) -> None:
        self._todo = iter(enumerate(pieces))
        self._start = start
        self.pending: dict[Any, int] = {}

    def submit(self, k: int) -> None:
        for i, piece in self._todo:
            self.pending[self._start(i, piece)] = i
            k -= 1
            if k <= 0:
                return


# --------------------------------------------------------------------------- local
class InlineExecutor(_Closing):
    """Every piece in this process, one after the other (the default; no dependency)."""

    name = "local"
    workers = 1

    def run(self, factory: WorkerFactory, pieces: Sequence[Any]) -> Iterator[Outcome[Any]]:
        if not pieces:
            return
        try:
            fn = factory()
        except Exception as exc:
            fn = _setup_failed(exc)
        host = socket.gethostname()
        for i, piece in enumerate(pieces):
            yield _call(fn, i, piece, host)


# The one worker of a pool process, built by the pool's initializer.  It is per process
# (each spawned interpreter has its own), which is exactly the lifetime a warm worker needs.
_POOL_WORKER: dict[str, Callable[[Any], Any]] = {}


def _pool_init(parent_pid: int, factory: WorkerFactory) -> None:
    """Build the worker, and exit on our own if the parent is killed (no orphan keeps
    writing or computing after ``kill -9`` of the run)."""

    def watch() -> None:
        while True:
            if os.getppid() != parent_pid:
                os._exit(3)
            time.sleep(0.2)

    threading.Thread(target=watch, daemon=True).start()
    try:
        _POOL_WORKER["fn"] = factory()
    except Exception as exc:  # reported with every piece, not as a broken pool
        _POOL_WORKER["fn"] = _setup_failed(exc)


def _setup_failed(exc: Exception) -> Callable[[Any], Any]:
    msg = f"worker setup failed: {type(exc).__name__}: {exc}"

    def fail(piece: Any) -> Any:
        raise RuntimeError(msg)

    return fail


def _pool_piece(index: int, piece: Any) -> Outcome[Any]:
    return _call(_POOL_WORKER["fn"], index, piece, socket.gethostname())


class LocalExecutor(_Closing):
    """``workers`` processes on this machine (spawned: mitsuba and torch start cleanly);
    ``workers=1`` runs in this process."""

    name = "local"

    def __init__(self, workers: int = 1) -> None:
        if isinstance(workers, bool) or not isinstance(workers, int) or not 1 <= workers <= 256:
            raise ExecutorError(f"workers must be an integer in 1..256, got {workers!r}")
        self.workers = workers

    def run(self, factory: WorkerFactory, pieces: Sequence[Any]) -> Iterator[Outcome[Any]]:
        if self.workers == 1 or len(pieces) <= 1:
            yield from InlineExecutor().run(factory, pieces)
            return
        import multiprocessing as mp
        from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait

        n = min(self.workers, len(pieces))
        with ProcessPoolExecutor(
            max_workers=n,
            mp_context=mp.get_context("spawn"),
            initializer=_pool_init,
            initargs=(os.getpid(), factory),
        ) as pool:
            window = _Window(pieces, lambda i, piece: pool.submit(_pool_piece, i, piece))
            window.submit(4 * n)
            pending: dict[Future[Outcome[Any]], int] = window.pending
            while pending:
                done, _ = wait(pending, return_when=FIRST_COMPLETED)
                for fut in done:
                    i = pending.pop(fut)
                    try:
                        yield fut.result()
                    except Exception as exc:  # the worker process died (killed, crashed)
                        yield Outcome(i, None, f"worker lost: {type(exc).__name__}: {exc}")
                    window.submit(1)


# --------------------------------------------------------------------------- Ray
# Per Ray worker process: the worker built from the factory last seen, by its object id.
_RAY_WORKER: dict[str, Callable[[Any], Any]] = {}


def _ray_piece(factory_box: list[Any], index: int, piece: Any) -> Outcome[Any]:
    """The Ray task: one piece on a warm worker.  ``factory_box`` holds the factory's
    ObjectRef inside a list so that Ray hands us the reference (a stable cache key), not
    the value."""
    import ray

    ref = factory_box[0]
    key = ref.hex()
    if key not in _RAY_WORKER:
        try:
            fn = ray.get(ref)()
        except Exception as exc:
            fn = _setup_failed(exc)
        _RAY_WORKER.clear()  # one warm worker per process: a new run replaces the old one
        _RAY_WORKER[key] = fn
    node = ray.get_runtime_context().get_node_id()
    return _call(_RAY_WORKER[key], index, piece, node)


class RayExecutor(_Closing):
    """Pieces as Ray tasks.  ``address``: an existing cluster (``"auto"``, ``"HOST:PORT"``,
    ``"ray://HOST:PORT"``); None starts a local Ray for this run with ``num_cpus`` CPUs
    (default: all) and stops it at :meth:`close`.

    ``cpus_per_piece`` is the CPUs Ray reserves per task (the pieces here use one thread);
    ``max_retries`` how often a piece lost with its worker or node is tried again.
    """

    name = "ray"

    def __init__(
        self,
        address: str | None = None,
        num_cpus: int | None = None,
        cpus_per_piece: float = 1.0,
        max_retries: int = 3,
        in_flight: int | None = None,
    ) -> None:
        if address is not None and (not isinstance(address, str) or not address.strip()):
            raise ExecutorError(f"address must be a non-empty string, got {address!r}")
        if address is not None and num_cpus is not None:
            raise ExecutorError("num_cpus is for a local Ray; an existing cluster has its own")
        if num_cpus is not None and (isinstance(num_cpus, bool) or not 1 <= int(num_cpus) <= 4096):
            raise ExecutorError(f"num_cpus must be in 1..4096, got {num_cpus!r}")
        if not 0 < float(cpus_per_piece) <= 1024:
            raise ExecutorError(f"cpus_per_piece must be in (0, 1024], got {cpus_per_piece!r}")
        if isinstance(max_retries, bool) or not 0 <= int(max_retries) <= 100:
            raise ExecutorError(f"max_retries must be in 0..100, got {max_retries!r}")
        if in_flight is not None and not 1 <= int(in_flight) <= 1_000_000:
            raise ExecutorError(f"in_flight must be >= 1, got {in_flight!r}")
        self._started = start_ray(address, num_cpus)
        import ray

        self.address = address
        self.cpus_per_piece = float(cpus_per_piece)
        self.max_retries = int(max_retries)
        self.in_flight = in_flight
        self._ray = ray
        self._task = ray.remote(_ray_piece)

    @property
    def workers(self) -> int:
        """CPUs in the cluster now (nodes may join or leave while it runs)."""
        return int(self._ray.cluster_resources().get("CPU", 1))

    def nodes(self) -> list[str]:
        """Ids of the cluster's live nodes."""
        return [n["NodeID"] for n in self._ray.nodes() if n.get("Alive")]

    def run(self, factory: WorkerFactory, pieces: Sequence[Any]) -> Iterator[Outcome[Any]]:
        if not pieces:
            return
        ray = self._ray
        box = [ray.put(factory)]
        task = self._task.options(
            num_cpus=self.cpus_per_piece,
            max_retries=self.max_retries,
            retry_exceptions=False,  # the pieces catch their own errors; never retried
        )
        limit = self.in_flight or max(2, int(2 * self.workers / self.cpus_per_piece))
        window = _Window(pieces, lambda i, piece: task.remote(box, i, piece))
        window.submit(limit)
        pending = window.pending
        try:
            while pending:
                done, _ = ray.wait(list(pending), num_returns=1)
                for ref in done:
                    i = pending.pop(ref)
                    try:
                        yield ray.get(ref)
                    except ray.exceptions.RayError as exc:  # lost max_retries + 1 times
                        msg = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
                        yield Outcome(i, None, f"lost: {type(exc).__name__}: {msg}")
                    window.submit(1)
        finally:
            for ref in pending:  # an abandoned run (Ctrl-C, an error) stops its tasks
                ray.cancel(ref, force=True)

    def close(self) -> None:
        if self._started and self._ray.is_initialized():
            self._ray.shutdown()
        self._started = False


def start_ray(address: str | None = None, num_cpus: int | None = None) -> bool:
    """Connect this process to Ray: ``address`` (``"auto"``, ``"HOST:PORT"``,
    ``"ray://HOST:PORT"``) or, without one, a new local Ray with ``num_cpus`` CPUs (default:
    all).  True when this call started or joined Ray (the caller then ends it with
    ``ray.shutdown()``); False when Ray was already up in this process (someone else owns
    it).  ExecutorError when Ray is missing or the cluster cannot be reached."""
    try:
        import ray
    except ImportError:
        raise ExecutorError(
            "the ray executor needs Ray: pip install 'treesketch[cluster]' (or pip install ray)"
        ) from None
    if ray.is_initialized():
        return False
    _check_reachable(address)
    try:
        ray.init(
            # "local": always a new Ray of our own, never one a stale
            # /tmp/ray/ray_current_cluster points at
            address=address or "local",
            num_cpus=num_cpus,
            include_dashboard=False,
            log_to_driver=False,
            configure_logging=False,
            # a local Ray's workers import the code this driver imports; a cluster's
            # nodes bring their own install
            runtime_env=None if address else {"env_vars": {"PYTHONPATH": _pythonpath()}},
        )
    except (ConnectionError, ValueError, RuntimeError) as exc:
        where = address or "a local Ray"
        raise ExecutorError(f"cannot start or reach {where}: {exc}") from None
    return True


def _check_reachable(address: str | None, timeout: float = 5.0) -> None:
    """A HOST:PORT that nobody answers on fails now, plainly (Ray itself would retry
    for minutes)."""
    if address is None or address == "auto" or "://" in address:
        return
    host, sep, port = address.rpartition(":")
    if not sep or not host or not port.isdigit():
        raise ExecutorError(
            f"--address must be auto, HOST:PORT or ray://HOST:PORT, got {address!r}"
        )
    try:
        socket.create_connection((host, int(port)), timeout=timeout).close()
    except OSError as exc:
        raise ExecutorError(
            f"no Ray cluster answers at {address} ({exc.strerror or exc}); "
            "start one with `ray start --head` or leave out --address for a local Ray"
        ) from None


def _pythonpath() -> str:
    import sys

    parts = [p for p in sys.path if p and os.path.isdir(p)]
    return os.pathsep.join(dict.fromkeys(parts))


# --------------------------------------------------------------------------- choice
def make_executor(
    kind: str = "local",
    workers: int = 1,
    address: str | None = None,
    num_cpus: int | None = None,
) -> LocalExecutor | RayExecutor:
    """``local`` (``workers`` processes) or ``ray`` (``address``: an existing cluster;
    without it a local Ray with ``num_cpus`` CPUs, default ``workers`` when above 1)."""
    if kind not in EXECUTORS:
        raise ExecutorError(f"unknown executor {kind!r}: choose from {', '.join(EXECUTORS)}")
    if kind == "local":
        if address is not None:
            raise ExecutorError("--address is for the ray executor (use --executor ray)")
        return LocalExecutor(workers)
    if address is None and num_cpus is None and workers > 1:
        num_cpus = workers
    return RayExecutor(address=address, num_cpus=num_cpus)


def from_options(
    kind: str, workers: int = 1, address: str | None = None
) -> LocalExecutor | RayExecutor | None:
    """The executor of the CLI's ``--executor/--workers/--address``; None for one local
    process (the caller then runs the pieces in-process, with every core to itself)."""
    kind = kind.strip().lower()
    if kind == "local" and workers == 1 and address is None:
        return None
    if kind == "ray" and address is not None and workers != 1:
        raise ExecutorError("--workers is for a local run; a Ray cluster has its own CPUs")
    return make_executor(kind, workers=workers, address=address)


def describe(outcomes: Iterable[Outcome[Any]]) -> dict[str, int]:
    """Pieces per node (to show where a run went)."""
    counts: dict[str, int] = {}
    for o in outcomes:
        counts[o.node] = counts.get(o.node, 0) + 1
    return counts
