"""tsn.predict: a checkpoint predicts a valid TreeParams from a rendered sketch; bad input."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from tsn_helpers import make_checkpoint

from render.reader import SketchError, normalise_drawing
from tsn import predict as tp
from tsn.checkpoint import CheckpointError
from tsn.data import augment, preprocess
from weberpenn import TreeParams, build_mesh, grow, species


@pytest.fixture(scope="module")
def model(tmp_path_factory: pytest.TempPathFactory) -> tp.TSNModel:
    path = make_checkpoint(tmp_path_factory.mktemp("ck") / "tiny.pt", size=64)
    return tp.load_model(path, device="cpu")


@pytest.fixture(scope="module")
def sketch() -> np.ndarray:
    from render.sketch import SketchRenderer

    mesh = build_mesh(grow(species.sample("palm", 4)), species="palm")
    return SketchRenderer(mesh).sketch(0.0, 128)


def test_predict_rendered_sketch(model: tp.TSNModel, sketch: np.ndarray) -> None:
    pred = tp.predict(model, sketch)
    assert isinstance(pred.params, TreeParams) and isinstance(pred.decoded, TreeParams)
    assert pred.species in species.SPECIES
    assert {h: v.shape for h, v in pred.raw.items()}["angle"] == (4, 16)
    assert pred.matrix.shape == (4, 62)
    # projected onto the species: its fixed values
    assert pred.params["levels"] == species.base(pred.species)["levels"]
    # same answer for the same drawing given as RGB, RGBA (on white), PIL, path, bytes
    rgba = np.zeros((*sketch.shape, 4), np.uint8)
    rgba[..., 3] = 255 - sketch  # ink opaque, page transparent
    im = Image.fromarray(sketch)
    buf = io.BytesIO()
    im.save(buf, format="PNG")
    for other in (np.stack([sketch] * 3, -1), rgba, im, buf.getvalue()):
        np.testing.assert_allclose(model.predict(other).matrix, pred.matrix, rtol=1e-4, atol=1e-3)
    big = np.asarray(im.resize((300, 300)))  # any size
    assert isinstance(model.predict(big).params, TreeParams)
    assert len(model.predict_batch([sketch, big])) == 2


def test_mirror_averaging(model: tp.TSNModel, sketch: np.ndarray) -> None:
    """flip=True (the default) is the mean of the network outputs for the prepared sketch
    and its mirror image."""
    import torch

    from tsn import encoding

    assert model.flip is True and "flip=True" in repr(model)
    both = model.raw_batch([sketch])[0]
    x = torch.from_numpy(tp.preprocess(sketch, model.size))[None, None]
    with torch.no_grad():
        outs = [model.net(t) for t in (x, torch.flip(x, dims=[3]))]
    alone, mirrored = (encoding.join_heads({h: v.numpy() for h, v in o.items()})[0] for o in outs)
    assert not np.allclose(alone, mirrored, atol=1e-6)  # the mirror is a different input
    np.testing.assert_allclose(both, 0.5 * (alone + mirrored), atol=1e-5)
    model.flip = False
    try:
        np.testing.assert_allclose(model.raw_batch([sketch])[0], alone, atol=1e-5)
    finally:
        model.flip = True
    # the mirrored drawing gives the same averaged output: same tree, either hand
    np.testing.assert_allclose(model.raw_batch([sketch[:, ::-1].copy()])[0], both, atol=1e-4)


def test_preprocess_crops_and_pads(sketch: np.ndarray) -> None:
    x = tp.preprocess(sketch, 64)
    assert x.shape == (64, 64) and x.dtype == np.float32 and 0 <= x.min() < 0.5 <= x.max() <= 1
    shifted = np.full((200, 300), 255, np.uint8)
    shifted[50:178, 100:228] = sketch
    np.testing.assert_allclose(tp.preprocess(shifted, 64), x, atol=1e-6)
    aug = augment(sketch, np.random.default_rng(0))
    assert aug.shape == sketch.shape and aug.dtype == np.uint8 and (aug < 200).any()
    assert preprocess(aug, 32).shape == (32, 32)


@pytest.mark.parametrize(
    "bad, match",
    [
        (np.full((64, 64), 255, np.uint8), "blank"),
        (np.zeros((64, 64), np.uint8), "all dark"),
        (np.full((64, 64, 4), 0, np.uint8), "blank"),  # fully transparent = white page
        ("no/such/file.png", "not found"),
        (b"not a png", "not an image"),
        (np.zeros(5), r"\(H, W\)"),
        (np.zeros((4, 4)), "at least"),
        (np.full((32, 32), np.nan), "NaN"),
        (None, "numbers"),
        ({"a": 1}, "numbers"),
    ],
)
def test_bad_inputs(model: tp.TSNModel, bad: object, match: str) -> None:
    with pytest.raises(SketchError, match=match):
        model.predict(bad)


def test_text_file_is_not_an_image(model: tp.TSNModel, tmp_path: Path) -> None:
    f = tmp_path / "notes.png"
    f.write_text("hello")
    with pytest.raises(SketchError, match="not an image"):
        model.predict(f)


def test_bad_checkpoints(tmp_path: Path) -> None:
    with pytest.raises(CheckpointError, match="no such checkpoint"):
        tp.load_model(tmp_path / "missing.pt")
    junk = tmp_path / "junk.pt"
    junk.write_bytes(b"\x00garbage")
    with pytest.raises(CheckpointError, match="not a TSN checkpoint"):
        tp.load_model(junk)
    import torch

    torch.save({"format": "other"}, tmp_path / "other.pt")
    with pytest.raises(CheckpointError, match="not a TSN checkpoint"):
        tp.load_model(tmp_path / "other.pt")


@pytest.mark.skipif(not tp.DEFAULT_CHECKPOINT.is_file(), reason="no shipped checkpoint")
def test_shipped_checkpoint_predicts_species() -> None:
    from render.sketch import SketchRenderer

    model = tp.load_model()
    assert model.size == 192 and model.net.backbone_name == "lite0"
    for name, seed, yaw in (("palm", 9001, 0.0), ("pine", 9002, 90.0), ("cherry", 9003, 180.0)):
        img = SketchRenderer(build_mesh(grow(species.sample(name, seed)), species=name)).sketch(
            yaw, 256
        )
        pred = model.predict(img)
        assert pred.species == name
        assert isinstance(pred.params, TreeParams)


def test_views_checkpoint_reads_trees_between_the_axes() -> None:
    from render.sketch import SketchRenderer

    path = Path(__file__).resolve().parents[1] / "checkpoints" / "tsn_lite0_views.pt"
    model = tp.load_model(path)
    assert model.size == 192 and model.info["config"]["normalise"] is True
    for name, seed, yaw in (("palm", 9011, 45.0), ("bonsai", 9012, 160.0), ("pine", 9013, 290.0)):
        img = SketchRenderer(build_mesh(grow(species.sample(name, seed)), species=name)).sketch(
            yaw, 256
        )
        assert model.predict(normalise_drawing(img)).species == name


def test_shipped_checkpoint_reads_bare_winter_trees() -> None:
    """A tree drawn without its foliage (``render.styles.bare``): the shipped network reads
    it as its own species (from the branching alone) or as the bare winter tree, never as
    another leafy species; and a drawing of the winter tree reads as winter."""
    from render.sketch import SketchRenderer
    from render.styles import Silhouettes, draw

    model = tp.load_model()
    cases = (("maple", 9021, 20.0), ("cherry", 9022, 200.0), ("bonsai", 9023, 110.0))
    for name, seed, yaw in cases:
        tree = build_mesh(grow(species.sample(name, seed)), species=name)
        sil = Silhouettes.from_parts(SketchRenderer(tree).parts(yaw, 256))
        img = draw("bare", sil, np.random.default_rng(seed), 256)
        assert model.predict(normalise_drawing(img)).species in (name, "winter")
    tree = build_mesh(grow(species.sample("winter", 9024)), species="winter")
    img = SketchRenderer(tree).sketch(40.0, 256)
    assert model.predict(normalise_drawing(img)).species == "winter"


def test_a_species_branch_is_stored_read_and_feeds_the_classifier(tmp_path: Path) -> None:
    """A checkpoint with a species branch: only the copied stages are stored, the features
    are the heads' pooled features then the branch's, the heads and the tree detector read
    the first part, the species classifier the whole; a damaged branch is named."""
    import torch

    from tsn.checkpoint import load_checkpoint, save_loaded
    from tsn.model import ModelError, SpeciesBranch
    from tsn.species_id import SpeciesClassifier

    loaded = load_checkpoint(make_checkpoint(tmp_path / "base.pt", size=64))
    branch = SpeciesBranch("lite0", 12)
    with pytest.raises(ModelError, match="starts inside"):
        SpeciesBranch("lite0", 0)
    state = branch.stage_state()
    assert state and all(k.startswith(("backbone._blocks.1", "backbone._conv_head",
                                       "backbone._bn1.")) for k in state)  # fmt: skip
    assert not any(k.startswith(("backbone._blocks.0.", "backbone._conv_stem")) for k in state)
    # the copy starts as the network's own stages: its features equal the heads'
    branch.load_stage_state({k: v for k, v in loaded.model.state_dict().items() if k in state})
    names = ("palm", "pine", "maple")
    nf = loaded.model.backbone.out_features
    rng = np.random.default_rng(0)
    clf = SpeciesClassifier(
        names, np.zeros(2 * nf), np.ones(2 * nf),
        np.hstack([np.zeros((3, nf)), rng.normal(size=(3, nf))]), np.zeros(3), 1.0,
        loaded.normaliser.scale, "features",
    )  # fmt: skip
    from tsn.tree_detect import TreeDetector

    det = TreeDetector.fit(rng.normal(size=(40, nf)), np.arange(40) % 2 == 0)
    path = save_loaded(
        loaded, tmp_path / "b.pt", {}, species_id=loaded.species_id.with_classifier(clf),
        tree_detector=det, species_branch=branch,
    )  # fmt: skip
    stored = torch.load(path, weights_only=True)["species_branch"]
    assert stored["start"] == 12 and set(stored["state_dict"]) == set(state)
    model = tp.load_model(path, device="cpu")
    assert model.branch is not None and model.head_width == nf
    img = np.full((64, 64), 255, np.uint8)  # symmetric: its mirror is itself
    img[10:54, 30:34] = 0
    img[10:30, 16:48] = 0
    raw, feats = model.raw_and_features([img])
    assert feats.shape == (1, 2 * nf)
    np.testing.assert_allclose(feats[:, nf:], feats[:, :nf], rtol=1e-3, atol=1e-3)
    # the detector reads the heads' part (it was fitted on nf columns)
    tree = model.tree_probabilities(feats)
    assert tree is not None
    np.testing.assert_allclose(tree, det.probabilities(feats[:, :nf]))
    base = tp.load_model(tmp_path / "base.pt", device="cpu")
    np.testing.assert_allclose(base.raw_and_features([img])[1], feats[:, :nf], atol=1e-4)
    np.testing.assert_allclose(base.raw_batch([img]), raw, atol=1e-4)  # the heads unchanged
    pred = model.predict(img)
    p = clf.probabilities(feats[0])
    assert pred.species == max(p, key=lambda s: p[s])
    # a damaged branch is refused by name when the checkpoint is read
    ck = torch.load(path, weights_only=True)
    ck["species_branch"]["state_dict"].pop(next(iter(state)))
    torch.save(ck, tmp_path / "bad.pt")
    with pytest.raises(CheckpointError, match="species branch"):
        tp.load_model(tmp_path / "bad.pt")


def test_the_shipped_checkpoint_reads_the_species_from_its_branch() -> None:
    model = tp.load_model()
    assert model.branch is not None
    clf = model.species_id.classifier
    assert clf is not None and clf.weight.shape[1] == 2 * model.head_width
    assert model.loaded.tree_detector is not None
    assert len(model.loaded.tree_detector.mean) == model.head_width


def test_drawing_and_mirror_side_by_side_give_the_batch_s_numbers(sketch: np.ndarray) -> None:
    """On one torch thread (as the estimator runs) the drawing and its mirror, run as two
    passes on two threads, give the one batch's outputs and features to the last bit."""
    import torch

    model = tp.load_model()
    n = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        side = model._forward([sketch], True, side_by_side=True)
        batch = model._forward([sketch], True, side_by_side=False)
        alone = model._forward([sketch], False, side_by_side=True)
    finally:
        torch.set_num_threads(n)
    for a, b in zip(side, batch, strict=True):
        assert a is not None and b is not None and a.shape == b.shape
        assert np.array_equal(a, b)
    assert side[0].shape[0] == 2 and side[2] is not None and side[2].shape[0] == 1
    # without the mirror, one pass: the drawing's features of the batch
    assert np.array_equal(alone[1], batch[1][:1]) and np.array_equal(alone[2], batch[2])
