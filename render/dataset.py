"""Synthetic dataset builder: species x trees x views -> sketches, parameters, renders.

``build_dataset(DatasetConfig(out=..., trees_per_species=250, ...))`` (or the CLI
``treesketch dataset build``) samples each tree's parameters with
``weberpenn.species.sample(species, seed=tree_seed)``, grows and meshes it, builds its
mitsuba scenes once and renders every view.

Layout of ``OUT`` (all paths in the manifest are relative to ``OUT``)::

    dataset.json                      the settings (a re-run must use the same ones)
    sketches/<species>/<tree_id>_<view>.png   (size x size, 8-bit grey, 255 = white)
    params/<species>/<tree_id>.json   the 70-key parameter dictionary (load_params)
    renders/<species>/<tree_id>.png   ground-truth colour render, front view (RGB)
    done/<tree_id>.json               per-tree marker, written LAST: the tree is finished
    failed/<tree_id>.json             a tree that raised: error, traceback, parameters
    manifest.jsonl, manifest.csv      one row per sketch (written at the end)
    DONE                              written last of all (JSON summary)

``tree_id`` is ``<species>_<index:04d>``.  ``tree_seed`` is derived from the dataset seed,
the species and the index (``numpy.random.SeedSequence([seed, species_no, index])``, below
2**31); the tree is ``build_mesh(grow(species.sample(species, seed=tree_seed)))``, so
``grow(load_params(params_json))`` rebuilds it exactly (the dictionary's ``seed`` key is
``tree_seed``).

Manifest columns (JSONL: one JSON object per line; CSV: the same columns, header first),
sorted by species (in ``weberpenn.species.SPECIES`` order), index, view order:

    species, tree_id, index, tree_seed, split, view, yaw, size, sketch, params, render
    [, style]   (only in datasets drawn in other styles than the paper's SG chain)

Drawing styles (``styles``, :mod:`render.styles`): with the default ``("sg",)`` every view
is drawn once by the paper's chain and the files and manifest are exactly those of a build
without styles.  Otherwise, when ``sg`` is listed every view is still drawn in SG (at the
same path, the same bytes) and, besides, in ``styles_per_view`` of the other listed styles,
chosen per view by a seeded draw (``numpy.random.default_rng([tree_seed, view_no, 83])``):
the SG dataset stays inside the mixed one (its test split is the SG benchmark, unchanged)
and SG is half of what the network sees, while every other style gets an equal share of
the views.  Without ``sg`` in the list, ``styles_per_view`` of the listed styles are drawn
per view.  Each styled sketch has its own seed (``[tree_seed, view_no, style_no]``) and
lives at ``sketches/<species>/<tree_id>_<view>_<style>.png``; its row says its ``style``.

``split`` is ``train``/``val``/``test``, assigned per TREE (every view of a tree is in the
same split), stratified per species: a seeded permutation of the indices, the first
``round(n * val_fraction)`` go to ``val``, the next ``round(n * test_fraction)`` to
``test``, the rest to ``train`` (250 trees -> 200/25/25).

Every file is written to a temporary name and renamed, and a tree's marker is written
after all its files, so killing the builder at any moment leaves no half-written file; a
re-run skips finished trees, redoes unfinished ones, and rewrites the manifest.  The same
settings give the same files (PNG bytes included).  A lock file stops two builders from
writing the same directory.

Trees are independent pieces: ``build_dataset(cfg, executor=...)`` hands them to an
executor (``treesketch.executor``: a local process pool, Ray).  Its workers build a tree
in a scratch folder and send the files back as bytes (:class:`TreeFiles`); only this
process writes into ``OUT`` (a tree's files together, then its marker), so the workers
need no shared disk, and a lost worker leaves nothing behind.  Whichever executor runs
them, the files are the same bytes.
"""

from __future__ import annotations

import contextlib
import csv
import functools
import io
import json
import logging
import math
import os
import sys
import tempfile
import time
import traceback
from collections.abc import Callable, Iterator, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from weberpenn.fileio import atomic_write, write_together

