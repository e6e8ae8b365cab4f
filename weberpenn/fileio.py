"""The project's one way to write files: atomically, readable by everyone, all or nothing.

- :func:`atomic_write` writes bytes or text through a temporary file in the same folder
  and a rename, so a reader never sees a half-written file.
- :func:`atomic_target` is the same for libraries that insist on writing to a path
  themselves (trimesh, torch.save, matplotlib): it yields the temporary path and renames
  it into place when the block succeeds.
- :func:`write_together` writes a set of files so that either all of them land or none
  (every file is staged first; only when all were written are they renamed into place,
  and a failure removes what was staged).
- :func:`check_targets` checks, before any work, that a command's outputs can be written:
  no output is a folder or a device, no two outputs are one file, and each folder exists
  (or can be made) and takes a new file.  A command calls it first, so a typo costs no
  minutes of refinement.

Files get mode 0644 (``mkstemp`` makes 0600): outputs are for the user's other tools.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Callable, Iterable, Iterator, Mapping
from pathlib import Path

__all__ = [
    "FILE_MODE",
    "OutputError",
    "atomic_target",
    "atomic_write",
    "check_targets",
    "write_together",
]

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


class OutputError(ValueError):
    """An output cannot be written where it was asked for; the message names it."""


def _folder_takes_files(folder: Path) -> str | None:
    """Why no file can be made in ``folder`` (made first if missing), or None.  Probed by
    making (and removing) an empty temporary file in the deepest folder that exists:
    permission bits say nothing of read-only mounts, ACLs or root."""
    probe = folder
    while not probe.exists():
        if probe.parent == probe:
            return f"{folder} cannot be made"
        probe = probe.parent
    if not probe.is_dir():
        return f"{probe} is a file, not a folder"
    try:
        fd, tmp = tempfile.mkstemp(prefix=".treesketch-probe.", dir=probe)
    except OSError as exc:
        return f"cannot write in {probe} ({exc.strerror or exc})"
    os.close(fd)
    os.unlink(tmp)
    return None


def check_targets(targets: Mapping[str, Iterable[str | os.PathLike[str]]]) -> None:
    """Check that every output can be written, before any work; raise :class:`OutputError`.

    ``targets`` maps a name for each output (a CLI option such as ``--params``) to the
    files it writes (an OBJ writes its ``.mtl`` and textures too).  Refused: a file that
    is a folder or anything but a regular file, one file named by two outputs (or twice
    by one), and a folder that cannot take a new file (missing folders are made when the
    outputs are written, so the deepest existing one must take one)."""
    owner: dict[Path, str] = {}
    folders: dict[Path, str] = {}
    for name, paths in targets.items():
        for p in paths:
            path = Path(p)
            if path.is_dir():
                raise OutputError(f"{name} {path} is a folder; give a file name")
            if path.exists() and not path.is_file():
                raise OutputError(f"{name} {path} is not a regular file; give a file name")
            key = path.resolve()
            if key in owner:
                first = owner[key]
                who = f"{first} and {name} both write" if first != name else f"{name} writes"
                raise OutputError(f"{who} {path}; give each output its own file")
            owner[key] = name
            folders.setdefault(key.parent, name)
    for folder, name in folders.items():
        why = _folder_takes_files(folder)
        if why is not None:
            raise OutputError(f"{name}: {why}")
