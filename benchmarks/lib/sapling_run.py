"""Blender's own Sapling on our species: run it, record what it grows, read the records.

The one place that runs ``scripts/blender_time_sapling.py`` inside Blender and that knows
where Sapling's recorded statistics live:

- the paper's five: ``../shared/reference/sapling_reference_stats.json`` (Sapling on the
  species' three published dictionaries, Sapling seeds 0, 1, 2);
- every species' base dictionary (``species.base(name)``, seed 0), and for the species
  people draw the untouched Sapling preset they start from (seeds 0, 1, 2, leaves shown):
  :data:`SPECIES_STATS`, written by :func:`record` (``compare_sapling.py --blender BIN``).

``bench_grow.py --blender`` (seconds) and ``compare_sapling.py`` (sizes and faces) use it;
``scripts/make_species_png.py`` labels its pictures from the record.
"""

from __future__ import annotations

import ast
import datetime as dt
import hashlib
import json
import os
import subprocess
import tempfile
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from weberpenn import species
from weberpenn.export import save_sapling_preset
from weberpenn.params import TreeParams

ROOT = Path(__file__).resolve().parents[2]
REFERENCE_STATS = ROOT.parent / "shared" / "reference" / "sapling_reference_stats.json"
SPECIES_STATS = ROOT / "benchmarks" / "lib" / "sapling_species_stats.json"
SCRIPT = ROOT / "scripts" / "blender_time_sapling.py"
PRESETS = Path("/usr/share/blender/scripts/addons/add_curve_sapling/presets")
#: Sapling seeds the untouched presets are grown with (their spread is part of the story).
PRESET_SEEDS = (0, 1, 2)


class SaplingError(RuntimeError):
    """Blender or its Sapling add-on could not be run, or a record is missing or stale."""


