"""The HTTP front: FastAPI routes over the job store and the worker pool.

Every route is ``async`` and does no pipeline work: database reads and writes are short
and run in the thread pool, refinements run in the worker processes (or Ray actors).  So ``/health`` and
``/jobs/{id}`` answer at once however busy the workers are.
"""

from __future__ import annotations

import asyncio
import json
import logging
import shutil
import time
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from fastapi import FastAPI, HTTPException, Request
from fastapi.responses import FileResponse, JSONResponse, Response, StreamingResponse
from starlette.concurrency import run_in_threadpool

from refine.search import DEFAULT_BUDGET
from treesketch.trees import REPLY_FACES

from .guards import LOOPBACK_HOSTS, AccessGuard, RedactTokens
from .interactive import add_interactive_routes
from .limits import MAX_VIEWS, LimitError, Limits, check_images, parse_options, read_form
from .outlines import add_outlines_route
from .owner import DataOwner
from .pool import WorkerPool, default_workers
from .preview import PREVIEW_FILES
from .ray_pool import RayWorkerPool
from .runner import ARTEFACTS, VIEW_ARTEFACTS, view_artefacts
from .store import Job, JobStore, StorageFull
from .tree_work import BIG_SECONDS

__all__ = ["ServiceConfig", "check_cors", "create_app"]

STATIC = Path(__file__).parent / "static"
EVENT_TICK = 0.25  # seconds between checks in the events stream and /predict


@dataclass(frozen=True)
class ServiceConfig:
    """Everything the service is started with (the CLI's options)."""

    data: Path
    workers: int | None = field(default_factory=default_workers)  # None: all the cluster's CPUs
    estimator: str = "tsn"
    estimators: tuple[str, ...] = ("template",)  # what a job may ask for besides the default
    max_queue: int = 64
    limits: Limits = Limits()
    default_budget: int = DEFAULT_BUDGET
    default_time_limit: float = 50.0
    retention_days: float | None = 30.0
    retention_bytes: int | None = 2 * 1024**3
    token: str | None = None
    cors: tuple[str, ...] = ()
    # the names the server answers to (Host header); "*": any (see guards.AccessGuard)
    hosts: tuple[str, ...] = LOOPBACK_HOSTS
    min_free_bytes: int = 64 * 1024**2  # below this free space, new jobs are refused (507)
    cancel_grace: float = 3.0
    retry_after: int = 10
    vendor: Path | None = None  # node_modules holding three (default: beside the page)
    executor: str = "local"  # local: worker processes here; ray: Ray actors
    address: str | None = None  # ray: an existing cluster; None: a local Ray for the service

    @property
    def allowed_estimators(self) -> tuple[str, ...]:
        return tuple(dict.fromkeys((self.estimator, *self.estimators)))


def _views(job: Job) -> int:
    """How many drawings a job has (its options' yaws are those after the first)."""
    return 1 + len(job.options.get("yaws") or ())


def _links(job: Job) -> dict[str, str]:
    base = f"/jobs/{job.id}"
    links = {"self": base, "events": f"{base}/events"}
    links.update({name: f"{base}/{name}" for name in ARTEFACTS})
    # the drawing's outline over the tree's (outlines.py; ?view=N for a later drawing)
    links["outlines.png"] = f"{base}/outlines.png"
    # a job of several drawings: each later view's sketches
    links.update(
        {name: f"{base}/{name}" for v in range(2, _views(job) + 1) for name in view_artefacts(v)}
    )
    # the current best tree while the job runs (interactive.py)
    links.update({f"preview/{name}": f"{base}/preview/{name}" for name in PREVIEW_FILES})
    return links


