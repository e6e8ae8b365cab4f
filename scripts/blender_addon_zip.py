"""Build the installable add-on zip: ``python scripts/blender_addon_zip.py [OUT.zip]``.

The zip holds the folder ``treesketch_addon/`` (Blender's Install... button takes it as
is), ``treesketch_addon/controls.json``: the controls table
(``weberpenn.controls.table()``) and the default budget, and
``treesketch_addon/species.json``: the species a person may pick (``weberpenn.species``:
name, display name, whether the paper has it), written here so that the add-on's panel
shows the very controls and species of the project that built it (Blender's Python cannot
import the project).  Written through the project's atomic writer.
"""

from __future__ import annotations

import io
import json
import sys
import zipfile
from pathlib import Path

from refine.search import DEFAULT_BUDGET
from weberpenn import species
from weberpenn.controls import table
from weberpenn.fileio import atomic_write

ROOT = Path(__file__).resolve().parents[1]

ADDON = ROOT / "blender" / "treesketch_addon"


def addon_zip() -> bytes:
    """The zip's bytes: every file of the add-on folder except caches."""
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as zf:
        for f in sorted(ADDON.rglob("*")):
            if f.is_file() and "__pycache__" not in f.parts:
                zf.write(f, f"treesketch_addon/{f.relative_to(ADDON).as_posix()}")
        zf.writestr("treesketch_addon/controls.json", controls_json())
        zf.writestr("treesketch_addon/species.json", species_json())
    return buf.getvalue()


def controls_json() -> str:
    return json.dumps({"controls": table(), "default_budget": DEFAULT_BUDGET}, indent=1)


def species_json() -> str:
    rows = [
        {"name": s, "display": species.display_name(s), "paper": s in species.PAPER_SPECIES}
        for s in species.SPECIES
    ]
    return json.dumps({"species": rows}, indent=1)


def main(argv: list[str]) -> int:
    out = Path(argv[0]) if argv else ROOT / "out" / "treesketch_addon.zip"
    atomic_write(out, addon_zip())
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
