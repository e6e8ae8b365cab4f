"""The service against hostile but realistic use (issue 30), each case against a real
server (uvicorn in a thread, one worker process, as ``test_service_faults.py`` does): a
second server on the same data folder, uploads of many tiny parts, the token in URLs and
logs, foreign Host and Origin headers, a full disk, the job database deleted or corrupt,
multipart edge cases, a lower-case ``bearer``."""

from __future__ import annotations

import contextlib
import logging
import os
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx
import pytest
from service_helpers import finished, http_service, refining, submit, wait_for

from treesketch.service import JobStore, ServiceConfig, create_app
from treesketch.service.inprocess import serve
from treesketch.service.limits import MAX_PARTS

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[1]
ESTIMATOR = "service_helpers:palm_estimator"
LONG = {"budget": "1000", "time_limit": "600"}  # runs until cancelled
BOUNDARY = "hostileboundary"
CTYPE = f"multipart/form-data; boundary={BOUNDARY}"


def config(data: Path, **kw: object) -> ServiceConfig:
    return ServiceConfig(data=data, workers=1, estimator=ESTIMATOR, **kw)  # type: ignore[arg-type]


def part(name: str, value: bytes, filename: str | None = None) -> bytes:
    disp = f'form-data; name="{name}"' + (f'; filename="{filename}"' if filename else "")
    return f"--{BOUNDARY}\r\nContent-Disposition: {disp}\r\n\r\n".encode() + value + b"\r\n"


def end() -> bytes:
    return f"--{BOUNDARY}--\r\n".encode()


def raw_post(url: str, path: str, body: bytes, headers: str = "") -> tuple[int, bytes]:
    """POST ``body`` over a plain socket (exactly these bytes, with a true Content-Length);
    (status, the answer's body)."""
    host, port = url.removeprefix("http://").split(":")
    with socket.create_connection((host, int(port)), timeout=60) as s:
        s.sendall(
            f"POST {path} HTTP/1.1\r\nHost: {host}\r\nContent-Type: {CTYPE}\r\n"
            f"Content-Length: {len(body)}\r\nConnection: close\r\n{headers}\r\n".encode()
        )
        with contextlib.suppress(OSError):  # the server may answer (and close) early
            s.sendall(body)
        answer = b""
        while chunk := s.recv(65536):
            answer += chunk
    head, _, rest = answer.partition(b"\r\n\r\n")
    return int(head.split(b" ")[1]), rest


# -- 1. the data folder has one owner -------------------------------------------------------
def test_second_server_on_the_same_data_is_refused_and_the_live_job_goes_on(
    tmp_path: Path, sketch: bytes
) -> None:
    with http_service(config(tmp_path)) as http:
        job = submit(http, sketch, **LONG)
        wait_for(http, job, refining)
        # a second `treesketch serve` on the same folder, another port
        with socket.socket() as s:
            s.bind(("127.0.0.1", 0))
            port = s.getsockname()[1]
        cmd = [sys.executable, "-m", "treesketch.cli", "serve", "--data", str(tmp_path)]
        cmd += ["--port", str(port), "--workers", "1", "--estimator", "template"]
        env = {**os.environ, "PYTHONPATH": f"{ROOT}{os.pathsep}{ROOT / 'tests'}"}
        try:
            r = subprocess.run(cmd, capture_output=True, text=True, timeout=60, env=env)
        except subprocess.TimeoutExpired as exc:  # it started serving: the bug
            raise AssertionError("a second server started on a folder in use") from exc
        assert r.returncode == 2, r.stderr
        assert "in use by another treesketch server" in r.stderr
        assert f"pid {os.getpid()}" in r.stderr and "Traceback" not in r.stderr
        # and in process: the app's start-up refuses before its recovery touches a job
        from fastapi.testclient import TestClient

        from treesketch.service.owner import DataFolderBusy

        with pytest.raises(DataFolderBusy), TestClient(create_app(config(tmp_path))):
            pass
        before = http.get(f"/jobs/{job}").json()["progress"]["evaluations"]
        body = wait_for(
            http, job, lambda b: b["state"] == "running" and b["progress"]["evaluations"] > before
        )
        assert body["error"] is None
        assert http.delete(f"/jobs/{job}").status_code == 202
        assert wait_for(http, job, finished, timeout=10)["state"] == "cancelled"
    # the first server is gone: the folder is free again
    with serve(create_app(config(tmp_path))) as url:
        assert httpx.get(url + "/health").json()["status"] == "ok"


