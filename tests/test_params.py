"""Tests of weberpenn.params: the table, every validation error path, loading and saving."""

from __future__ import annotations

import json
import math

import pytest
from paths import GT_PARAM_FILES as REF_FILES

from weberpenn import ParamError, TreeParams, default_params, load_params, save_params
from weberpenn.params import (
    HEAD_KEYS,
    HEADS,
    KEYS,
    PARAMS,
    PREDICTED_KEYS,
    SPECS,
    describe,
    validate,
)


def _d(**changes) -> dict:
    d = default_params().to_dict()
    d.update(changes)
    return d


def _err(**changes) -> str:
    with pytest.raises(ParamError) as info:
        TreeParams(_d(**changes))
    return str(info.value)


def test_table_shape():
    assert len(PARAMS) == 70 and len(KEYS) == 70
    assert len(PREDICTED_KEYS) == 62
    assert [len(HEAD_KEYS[h]) for h in HEADS] == [17, 4, 12, 12, 16, 1]
    assert sum(SPECS[k].is_vector for k in PREDICTED_KEYS) == 22
    assert set(KEYS) - set(PREDICTED_KEYS) == {
        "prune", "pruneBase", "prunePowerHigh", "prunePowerLow", "pruneRatio",
        "pruneWidth", "pruneWidthPeak", "seed",
    }  # fmt: skip
    for p in PARAMS:
        if p.kind in ("float", "int"):
            assert p.lo <= p.hi, p.name


def test_defaults_valid_and_immutable():
    p = default_params()
    assert isinstance(p, TreeParams) and len(p) == 70
    assert p.levels == p["levels"]
    with pytest.raises(AttributeError):
        p.levels = 2  # type: ignore[misc]
    q = p.replace(levels=2)
    assert q.levels == 2 and p.levels != 2 or p.levels == 2
    assert validate(p) is p


def test_unknown_key():
    msg = _err(oakiness=1.0)
    assert "oakiness" in msg and "unknown" in msg


def test_missing_key():
    d = _d()
    del d["ratio"]
    with pytest.raises(ParamError, match="missing.*'ratio'"):
        TreeParams(d)


def test_not_a_mapping():
    with pytest.raises(ParamError, match="mapping"):
        TreeParams([1, 2, 3])  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("key", "value", "fragment"),
    [
        ("scale", "big", "expected a number"),
        ("scale", None, "expected a number"),
        ("scale", True, "expected a number"),
        ("levels", 2.5, "integer"),
        ("levels", 0, "out of range"),
        ("levels", 5, "out of range"),
        ("ratio", -1.0, "out of range"),
        ("scale", math.nan, "finite"),
        ("scale", math.inf, "finite"),
        ("baseSize", 1.5, "out of range"),
        ("leafShape", "round", "allowed"),
        ("leafShape", 3, "allowed"),
        ("shape", "9", "allowed"),
        ("shapeS", "8", "allowed"),
        ("shape", True, "allowed"),
        ("prune", "yes", "boolean"),
        ("prune", 2, "boolean"),
        ("choiceNegPos1", 0, "-1 or 1"),
        ("choiceNegPos2", 0.5, "-1 or 1"),
        ("curveRes", 3, "list of 4"),
        ("curveRes", "3333", "list of 4"),
        ("curveRes", [3, 3, 3], "4 values"),
        ("curveRes", [3, 3, 3, 3, 3], "4 values"),
        ("curveRes", [3, 3, 3, 100_000], "out of range"),
        ("length", [1.0, math.nan, 0.5, 0.5], "finite"),
        ("taper", [1.0, 1.0, 1.0, 2.0], "out of range"),
    ],
)
def test_bad_values_name_key_value_and_range(key, value, fragment):
    msg = _err(**{key: value})
    assert key in msg and fragment in msg
    if fragment == "out of range":
        assert "allowed" in msg


def test_enum_and_bool_coercion():
    p = TreeParams(_d(shape=7, prune=1, leafShape="rect"))
    assert p.shape == "7" and p.prune is True and p.leafShape == "rect"
    assert TreeParams(_d(levels=3.0)).levels == 3


def test_explosive_sizes_rejected():
    with pytest.raises(ParamError, match="out of range") as e:
        TreeParams(_d(branches=[0, 10**7, 10, 10]))
    assert e.value.key == "branches"
    with pytest.raises(ParamError, match="stems") as e:
        TreeParams(_d(levels=4, branches=[0, 400, 400, 400]))
    assert e.value.key == "branches"
    with pytest.raises(ParamError, match="leaves") as e:
        TreeParams(_d(levels=3, branches=[0, 100, 40, 10], leaves=2000))
    assert e.value.key == "leaves"
    with pytest.raises(ParamError, match="vertices") as e:
        TreeParams(
            _d(
                levels=2,
                branches=[0, 500, 10, 10],
                curveRes=[64, 64, 3, 1],
                resU=int(SPECS["resU"].hi),
                bevelRes=int(SPECS["bevelRes"].hi),
            )
        )
    assert e.value.key == "curveRes"


