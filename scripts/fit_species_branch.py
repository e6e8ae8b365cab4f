"""Fit a TSN checkpoint's species branch: a copy of the network's last stages for the species.

    .venv/bin/python scripts/fit_species_branch.py cache --data DS_PEOPLE --cache DIR \
        [--doodles 300] [--styled 330] [--start 12]              # 20 min on two cores
    .venv/bin/python scripts/fit_species_branch.py train --cache DIR \
        [--epochs 4] [--lr 3e-4] --out branch.pt                   # 7 min on two cores
    .venv/bin/python scripts/fit_species_branch.py install --cache DIR --branch branch.pt \
        [--checkpoint checkpoints/tsn_lite0.pt] [--out PT]         # 30 s

The network's six heads read pooled features trained for the tree's values, not for telling
a lollipop doodle from a birch.  A species branch (``tsn.model.SpeciesBranch``) is a second
copy of the network's stages from ``--start`` on (12: the start of the 6 x 6 stages of
EfficientNet-Lite0), which reads the same map of that stage and is trained, with a linear
layer on top, on species labels only; the network, its heads and its tree detector stay as
they are.

``cache`` runs the frozen first stages once over the drawings the species classifier is
fitted on (``scripts/fit_species_classifier.py``'s: hand-style doodles from seed 1000,
trees in the renderer's styles from seed 4000, the dataset's training split), its held-out
sets (doodle seeds from 5000, styled trees from 7000, the validation split) and the test
sets (the dataset's test split by style, the hand-style doodles of seeds 0-39 that
``bench_species.py doodles`` scores, ``examples/hand``), each drawing and its mirror, and
keeps the maps (float16) in ``--cache``.  ``train`` starts the linear layer from the
checkpoint's classifier (so epoch 0 is its accuracy), trains the copy with AdamW and a
one-cycle schedule for ``--epochs`` (batch norms fixed, label smoothing 0.05, each drawing
or its mirror at random), prints the accuracy on every held-out and test set after each
epoch (the drawings as given, as at inference) and saves the branch.  ``install`` writes the
checkpoint with the branch and, as its species classifier, the trained linear layer on the
branch's features with its temperature fitted on the held-out sets (the test sets are not
used).  Measured in ``benchmarks/RESULTS.md``, "A species branch".
"""

from __future__ import annotations

import argparse
import copy
import json
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import torch
from torch import nn

from eval.doodles import TREE_SPECIES, tree_doodle
from eval.fitting import styled_trees
from render.dataset import read_manifest, row_style
from render.reader import SketchError
from treesketch.pipeline import load_sketch, prepare_input
from tsn import data as tdata
from tsn.checkpoint import Loaded, load_checkpoint, save_loaded
from tsn.model import SpeciesBranch
from tsn.species_id import SpeciesClassifier

ROOT = Path(__file__).resolve().parents[1]
CHECKPOINT = ROOT / "checkpoints" / "tsn_lite0.pt"
FIT = ("doodle_fit", "styled_fit", "ds_train")
HELD = ("doodle_held", "styled_held", "ds_val")


@torch.no_grad()
def _maps(loaded: Loaded, start: int, images: list[Any]) -> tuple[np.ndarray, list[bool]]:
    """``(N, 2, C, H, W)`` float16 maps after ``start`` stages of each accepted drawing and
    its mirror; which drawings were accepted (a blank page is refused, as in the pipeline)."""
    xs, kept = [], []
    for im in images:
        try:
            xs.append(tdata.preprocess(prepare_input(load_sketch(im)), loaded.size))
            kept.append(True)
        except SketchError:
            kept.append(False)
    net, out = loaded.model.eval(), []
    for i in range(0, len(xs), 64):
        x = torch.from_numpy(np.stack(xs[i : i + 64]))[:, None]
        f = net.features(torch.cat([x, torch.flip(x, dims=[3])]), start)
        n = len(f) // 2
        out.append(torch.stack([f[:n], f[n:]], 1).half().numpy())
    return np.concatenate(out), kept


