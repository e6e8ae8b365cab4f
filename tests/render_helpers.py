"""Small hand-made trees for the render tests (no dependency on weberpenn.mesh)."""

from __future__ import annotations

import numpy as np
import trimesh

from weberpenn.treemesh import TreeMesh


def empty_mesh() -> trimesh.Trimesh:
    return trimesh.Trimesh(vertices=np.zeros((0, 3)), faces=np.zeros((0, 3), dtype=np.int64))


def simple_tree(
    height: float = 10.0,
    trunk_radius: float = 0.3,
    crown_radius: float = 2.0,
    side_branch: bool = True,
    species: str | None = "maple",
) -> TreeMesh:
    """A cylinder trunk with its base at the origin, an icosphere crown near the top and
    (optionally) one side branch pointing 30 degrees from +X towards +Y with a small leaf ball, so views differ."""
    trunk_h = height - crown_radius
    trunk = trimesh.creation.cylinder(radius=trunk_radius, height=trunk_h, sections=16)
    trunk.apply_translation([0, 0, trunk_h / 2])
    parts = [trunk]
    leaves = [trimesh.creation.icosphere(2, radius=crown_radius).apply_translation([0, 0, trunk_h])]
    if side_branch:
        length = 1.6 * crown_radius
        br = trimesh.creation.cylinder(radius=trunk_radius * 0.4, height=length, sections=8)
        br.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, [0, 1, 0]))
        br.apply_translation([length / 2, 0, 0.45 * trunk_h])
        ball = trimesh.creation.icosphere(1, radius=0.35 * crown_radius).apply_translation(
            [length, 0, 0.45 * trunk_h]
        )
        turn = trimesh.transformations.rotation_matrix(np.radians(30), [0, 0, 1])
        parts.append(br.apply_transform(turn))
        leaves.append(ball.apply_transform(turn))
    return TreeMesh(trimesh.util.concatenate(parts), trimesh.util.concatenate(leaves), species)