from .camera import VIEWS, resolve_yaw

log = logging.getLogger(__name__)

FORMAT_VERSION = 1
MANIFEST_COLUMNS = (
    "species",
    "tree_id",
    "index",
    "tree_seed",
    "split",
    "view",
    "yaw",
    "size",
    "sketch",
    "params",
    "render",
)
SPLITS = ("train", "val", "test")
DEFAULT_STYLES = ("sg",)
VIEW_CHOICE_KEY = 83  # the third word of the per-view style draw's seed


class DatasetError(ValueError):
    """Bad dataset settings or an output folder that cannot be used."""


@dataclass(frozen=True)
class DatasetConfig:
    """Settings of a dataset build (everything that changes the output is stored)."""

    out: str
    trees_per_species: int = 250
    species: tuple[str, ...] = ("maple", "pine", "bonsai", "palm", "cherry")
    views: tuple[str, ...] = ("front", "back", "left", "right")
    size: int = 256
    seed: int = 0
    val_fraction: float = 0.1
    test_fraction: float = 0.1
    render_size: int | None = None  # colour render size; None = ``size``
    styles: tuple[str, ...] = DEFAULT_STYLES  # drawing styles (render.styles.STYLES)
    styles_per_view: int = 1  # other styles drawn per view (besides SG)
    workers: int = field(default=1, compare=False)

    def __post_init__(self) -> None:
        from weberpenn import species as wp_species

        if isinstance(self.trees_per_species, bool) or int(self.trees_per_species) < 1:
            raise DatasetError(f"trees_per_species must be >= 1, got {self.trees_per_species!r}")
        if int(self.trees_per_species) > 100_000:
            raise DatasetError(f"trees_per_species={self.trees_per_species} is over 100000")
        if not self.species:
            raise DatasetError("no species given")
        for s in self.species:
            if s not in wp_species.SPECIES:
                raise DatasetError(
                    f"unknown species {s!r}: choose from {', '.join(wp_species.SPECIES)}"
                )
        if len(set(self.species)) != len(self.species):
            raise DatasetError(f"species listed twice: {', '.join(self.species)}")
        if not self.views:
            raise DatasetError("no views given")
        yaws = []
        for v in self.views:
            try:
                yaw = resolve_yaw(v)
            except ValueError:
                yaw = math.nan
            if v not in VIEWS and not (math.isfinite(yaw) and 0 <= yaw < 360 and v == f"{yaw:g}"):
                raise DatasetError(
                    f"unknown view {v!r}: choose from {', '.join(VIEWS)} or a yaw in degrees "
                    "in [0, 360) written plainly (45, 22.5)"
                )
            yaws.append(yaw)
        if len(set(yaws)) != len(yaws):
            raise DatasetError(f"views listed twice (same yaw): {', '.join(self.views)}")
        for name in ("size", "render_size"):
            v = getattr(self, name)
            if v is not None and (isinstance(v, bool) or int(v) != v or not 32 <= int(v) <= 2048):
                raise DatasetError(f"{name} must be an integer in [32, 2048], got {v!r}")
        if isinstance(self.seed, bool) or int(self.seed) != self.seed or self.seed < 0:
            raise DatasetError(f"seed must be a non-negative integer, got {self.seed!r}")
        fr = (self.val_fraction, self.test_fraction)
        if not all(0.0 <= f < 1.0 for f in fr) or sum(fr) >= 1.0:
            raise DatasetError(
                f"val_fraction and test_fraction must be in [0, 1) with a sum below 1, got {fr}"
            )
        from .styles import check_styles

        try:
            check_styles(self.styles)
        except ValueError as exc:
            raise DatasetError(str(exc)) from None
        spv = self.styles_per_view
        if isinstance(spv, bool) or int(spv) != spv or not 1 <= int(spv) <= 16:
            raise DatasetError(f"styles_per_view must be an integer in 1..16, got {spv!r}")
        if isinstance(self.workers, bool) or not 1 <= int(self.workers) <= 64:
            raise DatasetError(f"workers must be in 1..64, got {self.workers!r}")

    @property
    def out_dir(self) -> Path:
        return Path(self.out)

    def settings(self) -> dict[str, Any]:
        """What ``dataset.json`` records (and what a re-run must match)."""
        d = asdict(self)
        d.pop("out")
        d.pop("workers")
        d["species"] = list(self.species)
        d["views"] = list(self.views)
        d["render_size"] = int(self.render_size or self.size)
        if tuple(self.styles) == DEFAULT_STYLES:  # SG-only datasets keep their old record
            d.pop("styles")
            d.pop("styles_per_view")
        else:
            d["styles"] = list(self.styles)
        d["format_version"] = FORMAT_VERSION
        return d


