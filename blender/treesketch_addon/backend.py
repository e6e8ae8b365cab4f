"""The add-on's work that needs no Blender: running the prediction, reading its outputs,
turning pen strokes into a drawing.  Plain Python and numpy (Blender's own Python has
both), so the project's test suite checks it without Blender.

- :func:`cli_command` / :func:`run_cli`: ``treesketch predict IMAGE --out X.glb --params
  X.json --preset X.py --preview DIR`` in the project's venv, its output lines handed to a
  callback; while it refines, the CLI keeps the current best tree in ``DIR/tree.glb``
  (the first estimate at once), which :class:`PreviewWatch` says when to show.
- :func:`post_predict`: the service's ``POST /predict`` (multipart ``sketch``), then the
  GLB it names is downloaded.  Only from the configured service: plain http(s), the same
  origin (scheme, host, port) for the GLB and any redirect, never ``file://`` or another
  host; the reply and the GLB have size caps; a token goes in an ``Authorization:
  Bearer`` header, never in a URL.  The job's outlines picture (the drawing's outline
  over the tree's) comes too when the service has one; ``cli_command`` asks the CLI for
  it (``--outlines``).
- :func:`read_preset`: the Sapling dict and the view yaw from a TreeSketch preset.
- :func:`strokes_png`: pen strokes (lists of 2-D points) drawn black on white as a PNG,
  framed the way the project's reader expects (tree filling the canvas, base at the
  bottom).
- :data:`VIEWS` / :func:`view_layers`: Grease Pencil layers named after Blender's views
  (Front, Right, Back, Left) are drawings of one tree from those sides, sent as the
  views of one prediction (``--view FILE@YAW``).
- :func:`glb_textures`: the PNG each material of a GLB carries (``bark``, ``leaf``), for
  the materials of a Sapling tree (Sapling makes none).
- :func:`numpy_bool_alias`: puts back ``numpy.bool``, which the glTF importer of Blender
  3.4 (Debian's) still calls though numpy 1.24 removed it.
- :func:`plain_error`: one line a person can read from an exception (an operator's
  ``RuntimeError`` carries Blender's whole "Error: Python: Traceback ..." text).
- :func:`species_of` / :func:`species_text_of` / :func:`preset_name`: the predicted
  species and the species in words ("a palm (87%); could also be a cherry") from the
  CLI's output, and a preset file name of its own for every prediction.
- :func:`load_species`: the species a person may pick (the project's list, shipped in
  the zip as ``species.json``); ``cli_command`` and ``post_predict`` pass the one picked
  (``--species`` / the ``species`` field).
- :func:`load_controls`, :func:`keep_value`, :func:`changed_controls`,
  :func:`grow_command`, :func:`post_trees`: the controls a person edits the predicted tree
  with (the project's table, shipped in the zip as ``controls.json``), and the tree grown
  again from them (``treesketch grow --params --set`` or the service's ``POST /trees``).
"""

from __future__ import annotations

import ast
import contextlib
import json
import os
import re
import struct
import subprocess
import time
import urllib.error
import urllib.parse
import urllib.request
import uuid
import zlib
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

__all__ = [
    "MAX_GLB_BYTES",
    "Outputs",
    "changed_controls",
    "grow_command",
    "keep_value",
    "load_controls",
    "load_species",
    "post_trees",
    "numpy_bool_alias",
    "plain_error",
    "preset_name",
    "species_of",
    "species_text_of",
    "PredictError",
    "PreviewWatch",
    "VIEWS",
    "cli_command",
    "glb_textures",
    "multipart_body",
    "post_predict",
    "progress_fraction",
    "read_preset",
    "run_cli",
    "strokes_png",
    "view_layers",
]

_ANSI = re.compile(r"\x1b\[[0-9;?]*[A-Za-z]")
_SPECIES = re.compile(r"^species: ([A-Za-z0-9_]+)")
_SPECIES_TEXT = re.compile(r"^it is (.+)$")
_ERROR_LINE = re.compile(r"^[A-Za-z_][\w.]*(Error|Exception|Exit)\b.*?: ")
_YAW = re.compile(r"^# view yaw: (-?[0-9.]+) degrees")