def cache(args: argparse.Namespace) -> None:
    loaded = load_checkpoint(args.checkpoint)
    args.cache.mkdir(parents=True, exist_ok=True)
    names = list(TREE_SPECIES)
    hand_dir = ROOT / "examples" / "hand"
    people = json.loads((hand_dir / "species.json").read_text(encoding="utf-8"))
    hand = sorted(people)

    def doodles(seed0: int, n: int) -> tuple[list, list]:
        return [tree_doodle(s, seed0 + k) for s in names for k in range(n)], [
            s for s in names for _ in range(n)
        ]

    def split(name: str) -> tuple[list, list, list]:
        rows = read_manifest(args.data, split=name)
        if not rows:
            raise SystemExit(f"error: {args.data} has no {name!r} split")
        return (
            [str(args.data / r["sketch"]) for r in rows],
            [r["species"] for r in rows],
            [row_style(r) for r in rows],
        )

    held_doodles = max(1, round(args.doodles * 0.4))
    sets: dict[str, Any] = {
        "hand": lambda: (
            [hand_dir / f"{k}.png" for k in hand],
            [people[k]["species"] for k in hand],
            [json.dumps(people[k]["also"]) for k in hand],
        ),
        "doodle_bench": lambda: doodles(0, 40),
        "ds_test": lambda: split("test"),
        "ds_val": lambda: split("val"),
        "ds_train": lambda: split("train"),
        "doodle_held": lambda: doodles(5000, held_doodles),
        "styled_held": lambda: styled_trees(7000, max(1, round(args.styled * 0.4))),
        "styled_fit": lambda: styled_trees(4000, args.styled),
        "doodle_fit": lambda: doodles(1000, args.doodles),
    }
    for tag, make in sets.items():
        t0 = time.perf_counter()
        images, labels, *extra = make()
        maps, kept = _maps(loaded, args.start, images)
        keep = np.asarray(kept)
        data = {"maps": maps, "species": np.asarray(labels)[keep], "start": args.start}
        if extra:
            data["extra"] = np.asarray(extra[0])[keep]
        np.savez(args.cache / f"{tag}.npz", **data)
        print(f"{tag}: {len(maps)} drawings, {time.perf_counter() - t0:.0f} s", flush=True)


class Branch(nn.Module):
    """A copy of the backbone's stages from ``start`` on, pooled, and a linear layer
    started from the checkpoint's classifier (its standardisation and temperature folded
    in).  A checkpoint that has a branch already goes on from that branch and the
    classifier's columns on its features; else the copy starts as the network's own
    stages and the classifier must read the heads' features."""

    def __init__(self, loaded: Loaded, start: int) -> None:
        super().__init__()
        clf = loaded.species_id.classifier
        nf = loaded.model.backbone.out_features
        old = loaded.species_branch
        cols = slice(0, nf) if old is None else slice(nf, 2 * nf)
        if clf is None or clf.reads != "features" or clf.weight.shape[1] != cols.stop:
            raise SystemExit("error: the checkpoint has no species classifier on pooled features")
        if old is not None and old.start != start:
            raise SystemExit(
                f"error: the checkpoint's branch starts at stage {old.start}, not {start}"
            )
        self.start = start
        self.backbone = copy.deepcopy(loaded.model.backbone if old is None else old.backbone)
        mean, std, weight = clf.mean[cols], clf.std[cols], clf.weight[:, cols]
        w = weight / std[None, :] / clf.temperature
        b = (clf.bias - (mean / std) @ weight.T) / clf.temperature
        self.linear = nn.Linear(w.shape[1], w.shape[0])
        self.linear.weight.data = torch.from_numpy(w).float()
        self.linear.bias.data = torch.from_numpy(b).float()
        for p in self.backbone.parameters():
            p.requires_grad = False
        for i in range(start, self.backbone.n_stages):
            for mod in self.backbone.stage_modules(i):
                for p in mod.parameters():
                    p.requires_grad = True

    def forward(self, maps: torch.Tensor) -> torch.Tensor:
        """``(B, C, H, W)`` maps of drawings -> ``(B, k)`` logits."""
        f = self.backbone.run_stages(maps, self.start, self.backbone.n_stages)
        return self.linear(f.mean(dim=(2, 3)))


def _load(cache_dir: Path, tag: str) -> dict[str, np.ndarray]:
    path = cache_dir / f"{tag}.npz"
    if not path.is_file():
        raise SystemExit(f"error: {path} is missing: run the cache step first")
    return dict(np.load(path))


