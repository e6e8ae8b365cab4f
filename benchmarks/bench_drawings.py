"""Benchmark: the pipeline on drawings it was not trained on (issue 12).

    nice -n 10 .venv/bin/python benchmarks/bench_drawings.py --part warning \\
        --json /work/data/bench_drawings_warning.json
    nice -n 10 .venv/bin/python benchmarks/bench_drawings.py --part refine \\
        --json /work/data/bench_drawings_refine.json
    .venv/bin/python benchmarks/bench_drawings.py --part estimate
    .venv/bin/python benchmarks/bench_drawings.py --markdown FILE.json
    nice -n 5 .venv/bin/python benchmarks/bench_drawings.py --part follow --people 40 \\
        --json /tmp/follow.json

``follow`` (issue 48): does the tree follow the drawing's outline?  The envelope overlap
(``eval.envelope``) of the prepared drawing and the first estimate's sketch, and of the
drawing and the returned tree's sketch (``Result.input_sketch``, ``sketch_before``,
``sketch_after``), at the pipeline's default settings (``--budget`` 40, ``--set``), on the
first ``--people`` held-out people's tree drawings (``eval.people``; ``--people-source``
strokes, or mouse224 or quickdraw28 for another folder's drawings in another hand) and the
paper's ten (its five drawings as published and as light pencil on grey paper, as
``bench_species.py paper`` makes them) and, with ``--pairs N``, N code-made trees per
species drawn in the doodle style from two sides 90 degrees apart (seeds
``--first-seed``+), refined with both drawings: each view's overlap (does a narrow side
stay narrow?); ``--only people``, ``paper`` or ``pairs`` for one set.  The sketches are
kept beside the ``--json`` (``.npz``).

``warning``: 50 pictures that are not trees, made by code (noise of several densities,
circles, ellipses, squares, a house, a face, text in PIL's default font, random strokes, a
spiral, a grid, a star, a car-like outline, a zigzag, rings; seeded) and 25 tree drawings
(5 per species, seeds 900+, a style other than "sg", a random yaw) through
``Pipeline("tsn", RefineSettings(budget=20, species_tries=1))``.  Records the final shape
and line distances and reports which are flagged at the current
``treesketch.pipeline.LOW_CONFIDENCE_LOSS`` (and ``LOW_CONFIDENCE_INK``), and the range of
shape thresholds that flags <= 10 % of trees and >= 95 % of non-trees, if there is one.

``refine``: 25 held-out-style drawings (5 per species, seeds 950+ or ``--first-seed``+)
through the pipeline at its default settings but ``--budget`` (40) and ``--set``:
the sketch distance before/after, the species after synthesis against the truth, and the
mesh error before (TSN) and after (refined):
the combined branch+leaf Hausdorff max distance normalised by the ground truth's diagonal
(``eval.hausdorff``), each tree turned into the ground truth's frame by its own view (TSN,
which has no view, as a front view), as ``benchmarks/bench_refine.py`` does, and the
"aligned" distance (each tree turned about its trunk to its best fit).

``--views both`` (refine) runs every drawing twice: alone, and with a second drawing of
the same tree in the same style from 90 degrees further round (``Pipeline.run`` with two
views); the summary has the two-view figures under ``"two views"``.

``estimate``: milliseconds per ``Pipeline.estimate`` (normaliser + TSN) on 10 drawings and
the hand drawings of examples/hand, and per stage, wall clock and CPU time, [median, max]
after one warm-up.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import statistics
import time
from collections.abc import Callable, Sequence
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.lib.settings import add_set_option
from eval.pictures import non_trees
from render.sketch import SketchRenderer
from render.styles import Silhouettes, draw
from treesketch import Pipeline, RefineSettings, SketchError
from treesketch import pipeline as ts_pipeline
from weberpenn import build_mesh, grow, species
from weberpenn.fileio import atomic_target, atomic_write

ROOT = Path(__file__).resolve().parents[1]

SIZE = 256
HELD_OUT_STYLES = ("pen", "cloud", "scribble", "pencil", "felt")
HAND = ROOT / "examples" / "hand"  # drawings made outside the training styles


def machine() -> str:
    load = os.getloadavg()[0]
    return (
        f"{platform.machine()}, {os.cpu_count()} shared CPUs, no GPU, load average {load:.1f}; "
        f"{datetime.now(UTC):%Y-%m-%d %H:%M} UTC"
    )


# ---------------------------------------------------------------- tree drawings


def tree_drawings(
    first_seed: int,
    per_species: int,
    side: bool = False,
    only: Sequence[str] | None = None,
    style: str | None = None,
) -> list[dict]:
    """Held-out-style drawings: per species ``per_species`` trees (seeds ``first_seed``+),
    each drawn in a style other than "sg" at a random yaw.  Dicts with the drawing, the
    ground-truth params, species, style and view yaw; ``side``: also ``"side"``, the same
    tree drawn in the same style from 90 degrees further round (drawn after the first, so
    the first drawing is the same with or without it).  ``only``: those species' drawings
    alone, each the same as in the whole set; ``style``: every drawing in that style."""
    out = []
    for si, name in enumerate(species.SPECIES):
        if only is not None and name not in only:
            continue
        for k in range(per_species):
            seed = first_seed + k
            rng = np.random.default_rng([seed, si])
            drawn = style or HELD_OUT_STYLES[(k + si) % len(HELD_OUT_STYLES)]
            yaw = float(rng.uniform(0.0, 360.0))
            gt = species.sample(name, seed=seed)
            renderer = SketchRenderer(build_mesh(grow(gt)), species=name)
            img = draw(drawn, Silhouettes.from_parts(renderer.parts(yaw, SIZE)), rng, SIZE)
            out.append(
                {"name": f"{name}{seed}", "species": name, "seed": seed, "style": drawn,
                 "yaw": yaw, "params": gt, "image": img}
            )  # fmt: skip
            if side:
                parts = renderer.parts((yaw + 90.0) % 360.0, SIZE)
                out[-1]["side"] = draw(drawn, Silhouettes.from_parts(parts), rng, SIZE)
    return out


# ---------------------------------------------------------------- parts


def flagged(rec: dict, limit: float, ink_limit: float) -> bool:
    """Warned at these limits (a refused picture counts as flagged)."""
    if "refused" in rec:
        return True
    return rec["loss_after"] > limit or rec["ink_after"] > ink_limit


def _get(rec: dict, key: str) -> float:
    return math.inf if "refused" in rec else rec[key]


def _mids(values: list[float]) -> list[float]:
    """One limit per distinct outcome: midway between sorted values, and above the top."""
    v = sorted(set(values))
    return [(a + b) / 2 for a, b in zip(v, v[1:], strict=False)] + [v[-1] + 0.1]


def _loss(rec: dict) -> float:
    return _get(rec, "loss_after")


def shape_limit(embedding: str) -> float:
    """The pipeline's shape limit for the distance a run used (``--embedding``)."""
    if embedding == "none":
        return ts_pipeline.LOW_CONFIDENCE_LOSS_SHAPE
    return ts_pipeline.LOW_CONFIDENCE_LOSS


