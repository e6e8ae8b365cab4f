"""The outline step alone, replayed: what another form of it would give the same drawings.

The outline step (``refine.search.outline_searched``) is the refinement's last part and
the cheapest to vary, but a ``bench_drawings.py --part follow`` run spends most of its
time before it (the first estimate, the search).  ``capture`` runs the benchmark with the
step wrapped so every call's inputs and result are pickled beside the run's JSON;
``replay`` runs the step again on them with the code as it is, with module constants
changed by ``--set`` (``refine.search.POLISH_AGAIN_EVALS=0``: the step before the polish
again; a longer step needs ``refine.search.OUTLINE_TREES`` set too: the calls made with
the whole step's trees then get that many), and scores both trees as the benchmark does
(the returned tree grown, meshed and sketched at its view, framed as drawn, its envelope
overlap with the prepared drawing at 256 px; a pair's side view too).  Only the calls for
the species the run returned are replayed; the step's other uses of the search's distance
are kept.

    .venv/bin/python benchmarks/probes/outline_replay.py capture RUN.json -- \\
        --part follow --only people --people 72 --people-from 0
    .venv/bin/python benchmarks/probes/outline_replay.py replay RUN.json [RUN2.json] \\
        --set refine.search.POLISH_AGAIN_EVALS=0
"""

from __future__ import annotations

import argparse
import importlib
import json
import pickle
import sys
import time
from collections.abc import Callable
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path[:0] = [str(ROOT), str(ROOT / "benchmarks")]


def _calls_dir(run: Path) -> Path:
    return run.with_suffix(".outline")


def capture(run: Path, bench_args: list[str]) -> int:
    """``bench_drawings.py`` with ``--json run`` and ``bench_args``, each outline step's
    inputs and result pickled in ``RUN.outline/`` (with the index of its drawing)."""
    import bench_drawings

    import refine.search as search
    import treesketch

    out = _calls_dir(run)
    out.mkdir(parents=True, exist_ok=True)
    real_step, real_run = search.outline_searched, treesketch.Pipeline.run
    state = {"case": -1, "n": 0}

    def step(result, drawing, views, run_, t0, trees, below=None):  # noqa: ANN001, ANN202
        done = real_step(result, drawing, views, run_, t0, trees, below)
        state["n"] += 1
        call = dict(case=state["case"], result=result, drawing=drawing, views=views)
        call |= dict(trees=trees, below=below, out=done, full=search.OUTLINE_TREES)
        (out / f"{state['n']:05d}.pkl").write_bytes(pickle.dumps(call))
        return done

    def pipeline_run(self, *a: Any, **k: Any) -> Any:
        state["case"] += 1
        return real_run(self, *a, **k)

    search.outline_searched = step
    treesketch.Pipeline.run = pipeline_run
    return bench_drawings.main([*bench_args, "--json", str(run)])


class _Distance:
    """The search's distance of a sketch to whichever drawing's target it is given."""

    def __init__(self, drawings: list[Any]) -> None:
        self.drawings = drawings

    def loss_of_sketch(self, sketch: np.ndarray, target: Any) -> float:
        return next(d for d in self.drawings if d.target is target).distance(sketch)


def _overlaps(result: Any, drawn: list[np.ndarray]) -> list[float]:
    """The returned tree's envelope overlap with each drawn view, as the benchmark scores
    it (``Result.sketch_after`` against ``Result.input_sketch``)."""
    from eval.envelope import envelope_overlap
    from render.sketch import SketchRenderer
    from treesketch.steps import SKETCH_SIZE, as_drawn
    from weberpenn import build_mesh, grow

    r = SketchRenderer(build_mesh(grow(result.params), species=result.species))
    yaws = [result.yaw, *(result.yaw + t for t in result.view_yaws)][: len(drawn)]
    return [
        envelope_overlap(d, as_drawn(r.sketch(y % 360.0, SKETCH_SIZE)))
        for d, y in zip(drawn, yaws, strict=True)
    ]


