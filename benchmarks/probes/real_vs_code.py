"""Probe: how well can a small classifier tell the tree doodles made by code from people's
drawings of a tree?  (Nearer 50% is better: the code-made ones look more like people's.)

People's drawings of "a tree" (``shared/people_doodles/strokes/tree.ndjson``, put on a 256
page where they drew them, a line 2 to 4 px wide; ``--n`` of them, a random choice by
author) against ``--n`` ``tree_doodle`` (seeds 0 to n-1, the species in turn: the eleven, or
``--broadleaves`` oak, maple and cherry), now and at a git revision (``--before``, e.g.
``main``).  Features of each image, its ink (below 128) only, so neither grey levels nor
antialiasing tell: ``shape`` (ink fraction, ink box, and the measures of
:func:`eval.drawing_stats.image_stats`: place, size, aspect, crown and trunk, ground line)
and ``ink 16`` (those plus the ink downsampled to 16 x 16).  An L2-regularised logistic
regression (numpy; its regularisation picked inside each training part), 5-fold
cross-validated (folds split people by author), prints the mean accuracy and its spread
over the folds.

    PYTHONPATH=$PWD .venv/bin/python benchmarks/probes/real_vs_code.py [--n 400] [--before main]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from types import ModuleType

import numpy as np

from eval.drawing_stats import image_stats

sys.path.insert(0, str(Path(__file__).resolve().parent))
from people_stats import BROADLEAVES, code_trees, load_generator, people  # noqa: E402

FOLDS = 5


def shape_features(img: np.ndarray) -> np.ndarray:
    """Ink fraction, ink box (0-1 of the page) and the drawing's measures."""
    ink = img < 128
    rows, cols = np.flatnonzero(ink.any(axis=1)), np.flatnonzero(ink.any(axis=0))
    box = np.array([cols[0], rows[0], cols[-1], rows[-1]], float) / img.shape[0]
    st = image_stats(img)
    return np.concatenate([[ink.mean()], box, list(st.values())])


def ink_features(img: np.ndarray, side: int = 16) -> np.ndarray:
    """The ink downsampled to ``side`` x ``side`` (the fraction of each block inked)."""
    ink = (img < 128).astype(float)
    k = img.shape[0] // side
    return ink.reshape(side, k, side, k).mean(axis=(1, 3)).ravel()


def fit_logistic(x: np.ndarray, y: np.ndarray, l2: float = 1.0, iters: int = 30) -> np.ndarray:
    """Weights (bias last) of an L2-regularised logistic regression, by Newton steps on
    standardised features (few hundred samples: the Hessian is small)."""
    xb = np.hstack([x, np.ones((len(x), 1))])
    w = np.zeros(xb.shape[1])
    reg = np.full(xb.shape[1], l2)
    reg[-1] = 0.0
    for _ in range(iters):
        p = 1 / (1 + np.exp(-xb @ w))
        grad = xb.T @ (p - y) + reg * w
        hess = (xb * (p * (1 - p))[:, None]).T @ xb + np.diag(reg + 1e-9)
        step = np.linalg.solve(hess, grad)
        w -= step
        if np.abs(step).max() < 1e-6:
            break
    return w


L2_GRID = (1.0, 10.0, 100.0, 1000.0)


def _folds(groups: np.ndarray, k: int, seed: int) -> np.ndarray:
    """A fold number per sample; a group (an author) stays in one fold."""
    uniq = np.unique(groups)
    fold_of = dict(zip(uniq, np.random.default_rng(seed).permutation(len(uniq)) % k, strict=True))
    return np.array([fold_of[g] for g in groups])


def _accuracy(xtr, ytr, xte, yte, l2: float) -> float:
    mu, sd = xtr.mean(axis=0), xtr.std(axis=0) + 1e-6
    w = fit_logistic((xtr - mu) / sd, ytr, l2)
    xt = np.hstack([(xte - mu) / sd, np.ones((len(xte), 1))])
    return float(np.mean(((xt @ w) > 0) == yte))


def cross_validated(x: np.ndarray, y: np.ndarray, groups: np.ndarray) -> np.ndarray:
    """Accuracy per fold, the regularisation chosen in each fold by a 3-fold split of its
    training part (nested: the held-out fold picks nothing)."""
    fold = _folds(groups, FOLDS, 0)
    acc = []
    for f in range(FOLDS):
        tr, te = fold != f, fold == f
        inner = _folds(groups[tr], 3, 1)
        xtr, ytr = x[tr], y[tr]
        best = max(
            L2_GRID,
            key=lambda l2: np.mean(
                [
                    _accuracy(
                        xtr[inner != i], ytr[inner != i], xtr[inner == i], ytr[inner == i], l2
                    )
                    for i in range(3)
                ]
            ),
        )
        acc.append(_accuracy(xtr, ytr, x[te], y[te], best))
    return np.array(acc)


def _people_sample(n: int) -> tuple[list[np.ndarray], np.ndarray]:
    rows, imgs = people()
    pick = np.random.default_rng(1).permutation(len(rows))[:n]
    return [imgs[i] for i in pick], np.array([rows[i]["author"] for i in pick])


def _features(imgs: list[np.ndarray]) -> dict[str, np.ndarray]:
    shape = np.array([shape_features(im) for im in imgs])
    ink = np.array([ink_features(im) for im in imgs])
    return {"shape": shape, "ink 16 + shape": np.hstack([ink, shape])}


def _score(gen: ModuleType, n: int, species: tuple[str, ...], real: dict, authors) -> dict:
    imgs = [gen.tree_doodle(s, k) for s, k in code_trees(n, species)]
    code = _features(imgs)
    y = np.concatenate([np.ones(len(authors)), np.zeros(n)])
    groups = np.concatenate([authors, [f"code{k}" for k in range(n)]])
    out = {}
    for name, xr in real.items():
        x = np.vstack([xr, code[name]])
        out[name] = cross_validated(x, y, groups)
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--n", type=int, default=400, help="drawings of each side")
    ap.add_argument("--before", default=None, help="a git revision to compare with (e.g. main)")
    ap.add_argument("--broadleaves", action="store_true", help="code: oak, maple, cherry only")
    args = ap.parse_args(argv)
    real_imgs, authors = _people_sample(args.n)
    real = _features(real_imgs)
    gens = [("now", load_generator(None))]
    if args.before:
        gens.insert(0, (args.before, load_generator(args.before)))
    print(
        f"people: {len(authors)} drawings; code: {args.n} tree_doodle (seeds 0-{args.n - 1}), "
        f"{'oak, maple, cherry' if args.broadleaves else 'the eleven species'}; "
        f"{FOLDS}-fold logistic regression, accuracy mean (min-max over folds)"
    )
    for label, gen in gens:
        species = BROADLEAVES if args.broadleaves else tuple(gen.TREE_SPECIES)
        for name, acc in _score(gen, args.n, species, real, authors).items():
            print(f"{label:>8} {name:>16}: {acc.mean():.3f} ({acc.min():.3f}-{acc.max():.3f})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
