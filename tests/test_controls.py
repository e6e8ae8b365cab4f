"""weberpenn.controls: the one table of a person's controls, mapped onto Weber-Penn keys."""

from __future__ import annotations

import pytest

from weberpenn import build_mesh, grow, species
from weberpenn.controls import (
    CONTROLS,
    apply_controls,
    check_controls,
    current,
    defaults,
    grow_with_controls,
    table,
)
from weberpenn.params import SPECS

NAMES = [c.name for c in CONTROLS]


def test_the_table_names_every_control_and_what_it_moves() -> None:
    assert NAMES == [
        "height",
        "crown_width",
        "crown_shape",
        "branch_count",
        "branch_angle",
        "trunk_lean",
        "trunk_bend",
        "leaf_size",
        "leaf_density",
        "leafy",
        "seed",
    ]
    for row in table():
        assert row["label"] and row["help"] and row["moves"]
        assert row["min"] <= row["max"]
        for how in row["moves"]:  # every key named is a Weber-Penn key
            assert how.split(":")[0].split("[")[0].split(",")[0] in SPECS, how
        if row["neutral"] is not None:
            assert row["min"] <= row["neutral"] <= row["max"]
    shapes = dict((c["value"], c["label"]) for c in table()[2]["choices"])
    assert set(shapes) == set(SPECS["shape"].choices) and shapes["0"] == "conical"


@pytest.mark.parametrize("name", species.SPECIES)
def test_defaults_come_from_each_species_base(name: str) -> None:
    d = defaults(name)
    base = species.base(name)
    assert set(d) == set(NAMES)
    assert d["crown_shape"] == str(base["shape"]) and d["seed"] == base["seed"]
    assert d["leafy"] == (base["leaves"] != 0) and d["crown_width"] == 1.0
    lo, hi = build_mesh(grow(base)).bounds()
    assert d["height"] == pytest.approx(hi[2] - lo[2])
    assert apply_controls(base, {k: v for k, v in d.items() if k != "height"}) == base


def test_each_control_moves_its_keys() -> None:
    p = species.sample("maple", 2)
    assert apply_controls(p, {"crown_width": 1.5})["length"][1] == pytest.approx(
        1.5 * p["length"][1]
    )
    assert apply_controls(p, {"branch_count": 2})["branches"][1] == 2 * p["branches"][1]
    assert apply_controls(p, {"branch_count": 0.25})["branches"][1] >= 1
    assert apply_controls(p, {"branch_angle": 10})["downAngle"][1] == pytest.approx(
        p["downAngle"][1] + 10
    )
    assert apply_controls(p, {"branch_angle": -45})["downAngle"][1] >= 0
    lean = apply_controls(p, {"trunk_lean": 45})
    assert lean["curve"][0] == pytest.approx(p["curve"][0] + 45)
    assert lean["attractUp"][0] == pytest.approx(p["attractUp"][0] * 0.5)
    assert lean["curveRes"][0] >= 6
    bend = apply_controls(p, {"trunk_bend": 30})
    assert bend["curve"][0] - p["curve"][0] == pytest.approx(30)
    assert bend["curveBack"][0] - p["curveBack"][0] == pytest.approx(-30)
    assert apply_controls(p, {"leaf_size": 2})["leafScale"] == pytest.approx(2 * p["leafScale"])
    assert apply_controls(p, {"leaf_density": 2})["leaves"] == 2 * p["leaves"]
    cherry = species.sample("cherry", 1)  # fanned leaves: a negative count keeps its sign
    assert apply_controls(cherry, {"leaf_density": 2})["leaves"] == 2 * cherry["leaves"] < 0
    assert apply_controls(p, {"leafy": False})["leaves"] == 0
    assert apply_controls(p, {"leafy": True}) == p
    assert apply_controls(p, {"crown_shape": "0"})["shape"] == "0"
    assert apply_controls(p, {"seed": 9})["seed"] == 9
    neutral = {c.name: c.neutral for c in CONTROLS if c.relative}
    assert apply_controls(p, neutral) == p
    assert current(p)["seed"] == p["seed"]


def test_order_does_not_matter() -> None:
    p = species.sample("pine", 1)
    a = apply_controls(p, {"trunk_lean": 20, "trunk_bend": -10, "branch_count": 1.5})
    b = apply_controls(p, {"branch_count": 1.5, "trunk_bend": -10, "trunk_lean": 20})
    assert a == b


@pytest.mark.parametrize("name", species.SPECIES)
def test_height_is_met(name: str) -> None:
    p = species.sample(name, 3)
    for want in (2.0, 15.0):
        params, mesh = grow_with_controls(p, {"height": want}, name)
        lo, hi = mesh.bounds()
        assert hi[2] - lo[2] == pytest.approx(want, rel=0.02)
        if p["scaleV"]:  # both size values move together
            assert params["scale"] / p["scale"] == pytest.approx(params["scaleV"] / p["scaleV"])


@pytest.mark.parametrize(
    ("controls", "words"),
    [
        ({"wings": 1}, "unknown control"),
        ({"crown_width": 5}, "crown_width"),
        ({"crown_width": "wide"}, "number"),
        ({"height": float("inf")}, "height"),
        ({"seed": 1.5}, "whole"),
        ({"seed": True}, "number"),
        ({"leafy": "maybe"}, "true or false"),
        ({"crown_shape": "11"}, "one of"),
        ([("height", 1)], "object"),
    ],
)
def test_bad_values_are_named(controls, words: str) -> None:
    with pytest.raises(ValueError, match=words):
        check_controls(controls)


def test_a_tree_past_the_generators_limits_is_refused_with_words() -> None:
    p = species.sample("cherry", 1)
    with pytest.raises(ValueError, match="controls make a tree the generator refuses"):
        apply_controls(p, {"branch_count": 2.5, "leaf_density": 3.0})


def test_fit_controls_stops_each_moved_slider_at_what_the_generator_grows() -> None:
    from weberpenn.controls import CONTROLS, fit_controls, grow_with_controls
    from weberpenn.params import ParamError

    step = {c.name: c.step for c in CONTROLS}
    p = species.sample("fir", 1)
    asked = {"leaf_density": 3.0, "branch_count": 2.5, "leaf_size": 1.5}
    fitted, adjusted = fit_controls(p, asked, "fir")
    assert set(adjusted) == {"leaf_density", "branch_count", "leaf_size"}
    for k, v in adjusted.items():
        assert 1.0 <= v < asked[k]
        assert abs(round((v - 1.0) / step[k]) * step[k] - (v - 1.0)) < 1e-6  # on its step
    grow_with_controls(p, fitted, "fir")  # grows
    # one slider, the others kept: a step further would not grow
    fitted, adjusted = fit_controls(p, {"leaf_density": 3.0}, "fir", ["leaf_density"])
    assert set(adjusted) == {"leaf_density"}
    with pytest.raises(ParamError):
        grow_with_controls(p, {"leaf_density": adjusted["leaf_density"] + 0.2}, "fir")
    # within the limits: as asked
    assert fit_controls(p, {"crown_width": 1.2}, "fir") == ({"crown_width": 1.2}, {})
    with pytest.raises(ValueError, match="wings"):
        fit_controls(p, {"leaf_density": 3.0}, "fir", ["wings"])
