"""render.dataset and `treesketch dataset build`: layout, manifest, split, resume, kill."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from build_helpers import kill_and_resume_build
from PIL import Image
from typer.testing import CliRunner

from render.dataset import (
    MANIFEST_COLUMNS,
    DatasetConfig,
    DatasetError,
    assign_splits,
    build_dataset,
    plan,
    read_manifest,
    tree_seed,
)
from treesketch.cli import app

ROOT = Path(__file__).resolve().parents[1]
SMALL = {"trees_per_species": 2, "views": ("front", "left"), "size": 48}


def _check_dataset(out: Path, cfg: DatasetConfig) -> list[dict]:
    """Every manifest row points at valid files; no duplicates; split by tree."""
    rows = read_manifest(out)
    n_trees = len(cfg.species) * cfg.trees_per_species
    assert len(rows) == n_trees * len(cfg.views)
    keys = [(r["tree_id"], r["view"]) for r in rows]
    assert len(set(keys)) == len(keys)
    split_of: dict[str, str] = {}
    for r in rows:
        assert list(r) == list(MANIFEST_COLUMNS)
        assert split_of.setdefault(r["tree_id"], r["split"]) == r["split"]
        with Image.open(out / r["sketch"]) as im:
            im.load()
            assert im.size == (cfg.size, cfg.size) and im.mode == "L"
        with Image.open(out / r["render"]) as im:
            im.load()
            assert im.mode == "RGB"
        params = json.loads((out / r["params"]).read_text())
        assert params["seed"] == r["tree_seed"]
    csv_lines = (out / "manifest.csv").read_text().splitlines()
    assert csv_lines[0].split(",") == list(MANIFEST_COLUMNS)
    assert len(csv_lines) == len(rows) + 1
    assert not list(out.rglob("*.tmp"))
    assert (out / "DONE").is_file()
    return rows


# --------------------------------------------------------------------------- planning
def test_split_is_by_tree_stratified_and_seeded():
    labels = assign_splits(250, 0, 0, 0.1, 0.1)
    assert labels.count("train") == 200 and labels.count("val") == 25
    assert labels.count("test") == 25
    assert labels == assign_splits(250, 0, 0, 0.1, 0.1)
    assert labels != assign_splits(250, 1, 0, 0.1, 0.1)
    assert assign_splits(1, 0, 0, 0.1, 0.1) == ["train"]
    assert "train" in assign_splits(3, 0, 0, 0.4, 0.4)


def test_plan_seeds_are_deterministic_and_distinct():
    cfg = DatasetConfig(out="unused", trees_per_species=250)
    jobs = plan(cfg)
    assert len(jobs) == 1250
    seeds = [j.tree_seed for j in jobs]
    assert len(set(seeds)) == len(seeds)
    assert all(0 <= s < 2**31 for s in seeds)
    assert seeds == [j.tree_seed for j in plan(cfg)]
    assert tree_seed(0, 0, 0) != tree_seed(1, 0, 0)
    # the demo sketch (examples/sketch_maple.png) uses maple seed 100000: not a train tree
    assert 100000 not in {j.tree_seed for j in jobs if j.split == "train"}
    # a species keeps its trees when built alone
    alone = plan(DatasetConfig(out="unused", trees_per_species=250, species=("palm",)))
    assert [j.tree_seed for j in alone] == [j.tree_seed for j in jobs if j.species == "palm"]


def test_views_between_the_axes_are_yaws_in_degrees():
    cfg = DatasetConfig(out="x", views=("front", "45", "22.5", "315"))
    assert cfg.views == ("front", "45", "22.5", "315")


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"species": ("baobab",)}, "unknown species 'baobab'"),
        ({"views": ("top",)}, "unknown view 'top'"),
        ({"views": ("front", "front")}, "twice"),
        ({"views": ("0", "front")}, "twice"),
        ({"views": ("45.0",)}, "unknown view '45.0'"),
        ({"views": ("360",)}, "unknown view '360'"),
        ({"views": ("-30",)}, "unknown view '-30'"),
        ({"views": ("nan",)}, "unknown view 'nan'"),
        ({"size": 10}, "size"),
        ({"trees_per_species": 0}, "trees_per_species"),
        ({"seed": -1}, "seed"),
        ({"val_fraction": 0.6, "test_fraction": 0.5}, "fraction"),
        ({"workers": 0}, "workers"),
        ({"styles": ("sg", "crayon")}, "unknown drawing style 'crayon'"),
        ({"styles": ()}, "no drawing style"),
        ({"styles": ("sg", "pen"), "styles_per_view": 0}, "styles_per_view"),
    ],
)
def test_bad_settings_are_clear_errors(kwargs, match):
    with pytest.raises(DatasetError, match=match):
        DatasetConfig(out="x", **kwargs)


@pytest.mark.parametrize(
    "args, match",
    [
        (["--views", "front,top"], "unknown view 'top'"),
        (["--species", "maple,baobab"], "unknown species 'baobab'"),
        (["--trees-per-species", "0"], "trees-per-species"),
        (["--size", "7"], "size"),
        (["--workers", "0"], "workers"),
        (["--views", ","], "at least one view"),
        (["--styles", "sg,crayon"], "unknown drawing style 'crayon'"),
    ],
)
def test_cli_bad_arguments(tmp_path, args, match):
    res = CliRunner().invoke(app, ["dataset", "build", "--out", str(tmp_path / "d"), *args])
    assert res.exit_code == 2
    text = " ".join((res.output + (res.stderr if res.stderr_bytes else "")).split())
    assert match in text
    assert not (tmp_path / "d").exists()


def test_cli_requires_out():
    res = CliRunner().invoke(app, ["dataset", "build"])
    assert res.exit_code == 2 and "--out" in res.output


# --------------------------------------------------------------------------- building
@pytest.fixture(scope="module")
def built(tmp_path_factory):
    out = tmp_path_factory.mktemp("ds") / "small"
    cfg = DatasetConfig(out=str(out), **SMALL)
    summary = build_dataset(cfg, progress=False)
    return out, cfg, summary


def test_build_writes_a_complete_dataset(built):
    out, cfg, summary = built
    assert summary.built == 10 and summary.failed == [] and summary.sketches == 20
    rows = _check_dataset(out, cfg)
    assert {r["species"] for r in rows} == set(cfg.species)
    assert json.loads((out / "dataset.json").read_text())["size"] == 48
    sk = np.asarray(Image.open(out / rows[0]["sketch"]))
    assert sk[0].min() == 255 and sk.min() < 128  # white background, dark lines


def test_rerun_skips_finished_trees_and_is_identical(built):
    out, cfg, _ = built
    before = (out / "manifest.jsonl").read_bytes()
    s = build_dataset(cfg, progress=False)
    assert s.skipped == 10 and s.built == 0
    assert (out / "manifest.jsonl").read_bytes() == before


def test_same_seed_same_bytes(built):
    out, cfg, _ = built
    victim = "palm_0001"
    files = {p: p.read_bytes() for p in out.rglob(f"{victim}*") if p.is_file()}
    assert len(files) == 5  # 2 sketches, params, render, marker
    (out / "done" / f"{victim}.json").unlink()
    s = build_dataset(cfg, progress=False)
    assert s.built == 1
    for p, data in files.items():
        if p.parent.name != "done":  # the marker holds timings
            assert p.read_bytes() == data, p


def test_other_settings_refused(built):
    out, cfg, _ = built
    other = DatasetConfig(out=str(out), **{**SMALL, "size": 64})
    with pytest.raises(DatasetError, match="other settings"):
        build_dataset(other, progress=False)


def test_failing_tree_is_logged_and_the_run_goes_on(tmp_path, monkeypatch):
    import weberpenn

    real_grow = weberpenn.grow

    def flaky_grow(params, seed=0):
        if params["seed"] == tree_seed(0, 3, 0):  # palm_0000
            raise RuntimeError("boom")
        return real_grow(params, seed)

    monkeypatch.setattr(weberpenn, "grow", flaky_grow)
    cfg = DatasetConfig(out=str(tmp_path / "d"), trees_per_species=1, views=("front",), size=32)
    s = build_dataset(cfg, progress=False)
    assert s.failed == ["palm_0000"] and s.built == 4
    rec = json.loads((tmp_path / "d" / "failed" / "palm_0000.json").read_text())
    assert "boom" in rec["error"] and rec["params"]["seed"] == tree_seed(0, 3, 0)
    assert len(read_manifest(tmp_path / "d")) == 4
    assert "1 failed" in s.text()


# --------------------------------------------------------------------------- kill -9
@pytest.mark.slow
def test_resumes_after_being_killed(tmp_path):
    out = tmp_path / "killed"
    # (the orphaned local workers notice and exit)
    kill_and_resume_build(out, ["--workers", "2"], timeout=120, settle=1.0)
    _check_dataset(out, DatasetConfig(out=str(out), **SMALL))


# --------------------------------------------------------------------------- styles
def test_sg_only_dataset_records_no_styles(built):
    out, _, _ = built
    assert "styles" not in json.loads((out / "dataset.json").read_text())
    assert all("style" not in r for r in read_manifest(out))
    assert read_manifest(out, styles=["sg"]) == read_manifest(out)
    assert read_manifest(out, styles=["pen"]) == []


def test_styled_build_keeps_the_sg_sketches_and_adds_one_style_per_view(built, tmp_path):
    sg_out, _, _ = built
    cfg = DatasetConfig(
        out=str(tmp_path / "styled"),
        **{**SMALL, "species": ("palm",)},
        styles=("sg", "pen", "pencil", "cloud"),
    )
    s = build_dataset(cfg, progress=False)
    assert s.failed == [] and s.sketches == 2 * 2 * 2
    out = Path(cfg.out)
    rows = read_manifest(out)
    assert all(list(r) == [*MANIFEST_COLUMNS, "style"] for r in rows)
    assert (out / "manifest.csv").read_text().splitlines()[0].endswith(",style")
    by_view: dict[tuple[str, str], list[str]] = {}
    for r in rows:
        by_view.setdefault((r["tree_id"], r["view"]), []).append(r["style"])
        with Image.open(out / r["sketch"]) as im:
            assert im.size == (48, 48) and im.mode == "L"
    for styles in by_view.values():  # SG, then one of the others
        assert styles[0] == "sg" and len(styles) == 2 and styles[1] in ("pen", "pencil", "cloud")
    for r in read_manifest(out, styles=["sg"]):  # the very bytes of an SG-only build
        assert (out / r["sketch"]).read_bytes() == (sg_out / r["sketch"]).read_bytes()
    other = [r for r in rows if r["style"] != "sg"]
    assert other and all(r["sketch"].endswith(f"_{r['style']}.png") for r in other)
    assert read_manifest(out, split="train", styles=["pen", "pencil", "cloud"]) == [
        r for r in other if r["split"] == "train"
    ]
    settings = json.loads((out / "dataset.json").read_text())
    assert settings["styles"] == ["sg", "pen", "pencil", "cloud"]
    before = {r["sketch"]: (out / r["sketch"]).read_bytes() for r in rows}
    (out / "done" / "palm_0000.json").unlink()
    again = build_dataset(cfg, progress=False)
    assert again.built == 1 and again.skipped == 1  # a finished styled tree is recognised
    assert {k: (out / k).read_bytes() for k in before} == before  # seeded: same bytes


def test_every_style_per_view(tmp_path):
    from render.dataset import view_styles

    st = {"styles": ["sg", "pen", "felt"], "styles_per_view": 5}
    assert view_styles(st, 123, 0) == ["sg", "pen", "felt"]
    st = {"styles": ["pen", "felt", "cloud"], "styles_per_view": 1}
    picks = {tuple(view_styles(st, seed, v)) for seed in range(30) for v in range(4)}
    assert picks == {("pen",), ("felt",), ("cloud",)}
    assert view_styles(st, 7, 2) == view_styles(st, 7, 2)


def test_only_one_split_builds_those_trees_with_the_full_builds_bytes(tmp_path):
    cfg = DatasetConfig(
        out=str(tmp_path / "full"), species=("palm",), trees_per_species=10,
        views=("front",), size=48, seed=3,
    )  # fmt: skip
    build_dataset(cfg, progress=False)
    part = DatasetConfig(**{**cfg.__dict__, "out": str(tmp_path / "test_only")})
    build_dataset(part, progress=False, only_split="test")
    rows = read_manifest(tmp_path / "test_only")
    full = [r for r in read_manifest(tmp_path / "full") if r["split"] == "test"]
    assert rows and [r["tree_id"] for r in rows] == [r["tree_id"] for r in full]
    for a, b in zip(rows, full, strict=True):
        assert (tmp_path / "test_only" / a["sketch"]).read_bytes() == (
            tmp_path / "full" / b["sketch"]
        ).read_bytes()
    with pytest.raises(DatasetError, match="only_split"):
        build_dataset(part, progress=False, only_split="holdout")


def test_doodles_of_palms_draw_their_fronds_as_strokes(tmp_path):
    """The species' fact reaches the style: palm doodles use the frond-stroke hint."""
    seen = []

    def spy(style, sil, rng, size):
        seen.append(sil.foliage_strokes)
        return np.full((size, size), 255, np.uint8)

    cfg = DatasetConfig(
        out=str(tmp_path / "d"), species=("palm", "maple"), trees_per_species=1,
        views=("front",), size=48, seed=0, styles=("doodle",),
    )  # fmt: skip
    import render.styles as styles

    saved = styles.draw
    styles.draw = spy
    try:
        build_dataset(cfg, progress=False)
    finally:
        styles.draw = saved
    assert seen == [True, False]  # palm first (species order), then maple
