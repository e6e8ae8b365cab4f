"""treesketch.service: the HTTP API through FastAPI's TestClient (no network)."""

from __future__ import annotations

import io

import numpy as np
import pytest
from fastapi.testclient import TestClient

from treesketch import Estimate
from treesketch.service import create_app
from weberpenn import build_mesh, grow, species


def _png(img: np.ndarray) -> bytes:
    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(img).save(buf, format="PNG")
    return buf.getvalue()


@pytest.fixture(scope="module")
def client() -> TestClient:
    calls = []

    class Palm:
        name = "palm-8"

        def estimate(self, img):
            calls.append(1)
            return Estimate(species.sample("palm", 8), "palm", {"palm": 1.0})

    app = create_app(model=Palm(), keep=2)
    app.state.calls = calls
    return TestClient(app)


@pytest.fixture(scope="module")
def palm_png() -> bytes:
    from render.sketch import SketchRenderer

    m = build_mesh(grow(species.sample("palm", 3)), species="palm")
    return _png(SketchRenderer(m).sketch(0, 256))


def test_health(client: TestClient) -> None:
    r = client.get("/health")
    assert r.status_code == 200 and r.json() == {"status": "ok", "estimator": "palm-8"}


def test_predict_and_glb(client: TestClient, palm_png: bytes) -> None:
    r = client.post(
        "/predict",
        files={"sketch": ("s.png", palm_png, "image/png")},
        data={"budget": "5", "height": "6"},
    )
    assert r.status_code == 200, r.text
    body = r.json()
    assert body["species"] == "palm" and body["evaluations"] <= 5
    assert body["losses"]["after"] <= body["losses"]["before"]
    assert len(body["params"]) == 70
    g = client.get(body["glb"])
    assert g.status_code == 200 and g.content[:4] == b"glTF"
    assert g.headers["content-type"] == "model/gltf-binary"


def test_no_refine(client: TestClient, palm_png: bytes) -> None:
    r = client.post(
        "/predict", files={"sketch": ("s.png", palm_png, "image/png")}, data={"refine": "false"}
    )
    assert r.status_code == 200 and r.json()["evaluations"] == 0


def test_bad_requests(client: TestClient, palm_png: bytes) -> None:
    r = client.post("/predict", files={"sketch": ("s.png", b"nope", "image/png")})
    assert r.status_code == 400 and "image" in r.json()["detail"]
    blank = _png(np.full((64, 64), 255, np.uint8))
    r = client.post("/predict", files={"sketch": ("b.png", blank, "image/png")})
    assert r.status_code == 422 and "blank" in r.json()["detail"]
    r = client.post(
        "/predict", files={"sketch": ("s.png", palm_png, "image/png")}, data={"budget": "0"}
    )
    assert r.status_code == 422 and "budget" in r.json()["detail"]
    r = client.post("/predict")
    assert r.status_code == 422
    assert client.get("/trees/unknown.glb").status_code == 404


def test_model_loaded_once_and_cache_bounded(client: TestClient, palm_png: bytes) -> None:
    for _ in range(3):
        r = client.post(
            "/predict", files={"sketch": ("s.png", palm_png, "image/png")}, data={"refine": "0"}
        )
        assert r.status_code == 200
    assert len(client.app.state.trees) == 2
