"""Sketch -> parameters with a trained TSN checkpoint.

``model = load_model()`` loads the shipped checkpoint (``checkpoints/tsn_lite0.pt``, or
the path in ``$TREESKETCH_TSN_CHECKPOINT``); ``model.predict(image)`` (or the module-level
``predict(model, image)``) accepts a path, PIL image, bytes or array of any size (grey,
RGB, or RGBA composited on white) and returns a :class:`Prediction`:

* ``raw``: the network's six head outputs (normalised ``(4, n)`` arrays, the paper's
  output, what 1-RMSE scores); with ``flip=True`` (the default) the mean of the outputs for
  the sketch and its mirror image (test-time averaging: a mirrored tree sketch is an
  equally plausible drawing of a tree with the same parameters; measured on the test split
  in ``benchmarks/RESULTS.md``);
* ``species``: the checkpoint's species classifier on the drawing's features, or
  Algorithm 1 on the denormalised output (``tsn.species_id``);
* ``decoded``: the output decoded to a valid dictionary (``tsn.encoding.decode``: rounded,
  thresholded, snapped, clamped to the training range);
* ``params``: ``decoded`` projected onto the identified species
  (``weberpenn.species.project``: its fixed values, unfixed ones clipped to its ranges).

A drawing's *features* (``raw_and_features``) are the pooled features the six heads read
(the first :attr:`TSNModel.head_width` columns, what the tree detector and a refit of the
heads read) followed, when the checkpoint has a species branch (``tsn.model.SpeciesBranch``),
by the branch's pooled features of the drawing as given (the heads' part is, with
``flip``, the mean over the drawing and its mirror): the species classifier reads them all.

``preprocess(image)`` is the network's input preparation (``tsn.data.preprocess``: crop
to the drawing, pad square, area-resize; float32, 1 = white), identical to training.
Bad input raises ``render.reader.SketchError`` (a ``ValueError``).
"""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import torch

from weberpenn import species as wp_species
from weberpenn.params import TreeParams

from . import data as tdata
from . import encoding
from .checkpoint import CheckpointError, Loaded, load_checkpoint
from .model import TSN, fold_batchnorm

__all__ = [
    "DEFAULT_CHECKPOINT",
    "CheckpointError",
    "Prediction",
    "TSNModel",
    "load_model",
    "predict",
    "preprocess",
]

DEFAULT_CHECKPOINT = Path(__file__).resolve().parents[1] / "checkpoints" / "tsn_lite0.pt"
ENV_CHECKPOINT = "TREESKETCH_TSN_CHECKPOINT"


