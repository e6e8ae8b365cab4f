"""tsn.species_id (Algorithm 1): 15/15 on the published dictionaries, plain-data save/load."""

from __future__ import annotations

import json

import numpy as np
import pytest
from paths import GT_PARAM_FILES as REF_FILES
from tsn_helpers import sampled_matrices

from tsn import encoding
from tsn.species_id import SpeciesIdentifier, SpeciesIdError
from weberpenn import load_params, species


@pytest.fixture(scope="module")
def identifier() -> SpeciesIdentifier:
    mats = sampled_matrices(20)
    norm = encoding.Normaliser.fit(np.concatenate(list(mats.values())))
    return SpeciesIdentifier.fit(mats, norm.scale)


def test_reference_files_15_of_15(identifier: SpeciesIdentifier) -> None:
    right = 0
    for path in REF_FILES:
        truth = species.canonical(path.stem.split("_", 1)[1])
        got = identifier.identify(load_params(path))
        right += got == truth
        shares = identifier.shares(encoding.encode(load_params(path)))
        assert shares[truth] == max(shares.values())
    assert right == 15


def test_held_out_samples_and_matrices(identifier: SpeciesIdentifier) -> None:
    for s in species.SPECIES:
        for seed in range(500, 505):
            p = species.sample(s, seed)
            assert identifier.identify(p) == s
            assert identifier.identify(encoding.encode(p)) == s


def test_characteristic_params_include_fixed_keys(identifier: SpeciesIdentifier) -> None:
    d = identifier.to_dict()
    for s in species.SPECIES:
        keys = set(d["cps"][s]["keys"])
        assert {"levels", "shape"} <= keys  # fixed in every species


def test_save_load_plain_data(identifier: SpeciesIdentifier) -> None:
    d = json.loads(json.dumps(identifier.to_dict()))
    other = SpeciesIdentifier.from_dict(d)
    p = species.sample("bonsai", 77)
    assert other.identify(p) == identifier.identify(p) == "bonsai"
    with pytest.raises(SpeciesIdError):
        SpeciesIdentifier.from_dict({"species": ["maple"]})
    with pytest.raises(SpeciesIdError, match=r"\(4, 62\)"):
        identifier.shares(np.zeros((4, 10)))
    with pytest.raises(SpeciesIdError, match="maple"):
        SpeciesIdentifier.fit({"maple": np.zeros((0, 4, 62))}, np.ones(62))
