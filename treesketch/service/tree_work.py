"""How ``POST /trees`` spends the server's time and memory (issue 49): two gates, a
child process with a time limit for expensive trees, and big replies streamed from disk.

- **Two gates.**  A cheap tree (a slider edit, a candidate's thumbnail; ``outline.png``
  too) goes through the edit gate (:data:`EDITS_AT_ONCE` at once, grown in the front's
  thread pool: a fraction of a second); an expensive one (by
  ``treesketch.trees.estimated_faces``, before any growing) through its own gate
  (:data:`BIG_AT_ONCE` at once).  So an edit never waits behind a big tree.  Each gate
  holds a bounded line of waiting requests; past it, ``503`` with ``Retry-After`` at
  once, before any work.
- **A child process with a time limit.**  An expensive tree is grown in a spawned
  process that is killed after :data:`BIG_SECONDS` (``503``): a thread cannot be
  stopped, and the memory a big tree took (up to about 1 GB) goes back to the system
  with the process instead of staying in the server's heap.
- **Big replies from disk.**  A GLB of more than :data:`MEMORY_REPLY_BYTES` is written to
  the data folder, opened, unlinked and streamed from the open file: a client that does
  not read its reply holds a file handle, not the reply's bytes.  A reply holds at most
  ``treesketch.trees.REPLY_FACES`` triangles (``413`` past it, before exporting).
"""

from __future__ import annotations

import asyncio
import contextlib
import multiprocessing as mp
import os
import time
import uuid
from collections.abc import AsyncIterator, Callable, Iterator
from pathlib import Path
from typing import Any, BinaryIO

from fastapi import HTTPException
from fastapi.responses import Response, StreamingResponse

__all__ = [
    "BIG_AT_ONCE",
    "BIG_SECONDS",
    "BIG_WAITING",
    "CHEAP_FACES",
    "EDITS_AT_ONCE",
    "EDITS_WAITING",
    "MEMORY_REPLY_BYTES",
    "Gate",
    "TreeTimeout",
    "grow_in_child",
    "is_expensive",
    "stream_file",
    "write_reply",
]

EDITS_AT_ONCE = 2  # cheap trees (and outlines) grown together in the thread pool
EDITS_WAITING = 32  # cheap ones waiting in line (each holds at most a 256 KB body)
BIG_AT_ONCE = 1  # expensive trees grown together (each in its own process)
BIG_WAITING = 2  # expensive ones waiting in line
BIG_SECONDS = 20.0  # an expensive tree's time limit, its process's start (about 2 s) included
# estimated triangles (``estimated_faces``, 2-10 times the real count; a full-detail GLB
# counts four times: its export costs more than the growing) above which a tree is
# expensive.  Every species' tree and its edits are below (the largest, a fir with height,
# branch count and leaf density past its limits: 13.8 M estimated, 0.6 M real, 1 s); the
# issue's trees are far above (a 4-level tree of 38^3 branches: 97 M, 20 s of growing; a
# palm of 500 thick branches at full detail: 22 M, a 110 MB GLB)
CHEAP_FACES = 16_000_000
FULL_DETAIL_FACTOR = 4.0
MEMORY_REPLY_BYTES = 4 * 2**20  # a GLB bigger than this is streamed from disk
RETRY_AFTER = 5  # seconds, with a 503 of a full line
CHUNK = 2**20
STALE_SECONDS = 600.0
CHILD_NICENESS = 10  # added to the tree process's niceness  # a reply file left behind (a crash) is removed after this


class TreeTimeout(Exception):
    """The tree's process ran past its time limit and was killed."""


class Gate:
    """At most ``slots`` requests at once and ``waiting`` more in line; one more is
    refused at once (503, ``Retry-After``) instead of waiting without bound."""

    def __init__(self, slots: int, waiting: int, what: str) -> None:
        self._slots = asyncio.Semaphore(slots)
        self._limit = slots + waiting
        self._inside = 0
        self.what = what

    @contextlib.asynccontextmanager
    async def enter(self) -> AsyncIterator[None]:
        if self._inside >= self._limit:
            raise HTTPException(
                503,
                f"too many {self.what} at once ({self._limit} in progress or waiting); "
                f"try again in {RETRY_AFTER} s",
                headers={"Retry-After": str(RETRY_AFTER)},
            )
        self._inside += 1
        try:
            async with self._slots:
                yield
        finally:
            self._inside -= 1


