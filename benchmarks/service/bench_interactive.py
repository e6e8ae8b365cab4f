"""Benchmark the interactive loop over HTTP: the first tree viewable, an edit's round
trip, the viewer's GLB.

    PYTHONPATH=$PWD .venv/bin/python benchmarks/service/bench_interactive.py [--trees 4]
        [--edits 10] [--estimator tsn] [--drawings 4] [--json FILE]

A real server (uvicorn on a local port, one worker process, ``--estimator``) is started.

1. **First tree viewable**: for each of ``--drawings`` example drawings
   (``examples/hand/``), ``POST /jobs`` (the default budget), then ``GET /jobs/{id}`` every
   20 ms until its progress carries a ``preview`` and ``GET .../preview/tree.glb`` answers;
   the seconds from the POST, and the job's whole run for comparison.
2. **Edit round trip**, per species of ``weberpenn.species.SPECIES``: ``--trees`` sampled
   trees, ``--edits`` edits each (random values of random controls, as a person drags a
   slider), timed from sending ``POST /trees`` (``Accept: model/gltf-binary``, the
   viewer's face budget, ``fit`` as the page sends it: an edit past the generator's limits
   gets the nearest tree that grows, counted as "fitted") to the whole GLB received;
   median and p95.  Run twice: with the
   worker idle ("quiet") and while it refines a drawing ("at load").
3. **Viewer GLB**: triangles and bytes of each edit's GLB per species (largest).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import random
import statistics
import tempfile
import time
from pathlib import Path
from typing import Any

import httpx

from treesketch.service import ServiceConfig, create_app
from treesketch.service.inprocess import serve
from treesketch.service.store import FINISHED
from treesketch.trees import VIEW_FACES
from weberpenn import species
from weberpenn.controls import CONTROLS

ROOT = Path(__file__).resolve().parents[2]


def wait_ready(client: httpx.Client) -> None:
    while client.get("/health").json()["workers"] < 1:
        time.sleep(0.2)


def random_edit(rng: random.Random, own: dict[str, Any]) -> dict[str, Any]:
    """One to three controls at random values (a height near the tree's own)."""
    out: dict[str, Any] = {}
    for c in rng.sample(CONTROLS, rng.randint(1, 3)):
        if c.kind == "toggle":
            out[c.name] = rng.random() < 0.8
        elif c.kind == "choice":
            out[c.name] = rng.choice(c.choices)[0]
        elif c.name == "seed":
            out[c.name] = rng.randrange(1000)
        elif c.name == "height":
            out[c.name] = round(own["height"] * rng.uniform(0.6, 1.6), 1)
        else:
            out[c.name] = round(rng.uniform(c.lo, c.hi), 2)
    return out


def glb_faces(data: bytes) -> int:
    import io

    import trimesh

    scene = trimesh.load(io.BytesIO(data), file_type="glb")
    return sum(len(g.faces) for g in scene.geometry.values())


def edits(client: httpx.Client, trees: int, n: int, seed: int) -> dict[str, Any]:
    rng = random.Random(seed)
    out: dict[str, Any] = {}
    for name in species.SPECIES:
        times, sizes, faces, refused, fitted = [], [], [], 0, 0
        for t in range(trees):
            params = species.sample(name, t).to_dict()
            own = client.post("/trees", json={"params": params, "species": name}).json()
            for _ in range(n):
                body = {
                    "params": params,
                    "species": name,
                    "controls": random_edit(rng, own["controls"]),
                    "max_faces": VIEW_FACES,
                    "fit": True,  # as the page sends it: past the limits, the nearest tree
                }
                t0 = time.perf_counter()
                r = client.post("/trees", json=body, headers={"Accept": "model/gltf-binary"})
                data = r.content
                dt = time.perf_counter() - t0
                if r.status_code != 200:  # a tree the generator refuses even fitted
                    refused += 1
                    continue
                fitted += r.headers.get("X-Tree-Adjusted", "{}") != "{}"
                times.append(dt)
                sizes.append(len(data))
                faces.append(glb_faces(data))
        times.sort()
        out[name] = {
            "edits": len(times),
            "refused": refused,
            "fitted": fitted,
            "median_ms": 1000 * statistics.median(times),
            "p95_ms": 1000 * times[min(len(times) - 1, int(0.95 * len(times)))],
            "max_glb_mb": max(sizes) / 1e6,
            "median_glb_mb": statistics.median(sizes) / 1e6,
            "max_faces": max(faces),
        }
        print(name, out[name], flush=True)
    return out


def first_tree(client: httpx.Client, drawings: list[Path]) -> list[dict[str, Any]]:
    rows = []
    for path in drawings:
        t0 = time.perf_counter()
        r = client.post("/jobs", files={"sketch": (path.name, path.read_bytes(), "image/png")})
        job = r.json()["id"]
        first = None
        while True:
            body = client.get(f"/jobs/{job}").json()
            if first is None and (body.get("progress") or {}).get("preview"):
                g = client.get(f"/jobs/{job}/preview/tree.glb")
                if g.status_code == 200:
                    first = time.perf_counter() - t0
            if body["state"] in FINISHED:
                break
            time.sleep(0.02)
        total = time.perf_counter() - t0
        rows.append({"drawing": path.name, "first_tree_s": first, "job_s": total})
        print(rows[-1], flush=True)
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trees", type=int, default=4, help="sampled trees per species")
    ap.add_argument("--edits", type=int, default=10, help="edits per tree")
    ap.add_argument("--estimator", default="tsn")
    ap.add_argument("--drawings", type=int, default=4, help="example drawings for step 1")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--json", type=Path, default=None)
    args = ap.parse_args()
    drawings = sorted((ROOT / "examples" / "hand").glob("*.png"))[: args.drawings]
    report: dict[str, Any] = {
        "machine": f"{platform.node()} {platform.machine()}, {os.cpu_count()} CPUs",
        "loadavg_start": os.getloadavg(),
        "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
    }
    with tempfile.TemporaryDirectory(prefix="bench-interactive-") as data:
        config = ServiceConfig(data=Path(data), workers=1, estimator=args.estimator)
        with serve(create_app(config)) as url, httpx.Client(base_url=url, timeout=600) as c:
            wait_ready(c)
            report["first_tree"] = first_tree(c, drawings)
            print("quiet edits", flush=True)
            report["edits_quiet"] = edits(c, args.trees, args.edits, args.seed)
            # at load: the worker refines a drawing (a long budget) meanwhile
            job = c.post(
                "/jobs",
                files={"sketch": ("d.png", drawings[0].read_bytes(), "image/png")},
                data={"budget": "1000", "time_limit": "600"},
            ).json()["id"]
            while c.get(f"/jobs/{job}").json()["state"] != "running":
                time.sleep(0.1)
            print("edits at load", flush=True)
            report["edits_load"] = edits(c, args.trees, args.edits, args.seed + 1)
            report["load_job_state"] = c.get(f"/jobs/{job}").json()["state"]
            c.delete(f"/jobs/{job}")
    report["loadavg_end"] = os.getloadavg()
    text = json.dumps(report, indent=1)
    if args.json:
        args.json.write_text(text + "\n")
    print(text)


if __name__ == "__main__":
    main()
