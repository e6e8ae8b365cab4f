"""`treesketch predict`: a sketch -> first estimate -> refinement -> GLB/OBJ, JSON, preset,
comparison picture.  Every option is checked before any work; the outputs are written all
together or not at all (``treesketch.outputs.write_outputs``)."""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

import typer

from refine.search import DEFAULT_BUDGET, RefineSettings

from .cli_common import (
    checkpoint_option,
    fail,
    max_faces_option,
    preset_option,
    textures_option,
)

if TYPE_CHECKING:
    from .pipeline import Progress, Result

__all__ = ["predict_command", "register"]


# options kept out of the command's signature so it reads as what it does
def _compare_option() -> Any:
    return typer.Option(
        None,
        "--compare",
        help="Also write a PNG: input sketch, first estimate's sketch, refined sketch with "
        "your drawing's outline (red) over the tree's (blue), colour render.",
    )


def _outlines_option() -> Any:
    return typer.Option(
        None,
        "--outlines",
        help="Also write a PNG: your drawing's outline (red) over the tree's (blue), seen "
        "from where you drew it (one picture per drawing, side by side).",
    )


def _embedding_option() -> Any:
    return typer.Option(
        "shipped",
        "--embedding",
        help="The learned style-blind shape embedding the refinement adds to its distance: "
        "shipped (checkpoints/shape_embed.pt), none (the hand-made shape distance alone) or "
        "a checkpoint file.",
    )


def _preview_option() -> Any:
    return typer.Option(
        None,
        "--preview",
        help="While it refines, keep the current best tree in this folder (tree.glb, light, "
        "and sketch.png): the first estimate at once, then at most one every 2 s (the "
        "Blender add-on shows it).",
    )


def predict_command(
    sketch: Path = typer.Argument(
        ..., help="The sketch: a PNG/JPEG of a tree, dark lines on white."
    ),
    out: Path = typer.Option(
        ..., "--out", "-o", help="Mesh file to write: .glb (branches and leaves) or .obj."
    ),
    view: list[str] = typer.Option(
        [],
        "--view",
        help="Another drawing of the same tree from another side, FILE@DEGREES (the turn "
        "about the trunk from the first drawing: side.png@90) or FILE@? (angle not known: "
        "found by the refinement); repeatable (at most 3). Two views pin the tree in depth.",
    ),
    no_refine: bool = typer.Option(
        False, "--no-refine", help="Skip the refinement: TSN's estimate only."
    ),
    budget: int = typer.Option(
        None,
        "--budget",
        help=f"Refinement: most trees to evaluate for the first species (default "
        f"{DEFAULT_BUDGET}; another candidate species gets half as many; under half the "
        f"default, the outline step after the search grows fewer trees too).",
    ),
    time_limit: float = typer.Option(
        None, "--time-limit", help="Refinement: most seconds (default 50)."
    ),
    species_name: str | None = typer.Option(
        None,
        "--species",
        help="The species you mean (maple, pine, bonsai, palm, cherry, fir, willow, oak, "
        "birch, poplar, winter; or a name people use: 'christmas tree', spruce, bare): "
        "only it is refined.",
    ),
    height: float = typer.Option(
        None,
        "--height",
        help="Make the tree this tall (metres); a sketch has no size: without it the tree "
        "keeps the network's size for its species.",
    ),
    params_path: Path | None = typer.Option(
        None, "--params", help="Also write the parameters (JSON)."
    ),
    preset_path: Path | None = preset_option(),
    compare_path: Path | None = _compare_option(),
    outlines_path: Path | None = _outlines_option(),
    estimator: str = typer.Option(
        "tsn", "--estimator", help="First estimate: tsn, template (no network) or nns."
    ),
    checkpoint: Path | None = checkpoint_option(),
    data: Path | None = typer.Option(
        None, "--data", help="Dataset folder (the nns estimator's index)."
    ),
    max_faces: int | None = max_faces_option(),
    face_view: bool = typer.Option(
        True,
        "--face-view/--no-face-view",
        help="Turn the exported tree so its front faces the way it was drawn (the found yaw).",
    ),
    textures: bool = textures_option(),
    summary_path: Path | None = typer.Option(
        None, "--summary", help="Also write a JSON summary: species, scores, distances, yaw."
    ),
    algorithm: str = typer.Option(
        RefineSettings.algorithm, "--algorithm", help="cobyla, bobyqa or sbplx."
    ),
    embedding: str = _embedding_option(),
    preview_dir: Path | None = _preview_option(),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="No progress bar."),
) -> None:
    """Turn a sketch of a tree into a 3D tree: a first estimate (TSN), refined so the
    tree's own sketch matches yours.

    Example: `treesketch predict examples/sketch_maple.png --out tree.glb --compare cmp.png`.
    """
    from weberpenn import species as wp_species

    from .estimators import load_estimator
    from .outputs import ExportOptions, write_outputs
    from .pipeline import Pipeline, SketchError, check_height

    # every option first: nothing is read, estimated or refined before they all pass
    files = (out, params_path, preset_path, compare_path, outlines_path, summary_path)
    outputs = dict(zip(OUTPUT_OPTIONS, files, strict=True))
    _check_outputs(outputs, textures, preview_dir)
    _check_estimator(estimator, checkpoint)
    try:
        settings = _settings(no_refine, algorithm, embedding, budget, time_limit)
        check_height(height)
        name = None if species_name is None else wp_species.canonical(species_name)
        export = ExportOptions(face_view, max_faces, textures).validate()
        drawing = _read_drawings(sketch, view)
        pipeline = Pipeline(load_estimator(estimator, checkpoint=checkpoint, data=data), settings)
    except (SketchError, ValueError) as exc:
        fail(_option_message(str(exc)))
    bar, on_progress = _progress_bar(settings.budget, quiet or no_refine, preview_dir)
    try:
        with bar:
            result = pipeline.run(drawing, height=height, progress=on_progress, species=name)
        written = write_outputs(result, outputs, export)
    except (SketchError, ValueError) as exc:
        fail(str(exc))
    except OSError as exc:
        fail(f"cannot write the outputs: {exc.strerror or exc} ({exc.filename or ''})")
    _report(result, written)


