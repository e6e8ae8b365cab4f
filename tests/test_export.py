"""Tests of weberpenn.export: upright GLB/OBJ, the drawn view, textures, all-or-nothing."""

from __future__ import annotations

import json
import struct

import numpy as np
import pytest
import trimesh

from weberpenn import build_mesh, default_params, grow, species
from weberpenn.export import colours, export_mesh, glb_bytes, mesh_files, obj_files
from weberpenn.orient import face_view_matrix, to_export_frame


@pytest.fixture(scope="module")
def tree():
    return build_mesh(grow(species.sample("palm", seed=1)), species="palm")


def _gltf_json(data: bytes) -> dict:
    """The JSON chunk of a GLB (read by hand, not through trimesh)."""
    assert data[:4] == b"glTF"
    length, kind = struct.unpack_from("<I4s", data, 12)
    assert kind == b"JSON"
    return json.loads(data[20 : 20 + length])


def _position_bounds(doc: dict) -> np.ndarray:
    acc = [
        doc["accessors"][p["attributes"]["POSITION"]]
        for m in doc["meshes"]
        for p in m["primitives"]
    ]
    return np.array(
        [np.min([a["min"] for a in acc], axis=0), np.max([a["max"] for a in acc], axis=0)]
    )


def test_glb_is_y_up_base_at_origin(tree):
    doc = _gltf_json(glb_bytes(tree))
    lo, hi = _position_bounds(doc)
    zb = tree.bounds()
    height = zb[1, 2]
    assert height > 1.0
    assert hi[1] == pytest.approx(height, rel=1e-5)  # glTF +Y is up
    assert abs(lo[1]) < 0.01 * height  # base at the origin
    assert lo[2] == pytest.approx(-zb[1, 1], rel=1e-5) and hi[2] == pytest.approx(-zb[0, 1])
    assert lo[0] == pytest.approx(zb[0, 0], rel=1e-5)
    assert not any("matrix" in n or "rotation" in n for n in doc["nodes"])


def test_glb_named_meshes_textures_and_alpha(tree, tmp_path):
    path = export_mesh(tree, tmp_path / "t.glb")
    doc = _gltf_json(path.read_bytes())
    assert {n["name"] for n in doc["nodes"] if "mesh" in n} == {"branches", "leaves"}
    mats = {m["name"]: m for m in doc["materials"]}
    assert set(mats) == {"bark", "leaf"}
    assert mats["leaf"]["alphaMode"] == "MASK"
    for m in mats.values():
        assert "baseColorTexture" in m["pbrMetallicRoughness"]
    assert len(doc["images"]) == 2
    scene = trimesh.load(path)
    for g in scene.geometry.values():
        assert g.visual.uv is not None and len(g.visual.uv) == len(g.vertices)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["t.glb"]  # no temp files


def test_glb_flat_colours_without_textures(tree):
    doc = _gltf_json(glb_bytes(tree, textures=False))
    assert "images" not in doc
    bark = next(m for m in doc["materials"] if m["name"] == "bark")
    rgb = bark["pbrMetallicRoughness"]["baseColorFactor"][:3]
    assert np.allclose(rgb, colours("palm")[0], atol=0.01)


def test_bark_seam_closed_in_export(tree):
    scene = trimesh.load(trimesh.util.wrap_as_stream(glb_bytes(tree)), file_type="glb")
    b = scene.geometry["branches"]
    fu = b.visual.uv[b.faces, 0]
    assert (fu.max(axis=1) - fu.min(axis=1)).max() <= 0.5  # no face spans the wrap
    assert b.visual.uv[:, 0].max() == pytest.approx(1.0)
    assert len(b.faces) == len(tree.branches.faces)