def is_expensive(body: Any) -> bool:
    """Whether a ``POST /trees`` body asks for an expensive tree (module text); ValueError
    for a bad body (checked here, before any gate)."""
    from treesketch.trees import VIEW_FACES, TreeRequest, estimated_faces

    request = TreeRequest.from_json(body)
    full = request.max_faces is None or request.max_faces > VIEW_FACES
    return estimated_faces(request) * (FULL_DETAIL_FACTOR if full else 1.0) > CHEAP_FACES


def _reply_path(folder: Path) -> Path:
    """A new reply file's name in ``folder`` (made if need be); files left there by a
    crash are removed first."""
    folder.mkdir(parents=True, exist_ok=True)
    now = time.time()
    for old in folder.glob("*.glb"):
        with contextlib.suppress(OSError):
            if now - old.stat().st_mtime > STALE_SECONDS:
                old.unlink()
    return folder / f"{uuid.uuid4().hex}.glb"


def write_reply(data: bytes, folder: Path) -> Path:
    """``data`` written to a new reply file in ``folder``; OSError (a full disk) leaves no
    file behind."""
    path = _reply_path(folder)
    try:
        path.write_bytes(data)
    except OSError:
        path.unlink(missing_ok=True)
        raise
    return path


def _chunks(handle: BinaryIO) -> Iterator[bytes]:
    try:
        while chunk := handle.read(CHUNK):
            yield chunk
    finally:
        handle.close()


def stream_file(path: Path, media_type: str, headers: dict[str, str]) -> Response:
    """A response streaming ``path``, which is unlinked at once (the open handle keeps it
    readable; nothing is left on disk whatever the client does)."""
    handle = path.open("rb")
    try:
        size = os.fstat(handle.fileno()).st_size
    finally:
        path.unlink(missing_ok=True)
    return StreamingResponse(
        _chunks(handle),
        media_type=media_type,
        headers={**headers, "Content-Length": str(size)},
    )


def _child(
    grow: Callable[[Any, bool], tuple[Any, dict[str, str]]],
    body: Any,
    want_glb: bool,
    path: str,
    conn: Any,
) -> None:
    """In the child: grow, write a GLB to ``path``, send ``(kind, answer, facts)``."""
    from treesketch.trees import TreeTooBig

    # below the server and its edits: a big tree takes the CPU an edit leaves over
    with contextlib.suppress(OSError):
        os.nice(CHILD_NICENESS)
    try:
        answer, facts = grow(body, want_glb)
        if isinstance(answer, bytes):
            Path(path).write_bytes(answer)
            answer = None
        conn.send(("ok", answer, facts))
    except TreeTooBig as exc:
        conn.send(("too big", str(exc), {}))
    except ValueError as exc:  # ParamError and bad controls: the request's fault
        conn.send(("refused", str(exc), {}))
    except (MemoryError, OSError) as exc:
        conn.send(("failed", f"{type(exc).__name__}: {exc}", {}))
    finally:
        conn.close()


def grow_in_child(
    grow: Callable[[Any, bool], tuple[Any, dict[str, str]]],
    body: Any,
    want_glb: bool,
    folder: Path,
    seconds: float = BIG_SECONDS,
) -> tuple[Path | dict[str, Any], dict[str, str]]:
    """``grow(body, want_glb)`` in a spawned process killed after ``seconds``: (the GLB's
    reply file, or the JSON answer; the facts).  Raises :class:`TreeTimeout`, the
    child's ``TreeTooBig`` or ValueError again, or RuntimeError when it died."""
    from treesketch.trees import TreeTooBig

    ctx = mp.get_context("spawn")
    path = _reply_path(folder)
    receive, send = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=_child, args=(grow, body, want_glb, str(path), send), daemon=True)
    answered = False
    try:
        proc.start()
        send.close()  # the child's end: an EOF when it dies
        if not receive.poll(seconds):
            raise TreeTimeout(f"growing the tree took more than {seconds:g} s")
        try:
            kind, answer, facts = receive.recv()
        except EOFError:
            raise RuntimeError("the tree's process ended without an answer") from None
        answered = True
    finally:
        send.close()  # (again, if the start failed: closing twice is harmless)
        receive.close()
        if proc.is_alive():
            proc.kill()
        proc.join()
        if not answered:  # after the kill: the child writes nothing more
            path.unlink(missing_ok=True)
    if kind == "ok":
        return (path if answer is None else answer), facts
    path.unlink(missing_ok=True)
    if kind == "too big":
        raise TreeTooBig(answer)
    if kind == "refused":
        raise ValueError(answer)
    raise RuntimeError(answer)
