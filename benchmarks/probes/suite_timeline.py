"""How did the test suite's two workers spend their time? Each worker's modules end to end.

Reads the output of ``pytest -n 2 --dist loadfile -v --durations=0`` (each test's setup,
call and teardown times, and the order each worker finished its tests in) and prints, per
worker, the sum of its tests' times and each module over ``--over`` seconds with the
second it started at: whether the suite's time is its work or a tail, and whether a module
waited (a long setup).

    .venv/bin/python -m pytest -n 2 --dist loadfile -v --durations=0 > LOG
    .venv/bin/python benchmarks/probes/suite_timeline.py LOG
"""

from __future__ import annotations

import argparse
import collections
import re
from pathlib import Path


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("log", type=Path)
    ap.add_argument("--over", type=float, default=8.0, help="seconds: modules shown")
    args = ap.parse_args()
    lines = args.log.read_text().splitlines()
    took: dict[str, float] = collections.defaultdict(float)
    for line in lines:
        m = re.match(r"^([\d.]+)s (setup|call|teardown)\s+(\S+)", line)
        if m:
            took[m.group(3)] += float(m.group(1))
    order: dict[str, list[str]] = collections.defaultdict(list)
    for line in lines:
        m = re.match(r"^\[(gw\d+)\] \[\s*\d+%\] (PASSED|FAILED|ERROR|SKIPPED) (\S+)", line)
        if m:
            order[m.group(1)].append(m.group(3))
    for worker, tests in sorted(order.items()):
        t = 0.0
        modules: list[list] = []
        for test in tests:
            module = test.split("::")[0]
            if not modules or modules[-1][0] != module:
                modules.append([module, t, 0.0])
            modules[-1][2] += took.get(test, 0.0)
            t += took.get(test, 0.0)
        print(f"{worker}: {len(tests)} tests, {t:.0f} s")
        for module, start, seconds in modules:
            if seconds > args.over:
                print(f"  from {start:6.0f} s  {seconds:6.1f} s  {module}")


if __name__ == "__main__":
    main()
