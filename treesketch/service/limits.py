"""Limits checked before any work: the upload's bytes, the image's size, the options.

``read_form(request, ...)`` parses a multipart body as it streams in, counting bytes: a
body over the cap is refused (413) as soon as the count passes it, and nothing is written
to disk (Starlette's own form parser would spool the whole file to a temporary folder
first).  It also counts parts (a form has a handful: MAX_PARTS) and part-header bytes,
parses in the thread pool (a body of many tiny parts must not hold the event loop),
takes the ``sketch`` part with or without a ``filename=`` (RFC 7578 makes it optional)
and refuses a body cut off before its closing boundary.  ``check_image(data)`` reads only the image header: pixel count, aspect ratio and
decompression bombs are refused before anything is decoded.  ``parse_options`` turns the
form fields into ``JobOptions`` or a 422 naming the bad field.
"""

from __future__ import annotations

import io
import math
from collections.abc import AsyncIterator, Collection, Mapping
from dataclasses import dataclass

from python_multipart.multipart import MultipartParser, parse_options_header
from starlette.concurrency import run_in_threadpool

from refine.search import DEFAULT_BUDGET
from render import reader
from treesketch.pipeline import MAX_HEIGHT

from .runner import JobOptions

__all__ = [
    "Limits",
    "LimitError",
    "check_image",
    "parse_options",
    "read_form",
]

FIELD_BYTES = 1024  # a form field (a number, a flag) is never longer
FORM_OVERHEAD = 64 * 1024  # boundaries, part headers and fields on top of the file
MAX_PARTS = 16  # the sketch and the options (six known), with room to spare
PARSE_BATCH = 256 * 1024  # bytes handed to the parser's thread at a time
HEADER_BYTES = 4096  # one part's headers (a Content-Disposition and a Content-Type)


@dataclass(frozen=True)
class Limits:
    """The service's limits; the image ones default to the sketch reader's own."""

    max_upload_bytes: int = reader.MAX_BYTES
    max_pixels: int = reader.MAX_PIXELS
    max_aspect: float = reader.MAX_ASPECT
    min_side: int = reader.MIN_SIDE
    max_budget: int = 1000  # a job is one refinement, not a study
    max_time_limit: float = 600.0
    max_height: float = MAX_HEIGHT


class LimitError(ValueError):
    """A request refused before any work; ``status`` is the HTTP status to answer."""

    def __init__(self, status: int, message: str) -> None:
        super().__init__(message)
        self.status = status


@dataclass
class _Part:
    headers: dict[str, str]
    data: bytearray
    name: str = ""


