"""Loops, sampled plants and responses of flexsat.analysis.frequency_domain against hand forms."""

from __future__ import annotations

import math

import numpy as np
import pytest

import control as ct
from flexsat.analysis.frequency_domain import (
    ResponseEvaluator,
    build_loop,
    close_other_channels,
    default_grid,
    delay_outputs,
    frequency_grid,
    frequency_response,
    sampled_plant,
)
from flexsat.input_checks import FieldError

EPS = np.finfo(float).eps
J = 2.0  # hub inertia, kg m²
KP, KD = 3.0, 4.0  # PD gains, N m / rad and N m s / rad


def _hub() -> ct.StateSpace:
    """θ'' = u / J, measured (θ, θ')."""
    return ct.ss(
        [[0.0, 1.0], [0.0, 0.0]],
        [[0.0], [1 / J]],
        np.eye(2),
        0.0,
        states=["theta", "theta_dot"],
        inputs=["torque"],
        outputs=["theta", "theta_dot"],
    )


def _pd(dt: float = 0.0) -> ct.StateSpace:
    """u = K y with the feedback sign inside: K = [−kp, −kd]."""
    args = (dt,) if dt else ()
    return ct.ss([], [], [], [[-KP, -KD]], *args, inputs=["theta", "theta_dot"], outputs=["torque"])


def test_the_loop_at_the_input_is_minus_k_p():
    """L_i = −K P = (kp + kd s) / (J s²); its closed loop 1 + L = 0 is J s² + kd s + kp = 0.
    Tolerance: a 2-state response evaluated through its eigen-decomposition, ~cond(V) ε."""
    loop = build_loop(_hub(), _pd(), "input")
    w = np.geomspace(0.01, 100.0, 60)
    s = 1j * w
    L = frequency_response(loop.transfer, omega_rad_s=w).values[:, 0, 0]
    assert np.allclose(L, (KP + KD * s) / (J * s**2), rtol=1e-10, atol=0)
    assert np.allclose(
        np.sort_complex(loop.poles), np.sort_complex(np.roots([J, KD, KP])), rtol=1e-12
    )
    assert loop.states == ("theta", "theta_dot") and loop.dt == 0.0


def test_a_discrete_law_samples_the_plant_and_the_response_lives_on_the_unit_circle():
    """ZOH of θ'' = u/J at h: Φ = [[1, h], [0, 1]], Γ = [h²/2, h]/J (Franklin, Powell &
    Workman 1998, §4.3.3), exact; the loop's response is G(e^{jωh}) up to π/h only."""
    h = 0.1
    P = sampled_plant(_hub(), h)
    assert np.allclose(P.A, [[1.0, h], [0.0, 1.0]], rtol=0, atol=4 * EPS)
    assert np.allclose(P.B.ravel(), [h**2 / 2 / J, h / J], rtol=4 * EPS, atol=0)
    assert P.dt == h and P.state_labels == ["theta", "theta_dot"]
    loop = build_loop(_hub(), _pd(h), "torque")
    w = np.linspace(0.1, math.pi / h, 20)
    z = np.exp(1j * w * h)
    # −K P(z) with P(z) = C (zI − Φ)⁻¹ Γ, by hand
    hand = [-_pd(h).D @ np.linalg.solve(zk * np.eye(2) - P.A, P.B) for zk in z]
    got = frequency_response(loop.transfer, omega_rad_s=w).values
    assert np.allclose(got, np.array(hand), rtol=1e-10, atol=0)
    with pytest.raises(FieldError, match="Nyquist frequency"):
        frequency_response(loop.transfer, omega_rad_s=[1.01 * math.pi / h])