def _view(job: Job, position: int | None, live: dict[str, Any] | None) -> dict[str, Any]:
    budget = job.options.get("budget")
    progress = live or job.progress
    if job.state == "queued" or progress is None:
        progress = {"evaluations": 0, "budget": budget, "best_loss": None, "elapsed": 0.0}
    if job.state == "running" and job.started is not None:
        progress = {**progress, "elapsed": time.time() - job.started}
    if job.state == "done" and job.summary:
        progress = {
            "evaluations": job.summary["evaluations"],
            "budget": budget,
            "best_loss": job.summary["losses"]["after"],
            "elapsed": job.summary["timings"].get("job"),
        }
    out: dict[str, Any] = {
        "id": job.id,
        "state": job.state,
        "position": position,
        "created": job.created,
        "started": job.started,
        "finished": job.finished,
        "options": job.options,
        "progress": progress,
        "error": job.error,
        "links": _links(job),
    }
    if job.state == "done":
        out["result"] = job.summary
    return out


def make_pool(config: ServiceConfig, store: JobStore) -> WorkerPool | RayWorkerPool:
    """The worker pool the config asks for (not started)."""
    retention = (
        None if config.retention_days is None else config.retention_days * 86400.0,
        config.retention_bytes,
    )
    if config.executor == "ray":
        return RayWorkerPool(
            store,
            config.workers,
            config.estimator,
            address=config.address,
            cancel_grace=config.cancel_grace,
            retention=retention,
        )
    if config.executor != "local":
        raise ValueError(f"unknown executor {config.executor!r}: choose local or ray")
    if config.address is not None:
        raise ValueError("an address is for the ray executor (executor='ray')")
    return WorkerPool(
        store,
        config.workers or default_workers(),
        config.estimator,
        cancel_grace=config.cancel_grace,
        retention=retention,
    )


def storage_problem(store: JobStore, min_free_bytes: int) -> str | None:
    """Why the data folder cannot take a new job (no space, or its database gone), or
    None."""
    gone = store.check()
    if gone:
        return gone
    free = shutil.disk_usage(store.root).free
    if store.full or free < min_free_bytes:
        return (
            f"storage full: {free / 2**20:.0f} MB free in the data folder {store.root}; "
            f"new jobs need {min_free_bytes / 2**20:.0f} MB (free some space, or lower the "
            "retention limits)"
        )
    return None


def check_cors(cors: tuple[str, ...], token: str | None) -> None:
    """ValueError for a CORS origin of any page (``*``, or ``null``: sandboxed frames and
    local files) without a token: every page a user visits could then read the job list,
    the drawings and the results (issue 49)."""
    wild = [o for o in cors if o.strip().lower() in ("*", "null")]
    if wild and not token:
        raise ValueError(
            f"--cors {wild[0]!r} lets any web page call this server: it needs a token "
            "(--token or TREESKETCH_TOKEN), or name the origins allowed "
            "(--cors https://app.example.org)"
        )


