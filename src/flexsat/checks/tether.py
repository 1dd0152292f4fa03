"""Vadali & Kim's tethered-subsatellite retrieval (issue 14): Junkins, Pollock & Rahman 1990,
Att. 12, Figs. 2-8 (docs/tether.md, tests/control/test_tether_laws.py). Every value is a live
rerun of the example under continuous feedback (:func:`flexsat.cases.tether.rerun`).

Two published numbers are not reproduced and carry a :class:`Discrepancy`: controller 1's
thrust index (0.997 for the printed 0.9) and the rate law's initial retrieval rate (5.83 m/s
for the printed 30 m/s).
"""

from __future__ import annotations

from collections.abc import Callable
from functools import cache, partial
from typing import Any

import numpy as np

from flexsat.checks.core import Check, Discrepancy

SOURCE = "Junkins, Pollock & Rahman 1990, Att. 12"


@cache
def _measures(key: str) -> dict[str, Any]:
    from flexsat.cases.tether import EXAMPLES, measures, paper_scales, rerun

    e = EXAMPLES[key]
    return measures(rerun(key), e.final_length, paper_scales(), e.law)


def _measure(key: str, name: str) -> float:
    return float(_measures(key)[name])


def _get(key: str, name: str) -> Callable[[], float]:
    return partial(_measure, key, name)


def _orbit_rate_per_minute() -> float:
    from flexsat.cases.tether import paper_scales

    return paper_scales().orbit_rate * 60


def _final_pitch_6_orbits() -> float:
    from flexsat.cases.tether import rerun

    return float(np.degrees(rerun("V13 K1=1.0").state[0, -1, 1]))


_INDEX_1 = Discrepancy(
    0.997,
    (
        "Not reproduced: Vadali & Kim (AIAA 90-1197) give controller 1's thrust index over two "
        "orbits as 0.9 (481 N s, which is 0.9 x m Omega L, so their conversion is consistent). "
        "Integrating their Eqs. 4, 14 and 15 (with the sign of the K3 term repaired, as solving "
        "their Eq. 13 requires) from their initial conditions gives 0.997 (533 N s), while the "
        "coupled-controller indices 0.24 and 0.258 are reproduced by the same code. No reading of "
        "the printed law gives 0.9 (K3 = 2.5 instead of 3 would)."
    ),
)
_IMPULSE_1 = Discrepancy(
    533.1,
    (
        "Not reproduced: 481 N s is the printed index 0.9 x m Omega L; the reproduced index 0.997 "
        "gives 533 N s (see the thrust-index row)."
    ),
)
_RATE = Discrepancy(
    5.83,
    (
        "Erratum: Vadali & Kim state that K1 = 0.25 gives an initial retrieval rate of 30 m/s, but "
        "their rate law (Eq. 24) from rest at lambda = 1 gives lambda' = -K1 (1 - 0.01) = -0.2475, "
        "i.e. 0.2475 x L Omega = 5.83 m/s for L = 20 km and Omega = 0.07068 rad/min; 30 m/s would "
        "need K1 = 1.29."
    ),
)

CHECKS: list[Check] = [
    # the printed rate has 4 significant figures: half a unit in the last
    Check(
        "tether",
        "orbit rate at 220 km",
        f"{SOURCE}, 'Tension Control Law Design Based on Decoupled Equations of Motion'",
        0.07068,
        "rad/min",
        _orbit_rate_per_minute,
        atol=5e-6,
    ),
    # V10. "The initial nondimensional tension is 4": (3 + K1)cos²5° − K1 λf cos5° = 3.960,
    # rounded by the paper; the band 0.05 holds that rounding, not a looser one
    Check(
        "tether",
        "controller 1: initial tension T^(0)",
        f"{SOURCE}, Figs. 2-3",
        4.0,
        "",
        _get("V10", "initial_tension"),
        atol=0.05,
    ),
    Check(
        "tether",
        "controller 1: initial tension",
        f"{SOURCE}, Figs. 2-3",
        2.52,
        "N",
        _get("V10", "initial_tension_N"),
        atol=0.03,
    ),
    # "in nearly two orbits": settled (|θ| <= 5°, λ within 2 % of its change) at 1.55 orbits
    Check(
        "tether",
        "controller 1: lambda and theta settle",
        f"{SOURCE}, Figs. 2-3",
        2.0,
        "orbits",
        _get("V10", "settling_orbits"),
        atol=0.5,
        note="|θ| <= 5°, λ within 2 %",
    ),
    # the integrator's quadrature is good to 1e-6; the band is half a unit of the printed 0.9
    Check(
        "tether",
        "controller 1: thrust index, 2 orbits",
        f"{SOURCE}, Figs. 2-3",
        0.9,
        "",
        _get("V10", "thrust_index_2_orbits"),
        atol=0.005,
        discrepancy=_INDEX_1,
    ),
    Check(
        "tether",
        "controller 1: thrust impulse, 2 orbits",
        f"{SOURCE}, Figs. 2-3",
        481.0,
        "N*s",
        _get("V10", "thrust_impulse_2_orbits_Ns"),
        atol=3.0,
        discrepancy=_IMPULSE_1,
    ),
    # V11, V12: issue 14's acceptance band for the index, ±0.01 (the paper prints 0.24 for the
    # reproduced 0.2369, two figures); the impulse band is that band x m Omega L (5.3 N s)
    Check(
        "tether",
        "controller 2: thrust index, 2 orbits",
        f"{SOURCE}, Figs. 4-5",
        0.24,
        "",
        _get("V11", "thrust_index_2_orbits"),
        atol=0.01,
    ),
    Check(
        "tether",
        "controller 2: thrust impulse, 2 orbits",
        f"{SOURCE}, Figs. 4-5",
        128.4,
        "N*s",
        _get("V11", "thrust_impulse_2_orbits_Ns"),
        atol=5.3,
    ),
    Check(
        "tether",
        "controller 2: max pitch",
        f"{SOURCE}, Fig. 4",
        29.3,
        "deg",
        _get("V11", "max_pitch_deg"),
        atol=0.05,
    ),  # half a unit in the last digit
    Check(
        "tether",
        "controller 2, K4 = 3: thrust index",
        f"{SOURCE}, Figs. 4-5",
        0.258,
        "",
        _get("V12", "thrust_index_2_orbits"),
        atol=0.01,
    ),
    # V13: "an undesirable equilibrium point is reached" (θ = π of Eq. 16's list), after six
    # orbits within 0.1° of it
    Check(
        "tether",
        "controller 2, lambda_r = .001, K1 = 1: final pitch",
        f"{SOURCE}, Fig. 6",
        180.0,
        "deg",
        _final_pitch_6_orbits,
        atol=0.5,
        note="the equilibrium θ = π; after 6 orbits",
    ),
    Check(
        "tether",
        "controller 2, lambda_r = .001, K1 = 0.9: max pitch",
        f"{SOURCE}, Fig. 7",
        21.9,
        "deg",
        _get("V13 K1=0.9", "max_pitch_deg"),
        atol=0.05,
    ),
    # V15: the law's first command is exact; the band is half a unit of 5.83
    Check(
        "tether",
        "rate law: initial retrieval rate",
        f"{SOURCE}, 'A Tether Rate Control Law', Fig. 8",
        30.0,
        "m/s",
        _get("V15", "initial_rate_m_s"),
        atol=0.005,
        discrepancy=_RATE,
    ),
]
