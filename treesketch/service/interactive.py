"""The routes of the interactive loop: the controls, a tree grown from them, a running
job's current best tree.

- ``GET /controls``: the controls table (``weberpenn.controls``), every species' defaults
  (the species list is ``weberpenn.species.SPECIES``), the default budget and the
  viewer's triangle budget.
- ``POST /trees`` (JSON: ``params``, ``controls``, ``seed``, ``species``, ``max_faces``,
  ``yaw``): the tree grown (its GLB turned to face the view from ``yaw``); ``Accept: model/gltf-binary`` answers its GLB (the tree's height,
  species and control values in ``X-Tree-*`` headers), otherwise JSON with its
  parameters, species, height and control values; ``Accept: application/zip`` answers
  the tree as OBJ (``tree.obj``, ``tree.mtl``, the bark and leaf textures) in a zip.
- ``GET /jobs/{id}/preview/tree.glb`` and ``.../sketch.png``: the job's current best tree
  while it runs (``preview.PreviewWriter``; the job's progress says which ``preview``
  version is there).  Local worker processes write it beside the job's results; a Ray
  actor hands it to the front with its progress, which writes it there.
- ``GET /jobs/{id}/outline.png?turn=DEG&size=N``: a finished job's tree as a sketch seen
  from ``turn`` degrees about the trunk, relative to the side it was drawn from (the
  result's yaw + turn, as ``render.sketch.SketchRenderer.sketch`` turns; the page's
  "Draw from this side" shows it faintly under a new drawing of that side).  Drawn the
  cheap way (``treesketch.trees.tree_sketch``: a median 0.18 s at 256 px, 0.30 s at 512
  px on a busy 2-core machine) and cached by the browser: a finished job's tree never
  changes.
- ``GET /jobs/{id}/drawing.png?view=N``: the drawing the job was sent (its first, or its
  ``view``-th), as uploaded: the page puts it back on the pad when a job's link is opened.
- ``GET /examples`` (names and links) and ``GET /examples/{name}``: the example drawings
  (the repository's ``examples/hand/``, when the service runs from a checkout);
  ``GET /help/controls.png``: pictures of what each control does (``docs/controls.png``).

A tree is grown here, not in a worker: an edit must not wait behind a refinement.  A
cheap one (an edit: a fraction of a second) grows in the front's thread pool, an
expensive one in a child process with a time limit, each behind its own bounded gate,
and a big GLB is streamed from disk (``tree_work``, issue 49).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

from fastapi import FastAPI, HTTPException, Request
from fastapi.responses import FileResponse, JSONResponse, Response
from starlette.concurrency import run_in_threadpool

from ..trees import TreeTooBig
from .preview import PREVIEW_FILES
from .store import JobStore
from .tree_work import (
    BIG_AT_ONCE,
    BIG_SECONDS,
    BIG_WAITING,
    EDITS_AT_ONCE,
    EDITS_WAITING,
    MEMORY_REPLY_BYTES,
    Gate,
    TreeTimeout,
    grow_in_child,
    is_expensive,
    stream_file,
    write_reply,
)

__all__ = [
    "EDITS_AT_ONCE",
    "MAX_TREE_BODY",
    "OUTLINE_SIZES",
    "add_interactive_routes",
    "outline_png",
    "parse_outline_query",
]

REPO = Path(__file__).resolve().parents[2]
EXAMPLES = REPO / "examples" / "hand"
CONTROLS_PICTURE = REPO / "docs" / "controls.png"
MAX_TREE_BODY = 256 * 1024  # bytes: a parameter dictionary is about 3 KB
GLB = "model/gltf-binary"
ZIP = "application/zip"
# an uploaded drawing's media type by its first bytes (the reader took it, so it is one)
PICTURE_MAGIC = (
    (b"\x89PNG", "image/png"),
    (b"\xff\xd8", "image/jpeg"),
    (b"GIF8", "image/gif"),
    (b"BM", "image/bmp"),
    (b"RIFF", "image/webp"),
)
OUTLINE_SIZES = (64, 512)  # px: the page's pad is 512 px
MAX_TURN = 3600.0  # degrees: ten turns either way (any finite turn means the same modulo 360)


def controls_table() -> dict[str, Any]:
    from refine.search import DEFAULT_BUDGET
    from treesketch.trees import VIEW_FACES
    from weberpenn import species
    from weberpenn.controls import defaults, table

    return {
        "controls": table(),
        "species": {name: defaults(name) for name in species.SPECIES},
        "default_budget": DEFAULT_BUDGET,
        "view_faces": VIEW_FACES,
    }


def grow_request(
    body: Any, want_glb: bool, want_zip: bool = False
) -> tuple[bytes | dict[str, Any], dict[str, str]]:
    """(GLB bytes, the OBJ zip's bytes or the JSON answer, headers) of one ``POST /trees``
    body; ValueError for a bad one."""
    from treesketch.trees import TreeRequest, edit_tree, reply_glb

    request = TreeRequest.from_json(body)
    tree = edit_tree(request)
    facts = {
        "X-Tree-Species": tree.species,
        "X-Tree-Height": f"{tree.height:.4f}",
        "X-Tree-Controls": json.dumps(tree.controls, separators=(",", ":")),
        "X-Tree-Adjusted": json.dumps(tree.adjusted, separators=(",", ":")),
    }
    if want_glb:
        # TreeTooBig (a ValueError) past the most a reply holds, before exporting
        return reply_glb(tree.mesh, yaw=request.yaw, max_faces=request.max_faces), facts
    if want_zip:
        return obj_zip(tree.mesh, yaw=request.yaw, max_faces=request.max_faces), facts
    return {
        "params": tree.params.to_dict(),
        "species": tree.species,
        "height": tree.height,
        "controls": tree.controls,
        "adjusted": tree.adjusted,
    }, facts


def grow_zip_request(body: Any, want_glb: bool) -> tuple[bytes | dict[str, Any], dict[str, str]]:
    """:func:`grow_request` answering the OBJ zip (``want_glb`` is ignored): the grower
    ``tree_work`` runs for an ``Accept: application/zip`` request."""
    return grow_request(body, False, True)


def obj_zip(mesh: Any, yaw: float = 0.0, max_faces: int | None = None) -> bytes:
    """The tree's OBJ export (``weberpenn.export.obj_files``: ``tree.obj``, ``tree.mtl``,
    the textures) as the bytes of one zip; :class:`TreeTooBig` past the most a reply holds,
    as for a GLB."""
    import io
    import tempfile
    import zipfile

    from treesketch.trees import REPLY_FACES, TreeTooBig
    from weberpenn.export import obj_files

    budget = REPLY_FACES if max_faces is None else min(max_faces, REPLY_FACES)
    if (max_faces is None or max_faces > REPLY_FACES) and mesh.n_faces > budget:
        raise TreeTooBig(
            f"the tree has {mesh.n_faces:,} triangles; a reply holds at most "
            f"{REPLY_FACES:,}: ask for max_faces <= {REPLY_FACES} (the same tree, lighter)"
        )
    with tempfile.TemporaryDirectory() as d:
        files = obj_files(mesh, Path(d) / "tree.obj", yaw=yaw, max_faces=max_faces)
    out = io.BytesIO()
    with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as z:
        for path, content in files.items():
            z.writestr(path.name, content)
    return out.getvalue()


def picture_type(data: bytes) -> str:
    """The media type of an uploaded picture by its first bytes."""
    for magic, media in PICTURE_MAGIC:
        if data.startswith(magic):
            return media
    return "application/octet-stream"


async def _json_body(request: Request) -> Any:
    size = request.headers.get("content-length")
    if size is not None and (not size.isdigit() or int(size) > MAX_TREE_BODY):
        raise HTTPException(413, f"the body must be at most {MAX_TREE_BODY} bytes")
    data = bytearray()
    async for chunk in request.stream():
        data += chunk
        if len(data) > MAX_TREE_BODY:
            raise HTTPException(413, f"the body must be at most {MAX_TREE_BODY} bytes")
    try:
        return json.loads(bytes(data))
    except (ValueError, RecursionError) as exc:
        # ValueError: not JSON (JSONDecodeError, UnicodeDecodeError) or an integer past
        # Python's 4,300 digits; RecursionError: arrays or objects nested too deep
        what = "nested too deep" if isinstance(exc, RecursionError) else str(exc)[:200]
        raise HTTPException(422, f"the body is not JSON this server reads: {what}") from None


def parse_outline_query(turn: str, size: str) -> tuple[float, int]:
    """(turn in degrees, size in px) of an outline request; ValueError naming the bad
    one."""
    try:
        degrees = float(turn.strip().removesuffix("deg"))
    except ValueError:
        raise ValueError(f"turn must be a number of degrees, got {turn[:40]!r}") from None
    if not math.isfinite(degrees) or abs(degrees) > MAX_TURN:
        raise ValueError(
            f"turn must be finite degrees in [-{MAX_TURN:g}, {MAX_TURN:g}], got {turn[:40]!r}"
        )
    lo, hi = OUTLINE_SIZES
    text = size.strip()
    if not (text.isdigit() and len(text) <= 5 and lo <= int(text) <= hi):
        raise ValueError(f"size must be a whole number of pixels in {lo}..{hi}, got {size[:40]!r}")
    return degrees, int(text)


def outline_png(summary: dict[str, Any], turn: float, size: int) -> bytes:
    """The PNG of a finished job's tree (its ``summary``: params, species, yaw) sketched
    from ``turn`` degrees about the trunk relative to the side it was drawn from."""
    from treesketch.outputs import png_bytes
    from treesketch.trees import tree_sketch
    from weberpenn import TreeParams

    yaw = (float(summary.get("yaw", 0.0)) + turn) % 360.0
    params = TreeParams(summary["params"])
    return png_bytes(tree_sketch(params, summary["species"], yaw, size))


def example_files(folder: Path = EXAMPLES) -> dict[str, Path]:
    """The example drawings by name (PNG files of ``folder``, sorted)."""
    if not folder.is_dir():
        return {}
    return {p.stem: p for p in sorted(folder.glob("*.png")) if p.is_file()}


def add_interactive_routes(app: FastAPI, store: JobStore) -> None:
    """Add the routes of the module text to ``app``, in this order (before the app's own
    ``/jobs/{id}/{artefact}``, which would take their names)."""
    # tree edits and outlines share one gate: both are cheap work for the thread pool
    gate = Gate(EDITS_AT_ONCE, EDITS_WAITING, "tree edits and outlines")
    big_gate = Gate(BIG_AT_ONCE, BIG_WAITING, "large trees")
    _add_help_routes(app)
    _add_trees_route(app, gate, big_gate, store.root / "trees")
    _add_job_picture_routes(app, store, gate)


def _add_help_routes(app: FastAPI) -> None:
    """The page's fixed material: the example drawings, the controls and their picture."""

    @app.get("/examples")
    async def examples() -> dict[str, Any]:
        names = await run_in_threadpool(example_files)
        return {"examples": [{"name": n, "url": f"/examples/{n}"} for n in names]}

    @app.get("/examples/{name}")
    async def example(name: str) -> Response:
        path = (await run_in_threadpool(example_files)).get(name)  # never a path from the URL
        if path is None:
            raise HTTPException(404, f"no example drawing {name!r}")
        return FileResponse(path, media_type="image/png")

    @app.get("/help/controls.png")
    async def controls_picture() -> Response:
        if not CONTROLS_PICTURE.is_file():
            raise HTTPException(404, "the controls picture is not installed")
        return FileResponse(CONTROLS_PICTURE, media_type="image/png")

    @app.get("/controls")
    async def controls() -> dict[str, Any]:
        return await run_in_threadpool(controls_table)


