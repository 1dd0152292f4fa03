"""Symmetric collocated output feedback, Att. 5 Example 1 (issue #4): Junkins
& Kim 1990 (Att. 5 of Junkins, Pollock & Rahman 1990), Tables 1-2 with the
converged gains of its Example 1 (flexsat.control.output_feedback).

The plant (M = I, K, D of Example 1) and the gains are the printed inputs; the checks recompute
the open- and closed-loop eigenvalues and the condition numbers of the modal matrix (plain
transpose normalisation φᵀBφ = 1, Eqs. 40-41). Two printed ζω do not reproduce: mode 2
(1.0290 for 1.0189) and mode 1 (0.7536 for 0.7532). Both are errata: the paper's own closed-loop
eigenvalues in the same rows give the computed values (``discrepancy`` rows).
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import TYPE_CHECKING

from flexsat.checks.core import Check, Discrepancy, series

if TYPE_CHECKING:
    import numpy as np

    from flexsat.control.output_feedback import SymmetricOutputFeedback

SOURCE = "Junkins, Pollock & Rahman 1990"
TABLE1 = f"{SOURCE}, Att. 5 Table 1"
TABLE2 = f"{SOURCE}, Att. 5 Table 2, Example 1 gains"
OPEN_OMEGA = (1.4447, 4.4721, 6.9219)
OPEN_CONDITION = 9.4903
CLOSED_REAL = (-0.8833, -1.0574, -0.5322)
CLOSED_OMEGA = (1.4447, 4.4721, 6.7872)
CLOSED_ZETA_OMEGA = (0.7532, 1.0189, 0.5306)
CLOSED_CONDITION = 8.1291


@lru_cache(maxsize=1)
def _plant() -> SymmetricOutputFeedback:
    from flexsat.control.output_feedback import SymmetricOutputFeedback

    return SymmetricOutputFeedback.example1()


@lru_cache(maxsize=1)
def _gains() -> tuple[np.ndarray, np.ndarray]:
    import numpy as np

    from flexsat.control.output_feedback import EXAMPLE1

    return np.array(EXAMPLE1["G1"]), np.array(EXAMPLE1["G2"])


def _zero_gains() -> tuple[np.ndarray, np.ndarray]:
    import numpy as np

    return np.zeros((2, 2)), np.zeros((2, 2))


@lru_cache(maxsize=1)
def _closed_loop() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(Re λ, ω, ζω) of the three closed-loop modes, ascending ω."""
    lam = _plant().eigenvalues(*_gains())
    lam = lam[lam.imag > 0]
    omega, zeta_omega = _plant().modes(*_gains())
    return lam.real, omega, zeta_omega


def _zeta_omega(re: float, im: float) -> float:
    """ζω = Im λ · (−Re λ)/|λ|: ω = Im λ and ζ = −Re λ/|λ| (the paper's Eqs. 47-49)."""
    return im * -re / math.hypot(re, im)


def _printed_eigenvalue_erratum(i: int) -> Discrepancy | None:
    """The ζω printed in Table 2's row ``i`` against the one its own printed eigenvalue gives:
    a discrepancy where the two differ by more than the printed eigenvalue's rounding."""
    implied = _zeta_omega(CLOSED_REAL[i], CLOSED_OMEGA[i])
    if abs(implied - CLOSED_ZETA_OMEGA[i]) <= 1e-4:  # 5e-5 rounding of each of Re λ, Im λ
        return None
    return Discrepancy(
        implied,
        (
            f"Erratum in Junkins & Kim 1990 (Att. 5 of Junkins, Pollock & Rahman 1990), Table 2: "
            f"the printed ζω = {CLOSED_ZETA_OMEGA[i]} contradicts the paper's own closed-loop "
            f"eigenvalue in the same row, {CLOSED_REAL[i]} ± {CLOSED_OMEGA[i]}i, which gives "
            f"ζω = Im λ·(−Re λ)/|λ| = {implied:.4f}, the value computed here from the printed "
            "gains; "
            f"the same formula gives row 3's printed {CLOSED_ZETA_OMEGA[2]} from its eigenvalue."
        ),
    )


# Open loop: exact given the plant; 4 printed decimals, half a unit: 5e-5.
CHECKS: list[Check] = series(
    "output_feedback",
    [f"ω_{i + 1}, open loop" for i in range(3)],
    TABLE1,
    OPEN_OMEGA,
    "rad/s",
    lambda: _plant().undamped_frequencies(),
    atol=5e-5,
)
CHECKS += [
    Check(
        "output_feedback",
        "condition number, open loop",
        f"{TABLE1}, Eq. 46",
        OPEN_CONDITION,
        "",
        lambda: _plant().condition_number(*_zero_gains()),
        atol=5e-5,
    ),
]
# Closed loop: the gains are printed to 4 decimals; symmetric ±5e-5 perturbations of them move
# these values by at most 4e-5 relative (measured, 2000 samples). Tolerance 2e-4, 5 times that,
# the rule of the Draper/RPL checks (docs/draper_rpl.md).
_GAIN_RTOL = 2e-4
CHECKS += series(
    "output_feedback",
    [f"Re λ_{i + 1}, closed loop" for i in range(3)],
    TABLE2,
    CLOSED_REAL,
    "rad/s",
    lambda: _closed_loop()[0],
    rtol=_GAIN_RTOL,
)
CHECKS += series(
    "output_feedback",
    [f"ω_{i + 1}, closed loop" for i in range(3)],
    TABLE2,
    CLOSED_OMEGA,
    "rad/s",
    lambda: _closed_loop()[1],
    rtol=_GAIN_RTOL,
)
CHECKS += series(
    "output_feedback",
    [f"ζω_{i + 1}, closed loop" for i in range(3)],
    TABLE2,
    CLOSED_ZETA_OMEGA,
    "rad/s",
    lambda: _closed_loop()[2],
    rtol=_GAIN_RTOL,
    discrepancies=[_printed_eigenvalue_erratum(i) for i in range(3)],
)
CHECKS += [
    Check(
        "output_feedback",
        "condition number, closed loop",
        f"{TABLE2}, Eq. 46",
        CLOSED_CONDITION,
        "",
        lambda: _plant().condition_number(*_gains()),
        rtol=_GAIN_RTOL,
    ),
]
