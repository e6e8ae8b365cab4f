"""``GET /jobs/{id}/outlines.png?view=N``: a finished job's drawing's outline (red) over its
tree's (blue), seen from the side that drawing was made from (``N``: 1-based, default 1):
``treesketch.outputs.outlines_images``, what the CLI's ``--compare`` and ``--outlines``
pictures show, as the page and the Blender add-on show it.

The picture is made by the worker when the job finishes (``runner.Runner.run``: the
prepared drawing is at hand there, the job keeps only the upload) and read here.  It is of
the job's returned tree: an edit on the page (``POST /trees``) grows a tree that belongs
to no job and carries no sketch at the drawn view, so an edited tree's outline is not
shown; the picture stays the job's refined result's.

404 with a message for an unknown job, a job not done, a view out of range or a picture
the job does not have (it finished before they were made); 410 once the job's files
expired.  Behind the same guards as every job route (``guards.AccessGuard`` wraps the
whole app).
"""

from __future__ import annotations

from fastapi import FastAPI, HTTPException
from fastapi.responses import Response
from starlette.concurrency import run_in_threadpool

from .runner import outlines_file
from .store import JobStore

__all__ = ["add_outlines_route"]


def add_outlines_route(app: FastAPI, store: JobStore) -> None:
    """Add ``GET /jobs/{id}/outlines.png`` to ``app``; before the job routes' catch-all
    ``/jobs/{id}/{name}``, which would take the name."""

    @app.get("/jobs/{job_id}/outlines.png")
    async def outlines(job_id: str, view: str = "1") -> Response:
        job = await run_in_threadpool(store.get, job_id)
        if job is None:
            raise HTTPException(404, f"no job {job_id!r}")
        if job.state == "expired":
            raise HTTPException(410, f"job {job_id} has expired; its files were removed")
        if job.state != "done":
            raise HTTPException(404, f"job {job_id} is {job.state}: no tree to lay its outline on")
        views = 1 + len(job.options.get("yaws") or ())
        n = int(view) if view.isdigit() and len(view) <= 2 else 0
        if not 1 <= n <= views:
            raise HTTPException(
                404, f"job {job_id} has {views} drawing(s): no view {view[:8]!r} (1..{views})"
            )
        path = store.result_dir(job_id) / outlines_file(n)
        try:
            data = await run_in_threadpool(path.read_bytes)
        except FileNotFoundError:
            raise HTTPException(
                404, f"job {job_id} has no outlines picture (it finished before they were made)"
            ) from None
        # a finished job's tree never changes
        return Response(
            data, media_type="image/png", headers={"Cache-Control": "private, max-age=86400"}
        )
