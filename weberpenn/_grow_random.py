"""Random draws that follow the tree's structure, for :mod:`weberpenn.grow`.

Every stem carries a 64-bit key derived from the tree's seeds and its place in the tree:
the trunk's from ``(seed, params['seed'])``, a child stem's from its parent's key and its
rank among the parent's child points, a split clone's from the spline it split from, the
segment and the clone's number.  A draw is a hash of (key, what it is for, counter):
counter-based, so all stems of a level draw at once and a stem's draws do not depend on
how many stems came before it.  Changing one value (an extra split, one more branch)
therefore changes the stems it touches and their descendants, not the whole level.

The hash is SplitMix64's finaliser (Steele, Lea and Flood 2014), whose outputs pass
BigCrush as a counter-based generator; a uniform in [0, 1) takes its top 53 bits.
"""

from __future__ import annotations

import numpy as np

# what a draw is for (mixed into the hash, so streams never overlap)
LENGTH = 1  # lengthV of a stem (or of a clone)
SPLIT = 2  # whether a spline splits at a segment
CHILD = 3  # a child stem's key, from its parent's
TIP = 4  # the key of the stem sprouting at a parent's tip
CLONE = 5  # a split clone's key
WHORL = 6  # whorl jitter of the trunk's child positions

_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_M1 = np.uint64(0xBF58476D1CE4E5B9)
_M2 = np.uint64(0x94D049BB133111EB)


_MASK = (1 << 64) - 1


def _mix(x: np.ndarray) -> np.ndarray:
    x = x ^ (x >> np.uint64(30))
    x = x * _M1
    x = x ^ (x >> np.uint64(27))
    x = x * _M2
    return x ^ (x >> np.uint64(31))


def _mix_int(x: int) -> int:
    """``_mix`` of one Python int (cheaper than a numpy call for a scalar counter)."""
    x &= _MASK
    x = ((x ^ (x >> 30)) * 0xBF58476D1CE4E5B9) & _MASK
    x = ((x ^ (x >> 27)) * 0x94D049BB133111EB) & _MASK
    return x ^ (x >> 31)


def derive(key: np.ndarray, purpose: int, counter: np.ndarray | int = 0) -> np.ndarray:
    """New keys from ``key`` (uint64 array), ``purpose`` and ``counter`` (broadcast)."""
    with np.errstate(over="ignore"):
        k = np.asarray(key, dtype=np.uint64)
        if isinstance(counter, int):
            g = 0x9E3779B97F4A7C15
            inner = np.uint64(_mix_int(counter * g + purpose * 0x94D049BB133111EB + g))
        else:
            c = np.asarray(counter, dtype=np.int64).astype(np.uint64)
            inner = _mix(c * _GOLDEN + np.uint64(purpose) * _M2 + _GOLDEN)
        return _mix((k ^ inner) + _GOLDEN)


def uniform(key: np.ndarray, purpose: int, counter: np.ndarray | int = 0) -> np.ndarray:
    """Uniform floats in [0, 1), one per broadcast (key, counter)."""
    bits = derive(key, purpose, counter) >> np.uint64(11)
    return np.atleast_1d(bits).astype(np.float64) * (1.0 / 9007199254740992.0)


def root_key(seed: int, params_seed: int) -> np.ndarray:
    """The trunk's key (a 1-element uint64 array) from ``grow``'s seed and the dictionary's."""
    words = []
    for s in (int(seed), int(params_seed)):
        words += [s & 0xFFFFFFFF, (s >> 32) & 0xFFFFFFFF]  # negative seeds as two's complement
    state = np.random.SeedSequence(words).generate_state(2, dtype=np.uint64)
    return np.array([state[0] ^ (state[1] << np.uint64(1))], dtype=np.uint64)
