"""Tests of the Blender add-on's Blender-free part (blender/treesketch_addon/backend.py)
and its zip; the add-on inside Blender is checked by `make blender-test`
(scripts/blender_test.sh), which the last test here runs when Blender is installed."""

from __future__ import annotations

import importlib.util
import io
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from weberpenn import species
from weberpenn.preset import save_sapling_preset

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def backend():
    path = ROOT / "blender" / "treesketch_addon" / "backend.py"
    spec = importlib.util.spec_from_file_location("treesketch_addon_backend", path)
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod
    spec.loader.exec_module(mod)
    yield mod
    del sys.modules[spec.name]


@pytest.fixture(scope="module")
def addon_zip(tmp_path_factory: pytest.TempPathFactory) -> zipfile.ZipFile:
    """The add-on zip as ``make blender-addon`` builds it (scripts/blender_addon_zip.py)."""
    out = tmp_path_factory.mktemp("addon") / "a.zip"
    script = ROOT / "scripts" / "blender_addon_zip.py"
    subprocess.run([sys.executable, str(script), str(out)], check=True, cwd=ROOT)
    return zipfile.ZipFile(out)


def test_cli_command(backend, tmp_path):
    out = backend.Outputs.in_folder(tmp_path)
    cmd = backend.cli_command("/v/bin/treesketch", "d.png", out, refine=True, budget=20)
    assert cmd[:3] == ["/v/bin/treesketch", "predict", "d.png"]
    assert cmd[cmd.index("--out") + 1] == str(tmp_path / "tree.glb")
    assert cmd[cmd.index("--preset") + 1] == str(tmp_path / "tree_sapling.py")
    assert cmd[cmd.index("--budget") + 1] == "20"
    assert cmd[cmd.index("--preview") + 1] == str(tmp_path / "preview")
    assert cmd[cmd.index("--outlines") + 1] == str(tmp_path / "tree_outlines.png")
    plain = backend.cli_command("t", "d.png", out, refine=False)
    assert "--no-refine" in plain and "--preview" not in plain  # the estimate is the result
    with pytest.raises(backend.PredictError, match="preferences"):
        backend.run_cli([str(tmp_path / "missing"), "predict"])


def test_run_cli_lines_and_failure(backend, tmp_path):
    script = tmp_path / "fake"
    script.write_text(
        "#!/bin/sh\nprintf '\\033[2Krefining   1/10\\r\\033[2Krefining 3/10\\n'\necho done\nexit $1\n"
    )
    script.chmod(0o755)
    lines = []
    backend.run_cli([str(script), "0"], on_line=lines.append)
    assert lines == ["refining 1/10", "refining 3/10", "done"]  # bar redraws, codes gone
    assert backend.progress_fraction(lines[1]) == pytest.approx(0.3)
    assert backend.progress_fraction("no numbers") is None
    with pytest.raises(backend.PredictError, match="done"):
        backend.run_cli([str(script), "3"])


def test_read_preset_yaw(backend, tmp_path):
    path = save_sapling_preset(species.sample("pine", 0), tmp_path / "p.py", yaw=-30.0)
    kwargs, yaw = backend.read_preset(path)
    assert yaw == -30.0 and kwargs["levels"] == species.sample("pine", 0).levels
    bad = tmp_path / "bad.py"
    bad.write_text("# nothing\n")
    with pytest.raises(backend.PredictError, match="no Sapling"):
        backend.read_preset(bad)


def test_strokes_png(backend):
    ring = [(np.cos(a), 3 + np.sin(a)) for a in np.linspace(0, 2 * np.pi, 40)]
    img = np.asarray(Image.open(io.BytesIO(backend.strokes_png([[(0, 0), (0, 2)], ring], 128))))
    assert img.shape == (128, 128) and img.dtype == np.uint8
    ink = np.argwhere(img < 128)
    assert len(ink) > 100
    assert ink[:, 0].max() > 118 and ink[:, 0].min() > 5  # base near the bottom, room above
    assert abs(ink[:, 1].mean() - 64) < 3  # centred
    with pytest.raises(backend.PredictError, match="empty"):
        backend.strokes_png([])


def test_multipart_body(backend):
    body, ctype = backend.multipart_body("sketch", "d.png", b"\x89PNG", {"budget": "5"})
    boundary = ctype.split("boundary=")[1]
    assert body.startswith(f"--{boundary}".encode()) and body.endswith(
        f"--{boundary}--\r\n".encode()
    )
    assert b'name="sketch"; filename="d.png"' in body and b'name="budget"\r\n\r\n5' in body


