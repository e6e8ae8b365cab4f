"""treesketch.service: the job API through FastAPI's TestClient, one real worker process
(a fixed palm as the first estimate, so no network is loaded)."""

from __future__ import annotations

import io
import json
import struct
import zlib
from collections.abc import AsyncIterator, Iterator
from pathlib import Path

import numpy as np
import pytest
from fastapi.testclient import TestClient
from service_helpers import (
    check_broken_estimator_is_reported,
    finished,
    png,
    run_coroutine,
    wait_for,
)

from treesketch.service import ARTEFACTS, JobStore, Limits, ServiceConfig, create_app
from treesketch.service.limits import LimitError, read_form

ESTIMATOR = "service_helpers:palm_estimator"


@pytest.fixture(scope="module")
def client(tmp_path_factory: pytest.TempPathFactory) -> Iterator[TestClient]:
    data = tmp_path_factory.mktemp("service")
    config = ServiceConfig(data=data, workers=1, estimator=ESTIMATOR, default_budget=5)
    with TestClient(create_app(config), base_url="http://127.0.0.1") as c:
        yield c


@pytest.fixture(scope="module")
def done_job(client: TestClient, sketch: bytes) -> dict:
    r = client.post("/jobs", files={"sketch": ("s.png", sketch, "image/png")}, data={"budget": "4"})
    assert r.status_code == 202, r.text
    body = r.json()
    assert body["state"] in ("queued", "running") and r.headers["location"] == body["links"]["self"]
    return wait_for(client, body["id"], finished)


def test_health_and_status(client: TestClient) -> None:
    h = client.get("/health").json()
    assert h["status"] == "ok" and h["estimator"] == ESTIMATOR and h["workers"] == 1
    s = client.get("/status").json()
    assert s["queue"]["max"] == 64 and set(s["jobs"]) >= {"queued", "running", "done"}
    assert s["estimators"] == [ESTIMATOR, "template"]


def test_job_result_and_artefacts(client: TestClient, done_job: dict) -> None:
    assert done_job["state"] == "done", done_job["error"]
    res = done_job["result"]
    assert res["species"] == "palm" and 1 <= res["evaluations"] <= 4
    assert res["losses"]["after"] <= res["losses"]["before"]
    assert len(res["params"]) == 70 and 0 < res["confidence"] <= 1
    assert done_job["progress"]["evaluations"] == res["evaluations"]
    for name, media in ARTEFACTS.items():
        r = client.get(done_job["links"][name])
        assert r.status_code == 200, name
        assert r.headers["content-type"].startswith(media), name
        assert len(r.content) > 100, name
    import trimesh

    glb = client.get(done_job["links"]["tree.glb"]).content
    assert glb[:4] == b"glTF"
    scene = trimesh.load(io.BytesIO(glb), file_type="glb")
    assert len(scene.geometry) == 2  # branches and leaves
    params = client.get(done_job["links"]["tree.json"]).json()
    assert params == res["params"]
    from PIL import Image

    im = Image.open(io.BytesIO(client.get(done_job["links"]["compare.png"]).content))
    assert im.width > im.height > 0


def test_events_stream(client: TestClient, sketch: bytes) -> None:
    r = client.post("/jobs", files={"sketch": ("s.png", sketch, "image/png")}, data={"budget": "3"})
    job_id = r.json()["id"]
    kinds, bodies = [], []
    with client.stream("GET", f"/jobs/{job_id}/events") as s:
        assert s.headers["content-type"].startswith("text/event-stream")
        for line in s.iter_lines():
            if line.startswith("event: "):
                kinds.append(line[7:])
            elif line.startswith("data: "):
                bodies.append(json.loads(line[6:]))
    assert kinds[-1] == "done" and kinds[0] == "progress"
    assert bodies[-1]["result"]["evaluations"] >= 1
    evals = [b["progress"]["evaluations"] for b in bodies]
    assert evals == sorted(evals)


def test_list_jobs(client: TestClient, done_job: dict) -> None:
    jobs = client.get("/jobs?limit=50").json()["jobs"]
    assert done_job["id"] in [j["id"] for j in jobs]
    assert client.get("/jobs?limit=0").status_code == 422


def _png_header(width: int, height: int) -> bytes:
    """A PNG whose header claims width x height (no pixel data worth decoding)."""

    def chunk(kind: bytes, data: bytes) -> bytes:
        return (
            struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
        )

    ihdr = struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0)
    idat = zlib.compress(b"\0" * 1024)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", idat) + chunk(b"IEND", b"")