def run_sapling(blender: str, presets: Sequence[Path], repeats: int = 1) -> list[dict]:
    """Sapling's rows (seconds per repeat, splines, faces, bounding boxes; see
    ``scripts/blender_time_sapling.py``) for each one-line preset, in order."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "sapling.json"
        cmd = [blender, "--background", "--factory-startup", "--python", str(SCRIPT), "--"]
        try:
            proc = subprocess.run(
                [*cmd, str(out), str(int(repeats)), *map(str, presets)],
                capture_output=True,
                text=True,
            )
        except OSError as exc:
            raise SaplingError(f"cannot run Blender {blender!r}: {exc}") from None
        if proc.returncode != 0 or not out.is_file():
            tail = (proc.stdout + proc.stderr)[-2000:]
            raise SaplingError(f"blender failed (exit {proc.returncode}):\n{tail}")
        return json.loads(out.read_text())


def preset_line(path: Path) -> dict[str, Any]:
    """A Sapling preset's dict literal (the first line not starting with '#', as Sapling's
    Import Preset reads it)."""
    with path.open(encoding="utf-8") as fh:
        line = next(t for t in fh if t.strip() and not t.lstrip().startswith("#"))
    return ast.literal_eval(line)


def base_key(params: TreeParams) -> str:
    """Fingerprint of a dictionary (a record of another dictionary is stale)."""
    text = json.dumps(params.to_dict(), sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def sizes(row: dict) -> dict[str, list[float]]:
    """Branch, leaf and whole-tree bounding-box sizes (width x, depth y, height z) of a
    recorded row."""
    out: dict[str, list[float]] = {}
    boxes = [b for b in (row.get("branch_bbox"), row.get("leaf_bbox")) if b]
    for name, box in (("branch", row.get("branch_bbox")), ("leaf", row.get("leaf_bbox"))):
        out[name] = [hi - lo for lo, hi in zip(*box, strict=True)] if box else [0.0] * 3
    if boxes:
        lo = [min(b[0][i] for b in boxes) for i in range(3)]
        hi = [max(b[1][i] for b in boxes) for i in range(3)]
        out["tree"] = [h - lo_ for lo_, h in zip(lo, hi, strict=True)]
    else:
        out["tree"] = [0.0] * 3
    return out


def _row(raw: dict, seed: int) -> dict:
    return {
        "seed": seed,
        "seconds_sapling": round(min(raw["seconds"]), 4),
        "splines": raw["splines"],
        "branch_faces": raw["branch_faces"],
        "leaf_faces": raw["leaf_faces"],
        "branch_bbox": raw["branch_bbox"],
        "leaf_bbox": raw["leaf_bbox"],
    }


def write_untouched(name: str, seed: int, path: Path) -> Path:
    """Write the untouched Sapling preset the species starts from as a one-line preset,
    with Sapling ``seed`` and its leaves shown (the presets of the fir, the willow and the
    aspen hide them; ours have them)."""
    preset = species.sapling_preset(name)
    if preset is None:
        raise SaplingError(f"{name} does not start from a Sapling preset")
    d = {**preset_line(PRESETS / f"{preset}.py"), "seed": int(seed), "showLeaves": True}
    path.write_text(repr(d) + "\n", encoding="utf-8")
    return path


def record(blender: str, out: Path = SPECIES_STATS, *, command: str = "", commit: str = "") -> dict:
    """Grow every species' base dictionary (seed 0) in Sapling, and each species people
    draw's untouched source preset (leaves shown, seeds :data:`PRESET_SEEDS`); write the
    record to ``out`` (atomically) and return it."""
    with tempfile.TemporaryDirectory() as tmp:
        jobs: list[tuple[str, str, int, Path]] = []
        for name in species.SPECIES:
            path = Path(tmp) / f"{name}.py"
            save_sapling_preset(species.base(name), path)
            jobs.append((name, "base", 0, path))
        for name in species.PEOPLE_SPECIES:
            for seed in PRESET_SEEDS:
                path = write_untouched(name, seed, Path(tmp) / f"{name}_preset_{seed}.py")
                jobs.append((name, "preset", seed, path))
        rows = run_sapling(blender, [j[3] for j in jobs])
    trees: dict[str, dict] = {}
    for (name, kind, seed, _), raw in zip(jobs, rows, strict=True):
        entry = trees.setdefault(name, {"display": species.display_name(name)})
        if kind == "base":
            entry["base_key"] = base_key(species.base(name))
            entry["base"] = _row(raw, seed)
        else:
            entry["preset"] = species.sapling_preset(name)
            entry.setdefault("preset_rows", []).append(_row(raw, seed))
    data = {
        "what": "Blender's Sapling (scripts/blender_time_sapling.py, bevel on, leaves on, "
        "armature off) on each species' base dictionary (species.base(name), exported with "
        "weberpenn.preset: our realised draws folded into Sapling's keys, Sapling seed 0), "
        "and on the untouched Sapling preset each species people draw starts from (only "
        "showLeaves set on; Sapling seeds 0, 1, 2). Bounding boxes [[lo], [hi]] in Blender "
        "units, Z up, branches as the bevelled curve evaluated to a mesh; faces are "
        "Sapling's quads (branches) and leaf polygons; seconds: tree_add alone. base_key: "
        "fingerprint of the base dictionary recorded (benchmarks/lib/sapling_run.py base_key).",
        "command": command,
        "commit": commit,
        "date": dt.datetime.now(dt.UTC).strftime("%Y-%m-%d %H:%M UTC"),
        "trees": trees,
    }
    tmp_path = out.with_suffix(".json.tmp")
    tmp_path.write_text(json.dumps(data, indent=1) + "\n")
    os.replace(tmp_path, out)
    return data


def recorded(path: Path = SPECIES_STATS) -> dict:
    """The species record written by :func:`record`; raises :class:`SaplingError` when it
    is missing or records a base dictionary other than today's."""
    if not path.is_file():
        raise SaplingError(f"no Sapling record at {path}; run compare_sapling.py --blender BIN")
    data = json.loads(path.read_text())
    stale = [
        n
        for n in species.SPECIES
        if n not in data["trees"] or data["trees"][n].get("base_key") != base_key(species.base(n))
    ]
    if stale:
        raise SaplingError(
            f"{path.name} does not record today's base dictionary of {', '.join(stale)}; "
            "run compare_sapling.py --blender BIN"
        )
    return data


def reference_rows(name: str) -> list[dict]:
    """Sapling's recorded rows for the paper species' three published dictionaries (empty
    for the species people draw or when the shared reference is absent)."""
    if not REFERENCE_STATS.is_file():
        return []
    trees = json.loads(REFERENCE_STATS.read_text())["trees"]
    return [r for f in species.reference_files(name) for r in trees.get(Path(f).stem, [])]
