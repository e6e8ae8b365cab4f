"""treesketch.service: a job of several drawings of one tree (``sketch`` parts, a ``yaw``
each) and the finished tree's outline from another side (``GET /jobs/{id}/outline.png``).
One real worker process, a fixed palm as the first estimate."""

from __future__ import annotations

import io
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from fastapi.testclient import TestClient
from PIL import Image
from service_helpers import finished, palm_sketch_png, png, wait_for

from treesketch.service import VIEW_ARTEFACTS, JobStore, Limits, ServiceConfig, create_app
from treesketch.service.limits import LimitError, parse_options
from treesketch.service.runner import JobOptions
from treesketch.views import MAX_VIEWS

ESTIMATOR = "service_helpers:palm_estimator"


def _parts(*drawings: bytes) -> list[tuple[str, tuple[str, bytes, str]]]:
    return [("sketch", (f"v{i}.png", d, "image/png")) for i, d in enumerate(drawings, 1)]


@pytest.fixture(scope="module")
def front() -> bytes:
    return palm_sketch_png(3)


@pytest.fixture(scope="module")
def side() -> bytes:
    return palm_sketch_png(5)


@pytest.fixture(scope="module")
def client(tmp_path_factory: pytest.TempPathFactory) -> Iterator[TestClient]:
    config = ServiceConfig(
        data=tmp_path_factory.mktemp("views"), workers=1, estimator=ESTIMATOR, default_budget=3
    )
    with TestClient(create_app(config), base_url="http://127.0.0.1") as c:
        yield c


@pytest.fixture(scope="module")
def two_view_job(client: TestClient, front: bytes, side: bytes) -> dict:
    r = client.post("/jobs", files=_parts(front, side), data={"yaw": ["0", "90"], "budget": "3"})
    assert r.status_code == 202, r.text
    body = r.json()
    assert body["options"]["yaws"] == [90.0]
    assert {"view2_before.png", "view2_after.png"} <= set(body["links"])
    assert "view3_before.png" not in body["links"]
    store: JobStore = client.app.state.store
    # both drawings stored beside each other, as sent
    assert store.read_uploads(body["id"], 2) == [front, side]
    return wait_for(client, body["id"], finished, timeout=180.0)


def test_two_drawings_make_one_tree_with_both_views(client: TestClient, two_view_job: dict) -> None:
    job = two_view_job
    assert job["state"] == "done", job["error"]
    views = job["result"]["views"]
    assert [v["yaw"] for v in views] == [0.0, 90.0]
    assert [v["searched"] for v in views] == [False, False]
    # the search minimises the views' mean distance: one view may give a little for the other
    before = np.mean([v["loss_before"] for v in views])
    after = np.mean([v["loss_after"] for v in views])
    assert after <= before + 1e-9
    assert after == pytest.approx(job["result"]["losses"]["after"])
    for name in ("view2_before.png", "view2_after.png"):
        r = client.get(job["links"][name])
        assert r.status_code == 200 and r.headers["content-type"] == "image/png", name
        im = Image.open(io.BytesIO(r.content))
        assert im.size == (256, 256) and np.asarray(im).min() < 128, name  # a drawn tree
    # the comparison has a row per view
    one_row = Image.open(io.BytesIO(client.get(job["links"]["sketch_before.png"]).content))
    compare = Image.open(io.BytesIO(client.get(job["links"]["compare.png"]).content))
    assert compare.height > 2 * one_row.height
    # the views' sketches differ: the second is the tree from its side
    a = client.get(job["links"]["sketch_after.png"]).content
    assert a != client.get(job["links"]["view2_after.png"]).content


@pytest.mark.slow
def test_an_unknown_side_is_searched(client: TestClient, front: bytes, side: bytes) -> None:
    r = client.post(
        "/predict",
        files=_parts(front, side),
        data={"yaw": ["", "?"], "budget": "2", "time_limit": "60"},
    )
    assert r.status_code == 200, r.text
    body = r.json()
    views = body["views"]
    assert len(views) == 2 and views[1]["searched"] is True and 0 <= views[1]["yaw"] < 360
    assert body["links"]["view2_after.png"].endswith("/view2_after.png")


