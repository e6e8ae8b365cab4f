"""Probe: can "is this a tree?" warn of kinds of things it never saw, in other forms?

The leave-categories-out detector of ``scripts/fit_people.py`` (fitted without the kinds
of ``eval.people.LEFT_OUT_KINDS``, people's and code-made) warns about two thirds of those
kinds on held-out authors; flowers and persons pass.  This fits other forms on the same
cached features (``scripts/people_features.py --out DIR``; ``fit_people.py`` leaves the
code-made ones beside them) and prints, for the held-out authors, trees unwarned, seen
kinds warned and left-out kinds warned (each limit balanced on the calibration authors'
seen kinds, as the shipped detector's):

- ``base``: the shipped form (five networks on the heads' features);
- ``all``: the same on every feature (the species branch's too);
- ``multi``: one network a kind (tree against each seen kind, softmax), P(tree);
- ``density``: how far a drawing lies from the fit trees (Mahalanobis distance in the
  first 64 principal components of their features, and the residual outside them), alone,
  combined with ``base`` by a logistic regression, and as a second gate after ``base``
  at the limits that spare 99.5-97 % of the calibration trees.

    PYTHONPATH=$PWD .venv/bin/python benchmarks/probes/unseen_kinds.py DIR [--forms base,all,multi,density]
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "scripts"))

from fit_people import calibrating, detector_data, subset  # noqa: E402

from eval.people import LEFT_OUT_KINDS  # noqa: E402
from tsn.tree_detect import TreeDetector  # noqa: E402

HEAD = 1280  # the heads' pooled features: the first columns of people_features' output
COMPONENTS = 64


def report(name: str, held: dict, is_tree: Callable[[np.ndarray], np.ndarray]) -> None:
    says = is_tree(held["features"])
    tree = held["kind"] == "tree"
    left = np.isin(held["kind"], LEFT_OUT_KINDS)
    seen = ~tree & ~left
    kinds = " ".join(f"{k} {np.mean(~says[held['kind'] == k]):.0%}" for k in LEFT_OUT_KINDS)
    print(
        f"| {name} | {np.mean(says[tree]):.1%} | {np.mean(~says[seen]):.1%} | "
        f"{np.mean(~says[left]):.1%} | {kinds} |",
        flush=True,
    )


def balanced(score: np.ndarray, is_tree: np.ndarray) -> float:
    """The limit on ``score`` where the smaller of trees spared and others warned is
    largest (``TreeDetector.with_balanced_limit``'s rule)."""
    limits = np.unique(score)
    spared = (score[is_tree][None] >= limits[:, None]).mean(1)
    warned = (score[~is_tree][None] < limits[:, None]).mean(1)
    return float(limits[np.argmax(np.minimum(spared, warned))])


def networks(x: np.ndarray, y: np.ndarray, w: np.ndarray, held: tuple, width: int) -> TreeDetector:
    return TreeDetector.fit(x[:, :width], y, held_out=(held[0][:, :width], held[1]), weights=w,
                            l2=1e-3, hidden=128, members=5)  # fmt: skip


def multi(code: dict, people: dict, x: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
    """Log-odds of "tree" against the other seen kinds from five softmax networks."""
    import torch

    keep_c = np.array([lab.removeprefix("other:") not in LEFT_OUT_KINDS for lab in code["label"]])
    lab_c = [lab.removeprefix("other:") if lab.startswith("other:") else "tree"
             for lab in code["label"][keep_c]]  # fmt: skip
    keep_p = ~np.isin(people["kind"], LEFT_OUT_KINDS)
    labels = np.array(lab_c + list(people["kind"][keep_p]))
    classes = sorted(set(labels))
    y = torch.tensor([classes.index(lab) for lab in labels])
    mean, std = x.mean(0), x.std(0) + 1e-6
    xt = torch.tensor((x - mean) / std, dtype=torch.float32)
    counts = np.bincount(y.numpy(), minlength=len(classes))
    weight = torch.tensor(len(y) / (len(classes) * np.maximum(counts, 1)), dtype=torch.float32)
    nets = []
    for seed in range(5):
        torch.manual_seed(seed)
        net = torch.nn.Sequential(
            torch.nn.Dropout(0.2), torch.nn.Linear(x.shape[1], 128), torch.nn.ReLU(),
            torch.nn.Dropout(0.3), torch.nn.Linear(128, len(classes)),
        )  # fmt: skip
        opt = torch.optim.AdamW(net.parameters(), 1e-3, weight_decay=1e-3)
        for _ in range(60):
            order = torch.randperm(len(y))
            for i in range(0, len(y), 256):
                b = order[i : i + 256]
                loss = torch.nn.functional.cross_entropy(net(xt[b]), y[b], weight=weight)
                opt.zero_grad()
                loss.backward()
                opt.step()
        nets.append(net.eval())
    t = classes.index("tree")

    def log_odds(f: np.ndarray) -> np.ndarray:
        with torch.no_grad():
            ft = torch.tensor((f[:, : x.shape[1]] - mean) / std, dtype=torch.float32)
            lp = torch.stack([torch.log_softmax(n(ft), 1) for n in nets]).mean(0)
            other = torch.cat([lp[:, :t], lp[:, t + 1 :]], 1)
            return (lp[:, t] - torch.logsumexp(other, 1)).numpy()

    return log_odds


def distances(x_trees: np.ndarray, spread: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
    """``(N, 2)``: Mahalanobis distance in the fit trees' first principal components and
    the residual outside them."""
    mu = x_trees.mean(0)
    z = (x_trees - mu) / spread
    _, s, vt = np.linalg.svd(z, full_matrices=False)
    basis, var = vt[:COMPONENTS], s[:COMPONENTS] ** 2 / len(z)

    def of(f: np.ndarray) -> np.ndarray:
        zz = (f[:, :HEAD] - mu) / spread
        q = zz @ basis.T
        return np.stack([np.sqrt((q**2 / var).sum(1)), np.linalg.norm(zz - q @ basis, axis=1)], 1)

    return of


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("features", type=Path, help="people_features.py's --out (after fit_people)")
    ap.add_argument("--forms", default="base,all,multi,density")
    args = ap.parse_args()
    d = args.features
    code_fit, code_held = dict(np.load(d / "code_fit.npz")), dict(np.load(d / "code_held.npz"))
    people, held = dict(np.load(d / "people_fit.npz")), dict(np.load(d / "people_held.npz"))
    calib = calibrating(people["key"], people["source"])
    p_fit, p_cal = subset(people, ~calib), subset(people, calib)
    x, y, w = detector_data(code_fit, p_fit, 2 * HEAD, LEFT_OUT_KINDS)
    hd = detector_data(code_held, p_cal, 2 * HEAD, LEFT_OUT_KINDS)[:2]
    seen = ~np.isin(p_cal["kind"], LEFT_OUT_KINDS)
    xc, yc = p_cal["features"][seen], p_cal["kind"][seen] == "tree"
    print(
        "| form | trees unwarned | seen kinds warned | left-out kinds warned | per left-out kind |"
    )
    print("|---|---:|---:|---:|---|")
    forms = args.forms.split(",")
    det = None
    if "base" in forms or "density" in forms:
        det = networks(x, y, w, hd, HEAD).with_balanced_limit(xc[:, :HEAD], yc)
    if "base" in forms:
        report("base", held, lambda f: det.probabilities(f[:, :HEAD]) >= 0.5)
    if "all" in forms:
        every = networks(x, y, w, hd, 2 * HEAD).with_balanced_limit(xc, yc)
        report("all features", held, lambda f: every.probabilities(f) >= 0.5)
    if "multi" in forms:
        odds = multi(code_fit, p_fit, x[:, :HEAD])
        limit = balanced(odds(xc), yc)
        report("one network a kind", held, lambda f: odds(f) >= limit)
    if "density" in forms:
        of = distances(x[y, :HEAD], x[:, :HEAD].std(0) + 1e-6)
        dens = TreeDetector.fit(of(xc), yc, l2=0).with_balanced_limit(of(xc), yc)
        report("density alone", held, lambda f: dens.probabilities(of(f)) >= 0.5)
        z = lambda f: det.logits(f[:, :HEAD]) / det.temperature  # noqa: E731
        both = TreeDetector.fit(np.column_stack([z(xc), of(xc)]), yc, l2=0)
        both = both.with_balanced_limit(np.column_stack([z(xc), of(xc)]), yc)
        report("density + base, one regression", held,
               lambda f: both.probabilities(np.column_stack([z(f), of(f)])) >= 0.5)  # fmt: skip
        dc = dens.logits(of(xc))
        for spare in (0.995, 0.99, 0.98, 0.97):
            t = float(np.quantile(dc[yc], 1 - spare))
            report(f"base, then density sparing {spare:.1%}", held,
                   lambda f, t=t: (det.probabilities(f[:, :HEAD]) >= 0.5) & (dens.logits(of(f)) >= t))  # fmt: skip


if __name__ == "__main__":
    main()