class PredictError(RuntimeError):
    """The prediction could not run or failed; the message says why in plain words."""


@dataclass(frozen=True)
class Outputs:
    """Where one prediction's files go (all in one folder)."""

    glb: Path
    params: Path
    preset: Path
    preview: Path  # the folder the CLI keeps the current best tree in while it refines
    # the drawing's outline (red) over the tree's (blue) at the drawn view: the CLI's
    # --outlines, or the service's GET /jobs/{id}/outlines.png
    outlines: Path

    @classmethod
    def in_folder(cls, folder: str | os.PathLike[str], stem: str = "tree") -> Outputs:
        d = Path(folder)
        return cls(
            d / f"{stem}.glb",
            d / f"{stem}.json",
            d / f"{stem}_sapling.py",
            d / "preview",
            d / f"{stem}_outlines.png",
        )


def cli_command(
    treesketch: str | os.PathLike[str],
    image: str | os.PathLike[str],
    outputs: Outputs,
    *,
    refine: bool = True,
    budget: int | None = None,
    max_faces: int | None = None,
    species: str | None = None,
    views: Sequence[tuple[str | os.PathLike[str], float]] = (),
) -> list[str]:
    """The ``treesketch predict`` command line for one drawing (``species``: the one the
    person means; None lets the drawing decide; ``views``: more drawings of the same
    tree, each with its yaw in degrees relative to ``image``)."""
    cmd = [str(treesketch), "predict", str(image), "--out", str(outputs.glb)]
    for path, yaw in views:
        cmd += ["--view", f"{path}@{float(yaw):g}"]
    cmd += ["--params", str(outputs.params), "--preset", str(outputs.preset)]
    cmd += ["--outlines", str(outputs.outlines)]
    if not refine:
        cmd.append("--no-refine")
    else:  # without a refinement the first estimate is the result: nothing to preview
        cmd += ["--preview", str(outputs.preview)]
        if budget is not None:
            cmd += ["--budget", str(int(budget))]
    if max_faces is not None:
        cmd += ["--max-faces", str(int(max_faces))]
    if species:
        cmd += ["--species", str(species)]
    return cmd


def run_cli(
    cmd: Sequence[str],
    on_line: Callable[[str], None] | None = None,
    cancel: Callable[[], bool] | None = None,
    timeout: float = 600.0,
) -> None:
    """Run the CLI, passing each output line to ``on_line``; raise :class:`PredictError`
    with its last lines when it fails, is cancelled or runs past ``timeout`` seconds."""
    exe = Path(cmd[0])
    if not exe.is_file():
        raise PredictError(
            f"TreeSketch CLI not found at {exe}: set it in the add-on preferences "
            "(the 'treesketch' program inside the project's .venv/bin)"
        )
    # a live progress bar although the output is a pipe (rich redraws it with \r and
    # cursor codes; the codes are stripped below, \r ends a line in text mode)
    env = {
        **os.environ,
        "PYTHONUNBUFFERED": "1",
        "COLUMNS": "100",
        "TTY_INTERACTIVE": "1",
        "TTY_COMPATIBLE": "1",
        "NO_COLOR": "1",
    }
    proc = subprocess.Popen(
        list(cmd),
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        bufsize=1,
        env=env,
    )
    tail: list[str] = []
    assert proc.stdout is not None
    start = time.monotonic()
    for raw in proc.stdout:
        for part in raw.replace("\r", "\n").splitlines():
            line = " ".join(_ANSI.sub("", part).split())
            if line:
                tail = (tail + [line])[-8:]
                if on_line is not None:
                    on_line(line)
        if (cancel is not None and cancel()) or time.monotonic() - start > timeout:
            proc.kill()
            proc.wait()
            raise PredictError("prediction cancelled" if cancel and cancel() else "timed out")
    if proc.wait() != 0:
        raise PredictError("treesketch predict failed:\n" + "\n".join(tail))


