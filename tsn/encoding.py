"""Parameter dictionary <-> TSN target matrices, and the max-abs normaliser.

Everything is derived from the one parameter table (``weberpenn.params``):

* :func:`encode` turns a dictionary into the paper's ``(4, 62)`` target matrix, columns in
  ``PREDICTED_KEYS`` order (the layout ``eval.metrics`` scores): per-level keys fill the
  four rows, scalars are repeated in all four rows, booleans and ``-1/+1`` signs become
  ``0/1``, enums their number (``leafShape``: hex=0, rect=1; shape enums their digit).
* :func:`split_heads` / :func:`join_heads` convert between the combined matrix and the six
  head sub-matrices ``(4, n)`` (``HEADS`` order: 17, 4, 12, 12, 16, 1 columns).
* :func:`decode` goes back: per-level keys read their four rows, scalars the mean of the
  four rows; integers are rounded, booleans and signs thresholded at 0.5, enums snapped to
  the nearest allowed value, everything clamped to the table's range (and to the range seen
  in training when a :class:`Normaliser` is given).  The non-predicted keys take
  :data:`NON_PREDICTED_DEFAULTS` (no pruning, the table's pruning defaults, seed 0).
* :class:`Normaliser`: per-column divisors, as TreeSketchNet's code: the ``[0,1]`` and
  ``[-1,1]`` heads unscaled, angles divided by 360, every other column by its max-abs
  value over the training split.  ``to_dict``/``from_dict`` give plain data for the
  checkpoint.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from weberpenn.params import (
    HEAD_KEYS,
    HEADS,
    PARAMS,
    PREDICTED_KEYS,
    SPECS,
    ParamError,
    TreeParams,
)

N_ROWS = 4
N_COLS = len(PREDICTED_KEYS)  # 62
COLUMN: dict[str, int] = {k: i for i, k in enumerate(PREDICTED_KEYS)}
#: Column indices of each head inside the combined matrix.
HEAD_COLUMNS: dict[str, np.ndarray] = {
    h: np.array([COLUMN[k] for k in HEAD_KEYS[h]], dtype=np.int64) for h in HEADS
}
HEAD_SIZES: dict[str, int] = {h: len(HEAD_KEYS[h]) for h in HEADS}

#: Values of the keys TSN does not predict (pruning off, the table's defaults, seed 0).
NON_PREDICTED_DEFAULTS: dict[str, Any] = {p.name: p.default for p in PARAMS if not p.predicted}

#: Heads that TreeSketchNet leaves unscaled, and the fixed divisor of the angle head.
UNSCALED_HEADS = ("0_1", "-1_1")
ANGLE_SCALE = 360.0


class EncodingError(ValueError):
    """A matrix or normaliser of the wrong shape or content."""


def _enum_number(spec, value: Any) -> float:
    s = str(value)
    if spec.name == "leafShape" or not s.lstrip("-").isdigit():
        return float(spec.choices.index(s))
    return float(s)


def _enum_values(spec) -> np.ndarray:
    return np.array([_enum_number(spec, c) for c in spec.choices], dtype=np.float64)


def encode(params: Mapping[str, Any]) -> np.ndarray:
    """``(4, 62)`` un-normalised target matrix (float64) of a parameter dictionary."""
    if not isinstance(params, TreeParams):
        params = TreeParams(params)
    out = np.empty((N_ROWS, N_COLS), dtype=np.float64)
    for j, key in enumerate(PREDICTED_KEYS):
        spec, v = SPECS[key], params[key]
        vals = list(v) if spec.is_vector else [v] * N_ROWS
        if spec.kind == "bool":
            row = [float(bool(x)) for x in vals]
        elif spec.kind == "sign":
            row = [1.0 if float(x) > 0 else 0.0 for x in vals]
        elif spec.kind == "enum":
            row = [_enum_number(spec, x) for x in vals]
        else:
            row = [float(x) for x in vals]
        out[:, j] = row
    return out


def encode_many(params: Iterable[Mapping[str, Any]]) -> np.ndarray:
    """``(N, 4, 62)`` matrices of several dictionaries."""
    mats = [encode(p) for p in params]
    if not mats:
        return np.zeros((0, N_ROWS, N_COLS))
    return np.stack(mats)


def _check_matrix(mat: np.ndarray, what: str = "matrix") -> np.ndarray:
    a = np.asarray(mat, dtype=np.float64)
    if a.shape[-2:] != (N_ROWS, N_COLS):
        raise EncodingError(f"{what}: expected shape (..., {N_ROWS}, {N_COLS}), got {a.shape}")
    if not np.isfinite(a).all():
        raise EncodingError(f"{what}: contains NaN or infinity")
    return a


def split_heads(mat: np.ndarray) -> dict[str, np.ndarray]:
    """Combined ``(..., 4, 62)`` -> ``{head: (..., 4, n_head)}`` in ``HEADS`` order."""
    a = np.asarray(mat)
    if a.shape[-2:] != (N_ROWS, N_COLS):
        raise EncodingError(f"expected shape (..., {N_ROWS}, {N_COLS}), got {a.shape}")
    return {h: a[..., HEAD_COLUMNS[h]] for h in HEADS}


def join_heads(heads: Mapping[str, np.ndarray]) -> np.ndarray:
    """``{head: (..., 4, n_head)}`` -> combined ``(..., 4, 62)``."""
    missing = [h for h in HEADS if h not in heads]
    if missing:
        raise EncodingError(f"missing head(s): {', '.join(missing)}")
    first = np.asarray(heads[HEADS[0]])
    out = np.zeros((*first.shape[:-1], N_COLS), dtype=np.float64)
    for h in HEADS:
        a = np.asarray(heads[h], dtype=np.float64)
        if a.shape[-1] != HEAD_SIZES[h] or a.shape[:-1] != first.shape[:-1]:
            raise EncodingError(
                f"head {h!r}: expected shape (..., {N_ROWS}, {HEAD_SIZES[h]}), got {a.shape}"
            )
        out[..., HEAD_COLUMNS[h]] = a
    return out


@dataclass(frozen=True)
class Normaliser:
    """Per-column divisors (``scale``) plus the per-cell range seen in training."""

    scale: np.ndarray  # (62,)
    lo: np.ndarray  # (4, 62) un-normalised minimum over the training split
    hi: np.ndarray  # (4, 62) maximum

    @classmethod
    def fit(cls, mats: np.ndarray) -> Normaliser:
        """Fit on the training split's ``(N, 4, 62)`` un-normalised matrices."""
        a = _check_matrix(mats, "training matrices")
        if a.ndim != 3 or not len(a):
            raise EncodingError("cannot fit a normaliser on no training samples")
        scale = np.abs(a).max(axis=(0, 1))
        scale = np.where(scale > 0, scale, 1.0)
        for h in UNSCALED_HEADS:
            scale[HEAD_COLUMNS[h]] = 1.0
        scale[HEAD_COLUMNS["angle"]] = ANGLE_SCALE
        return cls(scale, a.min(axis=0), a.max(axis=0))

    def normalise(self, mat: np.ndarray) -> np.ndarray:
        return _check_matrix(mat) / self.scale

    def denormalise(self, mat: np.ndarray) -> np.ndarray:
        return np.asarray(mat, dtype=np.float64) * self.scale

    def to_dict(self) -> dict[str, Any]:
        """Plain data (lists of floats) for the checkpoint."""
        return {
            "columns": list(PREDICTED_KEYS),
            "scale": self.scale.tolist(),
            "lo": self.lo.tolist(),
            "hi": self.hi.tolist(),
        }

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> Normaliser:
        try:
            cols = list(d["columns"])
            scale = np.asarray(d["scale"], dtype=np.float64)
            lo = np.asarray(d["lo"], dtype=np.float64)
            hi = np.asarray(d["hi"], dtype=np.float64)
        except (KeyError, TypeError, ValueError) as e:
            raise EncodingError(f"not a saved normaliser: {e}") from None
        if cols != list(PREDICTED_KEYS):
            raise EncodingError("saved normaliser has different columns than the parameter table")
        if scale.shape != (N_COLS,) or lo.shape != hi.shape != (N_ROWS, N_COLS):
            raise EncodingError(f"saved normaliser has bad shapes {scale.shape}, {lo.shape}")
        if not (np.isfinite(scale).all() and (scale > 0).all()):
            raise EncodingError("saved normaliser has non-positive or non-finite scales")
        return cls(scale, lo, hi)