def test_addon_zip(addon_zip):
    names = addon_zip.namelist()
    assert "treesketch_addon/__init__.py" in names and "treesketch_addon/backend.py" in names
    assert "treesketch_addon/drawing_maple.png" in names
    init = addon_zip.read("treesketch_addon/__init__.py").decode()
    assert '"blender": (3, 4, 0)' in init


def test_post_predict_against_a_local_service(backend, tmp_path):
    """The service path: POST /predict (multipart 'sketch'), then GET the GLB it names."""
    import json
    import threading
    from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

    seen = {}

    class Handler(BaseHTTPRequestHandler):
        def do_POST(self):  # noqa: N802 - http.server's name
            body = self.rfile.read(int(self.headers["Content-Length"]))
            seen["path"], seen["body"] = self.path, body
            reply = json.dumps({"species": "maple", "yaw": 45.0, "glb": "/trees/abc.glb"})
            self.send_response(200)
            self.end_headers()
            self.wfile.write(reply.encode())

        def do_GET(self):  # noqa: N802
            self.send_response(200 if self.path == "/trees/abc.glb" else 404)
            self.end_headers()
            self.wfile.write(b"glTF-bytes")

        def log_message(self, *args):
            pass

    server = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    try:
        image = tmp_path / "d.png"
        image.write_bytes(b"\x89PNG fake")
        url = f"http://127.0.0.1:{server.server_address[1]}"
        reply = backend.post_predict(url, image, tmp_path / "t.glb", budget=7)
        assert reply["yaw"] == 45.0 and (tmp_path / "t.glb").read_bytes() == b"glTF-bytes"
        assert seen["path"] == "/predict" and b'name="budget"\r\n\r\n7' in seen["body"]
        with pytest.raises(backend.PredictError, match="service"):
            backend.post_predict("http://127.0.0.1:1", image, tmp_path / "u.glb", timeout=5)
    finally:
        server.shutdown()


# ------------------------------------------------------ issue 30, item 7: the service path
@pytest.fixture()
def service():
    """A local stand-in for the service: ``routes[path] = (status, headers, body)``; the
    requests it saw (path, headers) are in ``seen``.  Yields (base URL, routes, seen)."""
    import threading
    from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

    routes: dict = {}
    seen: list = []

    class Handler(BaseHTTPRequestHandler):
        def _answer(self):
            if self.command == "POST":
                self.rfile.read(int(self.headers["Content-Length"]))
            seen.append((self.path, dict(self.headers)))
            status, headers, body = routes.get(self.path, (404, {}, b"{}"))
            self.send_response(status)
            for k, v in headers.items():
                self.send_header(k, v)
            self.end_headers()
            for i in range(0, len(body), 65536):
                try:
                    self.wfile.write(body[i : i + 65536])
                except OSError:  # the client stopped reading: what a cap does
                    return

        do_GET = do_POST = _answer  # noqa: N815 - http.server's names

        def log_message(self, *args):
            pass

    server = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    try:
        yield f"http://127.0.0.1:{server.server_address[1]}", routes, seen
    finally:
        server.shutdown()


def _reply(glb: str) -> tuple:
    import json

    return 200, {"Content-Type": "application/json"}, json.dumps({"glb": glb}).encode()


def _image(tmp_path):
    image = tmp_path / "d.png"
    image.write_bytes(b"\x89PNG fake")
    return image


@pytest.mark.parametrize(
    "glb",
    [
        "file:///etc/passwd",
        "FILE:/etc/hostname",
        "ftp://127.0.0.1/x.glb",
        "http://127.0.0.2:{port}/x.glb",  # another host
        "http://127.0.0.1:1/x.glb",  # another port
        "https://127.0.0.1:{port}/x.glb",  # another scheme
        "//example.com/x.glb",  # another host, relative to the scheme
    ],
)
def test_post_predict_follows_only_the_configured_origin(backend, tmp_path, service, glb):
    url, routes, seen = service
    port = url.rsplit(":", 1)[1]
    routes["/predict"] = _reply(glb.format(port=port))
    with pytest.raises(backend.PredictError, match="not on the configured service"):
        backend.post_predict(url, _image(tmp_path), tmp_path / "t.glb")
    assert [p for p, _ in seen] == ["/predict"]  # nothing else was fetched
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d.png"]


