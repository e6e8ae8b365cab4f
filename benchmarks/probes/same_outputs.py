"""Are the pipeline's outputs the same before and after a change that should not alter them?

    PYTHONPATH=$PWD .venv/bin/python benchmarks/probes/same_outputs.py OUT.json [--budget 10]
    .venv/bin/python benchmarks/probes/same_outputs.py --compare BEFORE.json AFTER.json

Runs ``Pipeline("tsn", RefineSettings(budget=..., time_limit=None))`` (the defaults but
the budget; no time limit, so the machine's speed cannot cut a run short) on the bundled
example (``examples/sketch_maple.png``) and every drawing of ``examples/hand``, and writes
for each what the run returns as data: the parameter dictionary, species, yaw, losses,
confidence, warning, the species tried and a SHA-256 of each uint8 sketch.  Run it in a
checkout before the change (``git archive HEAD | tar -x -C DIR``) and in the working tree
after; ``--compare`` says which drawings differ and in what.  About a minute at budget 10
on two cores.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def run(budget: int) -> dict:
    from treesketch import Pipeline, RefineSettings

    pipe = Pipeline("tsn", RefineSettings(budget=budget, time_limit=None))
    drawings = [ROOT / "examples" / "sketch_maple.png", *sorted(ROOT.glob("examples/hand/*.png"))]
    out = {}
    for path in drawings:
        r = pipe.run(path)
        out[path.name] = {
            "params": r.params.to_dict(),
            "species": r.species,
            "yaw": r.yaw,
            "losses": r.losses,
            "confidence": r.confidence,
            "warning": r.warning,
            "tried": r.extras.get("tried"),
            "evaluations": None if r.refinement is None else r.refinement.evaluations,
            "before": hashlib.sha256(r.sketch_before.tobytes()).hexdigest(),
            "after": hashlib.sha256(r.sketch_after.tobytes()).hexdigest(),
        }
        print(f"{path.name:>20} {r.species:>7} loss {r.losses['after']:.4f}", flush=True)
    return out


def compare(a: dict, b: dict) -> list[str]:
    """One line per drawing whose record differs (and the fields that do)."""
    lines = []
    for name in sorted(set(a) | set(b)):
        if name not in a or name not in b:
            lines.append(f"{name}: only in {'after' if name not in a else 'before'}")
            continue
        fields = [
            k for k in sorted(set(a[name]) | set(b[name])) if a[name].get(k) != b[name].get(k)
        ]
        if fields:
            lines.append(f"{name}: {', '.join(fields)} differ")
    return lines


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", type=Path, nargs="?", help="write the records here")
    ap.add_argument("--budget", type=int, default=10)
    ap.add_argument("--compare", type=Path, nargs=2, metavar=("BEFORE", "AFTER"))
    args = ap.parse_args(argv)
    if args.compare is not None:
        before, after = (json.loads(p.read_text()) for p in args.compare)
        diff = compare(before, after)
        print("\n".join(diff) if diff else f"identical: {len(before)} drawings")
        return 1 if diff else 0
    if args.out is None:
        ap.error("give OUT.json, or --compare BEFORE.json AFTER.json")
    args.out.write_text(json.dumps(run(args.budget), indent=1, sort_keys=True))
    return 0


if __name__ == "__main__":
    sys.exit(main())
