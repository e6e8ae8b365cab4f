"""The mesh of a tree: a branch mesh and a leaf mesh (plain trimesh objects)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import trimesh

from .skeleton import Skeleton


@dataclass(eq=False)
class TreeMesh:
    """Branches and leaves as two ``trimesh.Trimesh`` (both carry UVs when built by
    ``build_mesh``: branches around x along each stem, leaves over the leaf template).

    ``species`` (optional) picks the bark and leaf colours and textures used by exports.
    ``skeleton`` is the grown tree the meshes were built from, when known: level of
    detail (``weberpenn.lod``) re-meshes it at a coarser resolution.  Z is up, the trunk
    base sits at the origin.  Either mesh may be empty.  Write files with
    ``weberpenn.export.export_mesh``.
    """

    branches: trimesh.Trimesh
    leaves: trimesh.Trimesh
    species: str | None = None
    meta: dict = field(default_factory=dict)
    skeleton: Skeleton | None = None

    @property
    def is_empty(self) -> bool:
        return len(self.branches.faces) == 0 and len(self.leaves.faces) == 0

    @property
    def n_faces(self) -> int:
        """Triangles of both meshes together."""
        return len(self.branches.faces) + len(self.leaves.faces)

    def bounds(self) -> np.ndarray:
        """(2, 3) axis-aligned bounds of both meshes; zeros when empty."""
        parts = [m.vertices for m in (self.branches, self.leaves) if len(m.vertices)]
        if not parts:
            return np.zeros((2, 3))
        v = np.vstack(parts)
        return np.array([v.min(axis=0), v.max(axis=0)])

    def combined(self) -> trimesh.Trimesh:
        """Both meshes' geometry in one mesh (for distances and simple exports; no UVs)."""
        parts = [m for m in (self.branches, self.leaves) if len(m.faces)]
        verts = [np.asarray(m.vertices, dtype=np.float64) for m in parts]
        starts = np.cumsum([0] + [len(v) for v in verts])[:-1]
        faces = [
            np.asarray(m.faces, dtype=np.int64) + s for m, s in zip(parts, starts, strict=True)
        ]
        return trimesh.Trimesh(
            vertices=np.vstack(verts) if verts else np.zeros((0, 3)),
            faces=np.vstack(faces) if faces else np.zeros((0, 3), dtype=np.int64),
            process=False,
        )