def test_a_delay_of_d_samples_multiplies_the_response_by_z_to_the_minus_d():
    """u_k = v_{k−d}: the delayed law's response is K e^{−jωd h}, with d states per command."""
    h, d = 0.05, 3
    K = ct.ss([], [], [], [[2.5]], h, inputs=["y"], outputs=["u"])
    delayed = delay_outputs(K, d)
    assert delayed.nstates == d
    w = np.linspace(0.0, math.pi / h, 15)
    got = frequency_response(delayed, omega_rad_s=w).values[:, 0, 0]
    assert np.allclose(got, 2.5 * np.exp(-1j * w * d * h), rtol=0, atol=1e-13)
    with pytest.raises(FieldError, match="delay.*discrete"):
        delay_outputs(ct.ss([], [], [], [[1.0]]), 1)
    with pytest.raises(FieldError, match="delay.*whole number"):
        delay_outputs(K, 1.5)


def test_one_channel_broken_with_the_others_closed_is_the_lft():
    """L_ii with the others closed by −I: L_ii − L_io (I + L_oo)⁻¹ L_oi (Skogestad &
    Postlethwaite 2005, §4.9), compared pointwise on a random stable 3 × 3 loop."""
    rng = np.random.default_rng(2)
    n, m = 5, 3
    A = rng.normal(size=(n, n)) - 4 * np.eye(n)
    B, C, D = rng.normal(size=(n, m)), rng.normal(size=(m, n)), 0.3 * rng.normal(size=(m, m))
    i, o = 1, [0, 2]
    A1, B1, C1, D1 = close_other_channels((A, B, C, D), i)
    for w in (0.1, 1.0, 7.0):
        G = C @ np.linalg.solve(1j * w * np.eye(n) - A, B) + D
        lft = G[i, i] - G[i, o] @ np.linalg.solve(np.eye(2) + G[np.ix_(o, o)], G[o, i])
        got = (C1 @ np.linalg.solve(1j * w * np.eye(n) - A1, B1) + D1)[0, 0]
        assert got == pytest.approx(lft, rel=1e-10)


def test_a_defective_state_matrix_is_evaluated_by_schur_and_agrees_with_a_direct_solve():
    """A double integrator's Jordan block (κ(V) = ∞) goes through the Schur route; the result
    equals C (jωI − A)⁻¹ B + D solved directly (backward stable: ~ε relative)."""
    A = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, 0.0]])
    B, C, D = np.array([[0.0], [0.0], [1.0]]), np.array([[1.0, 0.5, 0.2]]), np.zeros((1, 1))
    evaluate = ResponseEvaluator(A, B, C, D, 0.0)
    assert not evaluate.modal
    w = np.geomspace(0.1, 10.0, 7)
    direct = [C @ np.linalg.solve(1j * wk * np.eye(3) - A, B) for wk in w]
    assert np.allclose(evaluate(w), np.array(direct), rtol=1e-13, atol=0)


def test_grids_are_in_rad_s_and_cover_the_dynamics():
    """frequency_grid converts its ends with their 2π; default_grid spans the poles two
    decades either side, or ends at π/dt for a sampled system."""
    w = frequency_grid("0.1 Hz", "10 Hz", 5)
    assert w[0] == pytest.approx(0.2 * math.pi, rel=4 * EPS)
    assert w[-1] == pytest.approx(20 * math.pi, rel=4 * EPS)
    sys = ct.ss(np.diag([-0.5, -40.0]), np.ones((2, 1)), np.ones((1, 2)), 0.0)
    g = default_grid(sys)
    assert g[0] == pytest.approx(0.005, rel=1e-12) and g[-1] == pytest.approx(4000.0, rel=1e-12)
    assert default_grid(ct.c2d(sys, 0.01))[-1] == pytest.approx(math.pi / 0.01, rel=1e-12)
    with pytest.raises(FieldError, match="high: need 0 < low < high"):
        frequency_grid("10 Hz", "1 Hz")


def test_mismatched_loops_are_refused_by_name():
    with pytest.raises(FieldError, match="break_at: must be 'input', 'output'"):
        build_loop(_hub(), _pd(), "thrust")
    with pytest.raises(FieldError, match="law: is continuous but the plant is discrete"):
        build_loop(sampled_plant(_hub(), 0.1), _pd())
    with pytest.raises(FieldError, match="plant: samples every 0.1 s, the law every 0.2 s"):
        build_loop(sampled_plant(_hub(), 0.1), _pd(0.2))


