"""A person's drawing, not only our renderer's: pencil on grey paper, a drawing in a corner of
a big page, a dark page, noise.  The one reader normalises them; the network and the
refinement see the same normalised image.  The style-blind distance puts one tree drawn in
two styles closer than two trees of a species, and the low-confidence warning flags what is
not a tree but not a plain outline drawing of one."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
from PIL import Image, ImageDraw

from eval.pages import bordered, captioned, within_a_pixel
from refine.objective import SearchSpace
from refine.shape import shape_distance
from render.reader import FRAME_BOTTOM, SketchError, light_on_dark, normalise_drawing
from treesketch import Pipeline, RefineSettings
from treesketch.pipeline import load_sketch, prepare_input
from weberpenn import build_mesh, grow, species

HAND = Path(__file__).resolve().parents[1] / "examples" / "hand"


@pytest.fixture(scope="module")
def sketches() -> dict[str, np.ndarray]:
    from render.sketch import SketchRenderer

    out = {}
    for name, seed in (("maple", 41), ("pine", 42)):
        tree = build_mesh(grow(species.sample(name, seed)), species=name)
        out[name] = SketchRenderer(tree).sketch(0.0, 256)
    return out


@pytest.fixture(scope="module")
def pipeline() -> Pipeline:
    return Pipeline("tsn", RefineSettings(refine=False))


def pencil_on_grey(img: np.ndarray, seed: int = 0) -> np.ndarray:
    """Light pencil strokes (about 40% as dark as pen) on grey paper lit from one side,
    with paper grain."""
    rng = np.random.default_rng(seed)
    h, w = img.shape
    paper = np.linspace(150.0, 205.0, w)[None, :] * np.ones((h, 1))
    stroke = (255.0 - img.astype(np.float64)) * 0.4
    return np.clip(paper - stroke + rng.normal(0, 4, (h, w)), 0, 255).astype(np.uint8)


def in_corner(img: np.ndarray, page: int = 850) -> np.ndarray:
    """The drawing at its own size in the top-right corner of a big white page (30% of the
    page's side)."""
    out = np.full((page, page), 255, np.uint8)
    h, w = img.shape
    out[30 : 30 + h, page - w - 40 : page - 40] = img
    return out


def _unit(params, name: str) -> np.ndarray:
    return SearchSpace.create(name, params, search_yaw=False).from_params(params)


def test_normalising_is_idempotent_and_frames_the_tree(sketches) -> None:
    for img in sketches.values():
        once = normalise_drawing(img, 256)
        twice = normalise_drawing(once, 256)
        assert np.mean(once != twice) < 0.002
        ys = np.flatnonzero((once < 128).any(axis=1))
        assert abs((ys[-1] + 1) / 256 - FRAME_BOTTOM) < 0.02


def test_pencil_on_grey_paper_reads_as_ink_and_the_same_species(sketches, pipeline) -> None:
    for name, img in sketches.items():
        grey = pencil_on_grey(img)
        assert (grey < 200).mean() > 0.5  # the old ink rule saw a dark page
        clean = prepare_input(grey)
        ink_clean, ink_true = clean < 128, prepare_input(img) < 128
        overlap = (ink_clean & ink_true).sum() / max(ink_true.sum(), 1)
        assert overlap > 0.9 and ink_clean.mean() < 1.3 * ink_true.mean()
        on_white, on_grey = pipeline.estimate(img), pipeline.estimate(grey)
        assert on_grey.species == on_white.species == name


@pytest.mark.parametrize("level", [140, 180, 210])
def test_a_flat_grey_pen_reads_like_black_ink(level: int) -> None:
    """A line drawing of two grey levels (a grey pen in a paint program, no smoothing) has
    its Otsu split at the pen's own level: its lines are the ink, not a blank page."""
    hand = Path(__file__).resolve().parents[1] / "examples" / "hand"
    for name in ("oak", "poplar", "palm_lines"):
        lines = np.asarray(Image.open(hand / f"{name}.png").convert("L")) < 128
        grey = prepare_input(np.where(lines, level, 255).astype(np.uint8)) < 128
        black = prepare_input(np.where(lines, 0, 255).astype(np.uint8)) < 128
        assert (grey != black).sum() <= 0.01 * black.sum(), name


def _lollipop(crown: tuple[int, int, int], fill: tuple[int, int, int] | None = None) -> Image.Image:
    """A child's lollipop tree in colour: a brown trunk under a round crown drawn with
    ``crown``'s pen, coloured in with ``fill``."""
    im = Image.new("RGB", (400, 400), "white")
    d = ImageDraw.Draw(im)
    d.line((200, 370, 200, 240), fill=(150, 100, 50), width=6)
    d.ellipse((110, 70, 290, 250), fill=fill, outline=crown, width=4)
    return im


def test_a_second_lighter_pen_is_ink_too(monkeypatch) -> None:
    """A yellow-green crown over a brown trunk: Otsu's split falls between the two pens,
    and the lighter one's lines are the drawing too (not the trunk alone).  A crown
    coloured in keeps its outline and leaves out its fill; a lined page's rules, one
    level too, stay paper."""
    import render.reader
    from render.reader import read_sketch

    black = prepare_input(read_sketch(_lollipop((0, 0, 0)))) < 128
    light = prepare_input(read_sketch(_lollipop((120, 210, 80)))) < 128
    assert (light & black).sum() / (light | black).sum() > 0.8
    filled = prepare_input(read_sketch(_lollipop((40, 140, 40), fill=(140, 220, 90)))) < 128
    assert filled.mean() < 2 * black.mean()  # lines, not a disc of ink
    assert (filled & black).sum() / (filled | black).sum() > 0.6
    lined = read_sketch(HAND / "ballpoint.png")
    now = prepare_input(lined)
    monkeypatch.setattr(render.reader, "PEN_SHARE", 2.0)  # no second pen
    assert np.array_equal(prepare_input(lined), now)


def _ink_read(page: Any) -> np.ndarray:
    """The ink of ``page`` as the pipeline reads and frames it."""
    from render.reader import ink_mask, read_sketch

    return ink_mask(prepare_input(read_sketch(page)))


def test_a_caption_under_or_over_the_drawing_is_not_the_tree(monkeypatch) -> None:
    """Words written under or over a drawing ("My tree", a title) are not the tree's roots
    or crown: it is framed as without them.  A pot drawn in pieces under a tree, apart
    from its trunk, stays the tree's."""
    import render.reader

    oak = Image.open(HAND / "oak.png")
    alone = _ink_read(captioned(oak, ""))  # the same page, nothing written
    for under, over in (("My tree", ""), ("Anna 7", "TREE")):
        # the words move the page's ink level a little: a line may move by a pixel
        assert within_a_pixel(_ink_read(captioned(oak, under, over)), alone) > 0.95, under
    # a tree over a pot drawn as four strokes, none touching the trunk
    img = Image.new("L", (400, 400), 255)
    d = ImageDraw.Draw(img)
    d.ellipse((110, 30, 290, 190), outline=0, width=4)
    d.line((190, 190, 190, 300), fill=0, width=4)
    d.line((210, 190, 210, 300), fill=0, width=4)
    for stroke in (
        (130, 315, 270, 315),
        (130, 322, 150, 370),
        (270, 322, 250, 370),
        (155, 376, 245, 376),
    ):
        d.line(stroke, fill=0, width=4)
    now = _ink_read(img)
    monkeypatch.setattr(render.reader, "CAPTION_MARKS", 10**9)  # no captions read
    assert np.array_equal(_ink_read(img), now)
    monkeypatch.undo()
    # the pot in pieces is no caption, written under it a name is
    assert within_a_pixel(_ink_read(captioned(img, "Anna")), _ink_read(captioned(img, ""))) > 0.95


def test_a_frame_drawn_round_the_drawing_is_not_the_tree(monkeypatch) -> None:
    """A border drawn round the drawing by hand (four wobbly strokes, gaps at the
    corners) is not the tree's outline: the tree is framed as without it."""
    import render.reader

    oak = Image.open(HAND / "oak.png")
    alone = _ink_read(bordered(oak, frame=False))
    assert within_a_pixel(_ink_read(bordered(oak)), alone) > 0.95
    monkeypatch.setattr(render.reader, "FRAME_COVER", 2.0)  # no frame read
    assert within_a_pixel(_ink_read(bordered(oak)), alone) < 0.5


def test_drawing_in_a_corner_gives_the_same_tree(sketches, pipeline) -> None:
    for name, img in sketches.items():
        page = in_corner(img)
        framed = prepare_input(page)
        ys = np.flatnonzero((framed < 128).any(axis=1))
        assert abs((ys[-1] + 1) / 256 - FRAME_BOTTOM) < 0.02
        centred, corner = pipeline.estimate(img), pipeline.estimate(page)
        assert corner.species == centred.species == name
        diff = np.abs(_unit(corner.params, name) - _unit(centred.params, name))
        assert diff.mean() < 0.05 and diff.max() < 0.25


def _frame_box(img: np.ndarray) -> tuple[int, int, int, int]:
    ys = np.flatnonzero((img < 128).any(axis=1))
    xs = np.flatnonzero((img < 128).any(axis=0))
    return int(ys[0]), int(ys[-1]), int(xs[0]), int(xs[-1])


def test_specks_away_from_the_drawing_do_not_shrink_it(sketches) -> None:
    """Pencil dust or a speck of dirt far from the tree is not part of the drawing: the
    tree is framed as without it (not shrunk towards the middle to make room for it)."""
    for img in sketches.values():
        page = np.full((512, 512), 255, np.uint8)
        page[128:384, 128:384] = img
        dusty = page.copy()
        for y, x in ((20, 30), (480, 470), (60, 440), (300, 15)):
            dusty[y : y + 3, x : x + 3] = 60  # a few specks, each 3 x 3 px
        clean, with_dust = normalise_drawing(page, 256), normalise_drawing(dusty, 256)
        assert np.abs(np.subtract(_frame_box(clean), _frame_box(with_dust))).max() <= 1
        assert np.mean(clean != with_dust) < 0.002


def grainy(img: np.ndarray, seed: int = 0, specks: int = 400) -> np.ndarray:
    """The drawing on coarse paper: ``specks`` dark grains of 1-3 px all over the page,
    among the strokes too (what pencil on textured paper or a noisy photo gives)."""
    rng = np.random.default_rng(seed)
    out = img.copy()
    h, w = img.shape
    for y, x, s in zip(
        rng.integers(0, h - 3, specks),
        rng.integers(0, w - 3, specks),
        rng.integers(1, 3, specks),
        strict=True,
    ):
        out[y : y + s, x : x + s] = 70
    return out


def test_paper_grain_among_the_strokes_is_not_ink(sketches, pipeline) -> None:
    """Grain near the drawing is not removed as strays; it goes as specks smaller than
    the strokes and apart from them, and the tree reads as on clean paper."""
    for name, img in sketches.items():
        page = np.full((384, 384), 255, np.uint8)
        page[64:320, 64:320] = img
        clean, coarse = (
            normalise_drawing(page, 256) < 128,
            normalise_drawing(grainy(page), 256) < 128,
        )
        assert np.abs(np.subtract(_frame_box(clean), _frame_box(coarse))).max() <= 2
        assert coarse.sum() < 1.1 * clean.sum()  # the grain is gone ...
        assert (coarse & clean).sum() > 0.97 * clean.sum()  # ... the strokes are not
        assert pipeline.estimate(grainy(page)).species == name


@pytest.mark.parametrize("name, seed", [("palm", 190), ("maple", 7), ("pine", 4)])
def test_light_pencil_on_fine_grain_reads_as_its_strokes(name: str, seed: int, pipeline) -> None:
    """Few light strokes on grey paper whose grain is fine and strong: Otsu alone splits
    the grain (a tenth of the page came out as ink), so a mark is ink only where some of
    it is darker than the paper's grain reaches.  The same strokes on the same paper
    without grain are the reference."""
    from render.sketch import SketchRenderer
    from render.styles import Silhouettes, pencil

    tree = build_mesh(grow(species.sample(name, seed)), species=name)
    sil = Silhouettes.from_parts(SketchRenderer(tree).parts(90.0, 256))
    hard = {
        "paper": (0.75, 0.75),
        "darkness": (0.4, 0.4),
        "shading": (0.0, 0.0),
        "line_px": (1.1, 1.1),
        "gaps": (0.3, 0.3),
    }
    grainy = pencil(sil, np.random.default_rng(seed), **hard, grain=(0.035, 0.035))
    smooth = pencil(sil, np.random.default_rng(seed), **hard, grain=(0.0, 0.0))
    assert np.std(grainy[grainy > 180]) > 5 > np.std(smooth[smooth > 180])  # the grain
    clean, coarse = normalise_drawing(smooth) < 128, normalise_drawing(grainy) < 128
    assert np.abs(np.subtract(_frame_box(clean), _frame_box(coarse))).max() <= 4
    assert 0.5 * clean.sum() < coarse.sum() < 2.0 * clean.sum()
    assert pipeline.estimate(grainy).species == pipeline.estimate(smooth).species == name


def test_the_renderers_own_small_marks_are_kept(sketches) -> None:
    """The grain rule leaves a renderer sketch as it is: its small marks (a leaf, a twig's
    end) lie next to its strokes."""
    from render.reader import drop_specks, stroke_width

    for img in sketches.values():
        for side in (256, 128):
            ink = np.asarray(Image.fromarray(img).resize((side, side), Image.BOX)) < 128
            assert 1.0 <= stroke_width(ink) <= 6.0
            assert np.array_equal(drop_specks(ink), ink)


def test_dark_page_is_a_clear_error() -> None:
    rng = np.random.default_rng(1)
    dark = np.clip(rng.normal(30, 8, (300, 300)), 0, 255).astype(np.uint8)
    with pytest.raises(SketchError, match="too dark"):
        prepare_input(dark)
    with pytest.raises(SketchError, match="blank"):
        prepare_input(np.clip(rng.normal(200, 3, (300, 300)), 0, 255).astype(np.uint8))
    # a black disc over most of a white page is a fill, not a dark page
    yy, xx = np.mgrid[:300, :300]
    disc = np.where((yy - 150) ** 2 + (xx - 150) ** 2 < 140**2, 0, 255).astype(np.uint8)
    with pytest.raises(SketchError, match="filled area"):
        prepare_input(disc)


def test_light_lines_on_a_dark_page_read_as_the_same_drawing(sketches) -> None:
    """Chalk on a board or a drawing app in dark mode: the light lines are the drawing,
    read as the same lines dark on white (the same normalised picture)."""
    img = sketches["maple"]
    want = prepare_input(img)
    assert np.array_equal(prepare_input(255 - img), want)
    # chalk on a grey-green board: a dark, grainy ground, lines at three fifths of white
    rng = np.random.default_rng(3)
    lines = (255 - img.astype(float)) / 255.0
    board = np.clip(55 + rng.normal(0, 6, img.shape) + 150 * lines, 0, 255).astype(np.uint8)
    got = prepare_input(board) < 128
    iou = (got & (want < 128)).sum() / (got | (want < 128)).sum()
    assert iou > 0.9
    # the page itself read, not its border: a dark drawing on white is read as before
    assert not light_on_dark(img) and light_on_dark(255 - img) and light_on_dark(board)
    # a night photo's lights (dots) and a lit window (an area) are no lines: too dark
    night = np.clip(rng.normal(30, 8, (300, 300)), 0, 255).astype(np.uint8)
    window = night.copy()
    window[80:150, 110:200] = 220
    for y, x in rng.integers(10, 290, (20, 2)):
        night[y - 3 : y + 3, x - 3 : x + 3] = 230
    with pytest.raises(SketchError, match="too dark"):
        prepare_input(night)
    assert not light_on_dark(window)
    # the board's photo put on a wider white page, as the web page's pad shows a picture
    # of another shape: read within its margins
    pad, plain = np.full((256, 400), 255, np.uint8), np.full((256, 400), 255, np.uint8)
    pad[:, 72:328], plain[:, 72:328] = board, img
    got, want = prepare_input(pad) < 128, prepare_input(plain) < 128
    assert (got & want).sum() / (got | want).sum() > 0.9


def _drawn(seed: int, style: str, index: int) -> np.ndarray:
    """Maple ``seed`` at yaw 30 drawn in ``style`` (as benchmarks/bench_distance.py draws)."""
    from render.sketch import SketchRenderer
    from render.styles import Silhouettes, draw

    tree = build_mesh(grow(species.sample("maple", seed)), species="maple")
    sil = Silhouettes.from_parts(SketchRenderer(tree).parts(30.0, 256))
    return normalise_drawing(draw(style, sil, np.random.default_rng([seed, index]), 256), 256)


def test_one_tree_in_two_styles_is_closer_than_two_trees_of_a_species() -> None:
    a_sg, a_cloud = _drawn(1, "sg", 0), _drawn(1, "cloud", 1)
    b_sg, b_cloud = _drawn(2, "sg", 0), _drawn(2, "cloud", 1)
    same_tree = shape_distance(a_sg, a_cloud)
    assert shape_distance(a_sg, a_sg) == 0.0
    # symmetric up to float32 rounding (the features are float32 sums)
    assert same_tree == pytest.approx(shape_distance(a_cloud, a_sg), abs=1e-6)
    assert same_tree < 0.8 * shape_distance(a_sg, b_sg)
    assert same_tree < 0.8 * shape_distance(a_cloud, b_cloud)


def _face() -> np.ndarray:
    im = Image.new("L", (256, 256), 255)
    d = ImageDraw.Draw(im)
    d.ellipse((28, 28, 228, 228), outline=0, width=3)
    d.ellipse((78, 80, 98, 100), fill=0)
    d.ellipse((158, 80, 178, 100), fill=0)
    d.arc((78, 110, 178, 190), 20, 160, fill=0, width=3)
    return np.asarray(im)


def _house() -> np.ndarray:
    im = Image.new("L", (256, 256), 255)
    d = ImageDraw.Draw(im)
    d.rectangle((50, 115, 205, 230), outline=0, width=3)
    d.line([(40, 115), (128, 40), (215, 115)], fill=0, width=3)
    d.rectangle((112, 170, 143, 230), outline=0, width=3)
    return np.asarray(im)


def _line(dot: bool = False) -> np.ndarray:
    """One slightly wobbly upright stroke (with a dot on its top)."""
    im = Image.new("L", (400, 400), 255)
    d = ImageDraw.Draw(im)
    d.line([(200, 370), (203, 260), (198, 150), (201, 90)], fill=0, width=4)
    if dot:
        d.ellipse((192, 72, 210, 90), fill=0)
    return np.asarray(im)


def _strokes(*lines: list[tuple[int, int]]) -> np.ndarray:
    """Straight strokes of a pen 4 px wide on a 400 px page."""
    im = Image.new("L", (400, 400), 255)
    d = ImageDraw.Draw(im)
    for line in lines:
        d.line(line, fill=0, width=4)
    return np.asarray(im)


TWO_LINES = {
    "a cross": lambda: _strokes([(200, 370), (201, 60)], [(110, 150), (290, 152)]),
    "an X": lambda: _strokes([(80, 80), (320, 320)], [(320, 80), (80, 320)]),
    "a T": lambda: _strokes([(200, 370), (201, 80)], [(90, 80), (310, 82)]),
    "a V": lambda: _strokes([(100, 80), (200, 350)], [(200, 350), (300, 80)]),
}

NOT_TREES = {
    "noise": lambda: ((np.random.default_rng(0).random((256, 256)) > 0.6) * 255).astype(np.uint8),
    "face": _face,
    "house": _house,
    "one line": _line,
    "a stick with a dot": lambda: _line(dot=True),
    **TWO_LINES,
}


def test_one_straight_line_is_told_from_every_drawn_tree() -> None:
    """``render.reader.line_spread``: a line (with a dot on it) spreads across its axis a
    small share of its reach; every drawing of ``examples/hand`` (a lollipop's stick
    under its crown, a palm's single-line trunk) spreads far more."""
    from render.reader import line_spread
    from treesketch.pipeline import LINE_SPREAD

    for img in (_line(), _line(dot=True)):
        assert line_spread(_ink_read(img)) < LINE_SPREAD / 2
    for path in sorted(HAND.glob("*.png")):
        assert line_spread(_ink_read(load_sketch(path))) > 2 * LINE_SPREAD, path.name


def test_two_straight_lines_are_told_from_every_drawn_tree() -> None:
    """``render.reader.straight_share``: a cross, an X, a T or a V drawn with two strokes
    lies wholly on its two strongest straight lines; a stick tree of three strokes (a
    trunk forking in two) and every drawing of ``examples/hand`` do not."""
    from render.reader import straight_share
    from treesketch.pipeline import STRAIGHT_SHARE

    for name, make in TWO_LINES.items():
        assert straight_share(_ink_read(make())) > (1 + STRAIGHT_SHARE) / 2, name
    fork = _strokes([(200, 370), (200, 200)], [(200, 200), (130, 90)], [(200, 200), (270, 90)])
    assert straight_share(_ink_read(fork)) < STRAIGHT_SHARE - 0.1
    for path in sorted(HAND.glob("*.png")):
        assert straight_share(_ink_read(load_sketch(path))) < STRAIGHT_SHARE / 2, path.name


@pytest.fixture(scope="module")
def refining() -> Pipeline:
    return Pipeline("tsn", RefineSettings(budget=10, species_tries=1))


@pytest.fixture(scope="module")
def estimating(refining: Pipeline) -> Pipeline:
    """The same network, its first tree returned unrefined."""
    return refining.with_settings(refine=False)


@pytest.mark.parametrize("kind", sorted(NOT_TREES))
def test_what_is_not_a_tree_gets_the_warning(kind: str, estimating: Pipeline) -> None:
    # the network's probability that the drawing is a tree (and the one-line rule) decide
    # the warning, not the search: the first tree carries it (refined: the next test)
    r = estimating.run(NOT_TREES[kind]())
    assert r.warning is not None and "low confidence" in r.warning, r.losses


@pytest.mark.slow
def test_a_refined_tree_keeps_the_warning_of_its_drawing(
    refining: Pipeline, estimating: Pipeline
) -> None:
    first = estimating.run(_house())
    refined = refining.run(_house())
    assert first.refinement is None and refined.refinement.evaluations > 0
    assert first.warning is not None and refined.warning is not None
    # the same question, the same probability; only the distances it quotes moved
    assert refined.warning.split("%")[0] == first.warning.split("%")[0]
    assert refined.estimate.tree_probability == first.estimate.tree_probability < 0.5


@pytest.mark.slow
def test_a_plain_outline_tree_gets_no_warning(refining: Pipeline) -> None:
    # a child's tree: a cloud of a crown on a trunk drawn as two lines, nothing inside
    r = refining.run(HAND / "cloud_tree.png")
    assert r.warning is None, r.losses


def on_lined_paper(img: np.ndarray, page: int = 512) -> np.ndarray:
    """The drawing on a page of lined paper: dark ruled lines every 24 px, one of them
    tilted by a pixel over the page, and a margin line down the left."""
    out = np.full((page, page), 250, np.uint8)
    h, w = img.shape
    y0, x0 = (page - h) // 2, (page - w) // 2
    for y in range(20, page, 24):
        out[y, :] = 110
    out[44, page // 2 :] = 250  # the tilted one: its right half one row down
    out[45, page // 2 :] = 110
    out[:, 40] = 120
    region = out[y0 : y0 + h, x0 : x0 + w]
    out[y0 : y0 + h, x0 : x0 + w] = np.minimum(region, img)
    return out


def test_a_tall_trunk_is_not_taken_for_a_margin() -> None:
    """A palm's trunk spans most of its framed sketch's height but not the page's edges:
    normalising keeps it (the same as on a page with a wide white border, where nothing
    spans 80 % of the height), at the search's size and the dataset's."""
    from pathlib import Path

    from scipy import ndimage

    from render.sketch import SketchRenderer
    from weberpenn import load_params

    gt = load_params(Path(__file__).parent / "data" / "treesketchnet_test_params" / "3_palm_3.json")
    renderer = SketchRenderer(build_mesh(grow(gt), species="palm"))
    for size in (128, 256):
        img = renderer.sketch(0.0, size)
        direct = normalise_drawing(img, size) < 128
        ref = normalise_drawing(np.pad(img, size // 2, constant_values=255), size) < 128
        near = ndimage.binary_dilation(direct, np.ones((3, 3), bool))
        assert (ref & ~near).sum() <= 0.02 * ref.sum(), size


def test_ruled_lines_and_margin_of_lined_paper_are_not_ink(sketches) -> None:
    img = sketches["maple"]
    plain = normalise_drawing(img, 256)
    lined = normalise_drawing(on_lined_paper(img), 256)
    ink_plain, ink_lined = plain < 128, lined < 128
    from scipy import ndimage

    # the same drawing, framed the same: nothing of the ruling is left, no stroke is cut
    # where it crosses a line (ink of either within 2 px of the other's)
    def off(a: np.ndarray, b: np.ndarray) -> float:
        return float((a & ~ndimage.binary_dilation(b, iterations=2)).sum() / a.sum())

    assert off(ink_lined, ink_plain) < 0.03 and off(ink_plain, ink_lined) < 0.03
    rows = ink_lined.mean(axis=1)
    assert rows.max() < 0.5  # no line across the page
    # a dense drawing that fills the page is not taken for ruling
    rng = np.random.default_rng(3)
    scribble = np.where(rng.random((256, 256)) < 0.35, 0, 255).astype(np.uint8)
    scribble[:, :] = np.where(np.arange(256)[None, :] % 3 == 0, 0, scribble)
    assert normalise_drawing(scribble, 256).mean() < 200
