"""tsn.model: pretrained EfficientNet-Lite0 weights, shapes, stage split, backbone registry."""

from __future__ import annotations

import pytest
import torch

from tsn.model import (
    BACKBONES,
    TSN,
    ModelError,
    fold_batchnorm,
    lite0_weights_path,
    make_backbone,
)
from weberpenn.params import HEAD_KEYS, HEADS


@pytest.fixture(scope="module")
def lite0() -> TSN:
    torch.manual_seed(0)
    return TSN("lite0").eval()


def test_pretrained_weights_loaded(lite0: TSN) -> None:
    sd = torch.load(lite0_weights_path(), map_location="cpu", weights_only=True)
    bb = lite0.backbone
    assert torch.equal(bb._conv_stem.weight, sd["_conv_stem.weight"])
    assert torch.equal(bb._bn0.running_var, sd["_bn0.running_var"])
    assert torch.equal(bb._blocks[15]._project_conv.weight, sd["_blocks.15._project_conv.weight"])
    assert torch.equal(bb._conv_head.weight, sd["_conv_head.weight"])
    fresh = TSN("lite0", pretrained=False)
    assert not torch.equal(fresh.backbone._conv_stem.weight, sd["_conv_stem.weight"])


def test_output_shapes_and_stage_split(lite0: TSN) -> None:
    x = torch.rand(2, 1, 64, 64)
    with torch.no_grad():
        out = lite0(x)
        assert list(out) == list(HEADS)
        for h in HEADS:
            assert out[h].shape == (2, 4, len(HEAD_KEYS[h]))
        for cut in (0, 5, 12, lite0.n_stages - 1):
            split = lite0.forward_from(lite0.features(x, cut), cut)
            for h in HEADS:
                torch.testing.assert_close(split[h], out[h], rtol=1e-4, atol=1e-5)
        # grey in, three equal ImageNet-normalised channels
        p = lite0.prepare(torch.ones(1, 1, 8, 8))
        assert p.shape == (1, 3, 8, 8)
        assert torch.allclose(p[0, :, 0, 0], (1 - lite0.mean.flatten()) / lite0.std.flatten())


def test_heads_have_paper_dropout(lite0: TSN) -> None:
    assert lite0.heads["angle"][0].p == 0.5
    assert lite0.heads["0_1"][0].p == 0.2 and lite0.heads["-inf_inf"][0].p == 0.2


def test_registry_and_second_backbone() -> None:
    assert {"lite0", "resnet_small"} <= set(BACKBONES)
    net = TSN("resnet_small").eval()
    with torch.no_grad():
        out = net(torch.rand(2, 1, 64, 64))
    assert out["angle"].shape == (2, 4, 16)
    assert len(net.frozen_modules(2)) == 2
    with pytest.raises(ModelError, match="unknown backbone"):
        make_backbone("vgg99")


@pytest.mark.parametrize("backbone", ["lite0", "resnet_small"])
def test_folded_batchnorm_gives_the_same_outputs(backbone: str) -> None:
    torch.manual_seed(1)
    net = TSN(backbone, pretrained=False)
    # non-trivial running statistics, as a trained network has
    for m in net.modules():
        if isinstance(m, torch.nn.BatchNorm2d):
            m.running_mean.uniform_(-0.5, 0.5)
            m.running_var.uniform_(0.5, 2.0)
            m.weight.data.uniform_(0.5, 1.5)
            m.bias.data.uniform_(-0.2, 0.2)
    net.eval()
    folded = fold_batchnorm(net)
    assert not any(isinstance(m, torch.nn.BatchNorm2d) for m in folded.modules())
    # the original is untouched (training goes on with its batch norms)
    assert any(isinstance(m, torch.nn.BatchNorm2d) for m in net.modules())
    x = torch.rand(3, 1, 96, 96)  # even and odd "same" paddings both occur
    with torch.no_grad():
        a, b = net(x), folded(x)
    for h in HEADS:
        torch.testing.assert_close(b[h], a[h], rtol=1e-4, atol=1e-5)
