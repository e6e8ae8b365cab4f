"""treesketch.service: hostile uploads and options refused before queueing (issue 30,
items 8 and 9): a picture format that is not read (EPS would reach Ghostscript) is refused
by its content, and an integer option of hundreds of digits is a 422, not a 500."""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from fastapi.testclient import TestClient
from PIL import Image

from treesketch.service import Limits, ServiceConfig, create_app
from treesketch.service.limits import LimitError, check_image, parse_options

EPS = b"%!PS-Adobe-3.0 EPSF-3.0\n%%BoundingBox: 0 0 64 64\nnewpath 0 0 moveto 64 64 lineto stroke\n"


@pytest.fixture(scope="module")
def client(tmp_path_factory: pytest.TempPathFactory) -> Iterator[TestClient]:
    config = ServiceConfig(
        data=tmp_path_factory.mktemp("service"),
        workers=1,
        estimator="service_helpers:palm_estimator",
        default_budget=5,
    )
    with TestClient(create_app(config), base_url="http://127.0.0.1") as c:
        yield c


def test_check_image_refuses_eps_by_content_without_pillow(monkeypatch) -> None:
    def no_decoding(*args: object, **kwargs: object) -> None:
        raise AssertionError("handed to Pillow")

    monkeypatch.setattr(Image, "open", no_decoding)
    with pytest.raises(LimitError, match="PostScript") as info:
        check_image(EPS, Limits())
    assert info.value.status == 415 and "PNG, JPEG" in str(info.value)
    with pytest.raises(LimitError, match="not an image in a format read here") as info:
        check_image(b"P5\n24 24\n255\n" + bytes(576), Limits())  # PGM: Pillow reads it
    assert info.value.status == 400


@pytest.mark.parametrize(
    ("data", "status", "words"),
    [
        (EPS, 415, "PostScript"),
        (b"%PDF-1.7\n" + bytes(64), 415, "PDF"),
        (b"P5\n24 24\n255\n" + bytes(576), 400, "PNG, JPEG, WebP, GIF, BMP or TIFF"),
    ],
    ids=["eps", "pdf", "pgm"],
)
def test_upload_in_a_format_not_read_is_refused(
    client: TestClient, data: bytes, status: int, words: str
) -> None:
    before = client.get("/status").json()["jobs"]
    r = client.post("/jobs", files={"sketch": ("tree.png", data, "image/png")})
    assert r.status_code == status, r.text
    assert words in r.json()["detail"]
    assert client.get("/status").json()["jobs"] == before  # nothing queued


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("budget", "1" + "0" * 308),
        ("budget", "-" + "9" * 400),
        ("max_faces", "1" + "0" * 308),
        ("time_limit", "1" + "0" * 308),
        ("height", "9" * 400),
    ],
    ids=["budget", "budget-neg", "max_faces", "time_limit", "height"],
)
def test_huge_numbers_are_a_422_naming_the_field(
    client: TestClient, sketch: bytes, field: str, value: str
) -> None:
    with pytest.raises(LimitError, match=field) as info:
        parse_options({field: value}, Limits(), ["tsn"], "tsn")
    assert info.value.status == 422
    before = client.get("/status").json()["jobs"]
    r = client.post("/jobs", files={"sketch": ("s.png", sketch, "image/png")}, data={field: value})
    assert r.status_code == 422, r.text
    assert field in r.json()["detail"] and len(r.json()["detail"]) < 200
    assert client.get("/status").json()["jobs"] == before


def test_numbers_past_pythons_own_int_limit_are_a_422() -> None:
    # int() refuses strings over 4300 digits itself; the form's fields are capped far
    # below that over HTTP, but parse_options is the API's own check
    with pytest.raises(LimitError, match="max_faces") as info:
        parse_options({"max_faces": "9" * 5000}, Limits(), ["tsn"], "tsn")
    assert info.value.status == 422 and len(str(info.value)) < 200
