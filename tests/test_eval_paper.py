"""eval.stamp and eval.paper's writer on small made-up results (no network, no rendering)."""

from __future__ import annotations

import csv
import hashlib
import math
import re
from pathlib import Path

import pytest

from eval.hausdorff import Distance
from eval.metrics import PAPER_ONE_MINUS_RMSE, Scores
from eval.paper import QUICK, PaperResults, PaperSizes, PublishedResult, published_trees, write
from eval.rotation import SweepResult, SweepRow
from eval.stamp import Stamp, file_sha256, make_stamp, parse_stamp, portable_path
from weberpenn import TreeParams, species

ROOT = Path(__file__).resolve().parents[1]


def _stamp(sha: str = "ab" * 32) -> Stamp:
    return Stamp("c" * 40, "checkpoints/tsn_lite0.pt", sha, "2026-01-02 03:04 UTC", "cpu, 2 cores")


def _results() -> PaperResults:
    heads = {k: v - 0.01 for k, v in PAPER_ONE_MINUS_RMSE.items() if k != "overall"}
    scores = Scores(heads, sum(heads.values()) / len(heads), {}, 4)
    d = Distance(1.0, 0.1, 0.05, 0.005, 20.0, 100, pred_to_gt_vertex=0.04, gt_to_pred_vertex=0.05)
    pub = [
        PublishedResult("0_acer_2.json", "maple", "maple", "maple", d, d, d, 0.5, 0.4, 0.0, 1.0),
        PublishedResult(
            "3_palm_3.json",
            "palm",
            "palm",
            "palm",
            d,
            d,
            d,
            0.3,
            0.2,
            90.0,
            1.0,
            d,
            "palm",
            0.1,
            2.0,
        ),
    ]
    gt = TreeParams(species.sample("palm", seed=1))

    def sweep(v: float) -> SweepResult:
        rows = [SweepRow(a, v, v, v, v, "ok", False, math.nan, math.nan, 0.1) for a in (0.0, 180.0)]
        return SweepResult(rows, gt)

    sweeps = {
        "palm": {
            "file": "3_palm_3.json",
            "alone": sweep(0.04),
            "refined": sweep(0.03),
            "two views": sweep(0.02),
        }
    }
    acc = {"overall": 0.9, "per_species": {"maple": 1.0, "palm": 0.8}, "n": 10}
    return PaperResults(scores, acc, 10, 2, pub, sweeps, 12.0)


def test_stamp_of_a_file_in_the_repository(tmp_path):
    ckpt = tmp_path / "net.pt"
    ckpt.write_bytes(b"weights")
    s = make_stamp(ckpt, ROOT)
    assert s.checkpoint_sha256 == hashlib.sha256(b"weights").hexdigest() == file_sha256(ckpt)
    assert re.fullmatch(r"[0-9a-f]{40}(\+dirty)?", s.commit)
    assert re.fullmatch(r"\d{4}-\d\d-\d\d \d\d:\d\d UTC", s.date)
    assert "cores" in s.machine
    assert s.checkpoint == "net.pt"  # outside the repository: the bare name, never its path
    assert parse_stamp(s.markdown()) == {
        "commit": s.commit,
        "checkpoint": "net.pt",
        "checkpoint_sha256": s.checkpoint_sha256,
        "date": s.date,
        "machine": s.machine,
    }


def test_portable_path():
    assert portable_path(ROOT / "checkpoints" / "tsn_lite0.pt", ROOT) == "checkpoints/tsn_lite0.pt"
    assert portable_path("/somewhere/else/x.pt", ROOT) == "x.pt"


