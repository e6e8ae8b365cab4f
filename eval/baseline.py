"""Nearest-neighbour sketch search (NNS) baseline: :class:`NNSIndex`.

Predicts the parameters of the indexed training sketch closest to the input (cosine
similarity between 32x32 area-downsized, blurred ink images).  It needs no network, so it
is the stand-in when no TSN checkpoint exists, and a row to compare TSN against.

1-RMSE needs normalised target matrices.  With ``reference`` (another backend's
``normalise_targets``, e.g. TSN's, whose normaliser was fitted on the training split and
saved with its checkpoint) NNS is scored on exactly the same scale as that model.  Without
it, a plain per-key max-abs scale (every head, angles included) is fitted on the indexed
training trees, over ``tsn.encoding``'s (4, 62) matrices.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

import numpy as np

from weberpenn import TreeParams

from .scoring import Scorer, dataset_sketch, progress_bar

__all__ = ["FEATURE", "NNS_NAME", "NNSIndex", "features"]

FEATURE = 32
NNS_NAME = "NNS baseline"

Normaliser = Callable[[Sequence[Mapping]], np.ndarray]


def features(img: np.ndarray) -> np.ndarray:
    """Unit-length (FEATURE*FEATURE,) ink descriptor of a uint8 sketch (255 = white)."""
    from scipy.ndimage import gaussian_filter

    a = np.asarray(img)
    if a.ndim != 2 or min(a.shape) < 1:
        raise ValueError(f"a sketch must be a 2-D greyscale image, got shape {a.shape}")
    a = 1.0 - a.astype(np.float32) / (255.0 if a.dtype == np.uint8 else 1.0)
    n = a.shape[0]
    if a.shape[1] == n and n % FEATURE == 0:
        k = n // FEATURE
        a = a.reshape(FEATURE, k, FEATURE, k).mean(axis=(1, 3))
    else:
        from PIL import Image

        a = np.asarray(
            Image.fromarray(np.ascontiguousarray(a), mode="F").resize(
                (FEATURE, FEATURE), Image.Resampling.BOX
            ),
            dtype=np.float32,
        )
    a = gaussian_filter(a, 1.0)
    return (a / (np.linalg.norm(a) + 1e-6)).ravel()


class NNSIndex:
    """Ink descriptors of a dataset's sketches and the parameters each was drawn from."""

    def __init__(
        self, index: np.ndarray, owners: Sequence[str], params: Mapping[str, TreeParams], info: str
    ) -> None:
        self.index = index
        self.owners = list(owners)
        self.params = dict(params)
        self.info = info

    @classmethod
    def fit(
        cls,
        data: str | Path,
        split: str = "train",
        max_rows: int | None = 2000,
        bar: bool = True,
    ) -> NNSIndex:
        """Index (up to ``max_rows`` evenly spaced rows of) ``split`` of the dataset."""
        from render.dataset import read_manifest

        data = Path(data)
        rows = read_manifest(data, split=split)
        if not rows:
            raise ValueError(f"{data}: the {split!r} split is empty")
        if max_rows is not None and len(rows) > max_rows:
            pick = np.linspace(0, len(rows) - 1, max_rows).round().astype(int)
            rows = [rows[i] for i in pick]
        params: dict[str, TreeParams] = {}
        feats, owners = [], []
        for r in progress_bar(rows, "NNS index", len(rows), bar):
            if r["params"] not in params:
                params[r["params"]] = TreeParams(
                    json.loads((data / r["params"]).read_text(encoding="utf-8"))
                )
            feats.append(features(dataset_sketch(data / r["sketch"])))
            owners.append(r["params"])
        info = f"{len(rows)} {split} sketches of {len(params)} trees"
        return cls(np.stack(feats), owners, params, info)

    def nearest(self, img: np.ndarray) -> str:
        return self.owners[int(np.argmax(self.index @ features(img)))]

    def predict(self, img: np.ndarray) -> TreeParams:
        return self.params[self.nearest(img)]

    def scorer(self, reference: Normaliser | None = None) -> Scorer:
        """A 1-RMSE scorer (see the module text for ``reference``)."""
        if reference is None:
            from tsn.encoding import encode_many

            scale = np.abs(encode_many(self.params.values())).max(axis=(0, 1))
            scale = np.where(scale > 0, scale, 1.0)

            def normalise_targets(ps: Sequence[Mapping]) -> np.ndarray:
                return encode_many(ps) / scale

            norm_info = "own max-abs scale over the indexed trees"
        else:
            normalise_targets = reference
            norm_info = "the reference model's normaliser"

        def predict_normalised(imgs: np.ndarray) -> np.ndarray:
            return np.asarray(normalise_targets([self.predict(i) for i in imgs]))

        return Scorer(
            name=NNS_NAME,
            predict_normalised=predict_normalised,
            normalise_targets=normalise_targets,
            info={"kind": "baseline", "index": self.info, "normalisation": norm_info},
        )