def multipart_body(
    field: str, filename: str, data: bytes, fields: dict[str, str]
) -> tuple[bytes, str]:
    """(body, content type) of a multipart/form-data request with one file."""
    boundary = uuid.uuid4().hex
    parts = []
    for name, value in fields.items():
        parts.append(
            f'--{boundary}\r\nContent-Disposition: form-data; name="{name}"\r\n\r\n{value}\r\n'.encode()
        )
    parts.append(
        (
            f'--{boundary}\r\nContent-Disposition: form-data; name="{field}"; '
            f'filename="{filename}"\r\nContent-Type: image/png\r\n\r\n'
        ).encode()
        + data
        + b"\r\n"
    )
    parts.append(f"--{boundary}--\r\n".encode())
    return b"".join(parts), f"multipart/form-data; boundary={boundary}"


MAX_REPLY_BYTES = 1024 * 1024  # the service's JSON answer
MAX_GLB_BYTES = 512 * 1024 * 1024  # the biggest tree (6 M triangles, textured) is far less
MAX_PRESET_BYTES = 1_000_000  # as the project's own parameter reader
MAX_OUTLINES_BYTES = 16 * 1024 * 1024  # a 256 px picture per view is some 10 KB
_CHUNK = 1024 * 1024


def _origin(url: str) -> tuple[str, str, int]:
    """(scheme, host, port) of an http(s) URL; PredictError for any other URL."""
    parts = urllib.parse.urlsplit(url)
    scheme = parts.scheme.lower()
    if scheme not in ("http", "https") or not parts.hostname:
        raise PredictError(f"the service URL must be http:// or https:// and a host, got {url!r}")
    try:
        port = parts.port or (443 if scheme == "https" else 80)
    except ValueError:
        raise PredictError(f"the service URL has a bad port: {url!r}") from None
    return scheme, parts.hostname.lower(), port


def _opener(origin: tuple[str, str, int]) -> urllib.request.OpenerDirector:
    """An opener that speaks http(s) only (no ``file:``, ``ftp:`` or ``data:`` handler,
    unlike ``urlopen``'s) and follows a redirect only within ``origin``."""

    class SameOrigin(urllib.request.HTTPRedirectHandler):
        def redirect_request(self, req, fp, code, msg, headers, newurl):  # noqa: ANN001
            target = urllib.parse.urljoin(req.full_url, newurl)
            if _safe_origin(target) != origin:
                raise PredictError(
                    f"the service redirected to {target!r}, away from the configured service"
                )
            return super().redirect_request(req, fp, code, msg, headers, newurl)

    opener = urllib.request.OpenerDirector()
    for handler in (
        urllib.request.ProxyHandler(),
        urllib.request.HTTPHandler(),
        urllib.request.HTTPSHandler(),
        urllib.request.HTTPDefaultErrorHandler(),
        SameOrigin(),
        urllib.request.HTTPErrorProcessor(),
    ):
        opener.add_handler(handler)
    return opener


def _safe_origin(url: str) -> tuple[str, str, int] | None:
    try:
        return _origin(url)
    except PredictError:
        return None


def _read_capped(resp, limit: int, what: str, sink=None) -> bytes:  # noqa: ANN001
    """The body of ``resp``, refused past ``limit`` bytes (by its Content-Length at once,
    else while it streams); written to ``sink`` chunk by chunk when one is given."""
    declared = resp.headers.get("Content-Length")
    if declared is not None and declared.strip().isdigit() and int(declared) > limit:
        raise PredictError(f"{what} is {int(declared):,} bytes, over the limit of {limit:,}")
    chunks, total = [], 0
    while chunk := resp.read(_CHUNK):
        total += len(chunk)
        if total > limit:
            raise PredictError(f"{what} is over the limit of {limit:,} bytes")
        if sink is None:
            chunks.append(chunk)
        else:
            sink.write(chunk)
    return b"".join(chunks)