def test_post_predict_redirects_only_within_the_origin(backend, tmp_path, service):
    url, routes, seen = service
    routes["/predict"] = _reply("/jobs/1/tree.glb")
    routes["/jobs/1/tree.glb"] = (302, {"Location": "/files/1.glb"}, b"")
    routes["/files/1.glb"] = (200, {}, b"glTF-bytes")
    backend.post_predict(url, _image(tmp_path), tmp_path / "t.glb")
    assert (tmp_path / "t.glb").read_bytes() == b"glTF-bytes"
    for away in ("file:///etc/passwd", "http://127.0.0.2:9/x.glb"):
        routes["/jobs/1/tree.glb"] = (302, {"Location": away}, b"")
        # urllib itself refuses a non-http scheme; another host is ours to refuse
        with pytest.raises(backend.PredictError, match="away from the configured|not allowed"):
            backend.post_predict(url, _image(tmp_path), tmp_path / "u.glb")
        assert not (tmp_path / "u.glb").exists()


def test_post_predict_caps_the_download(backend, tmp_path, service):
    url, routes, _ = service
    routes["/predict"] = _reply("/big.glb")
    big = b"g" * 300_000
    for headers in ({"Content-Length": str(len(big))}, {}):  # declared, or found streaming
        routes["/big.glb"] = (200, headers, big)
        with pytest.raises(backend.PredictError, match="over the limit"):
            backend.post_predict(url, _image(tmp_path), tmp_path / "t.glb", max_glb_bytes=100_000)
        assert sorted(p.name for p in tmp_path.iterdir()) == ["d.png"]  # no part left
    routes["/predict"] = (200, {}, b"[" * (2 * 1024 * 1024))
    with pytest.raises(backend.PredictError, match="answer is over the limit"):
        backend.post_predict(url, _image(tmp_path), tmp_path / "t.glb")
    routes["/predict"] = (200, {}, b'["not", "an object"]')
    with pytest.raises(backend.PredictError, match="names no GLB"):
        backend.post_predict(url, _image(tmp_path), tmp_path / "t.glb")


def test_post_predict_sends_the_token_in_a_header(backend, tmp_path, service):
    url, routes, seen = service
    routes["/predict"] = _reply("/t.glb")
    routes["/t.glb"] = (200, {}, b"glTF")
    backend.post_predict(url, _image(tmp_path), tmp_path / "t.glb", token="s3cret")
    assert [p for p, _ in seen] == ["/predict", "/t.glb"]  # no token in any URL
    assert all(h.get("Authorization") == "Bearer s3cret" for _, h in seen)
    routes["/predict"] = (401, {}, b'{"detail": "a token is needed"}')
    with pytest.raises(backend.PredictError, match="401 a token is needed"):
        backend.post_predict(url, _image(tmp_path), tmp_path / "t.glb")
    with pytest.raises(backend.PredictError, match="one line"):
        backend.post_predict(url, _image(tmp_path), tmp_path / "t.glb", token="a\r\nX-Evil: 1")


def test_post_predict_fetches_the_outlines_picture(backend, tmp_path, service):
    """The job's outlines picture (its links' outlines.png) comes with the tree, with the
    token, from the configured service only; without it the tree still comes."""
    import json

    url, routes, seen = service
    port = url.rsplit(":", 1)[1]
    png = b"\x89PNG\r\n\x1a\n picture"

    def reply(link):
        body = {"glb": "/t.glb", "links": {"outlines.png": link}}
        return 200, {"Content-Type": "application/json"}, json.dumps(body).encode()

    routes["/t.glb"] = (200, {}, b"glTF")
    routes["/jobs/1/outlines.png"] = (200, {"Content-Type": "image/png"}, png)
    out = tmp_path / "o.png"
    routes["/predict"] = reply("/jobs/1/outlines.png")
    backend.post_predict(url, _image(tmp_path), tmp_path / "t.glb", token="k", outlines_path=out)
    assert out.read_bytes() == png
    assert seen[-1] == ("/jobs/1/outlines.png", seen[-1][1])
    assert seen[-1][1].get("Authorization") == "Bearer k"
    out.unlink()
    for link in (f"http://127.0.0.2:{port}/jobs/1/outlines.png", "/missing.png", None):
        routes["/predict"] = reply(link)
        n = len(seen)
        backend.post_predict(url, _image(tmp_path), tmp_path / "t.glb", outlines_path=out)
        assert (tmp_path / "t.glb").read_bytes() == b"glTF" and not out.exists(), link
        assert all("127.0.0.2" not in p for p, _ in seen[n:])


