"""`treesketch predict`: outputs, errors, and nothing partial when interrupted."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

import treesketch.outputs
from treesketch.cli import app
from weberpenn import build_mesh, grow, species

runner = CliRunner()


@pytest.fixture()
def sketch_png(tmp_path):
    from PIL import Image

    from render.sketch import SketchRenderer

    img = SketchRenderer(build_mesh(grow(species.sample("palm", 3)), species="palm")).sketch(0, 256)
    p = tmp_path / "sketch.png"
    Image.fromarray(img).save(p)
    return p


def _args(tmp_path, sketch_png, *extra: str) -> list[str]:
    out = tmp_path / "out"
    return [
        "predict",
        str(sketch_png),
        "--out",
        str(out / "tree.glb"),
        "--params",
        str(out / "tree.json"),
        "--preset",
        str(out / "tree_sapling.py"),
        "--compare",
        str(out / "compare.png"),
        "--quiet",
        *extra,
    ]


def test_writes_all_outputs(tmp_path, sketch_png) -> None:
    res = runner.invoke(app, _args(tmp_path, sketch_png, "--budget", "6", "--height", "9"))
    assert res.exit_code == 0, res.output
    out = tmp_path / "out"
    assert sorted(p.name for p in out.iterdir()) == [
        "compare.png",
        "tree.glb",
        "tree.json",
        "tree_sapling.py",
    ]
    params = json.loads((out / "tree.json").read_text())
    assert params["levels"] == species.base("palm")["levels"]
    assert (out / "tree.glb").read_bytes()[:4] == b"glTF"
    assert "sketch distance" in res.output and "palm" in res.output
    from PIL import Image

    w, h = Image.open(out / "compare.png").size
    assert w == 4 * 256 and h > 256


def test_outlines_picture(tmp_path, sketch_png) -> None:
    """--outlines: the drawing's outline (red) over the tree's (blue), at the drawn view
    (the picture the Blender add-on shows)."""
    from PIL import Image

    from refine.envelope import DRAWING_RED, TREE_BLUE

    path = tmp_path / "out" / "outlines.png"
    res = runner.invoke(app, _args(tmp_path, sketch_png, "--no-refine", "--outlines", str(path)))
    assert res.exit_code == 0, res.output
    rgb = np.asarray(Image.open(path))
    assert rgb.shape == (256, 256, 3)
    for colour in (DRAWING_RED, TREE_BLUE):
        assert np.all(rgb == colour, axis=2).sum() > 200, colour
    res = runner.invoke(app, _args(tmp_path, sketch_png, "--outlines", str(tmp_path / "o.jpg")))
    assert res.exit_code != 0 and "--outlines" in res.output


def test_interrupted_run_writes_nothing(tmp_path, sketch_png, monkeypatch) -> None:
    def boom(result, size=256):
        raise KeyboardInterrupt  # e.g. Ctrl-C while the last output is being made

    monkeypatch.setattr(treesketch.outputs, "compare_image", boom)
    res = runner.invoke(app, _args(tmp_path, sketch_png, "--no-refine"))
    assert res.exit_code != 0
    out = tmp_path / "out"
    assert not out.exists() or list(out.iterdir()) == []  # no files, no temp folders


def test_compare_into_an_existing_folder_fails_before_work(tmp_path, sketch_png) -> None:
    folder = tmp_path / "out" / "compare.png"
    folder.mkdir(parents=True)
    args = _args(tmp_path, sketch_png)
    res = runner.invoke(app, args)
    assert res.exit_code == 2 and "folder" in res.output
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["compare.png"]


@pytest.mark.parametrize("height", ["inf", "1e308", "nan", "-3"])
def test_bad_height_fails_before_work(tmp_path, sketch_png, height: str) -> None:
    import time

    t0 = time.perf_counter()
    res = runner.invoke(app, _args(tmp_path, sketch_png, "--height", height))
    assert res.exit_code == 2 and "--height" in res.output
    assert time.perf_counter() - t0 < 5.0
    assert not (tmp_path / "out").exists() or list((tmp_path / "out").iterdir()) == []


def test_tiny_time_limit_still_returns_an_evaluated_tree(tmp_path, sketch_png) -> None:
    res = runner.invoke(
        app, _args(tmp_path, sketch_png, "--time-limit", "0.1", "--estimator", "tsn")
    )
    assert res.exit_code == 0, res.output
    assert "inf" not in res.output.split("sketch distance")[1].splitlines()[0]
    assert (tmp_path / "out" / "tree.glb").exists()


def test_estimator_option(tmp_path, sketch_png) -> None:
    res = runner.invoke(app, _args(tmp_path, sketch_png, "--estimator", "magic"))
    assert res.exit_code == 2 and "--estimator" in res.output
    res = runner.invoke(app, _args(tmp_path, sketch_png, "--checkpoint", str(tmp_path / "x.pt")))
    assert res.exit_code == 2
    assert not (tmp_path / "out").exists() or list((tmp_path / "out").iterdir()) == []


def test_bad_inputs(tmp_path, sketch_png) -> None:
    res = runner.invoke(app, ["predict", str(tmp_path / "nope.png"), "--out", "x.glb"])
    assert res.exit_code == 2 and "not found" in res.output
    res = runner.invoke(app, ["predict", str(sketch_png), "--out", str(tmp_path / "x.stl")])
    assert res.exit_code == 2 and ".glb or .obj" in res.output
    blank = tmp_path / "blank.png"
    from PIL import Image

    Image.fromarray(np.full((64, 64), 255, np.uint8)).save(blank)
    res = runner.invoke(app, ["predict", str(blank), "--out", str(tmp_path / "b.glb")])
    assert res.exit_code == 2 and "blank" in res.output
    assert not (tmp_path / "b.glb").exists()


def test_export_options(tmp_path, sketch_png) -> None:
    import trimesh

    out = tmp_path / "lod"
    args = ["predict", str(sketch_png), "--no-refine", "--quiet", "--max-faces", "3000"]
    args += ["--out", str(out / "tree.obj"), "--summary", str(out / "summary.json")]
    res = runner.invoke(app, args)
    assert res.exit_code == 0, res.output
    names = sorted(p.name for p in out.iterdir())
    assert "tree.obj" in names and "tree.mtl" in names and "summary.json" in names
    assert any(n.endswith(".png") for n in names)  # the textures travel with the OBJ
    scene = trimesh.load(out / "tree.obj", force="scene")
    assert sum(len(g.faces) for g in scene.geometry.values()) <= 3000
    summary = json.loads((out / "summary.json").read_text())
    assert summary["export"]["max_faces"] == 3000 and "yaw" in summary
    bad = runner.invoke(app, [*args[:5], "10", "--out", str(tmp_path / "x.glb")])
    assert bad.exit_code == 2 and "max_faces" in bad.output


def test_embedding_option_is_checked_before_work(tmp_path, sketch_png) -> None:
    res = runner.invoke(app, _args(tmp_path, sketch_png, "--embedding", str(tmp_path / "e.pt")))
    assert res.exit_code == 2 and "embedding" in res.output
    assert not (tmp_path / "out").exists() or list((tmp_path / "out").iterdir()) == []


def test_a_second_view(tmp_path, sketch_png) -> None:
    from PIL import Image

    from render.sketch import SketchRenderer

    side = tmp_path / "side.png"
    mesh = build_mesh(grow(species.sample("palm", 3)), species="palm")
    Image.fromarray(SketchRenderer(mesh).sketch(90, 256)).save(side)
    summary = tmp_path / "out" / "summary.json"
    args = _args(tmp_path, sketch_png, "--budget", "4", "--summary", str(summary))
    res = runner.invoke(app, [*args, "--view", f"{side}@90"])
    assert res.exit_code == 0, res.output
    assert "view 2: yaw 90 (given)" in res.output
    views = json.loads(summary.read_text())["views"]
    assert [v["yaw"] for v in views] == [0.0, 90.0]
    # the comparison picture has a row per view
    from PIL import Image as PILImage

    w, h = PILImage.open(tmp_path / "out" / "compare.png").size
    assert h > w / 4 * 1.5


@pytest.mark.parametrize(
    ("view", "message"),
    [("side.png@east", "got 'east'"), ("missing.png@90", "missing.png")],
)
def test_a_bad_view_fails_before_work(tmp_path, sketch_png, view: str, message: str) -> None:
    (tmp_path / "side.png").write_bytes(sketch_png.read_bytes())
    res = runner.invoke(app, [*_args(tmp_path, sketch_png), "--view", str(tmp_path / view)])
    assert res.exit_code != 0
    assert message in res.output and "Traceback" not in res.output
    assert not (tmp_path / "out").exists()


def test_preview_keeps_the_current_best_tree(tmp_path, sketch_png) -> None:
    """``--preview DIR``: the tree the refinement holds now, for the Blender add-on (the
    first estimate at once; the service's writer, at most one every 2 s)."""
    preview = tmp_path / "preview"
    res = runner.invoke(
        app, _args(tmp_path, sketch_png, "--budget", "4", "--preview", str(preview))
    )
    assert res.exit_code == 0, res.output
    assert sorted(p.name for p in preview.iterdir()) == ["sketch.png", "tree.glb"]
    assert (preview / "tree.glb").read_bytes()[:4] == b"glTF"
    blocked = tmp_path / "file"
    blocked.write_text("not a folder")
    res = runner.invoke(app, _args(tmp_path, sketch_png, "--preview", str(blocked)))
    assert res.exit_code == 2 and "--preview" in res.output


def test_a_preview_that_cannot_be_written_never_costs_the_result(tmp_path, sketch_png) -> None:
    """Issue 49, item 5: ``--preview LINK`` with ``LINK`` a dangling symlink (its folder
    cannot be made) warns and refines on; every output is written."""
    link = tmp_path / "preview"
    link.symlink_to(tmp_path / "gone")
    res = runner.invoke(app, _args(tmp_path, sketch_png, "--budget", "3", "--preview", str(link)))
    assert res.exit_code == 0, res.output
    assert "cannot write the preview" in res.output and "Traceback" not in res.output
    out = tmp_path / "out"
    assert (out / "tree.glb").read_bytes()[:4] == b"glTF" and (out / "tree.json").is_file()
