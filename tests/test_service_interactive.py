"""The service's interactive loop (treesketch.service.interactive): the controls table,
``POST /trees``, and a running job's current best tree (one real worker process, a fixed
palm as the first estimate)."""

from __future__ import annotations

import io
import json
from collections.abc import Iterator

import pytest
from fastapi.testclient import TestClient

from refine.search import DEFAULT_BUDGET
from treesketch.service import ServiceConfig, create_app
from treesketch.trees import VIEW_FACES
from weberpenn import species
from weberpenn.controls import CONTROLS

ESTIMATOR = "service_helpers:palm_estimator"
GLB = {"Accept": "model/gltf-binary"}


@pytest.fixture(scope="module")
def client(tmp_path_factory: pytest.TempPathFactory) -> Iterator[TestClient]:
    config = ServiceConfig(
        data=tmp_path_factory.mktemp("interactive"), workers=1, estimator=ESTIMATOR
    )
    with TestClient(create_app(config), base_url="http://127.0.0.1") as c:
        yield c


def _faces(glb: bytes) -> int:
    import trimesh

    scene = trimesh.load(io.BytesIO(glb), file_type="glb")
    return sum(len(g.faces) for g in scene.geometry.values())


def test_controls_table(client: TestClient) -> None:
    body = client.get("/controls").json()
    names = [c["name"] for c in body["controls"]]
    assert names == [c.name for c in CONTROLS]
    assert {"height", "crown_width", "crown_shape", "branch_count", "branch_angle"} <= set(names)
    assert {"trunk_lean", "trunk_bend", "leaf_size", "leaf_density", "leafy", "seed"} <= set(names)
    for row in body["controls"]:
        assert row["label"] and row["help"] and row["moves"], row
    assert set(body["species"]) == set(species.SPECIES)
    for name, d in body["species"].items():
        assert set(d) == set(names)
        assert d["height"] > 0 and d["crown_width"] == 1.0
        assert d["crown_shape"] == str(species.base(name)["shape"])
    assert body["default_budget"] == DEFAULT_BUDGET and body["view_faces"] == VIEW_FACES
    assert client.get("/status").json()["limits"]["default_budget"] == DEFAULT_BUDGET


def test_post_trees_applies_the_controls(client: TestClient) -> None:
    base = species.sample("maple", 2)
    plain = client.post("/trees", json={"params": base.to_dict()}).json()
    assert plain["species"] == "maple" and plain["params"] == base.to_dict()
    assert plain["controls"]["crown_width"] == 1.0 and plain["controls"]["seed"] == base["seed"]
    edits = {"crown_width": 1.3, "leafy": False, "height": 9.0}
    r = client.post("/trees", json={"params": base.to_dict(), "controls": edits, "seed": 7})
    assert r.status_code == 200, r.text
    body = r.json()
    p = body["params"]
    assert p["length"][1] == pytest.approx(1.3 * base["length"][1])
    assert p["leaves"] == 0 and p["seed"] == 7
    assert body["height"] == pytest.approx(9.0, rel=0.02)
    assert body["controls"]["seed"] == 7 and body["controls"]["leafy"] is False


def test_post_trees_answers_a_light_glb(client: TestClient) -> None:
    params = species.sample("cherry", 1).to_dict()
    r = client.post("/trees", json={"params": params, "species": "cherry"}, headers=GLB)
    assert r.status_code == 200, r.text
    assert r.headers["content-type"] == "model/gltf-binary" and r.content[:4] == b"glTF"
    assert r.headers["x-tree-species"] == "cherry" and float(r.headers["x-tree-height"]) > 1
    assert json.loads(r.headers["x-tree-controls"])["leafy"] is True
    assert _faces(r.content) <= VIEW_FACES and len(r.content) <= 5_000_000
    small = client.post(
        "/trees", json={"params": params, "species": "cherry", "max_faces": 5000}, headers=GLB
    )
    assert _faces(small.content) <= 5000


def test_an_edit_past_the_limits_is_refused_or_brought_back_within_them(
    client: TestClient,
) -> None:
    params = species.sample("fir", 1).to_dict()
    past = {"leaf_density": 3.0, "branch_count": 2.5}  # a fir of millions of leaves
    r = client.post("/trees", json={"params": params, "controls": past, "species": "fir"})
    assert r.status_code == 422 and "leaves" in r.json()["detail"]
    # the page says which slider is being dragged: only it moves back
    body = {"params": params, "controls": past, "species": "fir", "fit": ["leaf_density"]}
    r = client.post("/trees", json=body)
    assert r.status_code == 422 and "leaf density back" in r.json()["detail"]
    body = {**body, "controls": {"leaf_density": 3.0, "branch_count": 1.05}}
    r = client.post("/trees", json=body, headers=GLB)
    assert r.status_code == 200 and r.content[:4] == b"glTF"
    adjusted = json.loads(r.headers["x-tree-adjusted"])
    assert set(adjusted) == {"leaf_density"} and 1.0 <= adjusted["leaf_density"] < 3.0
    # all of them, by one fraction of their move; the tree is the one those values grow
    r = client.post("/trees", json={"params": params, "controls": past, "fit": True})
    assert r.status_code == 200, r.text
    got = r.json()
    assert set(got["adjusted"]) == {"leaf_density", "branch_count"}
    again = client.post(
        "/trees", json={"params": params, "controls": {**past, **got["adjusted"]}}
    ).json()
    assert again["params"] == got["params"]
    # within the limits nothing is adjusted
    fine = client.post("/trees", json={"params": params, "fit": True}).json()
    assert fine["adjusted"] == {} and fine["params"] == params


