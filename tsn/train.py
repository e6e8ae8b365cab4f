"""Training TSN on a dataset made by ``render.dataset`` (fast on a few CPU cores).

Recipe (``train(TrainConfig(...))`` or ``treesketch train``):

1. Read the ``train`` and ``val`` splits; encode every tree's dictionary (``tsn.encoding``);
   fit the max-abs :class:`~tsn.encoding.Normaliser` and the species identifier
   (Algorithm 1) on the training trees only.
2. Freeze the first ``cut`` stages of the backbone and run them ONCE over every training
   sketch and ``copies`` augmented copies of it (``tsn.data.augment``: affine jitter, stroke
   thickness, line breaks, missing crown parts) and over the clean validation sketches;
   the feature maps are kept as fp16 (and on disk in the work folder, so a resumed run
   does not recompute them).  ``cut=0`` trains the whole network on cached input images.
3. Train the remaining stages and the six heads with Adam (cosine learning-rate decay),
   loss = sum over heads of the MSE on normalised targets; each epoch visits every
   training sketch once, in one of its cached versions chosen at random.
4. After every epoch: validation loss and 1-RMSE per head on the ``val`` split (held-out
   trees), a row in ``log.csv``, ``loss.png``, the full training state (``state.pt``, for
   ``--resume``) and, when the validation 1-RMSE improved, the checkpoint at ``out``.
   Every file is written to a temporary name and renamed.
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
import math
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import torch

from render.reader import SketchError, normalise_drawing, read_sketch
from weberpenn.fileio import atomic_write
from weberpenn.params import HEADS, TreeParams

from . import data as tdata
from . import encoding
from .checkpoint import Loaded, atomic_torch_save, save_checkpoint
from .metrics import one_minus_rmse
from .model import BACKBONES, TSN, ModelError, SpeciesBranch
from .species_id import SpeciesClassifier, SpeciesIdentifier


class TrainError(ValueError):
    """Bad training settings or an unusable dataset."""


@dataclass
class TrainConfig:
    data: str
    out: str
    backbone: str = "lite0"
    size: int = 128
    epochs: int = 30
    batch: int = 64
    lr: float = 1e-3
    copies: int = 3  # augmented copies per training sketch (plus the clean one)
    cut: int | None = None  # frozen stages; None = the backbone's default
    seed: int = 0
    work: str | None = None  # cache, state, log; default: OUT with suffix .work
    threads: int | None = None
    max_sketches: int | None = None  # per split, for quick tests
    resume: bool = False
    pretrained: bool = True
    loss: str = "mse"  # "mse": sum of per-head MSE (paper); "rmse": sum of per-head RMSE
    more_data: tuple[str, ...] = ()  # datasets whose every split is added to the training set
    styles: tuple[str, ...] | None = None  # drawing styles kept (train and val); None = all
    init: str | None = None  # checkpoint to fine-tune from (its weights and normaliser)
    cache: str | None = None  # folder of the feature caches; default: the work folder
    # every sketch (and augmented copy) goes through the drawing normaliser first, as
    # predict and the service feed the network: training sees what inference sees
    normalise: bool = True
    extra: dict[str, Any] = field(default_factory=dict)

    def check(self) -> None:
        if self.backbone not in BACKBONES:
            raise TrainError(
                f"unknown backbone {self.backbone!r}; choose one of {', '.join(BACKBONES)}"
            )
        for name, lo, hi in (("size", 32, 1024), ("epochs", 1, 100_000), ("batch", 1, 4096)):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or not lo <= v <= hi:
                raise TrainError(f"--{name} must be an integer in [{lo}, {hi}], got {v!r}")
        if not 0 <= self.copies <= 64:
            raise TrainError(f"--copies must be in [0, 64], got {self.copies}")
        if not (self.lr > 0 and math.isfinite(self.lr)):
            raise TrainError(f"--lr must be a positive number, got {self.lr}")
        if self.loss not in LOSSES:
            raise TrainError(f"--loss must be one of {', '.join(LOSSES)}, got {self.loss!r}")
        if self.size % 32:
            raise TrainError(f"--size must be a multiple of 32, got {self.size}")
        if self.styles is not None:
            from render.styles import check_styles

            try:
                self.styles = check_styles(self.styles)
            except ValueError as e:
                raise TrainError(f"--styles: {e}") from None
        if self.init is not None and not Path(self.init).is_file():
            raise TrainError(f"--init {self.init}: no such checkpoint file")

    @property
    def work_dir(self) -> Path:
        return Path(self.work) if self.work else Path(self.out).with_suffix(".work")

    @property
    def cache_dir(self) -> Path:
        """Caches hold every sketch of a split (whatever ``styles`` keeps), so runs that
        keep other styles of the same dataset can share them."""
        return Path(self.cache) if self.cache else self.work_dir


# ----------------------------------------------------------------------------- data
@dataclass
class Split:
    images: list[np.ndarray]  # uint8 sketches
    mats: np.ndarray  # (N, 4, 62) un-normalised targets
    species: list[str]
    tree_ids: list[str]
    tree_seeds: list[int] = field(default_factory=list)
    styles: list[str] = field(default_factory=list)  # drawing style of each sketch

    def keep(self, styles: tuple[str, ...] | None) -> np.ndarray:
        """Indices of the sketches drawn in ``styles`` (all when ``None``)."""
        if styles is None:
            return np.arange(len(self.images))
        return np.flatnonzero([s in styles for s in self.styles])

    def subset(self, idx: np.ndarray) -> Split:
        return Split(
            [self.images[i] for i in idx],
            self.mats[idx],
            [self.species[i] for i in idx],
            [self.tree_ids[i] for i in idx],
            [self.tree_seeds[i] for i in idx],
            [self.styles[i] for i in idx],
        )

    @staticmethod
    def concat(parts: list[Split]) -> Split:
        return Split(
            [im for p in parts for im in p.images],
            np.concatenate([p.mats for p in parts]),
            [s for p in parts for s in p.species],
            [t for p in parts for t in p.tree_ids],
            [t for p in parts for t in p.tree_seeds],
            [s for p in parts for s in p.styles],
        )


def load_split(
    data: Path,
    split: str | None,
    limit: int | None = None,
    styles: tuple[str, ...] | None = None,
) -> Split:
    """The sketches and targets of ``split`` of a dataset (``None``: every split), only
    those drawn in ``styles`` when given."""
    from render.dataset import DatasetError, read_manifest, row_style

    try:
        rows = read_manifest(data, split=split, styles=styles)
    except DatasetError as e:
        raise TrainError(str(e)) from None
    if limit is not None:
        rows = rows[:limit]
    if not rows:
        what = "it has no sketches" if split is None else f"the {split!r} split is empty"
        if styles is not None:
            what += f" in the styles {', '.join(styles)}"
        raise TrainError(f"{data}: {what}")
    images, mats, cache = [], [], {}
    for r in rows:
        images.append(read_sketch(data / r["sketch"]))
        if r["params"] not in cache:
            p = TreeParams(json.loads((data / r["params"]).read_text(encoding="utf-8")))
            cache[r["params"]] = encoding.encode(p)
        mats.append(cache[r["params"]])
    return Split(
        images,
        np.stack(mats),
        [r["species"] for r in rows],
        [r["tree_id"] for r in rows],
        [int(r["tree_seed"]) for r in rows],
        [row_style(r) for r in rows],
    )


def load_more(cfg: TrainConfig, data: Path) -> list[tuple[Path, Split]]:
    """The ``more_data`` datasets (every split), refused where one shares a tree (same
    ``tree_seed``) with the validation or test split of ``data``: that would leak."""
    from render.dataset import read_manifest

    if not cfg.more_data:
        return []
    held = {int(r["tree_seed"]) for r in read_manifest(data) if r["split"] in ("val", "test")}
    out = []
    for d in cfg.more_data:
        path = Path(d)
        if not path.is_dir():
            raise TrainError(f"--more-data {path}: no such dataset folder")
        if path.resolve() == data.resolve():
            raise TrainError(f"--more-data {path} is the --data dataset itself")
        part = load_split(path, None, cfg.max_sketches)
        shared = held.intersection(part.tree_seeds)
        if shared:
            raise TrainError(
                f"--more-data {path}: {len(shared)} of its trees are validation/test trees of "
                f"{data} (same tree_seed; build it with another --seed)"
            )
        out.append((path, part))
    return out


def fit_species_id(split: Split, normaliser: encoding.Normaliser) -> SpeciesIdentifier:
    by: dict[str, list[np.ndarray]] = {}
    for m, s in zip(split.mats, split.species, strict=True):
        by.setdefault(s, []).append(m)
    return SpeciesIdentifier.fit({s: np.stack(v) for s, v in by.items()}, normaliser.scale)


# ----------------------------------------------------------------------------- cache
def frozen_digest(model: TSN, cut: int) -> str:
    """A digest of the weights of the first ``cut`` stages: the cached features are a
    function of these (not of where the init checkpoint lives: a renamed checkpoint keeps
    its cache, one overwritten with other weights does not)."""
    h = hashlib.sha1()
    for i, m in enumerate(model.frozen_modules(cut)):
        for name, t in sorted(m.state_dict().items()):
            h.update(f"{i}.{name}:{tuple(t.shape)}:{t.dtype}".encode())
            h.update(t.detach().cpu().contiguous().numpy().tobytes())
    return h.hexdigest()


def cache_key(
    cfg: TrainConfig, cut: int, split: Split, tag: str, data: str | None, frozen: str
) -> str:
    """Name of a feature cache: the data, its split, the input recipe and ``frozen``
    (:func:`frozen_digest` of the network that computes the features)."""
    h = hashlib.sha1()
    h.update(
        json.dumps(
            [tag, cfg.backbone, cfg.size, cut, cfg.copies, cfg.seed, cfg.pretrained]
            + (["normalised", normaliser_digest()] if cfg.normalise else []),
            sort_keys=True,
        ).encode()
    )
    h.update(str(Path(data or cfg.data).resolve()).encode())
    h.update(("frozen:" + frozen).encode())
    h.update("|".join(split.tree_ids).encode())
    return h.hexdigest()[:16]


def normaliser_digest() -> str:
    """Fingerprint of the drawing normaliser's code (``render.reader``): features cached
    from normalised sketches are recomputed when it changes, never silently reused."""
    import inspect

    from render import reader

    return hashlib.sha1(inspect.getsource(reader).encode()).hexdigest()[:12]


def normalised(img: np.ndarray) -> np.ndarray:
    """``render.reader.normalise_drawing`` of a training sketch; one the normaliser refuses
    (an augmented copy left nearly blank) is kept as it is."""
    try:
        return normalise_drawing(img)
    except SketchError:
        return img


@torch.no_grad()
def compute_features(
    model: TSN, imgs: list[np.ndarray], cut: int, size: int, device: str, batch: int = 64
) -> torch.Tensor:
    """Output of the first ``cut`` stages (fp16, CPU); ``cut=0``: the prepared grey input."""
    out = []
    model.eval()
    for s in range(0, len(imgs), batch):
        x = torch.from_numpy(np.stack([tdata.preprocess(i, size) for i in imgs[s : s + batch]]))
        x = x[:, None]
        f = x if cut == 0 else model.features(x.to(device), cut).cpu()
        out.append(f.to(torch.float16))
    return torch.cat(out)


def build_cache(
    model: TSN,
    split: Split,
    cut: int,
    cfg: TrainConfig,
    device: str,
    copies: int,
    tag: str,
    log: Callable[[str], None],
    data: str | None = None,
    part: int = 0,
) -> torch.Tensor:
    """``(copies + 1, N, ...)`` fp16: version 0 clean, 1.. augmented (seeded per image;
    ``part`` > 0 for the ``more_data`` datasets, so their augmentations differ)."""
    cfg.cache_dir.mkdir(parents=True, exist_ok=True)
    key = cache_key(cfg, cut, split, tag, data, frozen_digest(model, cut))
    path = cfg.cache_dir / f"cache_{tag}_{key}.pt"
    if path.is_file():
        try:
            t = torch.load(path, map_location="cpu", weights_only=True)
            if t.shape[:2] == (copies + 1, len(split.images)):
                log(f"[train] {tag} features from {path}")
                return t
        except Exception:  # noqa: BLE001 - a damaged cache is recomputed
            pass
    versions = []
    t0 = time.perf_counter()
    for v in range(copies + 1):
        if v == 0:
            imgs = split.images
        else:
            imgs = [
                tdata.augment(
                    im, np.random.default_rng([cfg.seed, v, i] + ([part] if part else []))
                )
                for i, im in enumerate(split.images)
            ]
        if cfg.normalise:
            imgs = [normalised(im) for im in imgs]
        versions.append(compute_features(model, imgs, cut, cfg.size, device))
        log(
            f"[train] {tag} version {v + 1}/{copies + 1} cached "
            f"({len(imgs)} sketches, {time.perf_counter() - t0:.0f} s)"
        )
    t = torch.stack(versions)
    atomic_torch_save(t, path)
    return t


# ----------------------------------------------------------------------------- training
def head_targets(mats_norm: np.ndarray) -> dict[str, torch.Tensor]:
    return {
        h: torch.from_numpy(np.ascontiguousarray(v)).float()
        for h, v in encoding.split_heads(mats_norm).items()
    }


def loss_fn(
    out: dict[str, torch.Tensor], tgt: dict[str, torch.Tensor], kind: str = "mse"
) -> torch.Tensor:
    """Sum over the six heads of the mean squared error (``kind="mse"``, the paper's loss),
    or of its square root (``"rmse"``: the paper's metric, 1 - RMSE per head, directly;
    heads with small errors then weigh as much as the others)."""
    mse = [torch.mean((out[h] - tgt[h]) ** 2) for h in HEADS]
    if kind == "rmse":
        return sum(torch.sqrt(m + 1e-12) for m in mse)  # type: ignore[return-value]
    return sum(mse)  # type: ignore[return-value]


LOSSES = ("mse", "rmse")


def _forward(model: TSN, f: torch.Tensor, cut: int) -> dict[str, torch.Tensor]:
    f = f.float()
    if cut == 0:
        f = model.prepare(f)
    return model.forward_from(f, cut)


@torch.no_grad()
def predict_cached(
    model: TSN, feats: torch.Tensor, cut: int, device: str, batch: int = 128
) -> np.ndarray:
    model.eval()
    outs = []
    for s in range(0, len(feats), batch):
        o = _forward(model, feats[s : s + batch].to(device), cut)
        outs.append(encoding.join_heads({h: v.cpu().numpy() for h, v in o.items()}))
    return np.concatenate(outs)


def set_trainable(model: TSN, cut: int) -> list[torch.nn.Parameter]:
    frozen = {id(p) for m in model.frozen_modules(cut) for p in m.parameters()}
    params = []
    for p in model.parameters():
        p.requires_grad_(id(p) not in frozen)
        if p.requires_grad:
            params.append(p)
    return params


def train_mode(model: TSN, cut: int) -> None:
    model.train()
    for m in model.frozen_modules(cut):
        m.eval()


def _plot(rows: list[dict[str, Any]], path: Path, loss: str = "mse") -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ep = [r["epoch"] for r in rows]
    fig, ax = plt.subplots(1, 2, figsize=(10, 4))
    ax[0].plot(ep, [r["train_loss"] for r in rows], label="train")
    ax[0].plot(ep, [r["val_loss"] for r in rows], label="val")
    ax[0].set_xlabel("epoch")
    ax[0].set_ylabel(f"loss (train: sum of head {loss.upper()}; val: sum of head MSE)")
    ax[0].set_yscale("log")
    ax[0].legend()
    for h in [*HEADS, "overall"]:
        ax[1].plot(ep, [r[f"val_{h}"] for r in rows], label=h, lw=2 if h == "overall" else 1)
    ax[1].set_xlabel("epoch")
    ax[1].set_ylabel("val 1-RMSE")
    ax[1].legend(fontsize=7)
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100)
    plt.close(fig)
    atomic_write(path, buf.getvalue())


def _write_csv(rows: list[dict[str, Any]], path: Path) -> None:
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=list(rows[0]))
    w.writeheader()
    w.writerows(rows)
    atomic_write(path, buf.getvalue())


def _load_init(cfg: TrainConfig) -> Any:
    """The ``--init`` checkpoint, refused when its network or input size differ."""
    from .checkpoint import CheckpointError, load_checkpoint

    try:
        start = load_checkpoint(str(cfg.init))
    except CheckpointError as e:
        raise TrainError(f"--init: {e}") from None
    if start.model.backbone_name != cfg.backbone or start.size != cfg.size:
        raise TrainError(
            f"--init {cfg.init} is a {start.model.backbone_name} network at {start.size} px; "
            f"this run asks for --backbone {cfg.backbone} --size {cfg.size}"
        )
    return start


def add_species_classifier(
    cfg: TrainConfig,
    f_trn: torch.Tensor,
    f_val: torch.Tensor,
    cut: int,
    device: str,
    trn: Split,
    val: Split,
    log: Callable[[str], None] = print,
) -> float:
    """Fit the kept network's species classifier (``tsn.species_id.SpeciesClassifier``)
    on its outputs for the clean training sketches, its temperature on the validation
    ones, and store it in the checkpoint; returns its validation accuracy."""
    from .checkpoint import load_checkpoint

    best = load_checkpoint(cfg.out, device)
    best.model.eval()
    norm = best.normaliser
    out_trn = norm.denormalise(predict_cached(best.model, f_trn, cut, device))
    out_val = norm.denormalise(predict_cached(best.model, f_val, cut, device))
    clf = SpeciesClassifier.fit(
        out_trn, list(trn.species), norm.scale, held_out=(out_val, list(val.species))
    )
    acc = float(
        np.mean(
            [
                clf.species[i] == s
                for i, s in zip(clf.probabilities_many(out_val).argmax(1), val.species, strict=True)
            ]
        )
    )
    save_checkpoint(
        cfg.out, best.model, best.size, cut, norm, best.species_id.with_classifier(clf),
        {**best.info, "val_classifier_species_acc": acc, "classifier_temperature": clf.temperature},
        best.tree_detector,
    )  # fmt: skip
    log(f"[train] species classifier: val accuracy {acc:.3f}, temperature {clf.temperature:.2f}")
    return acc


# the records of a species branch and its classifier in a checkpoint's ``info``
CARRIED_INFO = ("classifier", "species_branch")


def carried_species(
    start: Loaded | None, cut: int
) -> tuple[SpeciesClassifier, SpeciesBranch] | None:
    """The ``--init`` checkpoint's species classifier and species branch when a fine-tune
    leaves them valid: the branch reads the map of a stage the fine-tune freezes (its
    ``start`` is at or after ``cut``) and the classifier reads only the branch's part of
    the features (no weight on the heads' pooled features, which the fine-tune changes).
    None otherwise: the classifier is then fitted again on the new network's outputs."""
    branch = None if start is None else start.species_branch
    clf = None if start is None else start.species_id.classifier
    if branch is None or clf is None or branch.start < cut or clf.reads != "features":
        return None
    heads = int(start.model.backbone.out_features)
    if np.any(np.asarray(clf.weight)[:, :heads] != 0):
        return None
    return clf, branch


def _prepare(cfg: TrainConfig) -> tuple[str, Path, Path]:
    """Threads, device and seed of the run; the dataset folder and the state file, refused
    when a previous run's state is there and ``resume`` was not asked for."""
    if cfg.threads:
        torch.set_num_threads(int(cfg.threads))
    device = "cuda" if torch.cuda.is_available() else "cpu"
    torch.manual_seed(cfg.seed)
    data = Path(cfg.data)
    if not data.is_dir():
        raise TrainError(f"--data {data}: no such dataset folder")
    work = cfg.work_dir
    work.mkdir(parents=True, exist_ok=True)
    state_path = work / "state.pt"
    if state_path.exists() and not cfg.resume:
        raise TrainError(
            f"{state_path} exists: pass --resume to continue that run, or remove {work}"
        )
    return device, data, state_path


@dataclass
class _Sketches:
    """The run's sketches: every style of each split (the feature caches hold them all)
    and the kept styles' indices and subsets."""

    first: Split  # the training split of ``--data``
    more: list[tuple[Path, Split]]  # the ``--more-data`` datasets
    val_all: Split
    keep_trn: np.ndarray  # indices into the training sketches of every dataset
    keep_val: np.ndarray
    trn: Split
    val: Split


def _load_sketches(cfg: TrainConfig, data: Path) -> _Sketches:
    """Every style is loaded (and later cached); the kept ones are picked after caching.
    A split left with no sketch in the kept styles is refused."""
    first = load_split(data, "train", cfg.max_sketches)
    more = load_more(cfg, data)
    trn_all = Split.concat([first] + [m for _, m in more])
    val_all = load_split(data, "val", cfg.max_sketches)
    keep_trn, keep_val = trn_all.keep(cfg.styles), val_all.keep(cfg.styles)
    for name, idx in (("train", keep_trn), ("val", keep_val)):
        if len(idx) == 0:
            kept = ", ".join(cfg.styles or ())
            raise TrainError(f"{data}: the {name!r} split has no sketches in the styles {kept}")
    trn, val = trn_all.subset(keep_trn), val_all.subset(keep_val)
    return _Sketches(first, more, val_all, keep_trn, keep_val, trn, val)


def _describe(cfg: TrainConfig, data: Path, sk: _Sketches, device: str) -> str:
    """The log line that says what the run trains on."""
    return (
        f"[train] {len(sk.trn.images)} train ({len(sk.first.images)} from {data}"
        + "".join(f", {len(m.images)} from {p}" for p, m in sk.more)
        + f") / {len(sk.val.images)} val sketches"
        + (f" in the styles {', '.join(cfg.styles)}" if cfg.styles else "")
        + f", device {device}"
    )


def _network(cfg: TrainConfig, start: Loaded | None, device: str) -> tuple[TSN, int]:
    """The network (``--init``'s or a new one) on ``device`` and its number of frozen
    stages, refused when ``--cut`` is out of range."""
    try:
        model = (start.model if start else TSN(cfg.backbone, pretrained=cfg.pretrained)).to(device)
    except ModelError as e:
        raise TrainError(str(e)) from None
    cut = BACKBONES[cfg.backbone][1] if cfg.cut is None else int(cfg.cut)
    if not 0 <= cut < model.n_stages:
        raise TrainError(f"--cut must be in [0, {model.n_stages - 1}], got {cut}")
    return model, cut


def _features(
    cfg: TrainConfig,
    model: TSN,
    cut: int,
    sk: _Sketches,
    device: str,
    log: Callable[[str], None],
) -> tuple[torch.Tensor, torch.Tensor]:
    """The frozen stages' features of the kept sketches: training ones (versions, sketch,
    ...) from ``--data`` and each ``--more-data`` dataset, clean validation ones."""
    f_trn = torch.cat(
        [build_cache(model, sk.first, cut, cfg, device, cfg.copies, "train", log)]
        + [
            build_cache(model, m, cut, cfg, device, cfg.copies, "train", log, str(p), i)
            for i, (p, m) in enumerate(sk.more, start=1)
        ],
        dim=1,
    )[:, torch.from_numpy(sk.keep_trn)]
    f_val = build_cache(model, sk.val_all, cut, cfg, device, 0, "val", log)[0][
        torch.from_numpy(sk.keep_val)
    ]
    return f_trn, f_val


@dataclass
class _Progress:
    """How far a run has got: what ``state.pt`` keeps besides the network and optimiser."""

    rows: list[dict[str, Any]] = field(default_factory=list)  # one per epoch done
    best: float = -math.inf  # best validation 1-RMSE so far
    best_epoch: int = 0
    start_epoch: int = 1  # the next epoch to run
    elapsed_before: float = 0.0  # training seconds of the runs this one resumes


@dataclass
class _Run:
    """What every epoch of a run reads and updates: the settings, the network and its
    optimiser, the cached features and targets, and what the checkpoint records."""

    cfg: TrainConfig
    device: str
    model: TSN
    cut: int
    opt: torch.optim.Optimizer
    sched: torch.optim.lr_scheduler.LRScheduler
    f_trn: torch.Tensor  # (versions, N, ...) training features
    f_val: torch.Tensor
    y_trn: dict[str, torch.Tensor]  # normalised targets per head
    y_val: dict[str, torch.Tensor]
    y_val_norm: np.ndarray
    normaliser: encoding.Normaliser
    species_id: SpeciesIdentifier
    val: Split
    start: Loaded | None  # the --init checkpoint
    carried: tuple[SpeciesClassifier, SpeciesBranch] | None  # see carried_species
    state_path: Path
    log: Callable[[str], None]

    @property
    def n_train(self) -> int:
        """The number of kept training sketches."""
        return self.f_trn.shape[1]

    def resume(self) -> _Progress:
        """The progress of the run this one continues (network, optimiser, schedule and
        random state restored from ``state.pt``), or a fresh start."""
        if not (self.cfg.resume and self.state_path.is_file()):
            return _Progress()
        st = torch.load(self.state_path, map_location="cpu", weights_only=False)
        self.model.load_state_dict(st["model"])
        self.opt.load_state_dict(st["opt"])
        self.sched.load_state_dict(st["sched"])
        prog = _Progress(st["rows"], st["best"], st["best_epoch"], st["epoch"] + 1, st["elapsed"])
        torch.set_rng_state(st["rng"])
        self.log(f"[train] resumed after epoch {st['epoch']} (best val 1-RMSE {prog.best:.4f})")
        return prog

    def fit_epoch(self, perm: torch.Tensor, ver: torch.Tensor) -> float:
        """One pass over the training sketches in the order ``perm``, sketch ``i`` in its
        cached version ``ver[i]``; returns the mean training loss."""
        train_mode(self.model, self.cut)
        n, batch = len(perm), self.cfg.batch
        total, seen = 0.0, 0
        for s in range(0, n, batch):
            idx = perm[s : s + batch]
            if len(idx) < 2:  # batch norm needs two samples
                continue
            x = self.f_trn[ver[idx], idx].to(self.device)
            tgt = {h: y[idx].to(self.device) for h, y in self.y_trn.items()}
            loss = loss_fn(_forward(self.model, x, self.cut), tgt, self.cfg.loss)
            self.opt.zero_grad(set_to_none=True)
            loss.backward()
            self.opt.step()
            total += loss.item() * len(idx)
            seen += len(idx)
        return total / max(seen, 1)

    def validate(self) -> tuple[float, dict[str, float], float]:
        """Validation loss (always the paper's loss, comparable across runs), 1-RMSE per
        head and overall, and the species identifier's accuracy."""
        pred = predict_cached(self.model, self.f_val, self.cut, self.device)
        with torch.no_grad():
            heads = {h: torch.from_numpy(v).float() for h, v in encoding.split_heads(pred).items()}
            val_loss = float(loss_fn(heads, self.y_val))
        s = one_minus_rmse(pred, self.y_val_norm)
        scores = {**s.heads, "overall": s.overall}
        sp = self.species_id.identify_many(self.normaliser.denormalise(pred))
        sp_acc = float(np.mean([a == b for a, b in zip(sp, self.val.species, strict=True)]))
        return val_loss, scores, sp_acc

    def save_best(
        self, epoch: int, scores: dict[str, float], sp_acc: float, elapsed: float
    ) -> None:
        """Write the checkpoint at ``cfg.out``, with what made it in its ``info``."""
        cfg = self.cfg
        info = {
            "config": {k: v for k, v in asdict(cfg).items() if k != "resume"},
            "cut": self.cut,
            "epoch": epoch,
            "epochs": cfg.epochs,
            "val": scores,
            "val_species_acc": sp_acc,
            "n_train": self.n_train,
            "n_val": len(self.val.images),
            "train_seconds": elapsed,
            "device": self.device,
            "torch": str(torch.__version__),
            "threads": torch.get_num_threads(),
        }
        if self.carried is not None and self.start is not None:
            # how the carried parts were made
            info.update({k: self.start.info[k] for k in CARRIED_INFO if k in self.start.info})
        save_checkpoint(
            cfg.out, self.model, cfg.size, self.cut, self.normaliser, self.species_id, info,
            species_branch=None if self.carried is None else self.carried[1],
        )  # fmt: skip

    def save_state(self, prog: _Progress, epoch: int, elapsed: float) -> None:
        """Write ``state.pt`` (what ``resume`` reads), ``log.csv`` and ``loss.png``."""
        atomic_torch_save(
            {
                "model": self.model.state_dict(),
                "opt": self.opt.state_dict(),
                "sched": self.sched.state_dict(),
                "rows": prog.rows,
                "best": prog.best,
                "best_epoch": prog.best_epoch,
                "epoch": epoch,
                "elapsed": elapsed,
                "rng": torch.get_rng_state(),
            },
            self.state_path,
        )
        _write_csv(prog.rows, self.state_path.parent / "log.csv")
        _plot(prog.rows, self.state_path.parent / "loss.png", self.cfg.loss)

    def run_epoch(self, epoch: int, gen: torch.Generator, prog: _Progress, t_run: float) -> None:
        """Train one epoch, validate, log it and save what it changed."""
        t0 = time.perf_counter()
        n = self.n_train
        perm = torch.randperm(n, generator=gen)
        ver = torch.randint(0, self.cfg.copies + 1, (n,), generator=gen)
        train_loss = self.fit_epoch(perm, ver)
        self.sched.step()
        val_loss, scores, sp_acc = self.validate()
        row = {
            "epoch": epoch,
            "train_loss": train_loss,
            "val_loss": val_loss,
            **{f"val_{k}": v for k, v in scores.items()},
            "val_species_acc": sp_acc,
            "lr": self.opt.param_groups[0]["lr"],
            "seconds": time.perf_counter() - t0,
        }
        prog.rows.append(row)
        elapsed = prog.elapsed_before + time.perf_counter() - t_run
        improved = scores["overall"] > prog.best
        if improved:
            prog.best, prog.best_epoch = scores["overall"], epoch
            self.save_best(epoch, scores, sp_acc, elapsed)
        self.save_state(prog, epoch, elapsed)
        self.log(
            f"[train] epoch {epoch}/{self.cfg.epochs} train {train_loss:.4f} val {val_loss:.4f} "
            f"val 1-RMSE {scores['overall']:.4f} species {sp_acc:.3f} "
            f"({row['seconds']:.0f} s){' *' if improved else ''}"
        )


def train(cfg: TrainConfig, log: Callable[[str], None] = print) -> dict[str, Any]:
    """Train (or resume) and return a summary; the best checkpoint is at ``cfg.out``."""
    cfg.check()
    t_start = time.perf_counter()
    device, data, state_path = _prepare(cfg)
    sk = _load_sketches(cfg, data)
    start = _load_init(cfg) if cfg.init else None
    # a fine-tune keeps its checkpoint's target scale: the heads already speak it
    normaliser = start.normaliser if start else encoding.Normaliser.fit(sk.trn.mats)
    species_id = fit_species_id(sk.trn, normaliser)
    y_trn = head_targets(normaliser.normalise(sk.trn.mats))
    y_val_norm = normaliser.normalise(sk.val.mats)
    log(_describe(cfg, data, sk, device))

    model, cut = _network(cfg, start, device)
    f_trn, f_val = _features(cfg, model, cut, sk, device, log)
    carried = carried_species(start, cut)
    if carried is not None:
        species_id = species_id.with_classifier(carried[0])
        log(
            f"[train] the species branch (stage {carried[1].start} on) and its classifier are"
            f" carried from --init: the stages before {cut} stay frozen"
        )
    opt = torch.optim.Adam(set_trainable(model, cut), lr=cfg.lr)
    sched = torch.optim.lr_scheduler.CosineAnnealingLR(opt, T_max=cfg.epochs, eta_min=cfg.lr / 100)
    run = _Run(
        cfg=cfg,
        device=device,
        model=model,
        cut=cut,
        opt=opt,
        sched=sched,
        f_trn=f_trn,
        f_val=f_val,
        y_trn=y_trn,
        y_val=head_targets(y_val_norm),
        y_val_norm=y_val_norm,
        normaliser=normaliser,
        species_id=species_id,
        val=sk.val,
        start=start,
        carried=carried,
        state_path=state_path,
        log=log,
    )
    prog = run.resume()
    t_run = time.perf_counter()

    n = len(sk.trn.images)
    gen = torch.Generator().manual_seed(cfg.seed)
    for _ in range(prog.start_epoch - 1):  # same permutations as an uninterrupted run
        torch.randperm(n, generator=gen)
        torch.randint(0, cfg.copies + 1, (n,), generator=gen)
    for epoch in range(prog.start_epoch, cfg.epochs + 1):
        run.run_epoch(epoch, gen, prog, t_run)
    classifier_acc = (
        add_species_classifier(cfg, f_trn[0], f_val, cut, device, sk.trn, sk.val, log)
        if carried is None
        else None
    )
    return {
        "val_classifier_species_acc": classifier_acc,
        "best_val_overall": prog.best,
        "best_epoch": prog.best_epoch,
        "epochs": len(prog.rows),
        "rows": prog.rows,
        "out": cfg.out,
        "work": str(cfg.work_dir),
        "seconds": time.perf_counter() - t_start,
    }