def test_scale_plus_scale_v_positive():
    with pytest.raises(ParamError, match="scale \\+ scaleV"):
        TreeParams(_d(scale=2.0, scaleV=-2.0))
    assert TreeParams(_d(scale=2.0, scaleV=-1.5)).scaleV == -1.5


def test_json_round_trip(tmp_path):
    p = default_params().replace(levels=2, leafShape="rect", seed=12345678901234)
    path = save_params(p, tmp_path / "sub" / "tree.json")
    assert load_params(path) == p
    assert list(tmp_path.joinpath("sub").iterdir()) == [path]  # no temp files left
    assert json.loads(path.read_text())["leafShape"] == "rect"


@pytest.mark.parametrize(
    ("name", "text", "match"),
    [
        ("missing.json", None, "no such"),
        ("bad.json", "{not json", "JSON"),
        ("bad.json", "[1, 2]", "object"),
        ("bad.json", json.dumps(_d(ratio=-3.0)), r"bad\.json.*ratio"),
        ("bad.py", "import os; os.system('echo hacked')\n", None),  # never run
        ("bad.py", "# only a comment\n\n", "no dictionary"),
        ("bad.py", "[1, 2, 3]\n", "dict"),
    ],
)
def test_load_errors(tmp_path, name: str, text: str | None, match: str | None):
    path = tmp_path / name
    if text is not None:
        path.write_text(text)
    with pytest.raises(ParamError, match=match):
        load_params(path)


def test_load_one_line_sapling_preset(tmp_path):
    preset = {
        "seed": 7,
        "levels": 2,
        "scale": 8.0,
        "scaleV": 1.0,
        "bevel": True,
        "showLeaves": True,
        "useArm": False,
        "handleType": "0",
        "rMode": "rotate",
        "curveV": [20.0, 50.0, 75.0, 0.0],
        "splitAngleV": [0.0, 0.0, 0.0, 0.0],
        "attractUp": 0.5,
        "leafShape": "rect",
        "shape": "7",
        "branches": [0, 30, 10, 10],
        "downAngle": [90.0, 60.0, 45.0, 45.0],
        "rotate": [137.5, 137.5, 120.0, 137.5],
    }
    path = tmp_path / "preset.py"
    path.write_text("# a Sapling preset\n" + repr(preset) + "\n")
    p = load_params(path)
    assert p.levels == 2 and p.scale == 8.0 and p.seed == 7
    assert p.scaleV == 0.0  # Sapling's variation amplitude is not a realised value
    assert p.attractUp == (0.0, 0.0, 0.5, 0.5)  # scalar upgrade, as Sapling does
    assert p.leafDownAngle == 45.0 and p.leafRotate == 120.0  # copied at min(levels, 3)
    assert p.curveV1 == (0.0, 0.0, 0.0, 0.0)


def test_load_multiline_preset(tmp_path):
    d = default_params().to_dict()
    path = tmp_path / "multi.py"
    path.write_text("{\n" + ",\n".join(f"{k!r}: {v!r}" for k, v in d.items()) + "\n}\n")
    assert load_params(path) == default_params()


def test_sapling_preset_with_unknown_key(tmp_path):
    path = tmp_path / "p.py"
    path.write_text(repr({"levels": 2, "notASaplingKey": 1}) + "\n")
    with pytest.raises(ParamError, match="notASaplingKey"):
        load_params(path)


def test_all_reference_files_load():
    assert len(REF_FILES) == 15
    for f in REF_FILES:
        p = load_params(f)
        assert len(p) == 70, f.name


def test_describe_lists_every_key():
    text = describe()
    lines = text.splitlines()
    assert len(lines) == 71  # header + 70 keys
    listed = {line.split()[0] for line in lines[1:]}
    assert listed == set(KEYS)


def test_deeply_nested_json_is_refused_plainly(tmp_path) -> None:
    from weberpenn import load_params

    for name, text in (("deep.json", "[" * 100_000), ("deep.py", "{'a': " + "[" * 100_000)):
        f = tmp_path / name
        f.write_text(text)
        with pytest.raises(ParamError, match="nested"):
            load_params(f)
    huge = tmp_path / "huge.json"
    huge.write_text(" " * 2_000_000)
    with pytest.raises(ParamError, match="too large"):
        load_params(huge)