@dataclass(frozen=True)
class TreeJob:
    species: str
    species_no: int
    index: int
    tree_seed: int
    split: str

    @property
    def tree_id(self) -> str:
        return f"{self.species}_{self.index:04d}"


# --------------------------------------------------------------------------- planning
def tree_seed(seed: int, species_no: int, index: int) -> int:
    """The per-tree seed (below 2**31, so Sapling presets can hold it)."""
    ss = np.random.SeedSequence([int(seed), int(species_no), int(index)])
    return int(ss.generate_state(1, dtype=np.uint32)[0] >> 1)


def assign_splits(n: int, seed: int, species_no: int, val: float, test: float) -> list[str]:
    """Split labels for indices 0..n-1 of one species (seeded, stratified, by tree)."""
    n_val, n_test = int(round(n * val)), int(round(n * test))
    while n_val + n_test >= n and n_val + n_test > 0:  # tiny datasets: keep a training tree
        if n_test >= n_val:
            n_test -= 1
        else:
            n_val -= 1
    order = np.random.default_rng([int(seed), int(species_no), 7]).permutation(n)
    labels = ["train"] * n
    for k, i in enumerate(order):
        if k < n_val:
            labels[i] = "val"
        elif k < n_val + n_test:
            labels[i] = "test"
    return labels


def plan(cfg: DatasetConfig) -> list[TreeJob]:
    """Every tree of the dataset, in manifest order."""
    from weberpenn import species as wp_species

    jobs = []
    for s in cfg.species:
        no = wp_species.SPECIES.index(s)  # stable whatever subset is built
        n = int(cfg.trees_per_species)
        splits = assign_splits(n, cfg.seed, no, cfg.val_fraction, cfg.test_fraction)
        for i in range(n):
            jobs.append(TreeJob(s, no, i, tree_seed(cfg.seed, no, i), splits[i]))
    return jobs


# --------------------------------------------------------------------------- file helpers
def png_bytes(img: np.ndarray) -> bytes:
    """Deterministic PNG encoding (no timestamps or metadata)."""
    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(np.ascontiguousarray(img)).save(buf, format="PNG", optimize=False)
    return buf.getvalue()


def _json_bytes(obj: Any) -> bytes:
    return (json.dumps(obj, indent=1, sort_keys=False) + "\n").encode("utf-8")


def view_styles(settings: dict[str, Any], tree_seed_: int, view_no: int) -> list[str]:
    """The styles one view of one tree is drawn in (see the module docstring)."""
    styles = list(settings.get("styles", DEFAULT_STYLES))
    k = int(settings.get("styles_per_view", 1))
    first = ["sg"] if "sg" in styles else []
    others = [s for s in styles if s != "sg"]
    if not others:
        return first
    if k >= len(others):
        return first + others
    rng = np.random.default_rng([int(tree_seed_), int(view_no), VIEW_CHOICE_KEY])
    picked = set(rng.choice(len(others), size=k, replace=False).tolist())
    return first + [s for i, s in enumerate(others) if i in picked]


