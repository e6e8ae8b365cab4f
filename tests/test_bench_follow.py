"""The follow benchmark's summary (issue 48): people's drawings of outlines and those
that show their inside are told apart, as the refinement tells them."""

from __future__ import annotations

import math

import numpy as np
from PIL import Image, ImageDraw

from benchmarks.bench_drawings import follow_summary, inside_ink
from refine.start import LINES_INSIDE


def record(name: str, after: float, inside: float) -> dict:
    keys = ("loss_before", "loss_after", "first_seconds", "refine_seconds", "seconds")
    return {"name": name, "overlap_before": 0.5, "overlap_after": after, "inside_ink": inside} | {
        k: 1.0 for k in keys
    }


def test_the_summary_splits_outlines_from_drawn_insides() -> None:
    rs = [
        record("people/00", 0.9, 0.02),
        record("people/01", 0.7, 0.05),
        record("people/02", 0.4, LINES_INSIDE),
        record("paper/a", 0.8, 0.5),
    ]
    out = follow_summary(rs)
    assert out["people"]["n"] == 3
    assert out["people"]["outlines"] == [2, 0.8]
    assert out["people"]["insides"] == [1, 0.4]
    assert out["paper"]["outlines"][0] == 0 and math.isnan(out["paper"]["outlines"][1])
    # records from before the field: no split, the rest as before
    old = [{k: v for k, v in r.items() if k != "inside_ink"} for r in rs]
    assert "outlines" not in follow_summary(old)["people"]


def test_inside_ink_reads_a_drawn_outline_and_a_scribbled_crown() -> None:
    im = Image.new("L", (256, 256), 255)
    d = ImageDraw.Draw(im)
    d.line([(120, 240), (120, 140)], fill=0, width=3)
    d.line([(136, 240), (136, 140)], fill=0, width=3)
    d.ellipse([60, 20, 196, 148], outline=0, width=3)
    outline = np.asarray(im).copy()
    rng = np.random.default_rng(0)
    for _ in range(60):  # branches and leaves scribbled inside the crown
        x, y = rng.uniform(80, 176, 2), rng.uniform(40, 130, 2)
        d.line([(x[0], y[0]), (x[1], y[1])], fill=0, width=3)
    assert inside_ink(outline) < LINES_INSIDE <= inside_ink(np.asarray(im))


def test_people_cases_come_from_the_part_asked_for() -> None:
    """``--people-part fit`` reads the fit part's trees (drawings the held-out figures
    never use) under the same names; the default stays the held-out part."""
    from argparse import Namespace

    from benchmarks.bench_drawings import follow_cases
    from eval.people import people_drawings

    def names(part: str) -> list[str]:
        args = Namespace(
            only="people",
            people_source="strokes",
            people_part=part,
            people_pick=[0, 1],
            people_from=0,
            people=2,
        )
        return [name for name, _ in follow_cases(args)]

    for part in ("held", "fit"):
        keys = [d.key.replace("/", "-") for d in people_drawings(part, ("strokes",), ("tree",))[:2]]
        assert names(part) == [f"people/{i:02d}-{k}" for i, k in enumerate(keys)]
    assert set(names("held")).isdisjoint(names("fit"))
