"""The rotation experiment (paper, Fig. "HDD distances for each degree of rotation").

A ground-truth tree is turned about its trunk axis in ``step``-degree increments; at each
yaw its synthetic sketch is rendered (one ``render.SketchRenderer``, scenes built once), a
parameter dictionary is predicted from that sketch (and optionally refined), the predicted
tree is grown, and its symmetric Hausdorff distance to the ground truth is measured
(``eval.hausdorff``, combined branch+leaf mesh, normalised by the ground-truth
bounding-box diagonal).  ``turns`` adds other drawings of the tree at each yaw (e.g.
``(90,)``: a second sketch from 90 degrees further round), handed to the pipeline as the
views of one tree (``treesketch.views``).

The predictions come from a pipeline handed in (``treesketch.Pipeline``, or anything with
``settings``, ``estimate(sketch)`` and ``run(sketch)``): with refining settings each view is
estimated and refined (``run``), otherwise estimated only (``estimate``).  With an
executor the pipeline travels to its workers, so it must pickle (a ``treesketch.Pipeline``
does: a TSN estimator reloads its checkpoint in the worker).

Every tree is grown as the pipeline grows its own, ``grow(params)``: the random draws
come from the dictionary's ``seed`` key.  ``seed`` (when given) is the key both trees
carry, the paper's protocol (its predictions are grown with the ground truth's seed);
hand in a pipeline whose estimates carry the same key (``treesketch.estimators.
SeededEstimator``), so that a refinement searches the very trees it is measured as.
"""

from __future__ import annotations

import csv
import io
import json
import math
import time
from collections.abc import Callable, Mapping
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from weberpenn import TreeParams, build_mesh, grow
from weberpenn.fileio import atomic_write

from .hausdorff import DEFAULT_SAMPLES, hausdorff, rotate_about_trunk

Progress = Callable[[int, int], None]

CSV_FIELDS = (
    "angle",
    "hd_max",
    "hd_mean",
    "hd_max_norm",
    "hd_mean_norm",
    "status",
    "refined",
    "loss_before",
    "loss_after",
    "seconds",
)


@dataclass(frozen=True)
class SweepRow:
    angle: float
    hd_max: float
    hd_mean: float
    hd_max_norm: float
    hd_mean_norm: float
    status: str
    refined: bool
    loss_before: float
    loss_after: float
    seconds: float


