"""The project's one way to write files: atomically, readable by everyone, all or nothing.

- :func:`atomic_write` writes bytes or text through a temporary file in the same folder
  and a rename, so a reader never sees a half-written file.
- :func:`atomic_target` is the same for libraries that insist on writing to a path
  themselves (trimesh, torch.save, matplotlib): it yields the temporary path and renames
  it into place when the block succeeds.
- :func:`write_together` writes a set of files so that either all of them land or none
  (every file is staged first; only when all were written are they renamed into place,
  and a failure removes what was staged).

Files get mode 0644 (``mkstemp`` makes 0600): outputs are for the user's other tools.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Callable, Iterator, Mapping
from pathlib import Path

__all__ = ["FILE_MODE", "atomic_target", "atomic_write", "write_together"]

FILE_MODE = 0o644

Content = bytes | str | Callable[[Path], object]


def _stage(path: Path) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    return Path(tmp)


def _fill(tmp: Path, content: Content) -> None:
    if isinstance(content, bytes | bytearray | memoryview):
        tmp.write_bytes(bytes(content))
    elif isinstance(content, str):
        tmp.write_text(content, encoding="utf-8")
    else:
        content(tmp)
    os.chmod(tmp, FILE_MODE)


@contextlib.contextmanager
def atomic_target(path: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; on success it replaces ``path``."""
    final = Path(path)
    tmp = _stage(final)
    try:
        yield tmp
        os.chmod(tmp, FILE_MODE)
        os.replace(tmp, final)
    finally:
        tmp.unlink(missing_ok=True)


def atomic_write(path: str | os.PathLike[str], content: Content) -> Path:
    """Write ``content`` (bytes, text, or a function that writes to the path it is given)
    to ``path`` atomically; returns the path."""
    final = Path(path)
    with atomic_target(final) as tmp:
        _fill(tmp, content)
    return final


def write_together(files: Mapping[str | os.PathLike[str], Content]) -> list[Path]:
    """Write every file or none: all are staged beside their targets, then renamed.

    A failure while staging leaves no output (and no stray temporary file); the renames
    themselves are the only window, and they are quick and happen after all the work.
    """
    staged: list[tuple[Path, Path]] = []
    try:
        for path, content in files.items():
            final = Path(path)
            tmp = _stage(final)
            staged.append((tmp, final))
            _fill(tmp, content)
        for tmp, final in staged:
            os.replace(tmp, final)
        return [final for _, final in staged]
    finally:
        for tmp, _ in staged:
            tmp.unlink(missing_ok=True)