def set_constants(assignments: list[str]) -> Callable[[], None]:
    """Each ``module.NAME=value`` of ``assignments`` set (the value of NAME's own type);
    returns what puts them back."""
    was = []
    for a in assignments:
        name, value = a.split("=", 1)
        module, attr = name.rsplit(".", 1)
        mod = importlib.import_module(module)
        old = getattr(mod, attr)
        was.append((mod, attr, old))
        setattr(mod, attr, type(old)(value))

    def restore() -> None:
        for mod, attr, old in reversed(was):
            setattr(mod, attr, old)

    return restore


def replay(runs: list[Path], assignments: list[str]) -> None:
    import refine.search as search

    set_constants(assignments)
    rows = []
    times: list[float] = []
    kept = 0
    for run in runs:
        records = json.loads(run.read_text())["records"]
        sketches = np.load(run.with_suffix(".npz"))
        calls = [pickle.loads(p.read_bytes()) for p in sorted(_calls_dir(run).glob("*.pkl"))]
        # the whole step's trees when captured (runs captured before it was kept: the
        # most any of their calls had)
        then = max((c.get("full", c["trees"]) for c in calls), default=0)
        for call in calls:
            rec = records[call["case"]] if call["case"] < len(records) else None
            if rec is None or call["result"].species != rec["species"]:
                continue
            drawing, views = call["drawing"], call["views"]
            stub = SimpleNamespace(
                cancel=None,
                deadline=None,
                on_best=None,
                obj=_Distance([drawing, *(v.drawing for v in views)]),
            )
            # a call given the whole step's trees gets the whole step's as ``--set`` makes it
            trees = search.OUTLINE_TREES if call["trees"] >= then else call["trees"]
            t = time.perf_counter()
            new = search.outline_searched(
                call["result"], drawing, views, stub, t, trees, call["below"]
            )
            seconds = time.perf_counter() - t
            keys = ["input_sketch"] + [f"view{i}/input_sketch" for i in range(2, len(views) + 2)]
            drawn = [sketches[f"{rec['name']}/{k}"] for k in keys]
            was = _overlaps(call["out"], drawn)
            same = new.params == call["out"].params and new.yaw == call["out"].yaw
            now = was if same else _overlaps(new, drawn)
            rows.append((was, now))
            times.append(seconds)
            kept += same
            print(
                f"{rec['name']:>26} run {np.round(was, 3)} replayed {np.round(now, 3)} "
                f"{seconds:.1f} s, {new.outline_evaluations} trees",
                flush=True,
            )
    was = np.array([w for w, _ in rows])
    now = np.array([n for _, n in rows])
    for i in range(was.shape[1]):
        a, b = was[:, i], now[:, i]
        print(
            f"view {i + 1}, {len(a)} drawings: median {np.median(a):.4f} -> {np.median(b):.4f}, "
            f"mean {a.mean():.4f} -> {b.mean():.4f}, up {(b > a + 0.005).sum()}, "
            f"down {(b < a - 0.005).sum()} (by more than 0.005)"
        )
    print(
        f"the step: median {np.median(times):.2f} s, total {sum(times):.1f} s; "
        f"the run's own tree again {kept} of {len(rows)}"
    )


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    c = sub.add_parser("capture", help="run the benchmark, keeping each outline step's inputs")
    c.add_argument("run", type=Path, help="the run's JSON (the calls go to RUN.outline/)")
    c.add_argument("bench", nargs=argparse.REMAINDER, help="-- bench_drawings.py's arguments")
    r = sub.add_parser("replay", help="the captured steps again, with --set constants")
    r.add_argument("runs", type=Path, nargs="+")
    r.add_argument("--set", action="append", default=[], help="module.CONSTANT=value")
    args = ap.parse_args()
    if args.cmd == "capture":
        return capture(args.run, [a for a in args.bench if a != "--"])
    replay(args.runs, args.set)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
