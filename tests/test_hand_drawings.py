"""The bundled hand-style drawings (examples/hand, made by scripts/make_hand_png.py): each
reads and normalises to a framed drawing, each has the species a person would name in
examples/hand/species.json, and a plain lollipop tree passes the style-blind shape
distance."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from render.reader import FRAME_BOTTOM
from treesketch import Pipeline, RefineSettings
from treesketch.pipeline import LOW_CONFIDENCE_LOSS, load_sketch, prepare_input
from weberpenn.species import PEOPLE_SPECIES, SPECIES

HAND = Path(__file__).resolve().parents[1] / "examples" / "hand"
DRAWINGS = sorted(HAND.glob("*.png"))


def test_every_hand_drawing_normalises_to_a_framed_drawing() -> None:
    assert len(DRAWINGS) >= 10
    for path in DRAWINGS:
        assert path.stat().st_size < 30_000, path.name
        img = prepare_input(load_sketch(path))
        assert img.shape == (256, 256) and img.dtype == np.uint8
        ink = img < 128
        assert 0.002 < ink.mean() < 0.5, path.name
        rows, cols = np.flatnonzero(ink.any(axis=1)), np.flatnonzero(ink.any(axis=0))
        # the trunk base sits on the frame's bottom margin and the drawing fills the frame
        assert abs((rows[-1] + 1) / 256 - FRAME_BOTTOM) < 0.03, path.name
        assert rows[-1] - rows[0] > 0.5 * 256 or cols[-1] - cols[0] > 0.6 * 256, path.name


def test_every_hand_drawing_has_the_species_a_person_would_name() -> None:
    table = json.loads((HAND / "species.json").read_text(encoding="utf-8"))
    assert sorted(table) == sorted(p.stem for p in DRAWINGS)
    assert len(table) >= 24
    for name, row in table.items():
        assert row["species"] in SPECIES, name
        assert set(row["also"]) <= set(SPECIES) - {row["species"]}, name
        assert row["what"], name
    # the trees people draw most are all there, not only the paper's five
    assert set(PEOPLE_SPECIES) <= {row["species"] for row in table.values()}


@pytest.mark.slow
def test_the_lollipop_tree_is_refined_towards_its_shape() -> None:
    # a lollipop (round crown on a stick) is far from every species' sketch: the shape
    # distance falls but may stay near the warning's limit (benchmarks/RESULTS.md,
    # "Style-blind distance and warning, recalibrated": with one species tried it is
    # refined as a palm, 0.665)
    res = Pipeline("tsn", RefineSettings(budget=10, species_tries=1)).run(HAND / "lollipop.png")
    assert res.losses["after"] <= res.losses["before"]
    assert res.losses["after"] < 1.5 * LOW_CONFIDENCE_LOSS, res.losses
    assert res.tree_mesh.branches.faces.shape[0] > 0


@pytest.mark.slow
def test_a_palm_with_line_fronds_stays_a_palm() -> None:
    """Fronds drawn as single lines cover little of a filled crown's hull: the species is
    decided by the network's reading of the drawing and the refined distances together,
    and a confident palm is not overruled by a cherry whose crown happens to fit."""
    from eval.doodles import tree_doodle

    pipe = Pipeline("tsn", RefineSettings(budget=6))
    res = pipe.run(HAND / "palm_lines.png")
    assert res.species == "palm", res.species_text
    assert [c.species for c in res.candidates][0] == "palm"
    assert len(res.candidates) >= 3 and res.candidates[0].probability > 0.5, res.species_text
    # palms doodled by hand (made by code: fronds as strokes), read by the network alone
    for seed in range(4):
        est = pipe.estimate(tree_doodle("palm", seed))
        assert est.species == "palm", (seed, est.scores)