def _add_trees_route(app: FastAPI, gate: Gate, big_gate: Gate, replies: Path) -> None:
    """``POST /trees``: a cheap tree grown in the thread pool behind ``gate``, an
    expensive one in a child process behind ``big_gate``; a big reply is written to
    ``replies`` (unlinked as soon as it is opened) and streamed from there."""

    async def grow_cheap(body: Any, want_glb: bool, fn: Any) -> tuple[Any, dict[str, str]]:
        async with gate.enter():
            answer, facts = await run_in_threadpool(fn, body, want_glb)
        if isinstance(answer, bytes) and len(answer) > MEMORY_REPLY_BYTES:
            # a reply a slow client may hold for long: from disk, not from memory
            try:
                answer = await run_in_threadpool(write_reply, answer, replies)
            except OSError as exc:  # a full disk: nothing half-written is left
                raise HTTPException(507, f"cannot write the tree's reply: {exc}") from None
        return answer, facts

    async def grow_big(body: Any, want_glb: bool, fn: Any) -> tuple[Any, dict[str, str]]:
        async with big_gate.enter():
            try:
                return await run_in_threadpool(
                    grow_in_child, fn, body, want_glb, replies, BIG_SECONDS
                )
            except TreeTimeout as exc:
                raise HTTPException(
                    503,
                    f"{exc}, the limit of one POST /trees: ask for a smaller tree (fewer "
                    "branches or levels, a lower curveRes, fewer leaves) or a lighter GLB "
                    "(max_faces)",
                ) from None
            except RuntimeError as exc:  # the child died (out of memory?)
                raise HTTPException(503, f"the tree could not be grown: {exc}") from None

    @app.post("/trees")
    async def trees(request: Request) -> Response:
        body = await _json_body(request)
        accept = request.headers.get("accept", "")
        want_glb = GLB in accept
        # the OBJ zip: another grower, answered as the GLB is (from disk when big)
        fn, media = (
            (grow_request, GLB) if want_glb or ZIP not in accept else (grow_zip_request, ZIP)
        )
        try:
            # every field checked and the cost estimated before any gate or growing
            expensive = await run_in_threadpool(is_expensive, body)
            grow = grow_big if expensive else grow_cheap
            answer, facts = await grow(body, want_glb, fn)
        except TreeTooBig as exc:
            raise HTTPException(413, str(exc)) from None
        except ValueError as exc:  # ParamError and bad controls: the request's fault
            raise HTTPException(422, str(exc)) from None
        headers = {**facts, "Cache-Control": "no-store"}
        if isinstance(answer, Path):
            return stream_file(answer, media, headers)
        if isinstance(answer, bytes):
            return Response(answer, media_type=media, headers=headers)
        return JSONResponse(answer)


