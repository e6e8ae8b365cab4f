"""``GET /jobs/{id}/outlines.png?view=N`` (treesketch.service.outlines): a finished job's
drawing's outline (red) over its tree's (blue) at each drawn view, and its refusals.  One
real worker process, a fixed palm as the first estimate, no refinement (fast)."""

from __future__ import annotations

import io
from collections.abc import Iterator

import numpy as np
import pytest
from fastapi.testclient import TestClient
from PIL import Image
from service_helpers import finished, palm_sketch_png, wait_for

from refine.envelope import DRAWING_RED, TREE_BLUE
from treesketch.service import ServiceConfig, create_app
from treesketch.steps import SKETCH_SIZE

ESTIMATOR = "service_helpers:palm_estimator"


@pytest.fixture(scope="module")
def client(tmp_path_factory: pytest.TempPathFactory) -> Iterator[TestClient]:
    config = ServiceConfig(data=tmp_path_factory.mktemp("outlines"), workers=1, estimator=ESTIMATOR)
    with TestClient(create_app(config), base_url="http://127.0.0.1") as c:
        yield c


@pytest.fixture(scope="module")
def two_view_job(client: TestClient) -> dict:
    parts = [
        ("sketch", (f"v{i}.png", palm_sketch_png(seed), "image/png"))
        for i, seed in enumerate((3, 5), 1)
    ]
    r = client.post("/jobs", files=parts, data={"yaw": ["0", "90"], "refine": "false"})
    assert r.status_code == 202, r.text
    job = wait_for(client, r.json()["id"], finished, timeout=180.0)
    assert job["state"] == "done", job["error"]
    return job


def _colours(data: bytes) -> tuple[tuple[int, int], int, int]:
    """(size, red pixels, blue pixels) of a PNG."""
    im = Image.open(io.BytesIO(data))
    assert im.mode == "RGB", im.mode
    rgb = np.asarray(im)
    red = int(np.all(rgb == DRAWING_RED, axis=2).sum())
    blue = int(np.all(rgb == TREE_BLUE, axis=2).sum())
    return im.size, red, blue


def test_each_view_has_its_outlines(client: TestClient, two_view_job: dict) -> None:
    job = two_view_job
    assert job["links"]["outlines.png"] == f"/jobs/{job['id']}/outlines.png"
    pictures = []
    for view in ("1", "2"):
        r = client.get(job["links"]["outlines.png"], params={"view": view})
        assert r.status_code == 200, r.text
        assert r.headers["content-type"] == "image/png"
        size, red, blue = _colours(r.content)
        # the drawing's outline in red and the tree's in blue, at the sketches' size
        assert size == (SKETCH_SIZE, SKETCH_SIZE), size
        assert red > 200 and blue > 200, (view, red, blue)
        pictures.append(r.content)
    # view 1 by default; the second view's picture is its own
    assert client.get(job["links"]["outlines.png"]).content == pictures[0]
    assert pictures[0] != pictures[1]


@pytest.mark.parametrize("view", ["0", "3", "x", "-1", "100"])
def test_a_view_out_of_range_is_404(client: TestClient, two_view_job: dict, view: str) -> None:
    r = client.get(two_view_job["links"]["outlines.png"], params={"view": view})
    assert r.status_code == 404 and "2 drawing(s)" in r.json()["detail"], r.text


def test_an_unknown_or_unfinished_job_is_404(client: TestClient, two_view_job: dict) -> None:
    r = client.get("/jobs/nope/outlines.png")
    assert r.status_code == 404 and "no job" in r.json()["detail"]
    r = client.post(
        "/jobs",
        files={"sketch": ("s.png", palm_sketch_png(3), "image/png")},
        data={"budget": "1000"},
    )
    job_id = r.json()["id"]
    try:
        r = client.get(f"/jobs/{job_id}/outlines.png")
        assert r.status_code == 404, r.text
        detail = r.json()["detail"]
        assert ("queued" in detail or "running" in detail) and "no tree" in detail, detail
    finally:
        client.delete(f"/jobs/{job_id}")
    wait_for(client, job_id, finished, timeout=180.0)


def test_a_job_without_the_picture_is_404(client: TestClient, two_view_job: dict) -> None:
    """A job that finished before the pictures were made (its file removed here)."""
    store = client.app.state.store
    path = store.result_dir(two_view_job["id"]) / "view2_outlines.png"
    kept = path.read_bytes()
    path.unlink()
    try:
        r = client.get(two_view_job["links"]["outlines.png"], params={"view": "2"})
        assert r.status_code == 404 and "no outlines picture" in r.json()["detail"]
    finally:
        path.write_bytes(kept)


def test_the_route_is_behind_the_token(tmp_path) -> None:
    config = ServiceConfig(data=tmp_path, workers=1, estimator=ESTIMATOR, token="s3cret")
    c = TestClient(create_app(config), base_url="http://127.0.0.1")  # no workers started
    assert c.get("/jobs/nope/outlines.png").status_code == 401
    r = c.get("/jobs/nope/outlines.png", headers={"Authorization": "Bearer s3cret"})
    assert r.status_code == 404
