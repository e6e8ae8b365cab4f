"""treesketch.outputs: every artefact kind, written all or nothing, readable by everyone."""

from __future__ import annotations

import stat

import numpy as np
import pytest
from typer.testing import CliRunner

import treesketch.outputs as outputs
from treesketch import Estimate, Pipeline, RefineSettings
from treesketch.cli import app
from weberpenn import species


class Palm:
    name = "palm"

    def estimate(self, sketch: np.ndarray) -> Estimate:
        return Estimate(species.sample("palm", 4), "palm", {"palm": 1.0})


@pytest.fixture(scope="module")
def result():
    from render.sketch import SketchRenderer
    from weberpenn import build_mesh, grow

    img = SketchRenderer(build_mesh(grow(species.sample("palm", 2)), species="palm")).sketch(0, 256)
    return Pipeline(Palm(), RefineSettings(refine=False)).run(img)


def _modes(folder) -> set[int]:
    return {stat.S_IMODE(p.stat().st_mode) for p in folder.iterdir()}


def test_every_kind_and_modes(result, tmp_path) -> None:
    files = outputs.result_files(result, outputs.KINDS)
    assert files["glb"][:4] == b"glTF" and files["compare"][:4] == b"\x89PNG"
    assert b"mtllib" in files["obj"] and "tree.mtl" in files
    out = tmp_path / "o"
    written = outputs.write_outputs(
        result, {"mesh": out / "t.obj", "json": out / "t.json", "preset": out / "t.py"}
    )
    assert {p.name for p in written} >= {"t.obj", "t.mtl", "t.json", "t.py"}
    assert _modes(out) == {0o644}


def test_a_failure_leaves_nothing_behind(result, tmp_path, monkeypatch) -> None:
    def boom(*a, **k):
        raise OSError("disk full")

    monkeypatch.setattr(outputs, "compare_image", boom)
    out = tmp_path / "o"
    with pytest.raises(OSError):
        outputs.write_outputs(result, {"mesh": out / "t.obj", "compare": out / "c.png"})
    assert not out.exists() or list(out.iterdir()) == []  # no .obj, no stray .mtl, no temp


def test_grow_save_params_is_world_readable(tmp_path) -> None:
    res = CliRunner().invoke(
        app,
        ["grow", "--species", "palm", "--out", str(tmp_path / "p.glb"), "--save-params",
         str(tmp_path / "p.json")],
    )  # fmt: skip
    assert res.exit_code == 0, res.output
    assert _modes(tmp_path) == {0o644}
