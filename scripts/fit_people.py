"""Refit a TSN checkpoint's tree detector and species classifier on drawings by people.

    .venv/bin/python scripts/people_features.py --out DIR          # people's drawings, ~15 min
    .venv/bin/python scripts/fit_people.py --features DIR [--checkpoint checkpoints/tsn_lite0.pt] \
        [--out PT] [--pull 0.01] [--people-weight 1.0]

Both read the network's features of a drawing (``tsn.predict``): the detector the heads'
pooled features, the species classifier those and the species branch's.  Until now both
were fitted on drawings made by code only; people draw otherwise (thick short trunks, wide
flat or cloud crowns, a ground line, a few hasty strokes), so a third of their trees were
asked "is this a tree?" and a third of their other things passed as trees.

Fitting sets (the network, its heads and its branch untouched):

- **made by code**, as ``scripts/fit_tree_detector.py`` and
  ``scripts/fit_species_classifier.py`` make them: hand-style tree doodles of the eleven
  species (``eval.doodles.tree_doodle``, seeds from 1000; palms in the four forms people
  draw them, ``palm_doodle``), trees in the renderer's styles (seeds from 4000), doodles and simple pictures of
  other things (seeds from 20000); held out for the temperature: the same from seeds
  5000 / 7000 / 30000;
- **by people** (``eval.people``, its *fit* part only; the *held* part, about one author
  in five, is never read here): their trees and every other kind of thing, one author in
  four of the fit part kept apart for the temperature.

The detector (five networks of 128 hidden units, their logits averaged; ``--hidden 0``
the logistic regression) is refitted from scratch on both.  The species classifier is
refitted from the checkpoint's own (``SpeciesClassifier.refit``: an L2 pull toward its weights keeps what it
learned from the network's training sketches, not at hand here): code-made trees keep
their species; a tree a person drew may be any broadleaf or a fir, never a palm, bonsai or
pine (:data:`PEOPLE_TREE`), and the classifier puts it where its features lead.

A second detector is fitted with the kinds of :data:`eval.people.LEFT_OUT_KINDS` (and the
code-made doodles of those kinds) left out, and measured on people's held drawings of
those kinds: how "is this a tree?" meets kinds of things it never saw.  It is reported, not
shipped.  ``benchmarks/bench_species.py people`` measures the shipped checkpoint.
"""

from __future__ import annotations

import argparse
import sys
import time
import zlib
from pathlib import Path
from typing import Any

import numpy as np

from eval.doodles import (
    NONTREE_KINDS,
    PALM_FORMS,
    TREE_SPECIES,
    nontree_doodle,
    palm_doodle,
    tree_doodle,
)
from eval.fitting import read_drawings, styled_trees
from eval.people import LEFT_OUT_KINDS
from eval.pictures import picture
from treesketch.pipeline import load_sketch, prepare_input
from tsn.checkpoint import load_checkpoint, save_loaded
from tsn.predict import TSNModel
from tsn.species_id import SpeciesClassifier
from tsn.tree_detect import TreeDetector

ROOT = Path(__file__).resolve().parents[1]
#: What a person's "tree" may become: a broadleaf, a bare tree or a fir, never a palm, a
#: bonsai or a pine (a person draws those as such).
PEOPLE_TREE = frozenset({"maple", "cherry", "oak", "birch", "poplar", "willow", "winter", "fir"})
FIT_SEEDS = {"doodle": 1000, "styled": 4000, "other": 20_000}
HELD_SEEDS = {"doodle": 5000, "styled": 7000, "other": 30_000}
FIT_PICTURES = ("noise", "circle", "square", "house", "face", "text", "strokes", "grid", "car")
CALIB_EVERY = 4  # one author (or drawing) of the fit part in this many calibrates


def prepared(image: Any) -> np.ndarray:
    return prepare_input(load_sketch(image))


def code_made(
    seeds: dict[str, int], per_species: int, styled: int, per_kind: int, per_form: int
) -> dict:
    """``{set name: (images, labels)}``: a tree's label is its species, other things'
    their kind prefixed ``other:``."""
    trees = [
        (tree_doodle(s, seeds["doodle"] + k), s) for s in TREE_SPECIES for k in range(per_species)
    ]
    trees += [
        (palm_doodle(form, seeds["doodle"] + k), "palm")
        for form in PALM_FORMS
        for k in range(per_form)
    ]
    styled_imgs, styled_species = styled_trees(seeds["styled"], styled)
    others = [
        (nontree_doodle(kind, seeds["other"] + k), f"other:{kind}")
        for kind in NONTREE_KINDS
        for k in range(per_kind)
    ] + [
        (picture(kind, seeds["other"] + k), f"other:{kind}")
        for kind in FIT_PICTURES
        for k in range(per_kind)
    ]
    return {
        "tree doodles": ([i for i, _ in trees], [s for _, s in trees]),
        "styled trees": (styled_imgs, styled_species),
        "other things": ([i for i, _ in others], [s for _, s in others]),
    }


