"""eval.rotation: the yaw sweep with a stand-in predictor (no network needed)."""

from __future__ import annotations

import csv
import math

import numpy as np
import pytest

from eval.rotation import plot_cases, plot_sweep, rotation_sweep, write_csv, yaw_angles
from treesketch import Estimate, Pipeline, RefineSettings
from weberpenn import species


def test_yaw_angles():
    a = yaw_angles(5)
    assert len(a) == 72 and a[0] == 0 and a[-1] == 355
    assert len(yaw_angles(90)) == 4
    for bad in (0, -5, 7, 400, float("nan")):
        with pytest.raises(ValueError, match="step"):
            yaw_angles(bad)


@pytest.mark.slow
def test_sweep_72_rows_csv_and_plots(tmp_path):
    gt = species.sample("palm", seed=1)
    other = species.sample("palm", seed=2)
    calls = []

    class Alternating:
        name = "alternating"

        def estimate(self, img: np.ndarray) -> Estimate:
            assert img.dtype == np.uint8 and img.shape == (256, 256)
            calls.append(1)
            tree = gt if len(calls) % 2 else other  # two distinct predictions
            return Estimate(tree, "palm", {"palm": 1.0})

    ticks = []
    pipeline = Pipeline(Alternating(), RefineSettings(refine=False))
    res = rotation_sweep(
        gt, pipeline, step=5, size=64, samples=2000, progress=lambda i, n: ticks.append((i, n))
    )
    assert len(res.rows) == 72 and len(calls) == 72 and ticks[-1] == (72, 72)
    assert [r.angle for r in res.rows] == list(np.arange(72) * 5.0)
    exact = [r for i, r in enumerate(res.rows) if i % 2 == 0]
    assert all(r.hd_max == pytest.approx(0, abs=1e-6) for r in exact)
    assert all(r.hd_max > 0 and math.isfinite(r.hd_max_norm) for r in res.rows[1::2])
    assert res.cases()["worst"] % 2 == 1 and res.cases()["best"] % 2 == 0
    out = write_csv(res.rows, tmp_path / "sweep.csv")
    rows = list(csv.DictReader(out.open()))
    assert len(rows) == 72 and float(rows[1]["angle"]) == 5.0
    assert plot_sweep(res, tmp_path / "sweep.png").stat().st_size > 1000
    assert plot_cases(res, tmp_path / "cases.png", size=64).stat().st_size > 1000


def test_sweep_with_a_second_view_hands_the_pipeline_both_drawings():
    gt = species.sample("maple", seed=1)
    seen: list[np.ndarray] = []

    class Recording:
        name = "recording"

        def estimate(self, img: np.ndarray) -> Estimate:
            seen.append(img)
            return Estimate(gt, "maple", {"maple": 1.0})

    pipeline = Pipeline(Recording(), RefineSettings(refine=False))
    res = rotation_sweep(gt, pipeline, step=180, size=64, samples=500, turns=(90,))
    assert len(res.rows) == 2 and len(seen) == 4  # two drawings per angle
    # the second drawing is the tree from 90 degrees further round, not the first again
    assert not np.array_equal(seen[0], seen[1])
    assert all(r.hd_max == pytest.approx(0, abs=1e-6) for r in res.rows)
    with pytest.raises(ValueError, match="turns"):
        rotation_sweep(gt, pipeline, step=180, size=64, turns=(float("nan"),))


def test_the_sweep_draws_and_measures_the_trees_the_pipeline_grows():
    """Every tree is grown as the pipeline (and its refinement) grows one, ``grow(params)``
    with the dictionary's seed key: a refinement that starts from the truth's own values
    can then reproduce the very drawing it is given. ``seed`` replaces both keys."""
    from render.sketch import SketchRenderer
    from weberpenn import build_mesh, grow

    gt = species.sample("palm", seed=5)  # seed key 5
    other = gt.replace(seed=11)

    class Exact:
        name = "exact"

        def estimate(self, img: np.ndarray) -> Estimate:
            return Estimate(other, "palm", {"palm": 1.0})  # the truth's values, key 11

    pipeline = Pipeline(Exact(), RefineSettings(refine=False))
    own = rotation_sweep(gt, pipeline, step=180, size=64, samples=500)
    drawn = SketchRenderer(build_mesh(grow(gt))).sketch(180.0, size=64)
    assert np.array_equal(own.sketches[1], drawn)  # the truth as grow(gt) draws it
    assert all(r.hd_max > 0 for r in own.rows)  # key 11 against key 5: other draws
    same = rotation_sweep(gt, pipeline, step=180, size=64, samples=500, seed=11)
    assert np.array_equal(
        same.sketches[0], SketchRenderer(build_mesh(grow(other))).sketch(0.0, size=64)
    )
    assert all(r.hd_max == pytest.approx(0, abs=1e-6) for r in same.rows)
    assert same.seed == 11 and own.seed is None


def test_cli_rotation_grows_the_estimates_with_the_truth_s_seed_key(tmp_path):
    from typer.testing import CliRunner

    from treesketch.cli import app
    from weberpenn import save_params

    gt = tmp_path / "palm.json"
    save_params(species.sample("palm", seed=3), gt)
    args = ["eval", "rotation", "--params", str(gt), "--step", "180", "--size", "64",
            "--samples", "500"]  # fmt: skip
    res = CliRunner().invoke(app, [*args, "--out", str(tmp_path / "own")])
    assert res.exit_code == 0, res.output
    rows = list(csv.DictReader((tmp_path / "own" / "rotation.csv").open()))
    assert [float(r["angle"]) for r in rows] == [0.0, 180.0]
    assert all(r["status"] == "ok" and math.isfinite(float(r["hd_max_norm"])) for r in rows)
    # the ground truth's own key (3) is the default: --seed 3 gives the same rows
    res = CliRunner().invoke(app, [*args, "--seed", "3", "--out", str(tmp_path / "three")])
    assert res.exit_code == 0, res.output
    again = list(csv.DictReader((tmp_path / "three" / "rotation.csv").open()))
    assert [r["hd_max"] for r in again] == [r["hd_max"] for r in rows]
    res = CliRunner().invoke(app, [*args, "--seed", "-1", "--out", str(tmp_path / "bad")])
    assert res.exit_code != 0 and "seed" in res.output.lower()