def paths_for(job: TreeJob, view: str, style: str = "sg") -> dict[str, str]:
    tail = "" if style == "sg" else f"_{style}"
    return {
        "sketch": f"sketches/{job.species}/{job.tree_id}_{view}{tail}.png",
        "params": f"params/{job.species}/{job.tree_id}.json",
        "render": f"renders/{job.species}/{job.tree_id}.png",
    }


# --------------------------------------------------------------------------- one tree
@functools.lru_cache(maxsize=1)
def mesher_in_use() -> tuple[Callable[[Any], Any], str]:
    """The mesher and its name (recorded in every tree's marker)."""
    from weberpenn import build_mesh

    return build_mesh, "weberpenn.build_mesh"


def build_tree(job: TreeJob, settings: dict[str, Any], out: str) -> dict[str, Any]:
    """Make one tree's files and its marker; return the marker (or a failure record)."""
    from weberpenn import species as wp_species

    root = Path(out)
    t0 = time.perf_counter()
    params = None
    try:
        from weberpenn import grow

        from .sketch import SketchRenderer

        build_mesh, mesher = mesher_in_use()
        params = wp_species.sample(job.species, seed=job.tree_seed)
        tree = build_mesh(grow(params))
        t_mesh = time.perf_counter()
        renderer = SketchRenderer(tree, species=job.species)
        size = int(settings["size"])
        styled = "styles" in settings
        rows = []
        for view_no, view in enumerate(settings["views"]):
            for style, img in _draw_view(
                renderer, view, view_no, job.tree_seed, settings, job.species
            ):
                p = paths_for(job, view, style)
                atomic_write(root / p["sketch"], png_bytes(img))
                row = {
                    "species": job.species,
                    "tree_id": job.tree_id,
                    "index": job.index,
                    "tree_seed": job.tree_seed,
                    "split": job.split,
                    "view": view,
                    "yaw": resolve_yaw(view),
                    "size": size,
                    **p,
                }
                rows.append({**row, "style": style} if styled else row)
        colour = renderer.colour("front", int(settings["render_size"]), supersample=1)
        p = paths_for(job, settings["views"][0])
        atomic_write(root / p["render"], png_bytes(colour))
        atomic_write(root / p["params"], _json_bytes(params.to_dict()))
        marker = {
            "tree_id": job.tree_id,
            "status": "done",
            "mesher": mesher,
            "faces": int(len(tree.branches.faces) + len(tree.leaves.faces)),
            "seconds_mesh": round(t_mesh - t0, 4),
            "seconds_total": round(time.perf_counter() - t0, 4),
            "rows": rows,
        }
        atomic_write(root / "done" / f"{job.tree_id}.json", _json_bytes(marker))
        (root / "failed" / f"{job.tree_id}.json").unlink(missing_ok=True)
        return marker
    except Exception as exc:  # one bad tree never stops the run
        record = _failed_record(
            job,
            f"{type(exc).__name__}: {exc}",
            traceback.format_exc(),
            params.to_dict() if params is not None else None,
        )
        with contextlib.suppress(OSError):  # disk trouble: still report the failure
            atomic_write(root / "failed" / f"{job.tree_id}.json", _json_bytes(record))
        return record


def _draw_view(
    renderer: Any,
    view: str,
    view_no: int,
    tree_seed_: int,
    settings: dict[str, Any],
    species: str | None = None,
) -> list[tuple[str, np.ndarray]]:
    """One view in each of its styles, as (style, uint8 sketch); the SG one is exactly
    ``renderer.sketch(view, size)``."""
    size = int(settings["size"])
    styles = view_styles(settings, tree_seed_, view_no)
    if styles == ["sg"]:
        return [("sg", renderer.sketch(view, size))]
    from weberpenn.species import doodle_foliage

    from .styles import STYLES, Silhouettes, draw

    parts = renderer.parts(view, size)
    sil = Silhouettes.from_parts(parts, species is not None and doodle_foliage(species))
    out = []
    for style in styles:
        if style == "sg":
            out.append((style, parts.sketch))
        else:
            rng = np.random.default_rng([int(tree_seed_), int(view_no), list(STYLES).index(style)])
            out.append((style, draw(style, sil, rng, size)))
    return out


