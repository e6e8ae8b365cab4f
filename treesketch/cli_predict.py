"""`treesketch predict`: a sketch -> TSN estimate -> refinement -> GLB/OBJ, JSON, preset,
comparison picture.

Every output is first written into a temporary folder beside its target and moved into
place only after all of them were made, so an interrupted run (Ctrl-C, an error) leaves
no partial or half-written file.
"""

from __future__ import annotations

import os
import shutil
import tempfile
from pathlib import Path
from typing import Any

import numpy as np
import typer

__all__ = ["compare_image", "predict_command", "register", "write_outputs"]


def _fail(message: str) -> None:
    typer.echo(f"error: {message}", err=True)
    raise typer.Exit(code=2)


def compare_image(result: Any, size: int = 256) -> np.ndarray:
    """Side by side: input sketch | first estimate's sketch | refined sketch | colour render
    (RGB uint8, captioned)."""
    from PIL import Image, ImageDraw

    from render.sketch import SketchRenderer

    def grey(img: np.ndarray) -> Image.Image:
        return Image.fromarray(np.asarray(img, np.uint8)).convert("RGB").resize((size, size))

    colour = SketchRenderer(result.tree_mesh, species=result.species).colour(
        result.yaw, size, supersample=2
    )
    est = "TSN" if result.estimator == "tsn" else "template"
    panels = [
        ("input sketch", grey(result.input_sketch)),
        (f"{est} ({result.losses['before']:.3f})", grey(result.sketch_before)),
        (f"refined ({result.losses['after']:.3f})", grey(result.sketch_after)),
        (f"{result.species}, yaw {result.yaw:.0f}", Image.fromarray(colour).convert("RGB")),
    ]
    cap = 18
    out = Image.new("RGB", (size * len(panels), size + cap), (255, 255, 255))
    draw = ImageDraw.Draw(out)
    for i, (title, im) in enumerate(panels):
        out.paste(im, (i * size, cap))
        draw.text((i * size + 4, 3), title, fill=(0, 0, 0))
        if i:
            draw.line([(i * size, 0), (i * size, size + cap)], fill=(180, 180, 180))
    return np.asarray(out)


def write_outputs(result: Any, outputs: dict[str, Path | None]) -> list[Path]:
    """Write the requested outputs (keys ``out``, ``params``, ``preset``, ``compare``)
    all-or-nothing: into a temporary folder first, then renamed into place."""
    from PIL import Image

    from weberpenn.export import export_mesh, save_sapling_preset
    from weberpenn.params import save_params

    made: list[tuple[Path, Path]] = []  # (temporary file, final path)
    tmpdirs: dict[Path, Path] = {}

    def tmp_for(final: Path) -> Path:
        parent = final.resolve().parent
        parent.mkdir(parents=True, exist_ok=True)
        if parent not in tmpdirs:
            tmpdirs[parent] = Path(tempfile.mkdtemp(prefix=".treesketch-", dir=parent))
        return tmpdirs[parent] / final.name

    try:
        out = outputs.get("out")
        if out is not None:
            tmp = tmp_for(out)
            export_mesh(result.tree_mesh, tmp)
            made.append((tmp, out))
            if out.suffix.lower() == ".obj":
                made.append((tmp.with_suffix(".mtl"), out.with_suffix(".mtl")))
        if outputs.get("params") is not None:
            final = outputs["params"]
            assert final is not None
            made.append((save_params(result.params, tmp_for(final)), final))
        if outputs.get("preset") is not None:
            final = outputs["preset"]
            assert final is not None
            made.append((save_sapling_preset(result.params, tmp_for(final)), final))
        if outputs.get("compare") is not None:
            final = outputs["compare"]
            assert final is not None
            tmp = tmp_for(final)
            Image.fromarray(compare_image(result)).save(tmp, format="PNG")
            made.append((tmp, final))
        for tmp, final in made:
            os.chmod(tmp, 0o644)
            os.replace(tmp, final)
        return [final for _, final in made]
    finally:
        for d in tmpdirs.values():
            shutil.rmtree(d, ignore_errors=True)


