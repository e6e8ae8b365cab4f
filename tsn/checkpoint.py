"""TSN checkpoint files: weights (fp16), normaliser, species identifier, training record.

A checkpoint is one ``torch.save`` file holding plain data only (tensors, lists, dicts,
strings, numbers), written to a temporary name and renamed::

    format        "treesketch-tsn/1"
    backbone      registry name (``tsn.model.BACKBONES``)
    size          input size in pixels (square)
    cut           stages frozen during training (informative)
    state_dict    model weights, floating tensors stored as fp16
    normaliser    ``tsn.encoding.Normaliser.to_dict()``
    species_id    ``tsn.species_id.SpeciesIdentifier.to_dict()``
    tree_detector ``tsn.tree_detect.TreeDetector.to_dict()`` (optional: is it a tree?)
    species_branch  ``{"start": stage, "state_dict": fp16 weights}`` of a
                  ``tsn.model.SpeciesBranch`` (optional: features for the species)
    train         how it was trained (config, epochs, wall time, validation scores)
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import torch

from weberpenn.fileio import atomic_target

from .encoding import Normaliser
from .model import TSN, SpeciesBranch
from .species_id import SpeciesIdentifier
from .tree_detect import TreeDetector

FORMAT = "treesketch-tsn/1"


class CheckpointError(ValueError):
    """A missing, unreadable or foreign checkpoint file."""


@dataclass
class Loaded:
    model: TSN
    normaliser: Normaliser
    species_id: SpeciesIdentifier
    size: int
    info: dict[str, Any]
    path: Path | None = None
    tree_detector: TreeDetector | None = None
    species_branch: SpeciesBranch | None = None


def atomic_torch_save(obj: Any, path: str | os.PathLike[str]) -> Path:
    with atomic_target(path) as tmp:
        torch.save(obj, tmp)
    return Path(path)


def half_state(model: torch.nn.Module) -> dict[str, torch.Tensor]:
    return _half(model.state_dict())


def _half(state: dict[str, torch.Tensor]) -> dict[str, torch.Tensor]:
    return {
        k: (v.detach().to("cpu", torch.float16) if v.is_floating_point() else v.detach().cpu())
        for k, v in state.items()
    }


def _full(state: dict[str, torch.Tensor]) -> dict[str, torch.Tensor]:
    return {k: v.float() if v.is_floating_point() else v for k, v in state.items()}


def save_checkpoint(
    path: str | os.PathLike[str],
    model: TSN,
    size: int,
    cut: int,
    normaliser: Normaliser,
    species_id: SpeciesIdentifier,
    info: dict[str, Any],
    tree_detector: TreeDetector | None = None,
    species_branch: SpeciesBranch | None = None,
) -> Path:
    extra: dict[str, Any] = {}
    if tree_detector is not None:
        extra["tree_detector"] = tree_detector.to_dict()
        if tree_detector.hidden_weight is not None:
            # most of its numbers: as a tensor it loads in milliseconds, as a list in 0.5 s
            hidden = tree_detector.hidden_weight.astype(np.float32)
            extra["tree_detector"]["hidden_weight"] = torch.from_numpy(hidden)
    if species_branch is not None:
        extra["species_branch"] = {
            "start": species_branch.start,
            "state_dict": _half(species_branch.stage_state()),
        }
    return atomic_torch_save(
        {
            "format": FORMAT,
            "backbone": model.backbone_name,
            "size": int(size),
            "cut": int(cut),
            "state_dict": half_state(model),
            "normaliser": normaliser.to_dict(),
            "species_id": species_id.to_dict(),
            "train": info,
            **extra,
        },
        path,
    )


def save_loaded(
    loaded: Loaded,
    path: str | os.PathLike[str],
    info: dict[str, Any],
    *,
    species_id: SpeciesIdentifier | None = None,
    tree_detector: TreeDetector | None = None,
    species_branch: SpeciesBranch | None = None,
) -> Path:
    """Write a loaded checkpoint again with new ``info`` and, when given, a new species
    identifier, tree detector or species branch (the parts fitted after training); the
    network's weights and normaliser as they were."""
    return save_checkpoint(
        path,
        loaded.model,
        loaded.size,
        int(loaded.info.get("cut", 12)),
        loaded.normaliser,
        species_id or loaded.species_id,
        info,
        tree_detector or loaded.tree_detector,
        species_branch or loaded.species_branch,
    )


def load_checkpoint(path: str | os.PathLike[str], device: str = "cpu") -> Loaded:
    path = Path(path)
    if not path.is_file():
        raise CheckpointError(f"{path}: no such checkpoint file")
    try:
        # early checkpoints recorded torch.__version__ (a TorchVersion, a str subclass)
        with torch.serialization.safe_globals([torch.torch_version.TorchVersion]):
            ck = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as e:  # noqa: BLE001 - torch raises many kinds for a bad file
        raise CheckpointError(f"{path}: not a TSN checkpoint ({type(e).__name__}: {e})") from None
    if not isinstance(ck, dict) or ck.get("format") != FORMAT:
        raise CheckpointError(f"{path}: not a TSN checkpoint (format {FORMAT!r} expected)")
    try:
        model = TSN(ck["backbone"], pretrained=False)
        model.load_state_dict(_full(ck["state_dict"]))
    except (KeyError, RuntimeError, ValueError) as e:
        raise CheckpointError(f"{path}: weights do not fit the network: {e}") from None
    model.eval().to(device)
    try:
        detector = TreeDetector.from_dict(ck["tree_detector"]) if "tree_detector" in ck else None
    except (KeyError, TypeError, ValueError) as e:
        raise CheckpointError(f"{path}: unreadable tree detector: {e}") from None
    branch = None
    if "species_branch" in ck:
        try:
            branch = SpeciesBranch(ck["backbone"], int(ck["species_branch"]["start"]))
            branch.load_stage_state(_full(ck["species_branch"]["state_dict"]))
        except (KeyError, TypeError, ValueError, RuntimeError) as e:
            raise CheckpointError(f"{path}: unreadable species branch: {e}") from None
        branch.eval().to(device)
    return Loaded(
        model,
        Normaliser.from_dict(ck["normaliser"]),
        SpeciesIdentifier.from_dict(ck["species_id"]),
        int(ck["size"]),
        dict(ck.get("train", {})),
        path,
        detector,
        branch,
    )
