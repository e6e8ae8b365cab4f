"""The CLI against hostile options and outputs (issue 30, items 9 and 12): every one is
refused with exit 2 and a plain message before any sketch is read, model loaded or tree
grown, and outputs are written all or none."""

from __future__ import annotations

from pathlib import Path

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


def test_predict_unknown_species_fails_before_the_model_loads(tmp_path, sketch_png, no_model):
    res = runner.invoke(
        app,
        ["predict", str(sketch_png), "--out", str(tmp_path / "t.glb"), "--species", "baobab"],
    )
    out = _plain(res)
    assert "unknown species 'baobab'" in out and "fir" in out
    assert not (tmp_path / "t.glb").exists()


@pytest.mark.parametrize("option", ["--budget", "--max-faces", "--time-limit", "--height"])
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


# ------------------------------------------------------------------- outputs (item 12)
def _unwritable_folder(tmp_path):
    """A folder no file can be made in: read-only bits, or (as root, whom they do not
    stop) /sys, a kernel file system that takes no new files."""
    import os
    import tempfile

    folder = tmp_path / "locked"
    folder.mkdir()
    folder.chmod(0o555)
    for candidate in (folder, Path("/sys")):
        try:
            fd, probe = tempfile.mkstemp(dir=candidate)
        except OSError:
            return candidate
        os.close(fd)
        os.unlink(probe)
    pytest.skip("no folder here refuses new files")


def test_check_targets(tmp_path):
    from weberpenn.fileio import OutputError, check_targets

    (tmp_path / "d").mkdir()
    (tmp_path / "f.txt").write_text("x")
    check_targets({"--a": [tmp_path / "new" / "deeper" / "a.json"], "--b": [tmp_path / "b.json"]})
    assert not (tmp_path / "new").exists()  # checked, not made
    cases = [
        ({"--a": [tmp_path / "d"]}, "--a .* is a folder"),
        ({"--a": [tmp_path / "f.txt" / "a.json"]}, "--a: .*f.txt is a file, not a folder"),
        ({"--a": [tmp_path / "s.json"], "--b": [tmp_path / "d" / ".." / "s.json"]}, "--a and --b"),
        ({"--a": [_unwritable_folder(tmp_path) / "x" / "a.glb"]}, "--a: cannot write in"),
        ({"--a": [Path("/dev/null")]}, "not a regular file"),
    ]
    for targets, words in cases:
        with pytest.raises(OutputError, match=words):
            check_targets(targets)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d", "f.txt", "locked"]


def _predict(sketch_png, tmp_path, *extra):
    return runner.invoke(
        app, ["predict", str(sketch_png), "--out", str(tmp_path / "t.glb"), "-q", *extra]
    )


def test_predict_two_outputs_on_one_file_fail_before_work(tmp_path, sketch_png, no_model):
    out = _plain(
        _predict(
            sketch_png,
            tmp_path,
            "--params",
            str(tmp_path / "s.json"),
            "--summary",
            str(tmp_path / "s.json"),
        )
    )
    assert "--params and --summary both write" in out
    assert sorted(p.name for p in tmp_path.iterdir()) == ["sketch.png"]


def test_predict_unwritable_folder_fails_before_work(tmp_path, sketch_png, no_model):
    locked = _unwritable_folder(tmp_path)
    out = _plain(_predict(sketch_png, tmp_path, "--compare", str(locked / "c.png")))
    assert "--compare" in out and "cannot write in" in out
    assert not (tmp_path / "t.glb").exists()


def test_predict_obj_texture_clash_fails_before_work(tmp_path, sketch_png, no_model):
    res = runner.invoke(
        app,
        ["predict", str(sketch_png), "--out", str(tmp_path / "t.obj"), "--compare",
         str(tmp_path / "t_bark.png"), "-q"],
    )  # fmt: skip
    assert "--out and --compare both write" in _plain(res)


def _grow(tmp_path, *extra):
    return runner.invoke(
        app, ["grow", "--species", "palm", "--out", str(tmp_path / "t.glb"), *extra]
    )


def test_grow_save_params_into_a_folder_writes_nothing(tmp_path):
    (tmp_path / "params").mkdir()
    out = _plain(_grow(tmp_path, "--lods", "1000", "--save-params", str(tmp_path / "params")))
    assert "--save-params" in out and "is a folder" in out
    assert sorted(p.name for p in tmp_path.iterdir()) == ["params"]  # no GLB, no LOD copy


def test_grow_outputs_on_one_file_and_unwritable_folder(tmp_path):
    out = _plain(_grow(tmp_path, "--lods", "1000", "--preset", str(tmp_path / "t_lod1.glb")))
    assert "--lods (1000) and --preset both write" in out
    locked = _unwritable_folder(tmp_path)
    assert "cannot write in" in _plain(_grow(tmp_path, "--preset", str(locked / "p.py")))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["locked"]


def test_grow_writes_all_or_nothing(tmp_path, monkeypatch):
    import weberpenn.export

    def late_failure(*args, **kwargs):
        raise ValueError("the preset could not be made")  # after the meshes are made

    monkeypatch.setattr(weberpenn.export, "preset_text", late_failure)
    res = _grow(tmp_path, "--lods", "1000", "--save-params", str(tmp_path / "p.json"),
                "--preset", str(tmp_path / "p.py"))  # fmt: skip
    assert "the preset could not be made" in _plain(res)
    assert list(tmp_path.iterdir()) == []
    monkeypatch.undo()
    res = _grow(tmp_path, "--lods", "1000", "--save-params", str(tmp_path / "p.json"),
                "--preset", str(tmp_path / "p.py"))  # fmt: skip
    assert res.exit_code == 0, res.output
    assert sorted(p.name for p in tmp_path.iterdir()) == ["p.json", "p.py", "t.glb", "t_lod1.glb"]


@pytest.mark.parametrize("chain", ["-" * 200_000 + "1", "not " * 100_000 + "1"])
def test_grow_a_preset_nested_too_deep_exits_2(tmp_path, chain):
    """Issue 49, item 6: a preset of 200,000 unary minus signs (the parser's MemoryError or
    RecursionError) is a plain error naming the file, not a traceback."""
    preset = tmp_path / "u.py"
    preset.write_text('{"levels": ' + chain + "}\n")
    res = runner.invoke(app, ["grow", "--params", str(preset), "--out", str(tmp_path / "t.glb")])
    assert res.exit_code == 2, res.output
    assert "nested too deep" in res.output and str(preset.name) in res.output
    assert "Traceback" not in res.output and not (tmp_path / "t.glb").exists()