@dataclass(frozen=True)
class TreeFiles:
    """One finished piece: the tree's record (its marker, or a failure record) and every
    file it made, by path relative to ``OUT``.  Pieces return bytes, the builder writes
    them, so workers on other machines need no shared disk."""

    record: dict[str, Any]
    files: dict[str, bytes]


def build_tree_files(job: TreeJob, settings: dict[str, Any]) -> TreeFiles:
    """:func:`build_tree` into a scratch folder; the files come back as bytes."""
    with tempfile.TemporaryDirectory(prefix=f"treesketch_{job.tree_id}_") as tmp:
        record = build_tree(job, settings, tmp)
        base = Path(tmp)
        files = {
            f.relative_to(base).as_posix(): f.read_bytes()
            for f in sorted(base.rglob("*"))
            if f.is_file() and not f.name.endswith(".tmp")
        }
    return TreeFiles(record, files)


@dataclass(frozen=True)
class TreeWorker:
    """The worker factory the executor runs (picklable): called once per worker process,
    it starts mitsuba (``threads`` Dr.Jit threads; None = all cores) and returns the
    function that builds one tree."""

    settings: dict[str, Any]
    threads: int | None = 1

    def __call__(self) -> Callable[[TreeJob], TreeFiles]:
        from .backend import init_mitsuba

        init_mitsuba(threads=self.threads)
        return functools.partial(build_tree_files, settings=self.settings)


class PieceRunner(Protocol):
    """What :func:`build_dataset` needs of an executor (``treesketch.executor`` has them):
    run ``factory()``'s function over ``pieces`` and yield outcomes with ``index``,
    ``value`` and ``error`` (a string when the piece or its worker was lost)."""

    def run(self, factory: Callable[[], Callable[[Any], Any]], pieces: Sequence[Any]) -> Any: ...


def _store(root: Path, job: TreeJob, tf: TreeFiles) -> dict[str, Any]:
    """Write a built tree: its files all together, then its marker (the tree is finished
    only once the marker is there, so a kill at any moment leaves it to be redone)."""
    marker = f"done/{job.tree_id}.json"
    failed = root / "failed" / f"{job.tree_id}.json"
    if tf.record.get("status") == "done":
        write_together({root / k: v for k, v in tf.files.items() if k != marker})
        atomic_write(root / marker, tf.files.get(marker) or _json_bytes(tf.record))
        failed.unlink(missing_ok=True)
    else:
        name = f"failed/{job.tree_id}.json"
        with contextlib.suppress(OSError):  # disk trouble: still report the failure
            atomic_write(failed, tf.files.get(name) or _json_bytes(tf.record))
    return tf.record


def _lost(job: TreeJob, error: str) -> TreeFiles:
    """The record of a tree whose worker was lost more often than the executor retries."""
    return TreeFiles(_failed_record(job, error.splitlines()[0] if error else "lost", error), {})


def _failed_record(
    job: TreeJob, error: str, trace: str, params: dict[str, Any] | None = None
) -> dict[str, Any]:
    """What ``failed/<tree_id>.json`` holds for a tree that could not be built."""
    return {
        "tree_id": job.tree_id,
        "status": "failed",
        "species": job.species,
        "index": job.index,
        "tree_seed": job.tree_seed,
        "error": error,
        "traceback": trace,
        "params": params,
    }


