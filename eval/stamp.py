"""The stamp every research output carries: commit, checkpoint sha256, date, machine.

A number without the code, the network, the day and the machine it came from cannot be
checked later; ``reports/`` prints this stamp in its README, in every CSV row and under
every plot, and the test suite compares its sha256 with the shipped checkpoint's so a new
network cannot ship with an old report.  Paths are written relative to the repository
(never this machine's absolute paths).
"""

from __future__ import annotations

import datetime as dt
import hashlib
import os
import platform
import re
import subprocess
from dataclasses import asdict, dataclass
from pathlib import Path

__all__ = ["Stamp", "file_sha256", "make_stamp", "parse_stamp", "portable_path"]

# how the README states it, one line each (parse_stamp reads them back)
_LINE = re.compile(
    r"^- \*\*(commit|checkpoint|checkpoint sha256|date|machine)\*\*: `([^`]*)`$", re.M
)


@dataclass(frozen=True)
class Stamp:
    commit: str  # 40 hex digits, "+dirty" when tracked files differ from it
    checkpoint: str  # relative to the repository when inside it, else the file name
    checkpoint_sha256: str
    date: str  # UTC, ISO 8601 to the minute
    machine: str

    def markdown(self) -> str:
        return "\n".join(f"- **{k.replace('_', ' ')}**: `{v}`" for k, v in asdict(self).items())

    def short(self) -> str:
        """One line for a plot's footer."""
        return (
            f"commit {self.commit[:10]} · checkpoint sha256 {self.checkpoint_sha256[:12]} · "
            f"{self.date} · {self.machine}"
        )

    def columns(self) -> dict[str, str]:
        return {"commit": self.commit, "checkpoint_sha256": self.checkpoint_sha256,
                "date": self.date, "machine": self.machine}  # fmt: skip


def file_sha256(path: str | os.PathLike[str]) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def portable_path(path: str | os.PathLike[str], root: Path) -> str:
    """``path`` relative to ``root`` when inside it, else its bare file name."""
    p = Path(path).resolve()
    try:
        return p.relative_to(root.resolve()).as_posix()
    except ValueError:
        return p.name


def _git(root: Path, *args: str) -> str:
    out = subprocess.run(
        ["git", "-C", str(root), *args], capture_output=True, text=True, check=False, timeout=30
    )
    if out.returncode != 0:
        raise RuntimeError(f"git {' '.join(args)} failed in the repository: {out.stderr.strip()}")
    return out.stdout.strip()


def _machine() -> str:
    cpu = platform.processor() or platform.machine()
    try:  # the CPU model is what makes timings comparable; Linux says it here
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    return f"{cpu}, {cores} cores, {platform.system()} {platform.machine()}"


def make_stamp(
    checkpoint: str | os.PathLike[str], root: Path, ignore: tuple[str, ...] = ()
) -> Stamp:
    """The stamp for outputs made now by ``root``'s checkout with ``checkpoint``;
    ``ignore``: repository-relative paths whose changes do not make the commit dirty
    (the report folder being rewritten)."""
    commit = _git(root, "rev-parse", "HEAD")
    excludes = [f":(exclude){p}" for p in ignore]
    if _git(root, "status", "--porcelain", "--untracked-files=no", "--", ".", *excludes):
        commit += "+dirty"
    return Stamp(
        commit=commit,
        checkpoint=portable_path(checkpoint, root),
        checkpoint_sha256=file_sha256(checkpoint),
        date=dt.datetime.now(dt.UTC).strftime("%Y-%m-%d %H:%M UTC"),
        machine=_machine(),
    )


def parse_stamp(markdown: str) -> dict[str, str]:
    """The stamp fields a README states (``Stamp.markdown``'s lines), by field name."""
    return {k.replace(" ", "_"): v for k, v in _LINE.findall(markdown)}
