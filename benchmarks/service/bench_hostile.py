"""Hostile uploads against the job service: does it stay responsive and small?

Runs ``treesketch serve`` as a subprocess (the real thing: uvicorn, SQLite, one spawned
worker; ``--source`` runs another checkout's code, e.g. the commit before a fix).  Three
client threads upload, over and over for ``--seconds``, a 10 MB body made of tiny text
parts (about 190,000 of them, like the issue-30 report) over plain sockets, reading the
answer whenever it comes (the server may answer early and close).  Meanwhile a sampler
times ``GET /health`` every 20 ms and another reads the server process's resident memory
(psutil; the server only, not its worker) every 50 ms.  The goal: /health p95 under
100 ms and the server under 250 MB throughout.  A second round does the same with one
10 MB file part (random bytes: parsed in full, then refused as no image).

    PYTHONPATH=$PWD .venv/bin/python benchmarks/service/bench_hostile.py --seconds 30

Two more cases on ``POST /trees`` (issue 49), against the same server (``--cases``):

- ``big-trees``: four clients ask, over and over, for expensive trees (a 4-level tree of
  38^3 branches with its controls past the limits and ``fit``, 10-20 s of growing; a
  palm of 500 thick branches at full detail, a 110 MB GLB before the cap) while a fifth
  makes slider edits of a maple (the page's request: a light GLB, ``fit`` the slider)
  and times each round trip.  Goal: edits' median <= 300 ms.
- ``slow-readers``: eight clients ask for the largest reply there is (that palm at the
  cap, 1.5 M triangles, about 40 MB) and never read it, holding the connection.
  Goal: the server's memory stays bounded (and is given back when they leave).

In both, /health is timed and the memory of the server and of the server with its child
processes (the job worker and the tree processes) is read, and ``after`` is the server's
memory 5 s after the clients went away.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import platform
import socket
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import httpx
import psutil

ROOT = Path(__file__).resolve().parents[2]
BOUNDARY = "hostilebench"


def tiny_parts_body(size: int) -> bytes:
    """About ``size`` bytes of one-character form fields, then a closing boundary."""
    part = f'--{BOUNDARY}\r\nContent-Disposition: form-data; name="budget"\r\n\r\n5\r\n'.encode()
    return part * (size // len(part)) + f"--{BOUNDARY}--\r\n".encode()


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@dataclass
class Tally:
    statuses: Counter[str] = field(default_factory=Counter)
    answer_s: list[float] = field(default_factory=list)
    sent_mb: float = 0.0
    health_ms: list[float] = field(default_factory=list)
    health_errors: int = 0
    rss_mb: list[float] = field(default_factory=list)
    lock: threading.Lock = field(default_factory=threading.Lock)


def upload(port: int, body: bytes, tally: Tally) -> None:
    """One upload over a socket: send the body while watching for an early answer."""
    t0 = time.perf_counter()
    sent = 0
    answer = b""
    with socket.create_connection(("127.0.0.1", port), timeout=60) as s:
        s.sendall(
            f"POST /jobs HTTP/1.1\r\nHost: 127.0.0.1\r\n"
            f"Content-Type: multipart/form-data; boundary={BOUNDARY}\r\n"
            f"Content-Length: {len(body)}\r\nConnection: close\r\n\r\n".encode()
        )
        view = memoryview(body)
        try:
            while sent < len(body):
                s.settimeout(0.0)
                try:
                    answer += s.recv(65536)
                    if answer:
                        break
                except BlockingIOError:
                    pass
                s.settimeout(60)
                n = s.send(view[sent : sent + 65536])
                sent += n
            s.settimeout(60)
            while b"\r\n" not in answer:
                chunk = s.recv(65536)
                if not chunk:
                    break
                answer += chunk
        except OSError:  # the server answered and closed while we sent
            s.settimeout(5)
            with contextlib.suppress(OSError):
                answer += s.recv(65536)
    status = answer.split(b" ")[1].decode() if answer.startswith(b"HTTP/") else "no answer"
    with tally.lock:
        tally.statuses[status] += 1
        tally.answer_s.append(time.perf_counter() - t0)
        tally.sent_mb += sent / 2**20


def pct(xs: list[float], q: int) -> float:
    return statistics.quantiles(xs, n=100)[q - 1] if len(xs) >= 2 else float("nan")


def one_file_body(size: int) -> bytes:
    """One ``sketch`` file part of ``size`` random bytes (parsed in full; not an image)."""
    head = (
        f'--{BOUNDARY}\r\nContent-Disposition: form-data; name="sketch"; filename="s.png"\r\n'
        "Content-Type: image/png\r\n\r\n"
    ).encode()
    return head + os.urandom(size) + f"\r\n--{BOUNDARY}--\r\n".encode()


def hammer(port: int, body: bytes, clients: int, seconds: float, server: psutil.Process) -> Tally:
    """``clients`` threads uploading ``body`` for ``seconds``, /health timed and the server's
    memory read meanwhile."""
    tally = Tally()
    stop = threading.Event()

    def client() -> None:
        while not stop.is_set():
            upload(port, body, tally)

    def health() -> None:
        with httpx.Client(base_url=f"http://127.0.0.1:{port}", timeout=30) as http:
            while not stop.is_set():
                t = time.perf_counter()
                try:
                    ok = http.get("/health").status_code == 200
                except httpx.HTTPError:
                    ok = False
                with tally.lock:
                    tally.health_ms.append(1000 * (time.perf_counter() - t))
                    tally.health_errors += not ok
                time.sleep(0.02)

    def memory() -> None:
        while not stop.is_set():
            tally.rss_mb.append(server.memory_info().rss / 2**20)
            time.sleep(0.05)

    threads = [threading.Thread(target=client) for _ in range(clients)]
    threads += [threading.Thread(target=health), threading.Thread(target=memory)]
    for t in threads:
        t.start()
    time.sleep(seconds)
    stop.set()
    for t in threads:
        t.join()
    return tally


def wide_palm() -> dict[str, Any]:
    """The palm of 500 branches, 64 points each and thick tubes (4.3 M triangles)."""
    from weberpenn import species

    base = species.base("palm").to_dict()
    return {
        **base,
        **{"levels": 2, "branches": [0, 500, 10, 10], "curveRes": [64, 64, 1, 1]},
        **{"leaves": 500, "bevelRes": 32, "resU": 1},
    }


def slow_tree() -> dict[str, Any]:
    """A 4-level tree of 38^3 branches, controls past the limits, ``fit``: 10-20 s."""
    from weberpenn import species

    params = {
        **species.base("cherry").to_dict(),
        **{"branches": [0, 38, 38, 38], "curveRes": [40, 40, 40, 14], "prune": True},
        **{"resU": 2, "bevelRes": 1, "segSplits": [0, 0, 0, 0]},
    }
    controls = {"height": 40, "branch_count": 2.5, "leaf_density": 3.0}
    return {"params": params, "controls": controls, "fit": True, "species": "cherry"}


@dataclass
class TreeTally:
    statuses: Counter[str] = field(default_factory=Counter)
    edit_ms: list[float] = field(default_factory=list)
    edit_errors: Counter[str] = field(default_factory=Counter)
    health_ms: list[float] = field(default_factory=list)
    server_mb: list[float] = field(default_factory=list)
    total_mb: list[float] = field(default_factory=list)
    after_mb: float = float("nan")
    lock: threading.Lock = field(default_factory=threading.Lock)


def memory_mb(server: psutil.Process) -> tuple[float, float]:
    """(the server's resident memory, with every child process's) in MB."""
    own = server.memory_info().rss
    total = own
    for child in server.children(recursive=True):
        with contextlib.suppress(psutil.Error):
            total += child.memory_info().rss
    return own / 2**20, total / 2**20


def watch(port: int, tally: TreeTally, stop: threading.Event, server: psutil.Process) -> list:
    """The /health and memory samplers' threads (started)."""

    def health() -> None:
        with httpx.Client(base_url=f"http://127.0.0.1:{port}", timeout=30) as http:
            while not stop.is_set():
                t = time.perf_counter()
                with contextlib.suppress(httpx.HTTPError):
                    http.get("/health")
                with tally.lock:
                    tally.health_ms.append(1000 * (time.perf_counter() - t))
                time.sleep(0.05)

    def memory() -> None:
        while not stop.is_set():
            with contextlib.suppress(psutil.Error):
                own, total = memory_mb(server)
                tally.server_mb.append(own)
                tally.total_mb.append(total)
            time.sleep(0.1)

    threads = [threading.Thread(target=health), threading.Thread(target=memory)]
    for t in threads:
        t.start()
    return threads


