"""Fixed inputs shipped with the tests (no file outside the repository is needed)."""

from pathlib import Path

DATA = Path(__file__).resolve().parent / "data"
GT_PARAM_DIR = DATA / "treesketchnet_test_params"  # the paper's 15 ground-truth trees (BSD-3)
GT_PARAM_FILES = sorted(GT_PARAM_DIR.glob("*.json"))
