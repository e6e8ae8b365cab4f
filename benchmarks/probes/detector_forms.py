"""Check: which form of "is this a tree?" reads people's drawings best, on cached features?

``scripts/fit_people.py`` fits the tree detector on the network's features of code-made
and people's drawings (``scripts/people_features.py --out DIR``).  This probe fits, on the
same fitting data, the forms tried for it and measures each on the held part (authors
never fitted on): the logistic regression, single networks of one hidden layer (one per
seed, to see how much a seed moves them), the five averaged (what ships), and a one-class
score (the Mahalanobis distance from the trees' features in their first ``k`` principal
directions, its threshold at the calibration trees' 97th percentile).  With
``--leave-out`` the kinds of :data:`eval.people.LEFT_OUT_KINDS` are also left out of
fitting and the left-out kinds' warned share is reported.

    .venv/bin/python benchmarks/probes/detector_forms.py --features DIR [--seeds 3]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "scripts"))

from fit_people import calibrating, detector_data, subset  # noqa: E402

from eval.people import LEFT_OUT_KINDS  # noqa: E402
from tsn.tree_detect import TreeDetector  # noqa: E402

HEAD = 1280  # the heads' pooled features: what the detector reads


def line(name: str, p: np.ndarray, held: dict, left: np.ndarray | None) -> str:
    trees, warned = held["kind"] == "tree", p < 0.5
    out = f"| {name} | {1 - warned[trees].mean():.1%} | {warned[~trees].mean():.1%} |"
    if left is not None:
        out += f" {warned[left].mean():.1%} |"
    return out


def one_class(x: np.ndarray, calib_trees: np.ndarray, k: int) -> tuple:
    """Distance from the trees ``x`` in their first ``k`` principal directions, and the
    threshold that keeps 97 % of ``calib_trees``."""
    mean, std = x.mean(axis=0), x.std(axis=0) + 1e-6
    z = (x - mean) / std
    centre = z.mean(axis=0)
    _, s, vt = np.linalg.svd(z - centre, full_matrices=False)
    scale = s[:k] / np.sqrt(len(z))

    def dist(f: np.ndarray) -> np.ndarray:
        return ((((f - mean) / std - centre) @ vt[:k].T / scale) ** 2).sum(axis=1)

    return dist, float(np.quantile(dist(calib_trees), 0.97))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--features", type=Path, required=True)
    ap.add_argument("--seeds", type=int, default=3, help="members shown alone (<= 5)")
    ap.add_argument("--leave-out", action="store_true")
    args = ap.parse_args()
    load = lambda name: dict(np.load(args.features / f"{name}.npz"))  # noqa: E731
    code_fit, code_held = load("code_fit"), load("code_held")
    people, held = load("people_fit"), load("people_held")
    calib = calibrating(people["key"], people["source"])
    p_fit, p_cal = subset(people, ~calib), subset(people, calib)
    drop = LEFT_OUT_KINDS if args.leave_out else ()
    x, y, w = detector_data(code_fit, p_fit, HEAD, drop)
    cal = detector_data(code_held, p_cal, HEAD, drop)[:2]
    feats = held["features"][:, :HEAD]
    left = np.isin(held["kind"], LEFT_OUT_KINDS) if args.leave_out else None
    print(f"fitting {len(y)} drawings ({int(y.sum())} trees); held {len(feats)}\n")
    extra = left is not None
    print("| detector | trees unwarned | other things warned |" + (" left out, warned |" * extra))
    print("|---|---:|---:|" + ("---:|" * extra))
    linear = TreeDetector.fit(x, y, held_out=cal, l2=1e-2, weights=w)
    print(line("logistic regression", linear.probabilities(feats), held, left), flush=True)
    five = TreeDetector.fit(x, y, held_out=cal, l2=1e-3, weights=w, hidden=128, members=5)
    for seed in range(min(args.seeds, 5)):
        # member ``seed`` of the five alone (each member is fitted from its own seed)
        one = TreeDetector(
            five.mean, five.std, five.weight[seed : seed + 1],
            np.asarray(five.bias)[seed : seed + 1], five.temperature,
            five.hidden_weight[seed : seed + 1], five.hidden_bias[seed : seed + 1],
        )  # fmt: skip
        print(line(f"one network, seed {seed}", one.probabilities(feats), held, left), flush=True)
    print(line("five networks averaged (shipped)", five.probabilities(feats), held, left))
    for k in (32, 128):
        dist, limit = one_class(x[y], cal[0][np.asarray(cal[1], bool)], k)
        p = np.where(dist(feats) <= limit, 1.0, 0.0)
        print(line(f"one-class, {k} directions", p, held, left))


if __name__ == "__main__":
    main()