def big_trees(port: int, seconds: float, server: psutil.Process, clients: int = 4) -> TreeTally:
    """``clients`` threads asking for expensive trees while one times slider edits."""
    tally = TreeTally()
    stop = threading.Event()
    url = f"http://127.0.0.1:{port}/trees"
    glb = {"Accept": "model/gltf-binary"}
    bodies = [slow_tree(), {"params": wide_palm(), "max_faces": None}]

    def expensive(i: int) -> None:
        with httpx.Client(timeout=120) as http:
            n = i
            while not stop.is_set():
                try:
                    r = http.post(url, json=bodies[n % 2], headers=glb)
                    status = str(r.status_code)
                    if r.status_code == 503 and r.headers.get("retry-after"):
                        time.sleep(1.0)  # a client that honours part of Retry-After
                except httpx.HTTPError as exc:
                    status = type(exc).__name__
                with tally.lock:
                    tally.statuses[status] += 1
                n += 1

    def edits() -> None:
        from weberpenn import species

        params = species.base("maple").to_dict()
        with httpx.Client(timeout=120) as http:
            k = 0
            while not stop.is_set():
                width = 0.8 + 0.05 * (k % 9)  # a slider dragged to and fro
                body = {"params": params, "species": "maple", "max_faces": 80_000}
                body |= {"controls": {"crown_width": width}, "fit": ["crown_width"]}
                t = time.perf_counter()
                try:
                    r = http.post(url, json=body, headers=glb)
                    ok = r.status_code == 200 and r.content[:4] == b"glTF"
                    why = str(r.status_code)
                except httpx.HTTPError as exc:
                    ok, why = False, type(exc).__name__
                with tally.lock:
                    if ok:
                        tally.edit_ms.append(1000 * (time.perf_counter() - t))
                    else:
                        tally.edit_errors[why] += 1
                k += 1
                time.sleep(0.1)  # a person drags: about ten edits a second at most

    threads = watch(port, tally, stop, server)
    workers = [threading.Thread(target=expensive, args=(i,)) for i in range(clients)]
    for t in workers:
        t.start()
    time.sleep(3.0)  # the expensive ones are in
    editor = threading.Thread(target=edits)
    editor.start()
    time.sleep(seconds)
    stop.set()
    for t in [*threads, *workers, editor]:
        t.join()
    time.sleep(5.0)
    tally.after_mb = server.memory_info().rss / 2**20
    return tally