def calibrate(records: list[dict], embedding: str = "shipped") -> dict:
    """Flag rates at the current limits; the shape limits (the line limit kept) that flag
    <= 10 % of trees and >= 95 % of non-trees; the same for each distance alone."""
    ink_limit = ts_pipeline.LOW_CONFIDENCE_INK
    trees = [r for r in records if r["kind"] == "tree"]
    other = [r for r in records if r["kind"] == "non-tree"]
    hand = [r for r in records if r["kind"] == "hand"]

    def hand_flags(limit: float, line: float) -> str:
        return f"{sum(flagged(r, limit, line) for r in hand)}/{len(hand)}"

    def rates(limit: float) -> tuple[float, float]:
        ft = np.mean([flagged(r, limit, ink_limit) for r in trees])
        fo = np.mean([flagged(r, limit, ink_limit) for r in other])
        return float(ft), float(fo)

    current = shape_limit(embedding)
    cands = sorted({0.0, *(r["loss_after"] for r in records if "refused" not in r)})
    # between consecutive observed distances every limit gives the same flags
    mids = [(a + b) / 2 for a, b in zip(cands, cands[1:], strict=False)] + [cands[-1] + 0.1]
    ok = [m for m in mids if (lambda t, o: t <= 0.10 and o >= 0.95)(*rates(m))]
    ft, fo = rates(current)

    def alone(key: str) -> list[float] | None:
        """The limits on ``key`` alone that separate as asked (refused pictures flagged)."""
        vals = sorted({r[key] for r in records if "refused" not in r})
        ok1 = [
            m
            for m in [(a + b) / 2 for a, b in zip(vals, vals[1:], strict=False)]
            if np.mean([_get(r, key) > m for r in trees]) <= 0.10
            and np.mean([_get(r, key) > m for r in other]) >= 0.95
        ]
        return [min(ok1), max(ok1)] if ok1 else None

    def both() -> dict:
        """The (shape, line) limit pair that flags the most non-trees while flagging
        <= 10 % of trees (ties: the largest limits, the least eager to flag)."""
        kept = [r for r in records if "refused" not in r]
        best: tuple = ()
        for key_s in _mids([r["loss_after"] for r in kept]):
            for key_i in _mids([r["ink_after"] for r in kept]):
                ft = np.mean([flagged(r, key_s, key_i) for r in trees])
                if ft > 0.10:
                    continue
                fo = float(np.mean([flagged(r, key_s, key_i) for r in other]))
                cand = (fo, key_s + key_i, key_s, key_i, float(ft))
                best = max(best, cand) if best else cand
        if not best:
            return {}
        return {
            "shape": best[2],
            "line": best[3],
            "trees_flagged": best[4],
            "non_trees": best[0],
            "hand_flagged": hand_flags(best[2], best[3]),
        }

    return {
        "limit_now": current,
        "ink_limit": ink_limit,
        "trees_flagged_now": ft,
        "non_trees_flagged_now": fo,
        "hand_flagged_now": hand_flags(current, ink_limit),
        "feasible_min": min(ok) if ok else None,
        "feasible_max": max(ok) if ok else None,
        "shape_alone_feasible": alone("loss_after"),
        "line_alone_feasible": alone("ink_after"),
        "line_limit_fixed_shape_off_flags": list(rates(math.inf)),
        "best_pair": both(),
        "tree_loss_max": max(_loss(r) for r in trees),
        "tree_loss_p90": float(np.percentile([_loss(r) for r in trees], 90)),
        "non_tree_loss_p05": float(np.percentile([_loss(r) for r in other], 5)),
        "non_tree_loss_min": min(_loss(r) for r in other),
    }


