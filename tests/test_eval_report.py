"""eval.report: the whole report on a tiny hand-made dataset with a stand-in model."""

from __future__ import annotations

import json

import numpy as np
import pytest
from PIL import Image

from eval.report import build_report
from eval.scoring import Scorer
from treesketch import Estimate, Pipeline
from weberpenn import build_mesh, grow, species


def _tiny_dataset(root):
    from render.sketch import sketch

    rows = []
    for sp, n in (("palm", 2), ("maple", 1)):
        for i in range(n):
            p = species.sample(sp, seed=10 + i)
            tid = f"{sp}_{i:04d}"
            (root / "params").mkdir(exist_ok=True)
            (root / "sketches").mkdir(exist_ok=True)
            (root / "params" / f"{tid}.json").write_text(json.dumps(p.to_dict()))
            img = sketch(build_mesh(grow(p)), "front", size=64)
            Image.fromarray(img).save(root / "sketches" / f"{tid}_front.png")
            rows.append(
                {
                    "species": sp,
                    "tree_id": tid,
                    "split": "test",
                    "view": "front",
                    "sketch": f"sketches/{tid}_front.png",
                    "params": f"params/{tid}.json",
                }
            )
    (root / "manifest.jsonl").write_text("".join(json.dumps(r) + "\n" for r in rows))


class StandIn:
    name = "stand-in"
    guess = {"palm": species.sample("palm", seed=99), "maple": species.sample("maple", seed=99)}

    def estimate(self, img: np.ndarray) -> Estimate:
        assert img.dtype == np.uint8
        sp = "palm" if (img < 128).mean() < 0.2 else "maple"
        return Estimate(self.guess[sp], sp, {sp: 1.0})


def _stand_in() -> tuple[Pipeline, Scorer]:
    scorer = Scorer(
        name="stand-in",
        predict_normalised=lambda imgs: np.full((len(imgs), 4, 62), 0.1),
        normalise_targets=lambda ps: np.zeros((len(ps), 4, 62)),
    )
    return Pipeline(StandIn()), scorer


@pytest.mark.slow
def test_report_on_tiny_dataset(tmp_path):
    data = tmp_path / "ds"
    data.mkdir()
    _tiny_dataset(data)
    out = build_report(
        data,
        tmp_path / "rep",
        *_stand_in(),
        per_species=2,
        refine_budget=2,
        rotation_step=90,
        rotation_species=["palm"],
        rotation_size=64,
        samples=1000,
        bar=False,
    )
    md = out.read_text()
    assert "| stand-in | 0.9000" in md and "0.9253" in md and "0.031" in md
    assert "Symmetric Hausdorff distance" in md and "| palm | 2 |" in md and "| all | 3 |" in md
    assert "aligned max" in md and "(the aligned max on " in md
    assert (out.parent / "rotation_palm.png").stat().st_size > 1000
    assert (out.parent / "rotation_cases_palm.png").is_file()
    assert len((out.parent / "rotation_palm.csv").read_text().splitlines()) == 5
    res = json.loads((out.parent / "results.json").read_text())
    assert len(res["hausdorff"]) == 3 and res["hausdorff"][0]["refined"] is not None
    al = res["hausdorff"][0]["aligned_max_norm"]
    assert 0 <= al["tsn"] <= res["hausdorff"][0]["tsn"]["combined"]["max_norm"] + 0.02
    assert res["species_accuracy"]["n"] == 3


def test_report_errors(tmp_path):
    with pytest.raises(ValueError, match="no such dataset"):
        build_report(tmp_path / "missing", tmp_path / "o", *_stand_in())