def slow_readers(port: int, seconds: float, server: psutil.Process, clients: int = 8) -> TreeTally:
    """``clients`` sockets each asking for the largest reply and never reading it."""
    tally = TreeTally()
    stop = threading.Event()
    body = json.dumps({"params": wide_palm(), "max_faces": 1_500_000}).encode()
    request = (
        f"POST /trees HTTP/1.1\r\nHost: 127.0.0.1\r\nAccept: model/gltf-binary\r\n"
        f"Content-Type: application/json\r\nContent-Length: {len(body)}\r\n\r\n"
    ).encode() + body

    def reader() -> None:
        while not stop.is_set():
            with socket.create_connection(("127.0.0.1", port), timeout=120) as s:
                # a small receive buffer: what the client does not read stays server-side
                s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
                s.sendall(request)
                head = b""
                with contextlib.suppress(OSError):
                    while b"\r\n" not in head and not stop.is_set():
                        chunk = s.recv(64)
                        if not chunk:
                            break
                        head += chunk
                status = head.split(b" ")[1].decode() if head.startswith(b"HTTP/") else "none"
                with tally.lock:
                    tally.statuses[status] += 1
                if status != "200":
                    stop.wait(1.0)
                    continue
                stop.wait(seconds)  # hold the connection, reading nothing more

    threads = watch(port, tally, stop, server)
    readers = [threading.Thread(target=reader) for _ in range(clients)]
    for t in readers:
        t.start()
    time.sleep(seconds)
    stop.set()
    for t in [*threads, *readers]:
        t.join()
    time.sleep(5.0)
    tally.after_mb = server.memory_info().rss / 2**20
    return tally


def report_trees(name: str, tally: TreeTally, seconds: float) -> bool:
    h, e = tally.health_ms, tally.edit_ms
    print(f"{name}, {seconds:g} s: expensive answers {dict(tally.statuses)}")
    if name == "big trees":
        print(
            f"  slider edits: {len(e)} ok, median {pct(e, 50):.0f} ms, p95 {pct(e, 95):.0f} ms, "
            f"max {max(e, default=float('nan')):.0f} ms; failed {dict(tally.edit_errors)}"
        )
    print(
        f"  /health: {len(h)} samples, p50 {pct(h, 50):.1f} ms, p95 {pct(h, 95):.1f} ms; memory "
        f"max: server {max(tally.server_mb):.0f} MB, with its child processes "
        f"{max(tally.total_mb):.0f} MB; server after {tally.after_mb:.0f} MB"
    )
    if name == "big trees":
        return bool(e) and pct(e, 50) <= 300 and not tally.edit_errors
    return max(tally.server_mb) < 1024