@dataclass(frozen=True)
class JobDesk:
    """What the job routes share: a job by id (404 when none), its view, a submission
    checked and queued."""

    config: ServiceConfig
    store: JobStore
    pool: WorkerPool | RayWorkerPool

    async def get(self, job_id: str) -> Job:
        job = await run_in_threadpool(self.store.get, job_id)
        if job is None:
            raise HTTPException(404, f"no job {job_id!r}")
        return job

    async def view(self, job: Job) -> dict[str, Any]:
        position = (
            await run_in_threadpool(self.store.position, job.id) if job.state == "queued" else None
        )
        return _view(job, position, self.pool.live(job.id) if job.state == "running" else None)

    async def submit(self, request: Request) -> Job:
        if self.pool.broken:
            raise HTTPException(503, f"no worker can start: {self.pool.error}")
        problem = storage_problem(self.store, self.config.min_free_bytes)
        if problem:  # before the body is read
            raise HTTPException(507 if self.store.check() is None else 503, problem)
        refused: LimitError | None = None
        drawings: list[bytearray] = []
        try:
            fields, drawings = await read_form(
                request.headers.get("content-type", ""),
                request.headers.get("content-length"),
                request.stream(),
                self.config.limits,
            )
            if not drawings:
                raise LimitError(422, "no sketch: send the image as a file field named 'sketch'")
            options = parse_options(
                fields,
                self.config.limits,
                self.config.allowed_estimators,
                self.config.estimator,
                self.config.default_budget,
                self.config.default_time_limit,
                views=len(drawings),
            )
            # every drawing, before the job is queued
            await run_in_threadpool(check_images, drawings, self.config.limits)
        except LimitError as exc:
            # a fresh error, raised out here: the caught one's traceback holds the upload's
            # bytes (and a reference cycle may keep it until a full garbage collection)
            refused = LimitError(exc.status, str(exc))
        if refused is not None:
            for data in drawings:  # read_form's own buffers: free them, whoever holds them
                data.clear()
            headers = {"Connection": "close"} if refused.status == 413 else None
            raise HTTPException(refused.status, str(refused), headers=headers)
        try:
            job = await run_in_threadpool(
                self.store.create, drawings, options.to_dict(), self.config.max_queue
            )
        except StorageFull as exc:
            raise HTTPException(507, str(exc)) from exc
        if job is None:
            raise HTTPException(
                503,
                f"the queue is full ({self.config.max_queue} jobs waiting); try again later",
                headers={"Retry-After": str(self.config.retry_after)},
            )
        self.pool.wakeup()
        return job


def create_app(config: ServiceConfig) -> FastAPI:
    """The app; its worker pool starts and stops with the app's lifespan, which first takes
    the data folder (``owner.DataOwner``: a second server on it is refused before it
    touches any job).  Raises ``store.StoreError`` for a data folder or database that
    cannot be used, ValueError for CORS open to any page without a token."""
    check_cors(config.cors, config.token)
    store = JobStore(config.data)
    pool = make_pool(config, store)
    app = FastAPI(
        title="TreeSketch",
        description="A sketch of a tree -> a 3D Weber-Penn tree, as jobs with live progress.",
        lifespan=_lifespan(pool, DataOwner(config.data), RedactTokens()),
    )
    app.state.store, app.state.pool, app.state.config = store, pool, config
    _add_guards(app, config)
    desk = JobDesk(config, store, pool)
    # the interactive routes before the jobs' catch-all /jobs/{id}/{name}
    add_interactive_routes(app, store)
    add_outlines_route(app, store)
    add_page_routes(app, desk)
    add_job_routes(app, desk)
    add_predict_route(app, desk)
    _mount_static(app, config)
    return app


def _lifespan(pool: WorkerPool | RayWorkerPool, owner: DataOwner, redact: RedactTokens) -> Any:
    """The app's lifespan: the data folder taken, the workers started; both given back."""

    @asynccontextmanager
    async def lifespan(app: FastAPI) -> AsyncIterator[None]:
        owner.acquire()  # before the pool's recovery touches a job
        logging.getLogger("uvicorn.access").addFilter(redact)
        try:
            await run_in_threadpool(pool.start)
            try:
                yield
            finally:
                await run_in_threadpool(pool.stop)
        finally:
            logging.getLogger("uvicorn.access").removeFilter(redact)
            owner.release()

    return lifespan


def _add_guards(app: FastAPI, config: ServiceConfig) -> None:
    """Who may ask what (``guards.AccessGuard``), and CORS for the origins given."""
    open_paths = ("/", "/health", "/favicon.ico")

    @app.get("/favicon.ico", include_in_schema=False)
    async def favicon() -> Response:
        return Response(status_code=204)

    app.add_middleware(
        AccessGuard,
        hosts=config.hosts,
        cors=config.cors,
        token=config.token,
        open_paths=open_paths,
        open_prefixes=("/static/", "/vendor/"),
    )

    if config.cors:  # added last: outermost, so a preflight needs no token
        from fastapi.middleware.cors import CORSMiddleware

        app.add_middleware(
            CORSMiddleware,
            allow_origins=list(config.cors),
            allow_methods=["GET", "POST", "DELETE"],
            allow_headers=["Authorization", "Content-Type"],
        )


