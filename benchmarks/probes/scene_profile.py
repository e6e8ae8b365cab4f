"""Where the mitsuba scene build of one refinement evaluation goes.

    .venv/bin/python benchmarks/probes/scene_profile.py [--repeats 3] [--species cherry maple]

For ``species.sample(name, 0)``'s full mesh, per part (branches, leaves), the best of
``--repeats`` wall times of: creating the ``mi.Mesh`` and filling its buffers from numpy
(``mi.traverse`` + ``params.update()``, as ``render.silhouette`` does), loading the scene
(``mi.load_dict``: Embree's BVH build), and updating the loaded scene's vertex positions
in place (``mi.traverse(scene)`` + ``params.update()``, which rebuilds the BVH).  Then the
ray casts of one 128 px sketch on a new scene, with the number of Dr.Jit kernels compiled
for it (``dr.kernel_history``: a new scene reuses the cached kernels).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from render.backend import init_mitsuba  # noqa: E402
from render.silhouette import mesh_arrays  # noqa: E402
from render.sketch import SketchRenderer  # noqa: E402
from weberpenn import build_mesh, grow, species  # noqa: E402


def _best(fn, repeats: int) -> float:
    best = float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--species", nargs="*", default=["maple", "cherry"])
    args = ap.parse_args()
    backend = init_mitsuba()
    import drjit as dr
    import mitsuba as mi

    print(
        f"mitsuba {mi.__version__}, variant {backend.variant}, {backend.threads} threads, "
        f"Embree {bool(getattr(mi, 'MI_ENABLE_EMBREE', False))}"
    )
    SketchRenderer(build_mesh(grow(species.sample("palm", 0)))).sketch(0.0, 128)  # warm-up
    print(
        "| species | part | triangles | mi.Mesh + buffers ms | scene load (BVH) ms "
        "| in-place update ms | us per triangle (load) |"
    )
    print("|---|---|---:|---:|---:|---:|---:|")
    for name in args.species:
        mesh = build_mesh(grow(species.sample(name, 0)), species=name)
        for part in ("branches", "leaves"):
            arrays = mesh_arrays(getattr(mesh, part))
            if arrays is None:
                continue
            v, f = arrays

            def make(v=v, f=f, part=part):
                m = mi.Mesh(part, len(v) // 3, len(f) // 3, has_vertex_normals=False)
                p = mi.traverse(m)
                p["vertex_positions"] = mi.Float(v)
                p["faces"] = mi.UInt(f)
                p.update()
                dr.eval()
                return m

            t_mesh = _best(make, args.repeats)
            t_load = (
                _best(
                    lambda make=make, part=part: mi.load_dict({"type": "scene", part: make()}),
                    args.repeats,
                )
                - t_mesh
            )
            scene = mi.load_dict({"type": "scene", part: make()})
            params = mi.traverse(scene)
            key = f"{part}.vertex_positions"

            def update(params=params, key=key, v=v):
                params[key] = mi.Float(v * np.float32(1.001))
                params.update()
                dr.eval()

            t_upd = _best(update, args.repeats)
            print(
                f"| {name} | {part} | {len(f) // 3} | {1e3 * t_mesh:.1f} | {1e3 * t_load:.0f} "
                f"| {1e3 * t_upd:.0f} | {1e6 * t_load / (len(f) // 3):.2f} |",
                flush=True,
            )
        rend = SketchRenderer(mesh)
        dr.set_flag(dr.JitFlag.KernelHistory, True)
        dr.kernel_history()  # reading the history empties it
        t0 = time.perf_counter()
        rend.scene.coverage(0.0, 256, 2, keep_hr=True, leaf_supersample=1)
        t_rays = time.perf_counter() - t0
        hist = dr.kernel_history()
        dr.set_flag(dr.JitFlag.KernelHistory, False)
        compiled = sum(1 for k in hist if not k.get("cache_hit", False))
        print(
            f"{name}: ray casts of one sketch on a new scene {1e3 * t_rays:.0f} ms, "
            f"{len(hist)} kernels launched, {compiled} compiled (the rest from the cache)"
        )


if __name__ == "__main__":
    main()