# what each output option takes: its kind in ``write_outputs`` and its file endings
OUTPUT_OPTIONS = {
    "mesh": ("--out", (".glb", ".obj")),
    "json": ("--params", (".json",)),
    "preset": ("--preset", (".py",)),
    "compare": ("--compare", (".png",)),
    "outlines": ("--outlines", (".png",)),
    "summary": ("--summary", (".json",)),
}


def _check_outputs(outputs: dict[str, Path | None], textures: bool, preview: Path | None) -> None:
    """Each output's file ending, and a folder, two outputs on one file or a folder that
    takes no file refused now, not after minutes of refinement."""
    from weberpenn.export import mesh_paths
    from weberpenn.fileio import OutputError, check_targets

    for kind, (opt, exts) in OUTPUT_OPTIONS.items():
        p = outputs[kind]
        if p is not None and p.suffix.lower() not in exts:
            fail(f"{opt} {p}: expected a {' or '.join(exts)} file")
    targets = {"--out": mesh_paths(outputs["mesh"], textures=textures)}
    for kind, (opt, _) in OUTPUT_OPTIONS.items():
        if kind != "mesh" and outputs[kind] is not None:
            targets[opt] = [outputs[kind]]
    if preview is not None:
        targets["--preview"] = [preview / "tree.glb", preview / "sketch.png"]
    try:
        check_targets(targets)
    except OutputError as exc:
        fail(str(exc))


def _settings(
    no_refine: bool,
    algorithm: str,
    embedding: str,
    budget: int | None,
    time_limit: float | None,
) -> RefineSettings:
    """The refinement settings the options ask for, checked (ValueError names the one)."""
    settings = RefineSettings(refine=not no_refine, algorithm=algorithm, embedding=embedding)
    if budget is not None:
        settings = settings.replace(budget=budget)
    if time_limit is not None:
        settings = settings.replace(time_limit=time_limit)
    return settings.validate()


def _check_estimator(estimator: str, checkpoint: Path | None) -> None:
    """A known estimator, and a checkpoint only for TSN."""
    from .estimators import ESTIMATORS

    if estimator not in ESTIMATORS:
        fail(f"--estimator {estimator!r}: choose one of {', '.join(ESTIMATORS)}")
    if checkpoint is not None and estimator != "tsn":
        fail("--checkpoint is for --estimator tsn")