def report(name: str, body: bytes, tally: Tally, clients: int, seconds: float) -> bool:
    h = tally.health_ms
    parts = body.count(b"Content-Disposition")
    print(
        f"{name}: {clients} clients, {seconds:g} s: {sum(tally.statuses.values())} uploads of "
        f"{len(body) / 1e6:.1f} MB in {parts} part(s), answers {dict(tally.statuses)}, "
        f"{tally.sent_mb:.0f} MB sent, answer time median {statistics.median(tally.answer_s):.2f} s"
    )
    print(
        f"  /health: {len(h)} samples, p50 {pct(h, 50):.1f} ms, p95 {pct(h, 95):.1f} ms, "
        f"max {max(h):.1f} ms, errors {tally.health_errors}; "
        f"server memory max {max(tally.rss_mb):.0f} MB"
    )
    return pct(h, 95) < 100 and max(tally.rss_mb) < 250 and not tally.health_errors


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seconds", type=float, default=30.0)
    ap.add_argument("--clients", type=int, default=3)
    ap.add_argument("--source", type=Path, default=ROOT, help="the checkout whose server runs")
    ap.add_argument(
        "--cases",
        default="uploads,big-trees,slow-readers",
        help="comma-separated: uploads (issue 30), big-trees, slow-readers (issue 49)",
    )
    ap.add_argument(
        "--tree-clients",
        type=int,
        default=4,
        help="big-trees: clients asking for expensive trees (0: the edits' own time)",
    )
    args = ap.parse_args()
    cases = {c.strip() for c in args.cases.split(",") if c.strip()}
    unknown = cases - {"uploads", "big-trees", "slow-readers"}
    if unknown:
        ap.error(f"unknown case(s) {', '.join(sorted(unknown))}")

    from treesketch.service import Limits

    cap = Limits().max_upload_bytes  # the most the server takes
    bodies = {"tiny parts": tiny_parts_body(cap), "one file": one_file_body(cap - 1024)}
    port = free_port()
    url = f"http://127.0.0.1:{port}"
    results: dict[str, Tally] = {}
    trees: dict[str, TreeTally] = {}
    with tempfile.TemporaryDirectory() as data:
        cmd = [sys.executable, "-m", "treesketch.cli", "serve", "--port", str(port)]
        cmd += ["--data", data, "--workers", "1", "--estimator", "template"]
        env = {**os.environ, "PYTHONPATH": str(args.source.resolve())}
        proc = subprocess.Popen(  # in the source: `python -m` puts the cwd first on the path
            cmd, env=env, cwd=args.source, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
        )
        try:
            deadline = time.monotonic() + 120
            while True:
                try:
                    if httpx.get(url + "/health", timeout=2).status_code == 200:
                        break
                except httpx.HTTPError:
                    pass
                if time.monotonic() > deadline or proc.poll() is not None:
                    raise RuntimeError("the server did not start")
                time.sleep(0.3)
            time.sleep(3.0)  # let the worker finish loading
            server = psutil.Process(proc.pid)
            idle_mb = server.memory_info().rss / 2**20
            if "uploads" in cases:
                for name, body in bodies.items():
                    results[name] = hammer(port, body, args.clients, args.seconds, server)
            if "big-trees" in cases:
                trees["big trees"] = big_trees(port, args.seconds, server, args.tree_clients)
            if "slow-readers" in cases:
                trees["slow readers"] = slow_readers(port, args.seconds, server)
        finally:
            proc.terminate()
            try:
                proc.wait(30)
            except subprocess.TimeoutExpired:
                proc.kill()

    commit = subprocess.run(
        ["git", "-C", str(args.source), "rev-parse", "--short", "HEAD"],
        capture_output=True,
        text=True,
    ).stdout.strip()
    print(f"source {args.source} at {commit}; {platform.node()}, {os.cpu_count()} CPUs")
    print(f"server memory idle: {idle_mb:.0f} MB")
    if results:
        ok = [report(n, bodies[n], t, args.clients, args.seconds) for n, t in results.items()]
        verdict = "PASS" if ok[0] else "FAIL"
        print(f"{verdict} (tiny parts: /health p95 < 100 ms, server < 250 MB)")
        print(f"one file, same goal: {'met' if ok[1] else 'not met'}")
    for name, tally in trees.items():
        goal = "slider edits' median <= 300 ms" if name == "big trees" else "server < 1 GB"
        verdict = "PASS" if report_trees(name, tally, args.seconds) else "FAIL"
        print(f"{verdict} ({name}: {goal})")


if __name__ == "__main__":
    main()
