"""How long one call of the shape embedding takes with one torch thread and with two,
on an idle machine and beside busy processes.

    .venv/bin/python benchmarks/probes/embed_threads.py [--calls 200] [--busy 0 2]

The refinement embeds one sketch per evaluation (``refine.embed.ShapeEmbedder``), a
network of about 1 ms. For each ``--busy`` count, that many processes spin on the CPU
(a stand-in for another job on the machine) while the network runs ``--calls`` times on
a random 128 px mask pair, first with torch's pool at two threads, then at one, then
through ``ShapeEmbedder.embed_many`` (which runs it on one thread). Printed: median, 90th
percentile and mean milliseconds per call.
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import time
from collections.abc import Callable

import numpy as np
import torch

from refine.embed import EMBED_SIZE, load_embedder
from refine.shape import ShapeTarget


def _spin(stop: object) -> None:
    x = 0.0
    while not stop.is_set():  # type: ignore[attr-defined]
        for i in range(10000):
            x += i * 1e-9


def _calls(fn: Callable[[], object], n: int) -> list[str]:
    ts = []
    for _ in range(n):
        t = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t)
    ms = 1000 * np.asarray(ts)
    return [f"{np.median(ms):.2f}", f"{np.percentile(ms, 90):.2f}", f"{ms.mean():.2f}"]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--calls", type=int, default=200)
    ap.add_argument("--busy", type=int, nargs="+", default=[0, 2])
    args = ap.parse_args()
    emb = load_embedder()
    rng = np.random.default_rng(0)
    x = torch.from_numpy((rng.random((1, 2, EMBED_SIZE, EMBED_SIZE)) > 0.8).astype(np.float32))
    net = emb.net.eval()

    def plain() -> None:
        with torch.no_grad():
            net(x)

    target = ShapeTarget.from_image(
        np.where(rng.random((256, 256)) > 0.97, 0, 255).astype(np.uint8), EMBED_SIZE
    )

    print("| busy processes | torch threads | median ms | p90 ms | mean ms |")
    print("|---:|---|---:|---:|---:|")
    for busy in args.busy:
        stop = mp.Event()
        procs = [mp.Process(target=_spin, args=(stop,), daemon=True) for _ in range(busy)]
        for p in procs:
            p.start()
        try:
            time.sleep(0.5)
            for threads in (2, 1):
                torch.set_num_threads(threads)
                row = _calls(plain, args.calls)
                print(f"| {busy} | {threads} (the network alone) | " + " | ".join(row) + " |")
            torch.set_num_threads(2)
            row = _calls(lambda: emb.embed_many([target]), args.calls)
            print(f"| {busy} | `embed_many` (pool at 2) | " + " | ".join(row) + " |")
        finally:
            stop.set()
            for p in procs:
                p.join()


if __name__ == "__main__":
    main()
