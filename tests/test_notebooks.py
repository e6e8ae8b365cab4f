"""The research notebooks: executed with small sizes so they never rot, in a temporary
folder, leaving nothing in the checkout; stored with their (small) outputs so a reader on
the web sees the pictures (`make notebooks`, scripts/run_notebooks.py, regenerates them)."""

from __future__ import annotations

import base64
import importlib.util
import subprocess
from pathlib import Path

import pytest

nbformat = pytest.importorskip("nbformat")
nbclient = pytest.importorskip("nbclient")

ROOT = Path(__file__).resolve().parents[1]
NB_DIR = ROOT / "notebooks"
NAMES = ["01_tree_model.ipynb", "02_predict_and_refine.ipynb", "03_rotation_sweep.ipynb"]
SMALL = {
    "TS_NB_SIZE": "64",
    "TS_NB_BUDGET": "3",
    "TS_NB_STEP": "90",
    "TS_NB_SAMPLES": "1000",
    "TS_NB_SPECIES": "palm",
    "MPLBACKEND": "Agg",
}


# the test tools' own caches: another worker's tests (``make test`` runs two) write them
# while a notebook runs
CACHES = (".pytest_cache", ".hypothesis")


def _runner():
    spec = importlib.util.spec_from_file_location(
        "run_notebooks", ROOT / "scripts" / "run_notebooks.py"
    )
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _checkout_files() -> set[str]:
    """Every file of the checkout git would see (tracked, untracked, ignored), caches aside."""
    out = subprocess.run(
        ["git", "-C", str(ROOT), "ls-files", "--cached", "--others"],
        capture_output=True, text=True, check=True,
    )  # fmt: skip
    ignored = subprocess.run(
        ["git", "-C", str(ROOT), "ls-files", "--others", "--ignored", "--exclude-standard"],
        capture_output=True, text=True, check=True,
    )  # fmt: skip
    names = set(out.stdout.splitlines()) | set(ignored.stdout.splitlines())
    return {n for n in names if "__pycache__" not in n and not n.startswith(CACHES)}


@pytest.mark.slow
@pytest.mark.parametrize("name", NAMES)
def test_notebook_runs_and_leaves_nothing_behind(name, tmp_path):
    run = _runner()
    before = _checkout_files()
    stamp_before = (NB_DIR / name).read_bytes()
    nb = run.execute(NB_DIR / name, tmp_path, SMALL)
    assert not run.errors(nb), run.errors(nb)
    assert _checkout_files() == before, sorted(_checkout_files() ^ before)
    assert (NB_DIR / name).read_bytes() == stamp_before  # executing does not store


def test_notebooks_stored_with_small_outputs():
    run = _runner()
    assert sorted(p.name for p in NB_DIR.glob("*.ipynb")) == NAMES
    for name in NAMES:
        path = NB_DIR / name
        nb = nbformat.read(path, as_version=4)
        code = [c for c in nb.cells if c.cell_type == "code"]
        assert all(c.get("execution_count") for c in code), f"{name}: not executed; make notebooks"
        assert not run.errors(nb), (name, run.errors(nb))
        pngs = [
            base64.b64decode(o["data"]["image/png"])
            for c in code
            for o in c.get("outputs", [])
            if "image/png" in o.get("data", {})
        ]
        assert pngs, f"{name}: stored without pictures; run make notebooks"
        assert all(len(p) <= run.MAX_PNG_BYTES for p in pngs), (name, [len(p) for p in pngs])
        assert path.stat().st_size <= run.MAX_NOTEBOOK_BYTES, name
        assert str(ROOT) not in path.read_text(encoding="utf-8"), f"{name}: an absolute path"


def test_shrink_png_keeps_pictures_small():
    import io

    import numpy as np
    from PIL import Image

    rng = np.random.default_rng(0)
    img = Image.fromarray(rng.integers(0, 255, (600, 1400, 3), dtype=np.uint8))
    buf = io.BytesIO()
    img.save(buf, format="PNG")
    small = base64.b64decode(_runner().shrink_png(base64.b64encode(buf.getvalue()).decode()))
    out = Image.open(io.BytesIO(small))
    assert out.width == 640 and out.height == round(600 * 640 / 1400)
    assert len(small) < len(buf.getvalue())


def test_checkout_listing_sees_any_new_file():
    """The check above would see a file a notebook leaves, ignored by git or not."""
    before = _checkout_files()
    probe = ROOT / "notebooks" / "left_behind.tmp"  # *.tmp is git-ignored
    try:
        probe.write_text("x")
        assert _checkout_files() - before == {"notebooks/left_behind.tmp"}
    finally:
        probe.unlink()
    assert _checkout_files() == before
