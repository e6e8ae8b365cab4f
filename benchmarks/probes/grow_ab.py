"""CPU time of grow and grow + mesh for the code in two source trees, A/B on one machine.

    .venv/bin/python benchmarks/probes/grow_ab.py BEFORE_DIR AFTER_DIR [--trees 8] [--repeats 7]
        [--rounds 2]

Each directory is a checkout of this repository (e.g. ``git archive <commit> | tar -x``).
For each tree, a fresh interpreter imports ``weberpenn`` from it and times
``grow(species.sample(name, i))`` and ``build_mesh`` for ``i < --trees``, keeping the
best of ``--repeats`` per tree (process CPU time, which other jobs on a shared machine
disturb less than wall time); rounds alternate A and B.  Prints the mean over trees in
milliseconds per species and the ratio B / A of the last round.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys

CHILD = r"""
import json, sys, time
sys.path.insert(0, sys.argv[1])
from weberpenn import build_mesh, grow, species
trees, repeats = int(sys.argv[2]), int(sys.argv[3])
out = {}
for name in species.SPECIES:
    ps = [species.sample(name, s) for s in range(trees)]
    grow(ps[0])
    g_all, t_all = [], []
    for p in ps:
        g, t = [], []
        for _ in range(repeats):
            t0 = time.process_time()
            sk = grow(p)
            t1 = time.process_time()
            build_mesh(sk)
            t2 = time.process_time()
            g.append(t1 - t0)
            t.append(t2 - t0)
        g_all.append(min(g))
        t_all.append(min(t))
    out[name] = [1000 * sum(g_all) / trees, 1000 * sum(t_all) / trees]
print(json.dumps(out))
"""


def _run(src: str, trees: int, repeats: int) -> dict:
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", PYTHONPATH=src)
    cmd = [sys.executable, "-c", CHILD, src, str(trees), str(repeats)]
    res = subprocess.run(cmd, capture_output=True, text=True, check=True, env=env, cwd=src)
    return json.loads(res.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("a")
    ap.add_argument("b")
    ap.add_argument("--trees", type=int, default=8)
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--rounds", type=int, default=2)
    args = ap.parse_args()
    for r in range(args.rounds):
        a = _run(os.path.abspath(args.a), args.trees, args.repeats)
        b = _run(os.path.abspath(args.b), args.trees, args.repeats)
        print(f"round {r + 1}")
        print("| species | A grow ms | B grow ms | B/A | A grow+mesh ms | B grow+mesh ms | B/A |")
        print("|---|---:|---:|---:|---:|---:|---:|")
        for name in a:
            ga, ta = a[name]
            gb, tb = b[name]
            print(
                f"| {name} | {ga:.1f} | {gb:.1f} | {gb / ga:.2f} | {ta:.1f} | {tb:.1f} | "
                f"{tb / ta:.2f} |"
            )


if __name__ == "__main__":
    main()
