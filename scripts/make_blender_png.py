"""Make docs/blender.png: the demo's tree rendered in Blender beside its drawing.

    .venv/bin/python scripts/make_blender_png.py [--budget 40] [--blender blender]

Runs what ``make demo`` runs (examples/sketch_maple.png -> TSN -> refinement, budget 40),
writes the GLB turned to the drawn view (``export_mesh(..., yaw=result.yaw)``) to
out/blender_demo.glb, then renders it in Blender (scripts/blender_render.py, Workbench).
"""

from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from treesketch.pipeline import predict_then_refine  # noqa: E402
from weberpenn.export import export_mesh  # noqa: E402

SKETCH = ROOT / "examples" / "sketch_maple.png"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--budget", type=int, default=40)
    ap.add_argument("--blender", default="blender")
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "blender.png")
    args = ap.parse_args()
    result = predict_then_refine(SKETCH, budget=args.budget)
    glb = export_mesh(result.tree_mesh, ROOT / "out" / "blender_demo.glb", yaw=result.yaw)
    print(f"{result.species}, yaw {result.yaw:.1f}: {glb}")
    caption = f"its GLB: {result.species}, view yaw {result.yaw:.0f}"
    cmd = [args.blender, "-b", "--factory-startup", "--python-exit-code", "1"]
    cmd += ["--python", str(ROOT / "scripts" / "blender_render.py"), "--"]
    cmd += [str(SKETCH), str(glb), str(args.out), caption]
    return subprocess.run(cmd, check=False).returncode


if __name__ == "__main__":
    sys.exit(main())
