"""reports/ stays true: made with the shipped checkpoint, stamped, no absolute path.

These read the committed reports/ folder.  When they fail after a new network ships,
regenerate the report and commit it (the message names the command)."""

from __future__ import annotations

import csv
import re
import subprocess
from pathlib import Path

import pytest

from eval.stamp import file_sha256, parse_stamp

ROOT = Path(__file__).resolve().parents[1]
REPORTS = ROOT / "reports"
SHIPPED = ROOT / "checkpoints" / "tsn_lite0.pt"
FIX = (
    "regenerate it with `make reports` (= `.venv/bin/python -m treesketch.cli eval paper`, "
    "run from the repository root) and commit reports/"
)
# an absolute path: a Unix root folder name or a Windows drive after a separator
ABSOLUTE = re.compile(
    r"(?:^|[\s\"'`(=:,\[])(?:/(?:home|work|tmp|root|usr|var|mnt|opt|srv|data|Users|private)"
    r"(?:/|\b)|[A-Za-z]:\\)"
)


def _readme() -> str:
    path = REPORTS / "README.md"
    if not path.is_file():
        pytest.fail(f"reports/README.md is missing: {FIX}")
    return path.read_text(encoding="utf-8")


def test_report_names_the_shipped_checkpoint():
    stamp = parse_stamp(_readme())
    sha = stamp.get("checkpoint_sha256")
    shipped = file_sha256(SHIPPED)
    assert sha == shipped, (
        f"reports/README.md was made with checkpoint sha256 {sha or '(none stated)'} but the "
        f"shipped checkpoints/tsn_lite0.pt is {shipped}: {FIX}"
    )
    for path in sorted(REPORTS.glob("*.csv")):
        with path.open(encoding="utf-8") as f:
            shas = {row["checkpoint_sha256"] for row in csv.DictReader(f)}
        assert shas == {shipped}, f"reports/{path.name} holds rows of another checkpoint: {FIX}"


def test_report_stamp_is_complete():
    stamp = parse_stamp(_readme())
    assert re.fullmatch(r"[0-9a-f]{40}(\+dirty)?", stamp.get("commit", "")), (stamp, FIX)
    assert re.fullmatch(r"[0-9a-f]{64}", stamp.get("checkpoint_sha256", "")), (stamp, FIX)
    assert re.fullmatch(r"\d{4}-\d\d-\d\d \d\d:\d\d UTC", stamp.get("date", "")), (stamp, FIX)
    assert stamp.get("machine", "").strip(), (stamp, FIX)
    assert stamp.get("checkpoint") == "checkpoints/tsn_lite0.pt", (stamp, FIX)
    # the commit it names is in this history (not a commit of another branch or clone)
    commit = stamp["commit"].removesuffix("+dirty")
    git = subprocess.run(
        ["git", "-C", str(ROOT), "merge-base", "--is-ancestor", commit, "HEAD"],
        capture_output=True,
        check=False,
    )
    if git.returncode not in (0, 1):
        pytest.skip("no git history to check the commit against")
    assert git.returncode == 0, f"reports/ names commit {commit}, not in this history: {FIX}"


def test_report_holds_no_absolute_path():
    _readme()
    bad = []
    for path in sorted(REPORTS.rglob("*")):
        if path.suffix not in (".md", ".csv", ".json", ".txt"):
            continue
        for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            if ABSOLUTE.search(line) or str(ROOT) in line:
                bad.append(f"reports/{path.name}:{n}: {line.strip()[:120]}")
    assert not bad, "absolute paths in reports/ (" + FIX + "):\n" + "\n".join(bad[:10])


@pytest.mark.parametrize(
    ("text", "absolute"),
    [
        ("checkpoint: /work/main/checkpoints/tsn_lite0.pt", True),
        ('{"data": "/tmp/x"}', True),
        ("`C:\\Users\\me\\ckpt.pt`", True),
        ("`checkpoints/tsn_lite0.pt` and [rotation.csv](rotation.csv)", False),
        ("1-RMSE 0.93 / 0.95 (-inf,inf) angles [-360,360]", False),
    ],
)
def test_absolute_path_pattern(text, absolute):
    assert bool(ABSOLUTE.search(text)) is absolute