def test_yaw_turns_the_drawn_view_to_the_front(tree):
    # a camera at yaw a has +X' = (cos a, sin a, 0) on its right; after the turn that
    # direction is the front view's right (+X in Blender and glTF alike)
    for a in (0.0, 45.0, 90.0, 200.0):
        r = np.radians(a)
        right = np.array([[np.cos(r), np.sin(r), 0.0]])
        forward = np.array([[-np.sin(r), np.cos(r), 0.0]])
        assert np.allclose(to_export_frame(right, a), [[1, 0, 0]], atol=1e-12)
        assert np.allclose(to_export_frame(forward, a), [[0, 0, -1]], atol=1e-12)  # glTF view
    lo, hi = _position_bounds(_gltf_json(glb_bytes(tree, yaw=90.0)))
    b = tree.bounds()
    assert hi[1] == pytest.approx(b[1, 2], rel=1e-5)  # still upright
    assert lo[0] == pytest.approx(b[0, 1], rel=1e-5)  # world +Y turned onto +X
    with pytest.raises(ValueError, match="yaw"):
        face_view_matrix(float("nan"))


def test_max_faces_in_export(tree):
    doc = _gltf_json(glb_bytes(tree, max_faces=2000))
    tris = sum(
        doc["accessors"][p["indices"]]["count"] // 3 for m in doc["meshes"] for p in m["primitives"]
    )
    assert tris <= 2000


def test_obj_upright_with_mtl_and_textures(tree, tmp_path):
    path = export_mesh(tree, tmp_path / "t.obj", yaw=0.0)
    text = path.read_text()
    assert "o branches" in text and "o leaves" in text and "mtllib t.mtl" in text
    mtl = (tmp_path / "t.mtl").read_text()
    assert mtl.count("newmtl") == 2 and "map_Kd t_bark.png" in mtl and "map_d t_leaf.png" in mtl
    v = np.array([[float(x) for x in ln.split()[1:]] for ln in text.splitlines() if ln[:2] == "v "])
    assert v[:, 1].max() == pytest.approx(tree.bounds()[1, 2], rel=1e-4)  # Y up
    loaded = trimesh.load(path, process=False)
    n = sum(len(g.faces) for g in loaded.geometry.values())
    assert n == len(tree.branches.faces) + len(tree.leaves.faces)
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == ["t.mtl", "t.obj", "t_bark.png", "t_leaf.png"]
    files = obj_files(tree, tmp_path / "u.obj", textures=False)
    assert sorted(p.name for p in files) == ["u.mtl", "u.obj"]


def test_bad_format_and_empty_leave_nothing(tree, tmp_path):
    with pytest.raises(ValueError, match="format"):
        export_mesh(tree, tmp_path / "t.stl")
    empty = build_mesh(grow(default_params().replace(leaves=0)))
    empty.branches = trimesh.Trimesh(vertices=np.zeros((0, 3)), faces=np.zeros((0, 3), int))
    for name in ("e.glb", "e.obj"):
        with pytest.raises(ValueError, match="empty"):
            export_mesh(empty, tmp_path / name)
    with pytest.raises(ValueError, match="max_faces"):
        export_mesh(tree, tmp_path / "s.glb", max_faces=3)
    with pytest.raises(TypeError, match="TreeMesh"):
        export_mesh(tree.branches, tmp_path / "x.glb")
    assert list(tmp_path.iterdir()) == []


def test_colour_table():
    assert colours(None) == colours("no-such-species")
    assert colours("cherry") != colours("pine")


def test_mesh_files_for_write_together(tree, tmp_path):
    glb = mesh_files(tree, tmp_path / "a.gltf", yaw=30.0, max_faces=3000)
    assert list(glb) == [tmp_path / "a.glb"] and glb[tmp_path / "a.glb"][:4] == b"glTF"
    obj = mesh_files(tree, tmp_path / "a.obj")
    assert [p.name for p in obj] == ["a.obj", "a_bark.png", "a_leaf.png", "a.mtl"]
    with pytest.raises(ValueError, match="format"):
        mesh_files(tree, tmp_path / "a.ply")
    assert list(tmp_path.iterdir()) == []  # nothing written


def test_textures_are_png_encoded_once_not_per_export(tree, monkeypatch):
    """Issue 49: trimesh PNG-encoded both textures on every GLB (half of a slider edit's
    time); they are encoded once per species and the file is byte for byte the same."""
    from PIL import Image

    first = glb_bytes(tree, max_faces=20_000)

    def encoded(*args, **kwargs):
        raise AssertionError("a texture was PNG-encoded again")

    monkeypatch.setattr(Image.Image, "save", encoded)
    assert glb_bytes(tree, max_faces=20_000) == first
