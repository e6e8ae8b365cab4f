"""Probe: do the tree doodles made by code look like people's drawings of a tree, in numbers?

People's drawings of "a tree" (``shared/people_doodles/strokes/tree.ndjson``, 629 people,
drawn on a 400 px canvas, put on a 256 page where they drew them) against ``tree_doodle``
(seeds 0 to N-1, the species in turn: the eleven, and the broadleaves oak, maple and cherry
alone), now and at a git revision (``--before``, e.g. ``main``: its ``eval/doodles.py`` and
``eval/strokes.py`` loaded as they were).  Per measure of :mod:`eval.drawing_stats` (stroke
measures need the strokes: people's and ``tree_doodle_strokes`` now), the median and the
quartiles.

    PYTHONPATH=$PWD .venv/bin/python benchmarks/probes/people_stats.py [--n 400] [--before main]
"""

from __future__ import annotations

import argparse
import importlib
import importlib.util
import subprocess
import sys
import tempfile
from collections.abc import Callable, Sequence
from pathlib import Path
from types import ModuleType

import numpy as np

from eval.drawing_stats import (
    PEOPLE_CANVAS,
    image_stats,
    rasterise,
    read_strokes,
    stroke_stats,
    summarise,
)

ROOT = Path(__file__).resolve().parents[2]
PEOPLE = ROOT.parent / "shared" / "people_doodles" / "strokes" / "tree.ndjson"
BROADLEAVES = ("oak", "maple", "cherry")


def load_generator(rev: str | None) -> ModuleType:
    """``eval.doodles`` now (``rev`` None), or as it was at git revision ``rev``, loaded
    under another package name (with its ``eval.strokes``) beside today's."""
    if rev is None:
        return importlib.import_module("eval.doodles")
    pkg_dir = Path(tempfile.mkdtemp(prefix="doodles_")) / "before_eval"
    pkg_dir.mkdir()
    for name in ("doodles.py", "strokes.py"):
        text = subprocess.run(
            ["git", "show", f"{rev}:eval/{name}"], cwd=ROOT, check=True, capture_output=True
        ).stdout
        (pkg_dir / name).write_bytes(text)
    (pkg_dir / "__init__.py").write_text("")
    name = f"before_eval_{abs(hash(rev))}"
    spec = importlib.util.spec_from_file_location(
        name, pkg_dir / "__init__.py", submodule_search_locations=[str(pkg_dir)]
    )
    assert spec is not None and spec.loader is not None
    pkg = importlib.util.module_from_spec(spec)
    sys.modules[name] = pkg
    spec.loader.exec_module(pkg)
    return importlib.import_module(f"{name}.doodles")


def people(path: Path = PEOPLE, seed: int = 0) -> tuple[list[dict], list[np.ndarray]]:
    """People's drawings (rows of :func:`eval.drawing_stats.read_strokes`) and their images:
    each put on a 256 page where it was drawn on the canvas, with a line 2 to 4 px wide."""
    rows = read_strokes(path)
    rng = np.random.default_rng(seed)
    widths = rng.integers(2, 5, len(rows))
    return rows, [
        rasterise(r["strokes"], PEOPLE_CANVAS, 256, int(w))
        for r, w in zip(rows, widths, strict=True)
    ]


def code_trees(n: int, species: Sequence[str]) -> list[tuple[str, int]]:
    """``n`` (species, seed) pairs: seeds 0 to n-1 (benchmark seeds), the species in turn."""
    return [(species[k % len(species)], k) for k in range(n)]


def _column(rows: list[dict[str, float]]) -> dict[str, str]:
    return {k: f"{m:.3g} ({lo:.3g}-{hi:.3g})" for k, (lo, m, hi) in summarise(rows).items()}


def _stats(
    images: list[np.ndarray], strokes: Callable[[], list[list[np.ndarray]]] | None
) -> dict[str, str]:
    measured = [image_stats(im) for im in images]
    col = _column(measured)
    col["ground"] = f"{np.mean([m['ground'] for m in measured]):.3f} drawings"
    if strokes is not None:
        col.update(_column([stroke_stats(s) for s in strokes()]))
    return col


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--n", type=int, default=400, help="code-made drawings per column")
    ap.add_argument("--before", default=None, help="a git revision to compare with (e.g. main)")
    args = ap.parse_args(argv)
    rows, imgs = people()
    columns = {"people": _stats(imgs, lambda: [r["strokes"] for r in rows])}
    gens = [("now", load_generator(None))]
    if args.before:
        gens.insert(0, (args.before, load_generator(args.before)))
    for label, gen in gens:
        for group, species in (("eleven", gen.TREE_SPECIES), ("broadleaves", BROADLEAVES)):
            pairs = code_trees(args.n, species)
            images = [gen.tree_doodle(s, k) for s, k in pairs]
            has_strokes = hasattr(gen, "tree_doodle_strokes")
            strokes = (
                (lambda p=pairs, g=gen: [g.tree_doodle_strokes(s, k) for s, k in p])
                if has_strokes
                else None
            )
            columns[f"{label}: {group}"] = _stats(images, strokes)
    keys = list(dict.fromkeys(k for col in columns.values() for k in col))
    print(f"people: {len(rows)} drawings; code: {args.n} per column (seeds 0-{args.n - 1})")
    print("| measure | " + " | ".join(columns) + " |")
    print("|---|" + "---:|" * len(columns))
    for k in keys:
        print(f"| {k} | " + " | ".join(col.get(k, "-") for col in columns.values()) + " |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