def _flexible_three_axis_loop() -> tuple[np.ndarray, ...]:
    """(A, B, C, D, dt) of a sampled loop broken at the input: three rigid axes (double
    integrators, exact Jordan blocks at z = 1 after the hold) and ten 0.5 %-damped modes under
    a random discrete dynamic law."""
    rng = np.random.default_rng(3)
    nm, m = 10, 3
    wm = np.sort(rng.uniform(0.5, 20.0, nm))
    n = 6 + 2 * nm
    A = np.zeros((n, n))
    A[0:3, 3:6] = np.eye(3)
    for k in range(nm):
        i = 6 + 2 * k
        A[i, i + 1], A[i + 1, i], A[i + 1, i + 1] = 1.0, -(wm[k] ** 2), -0.01 * wm[k]
    B = np.zeros((n, m))
    B[3:6] = np.eye(3) + 0.1 * rng.normal(size=(3, 3))
    B[7::2] = rng.normal(size=(nm, m))
    C = np.zeros((2 * m, n))
    C[:3, :3], C[3:, 3:6] = np.eye(3), np.eye(3)
    C[:3, 6::2] = 0.1 * rng.normal(size=(3, nm))
    names_u, names_y = [f"u{i}" for i in range(m)], [f"y{i}" for i in range(2 * m)]
    P = ct.ss(A, B, C, 0.0, inputs=names_u, outputs=names_y)
    K = ct.ss(
        np.diag(rng.uniform(-0.5, 0.5, 4)),
        rng.normal(size=(4, 2 * m)),
        rng.normal(size=(m, 4)),
        -np.hstack([np.eye(3), 2.0 * np.eye(3)]),
        0.1,
        inputs=names_y,
        outputs=names_u,
    )
    L = build_loop(P, K, "input").transfer
    return tuple(np.asarray(M, float) for M in (L.A, L.B, L.C, L.D)) + (0.1,)


def test_the_block_modal_response_equals_a_dense_solve_to_its_conditioning():
    """The rigid axes' Jordan blocks make the eigenvectors singular (κ(V) ~ 1e15): the
    evaluator keeps the 20 modal eigenvectors and one 6 × 6 block on the cluster at z = 1.
    Against D + C (xI − A)⁻¹ B solved densely at every frequency, both are exact for a
    perturbed A + E: the similarity W (κ(W)) gives ‖E‖ <= c n ε κ(W) ‖xI − A‖, the dense LU
    c n ε ‖xI − A‖, so to first order |ΔG| <= 10 n ε (1 + κ(W)) ‖xI − A‖ ‖C R‖ ‖R B‖ with
    R = (xI − A)⁻¹ (the resolvent's first-order change, R E R)."""
    A, B, C, D, dt = _flexible_three_axis_loop()
    evaluate = ResponseEvaluator(A, B, C, D, dt)
    assert evaluate.method == "block"
    assert [T.shape for T, _, _ in evaluate.blocks] == [(6, 6)]
    assert evaluate.condition < 1e6
    n = A.shape[0]
    w = np.geomspace(1e-3, math.pi / dt, 40)
    G = evaluate(w)
    for k, wk in enumerate(w):
        x = np.exp(1j * wk * dt)
        R = np.linalg.inv(x * np.eye(n) - A)
        direct = D + C @ R @ B
        bound = (
            10
            * n
            * EPS
            * (1 + evaluate.condition)
            * np.linalg.norm(x * np.eye(n) - A, 2)
            * np.linalg.norm(C @ R, 2)
            * np.linalg.norm(R @ B, 2)
        )
        assert np.abs(G[k] - direct).max() <= bound, wk
        if wk > 0.1:
            # above the rigid double pole (whose R grows as 1/ω², the bound as 1/ω⁴) the bound
            # is far below |G|: an error of the block's size could not pass
            assert bound < 1e-6 * np.abs(direct).max(), wk
