"""Spillover of truncated modes (issue 24): a law designed on a reduced model closed on the full
plant — the spillover gain of a residual mode against the loop gain through that mode computed
from the two models' frequency responses, and a destabilising spillover whose verdict is checked
against the roots of the closed-loop characteristic polynomial (Routh–Hurwitz by np.roots)."""

import numpy as np
import pytest
import scipy.linalg as sla

import control as ct
from flexsat.analysis.frequency_domain import frequency_response
from flexsat.analysis.reduction import modal_truncation
from flexsat.analysis.spillover import spillover, spillover_table
from flexsat.control.estimation import kalman
from flexsat.control.lqr import lqr


def rigid_and_modes(phis, omegas, zeta=0.005):
    """A rigid hub and modes; input enters each mode with 1, the sensor reads y = θ + Σ φ_i q_i
    and its rate."""
    blocks = [np.array([[0, 1], [0, 0.0]])]
    blocks += [np.array([[0, 1], [-(w**2), -2 * zeta * w]]) for w in omegas]
    A = sla.block_diag(*blocks)
    n = A.shape[0]
    B = np.zeros((n, 1))
    B[1::2] = 1.0
    C = np.zeros((2, n))
    C[0, 0], C[1, 1] = 1.0, 1.0
    for i, phi in enumerate(phis):
        C[0, 2 + 2 * i], C[1, 3 + 2 * i] = phi, phi
    return ct.ss(A, B, C, 0, inputs=["u"], outputs=["y", "y_dot"])


def test_spillover_gain_is_the_loop_gain_through_the_mode():
    """With one residual mode, G_full − G_reduced is that mode exactly, so the spillover gain
    equals |K (G_full − G_red)(jω_i)| (to the round-off of the two responses, 1e-9)."""
    full = rigid_and_modes([0.8, -0.6], [2.0, 9.0])
    red = modal_truncation(full, 1, "h2").system
    K = ct.ss([], [], [], [[-1.0, -1.5]], inputs=["y", "y_dot"], outputs=["u"])
    rep = spillover(full, red, K)
    assert len(rep.residual) == 1
    r = rep.residual[0]
    w = np.array([r.frequency_rad_s])
    diff = (
        frequency_response(full, omega_rad_s=w).values
        - frequency_response(red, omega_rad_s=w).values
    )
    assert r.spillover_gain == pytest.approx(abs((K.D @ diff[0])[0, 0]), rel=1e-9)
    assert r.open_loop_damping == pytest.approx(0.005, rel=1e-9)
    assert "residual mode" in spillover_table(rep)


def test_destabilising_spillover_agrees_with_characteristic_roots():
    """A PD designed on the rigid body alone, with a sensor seeing the mode with the opposite
    sign (non-collocated): stable on the design model, unstable on the full plant, as the roots
    of the closed-loop characteristic polynomial say."""
    full = rigid_and_modes([-1.5], [3.0], zeta=0.002)
    red = modal_truncation(full, 0).system
    K = ct.ss([], [], [], [[-1.0, -2.0]], inputs=["y", "y_dot"], outputs=["u"])
    rep = spillover(full, red, K)
    # 1 + L with L = −K P = 1.0 y/u + 2.0 ẏ/u; its numerator is the characteristic polynomial
    char = ct.tf(1, 1) + 1.0 * ct.tf(full[0, 0]) + 2.0 * ct.tf(full[1, 0])
    num = np.atleast_1d(np.squeeze(ct.minreal(char, verbose=False).num[0][0]))
    roots = np.roots(num)
    assert rep.stable_reduced
    assert rep.stable_full == bool(np.all(roots.real < 0))
    assert not rep.stable_full
    assert rep.disk_margin_full == 0.0 and rep.least_damping_full < 0


def test_tamu_lqg_on_two_modes_reports_every_residual_mode():
    """An LQG designed on a 2-mode model of TAMU: every one of the 8 other modes is reported,
    and the full loop's margin is below the design model's (spillover costs margin)."""
    from flexsat.cases.tamu import tamu
    from flexsat.dynamics.linear_model import plant_state_space

    P = plant_state_space(tamu().model(), outputs=["theta", "root_moment"])
    red = modal_truncation(P, 2, "h2").system
    A, B, C = red.A, red.B, red.C
    n = A.shape[0]
    K = lqr(A, B, np.diag([100.0] + [1.0] * (n - 1)), np.eye(1)).gain
    L = kalman(A, B, C, np.eye(1) * 10, np.diag([1e-6, 1e-4])).gain
    law = ct.ss(A - B @ K - L @ C, L, -K, 0, inputs=list(P.output_labels), outputs=["torque"])
    rep = spillover(P, red, law)
    assert len(rep.residual) == 8
    assert rep.stable_reduced and rep.stable_full
    assert rep.disk_margin_full < rep.disk_margin_reduced
    freqs = sorted(r.frequency_rad_s for r in rep.residual)
    assert freqs[0] > 100  # the two kept modes are the lowest (21 and 68 rad/s)


def test_sampled_law_converges_to_the_continuous_report():
    """The law discretised (ZOH) at a rate far above the loop's bandwidth: the sampled-data
    report tends to the continuous one (disk margin and spillover gains within the hold's
    phase lag ω dt/2 ~ 1e-3 relative at 1 kHz, allowed 2 %)."""
    full = rigid_and_modes([0.8, -0.6, 0.3], [2.0, 9.0, 30.0])
    red = modal_truncation(full, 1, "h2").system
    A, B, C = red.A, red.B, red.C
    n = A.shape[0]
    K = lqr(A, B, np.eye(n), np.eye(1)).gain
    L = kalman(A, B, C, np.eye(1), np.eye(2) * 1e-2).gain
    law = ct.ss(A - B @ K - L @ C, L, -K, 0, inputs=["y", "y_dot"], outputs=["u"])
    cont = spillover(full, red, law)
    samp = spillover(full, red, ct.c2d(law, 1e-3, "zoh"))
    assert samp.stable_full == cont.stable_full
    assert samp.disk_margin_full == pytest.approx(cont.disk_margin_full, rel=2e-2)
    got = [r.spillover_gain for r in samp.residual]
    want = [r.spillover_gain for r in cont.residual]
    np.testing.assert_allclose(got, want, rtol=2e-2)
