"""tsn.species_id (Algorithm 1): 15/15 on the published dictionaries, plain-data save/load."""

from __future__ import annotations

import json

import numpy as np
import pytest
from paths import GT_PARAM_FILES as REF_FILES
from tsn_helpers import sampled_matrices

from tsn import encoding
from tsn.species_id import SpeciesClassifier, SpeciesIdentifier, SpeciesIdError
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


def test_classifier_is_accurate_calibrated_and_plain_data(identifier: SpeciesIdentifier) -> None:
    from tsn.species_id import SpeciesClassifier

    rng = np.random.default_rng(0)
    mats = sampled_matrices(12)
    names = list(mats)
    x = np.concatenate([mats[s] for s in names])
    y = [s for s in names for _ in range(len(mats[s]))]
    # a network's outputs are the truth plus noise: fit on noisy copies, calibrate on others
    scale = identifier.scale

    def noisy(a: np.ndarray, k: float) -> np.ndarray:
        return a + rng.normal(0, k, a.shape) * scale[None, None, :]

    clf = SpeciesClassifier.fit(noisy(x, 0.05), y, scale, held_out=(noisy(x, 0.3), y))
    assert clf.temperature > 0
    p = clf.probabilities_many(noisy(x, 0.05))
    assert p.shape == (len(y), len(names)) and np.allclose(p.sum(axis=1), 1.0)
    assert np.mean([clf.species[i] == s for i, s in zip(p.argmax(1), y, strict=True)]) > 0.9
    # calibrated on outputs as noisy as these: its confidence matches its accuracy
    fresh = clf.probabilities_many(noisy(x, 0.3))
    conf = fresh.max(axis=1)
    right = np.array([clf.species[i] == s for i, s in zip(fresh.argmax(1), y, strict=True)])
    assert abs(conf.mean() - right.mean()) < 0.1
    with_clf = identifier.with_classifier(clf)
    back = SpeciesIdentifier.from_dict(json.loads(json.dumps(with_clf.to_dict())))
    assert back.classifier is not None and back.classifier.species == clf.species
    m = x[0]
    assert back.identify(m) == with_clf.identify(m) == y[0]
    assert back.scores(m) == pytest.approx(clf.probabilities(m))
    assert identifier.scores(m) == identifier.shares(m)  # no classifier: Algorithm 1's shares


def test_a_classifier_that_reads_the_network_features(identifier: SpeciesIdentifier) -> None:
    """reads="features": fitted on (N, m) pooled features; the identifier asks for them,
    reads a dictionary (which has none) by Algorithm 1, and saves what it reads."""
    from tsn.species_id import SpeciesClassifier

    rng = np.random.default_rng(1)
    names = list(identifier.species)
    centres = rng.normal(0, 1, (len(names), 16))  # each species' features, and noise
    y = [s for s in names for _ in range(30)]
    feats = np.concatenate([centres[i] + rng.normal(0, 0.3, (30, 16)) for i in range(len(names))])
    held = np.concatenate([centres[i] + rng.normal(0, 0.6, (30, 16)) for i in range(len(names))])
    clf = SpeciesClassifier.fit(feats, y, identifier.scale, held_out=(held, y), reads="features")
    assert clf.reads == "features" and clf.weight.shape == (len(names), 16)
    with_clf = identifier.with_classifier(clf)
    back = SpeciesIdentifier.from_dict(json.loads(json.dumps(with_clf.to_dict())))
    assert back.classifier is not None and back.classifier.reads == "features"
    mats = sampled_matrices(2)
    m = mats[names[0]][0]
    # the features decide, whatever the output says
    for i, s in enumerate(names):
        assert back.identify(m, centres[i]) == s
        assert max(back.scores(m, centres[i]).items(), key=lambda kv: kv[1])[0] == s
    # no features at hand (a dictionary): Algorithm 1, the paper's way
    p = species.sample(names[1], 3)
    assert back.identify(p) == identifier.identify(p)
    assert back.scores(m) == identifier.shares(m)
    with pytest.raises(SpeciesIdError, match="pooled features"):
        clf.of(m, None)
    with pytest.raises(SpeciesIdError, match="reads one of"):
        SpeciesClassifier.from_dict({**clf.to_dict(), "reads": "pixels"})
    with pytest.raises(SpeciesIdError, match=r"\(N, m\)"):
        clf.probabilities_many(np.zeros((2, 4, 62)))


def test_refit_learns_drawings_known_only_as_a_set_of_species() -> None:
    # three species; a new kind of drawing (shifted on feature 2) that the old classifier
    # reads as "c", and that is known only to be "a" or "b"
    rng = np.random.default_rng(0)
    centres = {"a": [2.0, 0.0, 0.0], "b": [0.0, 2.0, 0.0], "c": [0.0, 0.0, 2.0]}
    x = np.concatenate([rng.normal(centres[s], 0.5, (60, 3)) for s in centres])
    labels = [s for s in centres for _ in range(60)]
    clf = SpeciesClassifier.fit(x, labels, np.ones(62), reads="features")
    new = rng.normal([1.5, 0.3, 2.5], 0.4, (80, 3))
    before = clf.probabilities_many(new)[:, clf.species.index("c")].mean()
    allowed = labels + [frozenset({"a", "b"})] * 80
    again = clf.refit(np.concatenate([x, new]), allowed, pull=1e-3)
    p = again.probabilities_many(new)
    assert before > 0.5 and p[:, again.species.index("c")].mean() < 0.2
    # the old drawings keep their species
    old = again.probabilities_many(x).argmax(axis=1)
    assert np.mean(np.array(again.species)[old] == np.array(labels)) > 0.95
    assert again.temperature == clf.temperature and again.species == clf.species
    with pytest.raises(SpeciesIdError, match="no known species"):
        clf.refit(x[:1], [frozenset({"zebra"})])
    with pytest.raises(SpeciesIdError, match="weights"):
        clf.refit(x[:2], ["a", "b"], weights=[1.0])
