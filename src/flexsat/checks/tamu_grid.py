"""The TAMU 5′ × 5′ grid (issue #3): Junkins, Pollock & Rahman 1990, Att. 4, 6 and 8
(docs/structures_benchmarks.md §3, tests/cases/test_tamu_grid.py).

Checked: Att. 4 Table 1's printed SI column against pint's conversion of its US column; the
model's node, element and dof counts (Att. 6); the modelled frequencies of Att. 8 (Das et al.,
no motors) and Att. 6 (motors + gravity correction, with the docs' representative 0.5 kg
motors); the Att. 4 caption's first frequency and mode count.

Not checked: the measured frequencies (Att. 6, 8, 10), which the model is not tuned to and
which disagree with each other by up to 20 %, and the Att. 6 Table 2 mode-1 amplitudes, which
depend on the unpublished motor masses (the docs compare their shape only).
"""

from __future__ import annotations

from functools import cache, partial
from typing import TYPE_CHECKING

from flexsat.checks.core import Check, Discrepancy, series

if TYPE_CHECKING:
    from flexsat.cases.tamu_grid import TamuGridCase

SOURCE = "Junkins, Pollock & Rahman 1990"
ATT8 = (0.90, 2.34, 4.85, 6.05, 7.78, 12.84)  # Att. 8 Figure 4 table, "Modeled Value", Hz
ATT6 = (0.809, 2.21, 4.48, 5.65, 7.76)  # Att. 6 Table 1 "Modelled (Hz)"


@cache
def _grid(motor_mass: str = "0 kg") -> TamuGridCase:
    from flexsat.cases import tamu_grid

    return tamu_grid(motor_mass=motor_mass)


def _converted(quantity: str, unit: str) -> float:
    from flexsat.units import to_si

    return to_si(quantity, unit)


def _count(name: str) -> int:
    return _counts()[name]


def _counts() -> dict[str, int]:
    grid = _grid()
    return {
        "nodes": len(grid.structure().assemble().node_ids),
        "elements": len(grid.members),
        "dof": grid.n_dofs,
    }


def _modes_below_30_hz() -> int:
    return _grid().mode_details(1)["modes_below_30_hz_with_gravity"]


_TABLE1 = f"{SOURCE}, Att. 4 Table 1, SI column"
#: 3255.2 lbf in² in N m², to the printed digits
_EI_US = 9.34182
_TYPO = Discrepancy(
    _EI_US,
    (
        "Erratum in Kim & Junkins 1990 (Att. 4 of Junkins, Pollock & Rahman 1990), Table 1: the "
        "printed SI value 9.34982 N m² is a one-digit typo for 9.34182 N m², the exact conversion "
        "of "
        "the printed US value 3255.2 lbf in² (9.34982 N m² would be 3258.0 lbf in²). The US column "
        "is the consistent one: it gives E = 10.0e6 psi, aluminium's modulus, for the 2 in x 1/8 "
        "in "
        "strip, and the other three rows convert exactly. The model uses the US column."
    ),
)
_MOTORS = "0.5 kg motors at nodes 3, 7, 9 (masses unpublished; a representative value)"
#: the model's count (with or without gravity and motors), and the argument against the caption
_MODE_COUNT = Discrepancy(
    16,
    (
        "Model deviation: the Fig. 1 caption of Kim & Junkins 1990 (Att. 4 of Junkins, Pollock & "
        "Rahman 1990) says 10 modes lie below 30 Hz; this 60-dof grid model has 16, with or "
        "without "
        "gravity and motors, while it reproduces the first six modelled frequencies of Junkins & "
        "James 1988 (Att. 8: 0.90 ... 12.84 Hz) within 4 %. A plate-like grid's mode count grows "
        "about in proportion to frequency, so six modes below 12.84 Hz imply about 14 below 30 Hz: "
        "the caption's count is taken to be loose."
    ),
)

CHECKS: list[Check] = [
    # A pure unit conversion of the US column. The paper's conversion factors are not stated and
    # its last digit is not reliably rounded (GJ: 14.185494 printed 14.18550): one unit in the
    # last printed digit.
    Check(
        "tamu_grid",
        "EI, Table 1 US column in SI",
        _TABLE1,
        9.34982,
        "N m²",
        lambda: _converted("3255.2 lbf*in**2", "N*m**2"),
        atol=1e-5,
        discrepancy=_TYPO,
    ),
    Check(
        "tamu_grid",
        "GJ, Table 1 US column in SI",
        _TABLE1,
        14.18550,
        "N m²",
        lambda: _converted("4943.0 lbf*in**2", "N*m**2"),
        atol=1e-5,
    ),
    Check(
        "tamu_grid",
        "ρA, Table 1 US column in SI",
        _TABLE1,
        0.44678,
        "kg/m",
        lambda: _converted("0.0000648 lbf*s**2/in**2", "kg/m"),
        atol=1e-5,
    ),
    Check(
        "tamu_grid",
        "ρJ, Table 1 US column in SI",
        _TABLE1,
        0.0000965,
        "kg m",
        lambda: _converted("0.0000217 lbf*s**2", "kg*m"),
        atol=1e-7,
    ),
    # counts are exact
    *(
        Check(
            "tamu_grid",
            f"model {name}",
            f"{SOURCE}, Att. 6 'Hardware Description' and 'Initial Model'",
            float(value),
            "",
            partial(_count, name),
            atol=0,
        )
        for name, value in (("nodes", 25), ("elements", 36), ("dof", 60))
    ),
]