def settings(args: argparse.Namespace, **more: Any) -> RefineSettings:
    """The pipeline's refinement settings, but the options the command line sets."""
    return RefineSettings(
        budget=args.budget,
        embedding=args.embedding,
        **(dict(args.set) | more),
    ).validate()


def part_warning(args: argparse.Namespace) -> dict:
    pipe = Pipeline(
        "tsn",
        settings(args, species_tries=1),
    )
    cases = [("non-tree", n, img, None) for n, img in non_trees(0)]
    cases += [("tree", d["name"], d["image"], d) for d in tree_drawings(900, 5)]
    if args.hand:  # drawn outside every style: checked, never calibrated on
        from treesketch import load_sketch

        cases += [("hand", f.stem, load_sketch(f), None) for f in sorted(HAND.glob("*.png"))]
    sketches: dict[str, np.ndarray] = {}
    records: list[dict] = []
    if args.resume is not None:  # a stopped run's records are kept, their cases not rerun
        records = json.loads(args.resume.read_text())["records"]
    done = {r["name"] for r in records}
    for kind, name, img, d in cases:
        if name in done:
            continue
        t = time.perf_counter()
        try:
            res = pipe.run(img)
        except SketchError as exc:  # refused before any work: as good as a warning
            records.append({"kind": kind, "name": name, "refused": str(exc)})
            print(f"{kind:>8} {name:>12} refused: {exc}", flush=True)
            continue
        rec = {
            "kind": kind,
            "name": name,
            "style": None if d is None else d["style"],
            "species_true": None if d is None else d["species"],
            "species": res.species,
            "loss_before": res.losses["before"],
            "loss_after": res.losses["after"],
            "ink_after": res.losses["ink_after"],
            "warned": res.warning is not None,
            "seconds": time.perf_counter() - t,
        }
        records.append(rec)
        sketches[f"{name}/input"] = np.asarray(res.input_sketch)
        sketches[f"{name}/after"] = np.asarray(res.sketch_after)
        if args.json is not None:
            atomic_write(args.json, json.dumps({"part": "warning", "records": records}, indent=1))
            with atomic_target(args.json.with_suffix(".npz")) as tmp, open(tmp, "wb") as fh:
                np.savez_compressed(fh, **sketches)  # to re-score the same results offline
        print(
            f"{kind:>8} {name:>12} {rec['species']:>7} shape {rec['loss_after']:.3f} "
            f"ink {rec['ink_after']:.3f} warned {rec['warned']} {rec['seconds']:.1f}s",
            flush=True,
        )
    return {"records": records, "summary": calibrate(records, args.embedding)}