# --------------------------------------------------------------------------- the build
@dataclass
class BuildSummary:
    out: str
    trees: int
    skipped: int
    built: int
    failed: list[str]
    sketches: int
    seconds: float
    variant: str

    def text(self) -> str:
        rate = self.built / self.seconds if self.seconds > 0 else 0.0
        s = (
            f"{self.out}: {self.trees} trees ({self.skipped} already done, {self.built} built, "
            f"{len(self.failed)} failed), {self.sketches} sketches in the manifest; "
            f"{self.seconds:.1f} s ({rate:.2f} trees/s, mitsuba {self.variant})"
        )
        if self.failed:
            s += f"\nfailed trees (see {self.out}/failed/): {', '.join(self.failed[:20])}"
            if len(self.failed) > 20:
                s += f" ... (+{len(self.failed) - 20})"
        return s


class _Lock:
    """An advisory lock on ``OUT/.lock`` (released by the OS if the process dies)."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.fh: Any = None

    def __enter__(self) -> _Lock:
        import fcntl

        self.fh = open(self.path, "a+")  # noqa: SIM115 - held for the whole build
        try:
            fcntl.flock(self.fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            self.fh.close()
            raise DatasetError(
                f"{self.path.parent} is being written by another dataset build"
            ) from None
        return self

    def __exit__(self, *exc: object) -> None:
        import fcntl

        fcntl.flock(self.fh, fcntl.LOCK_UN)
        self.fh.close()


def _check_settings(root: Path, settings: dict[str, Any]) -> None:
    f = root / "dataset.json"
    if f.exists():
        try:
            old = json.loads(f.read_text(encoding="utf-8"))
        except (OSError, ValueError) as exc:
            raise DatasetError(
                f"{f} is unreadable ({exc}); remove it or use another --out"
            ) from None
        diff = {k: (old.get(k), v) for k, v in settings.items() if old.get(k) != v}
        if diff:
            what = "; ".join(f"{k}: was {a!r}, now {b!r}" for k, (a, b) in diff.items())
            raise DatasetError(
                f"{root} holds a dataset built with other settings ({what}); "
                "use the same settings to resume, or another --out"
            )
    else:
        atomic_write(f, _json_bytes(settings))


def _load_marker(path: Path) -> dict[str, Any] | None:
    try:
        m = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return m if isinstance(m, dict) and m.get("status") == "done" else None


def _is_finished(root: Path, job: TreeJob, settings: dict[str, Any]) -> bool:
    m = _load_marker(root / "done" / f"{job.tree_id}.json")
    n_rows = sum(
        len(view_styles(settings, job.tree_seed, i)) for i in range(len(settings["views"]))
    )
    if m is None or len(m.get("rows", [])) != n_rows:
        return False
    p = paths_for(job, settings["views"][0])
    files = [root / r["sketch"] for r in m["rows"]] + [root / p["params"], root / p["render"]]
    return all(f.is_file() for f in files)


def _clean_temp_files(root: Path) -> int:
    n = 0
    for sub in ("sketches", "params", "renders", "done", "failed", "."):
        d = root / sub
        if d.is_dir():
            for f in d.rglob(".*.tmp"):
                f.unlink(missing_ok=True)
                n += 1
    return n


def write_manifest(root: Path, jobs: Sequence[TreeJob]) -> int:
    """Manifest from the per-tree markers, in plan order; returns the number of rows."""
    rows: list[dict[str, Any]] = []
    for job in jobs:
        m = _load_marker(root / "done" / f"{job.tree_id}.json")
        if m is not None:
            rows.extend(m["rows"])
    cols = MANIFEST_COLUMNS + (("style",) if any("style" in r for r in rows) else ())
    lines = "".join(json.dumps({k: r[k] for k in cols}) + "\n" for r in rows)
    atomic_write(root / "manifest.jsonl", lines.encode("utf-8"))
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=list(cols), lineterminator="\n")
    w.writeheader()
    for r in rows:
        w.writerow({k: r[k] for k in cols})
    atomic_write(root / "manifest.csv", buf.getvalue().encode("utf-8"))
    return len(rows)


def _meshers(root: Path, jobs: Sequence[TreeJob]) -> dict[str, int]:
    """How many finished trees each mesher made."""
    out: dict[str, int] = {}
    for job in jobs:
        m = _load_marker(root / "done" / f"{job.tree_id}.json")
        if m is not None:
            name = str(m.get("mesher", "?"))
            out[name] = out.get(name, 0) + 1
    return out


def row_style(row: dict[str, Any]) -> str:
    """A manifest row's drawing style (rows of SG-only datasets have no column: ``sg``)."""
    return str(row.get("style", "sg"))


