"""What a worker does with one job: the pipeline run and the artefact files.

This is the only module of the service that touches the pipeline, through the seam:
``treesketch.Pipeline(estimator, settings).run(sketch, height, progress, cancel)`` and
``treesketch.result_files``.  A :class:`Runner` loads its estimator once per worker
process; ``Runner.run`` turns a job's stored drawings (one, or several views of the tree
whose yaws are in the options) and its options into artefact bytes and the result's
summary.

An estimator ``spec`` is whatever ``treesketch.load_estimator`` takes (``"tsn"``,
``"template"``, a checkpoint path) or ``"package.module:name"`` naming an estimator
object or class (how tests and researchers plug in their own without touching the
service).
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from refine.search import DEFAULT_BUDGET
from treesketch.views import MAX_VIEWS

__all__ = [
    "ARTEFACTS",
    "VIEW_ARTEFACTS",
    "VIEW_GLB",
    "JobOptions",
    "Runner",
    "load_estimator_spec",
    "outlines_file",
    "view_artefacts",
]

# file name -> (output kind of treesketch.result_files, media type), in the page's order
ARTEFACT_KINDS: dict[str, tuple[str, str]] = {
    "tree.glb": ("glb", "model/gltf-binary"),
    "tree.json": ("json", "application/json"),
    "tree_sapling.py": ("preset", "text/x-python"),
    "compare.png": ("compare", "image/png"),
    "sketch_before.png": ("sketch_before", "image/png"),
    "sketch_after.png": ("sketch_after", "image/png"),
    # the result's candidate species as sketches to pick from, best first (the summary's
    # "candidates" holds their species, probabilities and parameters)
    **{f"candidate{i}.png": (f"candidate{i}", "image/png") for i in (1, 2, 3)},
}
# the viewer's tree: at most ``treesketch.trees.VIEW_FACES`` triangles (tree.glb is the
# download, at the job's own max_faces)
VIEW_GLB = "tree_view.glb"
ARTEFACTS: dict[str, str] = {name: media for name, (_, media) in ARTEFACT_KINDS.items()} | {
    VIEW_GLB: "model/gltf-binary"
}


def view_artefacts(view: int) -> tuple[str, str]:
    """The file names of view ``view``'s (2 and up) first-estimate and result sketches."""
    return f"view{view}_before.png", f"view{view}_after.png"


def outlines_file(view: int) -> str:
    """The file name of view ``view``'s (1 and up) outlines picture: the drawing's outline
    (red) over the tree's (blue), served by ``GET /jobs/{id}/outlines.png?view=N``
    (``outlines.py``), not by the artefact route."""
    return "outlines.png" if view == 1 else f"view{view}_outlines.png"


# a job of several drawings also has each later view's sketches (view 1's are
# sketch_before.png and sketch_after.png)
VIEW_ARTEFACTS: dict[str, str] = {
    name: "image/png" for v in range(2, MAX_VIEWS + 1) for name in view_artefacts(v)
}


@dataclass(frozen=True)
class JobOptions:
    """A job's options, validated (see ``limits.parse_options``)."""

    refine: bool = True
    budget: int = DEFAULT_BUDGET
    time_limit: float | None = 50.0
    height: float | None = None
    estimator: str = "tsn"  # a spec the server allows
    max_faces: int | None = None  # the exported tree's triangle budget (weberpenn.lod)
    species: str | None = None  # the species the user means (None: the drawing decides)
    # the yaw of each drawing after the first, relative to it (None: searched); () for
    # a job of one drawing
    yaws: tuple[float | None, ...] = ()

    @property
    def views(self) -> int:
        """How many drawings the job has."""
        return 1 + len(self.yaws)

    def to_dict(self) -> dict[str, Any]:
        d = asdict(self)
        if not self.yaws:  # a job of one drawing is stored and shown as before
            del d["yaws"]
        else:
            d["yaws"] = list(self.yaws)
        return d

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> JobOptions:
        known = {k: v for k, v in d.items() if k in cls.__dataclass_fields__}
        if "yaws" in known:
            known["yaws"] = tuple(known["yaws"])
        return cls(**known)

    def settings(self) -> Any:
        """The pipeline's ``RefineSettings`` for these options (validated)."""
        from treesketch import RefineSettings

        return RefineSettings().replace(
            refine=self.refine, budget=self.budget, time_limit=self.time_limit
        )

    def export(self) -> Any:
        """How the artefacts are exported (``treesketch.outputs.ExportOptions``)."""
        from treesketch.outputs import ExportOptions

        return ExportOptions(max_faces=self.max_faces)


