"""A running job's current best tree, written for the page while the refinement runs.

The pipeline tells its progress callback of the current best tree (``Progress.params``,
``version``): the first estimate as soon as it exists, then each better tree the search
finds.  :class:`PreviewWriter` writes the first one at once and then at most one every
:data:`PREVIEW_EVERY` seconds (a tree that waits is written at the next report after
the pause, so the latest one always shows): ``results/<id>/preview/tree.glb`` (light,
``treesketch.trees.VIEW_FACES``) and ``preview/sketch.png``.  It returns the version it
wrote, which the progress the API shows carries as ``preview``.  Without a folder (a Ray
actor, whose node shares no disk with the front) it only keeps the latest files
(``files``), which the actor hands to the front with its progress.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

from weberpenn.fileio import write_together

__all__ = ["PREVIEW_EVERY", "PREVIEW_FILES", "PreviewWriter"]

PREVIEW_EVERY = 2.0  # seconds between two previews of one job (the first is at once)
PREVIEW_FILES = {"tree.glb": "model/gltf-binary", "sketch.png": "image/png"}


class PreviewWriter:
    """``offer(progress)`` -> the version written now, or None."""

    def __init__(self, folder: Path | None, every: float = PREVIEW_EVERY) -> None:
        self.folder = None if folder is None else Path(folder)
        self.every = float(every)
        self.written = 0
        self.last = -float("inf")
        self.files: dict[str, bytes] = {}  # the latest preview's, by name in PREVIEW_FILES

    def offer(self, p: Any) -> int | None:
        version = int(getattr(p, "version", 0) or 0)
        if version <= self.written or p.params is None:
            return None
        if time.monotonic() - self.last < self.every:
            return None
        self._write(p)
        self.written, self.last = version, time.monotonic()
        return version

    def _write(self, p: Any) -> None:
        from treesketch.outputs import png_bytes
        from treesketch.trees import light_glb, tree_sketch
        from weberpenn import build_mesh, grow

        mesh = build_mesh(grow(p.params), species=p.species)
        glb = light_glb(mesh, yaw=float(p.yaw))
        sketch = png_bytes(tree_sketch(p.params, p.species, float(p.yaw)))
        self.files = {"tree.glb": glb, "sketch.png": sketch}
        if self.folder is not None:
            self.folder.mkdir(parents=True, exist_ok=True)
            write_together({self.folder / name: data for name, data in self.files.items()})