def _http_error(exc: urllib.error.HTTPError) -> str:
    """``STATUS detail`` from the service's JSON error body (read capped)."""
    try:
        body = json.loads(exc.read(64 * 1024) or b"{}")
        detail = body.get("detail") if isinstance(body, dict) else None
    except (OSError, ValueError):
        detail = None
    return f"{exc.code} {detail or exc.reason}"


def post_predict(
    url: str,
    image: str | os.PathLike[str],
    glb_path: str | os.PathLike[str],
    *,
    refine: bool = True,
    budget: int | None = None,
    timeout: float = 600.0,
    token: str | None = None,
    max_glb_bytes: int = MAX_GLB_BYTES,
    species: str | None = None,
    outlines_path: str | os.PathLike[str] | None = None,
) -> dict:
    """``POST {url}/predict`` with the drawing; writes the returned GLB to ``glb_path``
    (whole or not at all) and returns the service's JSON (its ``species_text`` says the
    species in words).  ``token``: the service's token, sent as ``Authorization:
    Bearer``; ``species``: the one the person means (None lets the drawing decide);
    ``outlines_path``: where the job's outlines picture goes (its ``links``'
    ``outlines.png``), when the service has one (see :func:`_fetch_outlines`)."""
    origin = _origin(url)
    headers = {}
    if token:
        if any(c in token for c in "\r\n") or token != token.strip():
            raise PredictError("the service token must be one line without spaces around it")
        headers["Authorization"] = f"Bearer {token}"
    fields = {"refine": "true" if refine else "false"}
    if budget is not None:
        fields["budget"] = str(int(budget))
    if species:
        fields["species"] = str(species)
    body, ctype = multipart_body("sketch", Path(image).name, Path(image).read_bytes(), fields)
    base = url.rstrip("/") + "/"
    opener = _opener(origin)
    req = urllib.request.Request(
        urllib.parse.urljoin(base, "predict"),
        data=body,
        headers={"Content-Type": ctype, **headers},
    )
    glb_path = Path(glb_path)
    part = glb_path.with_name(glb_path.name + ".part")
    try:
        with opener.open(req, timeout=timeout) as resp:
            reply = json.loads(_read_capped(resp, MAX_REPLY_BYTES, "the service's answer"))
        if not isinstance(reply, dict) or not isinstance(reply.get("glb"), str):
            raise PredictError(f"TreeSketch service at {url}: its answer names no GLB")
        glb_url = urllib.parse.urljoin(base, reply["glb"])
        if _safe_origin(glb_url) != origin:
            raise PredictError(
                f"TreeSketch service at {url}: the GLB's address {glb_url!r} is not on the "
                "configured service; not followed"
            )
        glb_req = urllib.request.Request(glb_url, headers=headers)
        with opener.open(glb_req, timeout=timeout) as resp, open(part, "wb") as sink:
            _read_capped(resp, max_glb_bytes, "the GLB", sink)
        os.replace(part, glb_path)
        if outlines_path is not None:
            _fetch_outlines(opener, base, origin, reply, headers, Path(outlines_path), timeout)
    except urllib.error.HTTPError as exc:
        raise PredictError(f"TreeSketch service at {url}: {_http_error(exc)}") from None
    except (OSError, ValueError) as exc:
        raise PredictError(f"TreeSketch service at {url}: {exc}") from None
    finally:
        part.unlink(missing_ok=True)
    return reply


