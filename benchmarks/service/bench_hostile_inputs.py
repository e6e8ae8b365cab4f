"""Hostile inputs that used to cost time (issue 30, items 6 and 12), timed.

1. A Sapling preset of escaped quotes (``"\\"\\...``), the shape that made the bracket
   scan in ``weberpenn.params`` quadratic: ``load_params`` at several sizes up to the 1 MB
   cap (it must refuse each one, quickly).
2. ``treesketch predict`` with an output in a folder that takes no file: seconds to the
   exit-2 message (it used to come after the refinement).

    PYTHONPATH=$PWD nice -n 10 .venv/bin/python benchmarks/service/bench_hostile_inputs.py \\
        [--sizes 8000,32000,120000,999000] [--skip-cli]

Prints one line per measurement.  Run it against another checkout by putting that
checkout first on PYTHONPATH (and ``--sizes`` small there: the old scan is quadratic).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def preset_scan(sizes: list[int], folder: Path) -> None:
    from weberpenn import ParamError, load_params

    for n in sizes:
        f = folder / f"quotes_{n}.py"
        f.write_text('"\\' * (n // 2))
        t0 = time.perf_counter()
        try:
            load_params(f)
            outcome = "loaded (unexpected)"
        except ParamError:
            outcome = "refused"
        print(f"preset of {n:>9,} bytes: {time.perf_counter() - t0:8.3f} s, {outcome}")


def unwritable_output(folder: Path) -> None:
    locked = folder / "locked"
    locked.mkdir()
    locked.chmod(0o555)
    if os.access(locked, os.W_OK):  # root: permission bits do not stop it
        locked = Path("/sys")
    cmd = [
        sys.executable,
        "-m",
        "treesketch.cli",
        "predict",
        str(ROOT / "examples" / "sketch_maple.png"),
    ]
    cmd += ["--out", str(locked / "out" / "tree.glb"), "--budget", "20", "--quiet"]
    t0 = time.perf_counter()
    run = subprocess.run(cmd, capture_output=True, text=True, cwd=folder)
    seconds = time.perf_counter() - t0
    last = (run.stderr.strip().splitlines() or ["(nothing on stderr)"])[-1]
    print(f"predict --out in {locked}: exit {run.returncode} after {seconds:.1f} s: {last[:120]}")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="8000,32000,120000,999000")
    ap.add_argument("--skip-cli", action="store_true")
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        preset_scan([int(s) for s in args.sizes.split(",") if s], Path(tmp))
        if not args.skip_cli:
            unwritable_output(Path(tmp))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
