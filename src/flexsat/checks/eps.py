"""Earth Pointing Satellite (issue #3): EPS slew study c. 1989, "Model Development" (docs/eps.md,
tests/cases/test_eps.py).

The structure is a reconstruction (Fig. 1 is lost): the checks show how close it comes. Two
documented deviations (docs/eps.md, deviations 1 and 3) are ``discrepancy`` rows, pinned to the
model's values: the first truss mode (15.4 Hz for "about 7.0 Hz") and the deck's element count
(219 for 223).

The slew goals of "Simulation Results" (Euler-angle error within 3 % of the commanded 1 rad
at 1.25 T; the peak rim deflection from 1.25 T reduced at least 10:1 from the open loop's) are
requirements, not measured values: a goal row checks that the computed value meets it, the
bound written as an interval's midpoint and half-width (error ≤ 3 % is 1.5 ± 1.5 %; the
deflection ratio ≥ 10:1 as its inverse, closed / open ≤ 0.1, is 0.05 ± 0.05). They are
judged on the slews with torquers alone whose torque history is planned over the whole
maneuver (flexsat.design.planned_slew; docs/eps.md, "Planned slews with torquers alone"):
the 45-mode plant, the 10-mode design model, 50 Hz control, 20 sines per axis, two
relinearisations, about 2 s of CPU per slew.

Not checked: the total mass 1028 kg (the torquer mass is balanced to give it) and the other
published inputs (tube, material, damping).
"""

from __future__ import annotations

from functools import lru_cache, partial
from typing import TYPE_CHECKING

from flexsat.checks.core import Check, Discrepancy, series

if TYPE_CHECKING:
    from flexsat.cases.eps import EPSCase
    from flexsat.maneuvers.three_axis_slew import ThreeAxisSlew

SOURCE = "EPS slew study c. 1989"
#: "Model Development": paper modes 7-20, Hz
MODES_7_20 = (
    0.2422,
    0.4056,
    0.5652,
    0.6562,
    0.8882,
    0.8882,
    1.4377,
    1.5360,
    1.7762,
    1.7762,
    3.0258,
    3.0258,
    3.1532,
    3.1532,
)


@lru_cache(maxsize=1)
def _case() -> EPSCase:
    from flexsat.cases import eps

    return eps()


@lru_cache(maxsize=1)
def _nominal_slew() -> ThreeAxisSlew:
    """The 10 s nominal slew of the EPS slew study c. 1989 (1 rad about each 1-2-3 axis,
    ω_B = 2.5 rad/s, the
    paper's literal shaping weight ζ_B = 0) on the rebuilt model's inertia about its CG."""
    from flexsat.maneuvers import three_axis_slew

    inertia = _case().mass_properties()["inertia_center_of_mass"]
    return three_axis_slew(inertia, [1.0, 1.0, 1.0], 10.0, 2.5, zeta_b=0.0)


@lru_cache(maxsize=2)
def _planned_slew_goals(duration: float) -> tuple[float, float]:
    """(Euler-angle error at 1.25 T in % of the commanded 1 rad, rim deflection from 1.25 T
    closed / open loop) of the planned torquers-only slew of ``duration`` s (module
    docstring): 1 rad about each 1-2-3 axis, ω_B = 2.5 rad/s at 10 s and 5 rad/s at 6 s
    (cases A and D), ζ_B = 0."""
    import numpy as np

    from flexsat.control import NominalTorque
    from flexsat.design.planned_slew import planned_slew
    from flexsat.design.slew_weights import SlewEvaluation
    from flexsat.dynamics.attitude import euler123_to_quaternion
    from flexsat.dynamics.flexible_spacecraft import FlexibleSpacecraft
    from flexsat.maneuvers import three_axis_slew
    from flexsat.sim import SimConfig

    truth = _case().plant(n_modes=45)
    assert isinstance(truth, FlexibleSpacecraft)
    design = truth.reduced(10)
    omega_b = {10.0: 2.5, 6.0: 5.0}[duration]
    target = euler123_to_quaternion(np.ones(3))
    nominal = three_axis_slew(truth.inertia, target, duration, omega_b, zeta_b=0.0)
    # the deflection judged over 2 s past 1.25 T (half a period of the first mode, 0.25 Hz)
    config = SimConfig(duration=1.25 * duration + 2.0, control_rate=50.0)
    plan = planned_slew(truth, design, nominal, config, 20, iterations=2)
    m = SlewEvaluation(truth, design, nominal, config).run(NominalTorque(plan, config.dt))
    # the commanded angle is 1 rad about each axis: mrad / 1000 mrad × 100 %
    return 0.1 * float(m["angle_error_mrad"]), 1.0 / float(m["deflection_ratio_after"])


def _goal(duration: float, which: int) -> float:
    """Entry ``which`` of :func:`_planned_slew_goals` (what a goal row computes)."""
    return _planned_slew_goals(duration)[which]


def _peak_torque(axis: int) -> float:
    import numpy as np

    slew = _nominal_slew()
    return float(np.abs(slew.torque(np.linspace(0.0, slew.duration, 2001))[:, axis]).max())