@pytest.mark.parametrize("url", ["file:///tmp", "ftp://example.com", "127.0.0.1:8000", "http://"])
def test_post_predict_refuses_a_service_url_that_is_not_http(backend, tmp_path, url):
    with pytest.raises(backend.PredictError, match="http:// or https://"):
        backend.post_predict(url, _image(tmp_path), tmp_path / "t.glb")


@pytest.mark.parametrize(
    "text",
    [
        "{'levels': 3,\n",  # cut short: SyntaxError
        "{'levels': __import__('os')}\n",  # not a literal: ValueError
        "# view yaw: 1.2.3 degrees\n{'levels': 3}\n",  # a bad yaw
        b"\xff\xfe{'levels': 3}\n",  # not UTF-8
        "{'a': " + "(" * 300 + ")" * 300 + "}\n",  # too deep for the parser
        "# pad\n" * 200_000,  # too large
    ],
    ids=["syntax", "call", "yaw", "binary", "deep", "large"],
)
def test_read_preset_faults_are_predict_errors(backend, tmp_path, text):
    path = tmp_path / "p.py"
    if isinstance(text, bytes):
        path.write_bytes(text)
    else:
        path.write_text(text)
    with pytest.raises(backend.PredictError) as info:
        backend.read_preset(path)
    assert str(path) in str(info.value)


def test_numpy_bool_alias(backend, monkeypatch):
    """Debian Blender 3.4's glTF importer calls np.bool (removed in numpy 1.24): the
    add-on puts it back itself, once."""
    monkeypatch.delattr(np, "bool", raising=False)  # numpy 1.24..1.26 (numpy 2 has it back)
    assert "bool" not in np.__dict__
    assert backend.numpy_bool_alias() is True
    assert np.bool is bool
    assert backend.numpy_bool_alias() is False


def test_plain_error(backend):
    blender = RuntimeError(
        "Error: Python: Traceback (most recent call last):\n"
        '  File "/usr/share/blender/3.4/scripts/addons/io_scene_gltf2/__init__.py", line 1\n'
        "    np.bool\n"
        "AttributeError: module 'numpy' has no attribute 'bool'\n"
    )
    assert backend.plain_error(blender) == "module 'numpy' has no attribute 'bool'"
    assert backend.plain_error(RuntimeError("Error: no image file at /x.png")) == (
        "no image file at /x.png"
    )
    assert backend.plain_error(backend.PredictError("timed out")) == "timed out"
    assert backend.plain_error(RuntimeError("")) == "RuntimeError"


def test_species_and_unique_preset_names(backend):
    lines = ["refining ...", "species: cherry (first estimate: tsn); view yaw 15", "wrote x"]
    assert backend.species_of(lines) == "cherry"
    assert backend.species_of(["nothing here"]) is None
    taken = ["treesketch_cherry_1.py", "treesketch_cherry_2.py", "other.py"]
    assert backend.preset_name("cherry", taken) == "treesketch_cherry_3.py"
    assert backend.preset_name("maple", taken) == "treesketch_maple_1.py"
    assert backend.preset_name(None, []) == "treesketch_tree_1.py"


def test_controls_in_the_zip_and_the_grow_command(backend, addon_zip, tmp_path):
    """The panel's controls are the project's table (shipped in the zip); only the ones
    moved from their keep value go to `treesketch grow --set`."""
    (tmp_path / "controls.json").write_bytes(addon_zip.read("treesketch_addon/controls.json"))
    from refine.search import DEFAULT_BUDGET
    from weberpenn.controls import CONTROLS

    table = backend.load_controls(tmp_path / "controls.json")
    assert [r["name"] for r in table["controls"]] == [c.name for c in CONTROLS]
    assert table["default_budget"] == DEFAULT_BUDGET
    assert backend.load_controls(tmp_path / "missing.json")["controls"] == []
    rows = table["controls"]
    keep = {r["name"]: backend.keep_value(r) for r in rows}
    assert keep["crown_width"] == 1.0 and keep["height"] == 0.0 and keep["seed"] == -1
    assert keep["crown_shape"] == "KEEP" and keep["leafy"] is True
    assert backend.changed_controls(rows, keep) == {}
    moved = {**keep, "crown_width": 1.3, "leafy": False, "seed": 7, "branch_angle": 0.2}
    changed = backend.changed_controls(rows, moved)
    assert changed == {"crown_width": 1.3, "leafy": False, "seed": 7}  # 0.2 deg: within a step
    out = backend.Outputs.in_folder(tmp_path)
    cmd = backend.grow_command("/v/bin/treesketch", tmp_path / "p.json", out, changed)
    assert cmd[:4] == ["/v/bin/treesketch", "grow", "--params", str(tmp_path / "p.json")]
    sets = [cmd[i + 1] for i, a in enumerate(cmd) if a == "--set"]
    assert sets == ["crown_width=1.3", "leafy=false", "seed=7"]
    assert cmd[cmd.index("--preset") + 1] == str(out.preset)