@pytest.mark.parametrize(
    ("files", "data", "status", "words"),
    [
        (None, {"budget": "5"}, 415, "multipart"),
        ({"budget": (None, "5")}, {}, 422, "no sketch"),
        ({"sketch": ("s.png", b"nope", "image/png")}, {}, 400, "image"),
        ({"sketch": ("s.png", b"", "image/png")}, {}, 400, "empty"),
        ({"sketch": ("s.png", "TINY", "image/png")}, {}, 422, "at least"),
        ({"sketch": ("s.png", "THIN", "image/png")}, {}, 422, "aspect"),
        ({"sketch": ("s.png", _png_header(50000, 50000), "image/png")}, {}, 413, "pixels"),
        ({"sketch": ("s.png", "OK", "image/png")}, {"budget": "0"}, 422, "budget"),
        ({"sketch": ("s.png", "OK", "image/png")}, {"budget": "x"}, 422, "budget"),
        ({"sketch": ("s.png", "OK", "image/png")}, {"time_limit": "-1"}, 422, "time_limit"),
        ({"sketch": ("s.png", "OK", "image/png")}, {"height": "nan"}, 422, "height"),
        ({"sketch": ("s.png", "OK", "image/png")}, {"refine": "maybe"}, 422, "refine"),
        ({"sketch": ("s.png", "OK", "image/png")}, {"estimator": "nns9"}, 422, "estimator"),
        ({"sketch": ("s.png", "OK", "image/png")}, {"colour": "red"}, 422, "unknown option"),
    ],
)
def test_refused_before_queueing(
    client: TestClient, sketch: bytes, files: dict | None, data: dict, status: int, words: str
) -> None:
    stand_in = {
        "TINY": png(np.zeros((4, 4), np.uint8)),
        "THIN": png(np.zeros((10, 200), np.uint8)),
        "OK": sketch,
    }
    if files is not None and "sketch" in files:
        name, content, media = files["sketch"]
        files = {"sketch": (name, stand_in.get(content, content), media)}
    before = client.get("/status").json()["jobs"]
    r = client.post("/jobs", files=files, data=data) if files else client.post("/jobs", data=data)
    assert r.status_code == status, r.text
    assert words in r.json()["detail"]
    assert client.get("/status").json()["jobs"] == before  # nothing queued


def test_not_multipart_and_unknown(client: TestClient) -> None:
    r = client.post("/jobs", content=b"{}", headers={"content-type": "application/json"})
    assert r.status_code == 415 and "multipart" in r.json()["detail"]
    assert client.get("/jobs/nope").status_code == 404
    assert client.get("/jobs/nope/tree.glb").status_code == 404
    assert client.delete("/jobs/nope").status_code == 404


def test_artefact_names_and_states(client: TestClient, done_job: dict) -> None:
    r = client.get(f"/jobs/{done_job['id']}/secret.txt")
    assert r.status_code == 404 and "tree.glb" in r.json()["detail"]
    assert client.delete(f"/jobs/{done_job['id']}").status_code == 409


def test_blank_page_fails_with_message(client: TestClient) -> None:
    blank = png(np.full((64, 64), 255, np.uint8))
    r = client.post("/jobs", files={"sketch": ("b.png", blank, "image/png")})
    body = wait_for(client, r.json()["id"], finished)
    assert body["state"] == "failed" and "blank" in body["error"]
    r = client.post("/predict", files={"sketch": ("b.png", blank, "image/png")})
    assert r.status_code == 422 and "blank" in r.json()["detail"]


def test_predict_waits_for_the_result(client: TestClient, sketch: bytes) -> None:
    r = client.post(
        "/predict",
        files={"sketch": ("s.png", sketch, "image/png")},
        data={"budget": "2", "height": "6"},
    )
    assert r.status_code == 200, r.text
    body = r.json()
    assert body["species"] == "palm" and body["evaluations"] <= 2
    g = client.get(body["glb"])
    assert g.status_code == 200 and g.content[:4] == b"glTF"


def test_expired_job_is_410(client: TestClient, sketch: bytes) -> None:
    r = client.post(
        "/jobs", files={"sketch": ("s.png", sketch, "image/png")}, data={"refine": "false"}
    )
    body = wait_for(client, r.json()["id"], finished)
    assert body["state"] == "done"
    store: JobStore = client.app.state.store
    assert body["id"] in store.expire(max_age_s=0.0, max_bytes=None)
    assert not store.result_dir(body["id"]).exists()
    r = client.get(body["links"]["tree.glb"])
    assert r.status_code == 410 and "expired" in r.json()["detail"]
    assert client.get(body["links"]["self"]).json()["state"] == "expired"


def test_page_is_served(client: TestClient) -> None:
    r = client.get("/")
    assert r.status_code == 200 and "<canvas" in r.text
    assert client.get("/vendor/three/build/three.module.js").status_code == 200
    assert client.get("/vendor/three/examples/jsm/loaders/GLTFLoader.js").status_code == 200


def test_token_and_cors(tmp_path: Path) -> None:
    config = ServiceConfig(
        data=tmp_path, workers=1, estimator=ESTIMATOR, token="s3cret", cors=("http://a.example",)
    )
    # no lifespan: no workers needed to check headers
    c = TestClient(create_app(config), base_url="http://127.0.0.1")
    assert c.get("/health").status_code == 200
    assert c.get("/status").status_code == 401
    assert c.get("/status", headers={"Authorization": "Bearer s3cret"}).status_code == 200
    assert c.get("/status?token=s3cret").status_code == 401  # never from the URL
    r = c.get("/health", headers={"Origin": "http://a.example"})
    assert r.headers["access-control-allow-origin"] == "http://a.example"
    preflight = {"Origin": "http://a.example", "Access-Control-Request-Method": "POST"}
    assert c.options("/jobs", headers=preflight).status_code == 200  # no token needed
    plain = TestClient(
        create_app(ServiceConfig(data=tmp_path / "b", workers=1)), base_url="http://127.0.0.1"
    )
    r = plain.get("/health", headers={"Origin": "http://a.example"})
    assert "access-control-allow-origin" not in r.headers


