"""Mitsuba 3 start-up: pick the fastest variant that works, in ONE place.

``llvm_ad_rgb`` (vectorised, multi-threaded) needs a system libLLVM that Dr.Jit can use.
LLVM 15 aborts the whole process inside Dr.Jit, so it is never loaded: the search below
only accepts versions 16 and newer (preferring the newest, i.e. Debian's ``libllvm19``)
and sets ``DRJIT_LIBLLVM_PATH`` *before* drjit/mitsuba are imported.  When no usable
libLLVM is found, or the LLVM variant fails to start, ``scalar_rgb`` is used.

Environment overrides: ``TREESKETCH_MI_VARIANT`` (``llvm_ad_rgb`` or ``scalar_rgb``)
forces a variant; a ``DRJIT_LIBLLVM_PATH`` already set by the user is respected unless it
names LLVM 15 or older.

Only :mod:`render.silhouette` calls :func:`init_mitsuba`; importing other modules never
imports mitsuba.
"""

from __future__ import annotations

import functools
import glob
import logging
import os
import re
import sys
from dataclasses import dataclass
from pathlib import Path

log = logging.getLogger(__name__)

LLVM_VARIANT = "llvm_ad_rgb"
SCALAR_VARIANT = "scalar_rgb"
MIN_LLVM = 16  # LLVM 15 aborts inside Dr.Jit; older ones are not supported by it
LIB_DIRS = (
    "/usr/lib/x86_64-linux-gnu",
    "/usr/lib/aarch64-linux-gnu",
    "/usr/lib64",
    "/usr/lib",
    "/usr/local/lib",
    "/usr/lib/llvm-*/lib",
    "/opt/homebrew/opt/llvm/lib",
    "/usr/local/opt/llvm/lib",
)
_VERSION_RE = re.compile(r"libLLVM(?:-|\.so\.|\.)(\d+)")


@dataclass(frozen=True)
class Backend:
    """What :func:`init_mitsuba` chose: the variant and (for LLVM) the library path."""

    variant: str
    libllvm: str | None
    threads: int


def llvm_version(path: str | os.PathLike[str]) -> int | None:
    """Major version encoded in a libLLVM file name (``libLLVM-19.so`` -> 19), else None."""
    name = Path(path).name
    m = _VERSION_RE.search(name)
    if m:
        return int(m.group(1))
    parent = re.search(r"llvm-(\d+)", str(path))
    return int(parent.group(1)) if parent else None


def find_libllvm(dirs: tuple[str, ...] = LIB_DIRS) -> str | None:
    """Newest libLLVM (major >= 16) in the usual library folders, or None."""
    found: dict[str, int] = {}
    for pattern in dirs:
        for d in glob.glob(pattern):
            for f in glob.glob(os.path.join(d, "libLLVM*.so*")) + glob.glob(
                os.path.join(d, "libLLVM*.dylib")
            ):
                ver = llvm_version(f)
                if ver is not None and ver >= MIN_LLVM and os.path.isfile(f):
                    found.setdefault(os.path.realpath(f), ver)
    if not found:
        return None
    # newest version; among equal versions the shortest (canonical) name
    best = max(found.items(), key=lambda kv: (kv[1], -len(kv[0])))
    return best[0]


def choose_llvm_path() -> str | None:
    env = os.environ.get("DRJIT_LIBLLVM_PATH")
    if env:
        ver = llvm_version(env)
        if ver is not None and ver < MIN_LLVM:
            log.warning("ignoring DRJIT_LIBLLVM_PATH=%s (LLVM %d aborts Dr.Jit)", env, ver)
        elif os.path.isfile(env):
            return env
    return find_libllvm()


def init_mitsuba(threads: int | None = None) -> Backend:
    """Import mitsuba with the best variant (once per process) and return the choice.

    ``threads`` limits Dr.Jit's thread pool (dataset workers use 1 each); None keeps
    the current setting (Dr.Jit's default is all cores).
    """
    variant, lib = _init_once()
    import drjit as dr

    if threads is not None:
        dr.set_thread_count(max(1, int(threads)))
    return Backend(variant=variant, libllvm=lib, threads=int(dr.thread_count()))


@functools.lru_cache(maxsize=1)
def _init_once() -> tuple[str, str | None]:
    forced = os.environ.get("TREESKETCH_MI_VARIANT", "").strip()
    if forced and forced not in (LLVM_VARIANT, SCALAR_VARIANT):
        raise ValueError(
            f"TREESKETCH_MI_VARIANT={forced!r} is not one of {LLVM_VARIANT!r}, {SCALAR_VARIANT!r}"
        )
    lib = None if forced == SCALAR_VARIANT else choose_llvm_path()
    if lib is not None:
        if "drjit" in sys.modules and os.environ.get("DRJIT_LIBLLVM_PATH") != lib:
            log.warning("drjit was imported before render.backend; LLVM path may be ignored")
        os.environ["DRJIT_LIBLLVM_PATH"] = lib
    import mitsuba as mi

    variant = SCALAR_VARIANT
    if lib is not None:
        try:
            mi.set_variant(LLVM_VARIANT)
            (mi.Float([1.0, 2.0]) * 2.0).numpy()  # a tiny kernel proves the JIT works
            variant = LLVM_VARIANT
        except Exception as exc:  # pragma: no cover - depends on the machine
            log.warning("llvm_ad_rgb unavailable (%s); falling back to scalar_rgb", exc)
            lib = None
    elif forced != SCALAR_VARIANT:
        log.warning("no libLLVM >= %d found; using the slow scalar_rgb variant", MIN_LLVM)
    if variant == SCALAR_VARIANT:
        mi.set_variant(SCALAR_VARIANT)
    log.info("mitsuba %s variant %s%s", mi.__version__, variant, f" ({lib})" if lib else "")
    return variant, lib