def _fetch_outlines(
    opener: urllib.request.OpenerDirector,
    base: str,
    origin: tuple[str, str, int],
    reply: dict,
    headers: dict,
    path: Path,
    timeout: float,
) -> None:
    """The job's outlines picture (``reply["links"]["outlines.png"]``) written to
    ``path``, from the configured service only.  A convenience: a service without it (an
    older one), another origin, an error or a picture over the cap leave no file and
    never cost the tree."""
    links = reply.get("links")
    link = links.get("outlines.png") if isinstance(links, dict) else None
    if not isinstance(link, str):
        return
    target = urllib.parse.urljoin(base, link)
    if _safe_origin(target) != origin:
        return
    try:
        with opener.open(urllib.request.Request(target, headers=headers), timeout=timeout) as resp:
            data = _read_capped(resp, MAX_OUTLINES_BYTES, "the outlines picture")
    except (OSError, PredictError):  # HTTPError is an OSError
        return
    if data.startswith(b"\x89PNG"):  # whole or not at all, as the GLB
        part = path.with_name(path.name + ".part")
        part.write_bytes(data)
        os.replace(part, path)


def read_preset(path: str | os.PathLike[str]) -> tuple[dict, float]:
    """(Sapling's keyword arguments, view yaw in degrees) from a TreeSketch preset: the
    first line not starting with '#', read as Sapling reads it (a literal, never run).
    Any fault (too large, not text, not a literal, not a dict) is a PredictError, which
    the operator reports; nothing else escapes."""
    yaw = 0.0
    settings = None
    try:
        size = os.path.getsize(path)
        if size > MAX_PRESET_BYTES:
            raise PredictError(f"{path}: {size:,} bytes is too large for a preset")
        with open(path, encoding="utf-8") as fh:
            for line in fh:
                m = _YAW.match(line)
                if m:
                    yaw = float(m.group(1))
                if settings is None and line.strip() and not line.startswith("#"):
                    settings = ast.literal_eval(line.strip())
    except (OSError, ValueError, SyntaxError, MemoryError, RecursionError) as exc:
        # SyntaxError: not a literal; ValueError: not only literals, a bad yaw, not UTF-8
        reason = exc.msg if isinstance(exc, SyntaxError) else (str(exc) or type(exc).__name__)
        raise PredictError(f"{path}: not a Sapling preset TreeSketch can read ({reason})") from None
    if not isinstance(settings, dict):
        raise PredictError(f"{path}: no Sapling dictionary in the preset")
    return settings, yaw


def _png(gray: np.ndarray) -> bytes:
    """A greyscale uint8 image as PNG bytes (no imaging library needed)."""
    h, w = gray.shape
    raw = b"".join(b"\x00" + gray[y].tobytes() for y in range(h))

    def chunk(kind: bytes, data: bytes) -> bytes:
        return (
            struct.pack(">I", len(data))
            + kind
            + data
            + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)
        )

    head = struct.pack(">IIBBBBB", w, h, 8, 0, 0, 0, 0)
    return (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", head)
        + chunk(b"IDAT", zlib.compress(raw, 6))
        + chunk(b"IEND", b"")
    )


def strokes_png(strokes: Iterable[np.ndarray], size: int = 512, pen: float = 2.0) -> bytes:
    """Pen strokes (each (n, 2): x right, y up, any units) drawn black on white, scaled
    so the drawing fills about 85 % of the canvas height, centred, base near the bottom."""
    strokes = [np.asarray(s, dtype=np.float64).reshape(-1, 2) for s in strokes]
    strokes = [s for s in strokes if len(s)]
    if not strokes:
        raise PredictError("the drawing is empty: draw the tree with the Grease Pencil first")
    pts = np.vstack(strokes)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    extent = max(float((hi - lo).max()), 1e-9)
    scale = 0.85 * size / extent
    centre_x = (lo[0] + hi[0]) / 2.0
    img = np.full((size, size), 255, dtype=np.uint8)
    r = int(np.ceil(pen))
    oy, ox = np.mgrid[-r : r + 1, -r : r + 1]
    disc = (ox * ox + oy * oy) <= pen * pen
    ox, oy = ox[disc], oy[disc]  # pixel offsets of the pen's tip
    for s in strokes:
        px = (s[:, 0] - centre_x) * scale + size / 2.0
        py = size * 0.96 - (s[:, 1] - lo[1]) * scale
        if len(s) == 1:
            px, py = np.repeat(px, 2), np.repeat(py, 2)
        # samples every half pixel along each segment, the pen stamped at each
        seg = np.hypot(np.diff(px), np.diff(py))
        n = np.maximum(np.ceil(seg / 0.5).astype(int), 1)
        i = np.repeat(np.arange(len(n)), n)
        t = np.arange(len(i)) - np.repeat(np.cumsum(n) - n, n)
        t = t / np.repeat(n, n)
        sx = np.append(px[i] + (px[i + 1] - px[i]) * t, px[-1])
        sy = np.append(py[i] + (py[i + 1] - py[i]) * t, py[-1])
        cx = np.rint(sx).astype(np.int64)[:, None] + ox[None]
        cy = np.rint(sy).astype(np.int64)[:, None] + oy[None]
        ok = (cx >= 0) & (cx < size) & (cy >= 0) & (cy < size)
        img[cy[ok], cx[ok]] = 0
    return _png(img)


