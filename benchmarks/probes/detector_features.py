"""Probe: do other features tell kinds never seen from trees better than the heads' do?

The leave-categories-out detector (``scripts/fit_people.py``: fitted without the kinds of
``eval.people.LEFT_OUT_KINDS``) reads the heads' pooled features of the shipped network,
which was trained to read trees' values: in them a flower or a stick person lies among
the trees (about two thirds of left-out kinds warned).  This reads every drawing once more
and keeps, besides the heads' features, the pooled maps of earlier stages of the same
network (no extra pass at run time) and the pooled features of the ImageNet-pretrained
EfficientNet-Lite0 the network started from (a second pass), then fits the same detector
(five networks of 128 units, the limit balanced on the calibration authors' seen kinds)
on each set and prints, for the held-out authors: trees unwarned, seen kinds warned,
left-out kinds warned.

    PYTHONPATH=$PWD .venv/bin/python benchmarks/probes/detector_features.py --out DIR \
        [--quickdraw-fit 800] [--sets heads,stages,pretrained,heads+pretrained]

Features are cached in ``DIR/probe_<part>.npz`` (a stopped run resumes by chunk).  Every
feature here is of the drawing alone (no mirror), the heads' too, so the sets compare
like with like.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
import torch

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "scripts"))

from fit_people import (  # noqa: E402
    FIT_SEEDS,
    HELD_SEEDS,
    calibrating,
    code_made,
    detector_data,
    prepared,
    subset,
)

from eval.fitting import accepted  # noqa: E402
from eval.people import LEFT_OUT_KINDS, people_drawings  # noqa: E402
from tsn.model import EfficientNetLite0, load_pretrained_lite0  # noqa: E402
from tsn.predict import load_model  # noqa: E402
from tsn.tree_detect import TreeDetector  # noqa: E402

#: stages of the shipped backbone whose maps are pooled (after block 8: 80 channels at
#: 1/16; after 11: 112; after 15: 192 at 1/32; after 16: 320) and the heads' (18: 1280)
STAGES = (9, 12, 16, 17)
CHUNK = 256


def readings(model, pretrained: EfficientNetLite0, images: list) -> dict[str, np.ndarray]:
    """The feature sets of the images the pipeline accepts, and which it accepted."""
    prep, keep = accepted(images, prepared)
    out: dict[str, list] = {"heads": [], "stages": [], "pretrained": []}
    net = model.net
    with torch.no_grad():
        for i in range(0, len(prep), 32):
            x = torch.from_numpy(np.stack([model.preprocess(p) for p in prep[i : i + 32]]))
            x = net.prepare(x[:, None])
            f, pooled, start = x, [], 0
            for stop in STAGES:
                f = net.backbone.run_stages(f, start, stop)
                pooled.append(f.mean(dim=(2, 3)))
                start = stop
            out["heads"].append(net.pool(f, start).numpy())
            out["stages"].append(torch.cat(pooled, 1).numpy())
            out["pretrained"].append(pretrained.run_stages(x, 0, 18).mean(dim=(2, 3)).numpy())
    res = {k: np.concatenate(v) if v else np.zeros((0, 1)) for k, v in out.items()}
    res["kept"] = keep
    return res


def read_cached(model, pretrained, path: Path, items: list, meta: dict[str, list]) -> dict:
    """``readings`` of ``items`` ((image, ...)) by chunk into ``path``, with ``meta``
    (per item) kept for the accepted ones."""
    if path.exists():
        return dict(np.load(path))
    parts = []
    t0 = time.perf_counter()
    for i in range(0, len(items), CHUNK):
        part = path.with_suffix(f".{i // CHUNK:04d}.npz")
        if not part.exists():
            r = readings(model, pretrained, [it() for it in items[i : i + CHUNK]])
            kept = r.pop("kept")
            m = {k: np.asarray(v[i : i + CHUNK])[kept] for k, v in meta.items()}
            np.savez(part, **r, **m)
            print(f"{path.name}: {min(i + CHUNK, len(items))}/{len(items)} ({time.perf_counter() - t0:.0f} s)",
                  flush=True)  # fmt: skip
        parts.append(part)
    loaded = [dict(np.load(p)) for p in parts]
    out = {k: np.concatenate([c[k] for c in loaded]) for k in loaded[0]}
    np.savez(path, **out)
    for p in parts:
        p.unlink()
    return out


def people_part(model, pretrained, out: Path, part: str, per_kind: int, quick: int) -> dict:
    ds = people_drawings(part=part, sources=("strokes", "mouse224"), per_kind=per_kind)
    ds += people_drawings(part=part, sources=("quickdraw28",), per_kind=quick)
    meta = {
        "source": [d.source for d in ds],
        "kind": [d.kind for d in ds],
        "key": [d.key for d in ds],
    }
    return read_cached(model, pretrained, out / f"probe_people_{part}.npz",
                       [d.image for d in ds], meta)  # fmt: skip


def code_part(model, pretrained, out: Path, seeds: dict, scale: int) -> dict:
    sets = code_made(seeds, 40 // scale, 66 // scale, 16 // scale, 15 // scale)
    images = [im for imgs, _ in sets.values() for im in imgs]
    labels = [lab for _, labs in sets.values() for lab in labs]
    name = "fit" if scale == 1 else "held"
    items = [lambda im=im: im for im in images]
    return read_cached(model, pretrained, out / f"probe_code_{name}.npz", items, {"label": labels})


def columns(d: dict, which: str) -> np.ndarray:
    return np.concatenate([d[k] for k in which.split("+")], 1)


def data(code: dict, people: dict, which: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``fit_people.detector_data`` with the left-out kinds left out, on ``which``."""
    with_cols = [d | {"features": columns(d, which)} for d in (code, people)]
    return detector_data(*with_cols, with_cols[0]["features"].shape[1], LEFT_OUT_KINDS)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--fit-per-kind", type=int, default=600)
    ap.add_argument("--held-per-kind", type=int, default=400)
    ap.add_argument("--quickdraw-fit", type=int, default=800)
    ap.add_argument("--sets", default="heads,stages,pretrained,heads+stages,heads+pretrained")
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    torch.set_num_threads(2)
    model = load_model(None)
    pretrained = EfficientNetLite0()
    load_pretrained_lite0(pretrained)
    pretrained.eval()
    held = people_part(model, pretrained, args.out, "held", args.held_per_kind, args.held_per_kind)
    fit = people_part(model, pretrained, args.out, "fit", args.fit_per_kind, args.quickdraw_fit)
    code_fit = code_part(model, pretrained, args.out, FIT_SEEDS, 1)
    code_held = code_part(model, pretrained, args.out, HELD_SEEDS, 2)
    calib = calibrating(fit["key"], fit["source"])
    p_fit, p_cal = subset(fit, ~calib), subset(fit, calib)
    tree = held["kind"] == "tree"
    left = np.isin(held["kind"], LEFT_OUT_KINDS)
    seen = ~tree & ~left
    cal_seen = ~np.isin(p_cal["kind"], LEFT_OUT_KINDS)
    print(
        "| features | width | trees unwarned | seen kinds warned | left-out kinds warned | per left-out kind |"
    )
    print("|---|---:|---:|---:|---:|---|")
    for which in args.sets.split(","):
        x, y, w = data(code_fit, p_fit, which)
        hx, hy, _ = data(code_held, p_cal, which)
        det = TreeDetector.fit(x, y, held_out=(hx, hy), weights=w, l2=1e-3, hidden=128, members=5)
        det = det.with_balanced_limit(
            columns(p_cal, which)[cal_seen], p_cal["kind"][cal_seen] == "tree"
        )
        says = det.probabilities(columns(held, which)) >= 0.5
        kinds = " ".join(f"{k} {np.mean(~says[held['kind'] == k]):.0%}" for k in LEFT_OUT_KINDS)
        print(
            f"| {which} | {x.shape[1]} | {np.mean(says[tree]):.1%} | {np.mean(~says[seen]):.1%} | "
            f"{np.mean(~says[left]):.1%} | {kinds} |",
            flush=True,
        )


if __name__ == "__main__":
    main()