def test_post_trees_against_the_service(backend, tmp_path):
    """The service path of the panel's controls: the real ``POST /trees``."""
    import json

    from treesketch.service import ServiceConfig, create_app
    from treesketch.service.inprocess import serve

    config = ServiceConfig(
        data=tmp_path / "data", workers=1, estimator="service_helpers:palm_estimator"
    )
    params = species.sample("palm", 4).to_dict()
    out = backend.Outputs.in_folder(tmp_path)
    with serve(create_app(config)) as url:
        backend.post_trees(url, params, {"crown_width": 1.5, "seed": 3}, "palm", out)
        with pytest.raises(backend.PredictError, match="crown_width"):
            backend.post_trees(url, params, {"crown_width": 50}, "palm", out)
    edited = json.loads(out.params.read_text())
    assert edited["length"][1] == pytest.approx(1.5 * params["length"][1])
    assert edited["seed"] == 3 and out.glb.read_bytes()[:4] == b"glTF"


# ------------------------------------------------ issue 27, item 4: the species meant
def test_species_in_the_zip_and_the_species_meant_reaches_the_cli(backend, addon_zip, tmp_path):
    """The panel's species are the project's list (shipped in the zip as species.json);
    the one picked goes to ``treesketch predict --species``; the CLI's "it is ..." line is
    the species in words the panel shows."""
    assert addon_zip.namelist().count("treesketch_addon/species.json") == 1
    (tmp_path / "species.json").write_bytes(addon_zip.read("treesketch_addon/species.json"))
    rows = backend.load_species(tmp_path / "species.json")
    assert [r["name"] for r in rows] == list(species.SPECIES)
    assert all(r["display"] == species.display_name(r["name"]) for r in rows)
    assert {r["name"] for r in rows if r["paper"]} == set(species.PAPER_SPECIES)
    assert backend.load_species(tmp_path / "missing.json") == []

    out = backend.Outputs.in_folder(tmp_path)
    cmd = backend.cli_command("t", "d.png", out, species="fir")
    assert cmd[cmd.index("--species") + 1] == "fir"
    assert "--species" not in backend.cli_command("t", "d.png", out)  # the drawing decides
    lines = [
        "refining 3/3",
        "species: palm (first estimate: tsn); view yaw 0",
        "it is a palm (87%); could also be a cherry",
        "  candidate palm     87.0%  0.412",
    ]
    assert backend.species_text_of(lines) == "a palm (87%); could also be a cherry"
    assert backend.species_text_of(lines[:2]) is None


def test_post_predict_asks_the_service_for_the_species_meant(backend, tmp_path):
    """The service path: the species picked reaches the real service's job (the
    estimator says palm; a fir is asked for) and its answer says the species in words."""
    from service_helpers import palm_sketch_png

    from treesketch.service import ServiceConfig, create_app
    from treesketch.service.inprocess import serve

    config = ServiceConfig(
        data=tmp_path / "data", workers=1, estimator="service_helpers:palm_estimator"
    )
    image = tmp_path / "palm.png"
    image.write_bytes(palm_sketch_png())
    with serve(create_app(config)) as url:
        meant = backend.post_predict(url, image, tmp_path / "f.glb", refine=False, species="fir")
        free = backend.post_predict(url, image, tmp_path / "p.glb", refine=False)
        with pytest.raises(backend.PredictError, match="unknown species 'baobab'"):
            backend.post_predict(url, image, tmp_path / "b.glb", refine=False, species="baobab")
    assert meant["species"] == "fir" and meant["species_text"].startswith("a fir")
    assert (tmp_path / "f.glb").read_bytes()[:4] == b"glTF"
    assert free["species"] == "palm" and free["species_text"].startswith("a palm")


