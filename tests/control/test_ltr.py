"""LQG/LTR: the recovered loop converges to the LQ loop as q grows (Doyle & Stein 1979), the
margins rise towards the LQ loop's guaranteed ones, q = 0 is the plain LQG, the law exports to
StateSpace, conforms and slews the TAMU hub on the engine, and bad input is refused.

The convergence is measured on a grid from 0.1 to 100 rad/s (the crossover region and the
first appendage mode): max_ω |L_q(jω) − L_LQ(jω)| / |1 + L_LQ(jω)| must shrink monotonically
with q, and the phase margin must approach the LQ loop's within 1° at the largest q."""

import numpy as np
import pytest

from flexsat.analysis.frequency_domain import build_loop
from flexsat.analysis.margins import disk_margin, loop_margins
from flexsat.control.estimation import kalman
from flexsat.control.lqr import lqr
from flexsat.control.ltr import LTRController
from flexsat.control.state_space_export import continuous_law, discrete_law
from flexsat.dynamics.linear_model import plant_state_space
from flexsat.input_checks import FieldError
from flexsat.testing import check_controller
from flexsat.testing.checks import CHECK_RATE
from synthesis_plants import TAMU_RN, tamu_design

QS = (0.0, 10.0, 100.0, 1000.0, 1e4)


@pytest.fixture(scope="module")
def tamu():
    return tamu_design(3)


def design(tamu, q, dt=1 / 75, **kw):
    _, _, A, B, C, Q = tamu
    return LTRController.design(A, B, C, Q, 1.0, TAMU_RN, q, dt, ["theta"], ["torque"], **kw)


def test_loop_converges_to_the_lq_loop(tamu):
    _, plant, *_ = tamu
    P = plant_state_space(plant)
    w = np.logspace(-1, 2, 300)
    errors, pms = [], []
    for q in QS:
        law = design(tamu, q)
        loop = build_loop(P, continuous_law(law), "torque")
        target = law.target_loop()
        Lq = np.array([complex(np.squeeze(loop.transfer(1j * x))) for x in w])
        Llq = np.array([complex(np.squeeze(target(1j * x))) for x in w])
        errors.append(np.max(np.abs(Lq - Llq) / np.abs(1 + Llq)))
        pms.append(loop_margins(loop).phase_margin_deg)
    assert all(b < a for a, b in zip(errors, errors[1:])), errors
    assert errors[-1] < 0.05 * errors[0]
    lq = loop_margins(law.target_loop())
    # Kalman's inequality |1 + L_LQ| >= 1: PM >= 60°, no upper gain margin
    assert lq.phase_margin_deg >= 60.0 and np.isinf(lq.gain_margin)
    assert pms[0] < lq.phase_margin_deg - 10.0  # plain LQG lost margin
    assert abs(pms[-1] - lq.phase_margin_deg) < 1.0
    assert (
        disk_margin(build_loop(P, continuous_law(law), "torque")).alpha
        > disk_margin(build_loop(P, continuous_law(design(tamu, 0.0)), "torque")).alpha
    )


def test_q_zero_is_the_plain_lqg(tamu):
    """q = 0: the filter of the nominal noise B Bᵀ, the compensator (A − BK − LC, L, −K)."""
    _, _, A, B, C, Q = tamu
    law = design(tamu, 0.0)
    K = lqr(A, B, Q, 1.0).gain
    L = kalman(A, B, C, 1.0, TAMU_RN).gain
    np.testing.assert_array_equal(law.regulator.gain, K)
    np.testing.assert_array_equal(law.filter.gain, L)
    np.testing.assert_array_equal(law.system.A, A - B @ K - L @ C)
    # the recovery noise enters the filter as q² B Bᵀ on top of the nominal intensity
    q = 30.0
    Lq = kalman(A, None, C, (1 + q**2) * B @ B.T, TAMU_RN).gain
    # (the sum W0 + q² B Bᵀ is rounded differently from (1 + q²) B Bᵀ: the Riccati solve's
    # condition times ε, far below 1e-9)
    np.testing.assert_allclose(design(tamu, q).filter.gain, Lq, rtol=1e-9)