# -- 2. the parts of an upload are bounded ---------------------------------------------------
def test_an_upload_of_many_tiny_parts_is_refused(tmp_path: Path, sketch: bytes) -> None:
    tiny = part("budget", b"5")
    body = tiny * (10 * 2**20 // len(tiny)) + part("sketch", sketch, "s.png") + end()
    with serve(create_app(config(tmp_path))) as url:
        t0 = time.monotonic()
        status, answer = raw_post(url, "/jobs", body)
        assert status == 413 and f"more than {MAX_PARTS} parts".encode() in answer, answer
        assert time.monotonic() - t0 < 10
        # a form with every known option is well within the bound
        fields = [
            ("refine", "false"),
            ("budget", "2"),
            ("time_limit", "30"),
            ("height", "6"),
            ("estimator", ESTIMATOR),
            ("max_faces", "20000"),
        ]
        ok = b"".join(part(k, v.encode()) for k, v in fields)
        status, answer = raw_post(url, "/jobs", ok + part("sketch", sketch, "s.png") + end())
        assert status == 202, answer


# -- 3. and 15. the token: never in a URL or a log; the scheme in any case --------------------
class _Lines(logging.Handler):
    def __init__(self) -> None:
        super().__init__()
        self.lines: list[str] = []

    def emit(self, record: logging.LogRecord) -> None:
        self.lines.append(record.getMessage())


def test_token_from_header_or_cookie_never_from_the_url_and_never_logged(tmp_path: Path) -> None:
    secret = "s3cret-t0ken"
    app = create_app(config(tmp_path, token=secret))
    with serve(app, log_level="info") as url:
        access = logging.getLogger("uvicorn.access")
        lines = _Lines()
        access.addHandler(lines)
        try:
            with httpx.Client(base_url=url, timeout=30) as http:
                assert http.get("/status").status_code == 401
                r = http.get(f"/status?token={secret}")
                assert r.status_code == 401 and "never read" in r.json()["detail"]
                h = {"Authorization": f"Bearer {secret}"}
                assert http.get("/status", headers=h).status_code == 200
                # the page trades the token (header) for a cookie that is not the token
                assert http.post("/session").status_code == 401
                r = http.post("/session", headers={"Authorization": f"bearer {secret}"})
                assert r.status_code == 204
                cookie = r.headers["set-cookie"]
                assert "HttpOnly" in cookie and "SameSite=strict" in cookie and secret not in cookie
                assert "Secure" not in cookie  # plain http: a Secure cookie would not come back
                assert http.get("/status").status_code == 200  # the cookie alone
                # behind a TLS proxy on 127.0.0.1 (uvicorn trusts its X-Forwarded-Proto)
                r = http.post(
                    "/session",
                    headers={"Authorization": f"Bearer {secret}", "X-Forwarded-Proto": "https"},
                )
                assert r.status_code == 204 and "Secure" in r.headers["set-cookie"]
                http.cookies.clear()
                http.cookies.set("treesketch_session", cookie.split(";")[0].split("=", 1)[1])
                http.cookies.set("treesketch_session", "forged")
                assert http.get("/status").status_code == 401
                http.get(f"/health?token={secret}&x=1")
        finally:
            access.removeHandler(lines)
    assert len(lines.lines) >= 8, lines.lines
    assert not [line for line in lines.lines if secret in line], lines.lines
    assert any("token=[redacted]" in line for line in lines.lines)


def test_the_bearer_scheme_in_any_case(tmp_path: Path) -> None:
    with serve(create_app(config(tmp_path, token="t0k"))) as url:
        for scheme in ("Bearer", "bearer", "BEARER", "bEaReR"):
            h = {"Authorization": f"{scheme}  t0k"}
            assert httpx.get(url + "/status", headers=h).status_code == 200, scheme
        for wrong in ("Basic t0k", "Bearer t0kk", "t0k", "Bearer"):
            h = {"Authorization": wrong}
            assert httpx.get(url + "/status", headers=h).status_code == 401, wrong


def test_the_page_keeps_the_token_out_of_every_url(tmp_path: Path, browser: Any) -> None:
    """The page opened as /#token=...: it trades the token for the cookie, drops it from
    the address bar, and no request it makes (the job, the event stream, the pictures, the
    GLB, a download link) carries it.  ``browser`` is the test process's one Playwright
    (conftest): a second sync Playwright in the same process refuses to start."""
    from web_helpers import draw_with_mouse, picture_loaded

    secret = "page-t0ken-xyz"
    with serve(create_app(config(tmp_path, token=secret))) as url:
        ctx = browser.new_context(viewport={"width": 1200, "height": 900})
        try:
            page = ctx.new_page()
            urls: list[str] = []
            page.on("request", lambda r: urls.append(r.url))
            page.goto(f"{url}/#token={secret}")
            draw_with_mouse(page)
            page.fill("#budget", "2")
            page.click("#submit")
            page.wait_for_selector("body[data-state=done]", timeout=180_000)
            page.wait_for_selector("body[data-model=loaded]", timeout=30_000)
            assert picture_loaded(page, "#after") > 0
            links = page.evaluate("[...document.querySelectorAll('a[href]')].map(a => a.href)")
            cookies = ctx.cookies()
            address = page.evaluate("location.href")
        finally:
            ctx.close()
    requested = [u for u in urls if u.startswith(url)]
    assert any("/tree.glb" in u for u in requested), requested
    assert any("/events" in u for u in requested), requested
    # the first is the page itself, its #fragment never sent to the server
    assert not [u for u in requested[1:] + links if secret in u], (requested, links)
    assert secret not in address  # nor in the address bar (history, a shared link)
    (session,) = [c for c in cookies if c["name"] == "treesketch_session"]
    assert session["httpOnly"] and session["sameSite"] == "Strict"
    assert secret not in session["value"]


# -- 4. Host and Origin, with no token set (the default) ---------------------------------------
def test_foreign_host_and_cross_site_posts_are_refused(tmp_path: Path, sketch: bytes) -> None:
    files = {"sketch": ("s.png", sketch, "image/png")}
    with serve(create_app(config(tmp_path))) as url, httpx.Client(base_url=url, timeout=30) as http:
        # DNS rebinding: a foreign name that resolves to 127.0.0.1
        for path in ("/status", "/jobs", "/"):
            r = http.get(path, headers={"Host": "attacker.example:8000"})
            assert r.status_code == 421 and "attacker.example" in r.json()["detail"], path
        assert http.get("/status", headers={"Host": "localhost:1234"}).status_code == 200
        # a web page elsewhere posting a form to the local server
        for origin in ("http://attacker.example", "null", f"{url}.attacker.example"):
            r = http.post("/jobs", files=files, data={"budget": "1"}, headers={"Origin": origin})
            assert r.status_code == 403 and "may not change" in r.json()["detail"], origin
        r = http.post("/jobs", files=files, headers={"Sec-Fetch-Site": "cross-site"})
        assert r.status_code == 403
        assert http.get("/status").json()["jobs"]["queued"] == 0  # nothing was queued
        # reading is not changing: a GET with a foreign Origin is left to CORS
        assert http.get("/status", headers={"Origin": "http://attacker.example"}).status_code == 200
        # the server's own page (same origin), and scripts that send no Origin, may post
        r = http.post("/jobs", files=files, data={"refine": "false"}, headers={"Origin": url})
        assert r.status_code == 202, r.text
        job = r.json()["id"]
        r = http.delete(f"/jobs/{job}", headers={"Origin": "http://attacker.example"})
        assert r.status_code == 403
        assert http.delete(f"/jobs/{job}", headers={"Origin": url}).status_code in (200, 202, 409)


def test_allowed_names_and_cors_origins(tmp_path: Path, sketch: bytes) -> None:
    cfg = config(tmp_path, hosts=("trees.example.org",), cors=("https://app.example.org",))
    files = {"sketch": ("s.png", sketch, "image/png")}
    with http_service(cfg) as http:
        assert http.get("/health").status_code == 421  # 127.0.0.1 is not one of its names
        host = {"Host": "trees.example.org"}
        assert http.get("/status", headers=host).status_code == 200
        # behind a TLS proxy that passes the Host on: the page's own origin
        same = {**host, "Origin": "https://trees.example.org"}
        r = http.post("/jobs", files=files, data={"refine": "false"}, headers=same)
        assert r.status_code == 202, r.text
        r = http.post(
            "/jobs",
            files=files,
            data={"refine": "false"},
            headers={**host, "Origin": "https://app.example.org"},
        )
        assert r.status_code == 202 and r.headers["access-control-allow-origin"]
        r = http.post("/jobs", files=files, headers={**host, "Origin": "https://x.example.org"})
        assert r.status_code == 403


# -- 10. a full disk ---------------------------------------------------------------------------
def test_storage_full_is_507_and_reported_in_health(tmp_path: Path, sketch: bytes) -> None:
    # more free space asked for than any disk has: the server's own check, end to end
    with http_service(config(tmp_path, min_free_bytes=2**62)) as http:
        r = http.post("/jobs", files={"sketch": ("s.png", sketch, "image/png")})
        assert r.status_code == 507 and "storage full" in r.json()["detail"], r.text
        h = http.get("/health").json()
        assert h["status"] == "error" and "storage full" in h["error"]
        assert h["storage"]["full"] and h["storage"]["free_bytes"] > 0
        assert not list((tmp_path / "uploads").iterdir())


@contextlib.contextmanager
def small_disk(path: Path, size_kb: int) -> Iterator[Path]:
    """A tmpfs of ``size_kb`` at ``path`` (root only: mount)."""
    path.mkdir()
    r = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size_kb}k", "tmpfs", str(path)])
    if r.returncode:
        pytest.skip("cannot mount a small tmpfs here (needs root)")
    try:
        yield path
    finally:
        subprocess.run(["umount", "-l", str(path)], check=False)


