"""The CLI against hostile options and outputs (issue 30, items 9 and 12): every one is
refused with exit 2 and a plain message before any sketch is read, model loaded or tree
grown, and outputs are written all or none."""

from __future__ import annotations

import numpy as np
import pytest
from typer.testing import CliRunner

import treesketch.estimators
from treesketch.cli import app

runner = CliRunner()
HUGE = "1" + "0" * 320  # 321 digits: over a float's range


@pytest.fixture()
def sketch_png(tmp_path):
    from PIL import Image

    page = np.full((64, 64), 255, np.uint8)
    page[10:60, 30:33] = 0
    page[12:30, 15:50] = np.where(np.add.outer(np.arange(18), np.arange(35)) % 5 == 0, 0, 255)
    p = tmp_path / "sketch.png"
    Image.fromarray(page).save(p)
    return p


@pytest.fixture()
def no_model(monkeypatch):
    """Fail the test if the command gets as far as loading an estimator."""

    def loaded(*args, **kwargs):
        raise AssertionError("the estimator was loaded before the options were checked")

    monkeypatch.setattr(treesketch.estimators, "load_estimator", loaded)


def _plain(res) -> str:
    assert res.exit_code == 2, res.output
    assert "Traceback" not in res.output and "Error:" not in res.output.replace("error:", "")
    return res.output


@pytest.mark.parametrize("seed", ["-1", "4294967296", HUGE])
def test_predict_bad_seed_fails_before_the_model_loads(tmp_path, sketch_png, no_model, seed):
    res = runner.invoke(
        app, ["predict", str(sketch_png), "--out", str(tmp_path / "t.glb"), "--seed", seed, "-q"]
    )
    out = _plain(res)
    assert "--seed" in out and "0..4294967295" in out
    assert not (tmp_path / "t.glb").exists()


@pytest.mark.parametrize(
    "option", ["--budget", "--tree-seeds", "--max-faces", "--time-limit", "--height"]
)
def test_predict_huge_numbers_fail_before_the_model_loads(tmp_path, sketch_png, no_model, option):
    res = runner.invoke(
        app, ["predict", str(sketch_png), "--out", str(tmp_path / "t.glb"), option, HUGE, "-q"]
    )
    out = _plain(res)
    assert len(out) < 400


@pytest.mark.parametrize("option", ["--seed", "--max-faces"])
def test_grow_huge_numbers_exit_2(tmp_path, option):
    res = runner.invoke(
        app, ["grow", "--species", "palm", "--out", str(tmp_path / "t.glb"), option, HUGE]
    )
    out = _plain(res)
    assert len(out) < 400
    assert not (tmp_path / "t.glb").exists()
