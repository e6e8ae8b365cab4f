"""tsn.encoding: round trip on the 15 published dictionaries, heads, decoding, normaliser."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from paths import GT_PARAM_FILES as REF_FILES
from tsn_helpers import sampled_matrices

from tsn import encoding
from weberpenn import ParamError, TreeParams, load_params, species
from weberpenn.params import HEAD_KEYS, HEADS, PREDICTED_KEYS, SPECS


@pytest.mark.parametrize("path", REF_FILES, ids=lambda p: p.stem)
def test_round_trip_reference(path: Path) -> None:
    p = load_params(path)
    mat = encoding.encode(p)
    assert mat.shape == (4, 62)
    q = encoding.decode(mat)
    for k in PREDICTED_KEYS:
        spec = SPECS[k]
        if spec.discrete:
            assert q[k] == p[k], k
        else:
            np.testing.assert_allclose(np.asarray(q[k], float), np.asarray(p[k], float), atol=1e-9)
    for k, v in encoding.NON_PREDICTED_DEFAULTS.items():
        assert q[k] == v
    # through the normaliser too (float32-ish rounding only)
    norm = encoding.Normaliser.fit(mat[None])
    back = norm.denormalise(norm.normalise(mat).astype(np.float32))
    q2 = encoding.decode(back)
    for k in PREDICTED_KEYS:
        if SPECS[k].discrete:
            assert q2[k] == p[k], k


def test_layout_matches_table() -> None:
    p = species.sample("cherry", 3)
    mat = encoding.encode(p)
    heads = encoding.split_heads(mat)
    assert list(heads) == list(HEADS)
    assert [h.shape for h in heads.values()] == [(4, len(HEAD_KEYS[h])) for h in HEADS]
    np.testing.assert_array_equal(encoding.join_heads(heads), mat)
    j = PREDICTED_KEYS.index("levels")
    assert (mat[:, j] == p["levels"]).all()  # scalars repeated over the four rows
    j = PREDICTED_KEYS.index("branches")
    assert list(mat[:, j]) == list(p["branches"])
    # signs, booleans and enums
    q = p.replace(choiceNegPos1=-1, horzLeaves=False, leafShape="rect", shape="10")
    m = encoding.encode(q)
    assert m[0, PREDICTED_KEYS.index("choiceNegPos1")] == 0.0
    assert m[0, PREDICTED_KEYS.index("horzLeaves")] == 0.0
    assert m[0, PREDICTED_KEYS.index("leafShape")] == 1.0
    assert m[0, PREDICTED_KEYS.index("shape")] == 10.0


def test_decode_rounds_thresholds_snaps_clamps() -> None:
    mat = encoding.encode(species.sample("maple", 0))
    col = {k: PREDICTED_KEYS.index(k) for k in PREDICTED_KEYS}
    m = mat.copy()
    m[:, col["levels"]] = 2.6
    m[:, col["choiceNegPos1"]] = 0.3
    m[:, col["useParentAngle"]] = 0.7
    m[:, col["shape"]] = 8.9  # between 8 and 10: nearest allowed is 8
    m[:, col["leafShape"]] = 0.8
    m[:, col["taper"]] = [1.5, -0.2, 0.5, 0.5]
    m[:, col["downAngle"]] = [900.0, 10.0, 10.0, 10.0]
    q = encoding.decode(m)
    assert q["levels"] == 3 and q["choiceNegPos1"] == -1 and q["useParentAngle"] is True
    assert q["shape"] == "8" and q["leafShape"] == "rect"
    assert q["taper"][:2] == (1.0, 0.0) and q["downAngle"][0] == 360.0


def test_decode_keeps_trees_within_limits() -> None:
    mat = encoding.encode(species.sample("cherry", 0))
    m = mat.copy()
    m[:, PREDICTED_KEYS.index("levels")] = 4
    m[:, PREDICTED_KEYS.index("branches")] = 400
    m[:, PREDICTED_KEYS.index("scaleV")] = -500
    q = encoding.decode(m)  # shrunk until valid, trunk kept positive
    assert isinstance(q, TreeParams) and q.scale + q.scaleV > 0


def test_normaliser_fit_save_load() -> None:
    mats = np.concatenate(list(sampled_matrices(6).values()))
    n = encoding.Normaliser.fit(mats)
    cols = encoding.HEAD_COLUMNS
    assert (n.scale[cols["angle"]] == 360.0).all()
    assert (n.scale[cols["0_1"]] == 1.0).all() and (n.scale[cols["-1_1"]] == 1.0).all()
    mx = np.abs(mats[:, :, cols["0_inf"]]).max(axis=(0, 1))
    np.testing.assert_allclose(n.scale[cols["0_inf"]], np.where(mx > 0, mx, 1.0))
    normed = n.normalise(mats)
    assert np.abs(normed[..., cols["0_inf"]]).max() <= 1.0 + 1e-12
    d = json.loads(json.dumps(n.to_dict()))  # plain data
    m = encoding.Normaliser.from_dict(d)
    np.testing.assert_array_equal(m.scale, n.scale)
    np.testing.assert_array_equal(m.lo, n.lo)
    np.testing.assert_allclose(encoding.normalise(mats[0], d), normed[0])
    np.testing.assert_allclose(m.denormalise(normed), mats)


def test_bad_inputs() -> None:
    with pytest.raises(encoding.EncodingError, match="shape"):
        encoding.decode(np.zeros((4, 61)))
    with pytest.raises(encoding.EncodingError, match="NaN"):
        encoding.decode(np.full((4, 62), np.nan))
    with pytest.raises(encoding.EncodingError, match="missing head"):
        encoding.join_heads({"0_1": np.zeros((4, 17))})
    with pytest.raises(encoding.EncodingError, match="head"):
        encoding.join_heads({h: np.zeros((4, 3)) for h in HEADS})
    with pytest.raises(encoding.EncodingError, match="no training"):
        encoding.Normaliser.fit(np.zeros((0, 4, 62)))
    with pytest.raises(encoding.EncodingError, match="normaliser"):
        encoding.Normaliser.from_dict({"scale": [1.0]})
    with pytest.raises(ParamError):
        encoding.encode({"levels": 3})
