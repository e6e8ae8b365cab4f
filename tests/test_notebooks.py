"""Execute the research notebooks with small budgets so they never rot (outputs discarded)."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

nbformat = pytest.importorskip("nbformat")
nbclient = pytest.importorskip("nbclient")

NB_DIR = Path(__file__).resolve().parent.parent / "notebooks"
SMALL = {
    "TS_NB_SIZE": "64",
    "TS_NB_BUDGET": "3",
    "TS_NB_STEP": "45",
    "TS_NB_SAMPLES": "1000",
    "TS_NB_SPECIES": "palm",
}


@pytest.mark.slow
@pytest.mark.parametrize(
    "name", ["01_tree_model.ipynb", "02_predict_and_refine.ipynb", "03_rotation_sweep.ipynb"]
)
def test_notebook_runs(name, tmp_path, monkeypatch):
    for k, v in {**SMALL, "TS_NB_OUT": str(tmp_path / "out"), "MPLBACKEND": "Agg"}.items():
        monkeypatch.setenv(k, v)
    root = str(NB_DIR.parent)
    monkeypatch.setenv("PYTHONPATH", root + os.pathsep + os.environ.get("PYTHONPATH", ""))
    nb = nbformat.read(NB_DIR / name, as_version=4)
    client = nbclient.NotebookClient(
        nb, timeout=240, kernel_name="python3", resources={"metadata": {"path": str(tmp_path)}}
    )
    client.execute()
    errors = [
        o
        for c in nb.cells
        if c.cell_type == "code"
        for o in c.get("outputs", [])
        if o.output_type == "error"
    ]
    assert not errors


def test_notebooks_committed_without_outputs():
    for path in sorted(NB_DIR.glob("*.ipynb")):
        nb = nbformat.read(path, as_version=4)
        assert all(not c.get("outputs") for c in nb.cells if c.cell_type == "code"), path.name
        assert path.stat().st_size < 50_000, path.name
