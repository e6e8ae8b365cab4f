"""Tests of weberpenn.export: GLB, OBJ and Sapling presets."""

from __future__ import annotations

import ast

import numpy as np
import pytest
import trimesh

from weberpenn import build_mesh, default_params, grow, load_params, species
from weberpenn.export import SAPLING_KEYS, colours, export_mesh, save_sapling_preset, to_sapling
from weberpenn.params import TSN_ONLY_NEUTRAL, ParamError


@pytest.fixture(scope="module")
def tree():
    return build_mesh(grow(species.sample("palm", seed=1)), species="palm")


def test_glb_two_named_meshes_with_materials(tree, tmp_path):
    path = export_mesh(tree, tmp_path / "t.glb")
    assert path.read_bytes()[:4] == b"glTF"
    scene = trimesh.load(path)
    assert set(scene.geometry) == {"branches", "leaves"}
    leaves = scene.geometry["leaves"]
    assert leaves.visual.uv is not None and len(leaves.visual.uv) == len(leaves.vertices)
    mats = {g.visual.material.name for g in scene.geometry.values()}
    assert mats == {"bark", "leaf"}
    bark = scene.geometry["branches"].visual.material.baseColorFactor[:3]
    assert np.allclose(np.asarray(bark) / 255.0, colours("palm")[0], atol=0.01)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["t.glb"]  # no temp files


def test_obj_and_mtl(tree, tmp_path):
    path = export_mesh(tree, tmp_path / "t.obj")
    text = path.read_text()
    assert "o branches" in text and "o leaves" in text and "mtllib t.mtl" in text
    assert (tmp_path / "t.mtl").read_text().count("newmtl") == 2
    loaded = trimesh.load(path, process=False)
    n = (
        sum(len(g.faces) for g in loaded.geometry.values())
        if hasattr(loaded, "geometry")
        else len(loaded.faces)
    )
    assert n == len(tree.branches.faces) + len(tree.leaves.faces)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["t.mtl", "t.obj"]


def test_bad_format_and_empty(tree, tmp_path):
    with pytest.raises(ValueError, match="format"):
        export_mesh(tree, tmp_path / "t.stl")
    empty = build_mesh(grow(default_params().replace(leaves=0)))
    empty.branches = trimesh.Trimesh(vertices=np.zeros((0, 3)), faces=np.zeros((0, 3), int))
    with pytest.raises(ValueError, match="empty"):
        export_mesh(empty, tmp_path / "e.glb")
    assert list(tmp_path.iterdir()) == []


def test_treemesh_export_method(tree, tmp_path):
    assert tree.export(tmp_path / "x.glb").is_file()


def test_colour_table():
    assert colours(None) == colours("no-such-species")
    assert colours("cherry") != colours("pine")


@pytest.mark.parametrize("name", species.SPECIES)
def test_sapling_preset_one_line_sapling_keys_only(name, tmp_path):
    p = species.sample(name, 4).replace(seed=1_656_000_000_123)  # epoch-ms seed
    path = save_sapling_preset(p, tmp_path / f"{name}.py")
    text = path.read_text()
    assert text.count("\n") == 1 and text.endswith("\n")
    d = ast.literal_eval(text.strip())
    assert isinstance(d, dict)
    assert set(d) <= set(SAPLING_KEYS)
    assert not set(d) & set(TSN_ONLY_NEUTRAL)
    assert -(2**31) <= d["seed"] < 2**31
    for key in ("shape", "shapeS", "leafDist", "leafShape", "handleType"):
        assert isinstance(d[key], str), key
    assert d["bevel"] is True and d["rMode"] == "rotate" and d["autoTaper"] is True
    assert d["showLeaves"] is (p.leaves != 0)
    assert sorted(q.name for q in tmp_path.iterdir()) == [f"{name}.py"]
    # our loader reads it back as a valid dictionary of the same overall size
    q = load_params(path)
    assert q.levels == p.levels and q.branches == p.branches
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
