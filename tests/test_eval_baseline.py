"""eval.baseline: the nearest-neighbour (NNS) baseline and `treesketch eval all --model nns`."""

from __future__ import annotations

import json

import numpy as np
import pytest
from PIL import Image
from typer.testing import CliRunner

from eval.baseline import NNS_NAME, NNSIndex, features
from eval.metrics import one_minus_rmse
from tsn.encoding import encode
from weberpenn import build_mesh, grow, species
from weberpenn.params import PREDICTED_KEYS, SPECS

COL = {k: i for i, k in enumerate(PREDICTED_KEYS)}


def _dataset(root, size: int = 64) -> None:
    """palm and maple, two train trees each (front, left), one test tree each (front)."""
    from render.sketch import SketchRenderer

    rows = []
    (root / "params").mkdir(parents=True)
    (root / "sketches").mkdir()
    for sp in ("palm", "maple"):
        for i, split in enumerate(("train", "train", "test")):
            p = species.sample(sp, seed=20 + i)
            tid = f"{sp}_{i:04d}"
            (root / "params" / f"{tid}.json").write_text(json.dumps(p.to_dict()))
            r = SketchRenderer(build_mesh(grow(p), species=sp))
            views = (("front", 0.0), ("left", 90.0)) if split == "train" else (("front", 0.0),)
            for view, yaw in views:
                Image.fromarray(r.sketch(yaw, size)).save(root / "sketches" / f"{tid}_{view}.png")
                rows.append(
                    {
                        "species": sp,
                        "tree_id": tid,
                        "split": split,
                        "view": view,
                        "yaw": yaw,
                        "sketch": f"sketches/{tid}_{view}.png",
                        "params": f"params/{tid}.json",
                    }
                )
    (root / "manifest.jsonl").write_text("".join(json.dumps(r) + "\n" for r in rows))


@pytest.fixture(scope="module")
def data(tmp_path_factory):
    root = tmp_path_factory.mktemp("nns") / "ds"
    _dataset(root)
    return root


def _sketch(data, name: str) -> np.ndarray:
    return np.asarray(Image.open(data / "sketches" / name).convert("L"))


def test_encode_layout() -> None:
    p = species.sample("pine", 3)
    m = encode(p)
    assert m.shape == (4, 62)
    assert np.all(m[:, COL["ratio"]] == p["ratio"])  # a scalar repeats in all four rows
    assert list(m[:, COL["branches"]]) == [float(v) for v in p["branches"]]
    for k in PREDICTED_KEYS:
        if SPECS[k].kind in ("bool", "sign"):
            assert set(np.unique(m[:, COL[k]])) <= {0.0, 1.0}, k


def test_features_are_unit_and_size_free() -> None:
    img = np.full((64, 64), 255, np.uint8)
    img[10:50, 30:34] = 0
    f = features(img)
    assert f.shape == (32 * 32,) and np.linalg.norm(f) == pytest.approx(1.0, abs=1e-4)
    g = features(np.asarray(Image.fromarray(img).resize((100, 100), Image.Resampling.NEAREST)))
    assert float(f @ g) > 0.95  # the same drawing at another size
    with pytest.raises(ValueError, match="2-D"):
        features(np.zeros((4, 4, 3), np.uint8))


def test_nearest_neighbour_returns_indexed_trees(data) -> None:
    idx = NNSIndex.fit(data, bar=False)
    b = idx.scorer()
    assert b.name == NNS_NAME and b.info["kind"] == "baseline"
    assert "4 train sketches" in b.info["index"] or "8 train sketches" in b.info["index"]
    for sp in ("palm", "maple"):
        for i in (0, 1):
            got = idx.predict(_sketch(data, f"{sp}_{i:04d}_front.png"))
            assert got.to_dict() == species.sample(sp, seed=20 + i).to_dict()
    # a held-out sketch gets a training tree of its own species
    pred = idx.predict(_sketch(data, "palm_0002_front.png"))
    assert any(pred.to_dict() == species.sample("palm", seed=20 + i).to_dict() for i in (0, 1))


def test_normalised_outputs_score_one_on_indexed_sketches(data) -> None:
    b = NNSIndex.fit(data, bar=False).scorer()
    names = [f"{sp}_{i:04d}_left.png" for sp in ("palm", "maple") for i in (0, 1)]
    imgs = np.stack([_sketch(data, n) for n in names])
    truth = [species.sample(sp, seed=20 + i) for sp in ("palm", "maple") for i in (0, 1)]
    pred, tgt = b.predict_normalised(imgs), b.normalise_targets(truth)
    assert pred.shape == tgt.shape == (4, 4, 62)
    assert np.abs(tgt).max() <= 1.0 + 1e-12  # max-abs scaled over the indexed trees
    assert one_minus_rmse(pred, tgt).overall == pytest.approx(1.0)


def test_reference_normaliser_is_used(data) -> None:
    seen = []

    def ref(ps):
        seen.append(len(ps))
        return np.full((len(ps), 4, 62), 0.5)

    b = NNSIndex.fit(data, bar=False).scorer(reference=ref)
    out = b.predict_normalised(np.stack([_sketch(data, "palm_0000_front.png")] * 3))
    assert out.shape == (3, 4, 62) and np.all(out == 0.5) and seen == [3]
    assert b.normalise_targets is ref


def test_subsampled_index_and_errors(data, tmp_path) -> None:
    b = NNSIndex.fit(data, max_rows=2, bar=False).scorer()
    assert b.info["index"].startswith("2 train sketches")
    with pytest.raises(ValueError, match="split is empty"):
        NNSIndex.fit(data, split="val", bar=False)
    with pytest.raises(ValueError, match="manifest"):
        NNSIndex.fit(tmp_path, bar=False)


@pytest.mark.slow
def test_eval_all_with_nns_model(data, tmp_path) -> None:
    from treesketch.cli import app

    out = tmp_path / "rep"
    res = CliRunner().invoke(
        app,
        [
            "eval",
            "all",
            "--data",
            str(data),
            "--out",
            str(out),
            "--model",
            "nns",
            "--per-species",
            "1",
            "--refine-budget",
            "2",
            "--rotation-step",
            "90",
            "--rotation-species",
            "palm",
            "--samples",
            "500",
        ],  # fmt: skip
    )
    assert res.exit_code == 0, res.output
    md = (out / "README.md").read_text()
    assert "No TSN checkpoint was evaluated here" in md
    assert "no second backbone was evaluated" in md
    assert "| NNS baseline |" in md and "| all | 2 |" in md
    assert len((out / "rotation_palm.csv").read_text().splitlines()) == 5
    res = json.loads((out / "results.json").read_text())
    assert len(res["hausdorff"]) == 2 and res["hausdorff"][0]["refined"] is not None


def test_eval_all_bad_model(data, tmp_path) -> None:
    from treesketch.cli import app

    res = CliRunner().invoke(
        app, ["eval", "all", "--data", str(data), "--out", str(tmp_path), "--model", "cnn"]
    )
    assert res.exit_code == 2 and "--model" in res.output