async def read_form(
    content_type: str,
    content_length: str | None,
    stream: AsyncIterator[bytes],
    limits: Limits,
    file_field: str = "sketch",
) -> tuple[dict[str, str], bytes | None]:
    """(text fields, the file's bytes or None) of a multipart body, read chunk by chunk."""
    cap = limits.max_upload_bytes
    mtype, params = parse_options_header(content_type)
    if mtype != b"multipart/form-data" or b"boundary" not in params:
        raise LimitError(
            415, "send the sketch as multipart/form-data (a file field named 'sketch')"
        )
    if content_length is not None:
        try:
            declared = int(content_length)
        except ValueError:
            raise LimitError(400, f"bad Content-Length {content_length!r}") from None
        if declared > cap + FORM_OVERHEAD:
            raise LimitError(413, f"the upload ({declared} bytes) is over {cap} bytes")

    parts: list[_Part] = []
    header: list[bytes] = [b"", b""]
    ended = [False]

    def on_part_begin() -> None:
        if len(parts) >= MAX_PARTS:
            raise LimitError(413, f"the form has more than {MAX_PARTS} parts")
        parts.append(_Part({}, bytearray()))

    def on_header_field(data: bytes, start: int, end: int) -> None:
        header[0] += data[start:end]
        _header_bytes()

    def on_header_value(data: bytes, start: int, end: int) -> None:
        header[1] += data[start:end]
        _header_bytes()

    def _header_bytes() -> None:
        size = (
            len(header[0])
            + len(header[1])
            + sum(len(k) + len(v) for k, v in parts[-1].headers.items())
        )
        if size > HEADER_BYTES:
            raise LimitError(413, f"a part's headers are over {HEADER_BYTES} bytes")

    def on_header_end() -> None:
        parts[-1].headers[header[0].decode("latin-1").lower()] = header[1].decode("latin-1")
        header[0], header[1] = b"", b""

    def on_headers_finished() -> None:
        part = parts[-1]
        _, disp = parse_options_header(part.headers.get("content-disposition", ""))
        part.name = disp.get(b"name", b"").decode("utf-8", "replace")

    def on_part_data(data: bytes, start: int, end: int) -> None:
        part = parts[-1]
        part.data += data[start:end]
        is_file = part.name == file_field
        if len(part.data) > (cap if is_file else FIELD_BYTES):
            what = "the sketch" if is_file else f"the form field {part.name[:40]!r}"
            raise LimitError(413, f"{what} is over {cap if is_file else FIELD_BYTES} bytes")

    def on_end() -> None:
        ended[0] = True

    parser = MultipartParser(
        params[b"boundary"],
        {
            "on_part_begin": on_part_begin,
            "on_header_field": on_header_field,
            "on_header_value": on_header_value,
            "on_header_end": on_header_end,
            "on_headers_finished": on_headers_finished,
            "on_part_data": on_part_data,
            "on_end": on_end,
        },
    )

    def feed(data: bytearray) -> None:
        try:
            parser.write(data)  # type: ignore[arg-type] - a bytearray parses as bytes do
        except LimitError:
            raise
        except Exception as exc:  # noqa: BLE001 - python-multipart's parse errors
            raise LimitError(400, f"malformed multipart body: {exc}") from exc

    total = 0
    pending = bytearray()
    chunk = b""
    try:
        async for chunk in stream:
            total += len(chunk)
            if total > cap + FORM_OVERHEAD:
                raise LimitError(413, f"the upload is over {cap} bytes")
            # parse in the thread pool, a batch at a time (a hop per 64 KB chunk costs
            # more than the parsing of a plain file part)
            pending += chunk
            if len(pending) >= PARSE_BATCH:
                await run_in_threadpool(feed, pending)
                pending.clear()
        if pending:
            await run_in_threadpool(feed, pending)
        parser.finalize()
        if not ended[0]:
            raise LimitError(
                400, "the upload was cut off: its closing multipart boundary is missing"
            )
    except BaseException:
        # the error's traceback keeps these frames, and a reference cycle on the way up may
        # keep the traceback until a full garbage collection: free the bytes now, or a
        # stream of refused uploads piles them up (100 MB in 20 s, bench_hostile.py)
        pending.clear()
        for part in parts:
            part.data.clear()
        chunk = b""
        raise

    fields: dict[str, str] = {}
    file: bytes | None = None
    for part in parts:
        if part.name == file_field:
            file = part.data  # no copy of up to 10 MB: a bytearray reads as bytes do
        elif part.name:
            fields[part.name] = part.data.decode("utf-8", "replace").strip()
    return fields, file


def check_image(data: bytes, limits: Limits) -> tuple[int, int]:
    """(width, height) of an image, from its header only; LimitError when it is not an
    image, too small, too many pixels, too long and thin, or a decompression bomb."""
    from PIL import Image, UnidentifiedImageError

    if not data:
        raise LimitError(400, "the uploaded sketch is empty")
    try:  # the reader's own format rule, by content: an EPS never reaches Pillow
        fmt = reader.image_format(data, "the uploaded sketch")
    except reader.FormatError as exc:
        raise LimitError(415, str(exc)) from None
    except reader.SketchError as exc:
        raise LimitError(400, str(exc)) from None
    # closed at the end: a refused image's traceback may live on (until a full garbage
    # collection) and must not keep a copy of the upload
    buffer = io.BytesIO(data)
    try:
        # lazy: reads the header, decodes nothing
        with Image.open(buffer, formats=[fmt]) as im:
            w, h = im.size
    except Image.DecompressionBombError as exc:
        raise LimitError(413, f"the image is a decompression bomb: {exc}") from exc
    except UnidentifiedImageError as exc:
        raise LimitError(
            400, "cannot read the sketch as an image (send a PNG, JPEG, WebP, GIF or BMP)"
        ) from exc
    except (OSError, SyntaxError, ValueError) as exc:
        raise LimitError(400, f"cannot read the sketch as an image: {exc}") from exc
    finally:
        buffer.close()
    if min(w, h) < limits.min_side:
        raise LimitError(422, f"the sketch is {w}x{h} px; it must be at least {limits.min_side} px")
    if w * h > limits.max_pixels:
        raise LimitError(
            413, f"the sketch is {w}x{h} px ({w * h} pixels), over {limits.max_pixels} pixels"
        )
    if max(w, h) / min(w, h) > limits.max_aspect:
        raise LimitError(
            422, f"the sketch is {w}x{h} px: aspect ratio over {limits.max_aspect:g} to 1"
        )
    return w, h


