"""Helpers for the service tests: a cheap estimator that spawned workers can import."""

from __future__ import annotations

import contextlib
import io
from collections.abc import Iterator
from typing import Any

import numpy as np

from treesketch import Estimate
from weberpenn import species


class PalmEstimator:
    """A fixed palm as the first estimate: no network, fast to grow and render."""

    name = "palm-8"

    def estimate(self, sketch: np.ndarray) -> Estimate:
        return Estimate(species.sample("palm", 8), "palm", {"palm": 1.0})


palm_estimator = PalmEstimator()


def png(img: np.ndarray) -> bytes:
    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(img).save(buf, format="PNG")
    return buf.getvalue()


def palm_sketch_png(seed: int = 3) -> bytes:
    from render.sketch import SketchRenderer
    from weberpenn import build_mesh, grow

    m = build_mesh(grow(species.sample("palm", seed)), species="palm")
    return png(SketchRenderer(m).sketch(0, 256))


@contextlib.contextmanager
def serve(app: Any, log_level: str = "warning") -> Iterator[str]:
    """Run ``app`` under uvicorn in a thread on a free localhost port; yields its base URL.
    (A real server, unlike TestClient: streamed bodies, disconnects, sockets.)"""
    import socket
    import threading
    import time

    import uvicorn

    sock = socket.socket()
    sock.bind(("127.0.0.1", 0))
    port = sock.getsockname()[1]
    server = uvicorn.Server(uvicorn.Config(app, log_level=log_level, lifespan="on"))
    thread = threading.Thread(target=server.run, kwargs={"sockets": [sock]}, daemon=True)
    thread.start()
    deadline = time.monotonic() + 60
    while not server.started:
        if time.monotonic() > deadline or not thread.is_alive():
            raise RuntimeError("the test server did not start")
        time.sleep(0.05)
    try:
        yield f"http://127.0.0.1:{port}"
    finally:
        server.should_exit = True
        thread.join(30)
        sock.close()
