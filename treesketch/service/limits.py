"""Limits checked before any work: the upload's bytes, the image's size, the options.

``read_form(request, ...)`` parses a multipart body as it streams in, counting bytes: a
body over the cap is refused (413) as soon as the count passes it, and nothing is written
to disk (Starlette's own form parser would spool the whole file to a temporary folder
first).  It also counts parts (a form has a handful: MAX_PARTS) and part-header bytes,
parses in the thread pool (a body of many tiny parts must not hold the event loop),
takes each ``sketch`` part (one per drawing of the tree, at most ``MAX_VIEWS``) with or
without a ``filename=`` (RFC 7578 makes it optional) and refuses a body cut off before its
closing boundary.  ``check_image(data)`` reads only the image header: pixel count, aspect
ratio and decompression bombs are refused before anything is decoded (``check_images``:
every drawing, an error naming the view).  ``parse_options`` turns the form fields (a
``yaw`` per drawing among them) into ``JobOptions`` or a 422 naming the bad field.
"""

from __future__ import annotations

import io
import math
from collections.abc import AsyncIterator, Callable, Collection, Mapping, Sequence
from dataclasses import dataclass

from python_multipart.multipart import MultipartParser, parse_options_header
from starlette.concurrency import run_in_threadpool

from refine.search import DEFAULT_BUDGET
from render import reader
from treesketch.pipeline import MAX_HEIGHT
from treesketch.views import MAX_VIEWS, parse_yaw

from .runner import JobOptions

__all__ = [
    "MAX_VIEWS",
    "Limits",
    "LimitError",
    "check_image",
    "check_images",
    "parse_options",
    "read_form",
]

FIELD_BYTES = 1024  # a form field (a number, a flag) is never longer
FORM_OVERHEAD = 64 * 1024  # boundaries, part headers and fields on top of the files
# every drawing and its yaw (MAX_VIEWS of each) and the options (seven known), with room
MAX_PARTS = 24
PARSE_BATCH = 256 * 1024  # bytes handed to the parser's thread at a time
HEADER_BYTES = 4096  # one part's headers (a Content-Disposition and a Content-Type)


@dataclass(frozen=True)
class Limits:
    """The service's limits; the image ones default to the sketch reader's own."""

    max_upload_bytes: int = reader.MAX_BYTES  # one image
    # the whole body: two full-size pictures, or four of half that (a drawing made on the
    # page is some 30 KB); what one request may hold in memory while it is read
    max_body_bytes: int = 2 * reader.MAX_BYTES
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


def _multipart_boundary(content_type: str, content_length: str | None, body_cap: int) -> bytes:
    """The boundary of a multipart/form-data body (415 for any other type); a declared
    length over ``body_cap`` is refused before a byte is read."""
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
        if declared > body_cap:
            raise LimitError(
                413, f"the upload ({declared} bytes) is over {body_cap - FORM_OVERHEAD} bytes"
            )
    return params[b"boundary"]


