"""Train the style-blind shape embedding (``refine.embed``) and write its checkpoint.

    .venv/bin/python scripts/train_shape_embed.py --data /work/data/embed/pairs.npz \
        --pairs 500 --workers 2 --epochs 20 --out checkpoints/shape_embed.pt

The training pairs are drawn once and kept in ``--data`` (reused when it exists and holds
as many pairs); ``--hold-out STYLE`` trains without a style (leave-one-style-out, see
``benchmarks/bench_distance.py --embedder``).  The log goes to stdout.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import torch

from refine.embed import PAIR_STYLES, PairData, build_pairs, save_embedder, train_embedder


def log(msg: str) -> None:
    print(f"{time.strftime('%H:%M:%S')} {msg}", flush=True)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--data", type=Path, required=True, help="training pairs (.npz), made if absent"
    )
    ap.add_argument("--pairs", type=int, default=500)
    ap.add_argument("--first-seed", type=int, default=1_000_000)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--epochs", type=int, default=20)
    ap.add_argument("--hold-out", default="", help="a style never shown in training")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", type=Path, required=True)
    args = ap.parse_args(argv)
    if args.hold_out and args.hold_out not in PAIR_STYLES:
        ap.error(f"--hold-out must be one of {', '.join(PAIR_STYLES)}")
    torch.set_num_threads(args.threads)
    data = PairData.load(args.data) if args.data.is_file() else None
    have = 0 if data is None else data.pairs
    if have < args.pairs:  # draw the missing pairs only: the first ``have`` are the same
        log(f"drawing pairs {have}..{args.pairs - 1} in {len(PAIR_STYLES)} styles -> {args.data}")
        more = build_pairs(args.pairs, args.first_seed, PAIR_STYLES, args.workers, log, have)
        data = more if data is None else data.extend(more)
        args.data.parent.mkdir(parents=True, exist_ok=True)
        data.save(args.data)
    elif have > args.pairs:
        keep = data.meta[:, 0] < args.pairs
        data = PairData(data.x[keep], data.meta[keep], data.styles)
    t0 = time.perf_counter()
    hold = (args.hold_out,) if args.hold_out else ()
    net = train_embedder(data, args.epochs, hold, seed=args.seed, log=log)
    info = {
        "pairs": data.pairs,
        "first_seed": args.first_seed,
        "styles": [s for s in data.styles if s not in hold],
        "held_out": list(hold),
        "epochs": args.epochs,
        "seed": args.seed,
        "train_seconds": round(time.perf_counter() - t0, 1),
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    save_embedder(net, args.out, info)
    log(f"wrote {args.out} {info}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