def add_page_routes(app: FastAPI, desk: JobDesk) -> None:
    """The page, the species it offers, the server's health and status."""

    @app.get("/", include_in_schema=False)
    async def index() -> Response:
        page = STATIC / "index.html"
        if not page.is_file():
            raise HTTPException(404, "the page is not installed")
        return FileResponse(page, media_type="text/html")

    @app.get("/species")
    async def species_list() -> dict[str, Any]:
        """The species a job may be asked for (the page's picker): name and what people
        call it, the paper's five first."""
        from weberpenn import species

        return {
            "species": [
                {"name": s, "display": species.display_name(s), "paper": s in species.PAPER_SPECIES}
                for s in species.SPECIES
            ]
        }

    @app.get("/health")
    async def health() -> dict[str, Any]:
        workers = desk.pool.status()
        problems = [f"no worker can start: {desk.pool.error}"] if desk.pool.broken else []
        storage = storage_problem(desk.store, desk.config.min_free_bytes)
        problems += [storage] if storage else []
        return {
            "status": "error" if problems else "ok",
            "error": "; ".join(problems) or None,
            "estimator": desk.config.estimator,
            "workers": sum(w["alive"] for w in workers),
            "busy": sum(w["job"] is not None for w in workers),
            "storage": {
                "free_bytes": shutil.disk_usage(desk.store.root).free,
                "full": bool(storage) and desk.store.check() is None,
                "database": desk.store.check() or "ok",
            },
        }

    @app.get("/status")
    async def status() -> dict[str, Any]:
        counts = await run_in_threadpool(desk.store.counts)
        return {
            "jobs": counts,
            "queue": {"waiting": counts["queued"], "max": desk.config.max_queue},
            "workers": desk.pool.status(),
            "workers_replaced": desk.pool.replaced,
            "worker_error": desk.pool.error,
            "estimators": list(desk.config.allowed_estimators),
            "limits": {
                "max_upload_bytes": desk.config.limits.max_upload_bytes,
                "max_body_bytes": desk.config.limits.max_body_bytes,
                "max_views": MAX_VIEWS,
                "max_pixels": desk.config.limits.max_pixels,
                "max_budget": desk.config.limits.max_budget,
                "default_budget": desk.config.default_budget,
                # POST /trees (interactive.py, tree_work.py)
                "tree_reply_faces": REPLY_FACES,
                "tree_seconds": BIG_SECONDS,
            },
        }


