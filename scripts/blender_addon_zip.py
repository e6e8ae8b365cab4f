"""Build the installable add-on zip: ``python scripts/blender_addon_zip.py [OUT.zip]``.

The zip holds the folder ``treesketch_addon/`` (Blender's Install... button takes it as
is).  Written through the project's atomic writer.
"""

from __future__ import annotations

import io
import sys
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from weberpenn.fileio import atomic_write  # noqa: E402

ADDON = ROOT / "blender" / "treesketch_addon"


def addon_zip() -> bytes:
    """The zip's bytes: every file of the add-on folder except caches."""
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as zf:
        for f in sorted(ADDON.rglob("*")):
            if f.is_file() and "__pycache__" not in f.parts:
                zf.write(f, f"treesketch_addon/{f.relative_to(ADDON).as_posix()}")
    return buf.getvalue()


def main(argv: list[str]) -> int:
    out = Path(argv[0]) if argv else ROOT / "out" / "treesketch_addon.zip"
    atomic_write(out, addon_zip())
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