def _number(fields: Mapping[str, str], name: str, kind: type) -> float | int | None:
    text = fields.get(name, "").strip()
    if text == "" or text.lower() in ("none", "null"):
        return None
    if kind is int and len(text.lstrip("+-")) > 18:  # past int64: no option is that large
        raise LimitError(422, f"{name} is out of range ({len(text)} digits)")
    try:
        value = kind(text)
    except ValueError:
        raise LimitError(422, f"{name} must be a number, got {text[:40]!r}") from None
    if kind is float and not math.isfinite(value):  # (an int is finite; isfinite overflows)
        raise LimitError(422, f"{name} must be finite, got {text[:40]!r}")
    return value


def _flag(fields: Mapping[str, str], name: str, default: bool) -> bool:
    text = fields.get(name, "").strip().lower()
    if text == "":
        return default
    if text in ("1", "true", "yes", "on"):
        return True
    if text in ("0", "false", "no", "off"):
        return False
    raise LimitError(422, f"{name} must be true or false, got {text!r}")


def parse_options(
    fields: Mapping[str, str],
    limits: Limits,
    estimators: Collection[str],
    default_estimator: str,
    default_budget: int = DEFAULT_BUDGET,
    default_time_limit: float = 50.0,
) -> JobOptions:
    """Validated job options from form fields; LimitError(422) naming the first bad one."""
    known = {"refine", "budget", "time_limit", "height", "estimator", "max_faces", "species"}
    unknown = sorted(set(fields) - known)
    if unknown:
        raise LimitError(
            422, f"unknown option(s) {', '.join(unknown)}; known: {', '.join(sorted(known))}"
        )
    budget = _number(fields, "budget", int)
    budget = default_budget if budget is None else int(budget)
    if not 1 <= budget <= limits.max_budget:
        raise LimitError(422, f"budget must be in 1..{limits.max_budget}, got {budget}")
    seconds = _number(fields, "time_limit", float)
    seconds = default_time_limit if seconds is None else float(seconds)
    if not 0 < seconds <= limits.max_time_limit:
        raise LimitError(
            422, f"time_limit must be in (0, {limits.max_time_limit:g}] seconds, got {seconds}"
        )
    height = _number(fields, "height", float)
    if height is not None and not 0 < height <= limits.max_height:
        raise LimitError(422, f"height must be in (0, {limits.max_height:g}] metres, got {height}")
    estimator = fields.get("estimator", "").strip() or default_estimator
    if estimator not in estimators:
        raise LimitError(
            422, f"estimator must be one of {', '.join(sorted(estimators))}, got {estimator!r}"
        )
    max_faces = _number(fields, "max_faces", int)
    species_name = fields.get("species", "").strip()[:64] or None
    if species_name is not None:
        from weberpenn import ParamError, species

        try:
            species_name = species.canonical(species_name)
        except ParamError as exc:
            raise LimitError(422, str(exc)) from exc
    options = JobOptions(
        refine=_flag(fields, "refine", True),
        budget=budget,
        time_limit=seconds,
        height=None if height is None else float(height),
        estimator=estimator,
        max_faces=None if max_faces is None else int(max_faces),
        species=species_name,
    )
    try:
        options.settings()  # the pipeline's own check, before the job is queued
        options.export().validate()
    except ValueError as exc:
        raise LimitError(422, str(exc)) from exc
    return options
