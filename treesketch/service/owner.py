"""One server per data folder: an exclusive lock on ``DATA/server.lock``.

A server takes the lock before it touches its jobs (the start-up recovery marks jobs
left running as failed: done by a second server on a live folder, it would fail the live
server's jobs).  The lock is the kernel's (``flock``): it goes with the process, so a
killed server leaves no stale lock behind.  The file holds the owner's pid, for the
message a second server shows.
"""

from __future__ import annotations

import contextlib
import fcntl
import os
from pathlib import Path
from typing import IO

from .store import StoreError

__all__ = ["LOCK_NAME", "DataFolderBusy", "DataOwner"]

LOCK_NAME = "server.lock"


class DataFolderBusy(StoreError):
    """Another server holds the data folder."""


class DataOwner:
    """``acquire()`` the data folder (DataFolderBusy when another server has it),
    ``release()`` it; also a context manager."""

    def __init__(self, root: str | Path) -> None:
        self.root = Path(root).expanduser()
        self.path = self.root / LOCK_NAME
        self._file: IO[str] | None = None

    def acquire(self) -> None:
        if self._file is not None:
            return
        try:
            f = open(self.path, "a+", encoding="utf-8")  # noqa: SIM115 - held until release
        except OSError as exc:
            raise StoreError(f"cannot use {self.root} as a data folder: {exc.strerror}") from None
        try:
            fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            f.seek(0)
            pid = f.read().strip() or "unknown"
            f.close()
            raise DataFolderBusy(
                f"the data folder {self.root} is in use by another treesketch server "
                f"(pid {pid}); stop that one first, or give this one another --data"
            ) from None
        f.seek(0)
        f.truncate()
        f.write(f"{os.getpid()}\n")
        f.flush()
        self._file = f

    def release(self) -> None:
        if self._file is None:
            return
        with contextlib.suppress(OSError):
            fcntl.flock(self._file, fcntl.LOCK_UN)
        self._file.close()
        self._file = None

    def __enter__(self) -> DataOwner:
        self.acquire()
        return self

    def __exit__(self, *exc: object) -> None:
        self.release()

    def probe(self) -> None:
        """Raise DataFolderBusy if another server holds the folder (taking and giving back
        the lock); nothing to do for a folder that does not exist yet."""
        if self.root.is_dir():
            with self:
                pass
