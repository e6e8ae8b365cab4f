"""Tests of weberpenn.species: sampling, fixed values, ranges, projection."""

from __future__ import annotations

import json

import numpy as np
import pytest
from paths import GT_PARAM_DIR as PARAM_DIR

from weberpenn import ParamError, TreeParams, species
from weberpenn.params import SPECS


def _value(p, key, index):
    return p[key] if index is None else p[key][index]


def _unfixed_slots(name):
    return {(u.key, u.index) for u in species.unfixed(name)}


@pytest.mark.parametrize("name", species.SPECIES)
def test_sample_deterministic_and_seed_dependent(name):
    a = species.sample(name, 5)
    b = species.sample(name, 5)
    c = species.sample(name, 6)
    assert isinstance(a, TreeParams)
    assert a == b
    assert a != c
    assert a.seed == 5


@pytest.mark.parametrize("name", species.SPECIES)
def test_unfixed_values_inside_ranges(name):
    for seed in range(8):
        p = species.sample(name, seed)
        for u in species.unfixed(name):
            v = _value(p, u.key, u.index)
            if u.rule == "sign":
                assert v in (-1, 1)
            elif u.rule == "mirror":
                assert v == pytest.approx(-_value(p, "curve", u.index))
            elif u.rule == "split_height":
                assert v in (pytest.approx(u.lo), pytest.approx(u.hi))
            else:
                assert u.lo - 1e-9 <= v <= u.hi + 1e-9, (u, v)
            if SPECS[u.key].kind == "int":
                assert float(v).is_integer()


@pytest.mark.parametrize("name", species.SPECIES)
def test_fixed_values_equal_base(name):
    base = species.base(name)
    slots = _unfixed_slots(name)
    p = species.sample(name, 11)
    for key in base:
        if key == "seed":
            continue
        if SPECS[key].is_vector:
            for i in range(4):
                if (key, i) not in slots:
                    assert p[key][i] == base[key][i], (key, i)
        elif (key, None) not in slots:
            assert p[key] == base[key], key


@pytest.mark.parametrize("name", species.PAPER_SPECIES)
def test_fixed_values_match_reference_files(name):
    files = species.reference_files(name)
    assert len(files) == 3
    refs = [json.loads((PARAM_DIR / f).read_text()) for f in files]
    slots = _unfixed_slots(name)
    p = species.sample(name, 2)
    for key in p:
        if key == "seed":
            continue
        idxs = range(4) if SPECS[key].is_vector else [None]
        for i in idxs:
            vals = [r[key] if i is None else r[key][i] for r in refs]
            if (key, i) in slots or any(v != vals[0] for v in vals):
                continue  # unfixed (or varies across the references)
            got = _value(p, key, i)
            if isinstance(got, float):
                assert got == pytest.approx(float(vals[0]), rel=1e-6, abs=1e-9), (key, i)
            else:
                assert str(got) == str(vals[0]) or got == vals[0], (key, i)


@pytest.mark.parametrize("name", species.SPECIES)
def test_project_round_trip(name):
    p = species.sample(name, 3)
    assert species.project(name, p) == p
    # a dictionary of another species is forced onto this one's fixed values
    other = species.sample("cherry" if name != "cherry" else "palm", 3)
    q = species.project(name, other)
    base = species.base(name)
    for key in ("levels", "leafShape", "curveRes"):
        if (key, None) not in _unfixed_slots(name):
            assert q[key] == base[key]


def test_unknown_species():
    with pytest.raises(ParamError, match="unknown species.*fir.*winter"):
        species.sample("baobab", 0)
    with pytest.raises(ParamError, match="unknown species"):
        species.unfixed("baobab")
    with pytest.raises(ParamError, match="seed"):
        species.sample("maple", -1)


def test_unfixed_keys_listed():
    for name in species.SPECIES:
        keys = species.unfixed_keys(name)
        assert keys and all(k in SPECS for k in keys)
        assert "seed" not in keys


