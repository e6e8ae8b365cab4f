"""Tests of weberpenn.preset: Sapling-readable, no Limit Import, lossless round trip."""

from __future__ import annotations

import ast

import numpy as np
import pytest

from weberpenn import build_mesh, grow, load_params, species
from weberpenn.params import TSN_ONLY_NEUTRAL, ParamError
from weberpenn.preset import SAPLING_KEYS, preset_text, save_sapling_preset, to_sapling


def _sapling_line(text: str) -> str:
    """The line Blender's Sapling ImportData reads: the first not starting with '#'."""
    return next(t for t in text.splitlines(keepends=True) if t and not t.startswith("#"))


@pytest.mark.parametrize("name", species.SPECIES)
def test_preset_sapling_keys_only_and_no_limit(name, tmp_path):
    p = species.sample(name, 4).replace(seed=1_656_000_000_123)  # epoch-ms seed
    path = save_sapling_preset(p, tmp_path / f"{name}.py")
    d = ast.literal_eval(_sapling_line(path.read_text()))
    assert isinstance(d, dict)
    assert set(d) <= set(SAPLING_KEYS) | {"limitImport"}
    assert d["limitImport"] is False  # Sapling sets it before it checks it: all levels
    assert next(iter(d)) == "limitImport"  # first: later keys re-arm Sapling's rebuild
    assert not set(d) & set(TSN_ONLY_NEUTRAL)
    assert -(2**31) <= d["seed"] < 2**31
    for key in ("shape", "shapeS", "leafDist", "leafShape", "handleType"):
        assert isinstance(d[key], str), key
    assert d["bevel"] is True and d["rMode"] == "rotate" and d["autoTaper"] is True
    assert d["showLeaves"] is (p.leaves != 0)
    assert sorted(q.name for q in tmp_path.iterdir()) == [f"{name}.py"]


def test_round_trip_is_lossless(tmp_path):
    p = species.sample("maple", 7)
    path = save_sapling_preset(p, tmp_path / "m.py", yaw=45.0)
    assert "view yaw: 45.00" in path.read_text()
    q = load_params(path)
    assert q == p
    a, b = build_mesh(grow(p)), build_mesh(grow(q))
    assert np.array_equal(a.branches.vertices, b.branches.vertices)
    assert np.array_equal(a.leaves.vertices, b.leaves.vertices)


def test_edited_sapling_line_wins(tmp_path):
    p = species.sample("pine", 1)
    text = preset_text(p)
    line = _sapling_line(text)
    d = ast.literal_eval(line)
    d["levels"] = 2
    path = tmp_path / "e.py"
    path.write_text(text.replace(line, repr(d) + "\n"))
    q = load_params(path)
    assert q.levels == 2  # the seal no longer matches: Sapling's keys are mapped
    assert q.scale == pytest.approx(p.scale + p.scaleV)


def test_sapling_mapping_rules():
    p = species.sample("maple", 2)
    d = to_sapling(p)
    for i in range(4):
        assert d["curveV"][i] == pytest.approx(
            (abs(p.curveV1[i]) + abs(p.curveV2[i])) * p.curveRes[i]
        )
        mean = (p.splitAngleV1[i] + p.splitAngleV2[i]) / 2
        assert d["splitAngle"][i] == pytest.approx(p.splitAngle[i] + mean)
        assert d["splitAngleV"][i] == pytest.approx(abs(p.splitAngleV1[i] - p.splitAngleV2[i]) / 2)
    assert d["scaleV"] == 0.0 and d["scaleV0"] == 0.0 and d["leafScaleV"] == 0.0
    assert d["scale0"] == pytest.approx(p.scale0 * p.scaleV0)
    assert d["leafScale"] == pytest.approx(p.leafScale * p.leafScaleV)
    assert d["rotate"][0] == pytest.approx(p.rotate[0] + p.rotateV[0]) and d["rotateV"][0] == 0.0
    assert d["leafRotate"] == pytest.approx(p.leafRotate + p.leafRotateV)
    with pytest.raises(ParamError):
        to_sapling({"levels": 2})
    with pytest.raises(ParamError, match="yaw"):
        preset_text(p, yaw=float("inf"))