# ------------------------------------------- issue 28, part 5: the Blender hand-off
def test_preview_watch_shows_each_new_tree_at_most_every_two_seconds(backend, tmp_path):
    watch = backend.PreviewWatch(tmp_path / "preview")
    assert watch.every == 2.0 and watch.poll(now=0.0) is None  # nothing written yet
    (tmp_path / "preview").mkdir()
    glb = tmp_path / "preview" / "tree.glb"
    glb.write_bytes(b"glTF first")
    assert watch.poll(now=1.0) == glb  # the first estimate: at once
    assert watch.poll(now=5.0) is None  # the same file: nothing new
    glb.write_bytes(b"glTF a better tree")
    assert watch.poll(now=6.0) == glb
    glb.write_bytes(b"glTF a still better tree")
    assert watch.poll(now=7.5) is None  # new, but within 2 s of the last shown
    assert watch.poll(now=8.0) == glb and watch.shown == 3


def test_glb_textures_are_the_exported_pngs(backend, tmp_path):
    from weberpenn import build_mesh, grow
    from weberpenn.export import TEXTURE_SIZE, export_mesh
    from weberpenn.textures import bark_texture, leaf_texture

    mesh = build_mesh(grow(species.sample("oak", 1)), species="oak")
    found = backend.glb_textures(export_mesh(mesh, tmp_path / "t.glb"))
    assert sorted(found) == ["bark", "leaf"]
    for name, made in (("bark", bark_texture), ("leaf", leaf_texture)):
        img = Image.open(io.BytesIO(found[name]))
        want = made("oak", TEXTURE_SIZE)
        assert img.mode == want.mode and np.array_equal(np.asarray(img), np.asarray(want))
    flat = backend.glb_textures(export_mesh(mesh, tmp_path / "f.glb", textures=False))
    assert flat == {}
    (tmp_path / "x.glb").write_bytes(b"PK\x03\x04 not a GLB at all")
    with pytest.raises(backend.PredictError, match="cannot read the textures"):
        backend.glb_textures(tmp_path / "x.glb")


# ----------------------------------------------- issue 29: two views from Grease Pencil
def test_view_layers_front_first_and_refusals(backend):
    assert backend.view_layers(["GP_Layer", "ink"]) == []  # one drawing, from the front
    assert backend.view_layers(["right", "Lines", " Front "]) == [
        (" Front ", "front"),
        ("right", "right"),
    ]
    with pytest.raises(backend.PredictError, match="no Front"):
        backend.view_layers(["Right", "Back"])
    with pytest.raises(backend.PredictError, match="two Grease Pencil layers are the Right"):
        backend.view_layers(["Front", "Right", "RIGHT"])


def test_views_follow_the_renderers_yaw(backend):
    """Each view's screen-right axis is the renderer's at that yaw (``render.camera``):
    Blender's Right view (camera at +X looking along -X, +Y on the right) is yaw 90."""
    from render.camera import Camera, Framing

    framing = Framing(0.0, 1.0, 0.5)
    for view, (yaw, (rx, ry)) in backend.VIEWS.items():
        right, up, forward = Camera(framing, yaw).basis()
        assert np.allclose(right, [rx, ry, 0.0]) and np.allclose(up, [0, 0, 1]), view
    _, _, forward = Camera(framing, backend.VIEWS["right"][0]).basis()
    assert np.allclose(forward, [-1.0, 0.0, 0.0])  # looking along -X: Blender's Right view


def test_cli_command_sends_the_other_views(backend, tmp_path):
    out = backend.Outputs.in_folder(tmp_path)
    cmd = backend.cli_command("t", "front.png", out, views=[("right.png", 90.0)])
    assert cmd[:3] == ["t", "predict", "front.png"]
    assert cmd[cmd.index("--view") + 1] == "right.png@90"
    assert "--view" not in backend.cli_command("t", "front.png", out)


@pytest.mark.slow
@pytest.mark.skipif(
    shutil.which("blender") is None or not (ROOT / ".venv" / "bin" / "treesketch").exists(),
    reason="needs Blender (make blender-test installs Debian's) and the project's .venv",
)
def test_the_addon_in_blender_headless():
    """`make blender-test` itself: the GLB in Blender's importer, the add-on end to end
    (Sapling trees dressed, leaves' shadows clipped, the preview while refining)."""
    res = subprocess.run(
        ["bash", str(ROOT / "scripts" / "blender_test.sh")],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=900,
        check=False,
    )
    assert res.returncode == 0, res.stdout[-4000:] + res.stderr[-4000:]
    assert "ALL OK" in res.stdout and "materials 'TreeSketch bark" in res.stdout, res.stdout
