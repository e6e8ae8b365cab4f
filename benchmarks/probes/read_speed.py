"""How long does reading a drawing take (``treesketch.steps.prepare_input``: the reader's
whole cleaning and framing)?  People's first ``--drawings`` held-out trees, read whole
three times; the best pass's time per drawing.  Run it in two code trees to compare.

    .venv/bin/python benchmarks/probes/read_speed.py [--drawings 60]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path[:0] = [str(ROOT)]


def main() -> None:
    from eval.people import people_drawings
    from treesketch.steps import load_sketch, prepare_input

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--drawings", type=int, default=60)
    args = ap.parse_args()
    held = people_drawings("held", ("strokes",), ("tree",))[: args.drawings]
    pages = [load_sketch(d.image()) for d in held]
    for page in pages[:3]:  # imports and first calls out of the timing
        prepare_input(page)
    best = float("inf")
    for _ in range(3):
        t = time.perf_counter()
        for page in pages:
            prepare_input(page)
        best = min(best, (time.perf_counter() - t) / len(pages))
    print(f"prepare_input: {1000 * best:.1f} ms a drawing (best of 3, {len(pages)} drawings)")


if __name__ == "__main__":
    main()
