"""`treesketch grow` (grow and mesh one tree, write GLB/OBJ/JSON/preset) and
`treesketch params` (the parameter table)."""

from __future__ import annotations

import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

import typer

from .cli_common import fail, max_faces_option, preset_option, textures_option

if TYPE_CHECKING:
    from weberpenn import TreeParams


def grow_command(
    out: Path = typer.Option(
        ...,
        "--out",
        "-o",
        help="Mesh file to write: .glb (two named meshes 'branches' and 'leaves' with bark "
        "and leaf materials, Y-up as glTF wants) or .obj (Blender's default OBJ axes, with a "
        ".mtl and the texture PNGs beside it).",
    ),
    species_name: str | None = typer.Option(
        None,
        "--species",
        "-s",
        help="Draw a tree of this species: maple, pine, bonsai, palm or cherry "
        "(its unfixed parameters are sampled from --seed).",
    ),
    params_path: Path | None = typer.Option(
        None,
        "--params",
        "-p",
        help="Grow from a parameter file instead: JSON with the 70 TreeSketchNet keys, or a "
        "Blender Sapling preset (.py dict literal).",
    ),
    seed: int | None = typer.Option(
        None,
        "--seed",
        min=0,
        help="With --species: seed for sampling its parameters (default 0). With --params: "
        "replaces the file's 'seed' key. The tree depends only on the parameters (their "
        "'seed' included): same parameters, same tree.",
    ),
    save_params_path: Path | None = typer.Option(
        None, "--save-params", help="Also write the parameters used, as JSON."
    ),
    preset_path: Path | None = preset_option(),
    yaw: float = typer.Option(
        0.0,
        "--yaw",
        help="Turn the exported tree so the view seen from this camera yaw (degrees) faces "
        "the front view (recorded in the preset's comment).",
    ),
    max_faces: int | None = max_faces_option(),
    lods: str | None = typer.Option(
        None,
        "--lods",
        help="Also write lighter copies, e.g. '50000,10000' writes OUT_lod1 and OUT_lod2 "
        "under those triangle counts (OUT itself is lod0).",
    ),
    textures: bool = textures_option(),
    settings: list[str] = typer.Option(
        [],
        "--set",
        help="Edit the tree with a control, NAME=VALUE (repeatable), e.g. --set "
        "crown_width=1.3 --set seed=7 --set height=12; `treesketch controls` lists them.",
    ),
) -> None:
    """Grow one Weber-Penn tree and write its mesh.

    Examples: `treesketch grow --species maple --seed 3 --out maple.glb`,
    `treesketch grow --params tree.json --out tree.obj --max-faces 20000`,
    `treesketch grow --params tree.json --set crown_width=1.3 --set seed=7 --out tree.glb`.
    """
    from weberpenn import build_mesh, grow
    from weberpenn.controls import grow_with_controls
    from weberpenn.export import mesh_files, preset_text
    from weberpenn.fileio import write_together
    from weberpenn.lod import lod
    from weberpenn.params import ParamError, params_text

    if (species_name is None) == (params_path is None):
        fail("give exactly one of --species NAME or --params FILE")
    suffix = out.suffix.lower()
    if suffix not in (".glb", ".obj"):
        fail(f"--out {out}: unknown mesh format {suffix or '(none)'!r}; use .glb or .obj")
    budgets = _lod_budgets(lods, max_faces)
    lod_outs = _check_outputs(out, budgets, textures, save_params_path, preset_path)
    checked = _controls(settings)
    try:
        params, name = _start(species_name, params_path, seed)
        t0 = time.perf_counter()
        if checked:
            params, full = grow_with_controls(params, checked, name)
        else:
            full = build_mesh(grow(params), species=name)
        dt = time.perf_counter() - t0
        if full.is_empty:
            fail("these parameters grow an empty tree (no branches and no leaves)")
        tree = full if max_faces is None else lod(full, max_faces)
        # all the files or none (staged, then renamed together)
        files = dict(mesh_files(tree, out, yaw=yaw, textures=textures))
        for budget, lod_out in zip(budgets, lod_outs, strict=True):
            files.update(mesh_files(full, lod_out, yaw=yaw, max_faces=budget, textures=textures))
        if save_params_path is not None:
            files[save_params_path] = params_text(params)
        if preset_path is not None:
            files[preset_path] = preset_text(params, yaw=yaw)
        write_together(files)
    except (ParamError, ValueError) as exc:
        fail(str(exc))
    except OSError as exc:
        fail(f"cannot write output: {exc}")
    typer.echo(
        f"{out}: {len(tree.branches.faces)} branch faces, {len(tree.leaves.faces)} leaf faces "
        f"(grow+mesh {dt:.2f} s)"
    )