def _cores() -> int:
    """The cores this process may run on."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1


@dataclass(frozen=True)
class Prediction:
    params: TreeParams  # decoded and projected onto the identified species
    species: str
    raw: dict[str, np.ndarray]  # per head, normalised network output (4, n)
    decoded: TreeParams  # decoded, not projected
    matrix: np.ndarray  # (4, 62) denormalised network output


class TSNModel:
    """A loaded checkpoint: network, normaliser, species identifier, input size."""

    def __init__(self, loaded: Loaded, flip: bool = True) -> None:
        self.loaded = loaded
        self.flip = bool(flip)
        # inference only: batch norms folded into the convolutions and channels-last layout
        # (oneDNN), each faster on CPU; outputs differ by float rounding only (~1e-7)
        self.net: TSN = fold_batchnorm(loaded.model).to(memory_format=torch.channels_last)
        branch = loaded.species_branch
        self.branch = (
            None if branch is None else fold_batchnorm(branch).to(memory_format=torch.channels_last)
        )
        self.head_width = int(self.net.backbone.out_features)
        self.normaliser = loaded.normaliser
        self.species_id = loaded.species_id
        self.size = loaded.size
        self.info = loaded.info
        self.device = next(self.net.parameters()).device

    def __repr__(self) -> str:
        return (
            f"TSNModel({self.loaded.path}, backbone={self.net.backbone_name}, size={self.size}, "
            f"flip={self.flip})"
        )

    def preprocess(self, image: Any) -> np.ndarray:
        return tdata.preprocess(image, self.size)

    @torch.no_grad()
    def _forward(
        self, images: Any, mirrored: bool, side_by_side: bool | None = None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        """Of the N images (then, with ``mirrored``, of their left-right mirrors: B = 2N):
        normalised outputs ``(B, 4, 62)``, the pooled features the heads read ``(B, m)``,
        and the species branch's pooled features of the N images as given (None without
        a branch).

        ``side_by_side`` (default: one image, torch on one thread, more than one core)
        runs the drawing and its mirror as two passes on two threads at once instead of
        one batch of two: the same numbers to the last bit (on one thread a batch of one
        takes the kernels a batch of two does; ``tests/test_tsn_predict.py``) in about
        half the time, which is most of a first estimate."""
        x = torch.from_numpy(np.stack([self.preprocess(im) for im in images]))[:, None]
        n = len(x)
        if side_by_side is None:
            side_by_side = n == 1 and torch.get_num_threads() == 1 and _cores() > 1
        if mirrored and side_by_side:
            pooled, species = self._side_by_side(x)
        else:
            batch = torch.cat([x, torch.flip(x, dims=[3])]) if mirrored else x
            pooled, species = self._pooled(batch, n)
        out = self.net.head_outputs(pooled)
        mats = encoding.join_heads({h: v.float().cpu().numpy() for h, v in out.items()})
        return mats, pooled.float().cpu().numpy(), species

    def _pooled(self, x: torch.Tensor, n: int) -> tuple[torch.Tensor, np.ndarray | None]:
        """The heads' pooled features of a batch and the branch's of its first ``n``
        images (none for ``n`` 0 or without a branch)."""
        x = x.to(self.device).contiguous(memory_format=torch.channels_last)
        if self.branch is None or n == 0:
            return self.net.pool(self.net.features(x, 0), 0), None
        # the branch reads the map of stage `start` the rest of the network reads, of the
        # drawing alone: its mirror too would add about 5 ms to each estimate and nothing
        # to the species (benchmarks/RESULTS.md, "A species branch")
        f = self.net.features(x, self.branch.start)
        species = self.branch(f[:n]).float().cpu().numpy()
        return self.net.pool(f, self.branch.start), species

    def _side_by_side(self, x: torch.Tensor) -> tuple[torch.Tensor, np.ndarray | None]:
        """:meth:`_pooled` of the images and of their mirrors, the mirrors' pass on a
        second thread (torch lets go of the GIL inside its operations; a third thread for
        the species branch measured no faster on two cores)."""

        def mirrors() -> torch.Tensor:
            with torch.no_grad():  # grad mode is per thread
                return self._pooled(torch.flip(x, dims=[3]), 0)[0]

        with ThreadPoolExecutor(max_workers=1) as pool:
            later = pool.submit(mirrors)
            pooled, species = self._pooled(x, len(x))
            return torch.cat([pooled, later.result()]), species

    def pooled_features(self, images: Any) -> tuple[np.ndarray, np.ndarray]:
        """The pooled features ``(N, m)`` the heads read, of the images and of their
        left-right mirrors (what a refit of the heads learns from: ``tsn.heads``)."""
        pooled = self._forward(images, True)[1]
        return pooled[: len(pooled) // 2], pooled[len(pooled) // 2 :]

    def head_features(self, features: np.ndarray) -> np.ndarray:
        """The columns of ``(N, m)`` features that the heads read (see the module text)."""
        return np.asarray(features)[:, : self.head_width]

    def raw_views(self, images: Any, mirrored: bool = True) -> tuple[np.ndarray, ...]:
        """Normalised network outputs ``(N, 4, 62)`` for the images as given and, with
        ``mirrored``, for their left-right mirrors (one batch of 2N)."""
        return self.views_and_features(images, mirrored)[0]

    def views_and_features(
        self, images: Any, mirrored: bool = True
    ) -> tuple[tuple[np.ndarray, ...], np.ndarray]:
        """:meth:`raw_views` and the drawings' features, ``(N, m)`` (see the module text;
        with ``mirrored``, the heads' part is the mean over the image and its mirror)."""
        mats, pooled, species = self._forward(images, mirrored)
        if mirrored:
            n = len(mats) // 2
            views, pooled = (mats[:n], mats[n:]), 0.5 * (pooled[:n] + pooled[n:])
        else:
            views = (mats,)
        return views, pooled if species is None else np.concatenate([pooled, species], axis=1)

    def raw_and_features(self, images: Any) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`raw_batch` and the drawings' features, ``(N, m)`` (see the module text;
        with ``self.flip``, the heads' part is the mean over the image and its mirror)."""
        views, pooled = self.views_and_features(images, self.flip)
        return (0.5 * (views[0] + views[1]) if self.flip else views[0]), pooled

    def tree_probabilities(self, features: np.ndarray) -> np.ndarray | None:
        """P(each drawing is a tree) from :meth:`raw_and_features`' features, or None when
        the checkpoint has no tree detector."""
        det = self.loaded.tree_detector
        return None if det is None else det.probabilities(self.head_features(features))

    def raw_batch(self, images: Any) -> np.ndarray:
        """Normalised network output ``(N, 4, 62)`` for a sequence of images: with
        ``self.flip`` the mean over each image and its mirror (:meth:`raw_views`)."""
        views = self.raw_views(images, mirrored=self.flip)
        return 0.5 * (views[0] + views[1]) if self.flip else views[0]

    def from_raw(self, raw: np.ndarray, features: np.ndarray | None = None) -> Prediction:
        """Decode one normalised ``(4, 62)`` network output (its species from the drawing's
        ``(m,)`` features too, when the checkpoint's species classifier reads them)."""
        mat = self.normaliser.denormalise(raw)
        name = self.species_id.identify(mat, features)
        decoded = encoding.decode(mat, self.normaliser)
        projected = wp_species.project(name, decoded)
        return Prediction(projected, name, encoding.split_heads(raw), decoded, mat)

    def predict(self, image: Any) -> Prediction:
        return self.predict_batch([image])[0]

    def predict_batch(self, images: Any) -> list[Prediction]:
        raw, features = self.raw_and_features(list(images))
        return [self.from_raw(r, f) for r, f in zip(raw, features, strict=True)]

    def __call__(self, image: Any) -> Prediction:
        return self.predict(image)


def load_model(
    path: str | os.PathLike[str] | None = None, device: str | None = None, flip: bool = True
) -> TSNModel:
    """Load a checkpoint (default: ``$TREESKETCH_TSN_CHECKPOINT`` or the shipped one).

    ``flip`` averages each output with that of the mirrored sketch (see the module text).
    """
    if path is None:
        path = os.environ.get(ENV_CHECKPOINT) or DEFAULT_CHECKPOINT
    dev = device or ("cuda" if torch.cuda.is_available() else "cpu")
    return TSNModel(load_checkpoint(path, dev), flip=flip)


def predict(model: TSNModel, image: Any) -> Prediction:
    """Module-level form of ``model.predict(image)``."""
    return model.predict(image)


def preprocess(image: Any, size: int = tdata.DEFAULT_SIZE) -> np.ndarray:
    """The network's input: crop to the drawing, pad square, area-resize (1 = white)."""
    return tdata.preprocess(image, size)
