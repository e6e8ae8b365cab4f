"""treesketch.executor on a local Ray (2 CPUs): the same bytes and values as the local
executor for a small dataset build and a small rotation sweep; a piece's own error is
reported once, a lost worker's piece is retried."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

ray = pytest.importorskip("ray", reason="the cluster extra (pip install .[cluster])")

from eval.rotation import rotation_sweep  # noqa: E402
from render.dataset import DatasetConfig, build_dataset  # noqa: E402
from treesketch import Estimate, Pipeline, RefineSettings  # noqa: E402
from treesketch.executor import RayExecutor, run_ordered  # noqa: E402
from weberpenn import species  # noqa: E402

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def rex():
    ex = RayExecutor(num_cpus=2)
    try:
        yield ex
    finally:
        ex.close()
    assert not ray.is_initialized()


class Tally:
    """Pieces append their number to a file per attempt, so the test can count tries.
    Piece 3 raises (its own fault); piece 5 kills its worker on the first try."""

    def __init__(self, folder: str) -> None:
        self.folder = folder

    def __call__(self):
        folder = Path(self.folder)

        def one(x: int) -> int:
            log = folder / f"{x}.tries"
            with open(log, "a") as fh:
                fh.write("x")
            if x == 3:
                raise ValueError("three is bad")
            if x == 5 and log.read_text() == "x":
                os._exit(1)  # a crash: Ray retries the piece on a new worker
            return x * 10

        return one


def test_errors_reported_once_lost_workers_retried(rex, tmp_path):
    outs = run_ordered(rex, Tally(str(tmp_path)), list(range(8)))
    assert [o.value for o in outs if o.ok] == [0, 10, 20, 40, 50, 60, 70]
    assert outs[3].error.startswith("ValueError: three is bad")
    tries = {x: len((tmp_path / f"{x}.tries").read_text()) for x in range(8)}
    assert tries[3] == 1  # a piece's own error is never retried
    assert tries[5] == 2  # the crashed worker's piece ran again
    assert all(tries[x] == 1 for x in range(8) if x not in (3, 5))
    assert len({o.node for o in outs}) == 1 and outs[0].node in rex.nodes()


def _tree_files(root: Path) -> dict[str, bytes]:
    # markers hold timings; everything else must be the same bytes
    return {
        p.relative_to(root).as_posix(): p.read_bytes()
        for p in sorted(root.rglob("*"))
        if p.is_file() and p.parent.name != "done" and p.name not in ("DONE", ".lock")
    }


def test_dataset_same_bytes_as_local(rex, tmp_path):
    small = {"trees_per_species": 1, "species": ("maple", "palm"), "views": ("front", "left")}
    local = DatasetConfig(out=str(tmp_path / "local"), size=48, **small)
    viaray = DatasetConfig(out=str(tmp_path / "ray"), size=48, **small)
    a = build_dataset(local, progress=False)
    b = build_dataset(viaray, progress=False, executor=rex)
    assert a.built == b.built == 2 and not a.failed and not b.failed
    fa, fb = _tree_files(tmp_path / "local"), _tree_files(tmp_path / "ray")
    assert len(fa) == 11  # settings, 2 manifests; per tree 2 sketches, params, render
    assert fa == fb
    again = build_dataset(viaray, progress=False, executor=rex)
    assert again.skipped == 2 and again.built == 0


class InkSide:
    """A picklable stand-in estimator: which half of the page holds more ink picks one of
    two dictionaries (deterministic in the sketch, as TSN is)."""

    name = "ink-side"

    def __init__(self, a, b) -> None:
        self.a, self.b = a, b

    def estimate(self, img: np.ndarray) -> Estimate:
        ink = img < 128
        half = img.shape[1] // 2
        tree = self.a if ink[:, :half].sum() >= ink[:, half:].sum() else self.b
        return Estimate(tree, "palm", {"palm": 1.0})


def test_rotation_sweep_same_values_as_local(rex):
    gt = species.sample("palm", seed=1)
    predict = Pipeline(
        InkSide(gt, species.sample("palm", seed=2)), RefineSettings(budget=3, size=48)
    )
    kw = {"step": 120, "size": 64, "samples": 1500}
    ticks: list[int] = []
    local = rotation_sweep(gt, predict, **kw)
    remote = rotation_sweep(gt, predict, executor=rex, progress=lambda i, n: ticks.append(i), **kw)
    assert ticks == [1, 2, 3]
    assert len(local.rows) == len(remote.rows) == 3
    for x, y in zip(local.rows, remote.rows, strict=True):
        assert x.status == y.status == "ok"
        for f in ("angle", "hd_max", "hd_mean", "hd_max_norm", "hd_mean_norm", "loss_after"):
            assert getattr(x, f) == getattr(y, f), f
    for p, q in zip(local.predictions, remote.predictions, strict=True):
        assert p.to_dict() == q.to_dict()
    for s, t in zip(local.sketches, remote.sketches, strict=True):
        assert np.array_equal(s, t)


def test_cli_dataset_build_through_ray(rex, tmp_path):
    """`--executor ray` (here it joins the Ray this module started) builds the same files
    as the in-process default."""
    from typer.testing import CliRunner

    from treesketch.cli import app

    args = ["dataset", "build", "--trees-per-species", "1", "--species", "palm"]
    args += ["--views", "front", "--size", "32", "--no-progress"]
    a = CliRunner().invoke(app, [*args, "--out", str(tmp_path / "a")])
    b = CliRunner().invoke(app, [*args, "--out", str(tmp_path / "b"), "--executor", "ray"])
    assert a.exit_code == 0 and b.exit_code == 0, a.output + b.output
    assert "1 built, 0 failed" in b.output
    assert _tree_files(tmp_path / "a") == _tree_files(tmp_path / "b")
    assert ray.is_initialized()  # the CLI left the Ray it did not start alone