class _PartCollector:
    """python-multipart's callbacks for one form: they keep its parts in memory and
    raise a LimitError as soon as a part, its headers or the part count goes over."""

    def __init__(self, cap: int, file_field: str, max_files: int) -> None:
        self.parts: list[_Part] = []
        self.ended = False  # the closing boundary was read
        self._cap = cap
        self._file_field = file_field
        self._max_files = max_files
        self._field = b""  # the header being read: its name and value so far
        self._value = b""

    def callbacks(self) -> dict[str, Callable[..., None]]:
        """The callbacks, by the names MultipartParser calls them."""
        return {
            "on_part_begin": self.on_part_begin,
            "on_header_field": self.on_header_field,
            "on_header_value": self.on_header_value,
            "on_header_end": self.on_header_end,
            "on_headers_finished": self.on_headers_finished,
            "on_part_data": self.on_part_data,
            "on_end": self.on_end,
        }

    def on_part_begin(self) -> None:
        if len(self.parts) >= MAX_PARTS:
            raise LimitError(413, f"the form has more than {MAX_PARTS} parts")
        self.parts.append(_Part({}, bytearray()))

    def on_header_field(self, data: bytes, start: int, end: int) -> None:
        self._field += data[start:end]
        self._check_header_bytes()

    def on_header_value(self, data: bytes, start: int, end: int) -> None:
        self._value += data[start:end]
        self._check_header_bytes()

    def _check_header_bytes(self) -> None:
        size = (
            len(self._field)
            + len(self._value)
            + sum(len(k) + len(v) for k, v in self.parts[-1].headers.items())
        )
        if size > HEADER_BYTES:
            raise LimitError(413, f"a part's headers are over {HEADER_BYTES} bytes")

    def on_header_end(self) -> None:
        name, value = self._field.decode("latin-1"), self._value.decode("latin-1")
        self.parts[-1].headers[name.lower()] = value
        self._field, self._value = b"", b""

    def on_headers_finished(self) -> None:
        part, field = self.parts[-1], self._file_field
        _, disp = parse_options_header(part.headers.get("content-disposition", ""))
        part.name = disp.get(b"name", b"").decode("utf-8", "replace")
        # refused as soon as the part begins: its bytes are never read
        if part.name == field and sum(p.name == field for p in self.parts) > self._max_files:
            raise LimitError(
                422,
                f"at most {self._max_files} drawings of one tree ('{field}' parts) in one job",
            )

    def on_part_data(self, data: bytes, start: int, end: int) -> None:
        part = self.parts[-1]
        part.data += data[start:end]
        is_file = part.name == self._file_field
        limit = self._cap if is_file else FIELD_BYTES
        if len(part.data) > limit:
            what = "the sketch" if is_file else f"the form field {part.name[:40]!r}"
            raise LimitError(413, f"{what} is over {limit} bytes")

    def on_end(self) -> None:
        self.ended = True

    def clear(self) -> None:
        """Free every part's bytes now (see ``_parse_stream``)."""
        for part in self.parts:
            part.data.clear()

    def form(self) -> tuple[dict[str, list[str]], list[bytearray]]:
        """(every value of each text field in order, every file's bytes in order)."""
        fields: dict[str, list[str]] = {}
        files: list[bytearray] = []
        for part in self.parts:
            if part.name == self._file_field:
                files.append(part.data)  # no copy of up to 10 MB: a bytearray reads as bytes do
            elif part.name:
                fields.setdefault(part.name, []).append(
                    part.data.decode("utf-8", "replace").strip()
                )
        return fields, files


def _feed(parser: MultipartParser, data: bytearray) -> None:
    """Parse ``data``; python-multipart's own errors become a 400."""
    try:
        parser.write(data)  # type: ignore[arg-type] - a bytearray parses as bytes do
    except LimitError:
        raise
    except Exception as exc:  # noqa: BLE001 - python-multipart's parse errors
        raise LimitError(400, f"malformed multipart body: {exc}") from exc


async def _parse_stream(
    parser: MultipartParser, stream: AsyncIterator[bytes], body_cap: int
) -> None:
    """Feed the body to ``parser`` as it streams in, refusing it once it passes
    ``body_cap``; parsing runs in the thread pool, a batch at a time (a hop per 64 KB
    chunk costs more than the parsing of a plain file part)."""
    total = 0
    pending = bytearray()
    chunk = b""
    try:
        async for chunk in stream:
            total += len(chunk)
            if total > body_cap:
                raise LimitError(413, f"the upload is over {body_cap - FORM_OVERHEAD} bytes")
            pending += chunk
            if len(pending) >= PARSE_BATCH:
                await run_in_threadpool(_feed, parser, pending)
                pending.clear()
        if pending:
            await run_in_threadpool(_feed, parser, pending)
        parser.finalize()
    except BaseException:
        # the error's traceback keeps these frames, and a reference cycle on the way up may
        # keep the traceback until a full garbage collection: free the bytes now, or a
        # stream of refused uploads piles them up (100 MB in 20 s, bench_hostile.py)
        pending.clear()
        chunk = b""
        raise


