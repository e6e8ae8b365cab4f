"""Symmetric Hausdorff distance between tree meshes (pymeshlab / MeshLab's Metro filter).

Definition used everywhere in this project (and stated in the reports):

* Each direction A->B samples points on A (``samples`` of its vertices and ``samples``
  area-weighted points on its faces, drawn from a fixed seed so the same meshes give the
  same distance in any process) and measures, for each sample, the distance to the
  closest point of B's *surface* (MeshLab ``get_hausdorff_distance``).  ``maxdist`` is set to the diagonal of the union of both bounding boxes, so no
  sample is ever discarded.
* Symmetric **max** = max of the two directional maxima (the classical Hausdorff distance).
  Symmetric **mean** = mean of the two directional means (each over its samples).
* **Normalised** values divide by the ground-truth bounding-box diagonal (for the branch
  and leaf parts: the diagonal of the whole ground-truth tree, so parts stay comparable).

Empty meshes: both empty gives 0 (``status="both empty"``); exactly one empty gives NaN
distances with ``status="pred empty"`` / ``"gt empty"``.  Aggregates should skip NaN and say
how many were skipped.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING

import numpy as np
import trimesh

if TYPE_CHECKING:  # pragma: no cover
    from weberpenn.treemesh import TreeMesh

PARTS = ("branches", "leaves", "combined")
DEFAULT_SAMPLES = 20_000


@dataclass(frozen=True)
class Distance:
    """One symmetric Hausdorff measurement (absolute units and normalised by ``diagonal``)."""

    max: float
    mean: float
    max_norm: float
    mean_norm: float
    diagonal: float
    samples: int
    status: str = "ok"

    def to_dict(self) -> dict:
        return asdict(self)


def _as_arrays(mesh: trimesh.Trimesh | tuple, name: str) -> tuple[np.ndarray, np.ndarray]:
    if isinstance(mesh, trimesh.Trimesh):
        v, f = mesh.vertices, mesh.faces
    elif isinstance(mesh, tuple) and len(mesh) == 2:
        v, f = mesh
    else:
        raise TypeError(
            f"{name}: expected a trimesh.Trimesh or (vertices, faces), got {type(mesh).__name__}"
        )
    v = np.ascontiguousarray(np.asarray(v, dtype=np.float64).reshape(-1, 3))
    f = np.ascontiguousarray(np.asarray(f, dtype=np.int32).reshape(-1, 3))
    if len(v) and not np.isfinite(v).all():
        raise ValueError(f"{name}: vertices contain NaN or infinity")
    if len(f) and (f.min() < 0 or f.max() >= len(v)):
        raise ValueError(f"{name}: face indices out of range 0..{len(v) - 1}")
    return v, f


def bbox_diagonal(vertices: np.ndarray) -> float:
    """Length of the axis-aligned bounding-box diagonal (0 for no vertices)."""
    v = np.asarray(vertices, dtype=np.float64).reshape(-1, 3)
    if not len(v):
        return 0.0
    return float(np.linalg.norm(v.max(axis=0) - v.min(axis=0)))


def _surface_points(v: np.ndarray, f: np.ndarray, samples: int, seed: int) -> np.ndarray:
    """``samples`` of the mesh's vertices and ``samples`` area-weighted points on its faces,
    drawn from a seeded generator: the same meshes give the same points in any process
    (pymeshlab's own sampler draws from one process-wide generator, so its distances
    depend on every call made before)."""
    rng = np.random.default_rng(seed)
    verts = v if len(v) <= samples else v[np.sort(rng.choice(len(v), samples, replace=False))]
    tri = v[f]
    area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    total = float(area.sum())
    if not total > 0:
        return verts
    face = rng.choice(len(f), samples, p=area / total)
    r = rng.random((samples, 2))
    flip = r.sum(axis=1) > 1.0  # fold the unit square onto the triangle
    r[flip] = 1.0 - r[flip]
    t = tri[face]
    on_faces = t[:, 0] + r[:, :1] * (t[:, 1] - t[:, 0]) + r[:, 1:] * (t[:, 2] - t[:, 0])
    return np.vstack([verts, on_faces])


def _directional(ms, points: np.ndarray, target: int, maxdist: float) -> dict:
    """Distances from every one of ``points`` to mesh ``target`` of ``ms``."""
    import pymeshlab

    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=np.ascontiguousarray(points)), "points")
    cloud = ms.current_mesh_id()
    return ms.get_hausdorff_distance(
        sampledmesh=cloud,
        targetmesh=target,
        samplevert=True,  # with samplenum = the point count, every point is measured
        sampleedge=False,
        samplefauxedge=False,
        sampleface=False,
        samplenum=len(points),
        maxdist=pymeshlab.PureValue(float(maxdist)),
    )


def hausdorff(
    pred: trimesh.Trimesh | tuple,
    gt: trimesh.Trimesh | tuple,
    samples: int = DEFAULT_SAMPLES,
    diagonal: float | None = None,
) -> Distance:
    """Symmetric Hausdorff distance between ``pred`` and ``gt`` (see the module docstring).

    ``diagonal`` (default: ``gt``'s bounding-box diagonal) is what normalised values divide by.
    """
    if int(samples) < 1:
        raise ValueError(f"samples must be >= 1, got {samples}")
    pv, pf = _as_arrays(pred, "pred")
    gv, gf = _as_arrays(gt, "gt")
    diag = bbox_diagonal(gv) if diagonal is None else float(diagonal)
    if not math.isfinite(diag) or diag < 0:
        raise ValueError(f"diagonal must be a finite non-negative number, got {diagonal}")
    p_empty, g_empty = len(pf) == 0, len(gf) == 0
    if p_empty or g_empty:
        if p_empty and g_empty:
            return Distance(0.0, 0.0, 0.0, 0.0, diag, 0, "both empty")
        nan = float("nan")
        return Distance(nan, nan, nan, nan, diag, 0, "pred empty" if p_empty else "gt empty")

    import pymeshlab

    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=pv, face_matrix=pf), "pred")
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=gv, face_matrix=gf), "gt")
    reach = bbox_diagonal(np.vstack([pv, gv])) * 1.01 + 1e-9  # nothing is farther: keep all
    ab = _directional(ms, _surface_points(pv, pf, int(samples), 0), 1, reach)
    ba = _directional(ms, _surface_points(gv, gf, int(samples), 1), 0, reach)
    dmax = float(max(ab["max"], ba["max"]))
    dmean = float(0.5 * (ab["mean"] + ba["mean"]))
    scale = 1.0 / diag if diag > 0 else float("nan")
    n = int(ab["n_samples"] + ba["n_samples"])
    return Distance(dmax, dmean, dmax * scale, dmean * scale, diag, n)


def tree_hausdorff(
    pred: TreeMesh, gt: TreeMesh, samples: int = DEFAULT_SAMPLES
) -> dict[str, Distance]:
    """Distances for the branch mesh, the leaf mesh and both combined.

    All three are normalised by the diagonal of the whole ground-truth tree.
    """
    diag = bbox_diagonal(gt.bounds())
    return {
        "branches": hausdorff(pred.branches, gt.branches, samples, diag),
        "leaves": hausdorff(pred.leaves, gt.leaves, samples, diag),
        "combined": hausdorff(pred.combined(), gt.combined(), samples, diag),
    }


def rotate_about_trunk(mesh: TreeMesh, degrees: float) -> TreeMesh:
    """A copy of ``mesh`` turned by ``degrees`` about the Z (trunk) axis.

    A tree found by refinement to match a sketch seen at yaw ``y_found`` estimates the
    ground truth seen at the sketch's yaw ``y_view``; turned by ``y_view - y_found`` it is
    in the ground truth's frame (camera yaw turns the camera, see ``render.camera``).
    """
    from weberpenn.treemesh import TreeMesh

    m = trimesh.transformations.rotation_matrix(math.radians(float(degrees)), [0, 0, 1])
    b, lv = mesh.branches.copy(), mesh.leaves.copy()
    if len(b.vertices):
        b.apply_transform(m)
    if len(lv.vertices):
        lv.apply_transform(m)
    return TreeMesh(branches=b, leaves=lv, species=mesh.species, meta=dict(mesh.meta))


def aligned_tree_hausdorff(
    pred: TreeMesh,
    gt: TreeMesh,
    samples: int = DEFAULT_SAMPLES,
    step: float = 15.0,
    coarse_samples: int = 2000,
) -> tuple[float, Distance]:
    """Mesh error up to a turn about the trunk: ``pred`` turned every ``step`` degrees,
    the turn with the smallest max distance between ``coarse_samples`` surface points of
    each (KD-trees) kept and measured exactly at ``samples``.  Returns (turn in degrees,
    the combined branch+leaf :class:`Distance`, normalised by the ground-truth diagonal).

    A single sketch says nothing about which way the tree faces in depth, and an estimate
    from it (TSN's or refined) has no reason to share the ground truth's orientation; this
    measures the shape alone.  The plain :func:`tree_hausdorff` stays the headline metric.
    """
    if not (math.isfinite(step) and 0 < step <= 360):
        raise ValueError(f"step must be in (0, 360] degrees, got {step}")
    from scipy.spatial import cKDTree

    a, b = pred.combined(), gt.combined()
    diag = bbox_diagonal(gt.bounds())
    if len(a.faces) == 0 or len(b.faces) == 0:
        return 0.0, hausdorff(a, b, samples, diag)
    # coarse search on surface point samples (a turn moves points, not the KD-trees)
    pa = np.asarray(trimesh.sample.sample_surface(a, coarse_samples, seed=0)[0])
    pb = np.asarray(trimesh.sample.sample_surface(b, coarse_samples, seed=1)[0])
    ta, tb = cKDTree(pa), cKDTree(pb)
    best, best_d = 0.0, math.inf
    for turn in np.arange(0.0, 360.0 - 1e-9, float(step)):
        c, s = math.cos(math.radians(turn)), math.sin(math.radians(turn))
        rot = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        d = max(tb.query(pa @ rot.T)[0].max(), ta.query(pb @ rot)[0].max())
        if d < best_d:
            best, best_d = float(turn), float(d)
    return best, hausdorff(rotate_about_trunk(pred, best).combined(), b, samples, diag)


def params_hausdorff(pred_params, gt_params, seed: int = 0, samples: int = DEFAULT_SAMPLES):
    """Grow both parameter dictionaries with the same ``seed`` and compare (dict per part)."""
    from weberpenn import build_mesh, grow

    return tree_hausdorff(
        build_mesh(grow(pred_params, seed=seed)), build_mesh(grow(gt_params, seed=seed)), samples
    )


def seed_floor(
    params, seeds: tuple[int, int] = (0, 1), samples: int = DEFAULT_SAMPLES
) -> dict[str, Distance]:
    """The noise floor: the same parameters grown with two different seeds.

    A prediction cannot be expected to come closer to the ground truth than this where
    randomness remains in the generator (leaf placement, etc.).
    """
    if len(seeds) != 2 or seeds[0] == seeds[1]:
        raise ValueError(f"seed_floor needs two different seeds, got {seeds}")
    from weberpenn import build_mesh, grow

    a = build_mesh(grow(params, seed=int(seeds[0])))
    b = build_mesh(grow(params, seed=int(seeds[1])))
    return tree_hausdorff(a, b, samples)


def summarise(values: list[Distance]) -> dict:
    """Mean of max/mean (absolute and normalised) over measurements, skipping NaN ones."""
    ok = [d for d in values if math.isfinite(d.max)]
    out = {"n": len(values), "skipped": len(values) - len(ok)}
    for k in ("max", "mean", "max_norm", "mean_norm"):
        out[k] = float(np.mean([getattr(d, k) for d in ok])) if ok else float("nan")
    return out
