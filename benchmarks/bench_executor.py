"""Benchmark the executors (treesketch.executor): local vs Ray on this machine, and a
two-node Ray cluster (Ray's test cluster utilities: two raylets on this machine).

    .venv/bin/python benchmarks/bench_executor.py                  # every part
    .venv/bin/python benchmarks/bench_executor.py --parts overhead,dataset

It prints Markdown tables, ready for RESULTS.md.

Parts:

* ``overhead``: ``--pieces`` empty pieces through each executor: milliseconds per piece.
* ``dataset``: the same dataset (``--trees-per-species`` x 5 species x 4 views at
  ``--size``) built in-process, by a 2-process local pool and by a local Ray with 2 CPUs;
  trees/s, Ray's time per tree as a ratio of the local pool's, and whether every file
  (markers aside: they hold timings) is the same bytes as the in-process build.
* ``scaling``: a Ray cluster of one node with 1 CPU, then of two nodes with 1 CPU each:
  trees/s and how many trees each node built.
* ``kill-external`` (with ``--address`` and ``--raylet-pid``): the same on a cluster made
  with ``ray start``, killing the given raylet with ``kill -9``.
* ``kill``: the two-node cluster again; once the second node has built 2 trees it is
  killed (its raylet and workers, no goodbye); the build completes on the head node,
  and the result is compared byte for byte with the in-process build.

Ray start-up (seconds) is reported apart from the build time.  Other processes share
the CPUs; the load average is printed with the numbers.
"""

from __future__ import annotations

import argparse
import hashlib
import os
import platform
import tempfile
import time
from collections.abc import Callable, Iterable, Iterator, Sequence
from pathlib import Path
from typing import Any

from render.dataset import DatasetConfig, build_dataset
from treesketch.executor import (
    InlineExecutor,
    LocalExecutor,
    Outcome,
    RayExecutor,
    run_ordered,
)


class Noop:
    def __call__(self) -> Callable[[Any], Any]:
        return _identity


def _identity(x: Any) -> Any:
    return x


class Watch:
    """An executor wrapper that records where each piece ran (and can act on it)."""

    def __init__(self, inner: Any, on_outcome: Callable[[Outcome[Any]], None] | None = None):
        self.inner = inner
        self.name = inner.name
        self.nodes: dict[str, int] = {}
        self.on_outcome = on_outcome

    def run(self, factory: Any, pieces: Sequence[Any]) -> Iterator[Outcome[Any]]:
        for o in self.inner.run(factory, pieces):
            self.nodes[o.node] = self.nodes.get(o.node, 0) + 1
            if self.on_outcome is not None:
                self.on_outcome(o)
            yield o


def digest(root: Path) -> str:
    """One hash of every file of a dataset but the per-tree markers (timings)."""
    h = hashlib.sha256()
    for p in sorted(root.rglob("*")):
        if p.is_file() and p.parent.name != "done" and p.name not in ("DONE", ".lock"):
            h.update(p.relative_to(root).as_posix().encode())
            h.update(p.read_bytes())
    return h.hexdigest()[:16]


def build(cfg_kw: dict, out: Path, executor: Any) -> dict:
    cfg = DatasetConfig(out=str(out), **cfg_kw)
    t0 = time.perf_counter()
    s = build_dataset(cfg, progress=False, executor=executor)
    dt = time.perf_counter() - t0
    return {
        "trees": s.built,
        "failed": len(s.failed),
        "seconds": dt,
        "trees_per_s": s.built / dt,
        "digest": digest(out),
    }


def part_overhead(n: int) -> list[dict]:
    rows = []
    for label, make in (
        ("in-process", InlineExecutor),
        ("local pool, 2 processes", lambda: LocalExecutor(2)),
        ("Ray, local, 2 CPUs", lambda: RayExecutor(num_cpus=2)),
    ):
        # a run starts its workers (a pool spawns them, Ray reuses its own): the
        # marginal cost of a piece is the difference between a long and a short run
        t0 = time.perf_counter()
        ex = make()
        start = time.perf_counter() - t0
        t0 = time.perf_counter()
        run_ordered(ex, Noop(), list(range(8)))
        first = time.perf_counter() - t0
        t0 = time.perf_counter()
        run_ordered(ex, Noop(), list(range(8)))
        short = time.perf_counter() - t0
        t0 = time.perf_counter()
        outs = run_ordered(ex, Noop(), list(range(n + 8)))
        long = time.perf_counter() - t0
        ex.close()
        assert all(o.ok for o in outs)
        dt = long - short
        rows.append(
            {
                "executor": label,
                "start_s": start,
                "first_s": first,
                "run8_s": short,
                "ms_per_piece": 1000 * dt / n,
            }
        )
    return rows


