"""The start with the drawn outline (refine.start, issue 48) on code-made drawings."""

from __future__ import annotations

import numpy as np
from PIL import Image, ImageDraw

from refine.objective import framed
from refine.start import fit_start, profile_of
from treesketch.trees import tree_sketch
from weberpenn import species

SIZE = 128


def drawing(crown: str, stick: float) -> np.ndarray:
    """A tree drawn with a pen: a trunk of two lines ``stick`` of the height tall under a
    crown outline, ``"round"`` (a lollipop) or ``"flat"`` (a wide flat-topped crown)."""
    im = Image.new("L", (256, 256), 255)
    d = ImageDraw.Draw(im)
    top, bottom = 20, 240
    base = bottom - stick * (bottom - top)
    d.line([(120, bottom), (120, base)], fill=0, width=3)
    d.line([(136, bottom), (136, base)], fill=0, width=3)
    if crown == "round":
        d.ellipse([78, top, 178, base + 8], outline=0, width=3)
    else:  # flat top, flat base: an umbrella's outline
        d.polygon([(40, top), (216, top), (200, base), (56, base)], outline=0, width=3)
    return np.asarray(im)


def outline(params, name: str):
    return profile_of(tree_sketch(params, name, 0.0, SIZE))


def test_a_lollipop_keeps_its_stick_to_crown_proportion() -> None:
    img = framed(drawing("round", 0.5), SIZE)
    want = profile_of(img)
    assert abs(want.crown_base - 0.5) < 0.08  # the reading itself
    start = species.base("oak")
    fitted = fit_start(img, start, "oak", SIZE)
    before, after = outline(start, "oak").crown_base, outline(fitted, "oak").crown_base
    assert abs(after - want.crown_base) < 0.12, (before, after, want.crown_base)
    assert abs(after - want.crown_base) < abs(before - want.crown_base)


def test_a_flat_topped_crown_stays_flat() -> None:
    img = framed(drawing("flat", 0.35), SIZE)
    want = profile_of(img)
    start = species.base("oak")  # a round crown by habit
    fitted = fit_start(img, start, "oak", SIZE)

    def flatness(p) -> float:  # the crown's width near its top over its widest
        w = p.widths
        return float(w[-3:].max() / w.max())

    assert flatness(want) > 0.9
    assert flatness(outline(fitted, "oak")) > flatness(outline(start, "oak"))
    assert flatness(outline(fitted, "oak")) > 0.6


def test_the_drawn_outline_wins_over_the_species_ranges() -> None:
    # a thick short trunk under a wide crown: the fitted values pass the species'
    # projection kept (species.project keep=), not clipped back to its habit
    img = framed(drawing("flat", 0.35), SIZE)
    fitted = fit_start(img, species.base("oak"), "oak", SIZE)
    kept = species.project("oak", fitted, search=True, keep=species.DRAWN_KEYS)
    for key in species.DRAWN_KEYS:
        assert kept[key] == fitted[key]
    assert species.project("oak", fitted, search=True)["shape"] == species.base("oak")["shape"]


def test_a_blank_drawing_leaves_the_start_alone() -> None:
    start = species.base("oak")
    assert fit_start(np.full((SIZE, SIZE), 255, np.uint8), start, "oak", SIZE) is start