def _lod_budgets(lods: str | None, max_faces: int | None) -> list[int]:
    """The ``--lods`` triangle counts, each (and ``--max-faces``) in range before the
    tree is grown (the exporters' own check)."""
    from weberpenn.lod import check_budget

    budgets: list[int] = []
    if lods is not None:
        try:
            budgets = [int(x) for x in lods.split(",") if x.strip()]
        except ValueError:
            fail(f"--lods {lods!r}: give triangle counts separated by commas, e.g. 50000,10000")
        if not budgets:
            fail(f"--lods {lods!r}: give at least one triangle count")
    asked = [] if max_faces is None else [("--max-faces", max_faces)]
    for opt, budget in [*asked, *((f"--lods {lods!r}", b) for b in budgets)]:
        try:
            check_budget(budget)
        except ValueError as exc:
            fail(f"{opt}: {exc}")
    return budgets


def _check_outputs(
    out: Path,
    budgets: list[int],
    textures: bool,
    save_params_path: Path | None,
    preset_path: Path | None,
) -> list[Path]:
    """Every output before any work (a folder, a clash or a folder that takes no file
    fails now, not after the tree is grown and half the files are written); the level of
    detail files' paths, one per budget."""
    from weberpenn.export import mesh_paths
    from weberpenn.fileio import OutputError, check_targets

    lod_outs = [out.with_name(f"{out.stem}_lod{i}{out.suffix}") for i in range(1, len(budgets) + 1)]
    try:
        check_targets(
            {
                "--out": mesh_paths(out, textures=textures),
                **{
                    f"--lods ({b})": mesh_paths(p, textures=textures)
                    for b, p in zip(budgets, lod_outs, strict=True)
                },
                "--save-params": [] if save_params_path is None else [save_params_path],
                "--preset": [] if preset_path is None else [preset_path],
            }
        )
    except OutputError as exc:
        fail(str(exc))
    return lod_outs


def _controls(settings: list[str]) -> dict[str, Any]:
    """The ``--set NAME=VALUE`` controls, checked (``weberpenn.controls``)."""
    from weberpenn.controls import check_controls

    controls: dict[str, str] = {}
    for item in settings:
        key, eq, value = item.partition("=")
        if not eq or not key.strip():
            fail(f"--set {item!r}: give NAME=VALUE, e.g. --set crown_width=1.3")
        controls[key.strip()] = value.strip()
    try:
        return check_controls(controls)
    except ValueError as exc:
        fail(f"--set: {exc}")


def _start(
    species_name: str | None, params_path: Path | None, seed: int | None
) -> tuple[TreeParams, str | None]:
    """The tree to grow: the species' sample of ``seed`` (0 when none), or the parameter
    file (its seed replaced when one is given); and the species when named."""
    from weberpenn import load_params, species

    if species_name is not None:
        name = species.canonical(species_name)
        return species.sample(name, 0 if seed is None else seed), name
    assert params_path is not None
    params = load_params(params_path)
    return (params if seed is None else params.replace(seed=seed)), None


def controls_command() -> None:
    """Print the controls `grow --set`, the page and the add-on edit a tree with."""
    from weberpenn.controls import CONTROLS

    for c in CONTROLS:
        if c.kind == "choice":
            what = "one of " + ", ".join(f"{v} ({label})" for v, label in c.choices)
        elif c.kind == "toggle":
            what = "true or false"
        else:
            what = f"{c.lo:g}..{c.hi:g} {c.unit}".rstrip()
            if c.relative:
                what += f" (unchanged at {c.neutral:g})"
        typer.echo(f"{c.name:13} {c.label}: {c.help}\n{'':13} {what}; moves {'; '.join(c.moves)}")


def params_command() -> None:
    """Print every parameter: shape, type, head, allowed range and meaning."""
    from weberpenn.params import describe

    typer.echo(describe())


def register(app: typer.Typer) -> None:
    """Add this module's commands to the main app."""
    app.command("grow")(grow_command)
    app.command("params")(params_command)
    app.command("controls")(controls_command)