def _read_drawings(sketch: Path, view: list[str]) -> Any:
    """The drawing, or the drawing and its ``--view`` drawings (read now, and their
    number checked): what ``Pipeline.run`` takes."""
    from .pipeline import load_sketch
    from .views import SketchView, as_views, parse_view

    image = load_sketch(sketch)
    others = [parse_view(v) for v in view]
    drawing = [image, *[SketchView(load_sketch(v.source), v.yaw) for v in others]]
    as_views(drawing)  # the number of views, now
    return drawing if others else image


def _progress_bar(
    budget: int, hidden: bool, preview_dir: Path | None
) -> tuple[Any, Callable[[Progress], None]]:
    """The refinement's progress bar and the callback that moves it (and keeps the
    ``--preview`` folder's tree the current best)."""
    from rich.progress import BarColumn, TextColumn, TimeElapsedColumn
    from rich.progress import Progress as Bar

    bar = Bar(
        TextColumn("refining"),
        BarColumn(),
        TextColumn("{task.completed}/{task.total} trees"),
        TextColumn("loss {task.fields[loss]}"),
        TimeElapsedColumn(),
        disable=hidden,
        transient=False,
    )
    task = bar.add_task("refine", total=budget, loss="-")
    preview = None
    if preview_dir is not None:
        # the service's writer: the page's preview and the add-on's are one tree
        from .service.preview import PreviewWriter

        preview = PreviewWriter(preview_dir)

    def on_progress(p: Progress) -> None:
        # the run's whole plan (every candidate species) and a distance that only falls
        loss = "-" if math.isnan(p.best_loss) else f"{p.best_loss:.4f}"
        bar.update(task, total=max(1, p.budget), completed=p.evaluations, loss=loss)
        if preview is not None:
            offer_preview(p)

    def offer_preview(p: Progress) -> None:
        """The preview is a convenience: one that cannot be written (a dangling link, a
        full disk) is warned of once and given up, never costs the result (issue 49)."""
        nonlocal preview
        assert preview is not None
        try:
            preview.offer(p)
        except Exception as exc:  # noqa: BLE001 - whatever went wrong, the result goes on
            preview = None
            why = f"{exc.strerror or exc}" if isinstance(exc, OSError) else f"{exc}"
            bar.console.print(
                f"warning: --preview {preview_dir}: cannot write the preview ({why}); "
                "refining on without it",
                markup=False,
                highlight=False,
                soft_wrap=True,  # one line, whatever the terminal's width
            )

    return bar, on_progress


def _report(result: Result, written: list[Path]) -> None:
    """What the run found, on the terminal: species, distances, views, candidates, the
    tree's size, the warning and the files written."""
    r = result.refinement
    typer.echo(
        f"species: {result.species} (first estimate: {result.estimator}); view yaw {result.yaw:.0f}"
    )
    line = f"sketch distance: {result.losses['before']:.4f} -> {result.losses['after']:.4f}"
    if r is not None:
        line += f" ({r.evaluations} trees, {r.seconds:.1f} s, stopped by {r.stopped_by})"
    typer.echo(line)
    for i, v in enumerate(result.views[1:], start=2):
        how = "found" if v.searched else "given"
        typer.echo(
            f"view {i}: yaw {v.yaw:.0f} ({how}); sketch distance "
            f"{v.loss_before:.4f} -> {v.loss_after:.4f}"
        )
    if result.candidates:
        typer.echo(f"it is {result.species_text}")
        for c in result.candidates:
            dist = "not refined" if c.distance is None else f"distance {c.distance:.3f}"
            typer.echo(f"  candidate {c.species:<7} {c.probability:6.1%}  {dist}")
    lo, hi = result.tree_mesh.bounds()
    typer.echo(
        f"tree: {hi[2] - lo[2]:.2f} m tall, {len(result.tree_mesh.branches.faces)} branch faces"
    )
    if result.warning:
        typer.echo(f"warning: {result.warning}", err=True)
    for p in written:
        typer.echo(f"wrote {p}")


def _option_message(text: str) -> str:
    """Name the CLI option where the message names the setting."""
    for name, opt in (
        ("time_limit", "--time-limit"),
        ("budget", "--budget"),
        ("height", "--height"),
        ("embedding", "--embedding"),
        ("seed", "--seed"),
    ):
        if text.startswith(name + " "):
            return opt + text[len(name) :]
    return text


def register(app: typer.Typer) -> None:
    """Add this module's commands to the main app."""
    app.command("predict")(predict_command)