def code_features(model: TSNModel, sets: dict, path: Path) -> dict[str, np.ndarray]:
    """Features and labels of the code-made ``sets``, cached at ``path``."""
    if path.exists():
        return dict(np.load(path))
    feats, labels, names = [], [], []
    for name, (images, labs) in sets.items():
        _, f, kept = read_drawings(model, images, prepared)
        feats.append(f)
        labels += [lab for lab, k in zip(labs, kept, strict=True) if k]
        names += [name] * len(f)
    out = {"features": np.concatenate(feats), "label": np.array(labels), "set": np.array(names)}
    np.savez(path, **out)
    return out


def calibrating(keys: np.ndarray, sources: np.ndarray) -> np.ndarray:
    """Which of the fit part's drawings calibrate (a second hash of who drew them)."""
    return np.array(
        [
            zlib.crc32(f"calib:{s}:{k}".encode() if s != "strokes" else f"calib:{k}".encode())
            % CALIB_EVERY
            == 0
            for s, k in zip(sources, keys, strict=True)
        ]
    )


def detector_data(
    code: dict[str, np.ndarray], people: dict[str, np.ndarray], head: int, leave_out: tuple = ()
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(features, is_tree, weight)`` of code-made and people's drawings, without the
    kinds in ``leave_out``; people's drawings weigh as much in all as the code-made."""
    keep_c = np.array([lab.removeprefix("other:") not in leave_out for lab in code["label"]])
    keep_p = np.array([k not in leave_out for k in people["kind"]])
    xc, xp = code["features"][keep_c, :head], people["features"][keep_p, :head]
    yc = np.array([not lab.startswith("other:") for lab in code["label"][keep_c]])
    yp = people["kind"][keep_p] == "tree"
    wc = np.ones(len(xc))
    wp = np.full(len(xp), len(xc) / max(1, len(xp)))
    return np.concatenate([xc, xp]), np.concatenate([yc, yp]), np.concatenate([wc, wp])


def subset(d: dict[str, np.ndarray], mask: np.ndarray) -> dict[str, np.ndarray]:
    return {k: v[mask] for k, v in d.items()}


def wrong_rates(det: TreeDetector, people: dict[str, np.ndarray], head: int) -> dict[str, float]:
    """Share judged wrongly per (source, kind) of people's drawings."""
    p = det.probabilities(people["features"][:, :head])
    out = {}
    for src in np.unique(people["source"]):
        for kind in np.unique(people["kind"][people["source"] == src]):
            m = (people["source"] == src) & (people["kind"] == kind)
            out[f"{src}/{kind}"] = float(np.mean((p[m] >= 0.5) != (kind == "tree")))
    return out


def species_refit(
    clf: SpeciesClassifier,
    code: dict[str, np.ndarray],
    people: dict[str, np.ndarray],
    pull: float,
    people_weight: float,
) -> SpeciesClassifier:
    trees_c = np.array([not lab.startswith("other:") for lab in code["label"]])
    trees_p = people["kind"] == "tree"
    x = np.concatenate([code["features"][trees_c], people["features"][trees_p]])
    allowed: list[str | frozenset[str]] = [str(s) for s in code["label"][trees_c]]
    allowed += [PEOPLE_TREE] * int(trees_p.sum())
    nc, np_ = int(trees_c.sum()), int(trees_p.sum())
    w = np.concatenate([np.ones(nc), np.full(np_, people_weight * nc / max(1, np_))])
    return clf.refit(x, allowed, w, pull=pull)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--features", type=Path, required=True, help="people_features.py's --out")
    ap.add_argument("--checkpoint", default=str(ROOT / "checkpoints" / "tsn_lite0.pt"))
    ap.add_argument("--per-species", type=int, default=40, help="code-made tree doodles")
    ap.add_argument("--styled", type=int, default=66)
    ap.add_argument("--per-kind", type=int, default=16, help="code-made other things per kind")
    ap.add_argument("--per-form", type=int, default=15, help="palms in each form people draw")
    ap.add_argument("--l2", type=float, default=1e-2, help="the linear detector's L2")
    ap.add_argument("--hidden", type=int, default=128, help="detector: hidden units (0: linear)")
    ap.add_argument("--members", type=int, default=5, help="detector: networks averaged")
    ap.add_argument("--decay", type=float, default=1e-3, help="detector networks' weight decay")
    ap.add_argument("--pull", type=float, default=1e-2, help="species: pull to the old weights")
    ap.add_argument("--people-weight", type=float, default=1.0)
    ap.add_argument("--out", default=None, help="checkpoint to write (default: --checkpoint)")
    args = ap.parse_args()
    t0 = time.perf_counter()
    loaded = load_checkpoint(args.checkpoint)
    model = TSNModel(loaded)
    head = model.head_width
    code_fit = code_features(
        model, code_made(FIT_SEEDS, args.per_species, args.styled, args.per_kind, args.per_form),
        args.features / "code_fit.npz",
    )  # fmt: skip
    code_held = code_features(
        model, code_made(
            HELD_SEEDS, args.per_species // 2, args.styled // 2, args.per_kind // 2,
            args.per_form // 2,
        ),
        args.features / "code_held.npz",
    )  # fmt: skip
    people = dict(np.load(args.features / "people_fit.npz"))
    calib = calibrating(people["key"], people["source"])
    p_fit, p_cal = subset(people, ~calib), subset(people, calib)
    print(f"features ready ({time.perf_counter() - t0:.0f} s): code {len(code_fit['label'])} "
          f"+ {len(code_held['label'])}, people {len(p_fit['kind'])} + {len(p_cal['kind'])}")  # fmt: skip

    shape = {
        "l2": args.decay if args.hidden else args.l2,
        "hidden": args.hidden,
        "members": args.members,
    }
    x, y, w = detector_data(code_fit, p_fit, head)
    det = TreeDetector.fit(
        x, y, held_out=detector_data(code_held, p_cal, head)[:2], weights=w, **shape
    )
    # the warning limit where the calibration authors' trees and other things are
    # judged wrongly alike (people's drawings only: they are what users send)
    det = det.with_balanced_limit(p_cal["features"][:, :head], p_cal["kind"] == "tree")
    x, y, w = detector_data(code_fit, p_fit, head, LEFT_OUT_KINDS)
    held = detector_data(code_held, p_cal, head, LEFT_OUT_KINDS)[:2]
    lco = TreeDetector.fit(x, y, held_out=held, weights=w, **shape)
    seen = ~np.isin(p_cal["kind"], LEFT_OUT_KINDS)
    lco = lco.with_balanced_limit(p_cal["features"][seen, :head], p_cal["kind"][seen] == "tree")
    old = loaded.species_id.classifier
    if old is None or old.reads != "features":
        raise SystemExit("the checkpoint's species classifier must read features")
    clf = species_refit(old, code_fit, p_fit, args.pull, args.people_weight)
    held_trees = np.array([not lab.startswith("other:") for lab in code_held["label"]])
    clf = clf.calibrated(code_held["features"][held_trees], list(code_held["label"][held_trees]))
    calib_rates = wrong_rates(det, p_cal, head)
    info = {
        **loaded.info,
        "people": {
            "tree_detector_fitted_on": {
                "code-made": int(len(code_fit["label"])),
                "people (fit part)": int(len(p_fit["kind"])),
            },
            "calibration_wrong": calib_rates,
            "tree_detector": shape | {"offset": det.offset},
            "species_pull": args.pull,
            "people_weight": args.people_weight,
            "command": " ".join(sys.argv),
        },
    }
    out = args.out or args.checkpoint
    save_loaded(
        loaded, out, info, tree_detector=det, species_id=loaded.species_id.with_classifier(clf)
    )
    np.savez(
        args.features / "lco_detector.npz",
        **{k: np.asarray(v) for k, v in lco.to_dict().items()},
    )
    for k, v in calib_rates.items():
        print(f"calibration part, {k}: {v:.1%} judged wrongly")
    print(f"temperatures: detector {det.temperature:.2f}, species {clf.temperature:.2f}")
    print(f"detector's limit: P(tree) {1 / (1 + np.exp(det.offset)):.3f} before the offset")
    print(
        f"wrote {out} and {args.features / 'lco_detector.npz'} ({time.perf_counter() - t0:.0f} s)"
    )


if __name__ == "__main__":
    main()
