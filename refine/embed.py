"""A learned, style-blind shape embedding: the shape distance's second term.

The hand-made shape distance (:mod:`refine.shape`) compares filled silhouettes and
outlines.  Drawing styles change exactly those at the scale that tells two trees of one
species apart (a felt tip's smooth blob, a cloud's scallops, a scribble's ragged fill), so
on its own it puts the same tree drawn two ways closer than two trees drawn one way in only
84-88 % of pairs (``benchmarks/bench_distance.py``).  This module learns a distance that
looks through the styles: a small CNN maps a prepared sketch (its framed ink and filled
silhouette, the two masks :class:`refine.shape.ShapeTarget` already holds) to a point, and
is trained so that the Euclidean distance of two points is the *style-free* shape distance
of the two trees: zero for one tree drawn in two styles, and for two trees of one species
at one view (in any styles) the hand-made distance of their drawings in the renderer's own
style, where it is reliable.  Labels are exact because every style is drawn from the same
tree view (:mod:`render.styles`); the trees are fresh seeds, never those of the benchmarks.

Distilling a distance (rather than learning "is it the very same tree", a triplet loss) is
what the refinement needs: a search can reach a tree's shape but never its random details,
so its objective must fall smoothly as the shape comes closer (measured: a triplet-trained
embedding separated the benchmark's pairs as well but made the refined meshes worse;
RESULTS.md).

- :class:`ShapeEmbedNet`: four strided convolutions (5x5 then 3x3) with batch norm, a 1x1
  reduction and a linear layer on the 8x8 map (position matters: a crown's place above the
  trunk is shape).
- :class:`ShapeEmbedder`: a loaded checkpoint (:func:`load_embedder`); ``embed(target)``.
- :func:`build_pairs` draws the training data (every style of both trees of each pair, at
  one random view); :func:`train_embedder` trains; ``scripts/train_shape_embed.py`` runs
  both (the shipped ``checkpoints/shape_embed.pt``: command in ``checkpoints/README.md``).

``refine.shape`` adds ``EMBED_WEIGHT`` times the embedding distance to the shape distance
when both sketches carry an embedding.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import torch
import torch.nn.functional as F
from torch import nn

from .shape import ShapeTarget

__all__ = [
    "DEFAULT_EMBEDDER",
    "EMBED_SIZE",
    "PAIR_STYLES",
    "PairData",
    "ShapeEmbedNet",
    "ShapeEmbedder",
    "build_pairs",
    "load_embedder",
    "shape_input",
    "train_embedder",
    "true_distances",
]

EMBED_SIZE = 128  # the masks' side the network reads
DEFAULT_EMBEDDER = Path(__file__).resolve().parents[1] / "checkpoints" / "shape_embed.pt"
PAIR_STYLES = ("sg", "pen", "cloud", "scribble", "pencil", "felt")
_FORMAT = "treesketch-shape-embed-2"


class ShapeEmbedNet(nn.Module):
    """(N, 2, 128, 128) masks (ink, filled silhouette) -> (N, dim) points whose Euclidean
    distance is the learned shape distance."""

    def __init__(self, dim: int = 64, widths: tuple[int, ...] = (16, 32, 64, 96)) -> None:
        super().__init__()
        c = (2, *widths)
        self.dim = int(dim)
        self.widths = tuple(int(w) for w in widths)
        self.convs = nn.ModuleList(
            nn.Conv2d(c[i], c[i + 1], 5 if i == 0 else 3, stride=2, padding=2 if i == 0 else 1)
            for i in range(len(widths))
        )
        self.bns = nn.ModuleList(nn.BatchNorm2d(w) for w in widths)
        side = EMBED_SIZE // 2 ** len(widths)
        self.head = nn.Sequential(
            nn.Conv2d(widths[-1], 32, 1), nn.Flatten(), nn.Linear(32 * side * side, dim)
        )

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        for conv, bn in zip(self.convs, self.bns, strict=True):
            x = F.relu(bn(conv(x)))
        return self.head(x)


def shape_input(target: ShapeTarget) -> np.ndarray:
    """The network's input for one sketch prepared at ``EMBED_SIZE``: (2, 128, 128)
    float32, its framed ink and its filled silhouette."""
    if target.size != EMBED_SIZE:
        raise ValueError(
            f"the embedding reads sketches prepared at {EMBED_SIZE} px, got {target.size}"
        )
    fill = target.levels[0].sdf <= 0 if target.levels[0].n else target.ink
    return np.stack([target.ink, fill]).astype(np.float32)


@dataclass(frozen=True)
class ShapeEmbedder:
    """A loaded embedding network (inference only)."""

    net: ShapeEmbedNet
    path: str
    info: dict[str, Any]
    size: int = EMBED_SIZE

    def __repr__(self) -> str:
        return f"ShapeEmbedder({self.path!r}, dim={self.net.dim})"

    @torch.no_grad()
    def embed_many(self, targets: Sequence[ShapeTarget]) -> np.ndarray:
        if not targets:
            return np.zeros((0, self.net.dim), np.float32)
        x = torch.from_numpy(np.stack([shape_input(t) for t in targets]))
        # one thread: the network (about 1 ms a sketch) is too small to share, and torch's
        # thread pool waits for a busy core: beside two busy processes on a 2-core machine
        # 8.9 ms a call on average with two threads, 2.2 ms with one
        # (benchmarks/probes/embed_threads.py, RESULTS.md)
        threads = torch.get_num_threads()
        torch.set_num_threads(1)
        try:
            return self.net(x).numpy().astype(np.float32)
        finally:
            torch.set_num_threads(threads)

    def embed(self, target: ShapeTarget) -> np.ndarray:
        """(dim,) point of one prepared sketch."""
        return self.embed_many([target])[0]


def load_embedder(path: str | os.PathLike[str] | None = None) -> ShapeEmbedder:
    """A checkpoint written by :func:`save_embedder` (default: the shipped one)."""
    p = Path(DEFAULT_EMBEDDER if path is None else path)
    if not p.is_file():
        raise FileNotFoundError(f"shape embedding checkpoint not found: {p}")
    try:
        ck = torch.load(p, map_location="cpu", weights_only=True)
    except Exception as e:  # a truncated or foreign file: say which file
        raise ValueError(f"{p} is not a shape embedding checkpoint ({type(e).__name__})") from e
    if not isinstance(ck, dict) or ck.get("format") != _FORMAT:
        raise ValueError(f"{p} is not a shape embedding checkpoint (format {_FORMAT})")
    net = ShapeEmbedNet(int(ck["dim"]), tuple(ck["widths"]))
    net.load_state_dict(ck["state"])
    net.eval()
    return ShapeEmbedder(net, str(p), dict(ck.get("info", {})))


def save_embedder(net: ShapeEmbedNet, path: str | os.PathLike[str], info: dict[str, Any]) -> None:
    from weberpenn.fileio import atomic_target

    ck = {
        "format": _FORMAT,
        "dim": net.dim,
        "widths": list(net.widths),
        "state": {k: v.detach().cpu() for k, v in net.state_dict().items()},
        "info": info,
    }
    with atomic_target(path) as tmp:
        torch.save(ck, tmp)


# --------------------------------------------------------------------------- training data
@dataclass(frozen=True)
class PairData:
    """Training masks: ``x`` (N, 2, 128, 128) bool; ``meta`` (N, 4) int: pair, tree of the
    pair (0 or 1), style index into ``styles``, species index."""

    x: np.ndarray
    meta: np.ndarray
    styles: tuple[str, ...]

    def save(self, path: str | os.PathLike[str]) -> None:
        from weberpenn.fileio import atomic_target

        with atomic_target(path) as tmp, open(tmp, "wb") as f:
            np.savez_compressed(
                f,
                x=np.packbits(self.x, axis=-1),
                meta=self.meta,
                styles=np.array(self.styles),
            )

    @property
    def pairs(self) -> int:
        return int(self.meta[:, 0].max()) + 1 if len(self.meta) else 0

    def extend(self, more: PairData) -> PairData:
        if more.styles != self.styles:
            raise ValueError(f"styles differ: {self.styles} vs {more.styles}")
        return PairData(
            np.concatenate([self.x, more.x]), np.concatenate([self.meta, more.meta]), self.styles
        )

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> PairData:
        with np.load(path) as d:
            x = np.unpackbits(d["x"], axis=-1)[..., :EMBED_SIZE].astype(bool)
            return cls(x, d["meta"].astype(np.int64), tuple(str(s) for s in d["styles"]))


def _pair_masks(args: tuple[int, int, tuple[str, ...]]) -> tuple[np.ndarray, np.ndarray]:
    """Both trees of pair ``t`` (one species, one random view) in every style."""
    from render.reader import normalise_drawing
    from render.sketch import SketchRenderer
    from render.styles import Silhouettes, draw
    from weberpenn import build_mesh, grow, species

    t, first_seed, styles = args
    name = species.SPECIES[t % len(species.SPECIES)]
    yaw = float(np.random.default_rng([first_seed, t]).uniform(0, 360))
    xs, meta = [], []
    for which in (0, 1):
        seed = first_seed + 2 * t + which
        r = SketchRenderer(build_mesh(grow(species.sample(name, seed)), species=name))
        sil = Silhouettes.from_parts(r.parts(yaw, 256))
        for i, s in enumerate(styles):
            img = normalise_drawing(draw(s, sil, np.random.default_rng([seed, i]), 256), 256)
            xs.append(shape_input(ShapeTarget.from_image(img, EMBED_SIZE)) > 0.5)
            meta.append((t, which, i, species.SPECIES.index(name)))
    return np.stack(xs), np.array(meta, np.int64)


def build_pairs(
    pairs: int,
    first_seed: int = 1_000_000,
    styles: Sequence[str] = PAIR_STYLES,
    workers: int = 1,
    log: Callable[[str], None] | None = None,
    start: int = 0,
) -> PairData:
    """Pairs ``start .. pairs - 1`` of trees (the species in turn), seeds ``first_seed +
    2t`` and ``+ 2t + 1``, each drawn in every style at one random view of the pair (so a
    set can be extended: :meth:`PairData.extend`)."""
    from render.styles import check_styles

    styles = check_styles(tuple(styles))
    jobs = [(t, int(first_seed), styles) for t in range(int(start), int(pairs))]
    if not jobs:
        raise ValueError(f"no pairs to draw: start {start}, pairs {pairs}")
    xs, metas = [], []
    with ProcessPoolExecutor(max_workers=max(1, workers)) as pool:
        for k, (x, m) in enumerate(pool.map(_pair_masks, jobs, chunksize=4)):
            xs.append(x)
            metas.append(m)
            if log is not None and (k + 1) % 25 == 0:
                log(f"{k + 1}/{len(jobs)} pairs drawn")
    return PairData(np.concatenate(xs), np.concatenate(metas), styles)


# --------------------------------------------------------------------------- training
def true_distances(data: PairData) -> np.ndarray:
    """Per pair, how different its two trees' shapes are: the hand-made shape distance
    (``refine.shape``) of their ``sg`` drawings, the renderer's own style, where that
    distance is reliable (same style on both sides)."""
    if "sg" not in data.styles:
        raise ValueError("the training pairs need the sg style (the reference distance)")
    sg = data.styles.index("sg")
    rows = {(int(t), int(w)): r for r, (t, w, s, _) in enumerate(data.meta) if s == sg}
    pairs = sorted({int(t) for t in data.meta[:, 0]})
    out = np.zeros(max(pairs) + 1, np.float32)

    def image(r: int) -> np.ndarray:
        return np.where(data.x[r, 0], 0, 255).astype(np.uint8)

    for t in pairs:
        a = ShapeTarget.from_image(image(rows[(t, 0)]), EMBED_SIZE)
        b = ShapeTarget.from_image(image(rows[(t, 1)]), EMBED_SIZE)
        out[t] = a.distance(b)
    return out


def train_embedder(
    data: PairData,
    epochs: int = 12,
    hold_out: Sequence[str] = (),
    batch: int = 64,
    lr: float = 2e-3,
    margin: float = 0.3,
    seed: int = 0,
    log: Callable[[str], None] | None = None,
) -> ShapeEmbedNet:
    """Distil a style-free shape distance into the embedding's Euclidean distance:

    - the same tree in two styles: distance 0 (squared error);
    - the pair's other tree (same species and view) in any style: the two trees' shape
      distance in the renderer's style (:func:`true_distances`), squared error, so the
      embedding's distance means "how different are the trees", not "is it the very
      same tree" (a search cannot reach a tree's random details, only its shape);
    - trees of other species in the batch: at least ``margin`` apart (squared hinge).

    Styles in ``hold_out`` are never seen (leave-one-style-out).  An epoch is 30 samples
    per pair; one-cycle schedule; a shift of up to 2 pixels as augmentation."""
    styles = [i for i, s in enumerate(data.styles) if s not in set(hold_out)]
    if len(styles) < 2:
        raise ValueError("training needs at least two styles that are not held out")
    torch.manual_seed(seed)
    rng = np.random.default_rng(seed)
    target = torch.from_numpy(true_distances(data))
    index = {(int(t), int(w), int(s)): r for r, (t, w, s, _) in enumerate(data.meta)}
    kind = {int(t): int(k) for t, _, _, k in data.meta}
    pairs = sorted(kind)
    x_all = torch.from_numpy(data.x.astype(np.float32))
    net = ShapeEmbedNet()
    opt = torch.optim.AdamW(net.parameters(), lr, weight_decay=1e-4)
    steps = max(1, epochs * len(pairs) * 30 // batch)
    sched = torch.optim.lr_scheduler.OneCycleLR(opt, lr, total_steps=steps)

    def shifted(rows: list[int]) -> torch.Tensor:
        dy, dx = (int(v) for v in rng.integers(-2, 3, 2))
        return torch.roll(x_all[rows], (dy, dx), (2, 3))

    t0 = time.perf_counter()
    net.train()
    for step in range(steps):
        a, p, n, ts = [], [], [], []
        for _ in range(batch):
            t = pairs[int(rng.integers(len(pairs)))]
            sx, sy = rng.choice(styles, 2, replace=False)
            w = int(rng.integers(2))
            a.append(index[(t, w, int(sx))])
            p.append(index[(t, w, int(sy))])
            n.append(index[(t, 1 - w, int(rng.choice(styles)))])
            ts.append(t)
        ea, ep, en = net(shifted(a)), net(shifted(p)), net(shifted(n))
        same = ((ea - ep) ** 2).sum(1)
        other = ((ea - en) ** 2).sum(1).clamp_min(1e-9).sqrt()
        spec = torch.tensor([kind[t] for t in ts])
        apart = (spec[:, None] != spec[None, :]).float()
        far = F.relu(margin - torch.cdist(ea, ep)) ** 2 * apart
        loss = same.mean() + ((other - target[ts]) ** 2).mean() + 0.5 * far.mean()
        opt.zero_grad()
        loss.backward()
        opt.step()
        sched.step()
        if log is not None and (step % 200 == 0 or step == steps - 1):
            log(
                f"step {step + 1}/{steps} loss {loss.item():.5f} same {same.mean().item():.5f} "
                f"other err {(other - target[ts]).abs().mean().item():.4f} "
                f"{time.perf_counter() - t0:.0f} s"
            )
    net.eval()
    return net