@dataclass
class SweepResult:
    rows: list[SweepRow]
    gt_params: TreeParams
    predictions: list[TreeParams] = field(default_factory=list)
    sketches: list[np.ndarray] = field(default_factory=list)
    seed: int | None = None  # the seed key both trees carry (None: each its own)
    size: int = 256

    def values(self, metric: str = "hd_max_norm") -> np.ndarray:
        return np.array([getattr(r, metric) for r in self.rows], dtype=np.float64)

    def cases(self, metric: str = "hd_max_norm") -> dict[str, int]:
        """Row indices of the worst, median and best angle (NaN rows ignored)."""
        v = self.values(metric)
        ok = np.flatnonzero(np.isfinite(v))
        if not len(ok):
            return {}
        order = ok[np.argsort(v[ok], kind="stable")]
        return {
            "worst": int(order[-1]),
            "median": int(order[len(order) // 2]),
            "best": int(order[0]),
        }

    def summary(self, metric: str = "hd_max_norm") -> dict[str, float]:
        v = self.values(metric)
        v = v[np.isfinite(v)]
        if not len(v):
            return {"n": 0, "failed": len(self.rows)}
        return {
            "n": len(v),
            "failed": len(self.rows) - len(v),
            "mean": float(v.mean()),
            "min": float(v.min()),
            "max": float(v.max()),
            "std": float(v.std()),
        }


def yaw_angles(step: float) -> np.ndarray:
    """0, step, 2 step, ... < 360 (``step`` must divide 360 into whole steps)."""
    step = float(step)
    if not math.isfinite(step) or step <= 0 or step > 360:
        raise ValueError(f"step must be in (0, 360] degrees, got {step}")
    n = 360.0 / step
    if abs(n - round(n)) > 1e-9:
        raise ValueError(f"step must divide 360 evenly, got {step} (360/step = {n:.3f})")
    return np.arange(int(round(n))) * step


def _seeded(params: Mapping[str, Any], seed: int | None) -> TreeParams:
    """The dictionary with the sweep's seed key (None: its own)."""
    p = TreeParams(params)
    return p if seed is None else p.replace(seed=int(seed))


def _params_key(p: Mapping[str, Any]) -> str:
    return json.dumps(TreeParams(p).to_dict(), sort_keys=True, default=str)


@dataclass(frozen=True)
class AngleResult:
    """One angle of the sweep: its row, the (refined) prediction and the input sketch."""

    row: SweepRow
    prediction: TreeParams | None
    sketch: np.ndarray | None


def _angle_fn(
    gt_mesh: Any,
    pipeline: Any,
    size: int,
    samples: int,
    seed: int | None,
    turns: tuple[float, ...] = (),
) -> Callable[[float], AngleResult]:
    """The function that does one angle: sketch at that yaw (and at each of ``turns``
    further round: the other views), estimate (and refine), Hausdorff to the ground
    truth."""
    from render.sketch import SketchRenderer

    gt_combined = gt_mesh.combined()
    renderer = SketchRenderer(gt_mesh)
    cache: dict[str, Any] = {}  # identical predictions share one mesh and distance

    def one(yaw: float) -> AngleResult:
        t0 = time.perf_counter()
        img = renderer.sketch(float(yaw), size=size)
        drawing: Any = img
        if turns:
            others = [(renderer.sketch((float(yaw) + t) % 360.0, size=size), t) for t in turns]
            drawing = [img, *others]
        lb = la = float("nan")
        refining = bool(pipeline.settings.refine)
        if refining:
            run = pipeline.run(drawing)
            pred, lb, la = run.params, run.losses["before"], run.losses["after"]
            # the refined tree matches the sketch at the yaw it found: turn it into the
            # ground truth's frame before measuring
            turn = (float(yaw) - run.yaw) % 360.0
        else:
            pred, turn = TreeParams(pipeline.estimate(drawing).params), 0.0
        key = f"{_params_key(pred)}@{turn:.6f}"
        if key not in cache:
            pm = build_mesh(grow(_seeded(pred, seed)))
            if turn:
                pm = rotate_about_trunk(pm, turn)
            cache[key] = hausdorff(pm.combined(), gt_combined, samples)
        d = cache[key]
        row = SweepRow(
            float(yaw),
            d.max,
            d.mean,
            d.max_norm,
            d.mean_norm,
            d.status,
            refining,
            lb,
            la,
            time.perf_counter() - t0,
        )
        return AngleResult(row, pred, img)

    return one


@dataclass(frozen=True)
class SweepWorker:
    """Worker factory for an executor (picklable): each worker grows the ground truth and
    builds its scene once, then does angles with its own copy of the pipeline."""

    gt: TreeParams
    pipeline: Any
    size: int
    samples: int
    seed: int | None
    turns: tuple[float, ...] = ()

    def __call__(self) -> Callable[[float], AngleResult]:
        from render.backend import init_mitsuba

        init_mitsuba(threads=1)
        gt_mesh = build_mesh(grow(_seeded(self.gt, self.seed)))
        return _angle_fn(gt_mesh, self.pipeline, self.size, self.samples, self.seed, self.turns)


def _failed_row(yaw: float, error: str) -> SweepRow:
    nan = float("nan")
    first = error.splitlines()[0] if error else "lost"
    return SweepRow(float(yaw), nan, nan, nan, nan, f"failed: {first}", False, nan, nan, 0.0)


def rotation_sweep(
    gt_params: Mapping[str, Any],
    pipeline: Any,
    step: float = 5.0,
    size: int = 256,
    samples: int = DEFAULT_SAMPLES,
    seed: int | None = None,
    progress: Progress | None = None,
    executor: Any = None,
    turns: tuple[float, ...] = (),
) -> SweepResult:
    """Run the sweep (see the module text).

    ``turns``: the other views' yaws relative to the swept one (degrees; ``(90,)`` for a
    front and a side drawing at every angle).

    ``executor`` (``treesketch.executor``: a local pool, Ray) spreads the angles; each is
    deterministic, so the rows are the same values whichever runs them.  An angle that
    fails there is reported as a row with status ``failed: ...`` and NaN distances (its
    prediction and sketch are None); in this process an error propagates.
    """
    gt = TreeParams(gt_params)
    angles = yaw_angles(step)
    gt_mesh = build_mesh(grow(_seeded(gt, seed)))
    if gt_mesh.is_empty:
        raise ValueError("the ground-truth parameters grow an empty tree; nothing to compare")
    result = SweepResult([], gt, seed=None if seed is None else int(seed), size=int(size))
    turns = tuple(float(t) % 360.0 for t in turns)
    if any(not math.isfinite(t) for t in turns) or len(turns) > 3:
        raise ValueError(f"turns must be at most 3 finite angles in degrees, got {turns}")
    opts = (int(size), int(samples), None if seed is None else int(seed), turns)
    outs: list[AngleResult] = []
    if executor is None:
        one = _angle_fn(gt_mesh, pipeline, *opts)
        for i, yaw in enumerate(angles):
            outs.append(one(float(yaw)))
            if progress is not None:
                progress(i + 1, len(angles))
    else:
        from_worker = executor.run(SweepWorker(gt, pipeline, *opts), [float(a) for a in angles])
        done: dict[int, AngleResult] = {}
        for o in from_worker:
            ok = o.error is None
            done[o.index] = (
                o.value if ok else AngleResult(_failed_row(angles[o.index], o.error), None, None)
            )
            if progress is not None:
                progress(len(done), len(angles))
        outs = [done[i] for i in range(len(angles))]
    for a in outs:
        result.rows.append(a.row)
        result.predictions.append(a.prediction)  # type: ignore[arg-type]
        result.sketches.append(a.sketch)  # type: ignore[arg-type]
    return result


def rows_csv(rows: list[SweepRow]) -> str:
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=CSV_FIELDS, lineterminator="\n")
    w.writeheader()
    for r in rows:
        d = asdict(r)
        w.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in d.items()})
    return buf.getvalue()


