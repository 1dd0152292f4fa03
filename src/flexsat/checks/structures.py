"""Beam benchmarks (issues #2 and #3): the exact frequency equation, 20-element uniform beams and
NAFEMS FV2 (docs/structures_benchmarks.md §1-§2, tests/cases/test_beams.py,
tests/structures/test_beam.py)."""

from __future__ import annotations

from functools import cache, lru_cache, partial
from typing import TYPE_CHECKING

from flexsat.checks.core import Check, series

if TYPE_CHECKING:
    import numpy as np

#: Blevins, *Formulas for Natural Frequency and Mode Shape* (1979)
BLEVINS = "Blevins (1979), Table 8-1"
NAFEMS = "NAFEMS R0015 (1987), test FV2, in-plane"

#: roots of 1 + cos z cosh z = 0 to 10 digits (flexsat.structures.beam.CLAMPED_FREE_BETA_L)
CLAMPED_FREE_10 = (1.875104069, 4.694091133, 7.854757438, 10.99554073, 14.13716839)
#: Blevins Table 8-1 as printed to 6 decimals (flexsat.cases.beams.PUBLISHED)
CANTILEVER = (1.875104, 4.694091, 7.854757, 10.995541)
FREE_FREE = (4.730041, 7.853205, 10.995608)
#: NAFEMS FV2 reference frequencies, Hz, modes 1-16 (multiplicities 1, 7, 1, 7)
FV2 = (11.336,) + (17.709,) * 7 + (45.345,) + (57.390,) * 7


@lru_cache(maxsize=1)
def _clamped_free() -> np.ndarray:
    from flexsat.structures.beam import clamped_free_beta_L

    return clamped_free_beta_L(len(CLAMPED_FREE_10))


@cache
def _beta_L(kind: str, plane: str) -> np.ndarray:
    from flexsat.cases import cantilever_beam, free_free_beam

    beam = cantilever_beam() if kind == "cantilever" else free_free_beam()
    n = len(CANTILEVER) if kind == "cantilever" else len(FREE_FREE)
    return beam.beta_L(n, plane)


@lru_cache(maxsize=1)
def _fv2() -> np.ndarray:
    from flexsat.cases import nafems_fv2

    return nafems_fv2().frequencies_hz(len(FV2))


def _ordinal(i: int) -> str:
    return f"βL_{i + 1}"


CHECKS: list[Check] = [
    # the exact solver (bounded-basis determinant + Brent) against the tabulated roots; they are
    # printed to 10 significant digits: 1e-9 relative is their own accuracy
    *series(
        "exact_beam",
        [f"{_ordinal(i)}, clamped-free, exact solver" for i in range(5)],
        f"{BLEVINS}, 10 digits",
        CLAMPED_FREE_10,
        "",
        _clamped_free,
        rtol=1e-9,
    ),
]

# 20 consistent-mass 3-D frame elements: issue #3 item 4 acceptance, βL within 0.01 %
for _plane in ("flatwise", "edgewise"):
    CHECKS += series(
        "cantilever_beam",
        [f"{_ordinal(i)}, {_plane}, 20 elements" for i in range(4)],
        BLEVINS,
        CANTILEVER,
        "",
        partial(_beta_L, "cantilever", _plane),
        rtol=1e-4,
    )
for _plane in ("flatwise", "edgewise"):
    CHECKS += series(
        "free_free_beam",
        [f"{_ordinal(i)}, {_plane}, 20 elements" for i in range(3)],
        BLEVINS,
        FREE_FREE,
        "",
        partial(_beta_L, "free_free", _plane),
        rtol=1e-4,
    )

# FV2's own acceptance: every frequency within 1 % with the benchmark mesh (4 elements per arm)
CHECKS += series(
    "nafems_fv2",
    [f"f_{i + 1}, 4 elements per arm" for i in range(len(FV2))],
    NAFEMS,
    FV2,
    "Hz",
    _fv2,
    rtol=1e-2,
)