def predict_command(
    sketch: Path = typer.Argument(
        ..., help="The sketch: a PNG/JPEG of a tree, dark lines on white."
    ),
    out: Path = typer.Option(
        ..., "--out", "-o", help="Mesh file to write: .glb (branches and leaves) or .obj."
    ),
    no_refine: bool = typer.Option(
        False, "--no-refine", help="Skip the refinement: TSN's estimate only."
    ),
    budget: int = typer.Option(
        None, "--budget", min=1, help="Refinement: most trees to evaluate (default 100)."
    ),
    time_limit: float = typer.Option(
        None, "--time-limit", min=0.1, help="Refinement: most seconds (default 50)."
    ),
    height: float = typer.Option(
        None, "--height", min=0.01, help="Make the tree this tall (metres); a sketch has no size."
    ),
    params_path: Path | None = typer.Option(
        None, "--params", help="Also write the parameters (JSON)."
    ),
    preset_path: Path | None = typer.Option(
        None, "--preset", help="Also write a Blender Sapling preset (.py)."
    ),
    compare_path: Path | None = typer.Option(
        None,
        "--compare",
        help="Also write a PNG: input sketch, first estimate's sketch, refined sketch, colour render.",
    ),
    algorithm: str = typer.Option("bobyqa", "--algorithm", help="bobyqa, sbplx or cobyla."),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="No progress bar."),
) -> None:
    """Turn a sketch of a tree into a 3D tree: TSN's estimate, refined so the tree's own
    sketch matches yours.

    Example: `treesketch predict examples/sketch_maple.png --out tree.glb --compare cmp.png`.
    """
    from refine.search import ALGORITHMS

    from .pipeline import DEFAULT_BUDGET, DEFAULT_TIME_LIMIT, SketchError, predict_then_refine

    if out.suffix.lower() not in (".glb", ".obj"):
        _fail(f"--out {out}: unknown mesh format {out.suffix or '(none)'!r}; use .glb or .obj")
    if algorithm.lower() not in ALGORITHMS:
        _fail(f"--algorithm {algorithm!r}: choose one of {', '.join(ALGORITHMS)}")
    if not sketch.is_file():
        _fail(f"sketch file not found: {sketch}")
    for opt, p, ext in (
        ("--params", params_path, ".json"),
        ("--preset", preset_path, ".py"),
        ("--compare", compare_path, ".png"),
    ):
        if p is not None and p.suffix.lower() != ext:
            _fail(f"{opt} {p}: expected a {ext} file")
    n_budget = DEFAULT_BUDGET if budget is None else int(budget)
    seconds = DEFAULT_TIME_LIMIT if time_limit is None else float(time_limit)

    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    bar = Progress(
        TextColumn("refining"),
        BarColumn(),
        TextColumn("{task.completed}/{task.total} trees"),
        TextColumn("loss {task.fields[loss]}"),
        TimeElapsedColumn(),
        disable=quiet or no_refine,
        transient=False,
    )
    task = bar.add_task("refine", total=n_budget, loss="-")

    def on_progress(evals: int, best: float) -> None:
        bar.update(task, completed=evals, loss=f"{best:.4f}")

    try:
        with bar:
            result = predict_then_refine(
                sketch,
                refine=not no_refine,
                budget=n_budget,
                time_limit=seconds,
                height=height,
                progress=on_progress,
                algorithm=algorithm,
            )
        written = write_outputs(
            result,
            {"out": out, "params": params_path, "preset": preset_path, "compare": compare_path},
        )
    except SketchError as exc:
        _fail(str(exc))
        return
    except (ValueError, OSError) as exc:
        _fail(f"{type(exc).__name__}: {exc}")
        return

    r = result.refinement
    typer.echo(
        f"species: {result.species} (first estimate: {result.estimator}); view yaw {result.yaw:.0f}"
    )
    line = f"sketch distance: {result.losses['before']:.4f} -> {result.losses['after']:.4f}"
    if r is not None:
        line += f" ({r.evaluations} trees, {r.seconds:.1f} s, stopped by {r.stopped_by})"
    typer.echo(line)
    lo, hi = result.tree_mesh.bounds()
    typer.echo(
        f"tree: {hi[2] - lo[2]:.2f} m tall, {len(result.tree_mesh.branches.faces)} branch faces"
    )
    if result.warning:
        typer.echo(f"warning: {result.warning}", err=True)
    for p in written:
        typer.echo(f"wrote {p}")


def register(app: typer.Typer) -> None:
    """Add this module's commands to the main app."""
    app.command("predict")(predict_command)
