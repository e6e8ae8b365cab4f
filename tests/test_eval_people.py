"""eval.people: people's drawings read from their folder, split by who drew them."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from eval.people import draw_strokes, people_drawings


def _folder(root: Path, authors: int = 40) -> Path:
    (root / "strokes").mkdir(parents=True)
    for kind in ("tree", "car"):
        with (root / "strokes" / f"{kind}.ndjson").open("w") as f:
            for a in range(authors):
                strokes = [[[10, 10], [60, 90 + a]], [[30, 5], [30, 40]]]
                f.write(json.dumps({"author": f"p{a}", "session": "s", "strokes": strokes}) + "\n")
    (root / "mouse224" / "tree").mkdir(parents=True)
    for i in range(12):
        im = np.full((224, 224, 4), 0, np.uint8)
        im[50:180, 100:104, 3] = 255  # a dark line on transparent paper
        Image.fromarray(im, "RGBA").save(root / "mouse224" / "tree" / f"{i}.png")
    (root / "quickdraw28").mkdir()
    q = np.zeros((30, 28, 28), np.uint8)
    q[:, 5:20, 14] = 255
    np.save(root / "quickdraw28" / "flower.npy", q)
    return root


def test_split_by_author_keeps_a_persons_drawings_together(tmp_path: Path) -> None:
    root = _folder(tmp_path)
    every = people_drawings(root=root)
    assert len(every) == 2 * 40 + 12 + 30
    held = people_drawings(part="held", root=root)
    fit = people_drawings(part="fit", root=root)
    assert len(held) + len(fit) == len(every) and 0 < len(held) < len(fit)
    held_authors = {d.key for d in held if d.source == "strokes"}
    fit_authors = {d.key for d in fit if d.source == "strokes"}
    assert held_authors and not held_authors & fit_authors
    # each held author's tree and car both held
    for a in held_authors:
        assert {d.kind for d in held if d.key == a} == {"tree", "car"}
    # the same split every time
    assert [d.name for d in people_drawings(part="held", root=root)] == [d.name for d in held]


def test_filters_and_images(tmp_path: Path) -> None:
    root = _folder(tmp_path)
    trees = people_drawings(kinds=("tree",), per_kind=5, root=root)
    assert {(d.source, d.kind) for d in trees} == {("strokes", "tree"), ("mouse224", "tree")}
    assert len(trees) == 10 and all(d.is_tree for d in trees)
    stroke_img = trees[0].image()
    assert stroke_img.dtype == np.uint8 and (stroke_img < 128).sum() > 50
    assert stroke_img[0, 0] == 255  # paper around the ink
    flower = people_drawings(sources=("quickdraw28",), per_kind=1, root=root)[0]
    img = flower.image()
    assert img.shape == (224, 224) and img[112, 5] == 255 and img.min() < 64  # ink is dark


def test_bad_requests(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="part"):
        people_drawings(part="test", root=tmp_path)
    with pytest.raises(ValueError, match="unknown source"):
        people_drawings(sources=("photos",), root=tmp_path)
    with pytest.raises(FileNotFoundError, match="people's drawings not found"):
        people_drawings(root=tmp_path / "nowhere")
    with pytest.raises(ValueError, match="without strokes"):
        draw_strokes([])