def part_refine(args: argparse.Namespace) -> dict:
    from eval.hausdorff import aligned_tree_hausdorff, bbox_diagonal, hausdorff, rotate_about_trunk

    pipe = Pipeline(
        "tsn",
        settings(args),
    )
    records: list[dict] = []
    # one of each species at a time, and each case saved as it ends: a run stopped early
    # still has a balanced, readable record
    drawings = sorted(
        tree_drawings(args.first_seed, args.per_species, args.views != "1", args.species),
        key=lambda d: (d["seed"], species.SPECIES.index(d["species"])),
    )
    counts = {"1": (1,), "2": (2,), "both": (1, 2)}[args.views]
    for d, views in ((d, v) for d in drawings for v in counts):
        t = time.perf_counter()
        res = pipe.run(d["image"] if views == 1 else [d["image"], (d["side"], 90.0)])
        secs = time.perf_counter() - t
        gt_mesh = build_mesh(grow(d["params"]), species=d["species"])
        gt_c, diag = gt_mesh.combined(), bbox_diagonal(gt_mesh.bounds())
        est = res.estimate
        m0 = build_mesh(grow(est.params), species=est.species)
        m1 = res.tree_mesh
        yaw0 = 0.0 if est.yaw is None else float(est.yaw)
        # each tree turned from its own view into the drawing's, the ground truth's frame
        truth = (gt_c, args.samples, diag)
        h0 = hausdorff(rotate_about_trunk(m0, d["yaw"] - yaw0).combined(), *truth)
        h1 = hausdorff(rotate_about_trunk(m1, d["yaw"] - res.yaw).combined(), *truth)
        _, a0 = aligned_tree_hausdorff(m0, gt_mesh, args.samples, args.align_step)
        _, a1 = aligned_tree_hausdorff(m1, gt_mesh, args.samples, args.align_step)
        rec = {
            "name": d["name"],
            "views": views,
            "style": d["style"],
            "species_true": d["species"],
            "species_tsn": est.species,
            "species": res.species,
            "loss_before": res.losses["before"],
            "loss_after": res.losses["after"],
            "haus_before": h0.max_norm,
            "haus_after": h1.max_norm,
            "aligned_before": a0.max_norm,
            "aligned_after": a1.max_norm,
            "yaw_view": d["yaw"],
            "yaw_found": res.yaw,
            "warned": res.warning is not None,
            "tried": res.extras.get("tried", {}),
            "seconds": secs,
        }
        records.append(rec)
        print(refine_line(rec), flush=True)
        if args.json is not None:
            partial = {"part": "refine", "records": records, "summary": refine_summaries(records)}
            atomic_write(args.json, json.dumps(partial | {"machine": machine()}, indent=1))
    return {"records": records, "summary": refine_summaries(records)}


def refine_summaries(records: list[dict]) -> dict:
    """:func:`refine_summary` of the one-view records, and of the two-view ones apart
    (``"two views"``) when there are any."""
    one = [r for r in records if r.get("views", 1) == 1]
    two = [r for r in records if r.get("views", 1) == 2]
    out = refine_summary(one) if one else {}
    if two:
        out["two views"] = refine_summary(two)
    return out


def refine_summary(records: list[dict]) -> dict:
    n = len(records)

    def frac(f: Callable[[dict], bool]) -> float:
        return sum(map(f, records)) / n

    summary = {
        "n": n,
        "loss_fell": frac(lambda r: r["loss_after"] < r["loss_before"]),
        "haus_improved": frac(lambda r: r["haus_after"] < r["haus_before"]),
        "aligned_improved": frac(lambda r: r["aligned_after"] < r["aligned_before"]),
        "species_tsn_right": frac(lambda r: r["species_tsn"] == r["species_true"]),
        "species_right": frac(lambda r: r["species"] == r["species_true"]),
        "warned": frac(lambda r: r["warned"]),
        **{
            f"{k}_mean": float(np.mean([r[k] for r in records]))
            for k in ("loss_before", "loss_after", "haus_before", "haus_after")
            + ("aligned_before", "aligned_after", "seconds")
        },
    }
    return summary


