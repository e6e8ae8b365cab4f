"""Benchmark TSN on the CPU: inference per sketch and training throughput.

    .venv/bin/python benchmarks/bench_tsn.py                       # shipped checkpoint
    .venv/bin/python benchmarks/bench_tsn.py --checkpoint PATH --markdown

Inference: ``model.predict(sketch)`` at batch 1 on 256 px dataset-style sketches, end to
end (preprocessing, network, decoding, species identification, projection), median over
``--repeats`` runs; the network alone too.  Reference in the same run: the same network
(EfficientNet-Lite0) at its standard 224 px input, batch 1.

Training: images per second of one optimiser step at ``--batch`` on cached features (the
recipe of ``tsn.train``: frozen early stages cached once, last stages + heads trained),
plus the one-off cost of caching (frozen stages forward, per image).  Reference in the
same run: a full training step of the whole network at the same input size (what
training without the cache would cost).  The load average is printed with the numbers:
the machine is shared and timings vary with it.
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import time
from datetime import UTC, datetime
from pathlib import Path

import numpy as np
import torch


def _median_ms(fn, repeats: int, warmup: int = 2) -> float:
    for _ in range(warmup):
        fn()
    ts = []
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        ts.append((time.perf_counter() - t) * 1000)
    return statistics.median(ts)


def _sketches(n: int) -> list[np.ndarray]:
    from render.sketch import SketchRenderer
    from weberpenn import build_mesh, grow, species

    out = []
    for i in range(n):
        name = species.SPECIES[i % len(species.SPECIES)]
        mesh = build_mesh(grow(species.sample(name, 100 + i)), species=name)
        out.append(SketchRenderer(mesh).sketch(90.0 * (i % 4), 256))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--checkpoint", type=Path, default=None)
    ap.add_argument("--repeats", type=int, default=30)
    ap.add_argument("--batch", type=int, default=64)
    ap.add_argument("--threads", type=int, default=1, help="torch threads for inference")
    ap.add_argument("--train-threads", type=int, default=1, help="torch threads for training")
    ap.add_argument("--markdown", action="store_true")
    args = ap.parse_args()
    torch.set_num_threads(args.threads)

    from tsn.encoding import HEAD_SIZES
    from tsn.model import TSN
    from tsn.predict import load_model
    from tsn.train import loss_fn, set_trainable, train_mode

    load0 = os.getloadavg()[0]
    model = load_model(args.checkpoint, device="cpu")
    net, size = model.net, model.size
    cut = int(model.info.get("cut", 12))
    sketches = _sketches(5)
    i = iter(range(10**9))

    def predict_one() -> None:
        model.predict(sketches[next(i) % len(sketches)])

    e2e = _median_ms(predict_one, args.repeats)
    x1 = torch.rand(1, 1, size, size)
    with torch.no_grad():
        net_ms = _median_ms(lambda: net(x1), args.repeats)
        x224 = torch.rand(1, 1, 224, 224)
        ref = TSN("lite0", pretrained=False).eval()
        ref_ms = _median_ms(lambda: ref(x224), args.repeats)

    # training: cached-feature step vs full-network step, same input size and batch
    torch.set_num_threads(args.train_threads)
    xb = torch.rand(args.batch, 1, size, size)
    y = {h: torch.zeros(args.batch, 4, HEAD_SIZES[h]) for h in HEAD_SIZES}
    tnet = TSN(net.backbone_name, pretrained=False)
    with torch.no_grad():
        tnet.eval()
        cache_ms = _median_ms(lambda: tnet.features(xb, cut), 3, 1) / args.batch
        feats = tnet.features(xb, cut)
    params = set_trainable(tnet, cut)
    opt = torch.optim.Adam(params, lr=1e-4)

    def step_cached() -> None:
        train_mode(tnet, cut)
        loss = loss_fn(tnet.forward_from(feats, cut), y)
        opt.zero_grad()
        loss.backward()
        opt.step()

    cached_ms = _median_ms(step_cached, 5, 1)
    full = TSN(net.backbone_name, pretrained=False)
    fopt = torch.optim.Adam(full.parameters(), lr=1e-4)

    def step_full() -> None:
        full.train()
        loss = loss_fn(full(xb), y)
        fopt.zero_grad()
        loss.backward()
        fopt.step()

    full_ms = _median_ms(step_full, 3, 1)
    load1 = os.getloadavg()[0]
    ips_cached = args.batch / (cached_ms / 1000)
    ips_full = args.batch / (full_ms / 1000)
    when = datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC")
    machine = (
        f"{platform.machine()}, {os.cpu_count()} CPUs, torch {torch.__version__}, "
        f"{args.threads} thread(s) inference / {args.train_threads} training, load average {load0:.2f} before / {load1:.2f} after"
    )
    lines = [
        f"`.venv/bin/python benchmarks/bench_tsn.py{' --checkpoint ' + str(args.checkpoint) if args.checkpoint else ''}`",
        "",
        f"machine: {machine}; {when}; checkpoint {model.loaded.path.name} "
        f"({net.backbone_name}, input {size} px, {cut} frozen stages)",
        "",
        "| what | ms | per second | reference (same run) | ratio |",
        "|---|---:|---:|---|---:|",
        f"| predict(), batch 1, end to end (256 px sketch in, projected TreeParams out) | "
        f"{e2e:.1f} | {1000 / e2e:.0f} sketches | Lite0 at 224 px, network only: {ref_ms:.1f} ms | "
        f"{ref_ms / e2e:.2f}x |",
        f"| network only, batch 1, {size} px | {net_ms:.1f} | {1000 / net_ms:.0f} sketches | "
        f"Lite0 at 224 px: {ref_ms:.1f} ms | {ref_ms / net_ms:.2f}x |",
        f"| training step on cached features, batch {args.batch} | {cached_ms / args.batch:.2f} "
        f"per image | {ips_cached:.0f} images | full-network step: {ips_full:.0f} images/s | "
        f"{ips_cached / ips_full:.1f}x |",
        f"| caching (frozen stages forward, once per image and copy) | {cache_ms:.2f} per image | "
        f"{1000 / cache_ms:.0f} images | | |",
        "",
        f"Inference target < 50 ms per sketch at batch 1: {'met' if e2e < 50 else 'NOT met'} "
        f"({e2e:.1f} ms).",
    ]
    text = "\n".join(lines)
    print(text if args.markdown else text.replace("|", " "))


if __name__ == "__main__":
    main()
