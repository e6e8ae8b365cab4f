"""Derive weberpenn/species_data.json: the paper's five species from its 15 published
ground-truth files, and the species people draw from Blender's bundled Sapling presets.

Fixed values: what stays equal across a species' three files.  Unfixed values: what
varies, with the draw rule of TreeSketchNet's ``set_variation`` and an amplitude that
covers every observed value (rounded up with a 10% margin).

    python scripts/make_species_data.py ../shared/reference/treesketchnet_test_params \
        /usr/share/blender/scripts/addons/add_curve_sapling/presets

The species people draw (:data:`PEOPLE_SPECIES`) start from a Sapling preset's numbers
(facts; Debian's ``blender`` package installs the presets, the add-on's GPL code is not
used), read by ``weberpenn.params.load_params`` like any preset, with a few values set
where the preset grows a different tree from the one people mean (each override is named
in the table, with why).  Their unfixed values are the preset's own variation keys
(``curveV``, ``downAngleV``, ``rotateV``, ``scaleV``...) realised the way TreeSketchNet
realises them for its five species, with the amplitudes the preset gives.
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

SPECIES_FILES = {
    "maple": "acer_2",
    "pine": "pine",
    "bonsai": "bonsai",
    "palm": "palm_3",
    "cherry": "cherry_blossom_3",
}


#: The species people draw: a Sapling preset (Blender 3.4's bundled presets), the values set
#: where the preset grows another tree than the one people mean, and the name people use.
PEOPLE_SPECIES: dict[str, dict] = {
    "fir": {
        "preset": "douglas_fir",
        "display": "fir (conical conifer)",
        # a Christmas-tree cone: widest at the base (the preset's envelope bulges in the
        # middle) and branches down to a tenth of the height (the preset: a third)
        "set": {"shape": "8", "customShape": [1.0, 0.6, 0.45, 0.05], "baseSize": 0.12},
    },
    "willow": {"preset": "weeping_willow", "display": "weeping willow", "set": {}},
    "oak": {
        "preset": "small_maple",
        "display": "oak (round crown)",
        # a round crown (spherical envelope) on a taller trunk: the lollipop people draw
        "set": {"shape": "1", "scale": 11.0},
    },
    "birch": {"preset": "white_birch", "display": "birch (slender broadleaf)", "set": {}},
    "poplar": {
        "preset": "quaking_aspen",
        "display": "poplar (columnar)",
        # the aspen is a Populus; a Lombardy poplar's column: cylindrical envelope, short
        # first-level branches held steeply up, branches from low on the trunk
        "set": {
            "shape": "3",
            "downAngle": [90.0, 25.0, 30.0, 45.0],
            "length": [1.0, 0.25, 0.5, 0.45],
            "branches": [0, 80, 15, 10],
            "leaves": 40,
            "attractUp": [0.0, 0.8, 0.5, 0.5],
            "baseSize": 0.12,
            "curve": [0.0, 0.0, -20.0, 0.0],
        },
        "preset_set": {"downAngleV": [0.0, 8.0, 10.0, 10.0]},
    },
    "winter": {
        "preset": "small_maple",
        "display": "bare tree (winter)",
        # the oak above in winter: every branch, no leaves
        "set": {"shape": "1", "scale": 11.0, "leaves": 0},
    },
}

#: Stems a fast sketch may leave out, as a fraction of its sample width (default 0.5):
#: where many twigs thinner than a pixel together darken the silhouette (a bare tree's
#: crown, a willow's curtain, an oak's twigs), leaving them out changes the sketch by
#: 4-12 % of its pixels (tests/test_render_raster.py); these keep them.
SKETCH_STEM_CUT = {"oak": 0.25, "winter": 0.1, "willow": 0.05}

#: Stems the outline step's sketches (``refine.start``: their envelopes alone are read)
#: leave out, as a fraction of the sample width: where the foliage draws the crown's
#: outline, the thin stems inside it change no envelope (people's 143 held-out drawings'
#: outline steps replayed: the same trees for these three; a birch's sparse leaves and a
#: willow's curtain leave twigs on the outline, and they changed four of ten there).
OUTLINE_STEM_CUT = {"oak": 2.0, "maple": 2.0, "cherry": 2.0}

#: Species whose foliage people draw as single strokes (fronds, hanging twigs).
FOLIAGE_STROKES = ("palm", "willow")

#: Display names of the paper's five.
PAPER_DISPLAY = {
    "maple": "maple",
    "pine": "pine",
    "bonsai": "bonsai",
    "palm": "palm",
    "cherry": "cherry",
}

# TreeSketchNet realises a Sapling variation once per tree (per half stem for the curve);
# a per-segment amplitude larger than this makes members of one species unrecognisable
CURVE_V_MAX = 40.0


def preset_dict(path: Path) -> dict:
    """A Sapling preset's dict literal (the first line that is not a comment)."""
    import ast

    with path.open(encoding="utf-8") as fh:
        line = next(t for t in fh if t.strip() and not t.lstrip().startswith("#"))
    return ast.literal_eval(line)


