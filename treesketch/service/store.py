"""The job store: one SQLite database (WAL mode) plus a results folder per job.

A job is one row: its options, its state, its latest progress and, when done, its
summary (species, scores, parameters, distances, ...).  The artefacts (GLB, JSON,
preset, PNGs) lie in ``results/<id>/``, written atomically by the worker that made them
(by the front for a Ray actor's job); the uploaded sketch lies in ``uploads/<id>.img`` and
a job of several drawings keeps the others beside it (``uploads/<id>.view2.img``, ...;
:func:`upload_name`): all are written before the job's row, together or not at all, and
removed with the first.

States: ``queued`` -> ``running`` -> ``done`` | ``failed`` | ``cancelled``; a finished
job whose artefacts were removed by the retention limits becomes ``expired`` (the API
answers 410 for its artefacts).  A running job whose Ray actor was lost goes back to
``queued`` once (``requeue``).

Faults are said plainly, as :class:`StoreError`: a data folder that cannot be one, a job
database that is not one (corrupt), a database deleted or replaced while the server runs
(``check()``), and a full disk (:class:`StorageFull`; the upload is removed again).  The
retention sweep also counts and removes, by the same limits, what no job refers to
(results and uploads left by a deleted database), and removes empty result folders;
only once they are ``ORPHAN_GRACE_S`` old.

Each thread keeps its own connection, so the store may be used from any thread and from
several processes; WAL lets readers (status pages) go on while a writer commits.
"""

from __future__ import annotations

import contextlib
import errno
import json
import os
import re
import shutil
import sqlite3
import threading
import time
import uuid
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from weberpenn.fileio import write_together

__all__ = [
    "FINISHED",
    "ORPHAN_GRACE_S",
    "STATES",
    "Job",
    "JobStore",
    "StorageFull",
    "StoreError",
    "is_full",
    "upload_name",
]

STATES = ("queued", "running", "done", "failed", "cancelled", "expired")
FINISHED = ("done", "failed", "cancelled", "expired")
# an upload is written before its row: anything younger than this may be a job being made
ORPHAN_GRACE_S = 600.0
_FULL_ERRNOS = (errno.ENOSPC, errno.EDQUOT)
_JOB_ID = re.compile(r"[0-9a-f]{32}")  # uuid4().hex
_UPLOAD = re.compile(r"([0-9a-f]{32})(?:\.view[0-9]{1,2})?\.img")  # upload_name's names


def upload_name(job_id: str, view: int = 1) -> str:
    """The file name of a job's drawing ``view`` (1: the first, the only one of most
    jobs) in the uploads folder."""
    return f"{job_id}.img" if view == 1 else f"{job_id}.view{view}.img"


class StoreError(RuntimeError):
    """The data folder or its job database cannot be used; the message says why and what
    to do."""


class StorageFull(StoreError):
    """The disk (or quota) holding the data folder is full."""


def _remove(paths: list[Path]) -> None:
    for p in paths:
        if p.is_dir():
            shutil.rmtree(p, ignore_errors=True)
        else:
            p.unlink(missing_ok=True)


def is_full(exc: BaseException) -> bool:
    """True for an error that means "no space left" (an OSError or SQLite's own)."""
    if isinstance(exc, OSError):
        return exc.errno in _FULL_ERRNOS
    return isinstance(exc, sqlite3.OperationalError) and "full" in str(exc).lower()


_SCHEMA = """
CREATE TABLE IF NOT EXISTS jobs (
    id TEXT PRIMARY KEY,
    seq INTEGER NOT NULL,
    state TEXT NOT NULL,
    created REAL NOT NULL,
    started REAL,
    finished REAL,
    options TEXT NOT NULL,
    progress TEXT,
    summary TEXT,
    error TEXT,
    bytes INTEGER NOT NULL DEFAULT 0
);
CREATE INDEX IF NOT EXISTS jobs_state_seq ON jobs (state, seq);
CREATE INDEX IF NOT EXISTS jobs_created ON jobs (created);
"""


@dataclass(frozen=True)
class Job:
    """One row of the store, as plain data."""

    id: str
    state: str
    created: float
    started: float | None
    finished: float | None
    options: dict[str, Any]
    progress: dict[str, Any] | None
    summary: dict[str, Any] | None
    error: str | None
    bytes: int

    @property
    def is_finished(self) -> bool:
        return self.state in FINISHED


def _job(row: sqlite3.Row) -> Job:
    def load(text: str | None) -> Any:
        return None if text is None else json.loads(text)

    return Job(
        id=row["id"],
        state=row["state"],
        created=row["created"],
        started=row["started"],
        finished=row["finished"],
        options=load(row["options"]),
        progress=load(row["progress"]),
        summary=load(row["summary"]),
        error=row["error"],
        bytes=int(row["bytes"]),
    )