def test_one_drawing_has_no_view_files(client: TestClient, front: bytes) -> None:
    r = client.post("/jobs", files=_parts(front), data={"yaw": "0", "refine": "false"})
    assert r.status_code == 202, r.text
    job = wait_for(client, r.json()["id"], finished, timeout=180.0)
    assert job["state"] == "done" and "views" not in job["result"]
    assert "yaws" not in job["options"]  # stored and shown as before
    assert not set(VIEW_ARTEFACTS) & set(job["links"])
    r = client.get(f"/jobs/{job['id']}/view2_before.png")
    assert r.status_code == 404 and "1 drawing" in r.json()["detail"]


@pytest.mark.parametrize(
    ("second", "status", "words"),
    [
        (b"not a picture", 400, "view 2: "),
        (b"", 400, "view 2: the uploaded sketch is empty"),
        ("TINY", 422, "view 2: the sketch is 4x4 px"),
    ],
    ids=["garbage", "empty", "tiny"],
)
def test_a_bad_second_drawing_is_refused_naming_it(
    client: TestClient, front: bytes, second: bytes | str, status: int, words: str
) -> None:
    data = png(np.zeros((4, 4), np.uint8)) if second == "TINY" else second
    store: JobStore = client.app.state.store
    uploads = set(store.uploads.iterdir())
    before = client.get("/status").json()["jobs"]
    r = client.post("/jobs", files=_parts(front, data), data={"yaw": ["0", "90"]})
    assert r.status_code == status, r.text
    assert r.json()["detail"].startswith(words), r.json()["detail"]
    assert client.get("/status").json()["jobs"] == before  # nothing queued
    assert set(store.uploads.iterdir()) == uploads  # nothing written


@pytest.mark.parametrize(
    ("count", "yaws", "status", "words"),
    [
        (MAX_VIEWS + 1, None, 422, f"at most {MAX_VIEWS} drawings"),
        (2, [], 422, "2 drawings and 0 'yaw' fields"),
        (2, ["0", "90", "180"], 422, "2 drawings and 3 'yaw' fields"),
        (2, ["45", "90"], 422, "yaw of view 1 must be 0"),
        (2, ["0", "north"], 422, "yaw of view 2"),
        (3, ["90", "inf"], 422, "yaw of view 3"),
        (1, ["30"], 422, "yaw of view 1 must be 0"),
    ],
)
def test_views_and_yaws_are_checked_before_queueing(
    client: TestClient,
    front: bytes,
    count: int,
    yaws: list[str] | None,
    status: int,
    words: str,
) -> None:
    before = client.get("/status").json()["jobs"]
    data = {"yaw": ["0"] + ["90"] * (count - 1) if yaws is None else yaws}
    r = client.post("/jobs", files=_parts(*[front] * count), data=data)
    assert r.status_code == status, r.text
    assert words in r.json()["detail"]
    assert client.get("/status").json()["jobs"] == before


@pytest.mark.slow
def test_a_full_form_of_four_drawings_is_taken(client: TestClient, front: bytes) -> None:
    """Every drawing, its yaw and every option are within the form's part limit."""
    options = {
        "refine": "false",
        "budget": "2",
        "time_limit": "30",
        "height": "6",
        "estimator": ESTIMATOR,
        "max_faces": "20000",
        "species": "palm",
    }
    yaws = ["0", "90", "180", "270"]
    r = client.post("/jobs", files=_parts(*[front] * MAX_VIEWS), data={**options, "yaw": yaws})
    assert r.status_code == 202, r.text
    assert r.json()["options"]["yaws"] == [90.0, 180.0, 270.0]
    job = wait_for(client, r.json()["id"], finished, timeout=180.0)
    assert job["state"] == "done", job["error"]
    assert len(job["result"]["views"]) == MAX_VIEWS
    assert client.get(job["links"]["view4_after.png"]).status_code == 200


def test_parse_options_yaws() -> None:
    def yaws(values: list[str], views: int) -> tuple[float | None, ...]:
        return parse_options({"yaw": values}, Limits(), ["tsn"], "tsn", views=views).yaws

    assert yaws([], 1) == () and yaws(["0"], 1) == ()
    assert yaws(["90"], 2) == (90.0,)  # one per drawing after the first
    assert yaws(["", "-90", "?", "725"], 4) == (270.0, None, 5.0)
    with pytest.raises(LimitError, match="1 to 4 drawings"):
        parse_options({}, Limits(), ["tsn"], "tsn", views=5)
    opts = JobOptions(yaws=(90.0, None))
    assert JobOptions.from_dict(opts.to_dict()) == opts and opts.views == 3
    assert "yaws" not in JobOptions().to_dict()