def test_recovery_moves_filter_poles_onto_the_plant_zeros(tamu):
    """Doyle & Stein 1979: as q → ∞ the filter poles tend to the transmission zeros of
    C(sI − A)⁻¹B (here the lightly damped clamped-appendage zeros) and to infinity; the
    slowest filter pole's damping falls towards the zero's."""
    import control as ct

    _, _, A, B, C, _ = tamu
    zeros = ct.ss(A, B, C, 0).zeros()
    z0 = zeros[np.argmin(np.abs(zeros))]
    slow = []
    for q in (100.0, 1e4):
        p = design(tamu, q).filter.poles
        slow.append(p[np.argmin(np.abs(p - z0))])
    assert abs(slow[1] - z0) < abs(slow[0] - z0) < 0.1 * abs(z0)


def test_exports_conforms_and_slews_on_the_engine(tamu):
    """q = 10: at larger q the estimate's error rings at the lightly damped zero (above), so a
    step settles slowly (the price of recovery)."""
    from flexsat.sim import simulate

    case, plant, *_ = tamu
    check_controller(design(tamu, 10.0, dt=1 / CHECK_RATE), plant)
    cfg = case.sim_config(duration=15.0, friction=False, noise=False)
    law = design(tamu, 10.0, dt=cfg.dt, references={"theta": 0.3})
    assert discrete_law(law, cfg.dt).dt == pytest.approx(cfg.dt)
    ds = simulate(plant, law, cfg, initial_state=plant.state_from(theta=0.0)).dataset
    assert np.abs(ds.theta.values[0, -150:] - 0.3).max() < np.radians(0.05)


def test_bad_input_names_the_field(tamu):
    _, _, A, B, C, Q = tamu
    with pytest.raises(FieldError, match="^q: must be >= 0"):
        design(tamu, -1.0)
    with pytest.raises(FieldError, match="^C: recovery at the plant input needs"):
        LTRController.design(
            A, np.hstack([B, B]), C, Q, np.eye(2), TAMU_RN, 1.0, 0.1, ["theta"], ["a", "b"]
        )
    with pytest.raises(FieldError, match="^Qn0: must have shape"):
        design(tamu, 1.0, Qn0=np.eye(2))


def test_mimo_recovery_on_the_collocated_draper_hub_and_tips():
    """Three torques (hub, tip pairs) and their three collocated angles: a square collocated
    plant, minimum phase with structural damping, so the 3×3 loop at the plant input recovers
    the LQ loop: σ̄(L_q − L_LQ)/σ̲(I + L_LQ) over the grid falls with q, and the multiloop disk
    margin rises towards the LQ loop's."""
    from flexsat.analysis.margins import disk_margins
    from synthesis_plants import draper_design

    _, _, P, Q = draper_design(6, 0.002)
    A, B = np.asarray(P.A), np.asarray(P.B)
    outs = list(P.output_labels)
    names = ["theta", "rot_tips_1_3", "rot_tips_2_4"]
    C = np.asarray(P.C)[[outs.index(n) for n in names]]
    w = np.logspace(-1, 2, 200)
    errors, alphas = [], []
    for q in (0.0, 10.0, 100.0, 1000.0):
        law = LTRController.design(
            A, B, C, Q, np.eye(3), 1e-4 * np.eye(3), q, 0.01, names, list(P.input_labels)
        )
        loop = build_loop(P, continuous_law(law), "input")
        target = law.target_loop()
        err = 0.0
        for x in w:
            Lq, Llq = loop.transfer(1j * x), target(1j * x)
            smin = np.linalg.svd(np.eye(3) + Llq, compute_uv=False)[-1]
            err = max(err, np.linalg.norm(Lq - Llq, 2) / smin)
        errors.append(err)
        alphas.append(disk_margins(loop)[1].alpha)
    assert all(b < a for a, b in zip(errors, errors[1:])), errors
    assert errors[-1] < 0.05 * errors[0]
    assert alphas[-1] > alphas[0]
