"""Execute notebooks/*.ipynb and store them with their outputs (`make notebooks`).

Each notebook runs in a temporary folder (its working directory), with the repository
first on the kernel's path, so nothing is written into the checkout.  Sizes are kept
moderate through the notebooks' own TS_NB_* settings; every picture is shrunk (at most
MAX_WIDTH pixels wide, a 64-colour palette) so the repository stays light; a notebook
with an error output is not written.  The test suite executes them too
(tests/test_notebooks.py, with its own smaller sizes and without storing anything).

    .venv/bin/python scripts/run_notebooks.py [NAME.ipynb ...]
"""

from __future__ import annotations

import base64
import io
import os
import sys
import tempfile
from collections.abc import Mapping
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
NB_DIR = ROOT / "notebooks"
STORED = {  # the sizes the stored outputs are made with (a few minutes on two cores)
    "TS_NB_SIZE": "128",
    "TS_NB_BUDGET": "10",
    "TS_NB_STEP": "30",
    "TS_NB_SAMPLES": "2000",
}
MAX_WIDTH = 640
MAX_PNG_BYTES = 100_000
MAX_NOTEBOOK_BYTES = 400_000
TIMEOUT_S = 900


def execute(path: Path, workdir: Path, env: Mapping[str, str]) -> object:
    """``path`` executed with ``workdir`` as its working directory and ``env`` added to the
    kernel's environment; returns the executed notebook (nbformat), errors included."""
    import nbclient
    import nbformat

    nb = nbformat.read(path, as_version=4)
    saved = dict(os.environ)
    os.environ.update(env)
    os.environ["PYTHONPATH"] = str(ROOT) + os.pathsep + saved.get("PYTHONPATH", "")
    os.environ["PYTHONDONTWRITEBYTECODE"] = "1"  # no __pycache__ in the checkout either
    if "MPLBACKEND" not in env:  # a non-interactive backend would drop every figure
        os.environ.pop("MPLBACKEND", None)
    try:
        client = nbclient.NotebookClient(
            nb,
            timeout=TIMEOUT_S,
            kernel_name="python3",
            allow_errors=True,
            resources={"metadata": {"path": str(workdir)}},
        )
        client.execute()
    finally:
        os.environ.clear()
        os.environ.update(saved)
    return nb


def errors(nb: object) -> list[str]:
    return [
        f"{o.get('ename')}: {o.get('evalue')}"
        for c in nb.cells  # type: ignore[attr-defined]
        if c.cell_type == "code"
        for o in c.get("outputs", [])
        if o.output_type == "error"
    ]


def shrink_png(data: str) -> str:
    """A base64 PNG made small: at most MAX_WIDTH wide, a 64-colour palette."""
    from PIL import Image

    img = Image.open(io.BytesIO(base64.b64decode(data))).convert("RGB")
    if img.width > MAX_WIDTH:
        img = img.resize((MAX_WIDTH, round(img.height * MAX_WIDTH / img.width)), Image.LANCZOS)
    buf = io.BytesIO()
    img.quantize(64).save(buf, format="PNG", optimize=True)
    return base64.b64encode(buf.getvalue()).decode("ascii")


def tidy(nb: object) -> None:
    """Small pictures, no run-specific metadata (timestamps), so a rerun diffs little."""
    for c in nb.cells:  # type: ignore[attr-defined]
        if c.cell_type != "code":
            continue
        c.metadata.pop("execution", None)
        for o in c.get("outputs", []):
            data = o.get("data", {})
            if "image/png" in data:
                data["image/png"] = shrink_png(data["image/png"])
                o.get("metadata", {}).pop("image/png", None)
                data.pop("text/plain", None)  # "<Figure size ...>" says nothing


def main(argv: list[str]) -> int:
    import nbformat

    from weberpenn.fileio import atomic_write

    names = argv or sorted(p.name for p in NB_DIR.glob("*.ipynb"))
    failed = 0
    for name in names:
        path = NB_DIR / name
        if not path.is_file():
            print(f"error: no notebook {name} in notebooks/", file=sys.stderr)
            return 2
        with tempfile.TemporaryDirectory(prefix="ts_nb_") as tmp:
            nb = execute(path, Path(tmp), STORED)
        bad = errors(nb)
        if bad:
            print(f"{name}: not stored, it raised: {bad[0]}", file=sys.stderr)
            failed += 1
            continue
        tidy(nb)
        text = nbformat.writes(nb) + "\n"
        if len(text) > MAX_NOTEBOOK_BYTES:
            print(f"{name}: not stored, {len(text)} bytes > {MAX_NOTEBOOK_BYTES}", file=sys.stderr)
            failed += 1
            continue
        atomic_write(path, text)
        print(f"{name}: stored with its outputs ({len(text) // 1024} KiB)")
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