def part_dataset(cfg_kw: dict, tmp: Path) -> list[dict]:
    rows = []
    for label, make in (
        ("in-process", lambda: None),
        ("local pool, 2 processes", lambda: LocalExecutor(2)),
        ("Ray, local, 2 CPUs", lambda: RayExecutor(num_cpus=2)),
    ):
        t0 = time.perf_counter()
        ex = make()
        start = time.perf_counter() - t0
        try:
            r = build(cfg_kw, tmp / label.split(",")[0].replace(" ", "_"), ex)
        finally:
            if ex is not None:
                ex.close()
        rows.append({"executor": label, "start_s": start, **r})
    return rows


def _cluster(num_nodes: int) -> tuple[Any, list[Any]]:
    from ray.cluster_utils import Cluster

    cluster = Cluster(
        initialize_head=True, head_node_args={"num_cpus": 1, "include_dashboard": False}
    )
    nodes = [cluster.head_node]
    for _ in range(num_nodes - 1):
        nodes.append(cluster.add_node(num_cpus=1))
    cluster.wait_for_nodes()
    return cluster, nodes


def part_scaling(cfg_kw: dict, tmp: Path) -> list[dict]:
    import ray

    rows = []
    for n_nodes in (1, 2):
        t0 = time.perf_counter()
        cluster, nodes = _cluster(n_nodes)
        ex = Watch(RayExecutor(address=cluster.address))
        start = time.perf_counter() - t0
        try:
            r = build(cfg_kw, tmp / f"nodes{n_nodes}", ex)
        finally:
            ex.inner.close()
            ray.shutdown()
            cluster.shutdown()
        per_node = [ex.nodes.get(n.node_id, 0) for n in nodes]
        rows.append({"nodes": n_nodes, "start_s": start, "per_node": per_node, **r})
    return rows


def part_kill(cfg_kw: dict, tmp: Path) -> dict:
    import ray

    cluster, (head, second) = _cluster(2)
    events: list[str] = []
    t0 = time.perf_counter()

    def maybe_kill(o: Outcome[Any]) -> None:
        if not events and ex.nodes.get(second.node_id, 0) >= 2:
            cluster.remove_node(second, allow_graceful=False)
            events.append(f"second node killed at {time.perf_counter() - t0:.1f} s")

    ex = Watch(RayExecutor(address=cluster.address), on_outcome=maybe_kill)
    try:
        r = build(cfg_kw, tmp / "killed", ex)
    finally:
        ex.inner.close()
        ray.shutdown()
        cluster.shutdown()
    return {
        **r,
        "head": ex.nodes.get(head.node_id, 0),
        "second": ex.nodes.get(second.node_id, 0),
        "events": events,
    }


def part_kill_external(cfg_kw: dict, tmp: Path, address: str, raylet_pid: int) -> dict:
    """Like ``kill``, on a cluster started with ``ray start``: ``kill -9`` of the given
    raylet (a node other than the head) once 3 trees are done."""
    import signal

    events: list[str] = []
    t0 = time.perf_counter()

    def maybe_kill(o: Outcome[Any]) -> None:
        done = sum(ex.nodes.values())
        if not events and len(ex.nodes) >= 2 and done >= 3:
            os.kill(raylet_pid, signal.SIGKILL)
            events.append(
                f"raylet pid {raylet_pid} killed after {done} trees, "
                f"at {time.perf_counter() - t0:.1f} s"
            )

    inner = RayExecutor(address=address)
    alive = len(inner.nodes())
    ex = Watch(inner, on_outcome=maybe_kill)
    try:
        r = build(cfg_kw, tmp / "killed_external", ex)
    finally:
        inner.close()
    return {**r, "alive_before": alive, "per_node": dict(ex.nodes), "events": events}


def _table(title: str, header: str, lines: Iterable[str]) -> None:
    """A section of the report: its title, then a markdown table (``header`` with its
    rule line) of ``lines``."""
    print(f"\n## {title}\n")
    print(header)
    for line in lines:
        print(line)


