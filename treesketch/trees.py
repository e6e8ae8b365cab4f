"""A tree to look at now: parameters (+ a person's controls) -> a light GLB or a sketch.

What the page's live preview, ``POST /trees``, ``treesketch grow --set`` and a running
job's current best tree share: :func:`edit_tree` (a :class:`TreeRequest` checked, the
controls applied, the tree grown) and :func:`light_glb` (the viewer's GLB, at most
:data:`VIEW_FACES` triangles; full detail is the download's).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from weberpenn import TreeMesh, TreeParams
from weberpenn import species as species_table

__all__ = [
    "REPLY_FACES",
    "VIEW_FACES",
    "EditedTree",
    "TreeRequest",
    "TreeTooBig",
    "edit_tree",
    "estimated_faces",
    "light_glb",
    "reply_glb",
    "tree_sketch",
]

# the viewer's default triangle budget (and the live preview's): the heaviest species
# stays under 5 MB of GLB with its textures (docs/history/results-2026-12-05.md, "The interactive loop")
VIEW_FACES = 80_000
# the most triangles one reply's GLB holds (26-31 bytes each: at most 47 MB): every
# species' tree at full detail fits (the largest, willow, about 0.85 M); a bigger export
# is `treesketch grow`'s (issue 49: a 4.3 M-triangle reply was 110 MB, held per client)
REPLY_FACES = 1_500_000


class TreeTooBig(ValueError):
    """The tree has more triangles than one reply holds (:data:`REPLY_FACES`)."""


@dataclass(frozen=True)
class TreeRequest:
    """A tree to grow: ``params`` (a Sapling dictionary), ``controls`` (name: value, see
    ``weberpenn.controls``), ``seed`` (the variant; same as ``controls["seed"]``),
    ``species`` (its textures and leaf shape; None: the nearest species to ``params``),
    ``max_faces`` (None: full detail), ``yaw`` (degrees: the GLB is turned to face the
    camera that sees the tree from there, as a job's files face their drawing, so an edit
    of a job's tree keeps the side it was drawn from)."""

    params: TreeParams
    controls: Mapping[str, Any] = field(default_factory=dict)
    seed: int | None = None
    species: str | None = None
    max_faces: int | None = VIEW_FACES
    yaw: float = 0.0
    # bring controls past the generator's limits back within them: all (True) or these
    fit: bool | tuple[str, ...] = False

    @classmethod
    def from_json(cls, body: Any) -> TreeRequest:
        """From a JSON object (``POST /trees``); ValueError naming the bad field."""
        from weberpenn.controls import CONTROLS, check_controls
        from weberpenn.lod import check_budget

        if not isinstance(body, Mapping):
            raise ValueError("the body must be a JSON object with 'params'")
        unknown = sorted(
            set(body) - {"params", "controls", "seed", "species", "max_faces", "yaw", "fit"}
        )
        if unknown:
            raise ValueError(
                f"unknown field(s) {', '.join(unknown)}; "
                "send params, controls, seed, species, max_faces, yaw, fit"
            )
        if "params" not in body or not isinstance(body["params"], Mapping):
            raise ValueError("'params' must be a parameter dictionary (a JSON object)")
        params = TreeParams(body["params"])  # ParamError names the key
        controls = check_controls(body.get("controls") or {})
        seed = body.get("seed")
        if seed is not None:
            controls = {**controls, **check_controls({"seed": seed})}
        name = body.get("species")
        if name is not None:
            name = species_table.canonical(name)
        max_faces = body.get("max_faces", VIEW_FACES)
        if max_faces is not None:
            check_budget(max_faces)
        yaw = _degrees(body.get("yaw", 0.0))
        fit = body.get("fit", False)
        if isinstance(fit, list) and all(isinstance(k, str) for k in fit):
            unknown = sorted(set(fit) - {c.name for c in CONTROLS})
            if unknown:
                raise ValueError(f"'fit' names unknown control(s) {', '.join(unknown)}")
            fit = tuple(fit)
        elif not isinstance(fit, bool):
            raise ValueError(
                f"'fit' must be true, false or a list of control names, got {fit!r:.40}"
            )
        return cls(params, controls, controls.get("seed"), name, max_faces, yaw % 360.0, fit)


def _degrees(yaw: Any) -> float:
    """``yaw`` as finite float degrees; ValueError otherwise (an int of 309 digits or more
    overflows a float: that is a bad value too, not an OverflowError)."""
    if isinstance(yaw, int) and not isinstance(yaw, bool) and yaw.bit_length() > 100:
        shown = f"a number of about {int(yaw.bit_length() * 0.30103) + 1} digits"
    else:
        shown = f"{yaw!r:.40}"
    bad = ValueError(f"'yaw' must be a finite number of degrees, got {shown}")
    if isinstance(yaw, bool) or not isinstance(yaw, int | float):
        raise bad
    try:
        degrees = float(yaw)
    except OverflowError:
        raise bad from None
    if not math.isfinite(degrees):
        raise bad
    return degrees


@dataclass(frozen=True)
class EditedTree:
    params: TreeParams
    species: str
    mesh: TreeMesh
    height: float
    controls: dict[str, Any]  # the values that leave ``params`` as it is (see ``current``)
    adjusted: dict[str, Any] = field(default_factory=dict)  # controls ``fit`` brought back


def edit_tree(request: TreeRequest) -> EditedTree:
    """Apply the request's controls and grow the tree (``weberpenn.controls``); with
    ``request.fit``, controls that make a tree past the generator's limits are brought
    back within them (``weberpenn.controls.fit_controls``) instead of refused."""
    from refine.search import guess_species
    from weberpenn.controls import current, fit_controls, grow_with_controls
    from weberpenn.params import ParamError

    name = request.species or guess_species(request.params)
    controls = dict(request.controls)
    if request.seed is not None:
        controls["seed"] = request.seed
    adjusted: dict[str, Any] = {}
    try:
        params, mesh = grow_with_controls(request.params, controls, name)
    except ParamError:
        if not request.fit:
            raise
        # only a tree past the limits pays for the search of the nearest one that grows
        only = None if request.fit is True else request.fit
        controls, adjusted = fit_controls(request.params, controls, name, only)
        params, mesh = grow_with_controls(request.params, controls, name)
    lo, hi = mesh.bounds()
    height = float(np.asarray(hi)[2] - np.asarray(lo)[2])
    return EditedTree(params, name, mesh, height, current(params, height), adjusted)


def estimated_faces(request: TreeRequest) -> float:
    """About how many triangles growing ``request`` builds, from its dictionary alone
    (``weberpenn.params.estimate_load``, an upper-bound-ish count, 2 to 10 times the
    real one; no growing): what tells a cheap edit from an expensive tree before paying
    for it.  A ``height`` control regrows the tree (half as much again); controls past
    the generator's limits count as the tree at their neutral values grown three times
    (``fit`` searches, growing up to nine trees, most of them smaller), ``inf`` when even
    that is past the limits."""
    from weberpenn.controls import CONTROLS, apply_controls
    from weberpenn.params import ParamError, estimate_load

    controls = {k: v for k, v in request.controls.items() if k != "height"}
    factor = 1.5 if "height" in request.controls else 1.0
    try:
        params = apply_controls(request.params, controls)
    except ParamError:
        movable = {c.name for c in CONTROLS if c.relative and c.kind == "number"}
        try:
            params = apply_controls(
                request.params, {k: v for k, v in controls.items() if k not in movable}
            )
        except ParamError:
            return math.inf
        factor *= 3.0
    _, leaves, tube_vertices = estimate_load(params)
    return factor * (2.0 * tube_vertices + 4.0 * leaves)  # a tube's quad per vertex; a leaf's 2-4


def reply_glb(mesh: TreeMesh, yaw: float = 0.0, max_faces: int | None = VIEW_FACES) -> bytes:
    """:func:`light_glb` for one reply: :class:`TreeTooBig` (before exporting) when it
    would hold more than :data:`REPLY_FACES` triangles."""
    budget = REPLY_FACES if max_faces is None else min(max_faces, REPLY_FACES)
    asked = max_faces is None or max_faces > REPLY_FACES
    if asked and mesh.n_faces > budget:
        raise TreeTooBig(
            f"the tree has {mesh.n_faces:,} triangles; a reply holds at most "
            f"{REPLY_FACES:,}: ask for max_faces <= {REPLY_FACES} (the same tree, lighter), "
            "or export it full size with `treesketch grow --params tree.json --out tree.glb`"
        )
    return light_glb(mesh, yaw=yaw, max_faces=max_faces)


def light_glb(mesh: TreeMesh, yaw: float = 0.0, max_faces: int | None = VIEW_FACES) -> bytes:
    """The tree as a binary glTF of at most ``max_faces`` triangles (None: all)."""
    from weberpenn.export import glb_bytes

    return glb_bytes(mesh, yaw=yaw, max_faces=max_faces)


def sketch_renderer(params: TreeParams, species: str, size: int = 256) -> Any:
    """A renderer of the tree's sketches the cheap way, for any view at up to ``size``
    pixels (thin stems left out, numpy rasteriser: the same sketch as mitsuba's up to a
    few pixels, as the refinement draws its candidates)."""
    from render.sketch import SketchRenderer, sketch_mesh
    from weberpenn import grow

    return SketchRenderer(sketch_mesh(grow(params), size, species), engine="raster")


def tree_sketch(params: TreeParams, species: str, yaw: float = 0.0, size: int = 256) -> np.ndarray:
    """The tree's sketch the cheap way (:func:`sketch_renderer`): what a running job shows
    of its current best tree, and a candidate's thumbnail."""
    return sketch_renderer(params, species, size).sketch(yaw, size)