def test_read_form_stops_a_huge_upload_early() -> None:
    """A 1.5 GB body is refused before 11 MB of it are read."""
    read = [0]

    async def body() -> AsyncIterator[bytes]:
        yield b'--B\r\nContent-Disposition: form-data; name="sketch"; filename="a.png"\r\n\r\n'
        chunk = b"\0" * (1 << 16)  # what uvicorn hands over at a time
        for _ in range(1536 * 16):
            read[0] += len(chunk)
            yield chunk

    with pytest.raises(LimitError) as exc:
        run_coroutine(read_form("multipart/form-data; boundary=B", None, body(), Limits()))
    assert exc.value.status == 413
    assert read[0] < 11 * 1024 * 1024
    read[0] = 0
    with pytest.raises(LimitError) as exc:  # declared up front: refused before any byte
        run_coroutine(read_form("multipart/form-data; boundary=B", "1610612736", body(), Limits()))
    assert exc.value.status == 413 and read[0] == 0


def test_estimator_that_cannot_load_is_reported(tmp_path: Path, sketch: bytes) -> None:
    config = ServiceConfig(data=tmp_path, workers=1, estimator="service_helpers:missing")
    check_broken_estimator_is_reported(create_app(config), sketch)


def test_default_data_folder(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    from treesketch.cli_serve import default_data_dir

    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path))
    assert default_data_dir() == tmp_path / "treesketch"
    monkeypatch.delenv("XDG_DATA_HOME")
    assert default_data_dir() == Path.home() / ".local" / "share" / "treesketch"


def test_retention_by_total_size(tmp_path: Path) -> None:
    """The oldest finished jobs go first until the results fit the size limit."""
    store = JobStore(tmp_path)
    ids = []
    for _ in range(3):
        job = store.create(b"x" * 100, {"budget": 1}, max_queued=8)
        assert job is not None and store.claim_next() is not None
        (store.result_dir(job.id)).mkdir()
        (store.result_dir(job.id) / "tree.glb").write_bytes(b"g" * 1000)
        store.finish(job.id, {"evaluations": 1})
        ids.append(job.id)
    assert store.get(ids[0]).bytes == 1100
    assert store.expire(max_age_s=None, max_bytes=2500) == [ids[0]]
    assert [store.get(i).state for i in ids] == ["expired", "done", "done"]
    assert store.expire(max_age_s=None, max_bytes=2500) == []


def test_serve_warns_off_localhost(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    import uvicorn
    from typer.testing import CliRunner

    from treesketch.cli import app

    seen = {}
    monkeypatch.setattr(uvicorn, "run", lambda a, **kw: seen.update(kw, app=a))
    args = ["serve", "--host", "0.0.0.0", "--data", str(tmp_path), "--workers", "1"]
    r = CliRunner().invoke(app, [*args, "--estimator", "template", "--cors", "http://a.b"])
    assert r.exit_code == 0, r.output
    assert "other machines can reach" in r.output and "--token" in r.output
    config = seen["app"].state.config
    assert seen["host"] == "0.0.0.0" and config.data == tmp_path and config.workers == 1
    assert config.cors == ("http://a.b",) and config.token is None
    r = CliRunner().invoke(app, ["serve", "--data", str(tmp_path), "--token", "t"])
    assert "warning" not in r.output and seen["app"].state.config.token == "t"


def test_the_species_picker_list_and_a_job_for_the_species_meant(
    client: TestClient, sketch: bytes
) -> None:
    listed = client.get("/species").json()["species"]
    names = [s["name"] for s in listed]
    assert names[:5] == ["maple", "pine", "bonsai", "palm", "cherry"] and "fir" in names
    assert all(s["display"] for s in listed)
    r = client.post(
        "/jobs",
        files={"sketch": ("s.png", sketch, "image/png")},
        data={"budget": "3", "species": "Christmas tree"},
    )
    assert r.status_code == 202, r.text
    job = wait_for(client, r.json()["id"], finished)
    assert job["state"] == "done", job["error"]
    res = job["result"]
    assert res["species"] == "fir"
    cands = res["candidates"]
    assert len(cands) >= 3 and cands[0]["species"] == "fir" and cands[0]["probability"] == 1.0
    assert len(cands[1]["params"]) == 70
    thumb = client.get(job["links"]["candidate1.png"])
    assert thumb.status_code == 200 and thumb.content[:8] == b"\x89PNG\r\n\x1a\n"
    bad = client.post(
        "/jobs", files={"sketch": ("s.png", sketch, "image/png")}, data={"species": "baobab"}
    )
    assert bad.status_code == 422 and "unknown species 'baobab'" in bad.json()["detail"]