def fill(disk: Path, leave: int) -> Path:
    """Fill ``disk`` until only about ``leave`` bytes are free; returns the filler file."""
    import shutil

    filler = disk / "filler"
    free = shutil.disk_usage(disk).free
    with open(filler, "ab") as f:
        f.write(b"\0" * max(0, free - leave))
    return filler


@pytest.mark.skipif(os.geteuid() != 0, reason="mounting a small tmpfs needs root")
def test_a_really_full_disk(tmp_path: Path, sketch: bytes) -> None:
    """On a 4 MB tmpfs: no space for the upload -> 507, nothing left behind, /health says
    so; no space for the results -> the job fails "storage full" and leaves no folder; space
    again -> jobs run."""
    with (
        small_disk(tmp_path / "disk", 4096) as disk,
        serve(create_app(config(disk, min_free_bytes=0))) as url,
        httpx.Client(base_url=url, timeout=30) as http,
    ):
        assert http.get("/health").json()["status"] == "ok"
        filler = fill(disk, len(sketch) // 2)
        r = http.post("/jobs", files={"sketch": ("s.png", sketch, "image/png")})
        assert r.status_code == 507 and "storage full" in r.json()["detail"], r.text
        assert not list((disk / "uploads").iterdir())  # not even a temporary file
        h = http.get("/health").json()
        assert h["status"] == "error" and h["storage"]["full"], h
        # room for the upload, not for the results (a GLB and pictures: about 1 MB)
        filler.unlink()
        filler = fill(disk, len(sketch) + 192 * 1024)
        job = submit(http, sketch, refine="false")
        body = wait_for(http, job, finished)
        assert body["state"] == "failed" and "storage full" in body["error"], body
        assert not (disk / "results" / job).exists()
        filler.unlink()
        job = submit(http, sketch, refine="false")
        assert wait_for(http, job, finished)["state"] == "done"
        assert http.get("/health").json()["status"] == "ok"


def test_the_dispatcher_outlives_a_database_that_cannot_be_written(
    tmp_path: Path, sketch: bytes
) -> None:
    """SQLite's own "disk full" while a job's result is saved: the result waits and is
    saved once the database takes writes again (the dispatcher thread used to die, and
    every later job waited for ever)."""
    import sqlite3

    app = create_app(config(tmp_path))
    store = app.state.store
    real_finish, failures = store.finish, [0]

    def finish(job_id: str, summary: dict) -> None:
        if failures[0] < 2:
            failures[0] += 1
            raise sqlite3.OperationalError("database or disk is full")
        real_finish(job_id, summary)

    store.finish = finish
    with serve(app) as url, httpx.Client(base_url=url, timeout=30) as http:
        first = submit(http, sketch, refine="false")
        assert wait_for(http, first, finished, timeout=60)["state"] == "done"
        assert failures[0] == 2
        second = submit(http, sketch, refine="false")
        assert wait_for(http, second, finished, timeout=60)["state"] == "done"


def test_retention_removes_empty_folders_and_counts_orphaned_results(tmp_path: Path) -> None:
    store = JobStore(tmp_path)
    job = store.create(b"x", {"budget": 1}, max_queued=4)
    assert job is not None and store.claim_next() is not None
    store.fail(job.id, "storage full")
    (store.result_dir(job.id)).mkdir()  # left empty by a failed write
    orphans = ["0123456789abcdef0123456789abcdef", "fedcba9876543210fedcba9876543210"]
    for i, orphan in enumerate(orphans):  # results no job refers to (a deleted database)
        (store.result_dir(orphan)).mkdir()
        (store.result_dir(orphan) / "tree.glb").write_bytes(b"g" * 1000 * (i + 1))
        store.upload_path(orphan).write_bytes(b"x" * 10)
    keep = store.results / "notes.txt"  # not the store's: never touched
    keep.write_text("mine")

    def age(paths: list[Path], days: float) -> None:
        t = time.time() - days * 86400
        for p in paths:
            for f in [p, *(p.rglob("*") if p.is_dir() else [])]:
                os.utime(f, (t, t))

    assert store.expire(max_age_s=None, max_bytes=None) == []
    assert store.result_dir(job.id).is_dir()  # too young: may be a job being saved
    age([store.result_dir(job.id)], 1)
    for i, orphan in enumerate(orphans):
        age([store.result_dir(orphan), store.upload_path(orphan)], 20 - i)
    young = "00000000000000000000000000000000"  # may be a job being made: never touched
    store.result_dir(young).mkdir()
    (store.result_dir(young) / "tree.glb").write_bytes(b"g" * 5000)
    assert store.expire(max_age_s=30 * 86400, max_bytes=None) == []
    assert not store.result_dir(job.id).exists()  # the empty folder went at once
    # orphans count towards the size limit, and go oldest first
    assert store.expire(max_age_s=30 * 86400, max_bytes=2500) == [orphans[0]]
    assert not store.result_dir(orphans[0]).exists() and not store.upload_path(orphans[0]).exists()
    assert store.result_dir(orphans[1]).is_dir()
    # and by their age
    assert store.expire(max_age_s=10 * 86400, max_bytes=None) == [orphans[1]]
    assert keep.read_text() == "mine" and store.upload_path(job.id).exists()
    assert (store.result_dir(young) / "tree.glb").exists()


# -- 11. the job database: deleted while running, corrupt at start, a bad --data -----------------
def test_database_deleted_while_running_is_detected_and_its_results_are_swept(
    tmp_path: Path, sketch: bytes
) -> None:
    with http_service(config(tmp_path)) as http:
        done = submit(http, sketch, refine="false")
        assert wait_for(http, done, finished)["state"] == "done"
        for name in ("jobs.sqlite", "jobs.sqlite-wal", "jobs.sqlite-shm"):
            (tmp_path / name).unlink(missing_ok=True)
        h = http.get("/health").json()
        assert h["status"] == "error" and "was deleted" in h["error"], h
        r = http.post("/jobs", files={"sketch": ("s.png", sketch, "image/png")})
        assert r.status_code == 503 and "restart the server" in r.json()["detail"]
        assert http.get(f"/jobs/{done}").json()["state"] == "done"  # still readable
    # restarted: an empty database; the old job's files are orphans that retention removes
    with http_service(config(tmp_path)) as http:
        assert http.get("/health").json()["status"] == "ok"
        assert http.get(f"/jobs/{done}").status_code == 404
        # made 40 days ago, its record gone: the 30-day retention finds the files
        old = time.time() - 40 * 86400
        for p in [tmp_path / "results" / done, tmp_path / "uploads" / f"{done}.img"]:
            for f in [p, *(p.rglob("*") if p.is_dir() else [])]:
                os.utime(f, (old, old))
        JobStore(tmp_path).expire(max_age_s=30 * 86400, max_bytes=2**31)
        assert not (tmp_path / "results" / done).exists()
        assert not (tmp_path / "uploads" / f"{done}.img").exists()


def run_serve(*args: str) -> subprocess.CompletedProcess[str]:
    cmd = [sys.executable, "-m", "treesketch.cli", "serve", "--workers", "1", *args]
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.run(cmd, capture_output=True, text=True, timeout=60, env=env)


def test_corrupt_database_or_bad_data_folder_is_a_plain_error(tmp_path: Path) -> None:
    corrupt = tmp_path / "corrupt"
    corrupt.mkdir()
    (corrupt / "jobs.sqlite").write_bytes(b"this is not a database, it is a text file\n" * 100)
    a_file = tmp_path / "a_file"
    a_file.write_text("x")
    for data, words in [
        (corrupt, "cannot be read"),
        (a_file, "it is a file"),
        (a_file / "below", "cannot use"),
    ]:
        r = run_serve("--data", str(data), "--estimator", "template")
        assert r.returncode == 2, (data, r.stderr)
        assert words in r.stderr and "Traceback" not in r.stderr, r.stderr
        assert len(r.stderr.strip().splitlines()) <= 3, r.stderr


# -- 13. multipart edge cases -------------------------------------------------------------------
def test_sketch_part_without_filename_is_accepted(tmp_path: Path, sketch: bytes) -> None:
    with serve(create_app(config(tmp_path))) as url:
        # RFC 7578: filename= is optional
        body = part("refine", b"false") + part("sketch", sketch) + end()
        status, answer = raw_post(url, "/jobs", body)
        assert status == 202, answer


def test_body_cut_off_before_its_closing_boundary_is_refused(tmp_path: Path, sketch: bytes) -> None:
    with serve(create_app(config(tmp_path))) as url, httpx.Client(base_url=url, timeout=30) as http:
        # the closing boundary never came (a Content-Length that matches what was sent)
        cut = part("refine", b"false") + part("sketch", sketch, "s.png")
        for body in (cut, cut[: len(cut) // 2]):
            status, answer = raw_post(url, "/jobs", body)
            assert status == 400 and b"cut off" in answer, answer
        assert http.get("/status").json()["jobs"] == {
            "queued": 0,
            "running": 0,
            "done": 0,
            "failed": 0,
            "cancelled": 0,
            "expired": 0,
        }


def test_serve_names_the_hosts_it_answers_to(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    import uvicorn
    from typer.testing import CliRunner

    from treesketch.cli import app

    seen: dict = {}
    monkeypatch.setattr(uvicorn, "run", lambda a, **kw: seen.update(kw, app=a))
    base = ["serve", "--data", str(tmp_path), "--workers", "1", "--estimator", "template"]
    r = CliRunner().invoke(app, base)
    assert r.exit_code == 0, r.output
    assert seen["app"].state.config.hosts == ("127.0.0.1", "localhost", "::1")
    r = CliRunner().invoke(app, [*base, "--host", "0.0.0.0", "--token", "t"])
    assert seen["app"].state.config.hosts == ("*",) and "--allow-host" in r.output
    r = CliRunner().invoke(
        app, [*base, "--host", "0.0.0.0", "--token", "t", "--allow-host", "trees.example.org"]
    )
    hosts = seen["app"].state.config.hosts
    assert "trees.example.org" in hosts and "*" not in hosts and "--allow-host" not in r.output
    r = CliRunner().invoke(app, [*base, "--host", "192.168.1.5", "--token", "t"])
    assert "192.168.1.5" in seen["app"].state.config.hosts
