"""tsn.train and `treesketch train` on a tiny generated dataset: a step lowers the loss,
checkpoint/log/plot written, resume, bad settings; `treesketch eval tsn` prints the table."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest
import torch
from tsn_helpers import build_tiny_dataset
from typer.testing import CliRunner

from treesketch.cli import app
from tsn import encoding
from tsn.model import TSN
from tsn.train import TrainConfig, TrainError, head_targets, load_split, loss_fn, train


@pytest.fixture(scope="module")
def tiny(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return build_tiny_dataset(tmp_path_factory.mktemp("tsn_ds") / "ds")


@pytest.mark.parametrize("backbone", ["lite0", "resnet_small"])
def test_one_step_lowers_the_loss(tiny: Path, backbone: str) -> None:
    split = load_split(tiny, "train")
    norm = encoding.Normaliser.fit(split.mats)
    y = head_targets(norm.normalise(split.mats))
    from tsn.data import preprocess

    x = torch.from_numpy(np.stack([preprocess(i, 64) for i in split.images]))[:, None]
    torch.manual_seed(0)
    model = TSN(backbone)
    model.train()
    opt = torch.optim.Adam(model.parameters(), lr=1e-3)

    def loss() -> torch.Tensor:
        torch.manual_seed(1)  # same dropout masks before and after the step
        return loss_fn(model(x), y)

    before = loss()
    opt.zero_grad()
    before.backward()
    opt.step()
    with torch.no_grad():
        after = loss()
    assert after.item() < before.item()


def test_train_cli_checkpoint_log_resume(tiny: Path, tmp_path: Path) -> None:
    out = tmp_path / "ck" / "tiny.pt"
    args = [
        "train",
        "--data",
        str(tiny),
        "--out",
        str(out),
        "--size",
        "64",
        "--batch",
        "8",
        "--copies",
        "1",
        "--threads",
        "2",
    ]
    r = CliRunner().invoke(app, [*args, "--epochs", "2"])
    assert r.exit_code == 0, r.output
    assert "best val 1-RMSE" in r.output and out.is_file()
    work = out.with_suffix(".work")
    rows = list(csv.DictReader((work / "log.csv").open()))
    assert [int(row["epoch"]) for row in rows] == [1, 2]
    assert {"train_loss", "val_loss", "val_overall", "val_angle"} <= set(rows[0])
    assert (work / "loss.png").stat().st_size > 1000
    assert out.stat().st_size < 50e6
    # a second run refuses to overwrite the state without --resume
    r = CliRunner().invoke(app, [*args, "--epochs", "3"])
    assert r.exit_code == 2 and "--resume" in r.output
    r = CliRunner().invoke(app, [*args, "--epochs", "3", "--resume"])
    assert r.exit_code == 0, r.output
    assert "resumed after epoch 2" in r.output and "cached" not in r.output  # cache reused
    rows = list(csv.DictReader((work / "log.csv").open()))
    assert [int(row["epoch"]) for row in rows] == [1, 2, 3]
    # the checkpoint predicts
    from tsn.predict import load_model

    m = load_model(out)
    assert m.size == 64 and m.info["config"]["backbone"] == "lite0"
    # and `treesketch eval tsn` prints the paper-style table
    r = CliRunner().invoke(
        app,
        [
            "eval",
            "tsn",
            "--data",
            str(tiny),
            "--checkpoint",
            str(out),
            "--json",
            str(tmp_path / "e.json"),
        ],
    )
    assert r.exit_code == 0, r.output
    assert "raw network output" in r.output and "decoded + projected" in r.output
    assert "species identification" in r.output and (tmp_path / "e.json").is_file()


def test_bad_settings(tiny: Path, tmp_path: Path) -> None:
    with pytest.raises(TrainError, match="backbone"):
        train(TrainConfig(str(tiny), str(tmp_path / "a.pt"), backbone="nope"))
    with pytest.raises(TrainError, match="multiple of 32"):
        train(TrainConfig(str(tiny), str(tmp_path / "a.pt"), size=100))
    with pytest.raises(TrainError, match="epochs"):
        train(TrainConfig(str(tiny), str(tmp_path / "a.pt"), epochs=0))
    with pytest.raises(TrainError, match="no such dataset"):
        train(TrainConfig(str(tmp_path / "none"), str(tmp_path / "a.pt")))
    with pytest.raises(TrainError, match="manifest"):
        train(TrainConfig(str(tmp_path), str(tmp_path / "a.pt")))
    r = CliRunner().invoke(
        app,
        [
            "train",
            "--data",
            str(tiny),
            "--out",
            str(tmp_path / "b.pt"),
            "--cut",
            "99",
            "--size",
            "64",
        ],
    )
    assert r.exit_code == 2 and "--cut" in r.output
    r = CliRunner().invoke(
        app, ["eval", "tsn", "--data", str(tiny), "--checkpoint", str(tmp_path / "missing.pt")]
    )
    assert r.exit_code == 2 and "no such checkpoint" in r.output


def test_more_data_adds_training_trees_and_refuses_leaks(tiny: Path, tmp_path: Path) -> None:
    from render.dataset import DatasetConfig, build_dataset

    more = tmp_path / "more"
    build_dataset(
        DatasetConfig(out=str(more), trees_per_species=1, views=("front",), size=64, seed=7),
        progress=False,
    )
    lines: list[str] = []
    common = dict(size=64, batch=8, copies=1, epochs=1, threads=2)
    res = train(
        TrainConfig(str(tiny), str(tmp_path / "m.pt"), more_data=(str(more),), **common),
        log=lines.append,
    )
    n_first = len(load_split(tiny, "train").images)
    n_more = len(load_split(more, None).images)
    assert n_more == 5  # every split of the extra dataset: one tree per species, one view
    assert any(f"{n_first + n_more} train ({n_first} from" in s for s in lines), lines
    from tsn.predict import load_model

    assert load_model(res["out"]).info["n_train"] == n_first + n_more
    # the same seed means the same trees: tiny's val/test trees would leak into training
    twin = tmp_path / "twin"
    build_dataset(
        DatasetConfig(out=str(twin), trees_per_species=4, views=("front",), size=64, seed=0),
        progress=False,
    )
    with pytest.raises(TrainError, match="validation/test trees"):
        train(TrainConfig(str(tiny), str(tmp_path / "x.pt"), more_data=(str(twin),)))
    with pytest.raises(TrainError, match="dataset itself"):
        train(TrainConfig(str(tiny), str(tmp_path / "x.pt"), more_data=(str(tiny) + "/",)))
    with pytest.raises(TrainError, match="no such dataset"):
        train(TrainConfig(str(tiny), str(tmp_path / "y.pt"), more_data=(str(tmp_path / "no"),)))


def test_styles_filter_and_fine_tune_from_a_checkpoint(tmp_path: Path) -> None:
    from render.dataset import DatasetConfig, build_dataset, read_manifest

    ds = tmp_path / "styled"
    build_dataset(
        DatasetConfig(
            out=str(ds),
            trees_per_species=4,
            species=("pine", "palm"),
            views=("front",),
            size=64,
            val_fraction=0.25,
            test_fraction=0.25,
            styles=("sg", "pen", "felt"),
            styles_per_view=2,
        ),
        progress=False,
    )
    n_train = len(read_manifest(ds, "train"))
    assert n_train == 2 * 2 * 3  # every view in sg, pen and felt
    common = dict(size=64, batch=4, copies=1, epochs=1, threads=2)
    lines: list[str] = []
    first = train(
        TrainConfig(str(ds), str(tmp_path / "a.pt"), styles=("sg", "pen"), **common),
        log=lines.append,
    )
    assert any(
        s.startswith("[train] 8 train (12 from") and "/ 4 val sketches in the styles sg, pen" in s
        for s in lines
    ), lines
    # fine-tune on every style from that checkpoint: its normaliser is kept
    cache = tmp_path / "cache"
    res = train(
        TrainConfig(str(ds), str(tmp_path / "b.pt"), init=first["out"], cache=str(cache), **common)
    )
    # another run keeping other styles reuses the same caches
    lines.clear()
    train(
        TrainConfig(
            str(ds),
            str(tmp_path / "d.pt"),
            init=first["out"],
            cache=str(cache),
            styles=("sg", "felt"),
            **common,
        ),
        log=lines.append,
    )
    assert sum("features from" in s for s in lines) == 2, lines
    from tsn.checkpoint import load_checkpoint

    a, b = load_checkpoint(first["out"]), load_checkpoint(res["out"])
    assert a.normaliser.to_dict() == b.normaliser.to_dict()
    assert b.info["n_train"] == n_train and b.info["config"]["init"] == first["out"]
    with pytest.raises(TrainError, match="at 64 px"):
        train(TrainConfig(str(ds), str(tmp_path / "c.pt"), init=first["out"], size=96))
    with pytest.raises(TrainError, match="no such checkpoint"):
        train(TrainConfig(str(ds), str(tmp_path / "c.pt"), init=str(tmp_path / "none.pt")))
    with pytest.raises(TrainError, match="unknown drawing style 'crayon'"):
        train(TrainConfig(str(ds), str(tmp_path / "c.pt"), styles=("crayon",)))
    with pytest.raises(TrainError, match="no sketches in the styles cloud"):
        train(TrainConfig(str(ds), str(tmp_path / "c.pt"), styles=("cloud",)))
    r = CliRunner().invoke(
        app,
        ["eval", "tsn", "--data", str(ds), "--checkpoint", res["out"], "--styles", "felt"],
    )
    assert r.exit_code == 0, r.output
    assert "2 sketches of 2 held-out trees" in r.output


def test_training_sketches_are_normalised_like_predicts_input(
    tiny: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from render.reader import normalise_drawing
    from tsn.model import TSN
    from tsn.train import cache_key, frozen_digest, normalised

    split = load_split(tiny, "train")
    img = split.images[0]
    # the same sketch as light pencil on grey paper: the normaliser gives the clean sketch
    pencil = (96 + (img.astype(np.float32) * 0.55)).astype(np.uint8)
    assert np.mean(normalised(pencil) != normalise_drawing(img)) < 0.02
    assert set(np.unique(normalised(img))) <= {0, 255}
    blank = np.full_like(img, 255)
    assert normalised(blank) is blank  # refused by the normaliser: kept as it is
    # normalised and raw features never share a cache file
    on = TrainConfig(str(tiny), str(tmp_path / "a.pt"))
    off = TrainConfig(str(tiny), str(tmp_path / "a.pt"), normalise=False)
    assert on.normalise and cache_key(on, 3, split, "train", None, "w") != cache_key(
        off, 3, split, "train", None, "w"
    )
    # a change to the normaliser's code gives new features, never the stale ones
    from tsn import train as tt

    keys = [cache_key(c, 3, split, "train", None, "w") for c in (on, off)]
    monkeypatch.setattr(tt, "normaliser_digest", lambda: "another normaliser")
    now = [cache_key(c, 3, split, "train", None, "w") for c in (on, off)]
    assert now[0] != keys[0] and now[1] == keys[1]  # raw sketches do not depend on it
    monkeypatch.undo()
    # the key follows the frozen weights, not the init checkpoint's path
    assert cache_key(on, 3, split, "train", None, "w") != cache_key(
        on, 3, split, "train", None, "v"
    )
    torch.manual_seed(0)
    a, b = TSN("resnet_small", pretrained=False), TSN("resnet_small", pretrained=False)
    b.load_state_dict(a.state_dict())
    assert frozen_digest(a, 2) == frozen_digest(b, 2)
    with torch.no_grad():
        b.heads["angle"][1].bias.add_(1.0)  # trained past the cut: same features
    assert frozen_digest(a, 2) == frozen_digest(b, 2)
    with torch.no_grad():
        b.backbone.stem[0].weight.mul_(1.01)  # a frozen stage changed: new features
    assert frozen_digest(a, 2) != frozen_digest(b, 2)
    ck = tmp_path / "n.pt"
    r = CliRunner().invoke(
        app,
        ["train", "--data", str(tiny), "--out", str(ck), "--size", "64", "--batch", "8"]
        + ["--copies", "0", "--epochs", "1", "--threads", "2"],
    )
    assert r.exit_code == 0, r.output
    from tsn.predict import load_model

    assert load_model(ck).info["config"]["normalise"] is True
    base = ["eval", "tsn", "--data", str(tiny), "--checkpoint", str(ck)]
    r = CliRunner().invoke(app, base)  # as the checkpoint was trained
    assert r.exit_code == 0, r.output
    assert "input: normalised drawing" in r.output
    r = CliRunner().invoke(app, [*base, "--raw"])
    assert r.exit_code == 0, r.output
    assert "input: dataset sketch" in r.output


def test_a_fine_tune_carries_a_species_branch_that_reads_frozen_stages(
    tiny: Path, tmp_path: Path
) -> None:
    """The branch reads stage 12's map, which a fine-tune with the stages before 12 frozen
    does not change: the branch and a classifier that reads only the branch's features go
    into the new checkpoint unchanged; a classifier that reads the heads' features (which
    the fine-tune changes) is fitted again instead."""
    from tsn_helpers import make_checkpoint

    from tsn.checkpoint import load_checkpoint, save_loaded
    from tsn.model import SpeciesBranch
    from tsn.predict import load_model
    from tsn.species_id import SpeciesClassifier

    base = load_checkpoint(make_checkpoint(tmp_path / "base.pt", size=64))
    branch = SpeciesBranch("lite0", 12)
    state = branch.stage_state()
    branch.load_stage_state({k: v for k, v in base.model.state_dict().items() if k in state})
    nf = base.model.backbone.out_features
    names = ("maple", "pine", "bonsai", "palm", "cherry")
    rng = np.random.default_rng(3)

    def classifier(heads_weight: float) -> SpeciesClassifier:
        w = np.hstack([heads_weight * rng.normal(size=(5, nf)), rng.normal(size=(5, nf))])
        return SpeciesClassifier(
            names, np.zeros(2 * nf), np.ones(2 * nf), w, np.zeros(5), 1.0,
            base.normaliser.scale, "features",
        )  # fmt: skip

    common = dict(size=64, batch=4, copies=0, epochs=1, threads=2, lr=1e-2)
    clf = classifier(0.0)
    record = {"species_branch": {"start": 12, "trained": {"epochs": 4}}, "classifier": {"t": 1}}
    init = save_loaded(base, tmp_path / "init.pt", record,
                       species_id=base.species_id.with_classifier(clf), species_branch=branch)  # fmt: skip
    lines: list[str] = []
    res = train(TrainConfig(str(tiny), str(tmp_path / "ft.pt"), init=str(init), **common),
                log=lines.append)  # fmt: skip
    assert any("carried from --init" in s for s in lines), lines
    out = load_checkpoint(res["out"])
    assert out.species_branch is not None and out.species_branch.start == 12
    for k, v in branch.stage_state().items():
        torch.testing.assert_close(out.species_branch.stage_state()[k].float(), v.half().float())
    assert {k: out.info[k] for k in record} == record
    kept = out.species_id.classifier
    assert kept is not None and kept.reads == "features"
    np.testing.assert_array_equal(kept.weight, clf.weight)
    # the fine-tune moved the heads' features, not the map the branch reads
    img = np.full((64, 64), 255, np.uint8)
    img[8:56, 30:34] = 0
    img[8:30, 14:50] = 0
    before, after = load_model(init, device="cpu"), load_model(res["out"], device="cpu")
    fb, fa = before.raw_and_features([img])[1], after.raw_and_features([img])[1]
    np.testing.assert_allclose(fa[:, nf:], fb[:, nf:], rtol=1e-3, atol=1e-3)
    assert np.abs(fa[:, :nf] - fb[:, :nf]).max() > 1e-3
    # a classifier that reads the heads' part is not carried: fitted again on the outputs
    init2 = save_loaded(base, tmp_path / "init2.pt", {},
                        species_id=base.species_id.with_classifier(classifier(1.0)),
                        species_branch=branch)  # fmt: skip
    lines.clear()
    res2 = train(TrainConfig(str(tiny), str(tmp_path / "ft2.pt"), init=str(init2), **common),
                 log=lines.append)  # fmt: skip
    assert not any("carried" in s for s in lines)
    out2 = load_checkpoint(res2["out"])
    assert out2.species_branch is None and out2.species_id.classifier.reads == "outputs"