async def read_form(
    content_type: str,
    content_length: str | None,
    stream: AsyncIterator[bytes],
    limits: Limits,
    file_field: str = "sketch",
    max_files: int = MAX_VIEWS,
) -> tuple[dict[str, list[str]], list[bytearray]]:
    """(every value of each text field in order, every file's bytes in order) of a
    multipart body, read chunk by chunk; more than ``max_files`` files is a 422."""
    cap = limits.max_upload_bytes
    body_cap = max(cap, limits.max_body_bytes) + FORM_OVERHEAD
    boundary = _multipart_boundary(content_type, content_length, body_cap)
    collector = _PartCollector(cap, file_field, max_files)
    parser = MultipartParser(boundary, collector.callbacks())
    try:
        await _parse_stream(parser, stream, body_cap)
        if not collector.ended:
            raise LimitError(
                400, "the upload was cut off: its closing multipart boundary is missing"
            )
    except BaseException:
        collector.clear()  # as _parse_stream frees its own buffers
        raise
    return collector.form()


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


def check_images(images: Sequence[bytes], limits: Limits) -> list[tuple[int, int]]:
    """:func:`check_image` of every drawing of a job, in order; when there are several, an
    error names the view (``view 2: ...``, the first drawing is view 1)."""
    if len(images) == 1:
        return [check_image(images[0], limits)]
    sizes = []
    for i, data in enumerate(images, 1):
        try:
            sizes.append(check_image(data, limits))
        except LimitError as exc:
            raise LimitError(exc.status, f"view {i}: {exc}") from None
    return sizes


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


def _yaws(values: Sequence[str], views: int) -> tuple[float | None, ...]:
    """The yaws of the drawings after the first, from the form's ``yaw`` fields: one per
    drawing (the first's 0 or empty) or one per drawing after the first; ``?`` or empty:
    not known (the refinement finds it)."""
    if views == 1 and not values:
        return ()
    if len(values) == views:
        first, values = values[0], values[1:]
        try:
            yaw0 = parse_yaw(first)
        except ValueError as exc:
            raise LimitError(422, f"yaw of view 1: {exc}") from None
        if first.strip() not in ("", "0") and yaw0 != 0.0:
            raise LimitError(
                422,
                f"yaw of view 1 must be 0 or empty (the other views' yaws are relative to "
                f"it), got {first[:40]!r}",
            )
    elif len(values) != views - 1:
        raise LimitError(
            422,
            f"{views} drawings and {len(values)} 'yaw' fields: send one 'yaw' per drawing, "
            "in the same order (the first 0, '?' for a side not known)",
        )
    out = []
    for i, text in enumerate(values, 2):
        try:
            out.append(parse_yaw(text))
        except ValueError as exc:
            raise LimitError(422, f"yaw of view {i}: {exc}") from None
    return tuple(out)


def parse_options(
    form: Mapping[str, str | Sequence[str]],
    limits: Limits,
    estimators: Collection[str],
    default_estimator: str,
    default_budget: int = DEFAULT_BUDGET,
    default_time_limit: float = 50.0,
    views: int = 1,
) -> JobOptions:
    """Validated job options from form fields (a value, or every value of a field in
    order: an option given twice takes the last, ``yaw`` takes one per drawing) for a job
    of ``views`` drawings; LimitError(422) naming the first bad one."""
    known = {"refine", "budget", "time_limit", "height", "estimator", "max_faces", "species"}
    unknown = sorted(set(form) - known - {"yaw"})
    if unknown:
        raise LimitError(
            422,
            f"unknown option(s) {', '.join(unknown)}; known: {', '.join(sorted(known | {'yaw'}))}",
        )
    if not 1 <= views <= MAX_VIEWS:
        raise LimitError(422, f"a job takes 1 to {MAX_VIEWS} drawings of one tree, got {views}")
    every = {k: [v] if isinstance(v, str) else list(v) for k, v in form.items()}
    yaws = _yaws(every.pop("yaw", []), views)
    fields = {k: v[-1] for k, v in every.items() if v}
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
        yaws=yaws,
    )
    try:
        options.settings()  # the pipeline's own check, before the job is queued
        options.export().validate()
    except ValueError as exc:
        raise LimitError(422, str(exc)) from exc
    return options