def read_manifest(
    out: str | os.PathLike[str],
    split: str | None = None,
    styles: Sequence[str] | None = None,
) -> list[dict[str, Any]]:
    """The rows of ``OUT/manifest.jsonl`` (only those of ``split`` and of ``styles`` when
    given)."""
    if split is not None and split not in SPLITS:
        raise DatasetError(f"unknown split {split!r}: use one of {', '.join(SPLITS)}")
    if styles is not None:
        from .styles import check_styles

        try:
            styles = check_styles(styles)
        except ValueError as exc:
            raise DatasetError(str(exc)) from None
    f = Path(out) / "manifest.jsonl"
    if not f.is_file():
        raise DatasetError(f"{f}: no manifest (has the dataset been built?)")
    rows = [json.loads(line) for line in f.read_text(encoding="utf-8").splitlines() if line]
    if split is not None:
        rows = [r for r in rows if r["split"] == split]
    if styles is not None:
        rows = [r for r in rows if row_style(r) in styles]
    return rows


def _run_jobs(
    cfg: DatasetConfig,
    jobs: list[TreeJob],
    settings: dict[str, Any],
    executor: PieceRunner | None,
) -> Iterator[dict[str, Any]]:
    root = cfg.out_dir
    if executor is None:  # in this process, mitsuba on every core
        build = TreeWorker(settings, threads=None)()
        for job in jobs:
            yield _store(root, job, build(job))
        return
    for o in executor.run(TreeWorker(settings, threads=1), jobs):
        job = jobs[o.index]
        yield _store(root, job, o.value if o.error is None else _lost(job, o.error))


def build_dataset(
    cfg: DatasetConfig,
    progress: bool | None = None,
    on_tree: Callable[[dict[str, Any]], None] | None = None,
    executor: PieceRunner | None = None,
    only_split: str | None = None,
) -> BuildSummary:
    """Build (or resume) the dataset described by ``cfg``; see the module docstring.

    ``only_split`` ("train", "val" or "test") builds only that split's trees, the same
    trees and files as the full build (a test split to score a network on, in a tenth of
    the time); the manifest then lists that split alone.

    ``executor`` spreads the trees (``treesketch.executor``: a local process pool, Ray);
    None builds them in this process.  Whichever runs them, the files are the same bytes.
    """
    if executor is None and int(cfg.workers) > 1:
        raise DatasetError(
            f"workers={cfg.workers} needs an executor: pass "
            f"executor=treesketch.executor.LocalExecutor({cfg.workers}) (the CLI does)"
        )
    if executor is not None and int(cfg.workers) > 1:
        raise DatasetError("give either workers or an executor, not both")
    if only_split not in (None, "train", "val", "test"):
        raise DatasetError(f"only_split must be train, val or test, got {only_split!r}")
    root = cfg.out_dir
    if root.exists() and not root.is_dir():
        raise DatasetError(f"--out {root} exists and is not a folder")
    try:
        root.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise DatasetError(f"cannot create --out {root}: {exc}") from None
    settings = cfg.settings()
    t0 = time.perf_counter()
    with _Lock(root / ".lock"):
        _check_settings(root, settings)
        removed = _clean_temp_files(root)
        if removed:
            log.info("removed %d temporary files left by an interrupted run", removed)
        jobs = [j for j in plan(cfg) if only_split is None or j.split == only_split]
        todo = [j for j in jobs if not _is_finished(root, j, settings)]
        skipped = len(jobs) - len(todo)
        if todo:
            (root / "DONE").unlink(missing_ok=True)
        log.info("%d trees planned, %d already done, %d to build", len(jobs), skipped, len(todo))
        failed: list[str] = []
        built = 0
        variant = "n/a"
        with _Progress(len(todo), enabled=progress) as bar:
            for rec in _run_jobs(cfg, todo, settings, executor):
                if rec["status"] == "done":
                    built += 1
                else:
                    failed.append(rec["tree_id"])
                    log.warning(
                        "tree %s failed: %s (parameters and traceback in %s)",
                        rec["tree_id"],
                        rec["error"],
                        root / "failed" / f"{rec['tree_id']}.json",
                    )
                bar.advance(len(failed))
                if on_tree is not None:
                    on_tree(rec)
        if todo:
            from .backend import init_mitsuba

            variant = init_mitsuba().variant if executor is None else _variant_name()
        n_rows = write_manifest(root, jobs)
        summary = BuildSummary(
            out=str(root),
            trees=len(jobs),
            skipped=skipped,
            built=built,
            failed=failed,
            sketches=n_rows,
            seconds=time.perf_counter() - t0,
            variant=variant,
        )
        done = {
            "trees": len(jobs),
            "sketches": n_rows,
            "failed": failed,
            "seconds_last_run": round(summary.seconds, 2),
            "meshers": _meshers(root, jobs),
        }
        atomic_write(root / "DONE", _json_bytes(done))
    return summary