def people_species(name: str, row: dict, presets: Path) -> dict:
    """Base dictionary and unfixed values of one species people draw."""
    from weberpenn.params import load_params

    path = presets / f"{row['preset']}.py"
    raw = preset_dict(path) | row.get("preset_set", {})
    base = load_params(path).replace(**row["set"]).to_dict()
    levels = int(base["levels"])
    unfixed: list[dict] = []

    def add(key: str, index: int | None, rule: dict) -> None:
        unfixed.append({"key": key, "index": index, **rule})

    for i in range(levels):
        amp = min(abs(float(raw["curveV"][i])), CURVE_V_MAX)
        if amp > 0:
            add("curveV1", i, {"rule": "uniform", "lo": 0.0, "hi": amp})
            add("curveV2", i, {"rule": "uniform", "lo": 0.0, "hi": amp})
    for i in range(1, min(levels + 1, 4)):
        if float(raw["downAngleV"][i]) > 0:
            add("downAngleV", i, {"rule": "uniform_sym", "amp": float(raw["downAngleV"][i])})
    for key in ("leafDownAngleV", "leafRotateV"):
        if base["leaves"] and float(raw.get(key, 0.0)) > 0:
            add(key, None, {"rule": "uniform_sym", "amp": float(raw[key])})
    if base["leaves"]:
        add(
            "leafScaleV",
            None,
            {"rule": "uniform_around_one", "amp": max(0.1, float(raw.get("leafScaleV", 0.0)))},
        )
    for i in range(4):
        add("rLastAng", i, {"rule": "uniform", "lo": 0.0, "hi": 360.0})
    add("rSplits2", None, {"rule": "uniform", "lo": 0.0, "hi": 1.0})
    add("rotate", 0, {"rule": "uniform", "lo": 0.0, "hi": 360.0})
    if float(raw["rotateV"][0]) > 0:
        add("rotateV", 0, {"rule": "uniform_sym", "amp": float(raw["rotateV"][0])})
    add("scaleV", None, {"rule": "uniform_sym", "amp": float(raw["scaleV"])})
    add(
        "scaleV0",
        None,
        {"rule": "uniform_around_one", "amp": min(0.2, max(0.05, float(raw["scaleV0"])))},
    )
    for i in range(min(levels, 3)):
        amp = float(raw["splitAngleV"][i])
        if amp > 0:
            add("splitAngleV1", i, {"rule": "uniform_sym", "amp": amp})
            add("splitAngleV2", i, {"rule": "uniform_sym", "amp": amp})
    add("choiceNegPos1", None, {"rule": "sign"})
    add("choiceNegPos2", None, {"rule": "sign"})
    base["seed"] = 0
    return {
        "display": row["display"],
        "source": f"Sapling preset {row['preset']} (Blender 3.4)"
        + (f", set: {', '.join(sorted(row['set']))}" if row["set"] else ""),
        "reference_files": [],
        "sapling_preset": row["preset"],
        "base": base,
        "unfixed": unfixed,
    }


def up(x: float) -> float:
    """Round |x| * 1.1 up to a tidy number, keeping the sign."""
    m = abs(x) * 1.1
    if m == 0:
        return 0.0
    step = 10 ** math.floor(math.log10(m)) / 2
    return math.copysign(math.ceil(m / step) * step, x)


