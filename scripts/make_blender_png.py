"""Make docs/blender.png: a hand drawing, and the tree the Blender add-on makes of it,
rendered in Blender.

    .venv/bin/python scripts/make_blender_png.py [--sketch examples/hand/oak.png]
        [--species oak] [--budget 20] [--blender blender]

Builds the add-on's zip, then runs scripts/blender_render.py in Blender (headless, a
private user-scripts folder): the add-on predicts through this checkout's CLI and adds a
native Sapling tree with its bark and leaf materials, which Eevee renders in a lit scene
(alpha-clipped leaves casting alpha-clipped shadows).  The drawing and the render are put
side by side with captions here (Pillow).  About 10 minutes on two busy cores (Eevee on a
software GL).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

from blender_addon_zip import main as addon_zip
from PIL import Image, ImageDraw, ImageFont

ROOT = Path(__file__).resolve().parents[1]

SKETCH = ROOT / "examples" / "hand" / "oak.png"
CLI = ROOT / ".venv" / "bin" / "treesketch"


def compose(sketch: Path, render: Path, info: dict, out: Path, picked: bool) -> None:
    """The drawing (left) and the render (right), captioned (``picked``: the species was
    picked in the panel, not left to the drawing)."""
    pic = Image.open(render).convert("RGB")
    side = pic.height
    drawing = Image.open(sketch).convert("RGB").resize((side * 2 // 3, side * 2 // 3))
    pad, head, foot = 30, 64, 52
    canvas = Image.new("RGB", (pad * 3 + drawing.width + pic.width, head + side + foot), "white")
    canvas.paste(drawing, (pad, head + (side - drawing.height) // 2))
    canvas.paste(pic, (pad * 2 + drawing.width, head))
    d = ImageDraw.Draw(canvas)
    big, small = ImageFont.load_default(size=26), ImageFont.load_default(size=17)
    d.text(
        (pad + drawing.width // 2, head // 2), "the drawing", font=big, fill="black", anchor="mm"
    )
    d.text(
        (pad * 2 + drawing.width + pic.width // 2, head // 2),
        "in Blender, through the add-on: "
        + (f"{info['species']} (picked)" if picked else info["species_text"]),
        font=big,
        fill="black",
        anchor="mm",
    )
    d.text(
        (canvas.width // 2, head + side + foot // 2),
        f"Blender {info['blender']}, {info['engine']}: a native Sapling tree ({info['height']:.1f} m) "
        f"with the add-on's bark and leaf materials; leaves alpha-clipped ({info['leaf_blend']}), "
        f"shadows too ({info['leaf_shadow']})",
        font=small,
        fill=(60, 60, 60),
        anchor="mm",
    )
    canvas.save(out, optimize=True)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sketch", type=Path, default=SKETCH)
    ap.add_argument("--species", default="oak", help="the species picked, or AUTO")
    ap.add_argument("--budget", type=int, default=20)
    ap.add_argument("--blender", default="blender")
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "blender.png")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="blender-png-") as tmp:
        t = Path(tmp)
        if addon_zip([str(t / "treesketch_addon.zip")]) != 0:
            return 1
        cmd = [args.blender, "-b", "--factory-startup", "--python-exit-code", "1"]
        cmd += ["--python", str(ROOT / "scripts" / "blender_render.py"), "--"]
        cmd += [str(t / "treesketch_addon.zip"), str(CLI), str(args.sketch.resolve())]
        cmd += [str(t / "render.png"), str(t / "info.json"), args.species, str(args.budget)]
        env = {
            **os.environ,
            "BLENDER_USER_SCRIPTS": str(t / "scripts"),  # the user's Blender left alone
            "BLENDER_USER_CONFIG": str(t / "config"),
            "PYTHONPATH": str(ROOT),  # this checkout's code, whichever the venv came from
        }
        rc = subprocess.run(cmd, env=env, check=False).returncode
        if rc != 0:
            return rc
        info = json.loads((t / "info.json").read_text())
        compose(args.sketch, t / "render.png", info, args.out, args.species != "AUTO")
    print(f"wrote {args.out}: {info}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