def write_csv(rows: list[SweepRow], path: str | Path) -> Path:
    return atomic_write(Path(path), rows_csv(rows))


def _save_fig(fig, path: Path) -> Path:
    return atomic_write(path, lambda tmp: fig.savefig(tmp, dpi=100, format="png"))


def plot_sweep(
    result: SweepResult, path: str | Path, metric: str = "hd_max_norm", title: str = ""
) -> Path:
    """Distance against angle, each point coloured by its value (the paper's figure)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    x = np.array([r.angle for r in result.rows])
    y = result.values(metric)
    fig, ax = plt.subplots(figsize=(7, 3.2))
    ok = np.isfinite(y)
    sc = ax.scatter(x[ok], y[ok], c=y[ok], cmap="jet_r", s=18, edgecolors="none")
    fig.colorbar(sc, ax=ax, label="HDD")
    top = (
        0.1 if ok.any() and np.nanmax(y) <= 0.1 else (float(np.nanmax(y)) * 1.1 if ok.any() else 1)
    )
    ax.set_ylim(0, top)
    ax.set_xlim(-5, 360)
    ax.set_xticks(range(0, 361, 45))
    ax.set_xlabel("angle (degree)")
    ax.set_ylabel("Hausdorff distance / GT diagonal" if metric.endswith("norm") else metric)
    s = result.summary(metric)
    if s.get("n"):
        ax.axhline(s["mean"], color="grey", lw=0.8, ls="--")
        ax.set_title(title or f"mean {s['mean']:.3f}, range {s['min']:.3f}-{s['max']:.3f}")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    try:
        return _save_fig(fig, Path(path))
    finally:
        plt.close(fig)


def plot_cases(
    result: SweepResult, path: str | Path, metric: str = "hd_max_norm", size: int = 192
) -> Path:
    """Worst, median and best angle: input sketch, predicted tree, ground truth (same yaw)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from render.sketch import SketchRenderer

    cases = result.cases(metric)
    if not cases:
        raise ValueError("no finite distances in the sweep; nothing to show")
    gt_r = SketchRenderer(build_mesh(grow(_seeded(result.gt_params, result.seed))))
    fig, axes = plt.subplots(3, 3, figsize=(7.5, 7.8))
    for col, (name, i) in enumerate(cases.items()):
        row = result.rows[i]
        pm = build_mesh(grow(_seeded(result.predictions[i], result.seed)))
        imgs = [
            (result.sketches[i], "input sketch"),
            (SketchRenderer(pm).colour(row.angle, size=size, supersample=1), "predicted"),
            (gt_r.colour(row.angle, size=size, supersample=1), "ground truth"),
        ]
        for r_i, (img, label) in enumerate(imgs):
            ax = axes[r_i, col]
            ax.imshow(img, cmap="gray" if img.ndim == 2 else None, vmin=0, vmax=255)
            ax.set_xticks([])
            ax.set_yticks([])
            if r_i == 0:
                ax.set_title(f"{name}: {row.angle:.0f} deg\nHDD {getattr(row, metric):.3f}")
            if col == 0:
                ax.set_ylabel(label)
    fig.tight_layout()
    try:
        return _save_fig(fig, Path(path))
    finally:
        plt.close(fig)
