"""The mesh of a tree: a branch mesh and a leaf mesh (plain trimesh objects)."""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import trimesh


@dataclass(eq=False)
class TreeMesh:
    """Branches and leaves as two ``trimesh.Trimesh`` (leaves carry UVs).

    ``species`` (optional) picks the bark and leaf colours used by exports and renders.
    Z is up, the trunk base sits at the origin.  Either mesh may be empty.
    """

    branches: trimesh.Trimesh
    leaves: trimesh.Trimesh
    species: str | None = None
    meta: dict = field(default_factory=dict)

    @property
    def is_empty(self) -> bool:
        return len(self.branches.faces) == 0 and len(self.leaves.faces) == 0

    def bounds(self) -> np.ndarray:
        """(2, 3) axis-aligned bounds of both meshes; zeros when empty."""
        parts = [m.vertices for m in (self.branches, self.leaves) if len(m.vertices)]
        if not parts:
            return np.zeros((2, 3))
        v = np.vstack(parts)
        return np.array([v.min(axis=0), v.max(axis=0)])

    def combined(self) -> trimesh.Trimesh:
        """Both meshes concatenated into one (for distances and simple exports)."""
        parts = [m for m in (self.branches, self.leaves) if len(m.faces)]
        if not parts:
            return trimesh.Trimesh(
                vertices=np.zeros((0, 3)), faces=np.zeros((0, 3), dtype=np.int64)
            )
        return trimesh.util.concatenate(parts)

    def export(self, path: str | os.PathLike[str]) -> Path:
        """Write GLB (``.glb``/``.gltf``) or OBJ (``.obj``), atomically; see ``weberpenn.export``."""
        from .export import export_mesh

        return export_mesh(self, path)
