"""How much faster is one code's refinement than another's, on people's drawings, when
the shared machine drifts by a quarter between runs?

Two worker processes, one per code tree (``--a`` and ``--b``: a checkout or a worktree;
each imports its own tree's code), load the pipeline and the drawings
(``benchmarks.bench_drawings.follow_cases``, people's held-out trees), warm up on the
first, then refine the drawings in turn: A then B on one drawing, B then A on the next
(and the other way in the next round), so both codes meet the same drift. Only one
works at a time. Prints each code's median and mean refinement seconds
(``Result.timings["refine"]``, the default settings) over all runs and per round, B's
time over A's, and whether both returned the same loss on every drawing (the same
searches).

    git worktree add /tmp/before 180227c
    .venv/bin/python benchmarks/probes/refine_paired.py --a /tmp/before --b . \\
        --people 12 --people-from 20 --rounds 3
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

WORKER = """
import argparse, json, sys
from benchmarks.bench_drawings import follow_cases
from treesketch import Pipeline, RefineSettings
n, start = int(sys.argv[1]), int(sys.argv[2])
ns = argparse.Namespace(only="people", people=n, people_from=start, pairs=0, hand=False)
cases = follow_cases(ns)
pipe = Pipeline("tsn", RefineSettings())
pipe.run(cases[0][1])
print("ready", flush=True)
for line in sys.stdin:
    res = pipe.run(cases[int(line)][1])
    print(json.dumps({"refine": res.timings["refine"], "loss": res.losses["after"]}), flush=True)
"""


def start(tree: Path, people: int, first: int) -> subprocess.Popen:
    from eval.people import ENV_ROOT, people_root

    # both codes read the drawings this checkout reads (a worktree elsewhere has no
    # ../shared beside it)
    env = dict(os.environ, PYTHONPATH=str(tree), **{ENV_ROOT: str(people_root())})
    cmd = [sys.executable, "-c", WORKER, str(people), str(first)]
    proc = subprocess.Popen(
        cmd, cwd=tree, env=env, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True
    )
    assert proc.stdout is not None
    for line in proc.stdout:
        if line.strip() == "ready":
            return proc
    raise SystemExit(f"the worker for {tree} stopped before it was ready")


def ask(proc: subprocess.Popen, i: int) -> dict:
    assert proc.stdin is not None and proc.stdout is not None
    proc.stdin.write(f"{i}\n")
    proc.stdin.flush()
    return json.loads(proc.stdout.readline())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--a", type=Path, required=True, help="the code tree to compare against")
    ap.add_argument("--b", type=Path, required=True, help="the code tree measured")
    ap.add_argument("--people", type=int, default=12)
    ap.add_argument("--people-from", type=int, default=20)
    ap.add_argument("--rounds", type=int, default=3)
    args = ap.parse_args()
    procs = {
        k: start(t.resolve(), args.people, args.people_from)
        for k, t in (("A", args.a), ("B", args.b))
    }
    times: dict[str, list[float]] = {"A": [], "B": []}
    losses: dict[str, dict[int, float]] = {"A": {}, "B": {}}
    for r in range(args.rounds):
        for i in range(args.people):
            for k in "AB" if (i + r) % 2 == 0 else "BA":
                rec = ask(procs[k], i)
                times[k].append(rec["refine"])
                losses[k][i] = rec["loss"]
    for proc in procs.values():
        assert proc.stdin is not None
        proc.stdin.close()
        proc.wait()
    a, b = np.array(times["A"]), np.array(times["B"])
    print(f"A {args.a}: median {np.median(a):.3f} s, mean {a.mean():.3f} s")
    print(f"B {args.b}: median {np.median(b):.3f} s, mean {b.mean():.3f} s")
    print(f"B / A: sums {b.sum() / a.sum():.3f}, median of per-run ratios {np.median(b / a):.3f}")
    print("the same losses on every drawing:", losses["A"] == losses["B"])
    n = args.people
    for r in range(args.rounds):
        sl = slice(r * n, (r + 1) * n)
        print(f"  round {r + 1}: A {np.median(a[sl]):.3f} s, B {np.median(b[sl]):.3f} s (medians)")


if __name__ == "__main__":
    main()
