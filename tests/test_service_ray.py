"""The job service with its workers as Ray actors (``executor="ray"``) on a local Ray with
2 CPUs, started once for the module: the same result as the local pool, progress over
the events stream, cancel, a job's own failure not retried, and actors killed mid-job
(the job is retried on another actor; lost twice, it fails with a message)."""

from __future__ import annotations

import json
import os
import signal
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from fastapi.testclient import TestClient
from service_helpers import (
    check_broken_estimator_is_reported,
    finished,
    palm_sketch_png,
    png,
    refining,
    submit,
    wait_for,
)

from treesketch.service import ServiceConfig, create_app

ray = pytest.importorskip("ray", reason="the cluster extra (pip install .[cluster])")

from treesketch.executor import RayExecutor  # noqa: E402

pytestmark = pytest.mark.slow

ESTIMATOR = "service_helpers:palm_estimator"
LONG = {"budget": "1000", "time_limit": "600"}  # runs until cancelled or killed


@pytest.fixture(scope="module")
def ray_session() -> Iterator[None]:
    ex = RayExecutor(num_cpus=2)  # the pools below use this Ray and leave it running
    try:
        yield
    finally:
        ex.close()
    assert not ray.is_initialized()


@pytest.fixture(scope="module")
def client(ray_session: None, tmp_path_factory: pytest.TempPathFactory) -> Iterator[TestClient]:
    config = ServiceConfig(
        data=tmp_path_factory.mktemp("ray_service"),
        workers=2,
        estimator=ESTIMATOR,
        default_budget=3,
        executor="ray",
        # the cancel test checks the flag path: on a busy 2-core machine one evaluation can
        # outlast the default 3 s grace, and the kill would hide whether the flag worked
        cancel_grace=30.0,
    )
    with TestClient(create_app(config), base_url="http://127.0.0.1") as c:
        yield c
    assert ray.is_initialized()  # not the pool's Ray: left to its owner


def comparable(summary: dict) -> dict:
    """A result without what depends on the run (times, which worker)."""
    return {k: v for k, v in summary.items() if k not in ("timings", "worker")}


