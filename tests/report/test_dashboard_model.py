"""What the design dashboard computes for a design point (flexsat.report.dashboard_model): the
maneuver through the one engine and the margins of the sampled loop, checked against a direct
run, an exact rigid-body sampled loop and a direct z-domain evaluation of the loop."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.optimize

from flexsat.cases.tamu import tamu
from flexsat.input_checks import FieldError
from flexsat.report.dashboard_model import (
    LAWS,
    USES,
    DesignPoint,
    TamuDesign,
    design_point,
    sweep_values,
)
from flexsat.sim import simulate
from flexsat.units import Q_


@pytest.fixture(scope="module")
def design():
    return TamuDesign()


def test_the_maneuver_is_the_engine_run_of_the_law(design):
    """The evaluation's histories and metrics are those of simulate() on the case's law."""
    point = design_point(g1="4000 ozf*in/rad", g2="900 ozf*in*s/rad", g3=0.5, alpha=0.15)
    e = design.evaluate(point)
    case = tamu()
    law = case.law_ii(point.g1, point.g2, point.g3, alpha=point.alpha)
    direct = simulate(case.model(), law, case.sim_config(duration=15.0))
    assert e.error == "" and e.margin_note == ""
    assert e.settling_time_s == pytest.approx(float(direct.metrics["settling_time_s"][0]))
    assert e.overshoot_deg == pytest.approx(float(direct.metrics["overshoot_deg"][0]))
    np.testing.assert_allclose(e.angle_rad, direct.dataset["theta"].values[0], rtol=1e-12)
    np.testing.assert_allclose(e.tip_deflection_m, direct.dataset["tip_deflection"].values[0])
    assert e.time_s.shape == e.torque_Nm.shape == e.command_Nm.shape == e.reference_rad.shape


def test_gains_convert_from_the_papers_units():
    point = design_point(g1="3000 ozf*in/rad", g2=Q_(800, "ozf*in*s/rad"), g3=1.0, alpha=0.2)
    assert point.g1 == pytest.approx(Q_(3000, "ozf*in/rad").to("N*m/rad").magnitude, rel=1e-15)
    assert point.g2 == pytest.approx(Q_(800, "ozf*in*s/rad").to("N*m*s/rad").magnitude, rel=1e-15)
    with pytest.raises(FieldError, match="g1"):
        design_point(g1="3000 ozf/rad")  # a force per angle is no torque gain


def _rigid_sampled_phase_margin(I: float, g1: float, g2: float, dt: float) -> tuple[float, float]:
    """Phase margin (deg) and crossover (rad/s) of PD on a rigid hub I θ'' = u sampled with a
    zero-order hold: the exact discrete transfers θ(z) = T²(z+1)/(2I(z−1)²) u(z) and
    θ'(z) = T/(I(z−1)) u(z) (Franklin, Powell & Workman 1998, §4.3.3), L = g1 Pθ + g2 Pθ'."""

    def loop(w: float) -> complex:
        z = np.exp(1j * w * dt)
        return g1 * dt**2 * (z + 1) / (2 * I * (z - 1) ** 2) + g2 * dt / (I * (z - 1))

    wc = scipy.optimize.brentq(lambda w: abs(loop(w)) - 1.0, 1e-3, math.pi / dt * 0.999)
    return math.degrees(np.angle(-loop(wc))), wc


@pytest.mark.parametrize("g1", ["3000 ozf*in/rad", "5000 ozf*in/rad"])
def test_margins_of_a_stiff_hub_are_the_exact_rigid_sampled_loop(g1):
    """With beams 10⁴ × stiffer the first flexible mode is near 350 Hz: the loop is the rigid
    hub's to within (ω_c/ω_1)² ≈ 1e-7 in relative gain, whose sampled PD phase margin is known
    exactly; tolerance 1e-3 deg covers that residual and the crossover search (brentq, 1e-12)."""
    case = tamu(modulus="161.6e10 ozf/in**2")
    stiff = TamuDesign(case)
    e = stiff.evaluate(design_point(g1=g1, hardware=False))
    pm, wc = _rigid_sampled_phase_margin(
        case.params.total_inertia, e.point.g1, e.point.g2, stiff.dt
    )
    assert e.margins is not None and e.disk is not None
    assert e.margins.phase_margin_deg == pytest.approx(pm, abs=1e-3)
    assert e.margins.gain_crossover_rad_s == pytest.approx(wc, rel=1e-5)
    # the disk margin never promises more than the phase margin it implies (Seiler et al. 2020)
    assert e.disk.phase_deg <= e.margins.phase_margin_deg + 1e-9


def test_the_loop_gain_is_the_sampled_loop_evaluated_on_the_unit_circle(design):
    """L(e^{jωT}) against a direct evaluation: the plant's ZOH equivalent by scipy and
    L = g·P(z) summed over the three measurements the law reads (its gains, signs included);
    tolerance: the condition of (zI − A) near the lightly damped modes times eps."""
    import scipy.signal

    point = design_point(g1="3000 ozf*in/rad", g2="800 ozf*in*s/rad", g3=0.7)
    e = design.evaluate(point)
    P = design.plant
    outputs = list(P.output_labels)
    rows = [outputs.index(name) for name in ("theta", "theta_dot", "root_torque")]
    column = list(P.input_labels).index("torque")
    Ad, Bd, Cd, Dd, _ = scipy.signal.cont2discrete((P.A, P.B, P.C, P.D), design.dt, "zoh")
    gains = np.array([point.g1, point.g2, point.g3])
    n = Ad.shape[0]
    for k in range(0, e.loop_omega_rad_s.size, 37):
        z = np.exp(1j * e.loop_omega_rad_s[k] * design.dt)
        Pz = Cd[rows] @ np.linalg.solve(z * np.eye(n) - Ad, Bd[:, [column]]) + Dd[rows][:, [column]]
        expected = complex(gains @ Pz[:, 0])  # L = −K P with K = −g
        assert e.loop_response[k] == pytest.approx(expected, rel=1e-7)


def test_a_gain_change_moves_the_settling_time_and_the_margins(design):
    """Raising g1 at fixed g2 raises the crossover and lowers the phase margin (a PD's phase
    lead atan(g2 ω_c/g1) falls as ω_c rises more slowly than g1)."""
    soft = design.evaluate(design_point(g1="3000 ozf*in/rad"))
    stiff = design.evaluate(design_point(g1="5000 ozf*in/rad"))
    assert soft.margins is not None and stiff.margins is not None
    assert stiff.margins.gain_crossover_rad_s > soft.margins.gain_crossover_rad_s
    assert stiff.margins.phase_margin_deg < soft.margins.phase_margin_deg
    assert stiff.settling_time_s != soft.settling_time_s


def test_pd_tracking_is_law_ii_without_its_root_load_gain(design):
    """Law II with g3 = 0 is u_ref − g1 (θ − θ_ref) − g2 (θ' − θ'_ref): the PD law tracking the
    same reference with its torque fed forward, to round-off."""
    law_ii = design.evaluate(design_point("law_ii", g3=0.0))
    pd = design.evaluate(design_point("pd"))
    np.testing.assert_allclose(pd.angle_rad, law_ii.angle_rad, rtol=0, atol=1e-12)
    assert pd.margins == law_ii.margins


@pytest.mark.parametrize("law", sorted(LAWS))
def test_every_law_runs_and_says_which_gains_it_uses(design, law):
    e = design.evaluate(design_point(law))
    assert e.error == "" and e.time_s.size == design.configs[True].n_steps + 1
    assert set(USES[law]) <= {"g1", "g2", "g3", "alpha"}


@pytest.mark.parametrize(
    "changes, field",
    [({"g1": -1.0}, "g1"), ({"g2": -0.5}, "g2"), ({"g3": -5.0}, "g3"), ({"alpha": 0.9}, "alpha")],
)
def test_a_refused_gain_is_a_message_naming_it_not_an_exception(design, changes, field):
    e = design.evaluate(design_point(**changes))
    assert e.error.startswith(f"{field}:")
    assert e.margins is None and e.time_s.size == 0 and e.settling_time_s is None


def test_an_unstable_sampled_loop_is_said_with_its_pole(design):
    """g1 far past the sampled loop's limit: the saturated maneuver still runs, the linear loop
    is unstable and its margins are not defined."""
    e = design.evaluate(design_point(g1="1e7 ozf*in/rad"))
    assert e.margins is None and e.disk is None
    assert "unstable" in e.margin_note and "pole" in e.margin_note


@pytest.mark.parametrize(
    "kwargs, field",
    [
        ({"law": "lqr"}, "law"),
        ({"g1": math.nan}, "g1"),
        ({"g2": "800"}, "g2"),
        ({"hardware": "yes"}, "hardware"),
    ],
)
def test_a_design_point_refuses_bad_fields(kwargs, field):
    values = {"law": "law_ii", "g1": 1.0, "g2": 1.0, "g3": 0.0, "alpha": 0.2, **kwargs}
    with pytest.raises(FieldError, match=f"^{field}:"):
        DesignPoint(**values)


def test_a_sweep_point_is_its_case_run_alone(design):
    """Each batch of the sweep is one batched simulate (metrics only): every case equals the
    same law run alone on that path bit for bit (the engine's guarantee), and its margins are
    those of the point's own evaluation."""
    point = design_point(g1="3000 ozf*in/rad")
    values = sweep_values(point, "g1", 6)
    swept = [p for chunk in design.sweep(point, "g1", values, chunk=4) for p in chunk]
    assert [p.value for p in swept] == pytest.approx(values, rel=1e-15)
    case = tamu()
    for p in swept[:: len(swept) - 1]:  # the first and the last (two batches)
        one = design_point(g1=p.value)
        alone = simulate(
            case.model(), design.law(one), design.configs[True], metrics_only=True
        ).metrics["settling_time_s"][0]
        assert p.settling_time_s == alone
        e = design.evaluate(one)
        assert p.phase_margin_deg == e.margins.phase_margin_deg
        assert p.disk_alpha == e.disk.alpha


def test_a_sweep_says_which_points_are_refused_and_runs_the_others(design):
    point = design_point()
    swept = [p for chunk in design.sweep(point, "g1", np.array([-1.0, 20.0])) for p in chunk]
    assert swept[0].note.startswith("g1:") and swept[0].settling_time_s is None
    assert swept[1].note == "" and swept[1].phase_margin_deg is not None


def test_sweep_values_cover_the_range_of_each_gain():
    point = design_point(g1=10.0, g2=4.0)
    np.testing.assert_allclose(sweep_values(point, "g1", 3), [5.0, 10.0, 20.0], rtol=1e-15)
    np.testing.assert_allclose(sweep_values(point, "g2", 3), [2.0, 4.0, 8.0], rtol=1e-15)
    assert sweep_values(point, "g3", 5).tolist() == [-2.0, -1.0, 0.0, 1.0, 2.0]
    assert sweep_values(point, "alpha", 2).tolist() == [0.02, 0.25]
    with pytest.raises(FieldError, match="^g1:"):
        sweep_values(design_point(g1=0.0), "g1")
    with pytest.raises(FieldError, match="^gain:"):
        sweep_values(point, "kp")