# Blender's views of a tree standing on +Z -> (yaw in degrees relative to the Front view,
# the world axis (x, y) that points right on the screen).  The project's yaw turns the
# camera about the trunk, counter-clockwise seen from above (``render.camera``: yaw 0
# looks along +Y, image right +X; yaw 90 looks along -X, image right +Y): Blender's Right
# view (numpad 3) is yaw 90; ``render.camera.VIEWS`` calls that side "left", the tree's
# own left as it faces the Front view.
VIEWS: dict[str, tuple[float, tuple[float, float]]] = {
    "front": (0.0, (1.0, 0.0)),
    "right": (90.0, (0.0, 1.0)),
    "back": (180.0, (-1.0, 0.0)),
    "left": (270.0, (0.0, -1.0)),
}


def view_layers(names: Iterable[str]) -> list[tuple[str, str]]:
    """The layers named after a view (any case, surrounding spaces ignored), as (layer
    name, view) in the order the prediction takes them: Front first, then Right, Back,
    Left.  None named so: [] (the whole drawing is one view from the front).  Views named
    without a Front, or one view named twice, are a PredictError."""
    found: dict[str, str] = {}
    for name in names:
        view = name.strip().lower()
        if view in VIEWS:
            if view in found:
                raise PredictError(
                    f"two Grease Pencil layers are the {view.title()} view: "
                    f"{found[view]!r} and {name!r}; keep one"
                )
            found[view] = name
    if found and "front" not in found:
        raise PredictError(
            f"the Grease Pencil layers name the {', '.join(v.title() for v in found)} view but "
            "no Front: draw the tree in a layer named Front too (the views are turned from it)"
        )
    return [(found[v], v) for v in VIEWS if v in found]


_FRACTION = re.compile(r"(\d+)\s*/\s*(\d+)")


def progress_fraction(line: str) -> float | None:
    """The done fraction a CLI progress line shows ('... 12/40 ...'), if any."""
    m = _FRACTION.search(line)
    if not m or int(m.group(2)) == 0:
        return None
    return min(int(m.group(1)) / int(m.group(2)), 1.0)


PREVIEW_EVERY = 2.0  # seconds between two previews shown (the first shows at once)


class PreviewWatch:
    """When to show the CLI's preview tree (``--preview DIR``: ``DIR/tree.glb``, replaced
    whole each time): :meth:`poll` returns the file when it is new since the last one
    shown and at least ``every`` seconds have passed since then, else None.  The CLI
    writes at most one every 2 s itself; the add-on's own pause keeps a slow import
    from following a fast refinement tree by tree."""

    def __init__(self, folder: str | os.PathLike[str], every: float = PREVIEW_EVERY) -> None:
        self.path = Path(folder) / "tree.glb"
        self.every = float(every)
        self.seen: tuple[int, int] | None = None  # (mtime_ns, size) of the last shown
        self.last = -float("inf")
        self.shown = 0  # previews returned so far

    def poll(self, now: float | None = None) -> Path | None:
        now = time.monotonic() if now is None else now
        if now - self.last < self.every:
            return None
        try:
            st = self.path.stat()
        except OSError:
            return None
        stamp = (st.st_mtime_ns, st.st_size)
        if stamp == self.seen:
            return None
        self.seen, self.last = stamp, now
        self.shown += 1
        return self.path


