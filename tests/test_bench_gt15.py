"""benchmarks/bench_gt15.py without the network: view sets, the drawings handed to the
pipeline for one view and for two, the record of a refinement and the tables."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from benchmarks import bench_gt15 as bench
from eval.hausdorff import FAMILY, FAMILY_PARTS, seed_floor


def test_view_sets():
    assert bench.view_set("front") == ("front",)
    assert bench.view_set("front, side") == ("front", "side")
    for bad, why in (("back", "unknown view"), ("side,front", "starts with front")):
        with pytest.raises(ValueError, match=why):
            bench.view_set(bad)
    with pytest.raises(ValueError, match="once"):
        bench.view_set("front,front")
    with pytest.raises(SystemExit):
        bench.main(["--views", "front", "front", "--species", "palm"])


class _Pipe:
    """Stands for ``treesketch.Pipeline``: keeps what ``run`` was given and answers the
    truth's own values, found to show the front drawing from ``yaw``."""

    def __init__(self, truth, mesh, yaw: float) -> None:
        self.truth, self.mesh, self.yaw, self.sources = truth, mesh, yaw, []

    def run(self, source, height=None):
        self.sources.append(source)
        n = len(source) if isinstance(source, list) else 1
        # each view's yaw relative to the first (Result.views); the tree's own in Result.yaw
        views = tuple(
            SimpleNamespace(yaw=90.0 * i, loss_before=0.3, loss_after=0.1) for i in range(n)
        )
        return SimpleNamespace(
            params=self.truth,
            species="palm",
            tree_mesh=self.mesh,
            losses={"before": 0.3, "after": 0.1},
            yaw=self.yaw,
            views=views,
            estimate=SimpleNamespace(params=self.truth, species="palm", yaw=None),
            refinement=None,
            extras={},
        )


@pytest.fixture(scope="module")
def small():
    from weberpenn import build_mesh, grow, species

    truth = species.sample("palm", 2).replace(leaves=20)
    mesh = build_mesh(grow(truth), species="palm")
    return truth, mesh, seed_floor(truth, (1, 0), 500, FAMILY_PARTS)


def test_one_view_and_two_as_the_pipeline_takes_them(small):
    truth, mesh, seed_d = small
    front, side = np.full((8, 8), 255, np.uint8), np.zeros((8, 8), np.uint8)
    sketches = {"front": front, "side": side}
    pipe = _Pipe(truth, mesh, 30.0)
    one = bench.refine_views(pipe, sketches, ("front",), truth, mesh, None, 500, seed_d)
    two = bench.refine_views(pipe, sketches, ("front", "side"), truth, mesh, None, 500, seed_d)
    assert pipe.sources[0] is front
    first, (second, yaw) = pipe.sources[1]
    assert first is front and second is side and yaw == 90.0
    assert one["yaw_found"] == two["yaw_found"] == 30.0
    assert [v["yaw"] for v in one["view_losses"]] == [0.0]
    assert [v["yaw"] for v in two["view_losses"]] == [0.0, 90.0]
    # with two drawings the network's fused first estimate is measured too (here the
    # truth's values at the front: no error at all)
    assert one["network"] is None
    assert two["network"]["family"]["combined"]["max_norm"] < 1e-9
    assert two["network"]["floors"]["perfect_values"]["branches"]["max"] < 1e-9
    for rec in (one, two):
        assert set(rec["refined"]) == set(FAMILY_PARTS) and set(FAMILY) <= set(
            rec["refined"]["combined"]
        )
        # the truth's values seen from the wrong view: its perfect-values floor is itself
        assert rec["floors"]["perfect_values"] == rec["refined"]
        assert rec["refined"]["combined"]["max_norm"] > 0.01
        # turned back to the truth's view, nothing is left
        assert rec["floors"]["aligned_turn"] == 30.0
        assert rec["floors"]["aligned"]["combined"]["max_norm"] < 1e-9
        assert "seed" not in rec["floors"]


def test_tables(small):
    truth, mesh, seed_d = small
    sketches = {"front": np.zeros((8, 8), np.uint8), "side": np.zeros((8, 8), np.uint8)}
    seed_rec = {k: d.to_dict() for k, d in seed_d.items()}
    recs = []
    for i, yaw in enumerate((0.0, 45.0)):
        pipe = _Pipe(truth, mesh, yaw)
        runs = {
            ",".join(n): bench.refine_views(pipe, sketches, n, truth, mesh, None, 500, seed_d)
            for n in (("front",), ("front", "side"))
        }
        tsn = runs["front"]["refined"]
        recs.append(
            {
                "file": f"{i}_palm_3.json",
                "species": "palm",
                "species_tsn": "palm",
                "tsn": tsn,
                "seed_floor": seed_rec,
                "tsn_floors": runs["front"]["floors"],
                "runs": runs,
            }
        )
    text = bench.markdown(recs)
    assert "| combined (mean of 2) | ours max | MeshLab p->g |" in text
    assert "| branches (mean of 2) |" in text
    assert text.count("refined, front,side") == 2  # one row per part
    assert text.count("network alone, front,side (fused)") == 2
    assert "The network reading these drawings (fused): 0.0000." in text
    assert "better than the network alone on 0 of 2" in text
    assert "Issue 29's must-show" in text and "not met" in text
    rows = bench.figures(recs)
    assert [r[0] for r in rows][:2] == ["seed floor", "network alone"] and len(rows) == 13
    mean = bench._mean([r["tsn"]["combined"]["max_norm"] for r in recs])
    assert f"| network alone | {mean:.4f} |" in text
    assert math.isnan(bench._mean([float("nan")]))
