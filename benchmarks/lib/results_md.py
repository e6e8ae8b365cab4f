"""Replace one section of ``benchmarks/RESULTS.md`` in place (the benchmarks' ``--write``),
and name the machine a section was measured on."""

from __future__ import annotations

import platform
import re
from pathlib import Path

from weberpenn.fileio import atomic_write

RESULTS = Path(__file__).resolve().parents[1] / "RESULTS.md"


def write_section(text: str, results: Path = RESULTS) -> None:
    """Put ``text`` (its first line a heading, ``## Title``) in place of the section of
    that title, at whatever level it stands in ``results`` (a ``##`` subject of its own or a
    ``###`` section under one; ``text``'s headings move to that level), up to the next
    heading of the same or a higher level; with no such section, append ``text`` at the
    end.  Written atomically; says so on stdout."""
    head, _, body = text.partition("\n")
    m = re.match(r"(#+) (.+)", head)
    if m is None:
        raise ValueError(f"a section starts with a heading, got {head!r}")
    title = m.group(2).strip()
    old = results.read_text() if results.is_file() else "# Benchmark results\n"
    found = re.search(rf"^(#+) {re.escape(title)}[ \t]*$", old, re.M)
    if found is None:
        atomic_write(results, old.rstrip("\n") + "\n\n" + text.rstrip("\n") + "\n")
        print(f"added {title!r} to {results}")
        return
    level = len(found.group(1))
    shift = level - len(m.group(1))
    section = "#" * level + " " + title + "\n" + body
    if shift:
        section = re.sub(
            r"^(#+) ", lambda h: "#" * (len(h.group(1)) + shift) + " ", section, flags=re.M
        )
    end = re.compile(rf"^#{{1,{level}}} ", re.M).search(old, found.end())
    rest = "" if end is None else "\n" + old[end.start() :]
    atomic_write(results, old[: found.start()] + section.rstrip("\n") + "\n" + rest)
    print(f"updated {title!r} in {results}")


def cpu_name() -> str:
    """The CPU's model name (``/proc/cpuinfo``), else what ``platform`` knows."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()
