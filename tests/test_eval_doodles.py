"""Doodles made by code (eval/doodles.py): seeded, drawable for every kind and species, ink
on the page and inside it, bad input refused by name, and tree doodles whose shapes differ
by species the way people draw them (a fir tall and pointed, an oak wide, a poplar a
column, a palm's crown on a thin trunk)."""

from __future__ import annotations

import numpy as np
import pytest

from eval.doodles import (
    NONTREE_KINDS,
    PALM_FORMS,
    SIZE,
    TREE_SPECIES,
    nontree_doodle,
    palm_doodle,
    tree_doodle,
)
from weberpenn.species import SPECIES

SEEDS = range(24)


def _check_page(img: np.ndarray, what: str) -> None:
    assert img.shape == (SIZE, SIZE) and img.dtype == np.uint8, what
    ink = img < 128
    assert 0.004 < ink.mean() < 0.3, (what, ink.mean())
    assert img.max() == 255, what  # the paper stays white
    # every stroke inside the page: a blank margin all round
    for edge in (img[:2], img[-2:], img[:, :2], img[:, -2:]):
        assert edge.min() >= 250, what


def _shape(img: np.ndarray) -> dict[str, float]:
    """Shape statistics of the ink's bounding box: height over width, how much of the width
    the top 15% of rows spans, and how much the lower half spans."""
    ink = img < 128
    rows, cols = np.flatnonzero(ink.any(axis=1)), np.flatnonzero(ink.any(axis=0))
    box = ink[rows[0] : rows[-1] + 1, cols[0] : cols[-1] + 1]
    h, w = box.shape

    def span(mask: np.ndarray) -> float:
        on = np.flatnonzero(mask.any(axis=0))
        return (on[-1] - on[0] + 1) / w if on.size else 0.0

    return {"aspect": h / w, "top": span(box[: max(1, h * 15 // 100)]), "low": span(box[h // 2 :])}


@pytest.fixture(scope="module")
def shapes() -> dict[str, list[dict[str, float]]]:
    return {sp: [_shape(tree_doodle(sp, seed)) for seed in SEEDS] for sp in TREE_SPECIES}


def _median(rows: list[dict[str, float]], key: str) -> float:
    return float(np.median([r[key] for r in rows]))


def test_the_kinds_and_species_cover_what_is_asked() -> None:
    assert set(TREE_SPECIES) == set(SPECIES)
    assert len(NONTREE_KINDS) >= 12 and len(set(NONTREE_KINDS)) == len(NONTREE_KINDS)
    asked = {"house", "car", "face", "cat", "fish", "bird", "cup", "word", "sun", "flower"}
    assert asked | {"bicycle", "chair"} <= set(NONTREE_KINDS)
    assert not set(NONTREE_KINDS) & set(SPECIES)


def test_same_seed_same_image_and_seeds_vary() -> None:
    for kind in NONTREE_KINDS:
        a = nontree_doodle(kind, 5)
        assert np.array_equal(a, nontree_doodle(kind, 5)), kind
        assert not np.array_equal(a, nontree_doodle(kind, 6)), kind
    for species in TREE_SPECIES:
        a = tree_doodle(species, 5)
        assert np.array_equal(a, tree_doodle(species, 5)), species
        assert not np.array_equal(a, tree_doodle(species, 6)), species
    # numpy integers are seeds too, and give the same drawing as the int
    assert np.array_equal(tree_doodle("oak", np.int64(3)), tree_doodle("oak", 3))


def test_every_kind_is_drawn_on_the_page_inside_it() -> None:
    for kind in NONTREE_KINDS:
        for seed in range(6):
            _check_page(nontree_doodle(kind, seed), f"{kind} {seed}")


def test_every_species_is_drawn_on_the_page_inside_it() -> None:
    for species in TREE_SPECIES:
        for seed in range(6):
            _check_page(tree_doodle(species, seed), f"{species} {seed}")


def test_the_hand_varies_line_width_size_and_position() -> None:
    imgs = [tree_doodle("maple", seed) for seed in SEEDS]
    ink = np.array([(img < 128).mean() for img in imgs])
    centres, heights = [], []
    for img in imgs:
        rows, cols = np.nonzero(img < 128)
        centres.append((rows.mean(), cols.mean()))
        heights.append(rows.max() - rows.min())
    assert ink.max() > 2.5 * ink.min()  # thin pen to thick finger
    assert np.ptp(np.array(centres), axis=0).min() > 20  # not always in the middle
    assert max(heights) > 1.4 * min(heights)
    # some antialiased (grey edge pixels), some aliased (the mouse: ink or paper only)
    grey = [((img > 40) & (img < 215)).mean() for img in imgs]
    assert min(grey) < 0.001 < max(grey)


def test_tree_shapes_differ_by_species(shapes: dict[str, list[dict[str, float]]]) -> None:
    # a fir: taller than wide and pointed, every time
    assert all(r["aspect"] > 1.15 and r["top"] < 0.35 for r in shapes["fir"])
    # a cherry: wider than tall, every time; an oak: mostly its broad crown, and sometimes
    # "a tree" as most people draw one (a lollipop or a cloud on a stick: taller)
    assert all(r["aspect"] < 1.0 for r in shapes["cherry"])
    assert _median(shapes["oak"], "aspect") < 1.0
    assert any(r["aspect"] > 1.0 for r in shapes["oak"])
    # a poplar: a tall column
    assert _median(shapes["poplar"], "aspect") > 2.5
    assert all(r["aspect"] > 1.4 for r in shapes["poplar"])
    # a palm and a birch: the crown up high on a thin trunk; the lower half stays narrow
    for species in ("palm", "birch"):
        assert _median(shapes[species], "low") < 0.35, species
    assert _median(shapes["palm"], "top") > 0.75
    # and in the order people draw them: poplar > fir > maple > oak, in height over width
    order = [_median(shapes[s], "aspect") for s in ("poplar", "fir", "maple", "oak")]
    assert order == sorted(order, reverse=True), order


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda: nontree_doodle("tree", 0), "unknown doodle kind 'tree'"),
        (lambda: nontree_doodle("oak", 0), "one of house"),
        (lambda: tree_doodle("spruce", 0), "unknown tree species 'spruce'"),
        (lambda: tree_doodle(["oak"], 0), r"unknown tree species \['oak'\]"),
        (lambda: tree_doodle("fir", -1), "non-negative integer, got -1"),
        (lambda: tree_doodle("fir", 1.5), "non-negative integer, got 1.5"),
        (lambda: nontree_doodle("cup", True), "non-negative integer, got True"),
    ],
)
def test_bad_input_is_refused_by_name(call, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        call()


# --------------------------------------------------------------------- palms as people draw them


def _ink_rows(img: np.ndarray) -> np.ndarray:
    return np.flatnonzero((img < 128).any(axis=1))


def test_palm_forms_are_seeded_distinct_and_on_the_page() -> None:
    assert PALM_FORMS == ("leaf", "arc", "jagged", "burst")
    firsts = []
    for form in PALM_FORMS:
        a = palm_doodle(form, 7)
        assert np.array_equal(a, palm_doodle(form, 7)), form
        assert not np.array_equal(a, palm_doodle(form, 8)), form
        firsts.append(a)
        for seed in range(6):
            _check_page(palm_doodle(form, seed), f"palm {form} {seed}")
    # the same seed gives a different drawing in each form
    for i in range(len(firsts)):
        for j in range(i):
            assert not np.array_equal(firsts[i], firsts[j])
    assert np.array_equal(palm_doodle("arc", np.int64(2)), palm_doodle("arc", 2))


def test_palm_crowns_sit_on_a_thin_trunk() -> None:
    # the fronds spread wide at the top; the trunk below is narrow (unless a ground line or
    # an island is drawn under it, which some seeds do)
    for form in PALM_FORMS:
        shapes = [_shape(palm_doodle(form, seed)) for seed in range(16)]
        assert _median(shapes, "low") < 0.45, form
        assert _median(shapes, "top") > 0.3, form
        assert _median(shapes, "aspect") > 1.1, form


def _palm_strokes(form: str, seed: int) -> list[np.ndarray]:
    from eval.doodles import _people_palm, _rng  # the module's own test may look inside it

    return _people_palm(_rng("palm:" + form, seed), form)


def _is_coconut(st: np.ndarray) -> bool:
    """A small closed round stroke (a coconut): ends together, a few units across."""
    span = np.ptp(st, axis=0)
    return bool(np.allclose(st[0], st[-1]) and 6 < span.min() <= span.max() < 16)


def _is_ring(st: np.ndarray) -> bool:
    """A short stroke across the trunk: a ring (three points, side to side, nearly level)."""
    dx, dy = np.ptp(st, axis=0)
    return len(st) <= 3 and 4 < dx < 25 and dy < 6


def test_some_palms_have_coconuts_and_some_ringed_trunks() -> None:
    with_nuts = with_rings = 0
    for form in PALM_FORMS:
        for seed in range(10):
            strokes = _palm_strokes(form, seed)
            with_nuts += any(_is_coconut(st) for st in strokes)
            with_rings += sum(_is_ring(st) for st in strokes) >= 3
    # sometimes, not always: about a third have coconuts, about half a ringed trunk
    assert 5 <= with_nuts <= 30, with_nuts
    assert 8 <= with_rings <= 32, with_rings


def test_tree_doodle_palms_include_the_people_forms() -> None:
    from eval.doodles import _variety  # the module's own test may look inside it

    varieties = [_variety("palm", seed) for seed in range(40)]
    assert None in varieties and set(PALM_FORMS) <= set(varieties)
    assert all(_variety("oak", seed) not in PALM_FORMS for seed in range(40))
    # a palm seed drawn with a people form is that form's drawing on the palm's own stream
    seed = varieties.index("leaf")
    _check_page(tree_doodle("palm", seed), "palm leaf")


# --------------------------------------------------------------------- broadleaves as people draw them


def _people_seeds(species: str, n: int) -> list[int]:
    from eval.doodles import _variety  # the module's own test may look inside it

    return [k for k in range(400) if _variety(species, k) == "people"][:n]


def test_people_trees_are_a_share_of_the_broadleaves_only() -> None:
    from eval.doodles import _variety

    for species in ("oak", "maple", "cherry"):
        share = np.mean([_variety(species, k) == "people" for k in range(400)])
        assert 0.25 < share < 0.6, (species, share)
    for species in ("pine", "fir", "poplar", "willow", "birch", "winter", "bonsai"):
        assert all(_variety(species, k) is None for k in range(100)), species


def test_people_trees_are_seeded_on_the_page_and_mostly_centred() -> None:
    for species in ("oak", "maple", "cherry"):
        seeds = _people_seeds(species, 12)
        a = tree_doodle(species, seeds[0])
        assert np.array_equal(a, tree_doodle(species, seeds[0]))
        for seed in seeds:
            _check_page(tree_doodle(species, seed), f"people {species} {seed}")
    # near the middle, as people draw; a few small in a corner
    centres, sizes = [], []
    for species, seed in [(s, k) for s in ("oak", "maple", "cherry") for k in _people_seeds(s, 30)]:
        rows, cols = np.nonzero(tree_doodle(species, seed) < 128)
        centres.append(np.hypot(rows.mean() - SIZE / 2, cols.mean() - SIZE / 2))
        sizes.append(max(np.ptp(rows), np.ptp(cols)) / SIZE)
    assert np.median(centres) < 25, np.median(centres)
    assert any(c > 60 and s < 0.55 for c, s in zip(centres, sizes, strict=True))


def test_people_trees_are_taller_than_their_trunks_are_wide() -> None:
    # the thick trunk people draw: a quarter of the crown's width, against a tenth for the
    # species' own drawers (eval.drawing_stats: the trunk is the narrow bottom of the ink)
    from eval.drawing_stats import image_stats

    people = [
        image_stats(tree_doodle("maple", k))["trunk_width"] for k in _people_seeds("maple", 16)
    ]
    assert 0.17 < np.median(people) < 0.35, np.median(people)


def test_people_trees_have_things_beside_them_for_some_seeds() -> None:
    from eval.doodles import _beside, _rng  # the module's own test may look inside it

    seen = {"ground": 0, "hill": 0, "grass": 0, "sun": 0, "cloud": 0, "nothing": 0}
    for seed in range(300):
        strokes = _beside(_rng("beside", seed), 50.0, 150.0)
        closed = [st for st in strokes if len(st) > 3 and np.allclose(st[0], st[-1])]
        seen["ground"] += any(len(st) == 2 and np.ptp(st[:, 0]) > 40 for st in strokes)
        seen["hill"] += any(len(st) == 30 for st in strokes)
        seen["grass"] += any(len(st) == 5 for st in strokes)
        rays = sum(len(st) == 2 and np.ptp(st[:, 0]) < 20 for st in strokes)
        seen["sun"] += bool(closed) and rays >= 6
        seen["cloud"] += bool(closed) and rays == 0
        seen["nothing"] += not strokes
    # each sometimes, none always; most trees stand alone
    assert all(v >= 5 for v in seen.values()), seen
    assert seen["nothing"] > 150, seen