def add_job_routes(app: FastAPI, desk: JobDesk) -> None:
    """Jobs: submit, list, read, cancel, follow (server-sent events), download."""

    @app.post("/jobs", status_code=202)
    async def create_job(request: Request) -> JSONResponse:
        job = await desk.submit(request)
        body = await desk.view(job)
        return JSONResponse(body, status_code=202, headers={"Location": f"/jobs/{job.id}"})

    @app.get("/jobs")
    async def list_jobs(limit: int = 20) -> dict[str, Any]:
        if not 1 <= limit <= 500:
            raise HTTPException(422, f"limit must be in 1..500, got {limit}")
        jobs = await run_in_threadpool(desk.store.recent, limit)
        return {"jobs": [_view(j, None, None) for j in jobs]}

    @app.get("/jobs/{job_id}")
    async def get_one(job_id: str) -> dict[str, Any]:
        return await desk.view(await desk.get(job_id))

    @app.delete("/jobs/{job_id}")
    async def cancel(job_id: str) -> JSONResponse:
        job = await desk.get(job_id)
        if job.state == "queued" and await run_in_threadpool(desk.store.cancel_queued, job_id):
            return JSONResponse(await desk.view(await desk.get(job_id)))
        if job.state in ("queued", "running") and desk.pool.cancel(job_id):
            body = await desk.view(job)
            body["cancelling"] = True
            return JSONResponse(body, status_code=202)
        job = await desk.get(job_id)
        if job.is_finished:
            raise HTTPException(409, f"job {job_id} is already {job.state}")
        return JSONResponse(await desk.view(job), status_code=202)

    @app.get("/jobs/{job_id}/events")
    async def events(job_id: str, request: Request) -> StreamingResponse:
        await desk.get(job_id)

        async def stream() -> AsyncIterator[bytes]:
            last: str | None = None
            yield b"retry: 1000\n\n"
            while True:
                job = await desk.get(job_id)
                body = await desk.view(job)
                kind = job.state if job.is_finished else "progress"
                text = json.dumps(body)
                if text != last:
                    last = text
                    yield f"event: {kind}\ndata: {text}\n\n".encode()
                if job.is_finished or await request.is_disconnected():
                    return
                await asyncio.sleep(EVENT_TICK)

        return StreamingResponse(
            stream(),
            media_type="text/event-stream",
            headers={"Cache-Control": "no-cache", "X-Accel-Buffering": "no"},
        )

    @app.get("/jobs/{job_id}/{name}")
    async def artefact(job_id: str, name: str) -> Response:
        if name not in ARTEFACTS and name not in VIEW_ARTEFACTS:
            raise HTTPException(404, f"no artefact {name!r}; there are {', '.join(ARTEFACTS)}")
        job = await desk.get(job_id)
        media = ARTEFACTS.get(name) or VIEW_ARTEFACTS[name]
        if name in VIEW_ARTEFACTS and name not in _links(job):
            raise HTTPException(404, f"job {job_id} has {_views(job)} drawing(s): no {name}")
        if job.state == "expired":
            raise HTTPException(410, f"job {job_id} has expired; its files were removed")
        if job.state != "done":
            raise HTTPException(409, f"job {job_id} is {job.state}, not done")
        path = desk.store.result_dir(job_id) / name
        if not path.is_file():
            raise HTTPException(410, f"job {job_id}'s {name} is gone")
        return FileResponse(
            path,
            media_type=media,
            filename=f"{job_id[:8]}_{name}",
            content_disposition_type="attachment" if not name.endswith(".png") else "inline",
        )


def add_predict_route(app: FastAPI, desk: JobDesk) -> None:
    """``POST /predict``: a job submitted and waited for in one request."""

    @app.post("/predict")
    async def predict(request: Request) -> dict[str, Any]:
        """Submit and wait: the job's result, or its error.  If the client goes away the
        job is cancelled."""
        job = await desk.submit(request)
        t0 = time.monotonic()
        while True:
            await asyncio.sleep(EVENT_TICK)
            if await request.is_disconnected():
                if not await run_in_threadpool(desk.store.cancel_queued, job.id):
                    desk.pool.cancel(job.id)
                raise HTTPException(499, "client disconnected")
            job = await desk.get(job.id)
            if job.is_finished:
                break
        if job.state == "done":
            assert job.summary is not None
            return {
                "id": job.id,
                **job.summary,
                "glb": f"/jobs/{job.id}/tree.glb",
                "links": _links(job),
                "seconds": time.monotonic() - t0,
            }
        input_error = bool(job.summary and job.summary.get("input_error"))
        status = 422 if input_error else 500 if job.state == "failed" else 409
        raise HTTPException(status, job.error or f"job {job.state}")


def _mount_static(app: FastAPI, config: ServiceConfig) -> None:
    """The page's files and three.js from npm (served here: the page works offline)."""
    if STATIC.is_dir():
        from fastapi.staticfiles import StaticFiles

        app.mount("/static", StaticFiles(directory=STATIC), name="static")
        vendor = config.vendor or STATIC / "node_modules"
        if (vendor / "three").is_dir():
            app.mount("/vendor/three", StaticFiles(directory=vendor / "three"), name="three")
