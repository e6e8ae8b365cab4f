"""Shared helpers of the tsn tests: tiny datasets and checkpoints built in tmp folders."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from weberpenn import species


def sampled_matrices(per_species: int = 12, seed0: int = 0) -> dict[str, np.ndarray]:
    """Encoded dictionaries drawn with ``weberpenn.species.sample`` (no dataset needed)."""
    from tsn import encoding

    return {
        s: np.stack([encoding.encode(species.sample(s, seed0 + i)) for i in range(per_species)])
        for s in species.SPECIES
    }


def make_checkpoint(path: Path, backbone: str = "lite0", size: int = 64) -> Path:
    """An untrained checkpoint (pretrained backbone, random heads) with a real normaliser."""
    from tsn import encoding
    from tsn.checkpoint import save_checkpoint
    from tsn.model import TSN
    from tsn.species_id import SpeciesIdentifier

    mats = sampled_matrices()
    norm = encoding.Normaliser.fit(np.concatenate(list(mats.values())))
    sid = SpeciesIdentifier.fit(mats, norm.scale)
    model = TSN(backbone, pretrained=backbone == "lite0")
    return save_checkpoint(path, model, size, 12, norm, sid, {"epoch": 0})


def build_tiny_dataset(out: Path, size: int = 64) -> Path:
    """4 trees per species (2 train, 1 val, 1 test), two views, small sketches."""
    from render.dataset import DatasetConfig, build_dataset

    build_dataset(
        DatasetConfig(
            out=str(out),
            trees_per_species=4,
            views=("front", "left"),
            size=size,
            val_fraction=0.25,
            test_fraction=0.25,
        ),
        progress=False,
    )
    return out
