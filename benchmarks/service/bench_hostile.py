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
"""

from __future__ import annotations

import argparse
import contextlib
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
    args = ap.parse_args()

    from treesketch.service import Limits

    cap = Limits().max_upload_bytes  # the most the server takes
    bodies = {"tiny parts": tiny_parts_body(cap), "one file": one_file_body(cap - 1024)}
    port = free_port()
    url = f"http://127.0.0.1:{port}"
    results: dict[str, Tally] = {}
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
            for name, body in bodies.items():
                results[name] = hammer(port, body, args.clients, args.seconds, server)
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
    ok = [report(n, bodies[n], t, args.clients, args.seconds) for n, t in results.items()]
    verdict = "PASS" if ok[0] else "FAIL"
    print(f"{verdict} (tiny parts: /health p95 < 100 ms, server < 250 MB)")
    print(f"one file, same goal: {'met' if ok[1] else 'not met'}")


if __name__ == "__main__":
    main()