def refine_line(r: dict) -> str:
    return (
        f"| {r['name']} | {r.get('views', 1)} | {r['style']} | {r['species_tsn']} -> {r['species']} | "
        f"{r['loss_before']:.3f} -> {r['loss_after']:.3f} | "
        f"{r['haus_before']:.3f} -> {r['haus_after']:.3f} | "
        f"{r['aligned_before']:.3f} -> {r['aligned_after']:.3f} | {r['seconds']:.0f} |"
    )


def part_estimate(args: argparse.Namespace) -> dict:
    """Wall and CPU milliseconds of ``Pipeline.estimate`` and of its two stages (reading +
    normalising, the estimator), per sketch; CPU time is what the shared machine's load
    does not inflate (much)."""
    from treesketch.pipeline import load_sketch, prepare_input

    pipe = Pipeline("tsn")
    imgs = [d["image"] for d in tree_drawings(900, 2)]
    pngs = sorted((ROOT / "examples" / "hand").glob("*.png"))
    sources = [*imgs, *pngs]
    pipe.estimate(sources[0])  # warm-up: the first call pays for lazy set-up
    clocks = {"wall": time.perf_counter, "cpu": time.process_time}
    per: dict[str, list[float]] = {}
    for src in sources:
        for clock, now in clocks.items():
            t = now()
            pipe.estimate(src)
            per.setdefault(f"estimate_{clock}", []).append((now() - t) * 1000)
            t = now()
            img = prepare_input(load_sketch(src))
            per.setdefault(f"prepare_{clock}", []).append((now() - t) * 1000)
            t = now()
            pipe.estimator.estimate(img)
            per.setdefault(f"tsn_{clock}", []).append((now() - t) * 1000)
    out = {"n": len(sources)} | {
        f"{k}_ms": [round(statistics.median(v), 1), round(max(v), 1)] for k, v in per.items()
    }
    print(json.dumps(out))
    return {"records": per, "summary": out}


def rescore(path: Path) -> None:
    """The line distance of every result in a warning ``--json`` recomputed by the current
    ``tree_line_distance`` from the input and final sketches saved beside it (``.npz``):
    the refinement's results kept, the warning's second test changed."""
    doc = json.loads(path.read_text())
    saved = np.load(path.with_suffix(".npz"))
    size = RefineSettings().size
    for rec in doc["records"]:
        if "refused" not in rec:
            drawing, after = saved[f"{rec['name']}/input"], saved[f"{rec['name']}/after"]
            rec["ink_after"] = ts_pipeline.tree_line_distance(drawing, after, size)
    doc["rescored"] = machine()
    atomic_write(path, json.dumps(doc, indent=1))


def markdown(doc: dict) -> str:
    part, recs = doc["part"], doc["records"]
    lines = [f"machine: {doc['machine']}", ""]
    if part == "warning":
        lines += ["| tree drawing | style | species found | shape distance | line distance |"]
        lines += ["|---|---|---|---:|---:|"]
        for r in sorted((r for r in recs if r["kind"] == "tree"), key=_loss):
            lines.append(
                f"| {r['name']} | {r['style']} | {r['species']} | {r['loss_after']:.3f} "
                f"| {r['ink_after']:.3f} |"
            )
        hand = [r for r in recs if r["kind"] == "hand"]
        if hand:
            lines += ["", "| hand drawing | species found | shape distance | line distance |"]
            lines += ["|---|---|---:|---:|"]
            for r in sorted(hand, key=_loss):
                lines.append(
                    f"| {r['name']} | {r.get('species', '-')} | {_loss(r):.3f} "
                    f"| {_get(r, 'ink_after'):.3f} |"
                )
        groups: dict[str, list[dict]] = {}
        for r in recs:
            if r["kind"] == "non-tree":
                groups.setdefault(r["name"].rstrip("0123456789."), []).append(r)
        lines += ["", "| non-trees | n | refused | shape distance min | line distance min |"]
        lines += ["|---|---:|---:|---:|---:|"]
        for g, rs in groups.items():
            kept = [r for r in rs if "refused" not in r]
            lo = min((r["loss_after"] for r in kept), default=math.nan)
            li = min((r["ink_after"] for r in kept), default=math.nan)
            lines.append(f"| {g} | {len(rs)} | {len(rs) - len(kept)} | {lo:.3f} | {li:.3f} |")
    elif part == "refine":
        lines += [
            "| drawing | views | style | species TSN -> final | sketch distance | Hausdorff max "
            "(gt frame) | aligned max | s |",
            "|---|---:|---|---|---|---|---|---:|",
            *map(refine_line, recs),
        ]
    embedding = doc.get("args", {}).get("embedding", "shipped")
    summary = calibrate(recs, embedding) if part == "warning" else doc["summary"]
    lines += ["", "```", json.dumps(summary, indent=1), "```"]
    return "\n".join(lines)


