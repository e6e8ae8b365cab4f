"""Benchmark the job service: throughput, latency under load, memory over many jobs.

Runs ``treesketch serve`` as a subprocess (the real thing: uvicorn, SQLite, spawned
worker processes) once per worker count.  Eight client threads submit the jobs
(``POST /jobs``) and poll ``GET /jobs/{id}`` until each is done; a sampler thread times
``GET /health`` and ``GET /jobs/{id}`` every 20 ms and keeps the samples taken while
every worker was busy.  Resident memory (server + workers, psutil) is read after 10 jobs
and, with the 2-worker server, after 100 (the jobs past the timed ones run at
``--memory-budget`` to keep the run short).  The reference, measured first in the same
run: the same pipeline in a bare loop in one process (no service).

    PYTHONPATH=$PWD .venv/bin/python benchmarks/service/bench_service.py --jobs 40 --clients 8 \\
        --budget 20 --workers 1,2 --memory-jobs 100 --reference 6
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import tempfile
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

import httpx
import psutil

from benchmarks.lib.serve_process import FINISHED, ServeProcess

ROOT = Path(__file__).resolve().parents[2]
SKETCH = ROOT / "examples" / "sketch_maple.png"


def rss_mb(pid: int) -> dict[str, float]:
    """Resident MB of the server process and the sum over its children (the workers)."""
    p = psutil.Process(pid)
    kids = p.children(recursive=True)
    return {
        "server": p.memory_info().rss / 2**20,
        "workers": sum(k.memory_info().rss for k in kids) / 2**20,
    }


@dataclass
class Run:
    workers: int
    seconds: float = 0.0
    done: int = 0
    failed: int = 0
    latency: dict[str, list[float]] = field(default_factory=lambda: {"health": [], "job": []})
    rss: dict[int, dict[str, float]] = field(default_factory=dict)


class Server(ServeProcess):
    def __init__(self, workers: int, data: Path, budget: int) -> None:
        args = ["--budget", str(budget), "--max-queue", "256"]
        super().__init__(args, data, workers, data / "serve.log", timeout=180.0)


def run_jobs(
    server: Server, run: Run, n: int, clients: int, budget: int, rss_at: tuple[int, ...]
) -> None:
    sketch = SKETCH.read_bytes()
    lock = threading.Lock()
    next_job = [0]
    active: list[str] = []
    stop = threading.Event()

    def client() -> None:
        with httpx.Client(base_url=server.url, timeout=60) as http:
            while True:
                with lock:
                    if next_job[0] >= n:
                        return
                    next_job[0] += 1
                r = http.post(
                    "/jobs",
                    files={"sketch": ("s.png", sketch, "image/png")},
                    data={"budget": str(budget)},
                )
                while r.status_code == 503:
                    time.sleep(float(r.headers.get("retry-after", "1")))
                    r = http.post("/jobs", files={"sketch": ("s.png", sketch, "image/png")})
                job = r.json()["id"]
                with lock:
                    active.append(job)
                while True:
                    state = http.get(f"/jobs/{job}").json()["state"]
                    if state in FINISHED:
                        break
                    time.sleep(0.5)
                with lock:
                    active.remove(job)
                    run.done += state == "done"
                    run.failed += state != "done"
                    if run.done + run.failed in rss_at:
                        run.rss[run.done + run.failed] = rss_mb(server.proc.pid)

    def sampler() -> None:
        with httpx.Client(base_url=server.url, timeout=60) as http:
            while not stop.is_set():
                t = time.perf_counter()
                h = http.get("/health").json()
                dt = time.perf_counter() - t
                busy = h["busy"] == run.workers
                with lock:
                    job = active[0] if active else None
                if job is not None:
                    t = time.perf_counter()
                    http.get(f"/jobs/{job}")
                    dj = time.perf_counter() - t
                    if busy:
                        run.latency["job"].append(dj)
                if busy:
                    run.latency["health"].append(dt)
                time.sleep(0.02)

    threads = [threading.Thread(target=client) for _ in range(clients)]
    s = threading.Thread(target=sampler)
    t0 = time.perf_counter()
    s.start()
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    stop.set()
    s.join()
    run.seconds += time.perf_counter() - t0


def reference(n: int, budget: int) -> float:
    """Seconds per job of the bare pipeline in this process (model loaded once)."""
    from treesketch import Pipeline, RefineSettings

    pipeline = Pipeline("tsn", RefineSettings(budget=budget))
    pipeline.with_settings(budget=2).run(SKETCH)  # warm-up
    t0 = time.perf_counter()
    for _ in range(n):
        pipeline.run(SKETCH)
    return (time.perf_counter() - t0) / n


def pct(xs: list[float], q: float) -> float:
    return 1000 * statistics.quantiles(xs, n=100)[q - 1] if len(xs) >= 2 else float("nan")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--jobs", type=int, default=40)
    ap.add_argument("--clients", type=int, default=8)
    ap.add_argument("--budget", type=int, default=20)
    ap.add_argument("--workers", default="1,2")
    ap.add_argument("--memory-jobs", type=int, default=100)
    ap.add_argument("--memory-budget", type=int, default=5)
    ap.add_argument("--reference", type=int, default=6, help="bare-loop jobs (0: skip)")
    args = ap.parse_args()

    print(
        f"machine: {platform.machine()}, {os.cpu_count()} CPUs, load average "
        f"{os.getloadavg()[0]:.2f}; {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}"
    )
    if args.reference:
        per = reference(args.reference, args.budget)
        print(
            f"reference: bare pipeline loop, budget {args.budget}: {per:.2f} s/job = "
            f"{60 / per:.1f} jobs/min (one process)"
        )
    worker_counts = [int(w) for w in args.workers.split(",")]
    print(
        "| workers | jobs | failed | jobs/min | GET /jobs/{id} p50 / p95 ms | /health p50 / p95 ms "
        "| samples (all busy) | RSS MB after 10 jobs (server + workers) |"
    )
    print("|---:|---:|---:|---:|---:|---:|---:|---:|")
    runs = []
    for w in worker_counts:
        with tempfile.TemporaryDirectory(prefix="bench-service-") as d:
            server = Server(w, Path(d), args.budget)
            try:
                run = Run(workers=w)
                run_jobs(server, run, args.jobs, args.clients, args.budget, rss_at=(10,))
                seconds, done = run.seconds, run.done
                latency = {k: list(v) for k, v in run.latency.items()}
                if w == max(worker_counts) and args.memory_jobs > args.jobs:
                    # the same server and tally, on to memory_jobs at a small budget
                    run_jobs(
                        server,
                        run,
                        args.memory_jobs - args.jobs,
                        args.clients,
                        args.memory_budget,
                        rss_at=(args.memory_jobs,),
                    )
            finally:
                server.stop()
        r10 = run.rss.get(10, {})
        print(
            f"| {w} | {done} | {run.failed} | {60 * done / seconds:.1f} "
            f"| {pct(latency['job'], 50):.1f} / {pct(latency['job'], 95):.1f} "
            f"| {pct(latency['health'], 50):.1f} / {pct(latency['health'], 95):.1f} "
            f"| {len(latency['health'])} "
            f"| {r10.get('server', 0):.0f} + {r10.get('workers', 0):.0f} |",
            flush=True,
        )
        runs.append(run)
    last = runs[-1].rss
    if args.memory_jobs in last:
        a, b = last[10], last[args.memory_jobs]
        print(
            f"\nmemory, {worker_counts[-1]} workers: after 10 jobs {a['server']:.0f} + "
            f"{a['workers']:.0f} MB; after {args.memory_jobs} jobs {b['server']:.0f} + "
            f"{b['workers']:.0f} MB (server + workers); load average now "
            f"{os.getloadavg()[0]:.2f}"
        )


if __name__ == "__main__":
    main()