def _variant_name() -> str:
    """The variant the workers pick (same rule, without importing mitsuba here)."""
    from .backend import LLVM_VARIANT, SCALAR_VARIANT, choose_llvm_path

    forced = os.environ.get("TREESKETCH_MI_VARIANT", "").strip()
    if forced:
        return forced
    return LLVM_VARIANT if choose_llvm_path() else SCALAR_VARIANT


class _Progress:
    """A rich progress bar on a terminal; periodic log lines (rate, ETA) otherwise."""

    def __init__(self, total: int, enabled: bool | None = None, every_s: float = 15.0) -> None:
        self.total = total
        self.tty = sys.stderr.isatty() if enabled is None else enabled
        self.every_s = every_s
        self.done = 0
        self.t0 = time.perf_counter()
        self.last = self.t0
        self._rich: Any = None
        self._task: Any = None

    def __enter__(self) -> _Progress:
        if self.tty and self.total:
            from rich.progress import (
                BarColumn,
                MofNCompleteColumn,
                Progress,
                TextColumn,
                TimeElapsedColumn,
                TimeRemainingColumn,
            )

            self._rich = Progress(
                TextColumn("[bold]trees"),
                BarColumn(),
                MofNCompleteColumn(),
                TextColumn("{task.fields[rate]}"),
                TimeElapsedColumn(),
                TextColumn("ETA"),
                TimeRemainingColumn(),
                TextColumn("{task.fields[failed]}"),
            )
            self._rich.start()
            self._task = self._rich.add_task("build", total=self.total, rate="", failed="")
        return self

    def advance(self, n_failed: int) -> None:
        self.done += 1
        now = time.perf_counter()
        el = now - self.t0
        rate = self.done / el if el > 0 else 0.0
        eta = (self.total - self.done) / rate if rate > 0 else float("inf")
        if self._rich is not None:
            self._rich.update(
                self._task,
                advance=1,
                rate=f"{rate:.2f} trees/s",
                failed=f"{n_failed} failed" if n_failed else "",
            )
        elif now - self.last >= self.every_s or self.done == self.total:
            self.last = now
            print(
                f"[dataset] {self.done}/{self.total} trees, {rate:.2f} trees/s, "
                f"elapsed {el:.0f} s, ETA {eta:.0f} s, {n_failed} failed",
                file=sys.stderr,
                flush=True,
            )

    def __exit__(self, *exc: object) -> None:
        if self._rich is not None:
            self._rich.stop()