@torch.no_grad()
def _predict(net: Branch, names: list[str], maps: np.ndarray) -> np.ndarray:
    net.eval()
    out = [
        net(torch.from_numpy(maps[i : i + 256, 0]).float()).argmax(1).numpy()
        for i in range(0, len(maps), 256)
    ]
    return np.asarray(names)[np.concatenate(out)]


def _score(net: Branch, names: list[str], sets: dict[str, dict]) -> dict[str, str | int]:
    out: dict[str, str | int] = {}
    test = sets["ds_test"]
    ok = _predict(net, names, test["maps"]) == test["species"]
    for style in sorted(set(test["extra"])):
        sel = test["extra"] == style
        out[f"test {style}"] = f"{ok[sel].mean():.1%} ({int((~ok[sel]).sum())} wrong)"
    bench = sets["doodle_bench"]
    out["hand-style doodles"] = (
        f"{(_predict(net, names, bench['maps']) == bench['species']).mean():.1%}"
    )
    hand = sets["hand"]
    pred = _predict(net, names, hand["maps"])
    out["examples/hand"] = sum(
        p == s or p in json.loads(a)
        for p, s, a in zip(pred, hand["species"], hand["extra"], strict=True)
    )
    for tag in HELD:
        d = sets[tag]
        out[tag] = f"{(_predict(net, names, d['maps']) == d['species']).mean():.1%}"
    return out