MAX_GLB_JSON_BYTES = 16 * 1024 * 1024


def glb_textures(path: str | os.PathLike[str]) -> dict[str, bytes]:
    """{material name: the image bytes of its base colour texture} of a binary glTF
    (what our exporter writes: ``bark`` and ``leaf``, PNGs inside the file).  A material
    without a texture is left out; a file that is not a GLB is a PredictError."""
    try:
        data = Path(path).read_bytes()
        magic, _version, length = struct.unpack_from("<4sII", data, 0)
        if magic != b"glTF" or length > len(data):
            raise ValueError("not a binary glTF")
        n, kind = struct.unpack_from("<I4s", data, 12)
        if kind != b"JSON" or n > MAX_GLB_JSON_BYTES:
            raise ValueError("no JSON chunk first")
        doc = json.loads(data[20 : 20 + n])
        binary = b""
        at = 20 + ((n + 3) & ~3)
        if at + 8 <= len(data):
            m, kind = struct.unpack_from("<I4s", data, at)
            if kind == b"BIN\x00":
                binary = data[at + 8 : at + 8 + m]
        out = {}
        for mat in doc.get("materials", []):
            ref = mat.get("pbrMetallicRoughness", {}).get("baseColorTexture")
            if ref is None:
                continue
            image = doc["images"][doc["textures"][ref["index"]]["source"]]
            view = doc["bufferViews"][image["bufferView"]]
            start = view.get("byteOffset", 0)
            out[str(mat.get("name", f"material{len(out)}"))] = binary[
                start : start + view["byteLength"]
            ]
    except (OSError, ValueError, KeyError, IndexError, TypeError, struct.error) as exc:
        raise PredictError(f"{path}: cannot read the textures of the GLB ({exc})") from None
    return out


def numpy_bool_alias() -> bool:
    """Give numpy its old ``bool`` alias back when it lacks it (Blender 3.4's glTF importer
    uses ``np.bool``, removed in numpy 1.24); True when it was added now."""
    if "bool" in np.__dict__:
        return False
    np.bool = bool  # type: ignore[attr-defined]
    return True


def plain_error(exc: BaseException) -> str:
    """One line for a person: an operator's "Error: Python: Traceback ..." becomes its last
    line ("AttributeError: module 'numpy' has no attribute 'bool'" -> that sentence
    without the exception's class name)."""
    lines = [ln.strip() for ln in str(exc).splitlines() if ln.strip()]
    if not lines:
        return type(exc).__name__
    if any("Traceback" in ln for ln in lines):
        last = lines[-1]
        for prefix in ("Error: ", "Python: "):
            last = last.removeprefix(prefix)
        return _ERROR_LINE.sub("", last) or last
    first = lines[0]
    for prefix in ("Error: ", "Python: "):
        first = first.removeprefix(prefix)
    return first


def species_of(lines: Iterable[str]) -> str | None:
    """The species ``treesketch predict`` printed ("species: maple (first estimate: ...)")."""
    for line in lines:
        m = _SPECIES.match(line)
        if m:
            return m.group(1)
    return None


def species_text_of(lines: Iterable[str]) -> str | None:
    """The species in words ``treesketch predict`` printed ("it is a palm (87%); could
    also be a cherry" -> "a palm (87%); could also be a cherry")."""
    for line in lines:
        m = _SPECIES_TEXT.match(line)
        if m:
            return m.group(1)
    return None


def preset_name(species: str | None, taken: Iterable[str]) -> str:
    """A Sapling preset file name no earlier prediction has: treesketch_<species>_<n>.py
    with the first free n."""
    stem = f"treesketch_{species or 'tree'}"
    used = set(taken)
    n = 1
    while f"{stem}_{n}.py" in used:
        n += 1
    return f"{stem}_{n}.py"


