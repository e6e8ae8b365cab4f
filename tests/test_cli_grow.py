"""Tests of `treesketch grow` and `treesketch params` (typer CliRunner)."""

from __future__ import annotations

import json

import pytest
import trimesh
from typer.testing import CliRunner

from treesketch.cli import app
from weberpenn import load_params, save_params, species

runner = CliRunner()


def test_grow_species_glb_params_and_preset(tmp_path):
    out = tmp_path / "maple.glb"
    res = runner.invoke(
        app,
        ["grow", "--species", "maple", "--seed", "3", "--out", str(out),
         "--save-params", str(tmp_path / "p.json"), "--preset", str(tmp_path / "p.py")],
    )  # fmt: skip
    assert res.exit_code == 0, res.output
    assert "branch faces" in res.output
    assert set(trimesh.load(out).geometry) == {"branches", "leaves"}
    assert load_params(tmp_path / "p.json") == species.sample("maple", 3)
    assert load_params(tmp_path / "p.py") == species.sample("maple", 3)  # lossless preset


def test_grow_from_params_same_tree(tmp_path):
    pj = tmp_path / "p.json"
    pj.write_text(json.dumps(species.sample("palm", 2).to_dict()))
    a, b = tmp_path / "a.obj", tmp_path / "b.obj"
    assert runner.invoke(app, ["grow", "--params", str(pj), "--out", str(a)]).exit_code == 0
    assert (
        runner.invoke(app, ["grow", "--species", "palm", "--seed", "2", "--out", str(b)]).exit_code
        == 0
    )
    assert a.read_text().split("\n", 2)[2] == b.read_text().split("\n", 2)[2]


def test_errors_exit_2_without_traceback(tmp_path):
    cases = [
        ["grow", "--species", "baobab", "--out", str(tmp_path / "x.glb")],
        ["grow", "--params", str(tmp_path / "missing.json"), "--out", str(tmp_path / "x.glb")],
        ["grow", "--out", str(tmp_path / "x.glb")],
        ["grow", "--species", "maple", "--params", "p.json", "--out", str(tmp_path / "x.glb")],
        ["grow", "--species", "maple", "--out", str(tmp_path / "x.stl")],
    ]
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({**species.sample("maple", 0).to_dict(), "ratio": -1.0}))
    cases.append(["grow", "--params", str(bad), "--out", str(tmp_path / "x.glb")])
    for args in cases:
        res = runner.invoke(app, args)
        assert res.exit_code == 2, (args, res.output)
        assert "Traceback" not in res.output
        assert "error" in res.output.lower()
    res = runner.invoke(app, cases[-1])
    assert "ratio" in res.output
    assert not (tmp_path / "x.glb").exists()


def test_help_explains_options():
    res = runner.invoke(app, ["grow", "--help"])
    assert res.exit_code == 0
    for opt in ("--species", "--params", "--seed", "--out", "--save-params", "--preset"):
        assert opt in res.output


def test_params_command():
    res = runner.invoke(app, ["params"])
    assert res.exit_code == 0
    assert "leafShape" in res.output and "curveRes" in res.output


def test_grow_light_turned_lods_and_bad_lods(tmp_path):
    out = tmp_path / "c.glb"
    res = runner.invoke(
        app,
        ["grow", "--species", "cherry", "--out", str(out), "--max-faces", "20000",
         "--lods", "5000,1000", "--yaw", "30", "--preset", str(tmp_path / "c.py")],
    )  # fmt: skip
    assert res.exit_code == 0, res.output
    faces = [
        sum(len(g.faces) for g in trimesh.load(p).geometry.values())
        for p in (out, tmp_path / "c_lod1.glb", tmp_path / "c_lod2.glb")
    ]
    assert faces[0] <= 20000 and faces[1] <= 5000 and faces[2] <= 1000
    assert "view yaw: 30.00" in (tmp_path / "c.py").read_text()
    res = runner.invoke(app, ["grow", "--species", "palm", "--out", str(out), "--lods", "5,x"])
    assert res.exit_code == 2 and "--lods" in res.output


@pytest.mark.parametrize("option", ["--max-faces", "--lods"])
def test_grow_checks_every_triangle_budget_before_growing(tmp_path, monkeypatch, option):
    import weberpenn

    def no_growing(*args, **kwargs):
        raise AssertionError("the tree was grown before the budget was checked")

    monkeypatch.setattr(weberpenn, "build_mesh", no_growing)
    out = tmp_path / "t.glb"
    res = runner.invoke(app, ["grow", "--species", "palm", "--out", str(out), option, "50"])
    assert res.exit_code == 2, res.output
    assert option in res.output and "out of range" in res.output
    assert not out.exists()


def test_grow_with_controls(tmp_path):
    pj = tmp_path / "tree.json"
    save_params(species.sample("maple", 2), pj)
    out, saved = tmp_path / "edited.glb", tmp_path / "edited.json"
    args = ["grow", "--params", str(pj), "--out", str(out), "--save-params", str(saved)]
    res = runner.invoke(
        app, [*args, "--set", "crown_width=1.3", "--set", "seed=7", "--set", "leafy=false"]
    )
    assert res.exit_code == 0, res.output
    p, base = load_params(saved), species.sample("maple", 2)
    assert p["length"][1] == pytest.approx(1.3 * base["length"][1])
    assert p["seed"] == 7 and p["leaves"] == 0
    assert out.read_bytes()[:4] == b"glTF"
    res = runner.invoke(app, [*args, "--set", "height=9"])
    assert res.exit_code == 0, res.output
    lo, hi = trimesh.load(out, force="scene").bounds
    assert hi[1] - lo[1] == pytest.approx(9.0, rel=0.02)  # glTF is Y-up
    for bad, words in (
        ("crown_width=9", "crown_width"),
        ("wings=2", "wings"),
        ("crown_width", "NAME=VALUE"),
        ("leafy=maybe", "leafy"),
    ):
        res = runner.invoke(app, [*args, "--set", bad])
        assert res.exit_code == 2 and words in res.output and "Traceback" not in res.output


def test_controls_command():
    res = runner.invoke(app, ["controls"])
    assert res.exit_code == 0
    for name in ("height", "crown_width", "trunk_lean", "leafy", "seed"):
        assert name in res.output
    assert "length[1]" in res.output