@lru_cache(maxsize=1)
def _first_truss_mode() -> tuple[int, float, str]:
    return _case().first_truss_mode()


_TRUSS = Discrepancy(
    15.36,
    (
        'Model deviation: the EPS study gives the first truss mode as "about 7.0 Hz" (elastic '
        "mode 50; the model's mode number agrees). The model keeps the published truss, a 3 m "
        "cross "
        "section of 51 mm x 1.59 mm graphite tubes, whose bending stiffness (about EA x 4 x (1.5 "
        "m)² "
        "= 6.1e8 N m²) puts the first bending mode of the 25 m truss near 15.4 Hz; the antennas, "
        "isolated by their supports, cannot lower it much. Only a truss about 1.25 m wide gives "
        "7 Hz, against the published 3 m and structural mass. The paper's figure of the truss is "
        "lost."
    ),
)
_ELEMENTS = Discrepancy(
    219,
    (
        "Model deviation: the EPS study's NASTRAN deck has 95 nodes (reproduced) and 223 elements. "
        "The paper's figure of the structure is lost; the reconstruction carries the torquer mass "
        "on "
        "4 support tubes, giving 219 elements. With 8 tubes (every bay corner) it would have 223, "
        "but about 17 kg more structure: 570 kg instead of the published 548 kg, which the model "
        "reproduces within 1 %."
    ),
)

# Issue #3: each of paper modes 7-20 within ±25 % of the table (achieved: −6.9 … +3.4 %).
CHECKS: list[Check] = series(
    "eps",
    [f"f, paper mode {i + 7}" for i in range(len(MODES_7_20))],
    f"{SOURCE}, 'Model Development'",
    MODES_7_20,
    "Hz",
    lambda: _case().frequencies_hz(len(MODES_7_20)),
    rtol=0.25,
)
CHECKS += [
    # "about 7.0 Hz": the same ±25 % as the antenna modes. Not reproduced (docs/eps.md dev. 1)
    Check(
        "eps",
        "first truss mode frequency",
        f"{SOURCE}, 'Model Development'",
        7.0,
        "Hz",
        lambda: _first_truss_mode()[1],
        rtol=0.25,
        discrepancy=_TRUSS,
    ),
    # counts: exact
    Check(
        "eps",
        "first truss mode number (elastic)",
        f"{SOURCE}, 'Model Development'",
        50.0,
        "",
        lambda: _first_truss_mode()[0],
        atol=0,
    ),
    Check(
        "eps",
        "truss beam elements",
        f"{SOURCE}, 'Model Development'",
        135.0,
        "",
        lambda: _case().element_counts["truss"],
        atol=0,
    ),
    Check(
        "eps",
        "NASTRAN deck nodes",
        f"{SOURCE}, 'Model Development'",
        95.0,
        "",
        lambda: len(_case().assembly.node_ids),
        atol=0,
    ),
    Check(
        "eps",
        "NASTRAN deck elements",
        f"{SOURCE}, 'Model Development'",
        223.0,
        "",
        lambda: _case().n_elements,
        atol=0,
        discrepancy=_ELEMENTS,
    ),
    # The truss layout is reconstructed; its tube lengths set the structural mass. The tests' 1 %
    # band (achieved +0.95 %).
    Check(
        "eps",
        "structural mass",
        f"{SOURCE}, 'Model Development'",
        548.0,
        "kg",
        lambda: _case().mass_budget()["structural"],
        rtol=0.01,
    ),
    # "peak torque ≈ 12,000 N m about body z" of the 10 s nominal (Fig. 3). The paper's
    # inertia is not published: this is the optimal maneuver on the rebuilt model's inertia
    # (I_zz 9.1e4 kg m²), an order-of-magnitude comparison; the issue asks for no more. The
    # band ±50 % (achieved −3 %); with the damped reading ζ_B = 1 the peak is 7.3 kN m.
    Check(
        "eps",
        "peak nominal z torque, 10 s slew",
        f"{SOURCE}, Fig. 3",
        12000.0,
        "N*m",
        lambda: _peak_torque(2),
        rtol=0.5,
    ),
    # Goals, "Simulation Results": a requirement met when the computed value lies in the
    # interval (module docstring), not a number reproduced. Cases A and D with the feedback
    # miss them (docs/eps.md); the torque history planned over the maneuver meets both.
]
_GOALS = f"{SOURCE}, 'Simulation Results' (goal)"
for _duration, _case_name in ((10.0, "A"), (6.0, "D")):
    CHECKS += [
        Check(
            "eps",
            f"Euler error at 1.25 T, {_duration:.0f} s slew, torquers alone, planned (≤ 3 %)",
            _GOALS,
            1.5,
            "%",
            partial(_goal, _duration, 0),
            atol=1.5,
            note=f"torquers alone as case {_case_name}; the torque planned over the maneuver",
        ),
        Check(
            "eps",
            f"rim deflection from 1.25 T, closed / open, {_duration:.0f} s slew, torquers "
            "alone, planned (≤ 1/10)",
            _GOALS,
            0.05,
            "",
            partial(_goal, _duration, 1),
            atol=0.05,
            note=f"torquers alone as case {_case_name}; the torque planned over the maneuver",
        ),
    ]