def load_controls(path: str | os.PathLike[str]) -> dict:
    """The controls table the zip carries (``{"controls": [...], "default_budget": n}``);
    an empty table when the file is missing (an add-on run from the source folder)."""
    p = Path(path)
    if not p.is_file():
        return {"controls": [], "default_budget": None}
    return json.loads(p.read_text(encoding="utf-8"))


def load_species(path: str | os.PathLike[str]) -> list[dict]:
    """The species a person may pick, as the zip carries them (``species.json``:
    ``{"species": [{"name", "display", "paper"}, ...]}``); none when the file is missing
    (an add-on run from the source folder: the drawing decides)."""
    p = Path(path)
    if not p.is_file():
        return []
    return list(json.loads(p.read_text(encoding="utf-8"))["species"])


def keep_value(row: dict):
    """The panel's value of a control that leaves the predicted tree as it is: a relative
    control's neutral value; for the others a sentinel (height 0, seed -1, a choice
    "KEEP", a toggle on)."""
    if row.get("neutral") is not None:
        return row["neutral"]
    if row["kind"] == "toggle":
        return True
    if row["kind"] == "choice":
        return "KEEP"
    return -1 if row["kind"] == "integer" else 0.0


def changed_controls(rows: Iterable[dict], values: dict) -> dict:
    """The controls whose panel value is not their keep value (numbers within half a
    step of it count as kept)."""
    out = {}
    for row in rows:
        v, keep = values[row["name"]], keep_value(row)
        if row["kind"] in ("toggle", "choice") or row.get("neutral") is None:
            if v != keep:
                out[row["name"]] = v
        elif abs(float(v) - float(keep)) > float(row["step"]) / 2:
            out[row["name"]] = v
    return out


def _text(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return f"{v:.6g}"
    return str(v)


def grow_command(
    treesketch: str | os.PathLike[str],
    params: str | os.PathLike[str],
    outputs: Outputs,
    controls: dict,
) -> list[str]:
    """``treesketch grow --params P --set NAME=VALUE ...`` writing the GLB, the parameters
    and the Sapling preset of the edited tree."""
    cmd = [str(treesketch), "grow", "--params", str(params), "--out", str(outputs.glb)]
    cmd += ["--save-params", str(outputs.params), "--preset", str(outputs.preset)]
    for name, value in controls.items():
        cmd += ["--set", f"{name}={_text(value)}"]
    return cmd


def post_trees(
    url: str,
    params: dict,
    controls: dict,
    species: str | None,
    outputs: Outputs,
    timeout: float = 120.0,
) -> None:
    """The service's ``POST /trees``: the edited tree's parameters (JSON) and its GLB at
    full detail written to ``outputs``."""
    body = {"params": params, "controls": controls, "species": species, "max_faces": None}
    endpoint = urllib.parse.urljoin(url.rstrip("/") + "/", "trees")
    data = json.dumps(body).encode()
    try:
        for accept, path in (
            ("application/json", outputs.params),
            ("model/gltf-binary", outputs.glb),
        ):
            req = urllib.request.Request(
                endpoint,
                data=data,
                headers={"Content-Type": "application/json", "Accept": accept},
            )
            with urllib.request.urlopen(req, timeout=timeout) as resp:
                reply = resp.read()
            if accept == "application/json":
                reply = json.dumps(json.loads(reply)["params"]).encode()
            Path(path).write_bytes(reply)
    except urllib.error.HTTPError as exc:
        detail = exc.read().decode(errors="replace")
        with contextlib.suppress(ValueError, KeyError, TypeError):
            detail = json.loads(detail)["detail"]
        raise PredictError(f"TreeSketch service at {url} refused the edit: {detail}") from None
    except (OSError, ValueError, KeyError) as exc:
        raise PredictError(f"TreeSketch service at {url}: {exc}") from None