def test_serve_command_options(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    """Checked before serving, without starting Ray (this runs before the module's Ray)."""
    import uvicorn
    from typer.testing import CliRunner

    import treesketch.executor
    from treesketch.cli import app
    from treesketch.service.ray_pool import RayWorkerPool

    base = ["serve", "--data", str(tmp_path)]
    r = CliRunner().invoke(app, [*base, "--address", "127.0.0.1:1"])
    assert r.exit_code == 2 and "--executor ray" in r.output
    r = CliRunner().invoke(app, [*base, "--executor", "ray", "--address", "127.0.0.1:1"])
    assert r.exit_code == 2 and "no Ray cluster answers at 127.0.0.1:1" in r.output
    assert not ray.is_initialized()
    seen: dict = {}
    monkeypatch.setattr(uvicorn, "run", lambda a, **kw: seen.update(kw, app=a))
    monkeypatch.setattr(treesketch.executor, "start_ray", lambda *a: seen.update(ray=a) or False)
    r = CliRunner().invoke(app, [*base, "--executor", "ray", "--estimator", "template"])
    assert r.exit_code == 0, r.output
    assert "Ray actors on a local Ray" in r.output and seen["ray"] == (None, None)
    config = seen["app"].state.config
    assert config.executor == "ray" and config.workers is None and config.address is None
    assert isinstance(seen["app"].state.pool, RayWorkerPool)


def test_same_result_as_the_local_pool_with_progress_events(
    client: TestClient, sketch: bytes, tmp_path: Path
) -> None:
    health = client.get("/health").json()
    assert health["status"] == "ok" and health["workers"] == 2
    job_id = submit(client, sketch, budget="3")
    kinds, bodies = [], []
    with client.stream("GET", f"/jobs/{job_id}/events") as s:
        for line in s.iter_lines():
            if line.startswith("event: "):
                kinds.append(line[7:])
            elif line.startswith("data: "):
                bodies.append(json.loads(line[6:]))
    assert kinds[0] == "progress" and kinds[-1] == "done", kinds
    evals = [b["progress"]["evaluations"] for b in bodies]
    assert evals == sorted(evals) and evals[-1] == 3
    via_ray = bodies[-1]["result"]
    worker = via_ray["worker"]
    assert worker["attempt"] == 1 and worker["node"] == ray.get_runtime_context().get_node_id()
    assert worker["pid"] in {w["pid"] for w in client.get("/status").json()["workers"]}

    local = ServiceConfig(data=tmp_path / "local", workers=1, estimator=ESTIMATOR)
    with TestClient(create_app(local), base_url="http://127.0.0.1") as lc:
        local_id = submit(lc, sketch, budget="3")
        body = wait_for(lc, local_id, finished)
        assert body["state"] == "done", body["error"]
        assert "worker" not in body["result"]  # the local pool's answer is as it was
        assert comparable(via_ray) == comparable(body["result"])
        for name in ("tree.json", "tree_sapling.py"):  # written by the front, same bytes
            a = client.get(f"/jobs/{job_id}/{name}")
            b = lc.get(f"/jobs/{local_id}/{name}")
            assert a.status_code == b.status_code == 200 and a.content == b.content, name
    glb = client.get(f"/jobs/{job_id}/tree.glb")
    assert glb.status_code == 200 and glb.content[:4] == b"glTF"


def test_cancel_a_running_job(client: TestClient, sketch: bytes) -> None:
    pool = client.app.state.pool
    replaced = pool.replaced
    job_id = submit(client, sketch, **LONG)
    wait_for(client, job_id, refining)  # progress crossed from the actor
    # the current best tree crossed too: the front wrote it for the page
    body = wait_for(client, job_id, lambda b: bool((b["progress"] or {}).get("preview")))
    assert body["state"] == "running"
    glb = client.get(f"/jobs/{job_id}/preview/tree.glb")
    assert glb.status_code == 200 and glb.content[:4] == b"glTF"
    png_ = client.get(f"/jobs/{job_id}/preview/sketch.png")
    assert png_.status_code == 200 and png_.content[:8] == b"\x89PNG\r\n\x1a\n"
    r = client.delete(f"/jobs/{job_id}")
    assert r.status_code == 202 and r.json()["cancelling"]
    t0 = time.monotonic()
    body = wait_for(client, job_id, finished, timeout=40)
    assert body["state"] == "cancelled" and time.monotonic() - t0 < 25
    assert pool.replaced == replaced  # stopped by its flag, not killed
    assert client.get("/health").json()["busy"] == 0
    assert client.get(f"/jobs/{job_id}/preview/tree.glb").status_code == 404  # no leftovers


def test_two_drawings_of_one_tree(client: TestClient, sketch: bytes) -> None:
    """A job of two drawings: both cross to the actor, the front writes every view's
    sketches."""
    side = palm_sketch_png(5)
    r = client.post(
        "/jobs",
        files=[
            ("sketch", ("a.png", sketch, "image/png")),
            ("sketch", ("b.png", side, "image/png")),
        ],
        data={"yaw": ["0", "90"], "budget": "2"},
    )
    assert r.status_code == 202, r.text
    body = wait_for(client, r.json()["id"], finished)
    assert body["state"] == "done", body["error"]
    assert [v["yaw"] for v in body["result"]["views"]] == [0.0, 90.0]
    for name in ("view2_before.png", "view2_after.png"):
        got = client.get(body["links"][name])
        assert got.status_code == 200 and got.content[:8] == b"\x89PNG\r\n\x1a\n", name


def test_a_jobs_own_failure_is_reported_not_retried(client: TestClient) -> None:
    blank = png(np.full((64, 64), 255, np.uint8))
    body = wait_for(client, submit(client, blank), finished)
    assert body["state"] == "failed" and "blank" in body["error"]
    assert "lost" not in body["error"]


def test_killed_actors(client: TestClient, sketch: bytes) -> None:
    """Killed once (ray.kill) the job is retried on another actor and completes; killed
    on both tries (ray.kill, then SIGKILL of its process) it fails with a message."""
    pool = client.app.state.pool
    replaced = pool.replaced

    job_id = submit(client, sketch, budget="3")
    wait_for(client, job_id, lambda b: pool.actor_of(job_id) is not None or finished(b))
    first = pool.actor_of(job_id)
    assert first is not None, "the job finished before the test could kill its actor"
    ray.kill(first)
    body = wait_for(client, job_id, finished)
    assert body["state"] == "done", body["error"]
    assert body["result"]["worker"]["attempt"] == 2

    job_id = submit(client, sketch, **LONG)
    wait_for(client, job_id, refining)
    ray.kill(pool.actor_of(job_id))

    def second_try(body: dict) -> bool:
        workers = client.get("/status").json()["workers"]
        return finished(body) or any(
            w["job"] == job_id and w["attempt"] == 2 and w["ready"] for w in workers
        )

    again = wait_for(client, job_id, second_try)
    assert again["state"] in ("queued", "running"), again  # on another actor
    (w,) = [w for w in client.get("/status").json()["workers"] if w["job"] == job_id]
    os.kill(w["pid"], signal.SIGKILL)  # a crash, as the out-of-memory killer does it
    body = wait_for(client, job_id, finished, timeout=30)
    assert body["state"] == "failed" and "lost 2 times" in body["error"], body["error"]
    # the pool fails the job first, then starts the actor that replaces the lost one (an
    # actor's start, which a loaded machine makes slow): it shows within seconds
    deadline = time.monotonic() + 30
    while pool.replaced < replaced + 3 and time.monotonic() < deadline:
        time.sleep(0.05)
    assert pool.replaced == replaced + 3
    after = submit(client, sketch, budget="2")  # the replacements work
    assert wait_for(client, after, finished)["state"] == "done"


def test_estimator_that_cannot_load_is_reported(
    ray_session: None, tmp_path: Path, sketch: bytes
) -> None:
    config = ServiceConfig(
        data=tmp_path, workers=1, estimator="service_helpers:missing", executor="ray"
    )
    app = create_app(config)
    app.state.pool.cpus_per_worker = 0  # beside the module's pool, which holds both CPUs
    check_broken_estimator_is_reported(app, sketch)
