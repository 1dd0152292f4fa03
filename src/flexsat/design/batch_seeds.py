r"""The noise seeds of a batch's cases: case i's seed from the base seed and i alone.

Case i's noise seed is the i-th child of ``numpy.random.SeedSequence(base_seed)`` (its
``spawn_key`` is ``(i,)``, what ``SeedSequence.spawn`` gives the i-th child; computed directly so
a chunk never spawns the children before it), folded into the engine's seed range [0, 2⁶³):

.. math::

    s_i = \lfloor \mathrm{SeedSequence}(b, \mathrm{spawn\_key}=(i,))
          .\mathrm{generate\_state}(1, \mathrm{uint64})_0 / 2 \rfloor .

:mod:`flexsat.design.batch_runner` says why a case's result then does not depend on its chunk.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

from flexsat.input_checks import FieldError, require_finite


def nonneg_int(value: Any, name: str) -> int:
    """An integer >= 0 (bools and fractions refused), naming the field."""
    if isinstance(value, bool) or not float(require_finite(value, name)).is_integer() or value < 0:
        raise FieldError(name, f"must be an integer >= 0, got {value!r}")
    return int(value)


def case_seeds(base_seed: int, cases: npt.ArrayLike) -> npt.NDArray[np.int64]:
    """Noise seeds of the cases with indices ``cases`` (module docstring, :math:`s_i`), int64.

    Case i's seed depends on ``base_seed`` and i only, never on the chunk it is run in. Computed
    for all cases at once by :func:`_spawned_seeds` (numpy's own ``SeedSequence`` costs ~10 µs
    per case, 5 % of a metrics-only chunk); the same numbers (tests against numpy).
    """
    base = nonneg_int(base_seed, "base_seed")
    idx = np.asarray(cases, dtype=np.int64).reshape(-1)
    if base < 2**128 and (not idx.size or (idx.min() >= 0 and idx.max() < 2**32)):
        return _spawned_seeds(base, idx)
    return np.array(
        [
            int(np.random.SeedSequence(base, spawn_key=(int(i),)).generate_state(1, np.uint64)[0])
            >> 1
            for i in idx
        ],
        dtype=np.int64,
    )


_M32 = 0xFFFFFFFF
#: the hash constants of numpy's SeedSequence (O'Neill's seed_seq_fe, randutils.hpp, 2015)
_INIT_A, _MULT_A, _INIT_B, _MULT_B = 0x43B0D7E5, 0x931E8875, 0x8B51F9DD, 0x58F38DED
_MIX_L, _MIX_R = 0xCA01F9DD, 0x4973F715


def _spawned_seeds(base: int, idx: npt.NDArray[np.int64]) -> npt.NDArray[np.int64]:
    """``SeedSequence(base, spawn_key=(i,)).generate_state(1, uint64)[0] >> 1`` for every i of
    ``idx`` (0 <= i < 2**32, base < 2**128) in array operations.

    numpy's algorithm: the entropy words (base in four 32-bit words, then the spawn key i) are
    hashed into a pool of four words (hashmix: v ^= h; h *= MULT_A; v *= h; v ^= v >> 16, all
    mod 2**32) and mixed pairwise (mix: (MIX_L x − MIX_R y) ^ >> 16); the state words are
    pool words hashed with INIT_B / MULT_B. The hash constant advances the same way for every
    case, so all but the last word's mixing is the base's alone, done once in Python integers;
    the spawn word is mixed into the pool for all cases at once in uint64 arrays (products of
    two 32-bit words are exact in 64 bits, then reduced mod 2**32).
    """
    run = [(base >> (32 * k)) & _M32 for k in range(4)]
    h = _INIT_A

    def hashmix(v: int) -> int:
        nonlocal h
        v ^= h
        h = (h * _MULT_A) & _M32
        v = (v * h) & _M32
        return v ^ (v >> 16)

    def mix(x: int, y: int) -> int:
        r = (_MIX_L * x - _MIX_R * y) & _M32
        return r ^ (r >> 16)

    pool = [hashmix(w) for w in run]
    for src in range(4):
        for dst in range(4):
            if src != dst:
                pool[dst] = mix(pool[dst], hashmix(pool[src]))
    u = np.uint64
    i = idx.astype(u)
    words = []
    for dst in range(4):
        before, h = h, (h * _MULT_A) & _M32
        v = ((i ^ u(before)) * u(h)) & u(_M32)
        v ^= v >> u(16)
        r = (u(_MIX_L) * u(pool[dst]) - u(_MIX_R) * v) & u(_M32)  # wraps mod 2**64 first
        words.append(r ^ (r >> u(16)))
    state, hb = [], _INIT_B
    for w in words[:2]:  # one uint64: the first two pool words, low word first
        v = w ^ u(hb)
        hb = (hb * _MULT_B) & _M32
        v = (v * u(hb)) & u(_M32)
        state.append(v ^ (v >> u(16)))
    return ((state[0] | (state[1] << u(32))) >> u(1)).astype(np.int64)


__all__ = ["case_seeds", "nonneg_int"]
