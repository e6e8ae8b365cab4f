"""Helpers for the dataset build tests: a build killed with ``kill -9`` and resumed."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def kill_and_resume_build(
    out: Path, options: list[str], timeout: float, settle: float = 0.0
) -> subprocess.CompletedProcess:
    """``treesketch dataset build`` of 2 trees per species, front and left at 48 px, with
    ``options``, into ``out``: killed (-9) once its first tree is done, ``settle`` seconds
    left for orphaned workers to exit, then run again to the end.  Asserts the kill left
    1 to 9 trees done and no ``DONE`` marker, and that the rerun succeeded and skipped
    them; returns the rerun."""
    cmd = [sys.executable, "-m", "treesketch.cli", "dataset", "build", "--out", str(out)]
    cmd += ["--trees-per-species", "2", "--views", "front,left", "--size", "48"]
    cmd += [*options, "--no-progress"]
    proc = subprocess.Popen(cmd, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if any((out / "done").glob("*.json")):
            break
        if proc.poll() is not None:
            pytest.fail(f"builder ended before the kill: {proc.stdout.read().decode()}")
        time.sleep(0.05)
    else:
        proc.kill()
        pytest.fail(f"no tree finished within {timeout:g} s")
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    time.sleep(settle)
    n_done = len(list((out / "done").glob("*.json")))
    assert 1 <= n_done < 10 and not (out / "DONE").exists()
    res = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=timeout * 2.5)
    assert res.returncode == 0, res.stdout + res.stderr
    assert f"{n_done} already done" in res.stdout
    return res