class JobStore:
    """Jobs in ``root/jobs.sqlite``, uploads in ``root/uploads``, results in ``root/results``."""

    def __init__(self, root: str | Path) -> None:
        self.root = Path(root).expanduser()
        self.uploads = self.root / "uploads"
        self.results = self.root / "results"
        for d in (self.root, self.uploads, self.results):
            try:
                d.mkdir(parents=True, exist_ok=True)
            except FileExistsError:
                raise StoreError(f"cannot use {d} as a data folder: it is a file") from None
            except OSError as exc:
                raise StoreError(f"cannot use {d} as a data folder: {exc.strerror}") from None
        if not os.access(self.root, os.W_OK | os.X_OK):
            raise StoreError(f"cannot use {self.root} as a data folder: it is not writable")
        self.path = self.root / "jobs.sqlite"
        self._local = threading.local()
        self._full_at: int | None = None  # free bytes when a write last found the disk full
        try:
            with self._db() as db:
                db.execute("PRAGMA journal_mode=WAL")
                db.executescript(_SCHEMA)
                db.execute("SELECT id, seq, state, options, bytes FROM jobs LIMIT 1").fetchall()
        except sqlite3.DatabaseError as exc:
            raise StoreError(
                f"the job database {self.path} cannot be read ({exc}); move it aside to start "
                "with an empty one (the results no job refers to are then removed by the "
                "retention sweep)"
            ) from None
        self._identity = self._stat()

    def mark_full(self) -> None:
        """A write found the disk full: ``full`` holds until space is freed or a job is
        saved."""
        self._full_at = shutil.disk_usage(self.root).free

    @property
    def full(self) -> bool:
        """A write found the disk full, and no space was freed since."""
        return self._full_at is not None and shutil.disk_usage(self.root).free <= self._full_at

    def _stat(self) -> tuple[int, int] | None:
        try:
            st = self.path.stat()
        except OSError:
            return None
        return st.st_dev, st.st_ino

    def check(self) -> str | None:
        """None while the database this store opened is still at its path; otherwise what
        happened (deleted or replaced under the running server: what is written now would
        be lost at the next start)."""
        now = self._stat()
        if now == self._identity:
            return None
        what = "deleted" if now is None else "replaced"
        return (
            f"the job database {self.path} was {what} while the server ran; new jobs are "
            "refused (they would be lost): restart the server"
        )

    @contextmanager
    def _db(self) -> Iterator[sqlite3.Connection]:
        """This thread's connection (opened once per thread and process: a status poll
        then costs a query, not a connect)."""
        db = getattr(self._local, "db", None)
        if db is None or self._local.pid != os.getpid():
            db = sqlite3.connect(self.path, timeout=30.0, isolation_level=None)
            db.row_factory = sqlite3.Row
            db.execute("PRAGMA synchronous=NORMAL")
            self._local.db, self._local.pid = db, os.getpid()
        try:
            yield db
        except BaseException:
            if db.in_transaction:
                db.execute("ROLLBACK")
            raise

    # -- paths -------------------------------------------------------------------------
    def upload_path(self, job_id: str, view: int = 1) -> Path:
        return self.uploads / upload_name(job_id, view)

    def read_uploads(self, job_id: str, views: int) -> list[bytes]:
        """The job's ``views`` drawings, in order (OSError when one is gone)."""
        return [self.upload_path(job_id, v).read_bytes() for v in range(1, views + 1)]

    def _remove_uploads(self, job_id: str) -> None:
        """The job's drawings, every view's (a job id is hex: no glob pattern in it)."""
        for path in [self.upload_path(job_id), *self.uploads.glob(f"{job_id}.view*.img")]:
            path.unlink(missing_ok=True)

    def result_dir(self, job_id: str) -> Path:
        return self.results / job_id

    # -- writing -----------------------------------------------------------------------
    def create(
        self, sketch_png: bytes | Sequence[bytes], options: dict[str, Any], max_queued: int
    ) -> Job | None:
        """Queue a job (its drawing, or its drawings in order, saved first); None when
        ``max_queued`` jobs already wait.  Raises StorageFull (leaving nothing behind) when
        the disk is full."""
        job_id = uuid.uuid4().hex
        drawings = [sketch_png] if isinstance(sketch_png, bytes | bytearray) else list(sketch_png)
        size = sum(len(d) for d in drawings)
        try:
            write_together({self.upload_path(job_id, v): d for v, d in enumerate(drawings, 1)})
            now = time.time()
            with self._db() as db:
                db.execute("BEGIN IMMEDIATE")
                (queued,) = db.execute("SELECT COUNT(*) FROM jobs WHERE state='queued'").fetchone()
                if queued >= max_queued:
                    db.execute("ROLLBACK")
                    self._remove_uploads(job_id)
                    return None
                (seq,) = db.execute("SELECT COALESCE(MAX(seq), 0) + 1 FROM jobs").fetchone()
                db.execute(
                    "INSERT INTO jobs (id, seq, state, created, options, bytes) "
                    "VALUES (?,?,?,?,?,?)",
                    (job_id, seq, "queued", now, json.dumps(options), size),
                )
                db.execute("COMMIT")
        except (OSError, sqlite3.OperationalError) as exc:
            if not is_full(exc):
                raise
            self._remove_uploads(job_id)
            self.mark_full()
            raise StorageFull(
                f"storage full: the data folder {self.root} has no space left"
            ) from exc
        self._full_at = None
        job = self.get(job_id)
        assert job is not None
        return job

    def claim_next(self) -> Job | None:
        """The oldest queued job, now marked running; None when nothing waits."""
        with self._db() as db:
            db.execute("BEGIN IMMEDIATE")
            row = db.execute(
                "SELECT id FROM jobs WHERE state='queued' ORDER BY seq LIMIT 1"
            ).fetchone()
            if row is None:
                db.execute("ROLLBACK")
                return None
            db.execute(
                "UPDATE jobs SET state='running', started=? WHERE id=?", (time.time(), row["id"])
            )
            db.execute("COMMIT")
        return self.get(row["id"])

    def set_progress(self, job_id: str, progress: dict[str, Any]) -> None:
        with self._db() as db:
            db.execute(
                "UPDATE jobs SET progress=? WHERE id=? AND state='running'",
                (json.dumps(progress), job_id),
            )

    def finish(self, job_id: str, summary: dict[str, Any]) -> None:
        size = sum(p.stat().st_size for p in self.result_dir(job_id).glob("*") if p.is_file())
        with self._db() as db:
            db.execute(
                "UPDATE jobs SET state='done', finished=?, summary=?, bytes=bytes+? "
                "WHERE id=? AND state='running'",
                (time.time(), json.dumps(summary), size, job_id),
            )
        self._full_at = None  # a result was saved: there is room again

    def fail(
        self, job_id: str, message: str, state: str = "failed", input_error: bool = False
    ) -> bool:
        """Mark a queued or running job failed (or cancelled); False if it had finished.
        ``input_error``: the sketch or an option was at fault, not the program."""
        with self._db() as db:
            cur = db.execute(
                "UPDATE jobs SET state=?, finished=?, error=?, summary=? "
                "WHERE id=? AND state IN ('queued', 'running')",
                (state, time.time(), message, json.dumps({"input_error": input_error}), job_id),
            )
            return cur.rowcount > 0

    def requeue(self, job_id: str) -> bool:
        """Put a running job back at the head of the queue (its worker was lost); False if
        it is not running.  It keeps its place: no job queued after it runs first."""
        with self._db() as db:
            cur = db.execute(
                "UPDATE jobs SET state='queued', started=NULL, progress=NULL "
                "WHERE id=? AND state='running'",
                (job_id,),
            )
            return cur.rowcount > 0

    def cancel_queued(self, job_id: str) -> bool:
        """Cancel a job that has not started; False if it is not waiting."""
        with self._db() as db:
            cur = db.execute(
                "UPDATE jobs SET state='cancelled', finished=?, error=? "
                "WHERE id=? AND state='queued'",
                (time.time(), "cancelled before it started", job_id),
            )
            return cur.rowcount > 0

    def recover(self) -> list[str]:
        """At start-up: jobs left running by a stopped server are failed (their worker is
        gone and a re-run could take as long again); queued jobs stay queued.  Returns the
        failed ids."""
        with self._db() as db:
            ids = [r["id"] for r in db.execute("SELECT id FROM jobs WHERE state='running'")]
        for job_id in ids:
            self.fail(job_id, "the server stopped while this job was running; submit it again")
        return ids

    def expire(self, max_age_s: float | None, max_bytes: int | None) -> list[str]:
        """Remove the artefacts of finished jobs older than ``max_age_s`` and, oldest
        first, of as many more as needed to keep the total under ``max_bytes``.  Files no
        job refers to (left by a deleted database) count too, and go first: by their age
        (last change), and before any job's when the total is over.  Empty result folders
        of jobs that are not done are removed.  Returns the ids whose files were removed."""
        now = time.time()
        with self._db() as db:
            rows = db.execute(
                "SELECT id, created, bytes FROM jobs "
                "WHERE state IN ('done', 'failed', 'cancelled') ORDER BY seq"
            ).fetchall()
            (total,) = db.execute("SELECT COALESCE(SUM(bytes), 0) FROM jobs").fetchone()
        orphans = self._orphans(now)
        total += sum(size for _, size, _ in orphans.values())
        gone: list[str] = []
        for job_id, (changed, size, paths) in sorted(orphans.items(), key=lambda o: o[1][0]):
            too_old = max_age_s is not None and now - changed > max_age_s
            too_big = max_bytes is not None and total > max_bytes
            if too_old or too_big:
                _remove(paths)
                total -= size
                gone.append(job_id)
        expired: list[str] = []
        for row in rows:
            too_old = max_age_s is not None and now - row["created"] > max_age_s
            too_big = max_bytes is not None and total > max_bytes
            if not (too_old or too_big):
                continue
            total -= row["bytes"]
            expired.append(row["id"])
        for job_id in expired:
            shutil.rmtree(self.result_dir(job_id), ignore_errors=True)
            self._remove_uploads(job_id)
            with self._db() as db:
                db.execute("UPDATE jobs SET state='expired', bytes=0 WHERE id=?", (job_id,))
        self._remove_empty_results(now)
        return expired + gone

    def _entries(self, now: float) -> dict[str, list[Path]]:
        """The store's files (result folders, uploads) by job id, those older than
        ORPHAN_GRACE_S only: a younger one may be a job being made or saved."""
        found: dict[str, list[Path]] = {}
        for path in [*self.results.iterdir(), *self.uploads.glob("*.img")]:
            # never anything the store did not make
            if path.parent == self.results:
                if not _JOB_ID.fullmatch(path.name):
                    continue
                job_id = path.name
            else:
                upload = _UPLOAD.fullmatch(path.name)
                if upload is None:
                    continue
                job_id = upload.group(1)
            try:
                if now - path.stat().st_mtime < ORPHAN_GRACE_S:
                    continue
            except OSError:
                continue
            found.setdefault(job_id, []).append(path)
        return found

    def _known(self, ids: list[str]) -> dict[str, str]:
        """State by id, of those of ``ids`` the database knows."""
        out: dict[str, str] = {}
        for i in range(0, len(ids), 500):
            batch = ids[i : i + 500]
            with self._db() as db:
                rows = db.execute(
                    f"SELECT id, state FROM jobs WHERE id IN ({','.join('?' * len(batch))})",
                    batch,
                ).fetchall()
            out.update({r["id"]: r["state"] for r in rows})
        return out

    def _orphans(self, now: float) -> dict[str, tuple[float, int, list[Path]]]:
        """Files no job refers to: id -> (last change, bytes, paths)."""
        found = self._entries(now)
        known = self._known(list(found))
        out: dict[str, tuple[float, int, list[Path]]] = {}
        for job_id, paths in found.items():
            if job_id in known:
                continue
            files = [f for p in paths for f in ([p] if p.is_file() else p.rglob("*"))]
            stats = [f.stat() for f in files if f.is_file()]
            changed = max([p.stat().st_mtime for p in paths] + [st.st_mtime for st in stats])
            out[job_id] = (changed, sum(st.st_size for st in stats), paths)
        return out

    def _remove_empty_results(self, now: float) -> None:
        """Result folders left empty (a write that failed) by jobs that are not done."""
        found = {
            job_id: [p for p in paths if p.is_dir()] for job_id, paths in self._entries(now).items()
        }
        known = self._known([j for j, dirs in found.items() if dirs])
        for job_id, state in known.items():
            for folder in found[job_id]:
                if state != "done" and not any(folder.iterdir()):
                    with contextlib.suppress(OSError):  # a file came in meanwhile
                        folder.rmdir()

    # -- reading -----------------------------------------------------------------------
    def get(self, job_id: str) -> Job | None:
        with self._db() as db:
            row = db.execute("SELECT * FROM jobs WHERE id=?", (job_id,)).fetchone()
        return None if row is None else _job(row)

    def position(self, job_id: str) -> int | None:
        """How many queued jobs are ahead of this one (0: next); None if not queued."""
        with self._db() as db:
            row = db.execute(
                "SELECT (SELECT COUNT(*) FROM jobs q WHERE q.state='queued' AND q.seq < j.seq) "
                "AS ahead FROM jobs j WHERE j.id=? AND j.state='queued'",
                (job_id,),
            ).fetchone()
        return None if row is None else int(row["ahead"])

    def recent(self, limit: int) -> list[Job]:
        with self._db() as db:
            rows = db.execute("SELECT * FROM jobs ORDER BY seq DESC LIMIT ?", (limit,)).fetchall()
        return [_job(r) for r in rows]

    def counts(self) -> dict[str, int]:
        with self._db() as db:
            rows = db.execute("SELECT state, COUNT(*) AS n FROM jobs GROUP BY state").fetchall()
        out = dict.fromkeys(STATES, 0)
        out.update({r["state"]: int(r["n"]) for r in rows})
        return out