def test_the_body_limit_takes_four_drawings() -> None:
    # the whole body may hold more than one full-size picture, less than four of them
    limits = Limits()
    assert limits.max_upload_bytes < limits.max_body_bytes < MAX_VIEWS * limits.max_upload_bytes


def test_store_keeps_and_removes_every_drawing(tmp_path: Path) -> None:
    store = JobStore(tmp_path)
    job = store.create([b"a" * 10, b"b" * 20, b"c" * 30], {"yaws": [90, None]}, max_queued=1)
    assert job is not None and job.bytes == 60
    assert store.read_uploads(job.id, 3) == [b"a" * 10, b"b" * 20, b"c" * 30]
    assert store.create([b"d", b"e"], {}, max_queued=1) is None  # the queue is full
    assert sorted(p.name for p in store.uploads.iterdir()) == [
        f"{job.id}.img",
        f"{job.id}.view2.img",
        f"{job.id}.view3.img",
    ]
    assert store.claim_next() is not None
    store.result_dir(job.id).mkdir()
    store.finish(job.id, {"evaluations": 0})
    assert store.expire(max_age_s=0.0, max_bytes=None) == [job.id]
    assert not list(store.uploads.iterdir())


def test_orphaned_view_uploads_are_swept(tmp_path: Path) -> None:
    import os

    store = JobStore(tmp_path)
    orphan = "0" * 32
    paths = [store.upload_path(orphan), store.upload_path(orphan, 2)]
    for p in paths:
        p.write_bytes(b"x")
        os.utime(p, (time.time() - 7200, time.time() - 7200))
    (store.uploads / "notes.view2.img").write_bytes(b"mine")  # not the store's: kept
    assert store.expire(max_age_s=3600.0, max_bytes=None) == [orphan]
    assert not any(p.exists() for p in paths)
    assert (store.uploads / "notes.view2.img").exists()


# -- the outline from another side ------------------------------------------------------
def _outline(client: TestClient, job_id: str, query: str) -> np.ndarray:
    r = client.get(f"/jobs/{job_id}/outline.png?{query}")
    assert r.status_code == 200, r.text
    assert r.headers["content-type"] == "image/png" and "max-age" in r.headers["cache-control"]
    return np.asarray(Image.open(io.BytesIO(r.content)))


def test_outline_from_a_turn(client: TestClient, two_view_job: dict) -> None:
    from treesketch.trees import tree_sketch
    from weberpenn import TreeParams

    job_id, res = two_view_job["id"], two_view_job["result"]
    front = _outline(client, job_id, "turn=0&size=128")
    assert front.shape == (128, 128) and front.min() < 128
    turned = _outline(client, job_id, "turn=90&size=128")
    assert not np.array_equal(front, turned)
    assert np.array_equal(_outline(client, job_id, "turn=-270&size=128"), turned)  # mod 360
    # drawn at the result's yaw + turn, as the renderer turns
    want = tree_sketch(TreeParams(res["params"]), res["species"], (res["yaw"] + 90) % 360, 128)
    assert np.array_equal(turned, want)
    assert _outline(client, job_id, "turn=12.5").shape == (256, 256)  # the default size


@pytest.mark.parametrize(
    ("query", "words"),
    [
        ("turn=nan", "turn must be finite"),
        ("turn=inf", "turn must be finite"),
        ("turn=1e9", "turn must be finite"),
        ("turn=left", "turn must be a number"),
        ("size=0", "size must be a whole number"),
        ("size=513", "size must be a whole number"),
        ("size=128.5", "size must be a whole number"),
        ("size=99999999999999999999", "size must be a whole number"),
    ],
)
def test_outline_query_is_checked(
    client: TestClient, two_view_job: dict, query: str, words: str
) -> None:
    r = client.get(f"/jobs/{two_view_job['id']}/outline.png?{query}")
    assert r.status_code == 422 and words in r.json()["detail"], r.text


def test_outline_of_no_tree(client: TestClient) -> None:
    assert client.get("/jobs/nope/outline.png").status_code == 404
    blank = png(np.full((64, 64), 255, np.uint8))
    job = wait_for(
        client, client.post("/jobs", files=_parts(blank)).json()["id"], finished, timeout=180.0
    )
    assert job["state"] == "failed"
    r = client.get(f"/jobs/{job['id']}/outline.png")
    assert r.status_code == 409 and "no tree" in r.json()["detail"]
