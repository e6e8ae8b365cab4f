"""Mitsuba 3 renders of a tree: branch and leaf silhouettes, and a shaded colour picture.

:class:`TreeScene` builds one mitsuba scene per part (branches, leaves) from the
TreeMesh's in-memory arrays, ONCE (building the acceleration structure is the expensive
step), then renders any number of views by casting orthographic rays from
:class:`render.camera.Camera`:

- :meth:`TreeScene.coverage` casts shadow-test rays (``scene.ray_test``) on a regular
  ``ss x ss`` sub-pixel grid and returns the fraction of each pixel covered by the branches
  and by the leaves, separately (the paper renders the two meshes apart: a branch hidden
  behind leaves still shows in the branch silhouette).  The silhouette "black on white"
  image is ``1 - coverage``.
- :meth:`TreeScene.colour` intersects both scenes, keeps the nearer hit and shades it
  (ambient + two-sided Lambert from a fixed sun) with the species' bark and leaf colours,
  on a white background.

With ``llvm_ad_rgb`` all rays of a view go to mitsuba as one vectorised call; with the
``scalar_rgb`` fallback the same scenes are rendered by ``mi.render`` (a ``path``
integrator of depth 1 under a white constant emitter for silhouettes; the colour picture
uses the same geometry and a plain ``direct`` integrator), which is slower but needs no
LLVM.  Everything is deterministic: fixed sample positions, no random sampling in the
vectorised path, a fixed sampler seed in the fallback.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Any

import numpy as np

from .backend import LLVM_VARIANT, Backend, init_mitsuba
from .camera import Camera, Framing, check_size
from .edges import block_counts

log = logging.getLogger(__name__)

# bark and leaf colours (linear RGB, 0..1) per species, for colour renders
SPECIES_COLOURS: dict[str, tuple[tuple[float, float, float], tuple[float, float, float]]] = {
    "maple": ((0.36, 0.25, 0.17), (0.80, 0.30, 0.10)),
    "pine": ((0.40, 0.28, 0.20), (0.12, 0.36, 0.16)),
    "bonsai": ((0.33, 0.24, 0.18), (0.25, 0.50, 0.18)),
    "palm": ((0.55, 0.45, 0.32), (0.30, 0.58, 0.20)),
    "cherry": ((0.30, 0.20, 0.18), (0.96, 0.66, 0.78)),
}
DEFAULT_COLOURS = ((0.38, 0.27, 0.18), (0.25, 0.55, 0.20))
SUN = np.array([0.45, -0.65, 0.61])  # world direction towards the light
AMBIENT = 0.45


def species_colours(species: str | None) -> tuple[np.ndarray, np.ndarray]:
    bark, leaf = SPECIES_COLOURS.get((species or "").lower(), DEFAULT_COLOURS)
    return np.asarray(bark, dtype=np.float64), np.asarray(leaf, dtype=np.float64)


def mesh_arrays(mesh: Any) -> tuple[np.ndarray, np.ndarray] | None:
    """Contiguous float32 vertices and uint32 faces of a trimesh, or None when empty."""
    faces = np.asarray(mesh.faces)
    verts = np.asarray(mesh.vertices)
    if faces.size == 0 or verts.size == 0:
        return None
    if not np.isfinite(verts).all():
        raise ValueError("mesh has non-finite vertex coordinates")
    if faces.min() < 0 or faces.max() >= len(verts):
        raise ValueError("mesh faces index vertices that do not exist")
    v = np.ascontiguousarray(verts, dtype=np.float32).reshape(-1)
    f = np.ascontiguousarray(faces, dtype=np.uint32).reshape(-1)
    return v, f


def _build_scene(mi: Any, name: str, arrays: tuple[np.ndarray, np.ndarray]) -> Any:
    v, f = arrays
    mesh = mi.Mesh(name, len(v) // 3, len(f) // 3, has_vertex_normals=False)
    params = mi.traverse(mesh)
    # the buffers' own types: mi.Float/mi.UInt (LLVM) or dr.scalar.ArrayXf/ArrayXu (scalar)
    params["vertex_positions"] = type(params["vertex_positions"])(v)
    params["faces"] = type(params["faces"])(f)
    params.update()
    return mi.load_dict({"type": "scene", name: mesh})


@dataclass(frozen=True)
class Coverage:
    """Fraction of each pixel covered by the branches and by the leaves (1 = fully)."""

    branches: np.ndarray  # (size, size) float32
    leaves: np.ndarray  # (size, size) float32
    branches_hr: np.ndarray | None = None  # (size*ss, size*ss) bool, when kept

    def silhouettes(self) -> tuple[np.ndarray, np.ndarray]:
        """Black-on-white pictures (1 = white background) of branches and leaves."""
        return 1.0 - self.branches, 1.0 - self.leaves


class CoverageScene:
    """A tree's scene that draws silhouettes: ``framing`` and :meth:`coverage`, from how
    the scene hits one of its parts (``_hit``)."""

    framing: Framing

    def _hit(self, part: int, cam: Camera, size: int, k: int) -> np.ndarray:
        """``(size * k, size * k)`` bool: where rays, ``k x k`` per pixel, hit part 0
        (the branches) or 1 (the leaves)."""
        raise NotImplementedError

    def coverage(
        self,
        yaw: float = 0.0,
        size: int = 256,
        supersample: int = 2,
        pitch: float = 0.0,
        keep_hr: bool = False,
        leaf_supersample: int | None = None,
    ) -> Coverage:
        """Per-pixel coverage of branches (``supersample``^2 rays per pixel) and leaves
        (``leaf_supersample``^2, default the same); ``keep_hr`` keeps the branch hit mask
        at the supersampled resolution (for sub-pixel thinning)."""
        cam = Camera(self.framing, float(yaw), float(pitch))
        size = check_size(size)
        ss = int(supersample)
        ss_leaf = ss if leaf_supersample is None else int(leaf_supersample)
        if ss < 1 or ss_leaf < 1:
            raise ValueError(f"supersample must be >= 1, got {supersample!r}, {leaf_supersample!r}")
        hits = [self._hit(0, cam, size, ss), self._hit(1, cam, size, ss_leaf)]
        cov_b, cov_l = _covered(hits[0], ss), _covered(hits[1], ss_leaf)
        return Coverage(cov_b, cov_l, hits[0] if keep_hr else None)


class TreeScene(CoverageScene):
    """A tree's mitsuba scenes, built once; render any yaw/pitch/size afterwards."""

    def __init__(
        self, tree_mesh: Any, framing: Framing | None = None, species: str | None = None
    ) -> None:
        self.backend: Backend = init_mitsuba()
        import mitsuba as mi

        self._mi = mi
        self.species = species or getattr(tree_mesh, "species", None)
        b = mesh_arrays(tree_mesh.branches)
        lv = mesh_arrays(tree_mesh.leaves)
        verts = [a[0].reshape(-1, 3) for a in (b, lv) if a is not None]
        self.framing = framing or Framing.from_vertices(
            np.vstack(verts) if verts else np.zeros((0, 3))
        )
        self._branches = _build_scene(mi, "branches", b) if b is not None else None
        self._leaves = _build_scene(mi, "leaves", lv) if lv is not None else None

    @property
    def is_empty(self) -> bool:
        return self._branches is None and self._leaves is None

    # ------------------------------------------------------------------ silhouettes
    def _hit(self, part: int, cam: Camera, size: int, k: int) -> np.ndarray:
        scene = (self._branches, self._leaves)[part]
        n = size * k
        if scene is None:
            return np.zeros((n, n), dtype=bool)
        if self.backend.variant == LLVM_VARIANT:
            origins, direction = cam.rays(size, k)
            return self._ray_test(scene, origins, direction, n)
        return self._render_scalar(scene, cam, n)

    def _ray_test(self, scene: Any, origins: np.ndarray, direction: np.ndarray, n: int) -> Any:
        mi = self._mi
        d = [float(c) for c in direction]
        ray = mi.Ray3f(mi.Point3f(origins[0], origins[1], origins[2]), mi.Vector3f(*d))
        return scene.ray_test(ray).numpy().astype(bool).reshape(n, n)

    def _render_scalar(self, scene: Any, cam: Camera, n: int) -> np.ndarray:
        """Fallback for scalar_rgb: mi.render with a white constant emitter, depth 1."""
        if scene is None:
            return np.zeros((n, n), dtype=bool)
        mi = self._mi
        shapes = [s for s in scene.shapes()]
        d = {"type": "scene", "env": {"type": "constant", "radiance": {"type": "rgb", "value": 1}}}
        for i, s in enumerate(shapes):
            d[f"s{i}"] = s
        sc = mi.load_dict(d)
        img = np.asarray(
            mi.render(sc, sensor=_sensor(mi, cam, n, 1), integrator=_integrator(mi, "path"))
        )
        return img[..., 0] < 0.5

    # ------------------------------------------------------------------ colour
    def colour(
        self, yaw: float = 0.0, size: int = 256, supersample: int = 2, pitch: float = 0.0
    ) -> np.ndarray:
        """Shaded picture (size, size, 3) uint8 on white: bark and leaf colours, one sun."""
        cam = Camera(self.framing, float(yaw), float(pitch))
        ss = int(supersample)
        n = int(size) * ss
        origins, direction = cam.rays(size, ss)
        rgb = np.ones((n * n, 3), dtype=np.float32)
        if not self.is_empty:
            bark, leaf = species_colours(self.species)
            hits = []
            for scene, col in ((self._branches, bark), (self._leaves, leaf)):
                if scene is None:
                    continue
                t, normal = self._intersect(scene, origins, direction, cam, n)
                hits.append((t, normal, col))
            t_all = np.stack([h[0] for h in hits])  # (k, N)
            which = np.argmin(t_all, axis=0)
            t_min = t_all[which, np.arange(t_all.shape[1])]
            hit = np.isfinite(t_min)
            sun = SUN / np.linalg.norm(SUN)
            for k, (_, normal, col) in enumerate(hits):
                sel = hit & (which == k)
                lam = np.abs(normal[sel] @ sun.astype(np.float32))  # two-sided leaves
                shade = AMBIENT + (1.0 - AMBIENT) * lam
                rgb[sel] = np.clip(col[None, :] * shade[:, None] * 1.25, 0.0, 1.0)
        img = downsample(rgb.reshape(n, n, 3), ss)
        return np.round(np.clip(img, 0, 1) ** (1 / 2.2) * 255).astype(np.uint8)

    def _intersect(
        self, scene: Any, origins: np.ndarray, direction: np.ndarray, cam: Camera, n: int
    ) -> tuple[np.ndarray, np.ndarray]:
        mi = self._mi
        if self.backend.variant == LLVM_VARIANT:
            d = [float(c) for c in direction]
            ray = mi.Ray3f(mi.Point3f(origins[0], origins[1], origins[2]), mi.Vector3f(*d))
            si = scene.ray_intersect(ray)
            t = si.t.numpy().astype(np.float32).reshape(-1)
            normal = si.n.numpy().astype(np.float32).reshape(3, -1).T
            t[~np.isfinite(t)] = np.inf
            return t, normal
        # scalar fallback: per-pixel depth and normal via the AOV integrator
        img = np.asarray(
            mi.render(
                scene,
                sensor=_sensor(mi, cam, n, 1),
                integrator=mi.load_dict({"type": "aov", "aovs": "dd.y:depth,nn:geo_normal"}),
            )
        ).reshape(n * n, -1)
        depth = img[:, 0].astype(np.float32)
        normal = img[:, 1:4].astype(np.float32)
        t = np.where(depth > 0, depth, np.inf)
        return t, normal


