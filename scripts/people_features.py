"""The network's readings of people's drawings, kept on disk for fitting and measuring.

    .venv/bin/python scripts/people_features.py --out DIR [--fit-per-kind 600] \
        [--held-per-kind 400] [--quickdraw-fit 2000] [--checkpoint checkpoints/tsn_lite0.pt]

Reads ``../shared/people_doodles`` (``eval.people``), puts every drawing through the
pipeline's own reader and preparation, and writes ``DIR/people_<part>.npz`` for the fit and
held parts: ``features`` (N, m) as ``tsn.predict`` makes them (the heads' pooled features,
then the species branch's), ``outputs`` (N, 4, 62), and the drawings' ``source``, ``kind``
and ``key``.  At most ``--*-per-kind`` drawings of each (source, kind) are read (the
Quick, Draw! folders hold ~2,000 each).  Work is saved every chunk, so a stopped run
resumes where it stopped.  A drawing the reader refuses (a blank page) is left out, as the
pipeline would refuse it.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from eval.fitting import read_drawings
from eval.people import PeopleDrawing, people_drawings
from treesketch.pipeline import load_sketch, prepare_input
from tsn.predict import load_model

CHUNK = 256


def prepared(image: object) -> np.ndarray:
    return prepare_input(load_sketch(image))


def read_part(model: object, drawings: list[PeopleDrawing], path: Path) -> None:
    """Features of ``drawings`` into ``path``, resuming from its chunk files."""
    chunks = []
    t0 = time.perf_counter()
    for i in range(0, len(drawings), CHUNK):
        part = path.with_suffix(f".{i // CHUNK:04d}.npz")
        batch = drawings[i : i + CHUNK]
        if not part.exists():
            mats, feats, kept = read_drawings(model, [d.image() for d in batch], prepared)
            kept_d = [d for d, k in zip(batch, kept, strict=True) if k]
            np.savez(
                part,
                features=feats.astype(np.float32),
                outputs=mats.astype(np.float32),
                source=np.array([d.source for d in kept_d]),
                kind=np.array([d.kind for d in kept_d]),
                key=np.array([d.key for d in kept_d]),
            )
            done = i + len(batch)
            print(
                f"{path.name}: {done}/{len(drawings)} ({time.perf_counter() - t0:.0f} s)",
                flush=True,
            )
        chunks.append(part)
    loaded = [dict(np.load(p)) for p in chunks]
    np.savez(path, **{k: np.concatenate([c[k] for c in loaded]) for k in loaded[0]})
    for p in chunks:
        p.unlink()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True)
    ap.add_argument("--checkpoint", default=None)
    ap.add_argument("--fit-per-kind", type=int, default=600)
    ap.add_argument("--held-per-kind", type=int, default=400)
    ap.add_argument("--quickdraw-fit", type=int, default=2000)  # all of the fit part
    args = ap.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    model = load_model(args.checkpoint)
    for part, n in (("held", args.held_per_kind), ("fit", args.fit_per_kind)):
        path = out / f"people_{part}.npz"
        if path.exists():
            print(f"{path} exists; kept")
            continue
        drawings = people_drawings(part=part, sources=("strokes", "mouse224"), per_kind=n)
        quick = args.quickdraw_fit if part == "fit" else n
        drawings += people_drawings(part=part, sources=("quickdraw28",), per_kind=quick)
        read_part(model, drawings, path)


if __name__ == "__main__":
    main()