# Loads each file given on the command line and prints how long it took and what came of
# it; run in a child process so a slow (quadratic) scan fails the test in bounded time.
_TIMED_LOAD = """
import sys, time
from weberpenn import ParamError, load_params
for path in sys.argv[1:]:
    t0 = time.perf_counter()
    try:
        outcome = 'loaded levels=%d' % load_params(path)['levels']
    except ParamError as exc:
        outcome = 'refused: ' + str(exc)[-80:].replace(chr(10), ' ')
    print('%.3f %s' % (time.perf_counter() - t0, outcome))
"""


def test_a_1mb_hostile_preset_is_read_in_linear_time(tmp_path) -> None:
    """Issue 30, item 6: unclosed escaped quotes made the bracket scan quadratic (a 120 KB
    preset hung ``grow --params`` for over 20 s; the 1 MB cap would take ~50 minutes)."""
    import os
    import subprocess
    import sys

    from weberpenn import species
    from weberpenn.params import MAX_PARAM_FILE_BYTES
    from weberpenn.preset import save_sapling_preset

    n = MAX_PARAM_FILE_BYTES // 2 - 64
    hostile = {
        "quotes.py": '"\\' * n,
        "quotes.json": "'\\" * n,
        "mixed.py": "{'a': \"\\'\\" + '"\\' * (n - 8),
    }
    files = []
    for name, text in hostile.items():
        files.append(tmp_path / name)
        files[-1].write_text(text)
    # a real preset with a comment of 1 MB of such quotes: read as usual, and fast
    tree = species.sample("maple", 4)
    preset = save_sapling_preset(tree, tmp_path / "padded.py")
    preset.write_text(preset.read_text() + "# " + '"\\' * (n - 3000) + "\n")
    files.append(preset)
    assert all(f.stat().st_size <= MAX_PARAM_FILE_BYTES for f in files)
    assert max(f.stat().st_size for f in files) > 0.99 * MAX_PARAM_FILE_BYTES

    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    run = subprocess.run(
        [sys.executable, "-c", _TIMED_LOAD, *map(str, files)],
        capture_output=True,
        text=True,
        timeout=60,
        env=env,
    )
    assert run.returncode == 0, run.stderr
    lines = run.stdout.splitlines()
    assert len(lines) == 4, run.stdout
    for line in lines[:3]:
        assert " refused: " in line, line
    assert lines[3].endswith(f"loaded levels={tree.levels}"), lines[3]
    assert load_params(preset) == tree
    for line in lines:
        assert float(line.split()[0]) < 3.0, line


@pytest.mark.parametrize(
    "key", ["seed", "levels", "scale", "shape", "useParentAngle", "choiceNegPos2", "attractUp"]
)
def test_huge_integers_are_refused_plainly(key, tmp_path) -> None:
    """Issue 30, item 9: an int of 309+ digits raised OverflowError (math.isfinite/float)
    instead of naming the key."""
    huge = 10**400
    value = [huge] * 4 if SPECS[key].is_vector else huge
    with pytest.raises(ParamError, match=f"'{key}") as info:
        default_params().replace(**{key: value})
    assert len(str(info.value)) < 300 and "characters" in str(info.value)
    f = tmp_path / "huge.json"
    f.write_text(json.dumps({**default_params().to_dict(), key: value}))
    with pytest.raises(ParamError, match=key):
        load_params(f)


def test_replace_checks_the_changed_keys_and_the_whole_tree_as_a_new_dictionary_would() -> None:
    """``replace`` checks only the keys it changes and then the tree's limits: it gives
    what a whole new dictionary gives, and refuses what that refuses, with the same words."""
    from weberpenn.params import TreeParams

    p = default_params()
    for changes in (
        {"levels": 2, "baseSize": 0.25},
        {"customShape": [0.2, 1, 0.5, 0.4], "shape": 8.0},  # coerced: floats, an enum name
        {"scale": 3, "seed": 7},
    ):
        q = p.replace(**changes)
        assert q == TreeParams({**p.to_dict(), **changes})
        assert dict(q) == dict(TreeParams({**p.to_dict(), **changes}))
    assert p.replace(shape=8.0)["shape"] == "8"
    for bad in (
        {"baseSize": 1.5},
        {"nosuch": 1},
        {"levels": "two"},
        {"scale": 0.001, "scaleV": -0.001},  # each in range, together no size
        {"branches": [1, 200, 200, 200], "levels": 4},  # each in range, too many stems
    ):
        with pytest.raises(ParamError) as replaced:
            p.replace(**bad)
        with pytest.raises(ParamError) as whole:
            TreeParams({**p.to_dict(), **bad})
        assert str(replaced.value) == str(whole.value), bad