def _covered(hits: np.ndarray, ss: int) -> np.ndarray:
    """:func:`downsample` of a bool hit mask as float32, from its blocks' counts (the
    same floats: a count of ones is exact in float32 either way)."""
    if ss == 1:
        return hits.astype(np.float32)
    return block_counts(hits, ss).astype(np.float32) * np.float32(1.0 / (ss * ss))


def downsample(img: np.ndarray, ss: int) -> np.ndarray:
    if ss == 1:
        return img
    n = img.shape[0] // ss
    out = img.reshape(n, ss, n, ss, *img.shape[2:]).sum(axis=(1, 3), dtype=np.float32)
    return out * np.float32(1.0 / (ss * ss))


def _integrator(mi: Any, kind: str) -> Any:
    return mi.load_dict({"type": kind, "max_depth": 1})


def _sensor(mi: Any, cam: Camera, n: int, spp: int) -> Any:
    """A mitsuba orthographic sensor matching ``cam`` (used by the scalar fallback)."""
    right, up, forward = cam.basis()
    s = cam.framing.span
    centre = cam.framing.centre
    origin = centre - (2.0 * s + 1.0) * forward
    to_world = mi.ScalarTransform4f().look_at(
        origin=[float(x) for x in origin],
        target=[float(x) for x in centre],
        up=[float(x) for x in up],
    ) @ mi.ScalarTransform4f().scale([0.5 * s, 0.5 * s, 1.0])
    return mi.load_dict(
        {
            "type": "orthographic",
            "to_world": to_world,
            "film": {
                "type": "hdrfilm",
                "width": n,
                "height": n,
                "rfilter": {"type": "box"},
                "pixel_format": "rgb",
            },
            "sampler": {"type": "independent", "sample_count": spp, "seed": 0},
        }
    )
