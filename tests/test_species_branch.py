"""scripts/fit_species_branch.py: train a species branch on cached maps and install it."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from tsn_helpers import make_checkpoint

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = ROOT / "scripts" / "fit_species_branch.py"
NAMES = ("palm", "pine", "maple")


def _cache(tmp: Path, loaded, n: int = 12) -> Path:
    """Cached stage-12 maps of random drawings, every set the script reads; each species'
    drawings darker or lighter so there is something to learn."""
    import torch

    out = tmp / "cache"
    out.mkdir()
    rng = np.random.default_rng(0)
    tags = ("doodle_fit", "styled_fit", "ds_train", "doodle_held", "styled_held", "ds_val",
            "ds_test", "doodle_bench", "hand")  # fmt: skip
    for tag in tags:
        labels = np.array([NAMES[i % 3] for i in range(n)])
        x = rng.random((n, 1, 64, 64)).astype(np.float32)
        x *= np.array([0.3, 0.6, 0.9])[np.arange(n) % 3][:, None, None, None]
        x = torch.from_numpy(x)
        with torch.no_grad():
            f = loaded.model.features(torch.cat([x, torch.flip(x, dims=[3])]), 12)
        maps = torch.stack([f[:n], f[n:]], 1).half().numpy()
        data = {"maps": maps, "species": labels, "start": 12}
        if tag == "ds_test":
            data["extra"] = np.array(["sg", "doodle"] * (n // 2))
        if tag == "hand":
            data["extra"] = np.array([json.dumps([])] * n)
        np.savez(out / f"{tag}.npz", **data)
    return out


def _run(*args: str | Path) -> str:
    done = subprocess.run(
        [sys.executable, str(SCRIPT), *map(str, args)], capture_output=True, text=True,
        cwd=ROOT, check=False,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    return done.stdout


@pytest.mark.slow
def test_train_and_install_a_branch(tmp_path: Path) -> None:
    from tsn.checkpoint import load_checkpoint, save_loaded
    from tsn.predict import load_model
    from tsn.species_id import SpeciesClassifier

    base = load_checkpoint(make_checkpoint(tmp_path / "base.pt", size=64))
    rng = np.random.default_rng(1)
    feats = rng.normal(size=(30, 1280))
    clf = SpeciesClassifier.fit(
        feats, [NAMES[i % 3] for i in range(30)], base.normaliser.scale, reads="features"
    )
    ck = save_loaded(base, tmp_path / "ck.pt", {}, species_id=base.species_id.with_classifier(clf))
    cache = _cache(tmp_path, base)
    out = _run("--checkpoint", ck, "train", "--cache", cache, "--epochs", "1", "--batch", "8",
               "--out", tmp_path / "branch.pt")  # fmt: skip
    assert "epoch 0 (the shipped classifier)" in out and "epoch 1:" in out
    out = _run("--checkpoint", ck, "install", "--cache", cache, "--branch",
               tmp_path / "branch.pt", "--out", tmp_path / "with.pt")  # fmt: skip
    assert "temperature" in out
    loaded = load_checkpoint(tmp_path / "with.pt")
    assert loaded.species_branch is not None and loaded.species_branch.start == 12
    assert loaded.info["species_branch"]["trained"]["epochs"] == 1
    new = loaded.species_id.classifier
    assert new is not None and new.species == NAMES and new.weight.shape == (3, 2560)
    assert not new.weight[:, :1280].any()  # the heads' columns carry no weight
    # the network itself is the one it was installed on
    a, b = base.model.state_dict(), loaded.model.state_dict()
    assert all(bool((a[k] == b[k]).all()) for k in a)
    model = load_model(tmp_path / "with.pt", device="cpu")
    img = np.full((64, 64), 255, np.uint8)
    img[8:56, 28:36] = 0
    assert model.predict(img).species in NAMES
    # a checkpoint with a branch trains on from that branch and the classifier's columns
    out = _run("--checkpoint", tmp_path / "with.pt", "train", "--cache", cache, "--epochs", "1",
               "--batch", "8", "--out", tmp_path / "b2.pt")  # fmt: skip
    assert "epoch 1:" in out