def paper_drawings() -> list[tuple[str, np.ndarray]]:
    """The paper's five drawings as published and as light pencil on grey paper (the
    "ten drawings"; made as ``bench_species.py paper`` makes them, same seed)."""
    from PIL import Image

    from benchmarks.bench_species import PAPER_SPECIES, PAPER_STRIP, cut_at_blank_columns

    page = np.asarray(Image.open(PAPER_STRIP).convert("L"))
    rng = np.random.default_rng(0)
    out = []
    for name, img in zip(
        PAPER_SPECIES, cut_at_blank_columns(page, len(PAPER_SPECIES)), strict=True
    ):
        h, w = img.shape
        light = np.linspace(150.0, 205.0, w)[None, :] - 0.4 * (255.0 - img)
        grey = np.clip(light + rng.normal(0.0, 4.0, (h, w)), 0, 255).astype(np.uint8)
        out += [(f"paper/{name}", img), (f"paper/{name}-pencil", grey)]
    return out


def follow_cases(args: argparse.Namespace) -> list[tuple[str, Any]]:
    """The ``follow`` part's drawings: (name, what the pipeline reads), people's first,
    then the paper's, then ``--pairs`` code-made trees per species drawn in the doodle
    style from two sides 90 degrees apart (``[front, (side, 90.0)]``)."""
    from eval.people import people_drawings

    cases = []
    if args.only in (None, "people"):
        source = getattr(args, "people_source", "strokes")
        part = getattr(args, "people_part", "held")
        held = people_drawings(part, (source,), ("tree",))
        pick = getattr(args, "people_pick", None)
        first = args.people_from
        chosen = pick if pick is not None else range(first, min(len(held), first + args.people))
        if any(not 0 <= i < len(held) for i in chosen):
            raise SystemExit(f"--people-pick: {source} holds {len(held)} {part} part trees")
        # a mouse224 key names its folder ("tree/12"): one name part per drawing
        cases += [
            (f"people/{i:02d}-{held[i].key.replace('/', '-')}", held[i].image()) for i in chosen
        ]
    if args.only in (None, "paper"):
        cases += paper_drawings()
    if args.only in (None, "pairs") and args.pairs > 0:
        for d in tree_drawings(args.first_seed, args.pairs, side=True, style="doodle"):
            cases.append((f"pairs/{d['name']}", [d["image"], (d["side"], 90.0)]))
    return cases


def as_list(img: Any) -> list:
    """A follow case's drawings: ``[img]`` for one, the list (``[front, (side, yaw)]``)
    for two."""
    return img if isinstance(img, list) else [img]


def seen_shape(img: Any) -> Any:
    """A drawing's ``ShapeTarget`` as the refinement's search sees it (read, prepared,
    framed at its 128 px)."""
    from refine.objective import PreparedDrawing
    from treesketch.steps import load_sketch, prepare_input

    return PreparedDrawing.create(prepare_input(load_sketch(img)), 128).shape


def inside_ink(img: Any) -> float:
    """How much of a drawing's crown's inside is drawn (``ShapeTarget.inside_ink``), as
    the refinement sees it: under ``refine.start.LINES_INSIDE`` a drawing of outlines,
    searched for its outline; at or above it one that shows its inside."""
    return seen_shape(img).inside_ink