def _same(digest: str, ref: str | None, same: str, different: str) -> str:
    """How ``digest`` compares with the reference run's (nothing when there is none)."""
    return "" if ref is None else (same if digest == ref else different)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--parts", default="overhead,dataset,scaling,kill")
    ap.add_argument("--pieces", type=int, default=200, help="empty pieces (overhead)")
    ap.add_argument("--trees-per-species", type=int, default=3)
    ap.add_argument("--size", type=int, default=256)
    ap.add_argument("--address", default=None, help="part kill-external: a `ray start` cluster")
    ap.add_argument("--raylet-pid", type=int, default=0, help="part kill-external: node to kill")
    args = ap.parse_args()
    parts = [p.strip() for p in args.parts.split(",") if p.strip()]
    unknown = set(parts) - {"overhead", "dataset", "scaling", "kill", "kill-external"}
    if unknown:
        ap.error(f"unknown parts: {', '.join(sorted(unknown))}")
    cfg_kw = {"trees_per_species": args.trees_per_species, "size": args.size}
    n_trees = 5 * args.trees_per_species
    print(
        f"# {platform.node()} {os.cpu_count()} CPUs, {platform.python_version()}, "
        f"load {os.getloadavg()[0]:.1f}, {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}"
    )
    with tempfile.TemporaryDirectory(prefix="bench_executor_") as d:
        tmp = Path(d)
        ref = None
        if "overhead" in parts:
            _table(
                f"Per-piece overhead ({args.pieces} empty pieces, workers warm)",
                "| executor | start (s) | first run of 8 pieces (s) | next run of 8 (s) "
                "| ms per further piece |\n|---|---:|---:|---:|---:|",
                (
                    f"| {r['executor']} | {r['start_s']:.1f} | {r['first_s']:.2f} | "
                    f"{r['run8_s']:.2f} | {r['ms_per_piece']:.2f} |"
                    for r in part_overhead(args.pieces)
                ),
            )
        if "dataset" in parts:
            rows = part_dataset(cfg_kw, tmp)
            ref, pool = rows[0]["digest"], rows[1]["trees_per_s"]
            _table(
                f"Dataset build, {n_trees} trees x 4 views at {args.size} px",
                "| executor | start (s) | build (s) | trees/s | time per tree vs local pool "
                "| same bytes as in-process |\n|---|---:|---:|---:|---:|---|",
                (
                    f"| {r['executor']} | {r['start_s']:.1f} | {r['seconds']:.1f} | "
                    f"{r['trees_per_s']:.2f} | {pool / r['trees_per_s']:.2f} | "
                    f"{'yes' if r['digest'] == ref else 'NO'} ({r['digest']}) |"
                    for r in rows
                ),
            )
        if "scaling" in parts:
            rows = part_scaling(cfg_kw, tmp)
            base = rows[0]["trees_per_s"]
            _table(
                f"Two-node scaling (Ray test cluster, 1 CPU per node), {n_trees} trees",
                "| nodes | start (s) | build (s) | trees/s | speed-up | trees per node "
                "| digest |\n|---|---:|---:|---:|---:|---|---|",
                (
                    f"| {r['nodes']} | {r['start_s']:.1f} | {r['seconds']:.1f} | "
                    f"{r['trees_per_s']:.2f} | {r['trees_per_s'] / base:.2f} | "
                    f"{' + '.join(map(str, r['per_node']))} | {r['digest']}"
                    f"{_same(r['digest'], ref, ' same', ' DIFFERENT')} |"
                    for r in rows
                ),
            )
        if "kill" in parts:
            print(f"\n## Node killed mid-run, {n_trees} trees\n")
            r = part_kill(cfg_kw, tmp)
            same = _same(r["digest"], ref, ", same bytes", ", DIFFERENT")
            print(
                f"{'; '.join(r['events']) or 'the second node was never killed'}; "
                f"{r['trees']} trees built, {r['failed']} failed, in {r['seconds']:.1f} s; "
                f"outcomes from the head node {r['head']}, from the second node {r['second']}; "
                f"digest {r['digest']}{same}"
            )

        if "kill-external" in parts:
            if not args.address or args.raylet_pid <= 0:
                ap.error("part kill-external needs --address and --raylet-pid")
            print(f"\n## A `ray start` node killed mid-run, {n_trees} trees\n")
            r = part_kill_external(cfg_kw, tmp, args.address, args.raylet_pid)
            if ref is None:
                ref = build(cfg_kw, tmp / "reference", None)["digest"]
            per_node = ", ".join(f"{k[:8]}: {v}" for k, v in r["per_node"].items())
            print(
                f"{r['alive_before']} nodes alive at the start; "
                f"{'; '.join(r['events']) or 'nothing was killed'}; {r['trees']} trees built, "
                f"{r['failed']} failed, in {r['seconds']:.1f} s; trees per node: {per_node}; "
                f"digest {r['digest']}, in-process {ref}: "
                f"{'same bytes' if r['digest'] == ref else 'DIFFERENT'}"
            )


if __name__ == "__main__":
    main()
