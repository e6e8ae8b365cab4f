"""The service's app under uvicorn in a thread of this process, on a free localhost port:
a real server (streamed bodies, disconnects, sockets, unlike a TestClient) for the tests,
``benchmarks/service/bench_interactive.py`` and ``scripts/make_web_png.py``.  ``treesketch serve``
is the server people run."""

from __future__ import annotations

import contextlib
import socket
import threading
import time
from collections.abc import Iterator
from typing import Any


@contextlib.contextmanager
def serve(app: Any, log_level: str = "warning") -> Iterator[str]:
    """Run ``app`` under uvicorn in a daemon thread on a free localhost port; yields its
    base URL and stops the server on leaving."""
    import uvicorn

    # bound here and handed over, so no other process can take the port in between
    sock = socket.socket()
    sock.bind(("127.0.0.1", 0))
    port = sock.getsockname()[1]
    server = uvicorn.Server(uvicorn.Config(app, log_level=log_level, lifespan="on"))
    thread = threading.Thread(target=server.run, kwargs={"sockets": [sock]}, daemon=True)
    thread.start()
    deadline = time.monotonic() + 60
    while not server.started:
        if time.monotonic() > deadline or not thread.is_alive():
            raise RuntimeError("the in-process server did not start")
        time.sleep(0.05)
    try:
        yield f"http://127.0.0.1:{port}"
    finally:
        server.should_exit = True
        thread.join(30)
        sock.close()
