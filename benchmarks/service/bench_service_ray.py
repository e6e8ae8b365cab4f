"""The job service with its workers as Ray actors: job latency against the local pool, and
a two-node run (jobs on both nodes, then a node killed under a running job).

Each pool runs as the real thing, ``treesketch serve`` in a subprocess:

1. ``--workers 2`` (local worker processes, the reference);
2. ``--executor ray --workers 2`` (a local Ray started by the service, 2 CPUs);
3. ``--executor ray --address ADDR --workers 2`` against Ray's test cluster
   (``ray.cluster_utils.Cluster``): a head raylet and a second raylet on this machine,
   1 CPU each, so the two actors land one per node.

For 1 and 2: the time until every worker is ready, one warm-up job per worker (the
template estimator builds its templates on first use), then ``--jobs`` jobs one after the
other; a job's latency is submit -> ``done`` seen by a client polling every 20 ms, and
its overhead is that minus the worker's own time (``timings.job``).  For 3: ``--jobs``
jobs submitted at once (the node of each is in its result: ``worker.node``), then two
longer jobs, and the second node killed (``remove_node``, no goodbye) while its job runs.

    PYTHONPATH=$PWD .venv/bin/python benchmarks/service/bench_service_ray.py --jobs 6 --budget 3
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import httpx

from benchmarks.lib.serve_process import FINISHED, ServeProcess

ROOT = Path(__file__).resolve().parents[2]
SKETCH = ROOT / "examples" / "hand" / "palm.png"


class Server(ServeProcess):
    """The service with the template estimator, and a client to submit and wait."""

    def __init__(self, args: list[str], data: Path, workers: int, log: Path) -> None:
        super().__init__(["--estimator", "template", *args], data, workers, log)
        self.http = httpx.Client(base_url=self.url, timeout=30)

    def submit(self, budget: int) -> str:
        files = {"sketch": ("palm.png", SKETCH.read_bytes(), "image/png")}
        data = {"budget": str(budget), "estimator": "template"}
        r = self.http.post("/jobs", files=files, data=data)
        r.raise_for_status()
        return r.json()["id"]

    def wait(self, job_id: str, timeout: float = 600.0) -> dict[str, Any]:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            body = self.http.get(f"/jobs/{job_id}").json()
            if body["state"] in FINISHED:
                return body
            time.sleep(0.02)
        raise RuntimeError(f"job {job_id} did not finish in {timeout} s")


def latency(server: Server, jobs: int, budget: int) -> dict[str, Any]:
    warm = [server.submit(budget) for _ in range(2)]
    for j in warm:
        assert server.wait(j)["state"] == "done"
    rows = []
    for _ in range(jobs):
        t0 = time.perf_counter()
        body = server.wait(server.submit(budget))
        total = time.perf_counter() - t0
        assert body["state"] == "done", body["error"]
        work = body["result"]["timings"]["job"]
        rows.append({"latency": total, "work": work, "overhead": total - work})
    return {
        "start_s": server.start_s,
        "jobs": rows,
        **{
            f"median_{k}": statistics.median(r[k] for r in rows)
            for k in ("latency", "work", "overhead")
        },
    }


def two_nodes(jobs: int, budget: int, long_budget: int, data: Path) -> dict[str, Any]:
    import ray
    from ray.cluster_utils import Cluster

    # the nodes' workers import this worktree's treesketch, as a real node its install
    os.environ["PYTHONPATH"] = os.pathsep.join(dict.fromkeys([str(ROOT), *sys.path[1:]]))
    cluster = Cluster(
        initialize_head=True, head_node_args={"num_cpus": 1, "include_dashboard": False}
    )
    server = None
    try:
        second = cluster.add_node(num_cpus=1)
        cluster.wait_for_nodes()
        names = {cluster.head_node.node_id: "head", second.node_id: "second"}
        server = Server(["--executor", "ray", "--address", cluster.address], data, 2, data / "log")
        status = server.http.get("/status").json()["workers"]
        actors = {names.get(w["node"], w["node"]) for w in status}
        ids = [server.submit(budget) for _ in range(jobs)]
        t0 = time.perf_counter()
        bodies = [server.wait(j) for j in ids]
        burst_s = time.perf_counter() - t0
        per_job = [
            {
                "state": b["state"],
                "node": names.get(b["result"]["worker"]["node"], "?"),
                "node_id": b["result"]["worker"]["node"][:12],
                "attempt": b["result"]["worker"]["attempt"],
                "seconds": b["result"]["timings"]["job"],
            }
            for b in bodies
        ]
        # two longer jobs, one per actor; kill the second node while its job runs
        long_ids = [server.submit(long_budget) for _ in range(2)]
        killed_at = None
        deadline = time.monotonic() + 300
        while killed_at is None and time.monotonic() < deadline:
            for w in server.http.get("/status").json()["workers"]:
                if names.get(w["node"]) == "second" and w["job"] in long_ids:
                    job = server.http.get(f"/jobs/{w['job']}").json()
                    if (job["progress"] or {}).get("evaluations", 0) >= 1:
                        cluster.remove_node(second, allow_graceful=False)
                        killed_at = {"job": w["job"], "evaluations": job["progress"]["evaluations"]}
                        break
            time.sleep(0.05)
        long_bodies = [server.wait(j) for j in long_ids]
        after = [
            {
                "state": b["state"],
                "error": b["error"],
                "killed_under_it": b["id"] == (killed_at or {}).get("job"),
                **(
                    {
                        "node": names.get(b["result"]["worker"]["node"], "?"),
                        "attempt": b["result"]["worker"]["attempt"],
                    }
                    if b["state"] == "done"
                    else {}
                ),
            }
            for b in long_bodies
        ]
        status = server.http.get("/status").json()
        return {
            "actors_on": sorted(actors),
            "burst_s": burst_s,
            "jobs": per_job,
            "killed": killed_at,
            "long_jobs": after,
            "workers_after": [
                {"node": names.get(w["node"], w["node"][:12]), "ready": w["ready"]}
                for w in status["workers"]
            ],
            "workers_replaced": status["workers_replaced"],
        }
    finally:
        if server is not None:
            server.stop()
        ray.shutdown()
        cluster.shutdown()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--jobs", type=int, default=6)
    ap.add_argument("--budget", type=int, default=3)
    ap.add_argument("--long-budget", type=int, default=15)
    ap.add_argument("--parts", default="latency,two-node")
    ap.add_argument("--out", type=Path, default=None, help="write the numbers as JSON here")
    args = ap.parse_args()
    parts = set(args.parts.split(","))
    out: dict[str, Any] = {
        "machine": f"{platform.machine()}, {os.cpu_count()} CPUs, Python {platform.python_version()}",
        "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
        "load": os.getloadavg(),
    }
    with tempfile.TemporaryDirectory(prefix="bench_service_ray_") as tmp:
        if "latency" in parts:
            for name, extra in (("local pool", []), ("ray pool", ["--executor", "ray"])):
                data = Path(tmp) / name.replace(" ", "_")
                data.mkdir()
                server = Server(extra, data, 2, data / "log")
                try:
                    out[name] = latency(server, args.jobs, args.budget)
                finally:
                    server.stop()
                r = out[name]
                print(
                    f"{name}: start {r['start_s']:.1f} s; median latency {r['median_latency']:.2f} s"
                    f" = work {r['median_work']:.2f} + overhead {r['median_overhead']:.3f} s",
                    flush=True,
                )
        if "two-node" in parts:
            data = Path(tmp) / "two_node"
            data.mkdir()
            out["two-node"] = r = two_nodes(args.jobs, args.budget, args.long_budget, data)
            print(
                f"two nodes: actors on {r['actors_on']}; {args.jobs} jobs in {r['burst_s']:.1f} s"
            )
            for j in r["jobs"]:
                print(
                    f"  job on {j['node']} ({j['node_id']}), attempt {j['attempt']}, {j['state']}"
                )
            print(f"  second node killed under job {r['killed']}")
            for j in r["long_jobs"]:
                print(f"  long job: {j}")
            print(f"  workers after: {r['workers_after']}; replaced {r['workers_replaced']}")
    out["load_after"] = os.getloadavg()
    print(json.dumps(out, indent=1, default=str))
    if args.out is not None:
        from weberpenn.fileio import atomic_write

        atomic_write(args.out, json.dumps(out, indent=1, default=str))


if __name__ == "__main__":
    main()