# Das et al.'s FE model is unpublished (gravity treatment, mass model, pitch unknown); issue #3
# asked for the first frequency within 10 % and the same band is used for the other five.
# Achieved: all six within +4 % (docs §3.6). Default case: no motors, consistent gravity.
CHECKS += series(
    "tamu_grid",
    [f"f_{i + 1}, Das et al. model (no motors, gravity)" for i in range(len(ATT8))],
    f"{SOURCE}, Att. 8 Figure 4 table",
    ATT8,
    "Hz",
    lambda: _grid().frequencies_hz(len(ATT8)),
    rtol=0.10,
)
# Att. 6's model includes the motors, whose masses are unpublished: same 10 % band.
CHECKS += series(
    "tamu_grid",
    [f"f_{i + 1}, Att. 6 model (motors, gravity)" for i in range(len(ATT6))],
    f"{SOURCE}, Att. 6 Table 1",
    ATT6,
    "Hz",
    lambda: _grid("0.5 kg").frequencies_hz(len(ATT6)),
    rtol=0.10,
    notes=[_MOTORS] * len(ATT6),
)
CHECKS += [
    # ".8 Hz" is printed to one digit: half a unit, 0.05 Hz. The hardware carries its motors.
    Check(
        "tamu_grid",
        "first frequency of the hardware (with motors)",
        f"{SOURCE}, Att. 4 Fig. 1 caption",
        0.8,
        "Hz",
        lambda: _grid("0.5 kg").frequencies_hz(1)[0],
        atol=0.05,
        note=_MOTORS,
    ),
    # a count: exact. Not reproduced: 16 modes below 30 Hz with or without motors or gravity
    # (docs/structures_benchmarks.md §3.6)
    Check(
        "tamu_grid",
        "modes below 30 Hz",
        f"{SOURCE}, Att. 4 Fig. 1 caption",
        10.0,
        "",
        _modes_below_30_hz,
        atol=0,
        discrepancy=_MODE_COUNT,
    ),
]

# -- Att. 4 Table 3: LQR (Eq. 33) with r tuned to ω_i ζ_i ≥ T_i (flexsat.control.r_tuning) -------
#: symmetric three-wheel layouts (Att. 4: wheels "only at symmetric locations") that reach the
#: targets; Fig. 2's ten layouts are lost (docs/placement.md, "LQR with r tuned")
R_TUNING_LAYOUTS = (
    ("3RY", "7RX", "9RX"),
    ("3RX", "7RY", "9RY"),
    ("1RX", "3RX", "5RX"),
    ("1RX", "3RY", "5RX"),
    ("6RX", "8RX", "10RX"),
    ("16RX", "18RX", "20RX"),
    ("2RX", "3RX", "4RX"),
)


@cache
def r_tuning_designs() -> dict[tuple[str, ...], tuple[float, float, float]]:
    """(α, gain norm, κ) of the r-tuned LQR for each of :data:`R_TUNING_LAYOUTS` on the grid's
    first 10 modes (ζ = 0.005; Att. 4 gives none), output the lower-left corner (Att. 4)."""
    import numpy as np

    from flexsat.analysis import placement as pl
    from flexsat.control.r_tuning import tune_r

    model = _grid().modal_model(10, damping=0.005)
    cands = pl.actuator_candidates(model, range(1, 21), ("x", "y"), kind="torque")
    score = pl.kim_junkins_score(model, cands, model.displacement_output(1, "z")[None, :])
    out: dict[tuple[str, ...], tuple[float, float, float]] = {}
    for layout in R_TUNING_LAYOUTS:
        d_bar = np.column_stack([cands[k] for k in layout])
        design = tune_r(model.frequencies, model.damping, d_bar).design
        out[layout] = (score(layout), design.gain_norm, design.condition)
    return out


CHECKS += [
    # κ of the unit-norm closed-loop modal matrix stays near its open-loop value ω_10 (rad/s,
    # exact for the undamped open loop; control.r_tuning), so the smallest κ of Table 3
    # (configuration 8) tests the model's 10th frequency and the LQR: the 10 % band of the
    # grid's modelled frequencies (Das et al.'s FE model is unpublished, above).
    Check(
        "tamu_grid",
        "κ of the r-tuned LQR modal matrix, smallest over layouts",
        f"{SOURCE}, Att. 4 Table 3 (configuration 8)",
        127.8386,
        "",
        lambda: min(v[2] for v in r_tuning_designs().values()),
        rtol=0.10,
        note="Fig. 2 layouts lost: minimum over 7 symmetric layouts of our own",
    ),
]