def rule_for(key: str, idx: int | None, vals: list, base: dict) -> dict:
    if key == "rLastAng" or (key == "rotate" and idx == 0):
        return {"rule": "uniform", "lo": 0.0, "hi": 360.0}
    if key == "rSplits2":
        return {"rule": "uniform", "lo": 0.0, "hi": 1.0}
    if key.startswith("choiceNegPos"):
        return {"rule": "sign"}
    if key == "baseSplits":
        return {"rule": "randint", "lo": 0, "hi": base["maxBaseSplits"]}
    if key == "splitHeight":
        return {
            "rule": "split_height",
            "with_splits": 0.6,
            "without": [v for v, b in zip(vals, base["_baseSplits"], strict=True) if b == 0][0],
        }
    if key == "nrings":
        n = round((min(vals) + max(vals)) / 2)
        return {"rule": "randint", "lo": max(2, n - 3), "hi": n + 3}
    if key == "curve":
        return {"rule": "uniform_sym", "amp": up(max(abs(v) for v in vals)), "mirror": "curveBack"}
    if key == "curveBack":
        return {"rule": "mirror", "of": "curve"}
    if key in ("curveV1", "curveV2"):
        ext = max(vals, key=abs)
        return (
            {"rule": "uniform", "lo": 0.0, "hi": up(ext)}
            if ext > 0
            else {"rule": "uniform", "lo": up(ext), "hi": 0.0}
        )
    if key in ("leafScaleV", "scaleV0"):
        return {"rule": "uniform_around_one", "amp": min(0.9, up(max(abs(v - 1) for v in vals)))}
    # splitAngleV1/2, rotateV, leafRotateV, leafDownAngleV, scaleV, downAngleV
    return {"rule": "uniform_sym", "amp": up(max(abs(v) for v in vals))}


def main(src: str, presets: str) -> None:
    out: dict = {
        "_source": "TreeSketchNet test_set/tree_params_NN (BSD 3-Clause, (c) 2022 Gilda Manfredi, "
        "Nicola Capece, Ugo Erra); generated by scripts/make_species_data.py",
        "species": {},
    }
    for name, stem in SPECIES_FILES.items():
        files = sorted(Path(src).glob(f"*_{stem}.json"))
        dicts = [json.loads(f.read_text()) for f in files]
        assert len(dicts) == 3, (name, files)
        base = dict(dicts[0])
        base["_baseSplits"] = [d["baseSplits"] for d in dicts]
        unfixed = []
        for key in dicts[0]:
            if key == "seed":
                continue
            vals = [d[key] for d in dicts]
            if isinstance(vals[0], list):
                for i in range(4):
                    comp = [v[i] for v in vals]
                    if any(c != comp[0] for c in comp):
                        unfixed.append({"key": key, "index": i, **rule_for(key, i, comp, base)})
            elif any(v != vals[0] for v in vals):
                unfixed.append({"key": key, "index": None, **rule_for(key, None, vals, base)})
        base.pop("_baseSplits")
        base["seed"] = 0
        out["species"][name] = {
            "display": PAPER_DISPLAY[name],
            "source": f"TreeSketchNet ground truth {stem}",
            "reference_files": [f.name for f in files],
            "base": base,
            "unfixed": unfixed,
        }
    for name, row in PEOPLE_SPECIES.items():
        out["species"][name] = people_species(name, row, Path(presets))
    for name in FOLIAGE_STROKES:
        out["species"][name]["foliage_strokes"] = True
    for name, cut in SKETCH_STEM_CUT.items():
        out["species"][name]["sketch_stem_cut"] = cut
    for name, cut in OUTLINE_STEM_CUT.items():
        out["species"][name]["outline_stem_cut"] = cut
    out["_source"] += "; the species people draw from Blender 3.4's Sapling presets (numbers only)"
    dst = Path(__file__).resolve().parent.parent / "weberpenn" / "species_data.json"
    dst.write_text(json.dumps(out, indent=1) + "\n")
    print(f"wrote {dst}")


if __name__ == "__main__":
    main(
        sys.argv[1] if len(sys.argv) > 1 else "../shared/reference/treesketchnet_test_params",
        sys.argv[2]
        if len(sys.argv) > 2
        else "/usr/share/blender/scripts/addons/add_curve_sapling/presets",
    )