def _trunk_lean(params: TreeParams) -> float:
    from weberpenn import grow

    sk = grow(params)
    t = np.asarray(sk.points)[sk.offsets[0] : sk.offsets[1]]
    return float(np.hypot(*(t[-1, :2] - t[0, :2])) / max(t[-1, 2] - t[0, 2], 1e-6))


@pytest.mark.parametrize("name", ["palm", "bonsai"])
def test_a_leaning_trunk_is_reachable_by_the_search(name: str) -> None:
    from refine.objective import SearchSpace

    start = species.sample(name, 3)
    space = SearchSpace.create(name, start, search_yaw=False)
    assert "curveBack[0]" in space.labels and "curve[0]" in space.labels
    x = space.from_params(start)
    assert _trunk_lean(space.to_params(x)) < 0.3  # the published trunks end above their base
    i, j = space.labels.index("curve[0]"), space.labels.index("curveBack[0]")
    x[i], x[j] = 0.95, 0.5  # bend far one way, do not bend back
    if "attractUp[0]" in space.labels:
        x[space.labels.index("attractUp[0]")] = 0.0
    leaning = space.to_params(x)
    assert _trunk_lean(leaning) > 0.45
    # sampling and projection without the search are unchanged: the mirror holds there
    assert species.project(name, leaning)["curveBack"][0] == -leaning["curve"][0]


def test_a_conical_conifer_is_reachable_by_the_search() -> None:
    from refine.objective import SearchSpace
    from weberpenn import grow

    start = species.sample("pine", 3)
    space = SearchSpace.create("pine", start, search_yaw=False)
    x = space.from_params(start)
    for k, v in ((0, 1.0), (1, 1.0), (2, 0.0), (3, 0.0)):  # widest at the base, a point on top
        x[space.labels.index(f"customShape[{k}]")] = v
    sk = grow(space.to_params(x))
    pts, off = np.asarray(sk.points), np.asarray(sk.offsets)
    first = np.flatnonzero(np.asarray(sk.levels) == 1)
    base_z = pts[off[first], 2]
    length = np.array([np.linalg.norm(pts[off[i + 1] - 1] - pts[off[i]]) for i in first])
    low, high = base_z < np.quantile(base_z, 1 / 3), base_z > np.quantile(base_z, 2 / 3)
    assert length[low].mean() > 2.0 * length[high].mean()


def test_the_paper_five_come_first_and_people_species_follow():
    assert (
        species.SPECIES[:5]
        == species.PAPER_SPECIES
        == ("maple", "pine", "bonsai", "palm", "cherry")
    )
    assert set(species.PEOPLE_SPECIES) == {"fir", "willow", "oak", "birch", "poplar", "winter"}
    for name in species.SPECIES:
        assert species.display_name(name)
        assert species.source(name)


@pytest.mark.parametrize(
    ("alias", "name"),
    [
        ("Christmas tree", "fir"),
        ("spruce", "fir"),
        ("weeping-willow", "willow"),
        ("bare", "winter"),
    ],
)
def test_names_people_use(alias, name):
    assert species.canonical(alias) == name


@pytest.mark.parametrize("name", species.PEOPLE_SPECIES)
def test_people_species_have_variation_and_distinct_fixed_values(name):
    rows = species.unfixed(name)
    keys = {u.key for u in rows}
    assert {"rLastAng", "rotate", "scaleV"} <= keys
    a, b = species.sample(name, 1), species.sample(name, 2)
    assert a["scaleV"] != b["scaleV"]
    # no two species share a base dictionary: each is a tree of its own
    for other in species.SPECIES:
        if other != name:
            assert species.base(other) != species.base(name)


def test_the_winter_tree_is_bare_and_the_others_are_leafy():
    assert species.sample("winter", 0)["leaves"] == 0
    for name in ("fir", "willow", "oak", "birch", "poplar"):
        assert species.sample(name, 0)["leaves"] > 0
    assert species.doodle_foliage("palm") and species.doodle_foliage("willow")
    assert not species.doodle_foliage("oak")