def part_follow(args: argparse.Namespace) -> dict:
    from eval.envelope import envelope_overlap

    pipe = Pipeline("tsn", settings(args))
    records: list[dict] = []
    sketches: dict[str, np.ndarray] = {}
    for name, img in follow_cases(args):
        t = time.perf_counter()
        res = pipe.run(img)
        views = res.views or (res,)  # each drawn view's sketches (one view: the result's)
        before = [envelope_overlap(v.input_sketch, v.sketch_before) for v in views]
        after = [envelope_overlap(v.input_sketch, v.sketch_after) for v in views]
        rec = {
            "name": name,
            "species": res.species,
            "overlap_before": before[0],
            "overlap_after": after[0],
            "view_overlaps_before": before,
            "view_overlaps_after": after,
            "loss_before": res.losses["before"],
            "loss_after": res.losses["after"],
            "first_seconds": res.timings["prepare"] + res.timings["estimate"],
            "refine_seconds": res.timings["refine"],
            "seconds": time.perf_counter() - t,
            "yaw": res.yaw,
            # over the drawn views, as the refinement reads them
            "inside_ink": float(
                np.mean([inside_ink(v[0] if isinstance(v, tuple) else v) for v in as_list(img)])
            ),
            "params": res.params.to_dict(),
        }
        records.append(rec)
        for key in ("input_sketch", "sketch_before", "sketch_after"):
            sketches[f"{name}/{key}"] = np.asarray(getattr(res, key))
            for i, v in enumerate(views[1:], 2):
                sketches[f"{name}/view{i}/{key}"] = np.asarray(getattr(v, key))
        print(
            f"{name:>24} {rec['species']:>7} overlap {rec['overlap_before']:.3f} -> "
            f"{rec['overlap_after']:.3f} loss {rec['loss_before']:.3f} -> "
            f"{rec['loss_after']:.3f} {rec['seconds']:.1f}s",
            flush=True,
        )
        if args.json is not None:
            partial = {"part": "follow", "records": records, "summary": follow_summary(records)}
            atomic_write(args.json, json.dumps(partial | {"machine": machine()}, indent=1))
            with atomic_target(args.json.with_suffix(".npz")) as tmp, open(tmp, "wb") as fh:
                np.savez_compressed(fh, **sketches)
    return {"records": records, "summary": follow_summary(records)}


def follow_summary(records: list[dict]) -> dict:
    """Per set (people's, the paper's): the median overlap of the first estimate and of
    the returned tree, the share of drawings whose overlap the refinement raised, the
    median seconds (first tree, refinement, whole run), and the returned trees' median
    overlap for the drawings of outlines and those that show their inside
    (``inside_ink`` under ``refine.start.LINES_INSIDE`` or not; ``[n, median]``)."""
    from refine.start import LINES_INSIDE

    out = {}
    for group in ("people", "paper", "pairs"):
        rs = [r for r in records if r["name"].startswith(group + "/")]
        if not rs:
            continue

        def med(key: str, rs: list[dict] = rs) -> float:
            return float(statistics.median(r[key] for r in rs))

        out[group] = {
            "n": len(rs),
            "overlap_before": med("overlap_before"),
            "overlap_after": med("overlap_after"),
            "raised": sum(r["overlap_after"] > r["overlap_before"] for r in rs) / len(rs),
            # every drawn view's overlap (two-drawing pairs: the side's too)
            "view_overlaps_after": [
                float(
                    statistics.median(
                        r.get("view_overlaps_after", [r["overlap_after"]])[i] for r in rs
                    )
                )
                for i in range(len(rs[0].get("view_overlaps_after", [0])))
            ],
            "loss_before": med("loss_before"),
            "loss_after": med("loss_after"),
            "first_seconds": med("first_seconds"),
            "refine_seconds": med("refine_seconds"),
            "seconds": med("seconds"),
        }
        if all("inside_ink" in r for r in rs):
            for key, pick in (("outlines", True), ("insides", False)):
                sub = [r["overlap_after"] for r in rs if (r["inside_ink"] < LINES_INSIDE) == pick]
                out[group][key] = [len(sub), float(statistics.median(sub)) if sub else math.nan]
    return out


