"""Are the refinement's per-candidate passes of issue 48's last speed-up the same as the
plain numpy (or full-grow) rule they replace, and how much faster?

- liveness (``SearchSpace.live``, stopped at the first level that differs) against the
  rule that grows every probe whole: the same live dimensions on the eleven species x
  ``--trees`` sampled trees, and the seconds of each;
- ``render.edges.block_counts`` against numpy's sum over reshaped blocks (512-sample
  masks, 2 x 2 blocks: the refinement's hit masks);
- ``refine.objective.framed``'s 2 x 2 pooling (four strided minima) against numpy's min
  over reshaped blocks (a 256 px framed page);
- ``render.edges.binary_edges`` against the ramped float Sobel (256 px masks).

    .venv/bin/python benchmarks/probes/candidate_passes.py --trees 3
"""

from __future__ import annotations

import argparse
import dataclasses
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from refine.objective import SearchSpace
from render.edges import binary_edges, block_counts, sobel
from weberpenn import grow, species


def full_grow_live(space: SearchSpace, probe: float = 0.25) -> SearchSpace:
    """The rule before: every probe grown whole, leaves included."""

    def signature(params: Any) -> tuple[np.ndarray, ...]:
        sk = grow(params)
        return (np.asarray(sk.points), np.asarray(sk.radii), np.asarray(sk.leaf_matrices))

    def same(a: tuple[np.ndarray, ...], b: tuple[np.ndarray, ...]) -> bool:
        return all(
            x.shape == y.shape and np.allclose(x, y, rtol=0.0, atol=1e-9)
            for x, y in zip(a, b, strict=True)
        )

    x0 = space.from_params(space.base)
    ref = signature(space.to_params(x0))
    keep = []
    for i, u in enumerate(space.dims):
        for t in (x0[i] + probe, x0[i] - probe):
            if 0.0 <= t <= 1.0:
                x = x0.copy()
                x[i] = t
                if not same(signature(space.to_params(x)), ref):
                    keep.append(u)
                    break
    return dataclasses.replace(space, dims=tuple(keep))


def ms(fn: Callable[[], Any], repeats: int) -> float:
    fn()
    t = time.perf_counter()
    for _ in range(repeats):
        fn()
    return (time.perf_counter() - t) / repeats * 1e3


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--trees", type=int, default=3, help="sampled trees a species")
    ap.add_argument("--repeats", type=int, default=200)
    args = ap.parse_args()

    spaces = [
        SearchSpace.create(name, species.sample(name, 700 + seed))
        for name in species.SPECIES
        for seed in range(args.trees)
    ]
    t_old = t_new = 0.0
    same = 0
    for sp in spaces:
        t = time.perf_counter()
        a = full_grow_live(sp)
        t_old += time.perf_counter() - t
        t = time.perf_counter()
        b = sp.live()
        t_new += time.perf_counter() - t
        same += a.labels == b.labels
    print(
        f"liveness: the same live dimensions on {same} of {len(spaces)} spaces; "
        f"whole grows {t_old:.1f} s, by level {t_new:.1f} s"
    )

    rng = np.random.default_rng(0)
    mask = rng.random((512, 512)) < 0.05
    assert np.array_equal(block_counts(mask, 2), mask.reshape(256, 2, 256, 2).sum(axis=(1, 3)))
    old = ms(lambda: mask.reshape(256, 2, 256, 2).sum(axis=(1, 3), dtype=np.uint8), args.repeats)
    new = ms(lambda: block_counts(mask, 2), args.repeats)
    print(f"block counts (512-sample mask): numpy {old:.2f} ms, compiled {new:.2f} ms, the same")

    page = (rng.random((256, 256)) * 255).astype(np.uint8)

    def pooled() -> np.ndarray:
        return np.minimum(
            np.minimum(page[0::2, 0::2], page[0::2, 1::2]),
            np.minimum(page[1::2, 0::2], page[1::2, 1::2]),
        )

    assert np.array_equal(pooled(), page.reshape(128, 2, 128, 2).min(axis=(1, 3)))
    old = ms(lambda: page.reshape(128, 2, 128, 2).min(axis=(1, 3)), args.repeats)
    new = ms(pooled, args.repeats)
    print(
        f"2 x 2 pooling (256 px page): reshaped min {old:.2f} ms, strided minima {new:.2f} ms, the same"
    )

    m = rng.random((256, 256)) < 0.3
    assert np.array_equal(binary_edges(m), sobel(m.astype(np.float32), 4.0) >= 0.9)
    old = ms(lambda: sobel(m.astype(np.float32), 4.0) >= 0.9, args.repeats)
    new = ms(lambda: binary_edges(m), args.repeats)
    print(f"branch edges (256 px mask): float Sobel {old:.2f} ms, integer {new:.2f} ms, the same")


if __name__ == "__main__":
    main()