def load_estimator_spec(spec: str) -> Any:
    """An estimator from a spec (see the module text); ValueError when there is none."""
    from treesketch import load_estimator

    if ":" in spec and not Path(spec).exists():
        module, _, name = spec.partition(":")
        obj: Any = importlib.import_module(module)
        for part in name.split("."):
            obj = getattr(obj, part)
        if isinstance(obj, type):
            obj = obj()
        if not hasattr(obj, "estimate"):
            raise ValueError(f"{spec} is not an estimator (it has no estimate method)")
        return obj
    return load_estimator(spec)


class Runner:
    """One worker's pipeline: the default estimator loaded once, at start; another that
    a job asks for (from the server's short allowed list) loaded on first use and kept."""

    def __init__(self, spec: str) -> None:
        self.spec = spec
        self.estimators: dict[str, Any] = {spec: load_estimator_spec(spec)}

    def estimator(self, spec: str) -> Any:
        if spec not in self.estimators:
            self.estimators[spec] = load_estimator_spec(spec)
        return self.estimators[spec]

    def run(
        self,
        sketch: bytes | Sequence[bytes],
        options: JobOptions,
        progress: Callable[[Any], None],
        cancel: Callable[[], bool],
    ) -> tuple[dict[str, bytes], dict[str, Any]]:
        """(artefacts by file name, summary) of one job: ``sketch`` is its drawing, or its
        drawings in order (as many as ``options.views``).  Raises ``treesketch.Cancelled``
        within one evaluation of ``cancel()`` turning True, ``ValueError``
        (``SketchError``) for a sketch or option the pipeline rejects."""
        from treesketch import Pipeline, result_files
        from treesketch.trees import VIEW_FACES, light_glb

        drawings = [sketch] if isinstance(sketch, bytes | bytearray) else list(sketch)
        if len(drawings) != options.views:  # the service's own fault, never the input's
            raise RuntimeError(
                f"the job has {len(drawings)} drawing(s) but {options.views} view(s) in its options"
            )
        # one drawing goes in as it always did; several as the pipeline's list of views
        source: Any = (
            drawings[0]
            if len(drawings) == 1
            else [drawings[0], *zip(drawings[1:], options.yaws, strict=True)]
        )
        pipeline = Pipeline(self.estimator(options.estimator), options.settings())
        result = pipeline.run(
            source,
            height=options.height,
            progress=progress,
            cancel=cancel,
            species=options.species,
        )
        from treesketch.outputs import outlines_images, png_bytes

        kinds = {
            kind: name
            for name, (kind, _) in ARTEFACT_KINDS.items()
            if not kind.startswith("candidate")
        }
        export = options.export()
        files = result_files(result, kinds, export)
        out = {kinds[k]: data for k, data in files.items() if k in kinds}
        out[VIEW_GLB] = light_glb(
            result.tree_mesh,
            yaw=float(result.yaw) if export.face_view else 0.0,
            max_faces=min(VIEW_FACES, options.max_faces or VIEW_FACES),
        )
        for i, c in enumerate(result.candidates[:3], 1):
            if c.sketch is not None:
                out[f"candidate{i}.png"] = png_bytes(c.sketch)
        for i, view in enumerate(result.views[1:], 2):
            before, after = view_artefacts(i)
            out[before] = png_bytes(view.sketch_before)
            out[after] = png_bytes(view.sketch_after)
        # made now, while the prepared drawings are at hand (the job keeps only the
        # uploads): a view without its drawing has none, and its route answers 404
        for i, picture in enumerate(outlines_images(result), 1):
            if picture is not None:
                out[outlines_file(i)] = png_bytes(picture)
        return out, result.summary()
