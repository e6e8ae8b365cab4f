"""Helpers for the service tests: a cheap estimator that spawned workers can import."""

from __future__ import annotations

import asyncio
import contextlib
import io
import time
from collections.abc import Callable, Coroutine, Iterator
from concurrent.futures import ThreadPoolExecutor
from typing import Any, TypeVar

import numpy as np

from treesketch import Estimate
from treesketch.service.inprocess import serve
from treesketch.service.store import FINISHED
from weberpenn import species

T = TypeVar("T")


class PalmEstimator:
    """A fixed palm as the first estimate: no network, fast to grow and render."""

    name = "palm-8"

    def estimate(self, sketch: np.ndarray) -> Estimate:
        return Estimate(species.sample("palm", 8), "palm", {"palm": 1.0})


palm_estimator = PalmEstimator()


class LeaningPalmEstimator:
    """A palm leaning 45 degrees, drawn from yaw 180: it leans left seen from one side and
    right from the other (yaw 90: left, 270: right), and its result's yaw is not 0 (the
    exported tree is turned to face the drawing).  No network, fast to grow."""

    name = "leaning-palm"

    def estimate(self, sketch: np.ndarray) -> Estimate:
        from weberpenn.controls import apply_controls

        params = apply_controls(species.sample("palm", 8), {"trunk_lean": 45.0})
        return Estimate(params, "palm", {"palm": 1.0}, yaw=180.0)


leaning_palm_estimator = LeaningPalmEstimator()


class NotATreeEstimator(PalmEstimator):
    """The fixed palm, from an estimator sure the drawing is no tree (probability 0)."""

    name = "not-a-tree"

    def estimate(self, sketch: np.ndarray) -> Estimate:
        return Estimate(species.sample("palm", 8), "palm", {"palm": 1.0}, tree_probability=0.0)


not_a_tree_estimator = NotATreeEstimator()


def png(img: np.ndarray) -> bytes:
    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(img).save(buf, format="PNG")
    return buf.getvalue()


def palm_sketch_png(seed: int = 3) -> bytes:
    from render.sketch import SketchRenderer
    from weberpenn import build_mesh, grow

    m = build_mesh(grow(species.sample("palm", seed)), species="palm")
    return png(SketchRenderer(m).sketch(0, 256))


@contextlib.contextmanager
def http_service(config: Any) -> Iterator[Any]:
    """A real server of ``config``'s app (``treesketch.service.inprocess.serve``) and an
    httpx client on it."""
    import httpx

    from treesketch.service import create_app

    with serve(create_app(config)) as url, httpx.Client(base_url=url, timeout=30) as http:
        yield http


def submit(http: Any, sketch: bytes, **fields: str) -> str:
    """``POST /jobs`` (an httpx client or a TestClient) with ``sketch`` and form ``fields``;
    the new job's id."""
    r = http.post("/jobs", files={"sketch": ("s.png", sketch, "image/png")}, data=fields)
    assert r.status_code == 202, r.text
    return r.json()["id"]


def wait_for(http: Any, job_id: str, test: Callable[[dict], bool], timeout: float = 120.0) -> dict:
    """Poll ``GET /jobs/{job_id}`` (an httpx client or a TestClient) until ``test`` holds."""
    deadline = time.monotonic() + timeout
    body: dict = {}
    while time.monotonic() < deadline:
        body = http.get(f"/jobs/{job_id}").json()
        if test(body):
            return body
        time.sleep(0.05)
    raise AssertionError(f"job {job_id}: condition not met in {timeout} s; last {body}")


def finished_job_id(server: str, sketch: bytes, timeout: float = 180.0, **fields: str) -> str:
    """Submit ``sketch`` with form ``fields`` to the server at ``server`` and wait until
    the job is done (a failed or cancelled one fails the caller); its id."""
    import httpx

    with httpx.Client(base_url=server, timeout=30) as http:
        job_id = submit(http, sketch, **fields)
        body = wait_for(http, job_id, finished, timeout=timeout)
    assert body["state"] == "done", body
    return job_id


def refining(body: dict) -> bool:
    return body["state"] == "running" and (body["progress"] or {}).get("evaluations", 0) >= 1


def finished(body: dict) -> bool:
    return body["state"] in FINISHED


def check_broken_estimator_is_reported(app: Any, sketch: bytes) -> None:
    """``app``'s estimator cannot load: /health turns to an error naming it once the pool
    has tried ``LOAD_ATTEMPTS`` times, and a new job is refused (503)."""
    from fastapi.testclient import TestClient

    from treesketch.service.poolbase import LOAD_ATTEMPTS

    pool = app.state.pool
    pool.respawn_backoff = 0.1
    with TestClient(app, base_url="http://127.0.0.1") as c:
        deadline = time.monotonic() + 120
        while c.get("/health").json()["status"] == "ok":
            assert time.monotonic() < deadline, pool.status()
            time.sleep(0.2)
        h = c.get("/health").json()
        assert h["status"] == "error" and pool.estimator in h["error"]
        assert pool.replaced == LOAD_ATTEMPTS - 1
        r = c.post("/jobs", files={"sketch": ("s.png", sketch, "image/png")})
        assert r.status_code == 503 and "no worker can start" in r.json()["detail"]


def run_coroutine(coro: Coroutine[Any, Any, T]) -> T:
    """``asyncio.run(coro)`` on a thread of its own.  A page module's browser
    (Playwright's sync API), alive for the rest of its worker's session, keeps an event
    loop running on the main thread, where ``asyncio.run`` refuses to start: a service
    test that a worker runs after a page module would fail for the order alone."""
    with ThreadPoolExecutor(1) as pool:
        return pool.submit(asyncio.run, coro).result()