def _add_job_picture_routes(app: FastAPI, store: JobStore, gate: Gate) -> None:
    """A job's pictures: its tree's outline from another side (drawn behind ``gate``),
    the drawing it was sent, its current best tree while it runs."""

    # registered before the app's ``/jobs/{id}/{artefact}``, which would take the name
    @app.get("/jobs/{job_id}/outline.png")
    async def outline(job_id: str, turn: str = "0", size: str = "256") -> Response:
        try:
            degrees, px = parse_outline_query(turn, size)
        except ValueError as exc:
            raise HTTPException(422, str(exc)) from exc
        job = await run_in_threadpool(store.get, job_id)
        if job is None:
            raise HTTPException(404, f"no job {job_id!r}")
        # an expired job's files are gone but its result (the tree) is still known
        if job.state not in ("done", "expired") or not (job.summary or {}).get("params"):
            raise HTTPException(409, f"job {job_id} is {job.state}: it has no tree yet")
        async with gate.enter():
            try:
                data = await run_in_threadpool(outline_png, job.summary, degrees, px)
            except ValueError as exc:  # a stored result the tree cannot be grown from
                raise HTTPException(500, f"cannot draw job {job_id}'s tree: {exc}") from exc
        # a finished job's tree never changes
        return Response(
            data, media_type="image/png", headers={"Cache-Control": "private, max-age=86400"}
        )

    @app.get("/jobs/{job_id}/drawing.png")
    async def drawing(job_id: str, view: str = "1") -> Response:
        n = int(view) if view.isdigit() and len(view) <= 2 else 0
        job = await run_in_threadpool(store.get, job_id)
        if job is None:
            raise HTTPException(404, f"no job {job_id!r}")
        views = 1 + len(job.options.get("yaws") or ())
        if not 1 <= n <= views:
            raise HTTPException(422, f"view must be 1..{views}, got {view[:8]!r}")
        path = store.upload_path(job_id, n)
        if not path.is_file():
            raise HTTPException(410, f"job {job_id}'s drawing was removed")
        data = await run_in_threadpool(path.read_bytes)
        return Response(
            data,
            media_type=picture_type(data),
            headers={
                "Cache-Control": "private, max-age=86400",
                "X-Content-Type-Options": "nosniff",
            },
        )

    @app.get("/jobs/{job_id}/preview/{name}")
    async def preview(job_id: str, name: str) -> Response:
        if name not in PREVIEW_FILES:
            raise HTTPException(404, f"no preview {name!r}; there are {', '.join(PREVIEW_FILES)}")
        job = await run_in_threadpool(store.get, job_id)
        if job is None:
            raise HTTPException(404, f"no job {job_id!r}")
        path = store.result_dir(job_id) / "preview" / name
        if not path.is_file():
            raise HTTPException(404, f"job {job_id} has no tree to show yet")
        return FileResponse(
            path, media_type=PREVIEW_FILES[name], headers={"Cache-Control": "no-store"}
        )
