"""``treesketch serve`` as a subprocess for the service benchmarks: started on a free port,
waited for until its workers are ready, stopped."""

from __future__ import annotations

import socket
import subprocess
import sys
import time
from pathlib import Path

import httpx

from treesketch.service.store import FINISHED  # a job's end states, for the benchmarks' waits

__all__ = ["FINISHED", "ServeProcess", "free_port"]


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class ServeProcess:
    """``treesketch serve --port P --data DATA --workers N ARGS``, its output in ``log``;
    ``start_s``: seconds until all ``workers`` reported ready."""

    def __init__(
        self, args: list[str], data: Path, workers: int, log: Path, timeout: float = 300.0
    ) -> None:
        self.port = free_port()
        self.url = f"http://127.0.0.1:{self.port}"
        cmd = [sys.executable, "-m", "treesketch.cli", "serve", "--port", str(self.port)]
        cmd += ["--data", str(data), "--workers", str(workers), *args]
        self.log = open(log, "w")  # noqa: SIM115 - closed in stop()
        t0 = time.perf_counter()
        self.proc = subprocess.Popen(cmd, stdout=self.log, stderr=subprocess.STDOUT)
        deadline = time.monotonic() + timeout
        while not self._ready(workers):
            if time.monotonic() > deadline or self.proc.poll() is not None:
                self.stop()
                raise RuntimeError(f"the server did not start; see {log}")
            time.sleep(0.2)
        self.start_s = time.perf_counter() - t0

    def _ready(self, workers: int) -> bool:
        try:
            h = httpx.get(self.url + "/status", timeout=2).json()
            return sum(w["ready"] for w in h["workers"]) == workers
        except (httpx.HTTPError, ValueError, KeyError):
            return False

    def stop(self) -> None:
        self.proc.terminate()
        try:
            self.proc.wait(60)
        except subprocess.TimeoutExpired:
            self.proc.kill()
        self.log.close()