def test_write_stamps_every_output_and_replaces_the_folder(tmp_path):
    out = tmp_path / "reports"
    out.mkdir()
    (out / "README.md").write_text("old report\n")
    (out / "rotation_cases_pine.png").write_bytes(b"stale")  # from an older layout
    write(out, _results(), QUICK, _stamp(), "treesketch eval paper --quick")
    names = sorted(p.name for p in out.iterdir())
    assert names == sorted(
        [
            "README.md", "one_minus_rmse.csv", "species_accuracy.csv", "published_trees.csv",
            "published_trees.png", "rotation.csv", "rotation_palm.png", "results.json",
        ]
    )  # fmt: skip
    assert not list(tmp_path.glob(".reports.*"))  # no temporary folder left
    md = (out / "README.md").read_text()
    assert parse_stamp(md)["checkpoint_sha256"] == "ab" * 32
    assert "`treesketch eval paper --quick`" in md
    assert "Quick sizes" in md
    assert "![rotation palm](rotation_palm.png)" in md
    for path in out.glob("*.csv"):
        with path.open() as f:
            rows = list(csv.DictReader(f))
        assert rows, path.name
        assert {r["checkpoint_sha256"] for r in rows} == {"ab" * 32}, path.name
        assert {r["commit"] for r in rows} == {"c" * 40}, path.name
    with (out / "rotation.csv").open() as f:
        runs = [(r["run"], r["angle"], r["hd_max_norm"]) for r in csv.DictReader(f)]
    assert runs == [("alone", "0", "0.04"), ("alone", "180", "0.04"),
                    ("refined", "0", "0.03"), ("refined", "180", "0.03"),
                    ("two views", "0", "0.02"), ("two views", "180", "0.02")]  # fmt: skip
    # one view against two, and the whole family of 3D errors beside the floor
    assert "two sketches" in md and "The 3D error as the field reports it" in md
    assert "MeshLab one-sided" in md and "Metro symmetric max" in md
    with (out / "published_trees.csv").open() as f:
        pub = list(csv.DictReader(f))
    assert pub[0]["two_views_max"] == "" and float(pub[1]["two_views_max"]) == 0.05
    assert "refined_meshlab_pred_to_gt" in pub[0]
    for path in out.iterdir():
        if path.suffix != ".png":
            assert str(tmp_path) not in path.read_text(), path.name
    assert (out / "rotation_palm.png").read_bytes()[:4] == b"\x89PNG"
    assert (out / "rotation_palm.png").stat().st_size < 80_000


def test_write_refuses_a_folder_that_is_not_a_report(tmp_path):
    out = tmp_path / "mine"
    out.mkdir()
    (out / "notes.txt").write_text("keep me")
    with pytest.raises(ValueError, match="not a report"):
        write(out, _results(), QUICK, _stamp(), "treesketch eval paper")
    assert (out / "notes.txt").read_text() == "keep me"


def test_sizes_are_checked_before_any_work():
    with pytest.raises(ValueError, match="divide 360"):
        PaperSizes("bad", 10, 1, 7.0, 1, 1000).check()
    with pytest.raises(ValueError, match="budgets"):
        PaperSizes("bad", 10, 0, 90.0, 1, 1000).check()


def test_published_trees_are_the_papers_fifteen():
    trees = published_trees()
    assert len(trees) == 15
    assert [name for name, _, _ in trees][:2] == ["0_acer_2.json", "1_acer_2.json"]
    assert {sp for _, sp, _ in trees} == {"maple", "palm", "pine", "cherry", "bonsai"}


def test_cli_rejects_bad_input_before_any_work(tmp_path):
    from typer.testing import CliRunner

    from treesketch.cli import app

    runner = CliRunner()
    res = runner.invoke(app, ["eval", "paper", "--quick", "--checkpoint", str(tmp_path / "no.pt"),
                              "--out", str(tmp_path / "r"), "--cache", str(tmp_path / "c")])  # fmt: skip
    assert res.exit_code == 2
    assert "no.pt: no such file" in res.output and "Traceback" not in res.output
    afile = tmp_path / "file"
    afile.write_text("x")
    res = runner.invoke(app, ["eval", "paper", "--quick", "--out", str(afile),
                              "--cache", str(tmp_path / "c")])  # fmt: skip
    assert res.exit_code == 2 and "not a folder" in res.output
    assert not (tmp_path / "c").exists()  # nothing built