def train(args: argparse.Namespace) -> None:
    torch.manual_seed(args.seed)
    loaded = load_checkpoint(args.checkpoint)
    sets = {t: _load(args.cache, t) for t in (*FIT, *HELD, "ds_test", "doodle_bench", "hand")}
    start = int(sets["hand"]["start"])
    net = Branch(loaded, start)
    names = list(loaded.species_id.classifier.species)  # type: ignore[union-attr]
    print("epoch 0 (the shipped classifier):", json.dumps(_score(net, names, sets)), flush=True)
    maps = np.concatenate([sets[t]["maps"] for t in FIT])
    labels = torch.tensor([names.index(s) for t in FIT for s in sets[t]["species"]])
    trained = [p for p in net.backbone.parameters() if p.requires_grad]
    opt = torch.optim.AdamW(
        [
            {"params": trained, "lr": args.lr},
            {"params": net.linear.parameters(), "lr": 3 * args.lr},
        ],
        weight_decay=1e-4,
    )
    per_epoch = max(1, len(maps) // args.batch)
    sched = torch.optim.lr_scheduler.OneCycleLR(
        opt, max_lr=[args.lr, 3 * args.lr], total_steps=args.epochs * per_epoch, pct_start=0.1
    )
    for epoch in range(1, args.epochs + 1):
        net.train()
        net.backbone.eval()  # the batch norms keep the statistics the network was trained with
        rng = np.random.default_rng(args.seed + epoch)
        order = rng.permutation(len(maps))
        t0, total = time.perf_counter(), 0.0
        for i in range(per_epoch):
            idx = order[i * args.batch : (i + 1) * args.batch]
            # each drawing or its mirror at random: a drawing faces either way
            side = rng.integers(0, 2, len(idx))
            logits = net(torch.from_numpy(maps[idx, side]).float())
            loss = nn.functional.cross_entropy(logits, labels[idx], label_smoothing=0.05)
            opt.zero_grad()
            loss.backward()
            opt.step()
            sched.step()
            total += float(loss.detach())
        print(
            f"epoch {epoch}: loss {total / per_epoch:.4f}, {time.perf_counter() - t0:.0f} s;",
            json.dumps(_score(net, names, sets)),
            flush=True,
        )
    trained = {k: getattr(args, k) for k in ("epochs", "lr", "batch", "seed")}
    saved = {"start": start, "species": names, "state": net.state_dict(), "trained": trained}
    torch.save(saved, args.out)
    print(f"wrote {args.out}")


@torch.no_grad()
def _features(loaded: Loaded, branch: SpeciesBranch, maps: np.ndarray) -> np.ndarray:
    """``(N, m)`` features as ``tsn.predict`` makes them from cached maps: the heads'
    pooled features (the mean over each drawing and its mirror), then the branch's of the
    drawing."""
    out = []
    for i in range(0, len(maps), 128):
        pairs = torch.from_numpy(maps[i : i + 128]).float()
        heads = loaded.model.pool(pairs.flatten(0, 1), branch.start)
        heads = heads.view(len(pairs), 2, -1).mean(dim=1)
        out.append(torch.cat([heads, branch(pairs[:, 0])], dim=1).numpy())
    return np.concatenate(out).astype(np.float64)


def install(args: argparse.Namespace) -> None:
    t0 = time.perf_counter()
    loaded = load_checkpoint(args.checkpoint)
    saved = torch.load(args.branch, map_location="cpu", weights_only=True)
    state = saved["state"]
    branch = SpeciesBranch(loaded.model.backbone_name, int(saved["start"])).eval()
    try:
        branch.load_stage_state({k: state[k] for k in branch.stage_state()})
    except KeyError as e:
        raise SystemExit(f"error: {args.branch} lacks the branch weight {e}") from None
    names = tuple(saved["species"])
    w = state["linear.weight"].double().numpy()
    nf = loaded.model.backbone.out_features
    m = nf + w.shape[1]
    # the classifier reads the whole feature vector; the heads' part carries no weight
    clf = SpeciesClassifier(
        names, np.zeros(m), np.ones(m), np.hstack([np.zeros((len(names), nf)), w]),
        state["linear.bias"].double().numpy(), 1.0, loaded.normaliser.scale, "features",
    )  # fmt: skip
    held = {t: _load(args.cache, t) for t in HELD}
    if any(int(d["start"]) != branch.start for d in held.values()):
        raise SystemExit(f"error: {args.cache} holds maps of another stage than {branch.start}")
    feats = {t: _features(loaded, branch, d["maps"]) for t, d in held.items()}
    clf = clf.calibrated(
        np.concatenate(list(feats.values())), [s for d in held.values() for s in d["species"]]
    )
    accuracy = {
        t: float(
            np.mean(np.asarray(names)[clf.probabilities_many(x).argmax(1)] == held[t]["species"])
        )
        for t, x in feats.items()
    }
    info = {
        **loaded.info,
        "classifier": {
            "reads": "features (the species branch's)",
            "held_out_accuracy": accuracy,
            "temperature": clf.temperature,
        },
        "species_branch": {
            "start": branch.start,
            "trained": saved.get("trained", {}),
            "command": " ".join(sys.argv),
        },
    }
    out = args.out or args.checkpoint
    save_loaded(
        loaded, out, info, species_id=loaded.species_id.with_classifier(clf), species_branch=branch
    )
    for t, acc in accuracy.items():
        print(f"held out, {t}: species right {acc:.1%} ({len(held[t]['species'])} drawings)")
    print(f"temperature {clf.temperature:.2f}; wrote {out} ({time.perf_counter() - t0:.0f} s)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--checkpoint", type=Path, default=CHECKPOINT)
    sub = ap.add_subparsers(dest="step", required=True)
    c = sub.add_parser("cache", help="run the frozen first stages once and keep their maps")
    c.add_argument("--data", type=Path, required=True, help="the network's training dataset")
    c.add_argument("--cache", type=Path, required=True)
    c.add_argument("--doodles", type=int, default=300, help="hand-style doodles per species")
    c.add_argument("--styled", type=int, default=330, help="trees in the renderer's styles")
    c.add_argument("--start", type=int, default=12, help="the first stage the branch copies")
    t = sub.add_parser("train", help="train the branch on the cached maps, score each epoch")
    t.add_argument("--cache", type=Path, required=True)
    t.add_argument("--epochs", type=int, default=4)
    t.add_argument("--lr", type=float, default=3e-4)
    t.add_argument("--batch", type=int, default=64)
    t.add_argument("--seed", type=int, default=0)
    t.add_argument("--out", type=Path, required=True, help="save the trained branch here")
    i = sub.add_parser("install", help="write the checkpoint with the branch and its classifier")
    i.add_argument("--cache", type=Path, required=True, help="for the held-out drawings' maps")
    i.add_argument("--branch", type=Path, required=True, help="what train saved")
    i.add_argument("--out", type=Path, default=None, help="default: --checkpoint")
    args = ap.parse_args()
    {"cache": cache, "train": train, "install": install}[args.step](args)


if __name__ == "__main__":
    main()
