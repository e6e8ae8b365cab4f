"""MeshLab's Metro filter (``pymeshlab``): the reference :mod:`eval.hausdorff` is
checked against (``tests/test_eval_hausdorff.py``, ``benchmarks/probes/hausdorff_check.py``).
Needs ``pymeshlab``, which the evaluation itself does not."""

from __future__ import annotations

from typing import Any

__all__ = ["metro"]


def metro(a: Any, b: Any, samples: int, faces: bool, reach: float) -> list[dict[str, Any]]:
    """Metro's results (``max``, ``mean``, ... in mesh units) from ``a``'s samples to
    ``b`` and from ``b``'s to ``a`` (meshes with ``vertices`` and ``faces``): vertices
    sampled, and faces with ``faces``, ``samples`` at most; samples farther than
    ``reach`` are dropped."""
    import pymeshlab

    ms = pymeshlab.MeshSet()
    for m in (a, b):
        ms.add_mesh(pymeshlab.Mesh(vertex_matrix=m.vertices, face_matrix=m.faces))
    return [
        ms.get_hausdorff_distance(
            sampledmesh=i,
            targetmesh=1 - i,
            samplevert=True,
            sampleedge=False,
            samplefauxedge=False,
            sampleface=faces,
            samplenum=samples,
            maxdist=pymeshlab.PureValue(reach),
        )
        for i in (0, 1)
    ]