def species_list(text: str) -> tuple[str, ...]:
    """``--species``: comma-separated species names (``weberpenn.species.canonical``)."""
    try:
        names = tuple(species.canonical(n) for n in text.split(",") if n.strip())
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    if not names:
        raise argparse.ArgumentTypeError(f"no species named in {text!r}")
    return names


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--part", choices=("warning", "refine", "estimate", "follow"), default="warning"
    )
    ap.add_argument("--people", type=int, default=40, help="follow: people's drawings")
    ap.add_argument(
        "--people-from", type=int, default=0, help="follow: the first people's drawing's index"
    )
    ap.add_argument(
        "--people-pick",
        type=lambda t: [int(i) for i in t.split(",") if i.strip()],
        default=None,
        help="follow: only these people's drawings (comma-separated indices, as "
        "benchmarks/probes/reframed.py prints them; --people and --people-from ignored)",
    )
    ap.add_argument(
        "--people-source",
        choices=("strokes", "mouse224", "quickdraw28"),
        default="strokes",
        help="follow: which of people's folders (strokes: the web page's drawings, the "
        "figures of issue 48; mouse224: one drawing app's; quickdraw28: Quick, Draw!'s "
        "28 px doodles; the last two never looked at while the refinement was built)",
    )
    ap.add_argument(
        "--people-part",
        choices=("held", "fit"),
        default="held",
        help="follow: people's held-out part (the figures) or the fit part (by other people; "
        "to check a rule built looking at held-out drawings on drawings it never saw)",
    )
    ap.add_argument(
        "--only", choices=("people", "paper", "pairs"), default=None, help="follow: one set"
    )
    ap.add_argument(
        "--pairs", type=int, default=0, help="follow: two-drawing doodle pairs per species"
    )
    ap.add_argument("--budget", type=int, default=None, help="20 for warning, 40 for refine")
    ap.add_argument("--per-species", type=int, default=5)
    ap.add_argument(
        "--first-seed", type=int, default=950, help="refine: the drawings' first tree seed"
    )
    ap.add_argument("--samples", type=int, default=10_000, help="Hausdorff samples per side")
    ap.add_argument(
        "--views",
        choices=("1", "2", "both"),
        default="1",
        help="refine: each drawing alone (1), with the same tree drawn from 90 degrees "
        "further round (2), or both runs side by side in one run",
    )
    ap.add_argument(
        "--species",
        type=species_list,
        default=None,
        help="refine: comma list, only these species' drawings (each as in the whole set)",
    )
    ap.add_argument("--align-step", type=float, default=15.0)
    ap.add_argument("--json", type=Path, default=None)
    ap.add_argument("--resume", type=Path, default=None, help="warning: keep this JSON's records")
    ap.add_argument("--hand", action="store_true", help="warning: also examples/hand (reported)")
    ap.add_argument(
        "--rescore",
        type=Path,
        default=None,
        help="warning: recompute a --json's line distances from its saved sketches (.npz)",
    )
    ap.add_argument("--markdown", type=Path, default=None, help="print the tables of a --json")
    ap.add_argument(
        "--embedding",
        default="shipped",
        help="RefineSettings.embedding: shipped, none or a checkpoint (warning and refine)",
    )
    add_set_option(ap, "any other RefineSettings field (warning and refine), e.g. species_tries=1")
    args = ap.parse_args(argv)
    if args.markdown is not None:
        print(markdown(json.loads(args.markdown.read_text())))
        return 0
    if args.rescore is not None:
        rescore(args.rescore)
        print(markdown(json.loads(args.rescore.read_text())))
        return 0
    if args.budget is None:
        args.budget = 20 if args.part == "warning" else 40  # follow: the default, 40
    try:
        settings(args)
    except ValueError as exc:
        ap.error(str(exc))
    run = {
        "warning": part_warning,
        "refine": part_refine,
        "estimate": part_estimate,
        "follow": part_follow,
    }[args.part]
    t = time.perf_counter()
    doc = {"part": args.part, "args": {k: str(v) for k, v in vars(args).items()}}
    doc |= run(args)
    doc["machine"] = machine()
    doc["seconds"] = time.perf_counter() - t
    print(json.dumps(doc["summary"], indent=1))
    if args.json is not None:
        atomic_write(args.json, json.dumps(doc, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