def normalise(mat: np.ndarray, normaliser: Normaliser | Mapping[str, Any]) -> np.ndarray:
    """Divide by the normaliser's scales (accepts a ``Normaliser`` or its ``to_dict``)."""
    if not isinstance(normaliser, Normaliser):
        normaliser = Normaliser.from_dict(normaliser)
    return normaliser.normalise(mat)


def denormalise(mat: np.ndarray, normaliser: Normaliser | Mapping[str, Any]) -> np.ndarray:
    if not isinstance(normaliser, Normaliser):
        normaliser = Normaliser.from_dict(normaliser)
    return normaliser.denormalise(mat)


def _decode_values(spec, x: np.ndarray) -> list[Any]:
    if spec.kind == "bool":
        return [bool(v >= 0.5) for v in x]
    if spec.kind == "sign":
        return [1 if v >= 0.5 else -1 for v in x]
    if spec.kind == "enum":
        allowed = _enum_values(spec)
        return [spec.choices[int(np.argmin(np.abs(allowed - v)))] for v in x]
    x = np.clip(x, spec.lo, spec.hi)
    if spec.kind == "int":
        return [int(np.clip(round(float(v)), spec.lo, spec.hi)) for v in x]
    return [float(v) for v in x]


def decode_dict(mat: np.ndarray, normaliser: Normaliser | None = None) -> dict[str, Any]:
    """Un-normalised ``(4, 62)`` matrix -> plain 70-key dictionary (not yet validated).

    With a ``normaliser`` values are first clamped to the range seen in training.
    """
    a = _check_matrix(mat)
    if a.shape != (N_ROWS, N_COLS):
        raise EncodingError(f"expected one ({N_ROWS}, {N_COLS}) matrix, got {a.shape}")
    if normaliser is not None:
        a = np.clip(a, normaliser.lo, normaliser.hi)
    out: dict[str, Any] = {}
    for j, key in enumerate(PREDICTED_KEYS):
        spec = SPECS[key]
        col = a[:, j]
        if spec.is_vector:
            out[key] = tuple(_decode_values(spec, col))
        else:
            out[key] = _decode_values(spec, np.array([col.mean()]))[0]
    out.update(NON_PREDICTED_DEFAULTS)
    return {k: out[k] for k in (p.name for p in PARAMS)}