@pytest.mark.parametrize(
    ("body", "status", "match"),
    [
        ({"params": {"nope": 1}}, 422, "nope"),
        ({"controls": {}}, 422, "params"),
        ({"params": "x"}, 422, "params"),
        ({"params": None, "extra": 1}, 422, "extra"),
        ({"params": "P", "controls": {"crown_width": 9}}, 422, "crown_width"),
        ({"params": "P", "controls": {"wings": 2}}, 422, "wings"),
        ({"params": "P", "seed": -1}, 422, "seed"),
        ({"params": "P", "max_faces": 3}, 422, "max_faces"),
        ({"params": "P", "species": "oak-ish"}, 422, "species"),
        ({"params": "P", "yaw": "north"}, 422, "yaw"),
        ({"params": "P", "yaw": True}, 422, "yaw"),
        ({"params": "P", "fit": "yes"}, 422, "fit"),
        ({"params": "P", "fit": ["wings"]}, 422, "wings"),
    ],
)
def test_post_trees_refuses_bad_requests(
    client: TestClient, body: dict, status: int, match: str
) -> None:
    if body.get("params") == "P":
        body = {**body, "params": species.sample("palm", 0).to_dict()}
    r = client.post("/trees", json=body)
    assert r.status_code == status, r.text
    assert match in r.json()["detail"]


def test_post_trees_refuses_non_json_and_huge_bodies(client: TestClient) -> None:
    r = client.post("/trees", content=b"{not json", headers={"Content-Type": "application/json"})
    assert r.status_code == 422 and "not JSON" in r.json()["detail"]
    r = client.post("/trees", content=b"x" * (300 * 1024))
    assert r.status_code == 413
    # Python's JSON reader takes the non-standard Infinity and NaN: still no yaw
    params = json.dumps(species.sample("palm", 0).to_dict())
    for bad in ("Infinity", "NaN"):
        body = f'{{"params": {params}, "yaw": {bad}}}'.encode()
        r = client.post("/trees", content=body, headers={"Content-Type": "application/json"})
        assert r.status_code == 422 and "yaw" in r.json()["detail"], r.text


def test_a_running_job_shows_its_current_best_tree(client: TestClient, sketch: bytes) -> None:
    """The first estimate's tree is there while the refinement runs; the count never
    passes the budget; the best distance only falls."""
    r = client.post(
        "/jobs", files={"sketch": ("s.png", sketch, "image/png")}, data={"budget": "40"}
    )
    job_id = r.json()["id"]
    assert r.json()["links"]["preview/tree.glb"] == f"/jobs/{job_id}/preview/tree.glb"
    bodies = []
    with client.stream("GET", f"/jobs/{job_id}/events") as s:
        for line in s.iter_lines():
            if line.startswith("data: "):
                bodies.append(json.loads(line[6:]))
    assert bodies[-1]["state"] == "done", bodies[-1]
    running = [b["progress"] for b in bodies if b["state"] == "running"]
    shown = [p for p in running if p.get("preview")]
    assert shown, "no current best tree was shown while the job ran"
    assert shown[0]["evaluations"] < bodies[-1]["result"]["evaluations"]
    assert all(p["evaluations"] <= p["budget"] for p in running)
    losses = [p["best_loss"] for p in running if p.get("best_loss") is not None]
    assert all(b <= a for a, b in zip(losses, losses[1:], strict=False))
    glb = client.get(f"/jobs/{job_id}/preview/tree.glb")
    assert glb.status_code == 200 and glb.content[:4] == b"glTF"
    assert _faces(glb.content) <= VIEW_FACES
    png = client.get(f"/jobs/{job_id}/preview/sketch.png")
    assert png.status_code == 200 and png.content[:4] == b"\x89PNG"
    view = client.get(f"/jobs/{job_id}/tree_view.glb")
    assert view.status_code == 200 and _faces(view.content) <= VIEW_FACES
    assert client.get(f"/jobs/{job_id}/preview/other.bin").status_code == 404
    assert client.get("/jobs/nope/preview/tree.glb").status_code == 404
    # editing the job's tree starts from the very tree on show: grown again at the result's
    # yaw it is the job's own viewer file, byte for byte (the 3D view does not jump)
    result = bodies[-1]["result"]
    again = client.post(
        "/trees",
        json={"params": result["params"], "species": result["species"], "yaw": result["yaw"]},
        headers=GLB,
    )
    assert again.status_code == 200, again.text
    assert again.content == view.content
    turned = {"params": result["params"], "species": result["species"], "yaw": result["yaw"] + 90}
    assert client.post("/trees", json=turned, headers=GLB).content != view.content


def test_a_preview_is_written_at_most_every_two_seconds(tmp_path) -> None:
    from treesketch import Progress
    from treesketch.service.preview import PreviewWriter

    p = species.sample("palm", 1)
    writer = PreviewWriter(tmp_path, every=2.0)
    tell = lambda v: Progress("refine", v, 10, 0.5, 0.0, p, "palm", 0.0, v)  # noqa: E731
    assert writer.offer(tell(1)) == 1  # the first at once
    assert writer.offer(tell(1)) is None  # nothing new
    assert writer.offer(tell(2)) is None  # too soon
    writer.last -= 2.5
    assert writer.offer(tell(3)) == 3  # the latest, once the pause is over
    assert (tmp_path / "tree.glb").read_bytes()[:4] == b"glTF"
