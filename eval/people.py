"""Drawings by people, read from ``../shared/people_doodles/`` (never copied into the project).

Three sources (the folder's README has their formats and licences):

- ``strokes``: one drawing of each of 8 things by each of 590 people, as strokes on a web
  canvas; drawn here as lines 3 px wide on white, as the person saw them.
- ``mouse224``: trees, houses and persons drawn with a mouse, 224 px PNGs.
- ``quickdraw28``: Quick, Draw! doodles as 28 x 28 grey bitmaps (255 = ink), inverted and
  enlarged smoothly to 224 px (the reader takes them as pencil on paper).

Every drawing goes to one *part*, ``"fit"`` or ``"held"``, by a hash of who drew it: a
``strokes`` author's every drawing lands on one side (a person's tree and their car go
together), and the two sources without authors split by the drawing's own name.  The held
part (about one in five) is never trained or fitted on; benchmarks measure there.

"Is this a tree?" is also measured on kinds of things a detector was never fitted on:
:data:`LEFT_OUT_KINDS` are left out of the fitting of the detector that is measured that
way (``scripts/fit_people.py``).
"""

from __future__ import annotations

import json
import os
import zlib
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np
from PIL import Image, ImageDraw

__all__ = [
    "HELD_EVERY",
    "LEFT_OUT_KINDS",
    "PeopleDrawing",
    "SOURCES",
    "draw_strokes",
    "people_drawings",
    "people_root",
]

ENV_ROOT = "TREESKETCH_PEOPLE_DOODLES"
SOURCES = ("strokes", "mouse224", "quickdraw28")
#: One drawing (or author) in this many goes to the held part.
HELD_EVERY = 5
#: Kinds of things the leave-categories-out detector never sees (the folder's README's
#: suggestion): measured on them, it shows how "is this a tree?" meets new kinds.
LEFT_OUT_KINDS = ("bicycle", "guitar", "pencil", "person", "rainbow", "train", "flower")
STROKE_WIDTH = 3  # px on the person's canvas (about 400-500 px wide)
QUICKDRAW_SIDE = 224


def people_root() -> Path:
    """The folder of people's drawings: ``$TREESKETCH_PEOPLE_DOODLES`` or
    ``../shared/people_doodles`` beside the project."""
    env = os.environ.get(ENV_ROOT)
    return Path(env) if env else Path(__file__).resolve().parents[2] / "shared" / "people_doodles"


def part_of(source: str, key: str) -> str:
    """``"held"`` or ``"fit"``, a stable hash of who (or what) drew it."""
    h = zlib.crc32(f"{source}:{key}".encode() if source != "strokes" else key.encode())
    return "held" if h % HELD_EVERY == 0 else "fit"


def draw_strokes(
    strokes: Sequence[Sequence[Sequence[float]]], width: int = STROKE_WIDTH
) -> np.ndarray:
    """Strokes (lists of ``[x, y]`` canvas pixels, y down) as dark lines on a white page
    just large enough to hold them: ``(H, W)`` uint8, 255 paper."""
    pts = [np.asarray(s, dtype=np.float64).reshape(-1, 2) for s in strokes if len(s)]
    if not pts:
        raise ValueError("a drawing without strokes")
    allp = np.concatenate(pts)
    lo = allp.min(axis=0) - 2 * width
    size = np.ceil(allp.max(axis=0) - lo + 2 * width).astype(int)
    im = Image.new("L", (int(size[0]), int(size[1])), 255)
    d = ImageDraw.Draw(im)
    for s in pts:
        xy = [tuple(p) for p in s - lo]
        if len(xy) == 1:
            xy = xy * 2
        d.line(xy, fill=0, width=width, joint="curve")
    return np.asarray(im, dtype=np.uint8)


@dataclass(frozen=True)
class PeopleDrawing:
    """One person's drawing: where it comes from, what it shows, who drew it."""

    source: str  # one of SOURCES
    kind: str  # "tree", "car", ...
    key: str  # the author (strokes), the file's name (mouse224) or the row (quickdraw28)
    data: Any  # strokes, a path, or a (28, 28) array; see :meth:`image`

    @property
    def part(self) -> str:
        return part_of(self.source, self.key)

    @property
    def is_tree(self) -> bool:
        return self.kind == "tree"

    @cached_property
    def name(self) -> str:
        return f"{self.source}/{self.kind}/{self.key}"

    def image(self) -> Any:
        """The drawing as the pipeline's reader takes it: an array (255 paper) or a path."""
        if self.source == "strokes":
            return draw_strokes(self.data)
        if self.source == "mouse224":
            return self.data
        big = Image.fromarray(255 - np.asarray(self.data, np.uint8)).resize(
            (QUICKDRAW_SIDE, QUICKDRAW_SIDE), Image.Resampling.BICUBIC
        )
        return np.asarray(big, dtype=np.uint8)


def _strokes(root: Path) -> Iterator[PeopleDrawing]:
    for path in sorted((root / "strokes").glob("*.ndjson")):
        with path.open() as f:
            for line in f:
                row = json.loads(line)
                # an author who drew twice (two sessions) has both drawings on one side
                yield PeopleDrawing("strokes", path.stem, str(row["author"]), row["strokes"])


def _mouse(root: Path) -> Iterator[PeopleDrawing]:
    for folder in sorted(p for p in (root / "mouse224").iterdir() if p.is_dir()):
        for path in sorted(folder.glob("*.png"), key=lambda p: (len(p.stem), p.stem)):
            yield PeopleDrawing("mouse224", folder.name, f"{folder.name}/{path.stem}", path)


def _quickdraw(root: Path) -> Iterator[PeopleDrawing]:
    for path in sorted((root / "quickdraw28").glob("*.npy")):
        arr = np.load(path, mmap_mode="r")
        for i in range(len(arr)):
            yield PeopleDrawing("quickdraw28", path.stem, f"{path.stem}/{i}", np.array(arr[i]))


def people_drawings(
    part: str | None = None,
    sources: Sequence[str] = SOURCES,
    kinds: Sequence[str] | None = None,
    per_kind: int | None = None,
    root: str | os.PathLike[str] | None = None,
) -> list[PeopleDrawing]:
    """People's drawings of one ``part`` (``"fit"``, ``"held"`` or None for both), from
    ``sources``, of ``kinds`` (None: all), at most ``per_kind`` of each (source, kind)
    taken in the folder's order."""
    if part not in (None, "fit", "held"):
        raise ValueError(f"part must be 'fit', 'held' or None, not {part!r}")
    unknown = sorted(set(sources) - set(SOURCES))
    if unknown:
        raise ValueError(f"unknown source(s) {unknown}; one of {', '.join(SOURCES)}")
    base = Path(root) if root is not None else people_root()
    if not base.is_dir():
        raise FileNotFoundError(f"people's drawings not found at {base} (set ${ENV_ROOT})")
    readers = {"strokes": _strokes, "mouse224": _mouse, "quickdraw28": _quickdraw}
    out: list[PeopleDrawing] = []
    counts: dict[tuple[str, str], int] = {}
    for source in sources:
        for d in readers[source](base):
            if (kinds is not None and d.kind not in kinds) or (part and d.part != part):
                continue
            n = counts.get((source, d.kind), 0)
            if per_kind is not None and n >= per_kind:
                continue
            counts[(source, d.kind)] = n + 1
            out.append(d)
    return out