def _shrink(d: dict[str, Any], key: str | None) -> bool:
    """Make an over-large decoded tree smaller (``key``: the one the error blames); False =
    stuck."""
    if key == "branches":
        b = list(d["branches"])
        if max(b[1:]) <= 1 and d["baseSplits"] == 0:
            return False
        d["branches"] = (b[0], *(max(int(v * 0.8), 1) if v > 1 else v for v in b[1:]))
        d["baseSplits"] = int(d["baseSplits"] * 0.8)
        return True
    if key == "leaves":
        if abs(d["leaves"]) <= 1:
            return False
        d["leaves"] = int(d["leaves"] * 0.8)
        return True
    if key == "curveRes":
        if d["resU"] > 1:
            d["resU"] -= 1
            return True
        if d["bevelRes"] > 0:
            d["bevelRes"] -= 1
            return True
        c = list(d["curveRes"])
        if max(c) <= 1:
            return False
        d["curveRes"] = tuple(max(v - 1, 1) for v in c)
        return True
    return False


def decode(mat: np.ndarray, normaliser: Normaliser | None = None) -> TreeParams:
    """Un-normalised ``(4, 62)`` matrix -> validated :class:`TreeParams`.

    The trunk length must stay positive (``scale + scaleV > 0``); when the prediction
    breaks it, ``scaleV`` is raised to keep a tenth of ``scale``.  A prediction whose tree
    would exceed the table's size limits (stems, leaves, mesh vertices) is shrunk step by
    step (branch counts, leaves, resolutions times 0.8 or minus one) until it fits.
    """
    d = decode_dict(mat, normaliser)
    if d["scale"] + d["scaleV"] <= 0:
        d["scaleV"] = -0.9 * d["scale"]
    for _ in range(200):
        try:
            return TreeParams(d)
        except ParamError as e:
            if not _shrink(d, e.key):
                raise ParamError(f"decoded prediction is not a valid tree: {e}") from None
    raise ParamError("decoded prediction is not a valid tree: could not shrink it to the limits")
