"""Rigid body (issue 10 acceptance): a torque-free asymmetric body at large rates conserves its
inertial angular momentum and kinetic energy, follows the Euler–Poinsot solution and keeps a
unit quaternion; the propagator is of fourth order; a constant principal-axis torque gives the
closed-form single-axis rotation; bad input named."""

import re

import numpy as np
import pytest

from flexsat.dynamics import attitude as att
from flexsat.dynamics import rigid_body as rb
from rkmk4_reference import propagate

EPS = np.finfo(float).eps
MOMENTS = np.array([100.0, 200.0, 300.0])  # kg·m², asymmetric
# principal axes turned away from the body axes, so the body inertia is full (products of inertia)
R = att.euler123_to_dcm([0.4, -0.7, 1.1]).T  # columns: principal axes in body components
INERTIA = R @ np.diag(MOMENTS) @ R.T
# large rates (~1 rad/s, a revolution every few seconds), one case on each side of the
# separatrix: H² > 2T·I2 (rotation about the axis of greatest inertia) and H² < 2T·I2 (least)
W_PRINCIPAL = np.array([[1.0, 0.3, -0.8], [0.9, -0.5, 0.2]])
# RKMK4 global error ≈ C h⁴ with C ≈ 0.3 rad/s⁵ for these rates over 100 s (measured: 3.0e-9
# at h = 10 ms, 1.9e-10 at 5 ms, ratio 16): h = 5 ms puts ω 50× inside the 1e-8 bound
STEP = 0.005
T_END = 100.0


@pytest.fixture(scope="module")
def tumble():
    t = np.linspace(0.0, T_END, round(T_END / STEP) + 1)
    beta0 = att.principal_rotation_to_quaternion([0.0, 0.6, 0.8], 0.5)
    beta, w = propagate(beta0, W_PRINCIPAL @ R.T, INERTIA, t)
    return t, beta, w


@pytest.mark.numerics
def test_torque_free_body_conserves_momentum_and_energy(tumble):
    t, beta, w = tumble
    assert beta.shape == (2, t.size, 4) and w.shape == (2, t.size, 3)
    h = rb.angular_momentum_inertial(beta, w, INERTIA)
    drift = np.linalg.norm(h - h[:, :1], axis=-1) / np.linalg.norm(h[:, :1], axis=-1)
    assert drift.max() <= 1e-10  # issue 10 acceptance; measured ~1.4e-11
    T = rb.kinetic_energy(w, INERTIA)
    assert np.abs(T / T[:, :1] - 1).max() <= 1e-10  # measured ~1.3e-12


@pytest.mark.numerics
def test_quaternion_stays_unit_without_renormalisation(tumble):
    _, beta, _ = tumble
    # 20,000 steps of one exact exponential and one product each: round-off only (~√N eps)
    assert np.abs(np.linalg.norm(beta, axis=-1) - 1).max() <= 1e-12


@pytest.mark.numerics
def test_rates_equal_the_euler_poinsot_solution(tumble):
    t, _, w = tumble
    analytic = rb.euler_poinsot_rates(MOMENTS, W_PRINCIPAL, t)
    H2 = np.sum((MOMENTS * W_PRINCIPAL) ** 2, -1)
    T2 = np.sum(MOMENTS * W_PRINCIPAL**2, -1)
    assert H2[0] > T2[0] * MOMENTS[1] and H2[1] < T2[1] * MOMENTS[1]  # both branches
    assert np.abs(w @ R - analytic).max() <= 1e-8  # issue 10 acceptance; measured ~2e-10


@pytest.mark.parametrize("order", [[0, 1, 2], [2, 1, 0], [1, 2, 0]])  # sorted, odd, even
def test_euler_poinsot_solution_solves_eulers_equations(order):
    # independent of the propagator: the elliptic solution starts at ω0 and its derivative
    # (central differences, h = 1e-3 s: error h²/6 |ω'''| ~ 1e-6) satisfies Euler's equations
    # whatever the order of the moments along the (right-handed) axes: an odd relabelling
    # flips the pseudovector ω inside the solver
    t = np.linspace(0.0, 20.0, 20001)
    moments, w0 = MOMENTS[order], W_PRINCIPAL[:, order]
    w = rb.euler_poinsot_rates(moments, w0, t)
    assert np.abs(w[:, 0] - w0).max() <= 4 * EPS
    dw = (w[:, 2:] - w[:, :-2]) / (t[2] - t[0])
    assert np.abs(dw - rb.euler_rates(w[:, 1:-1], np.diag(moments))).max() <= 1e-5


@pytest.mark.numerics
def test_attitude_equals_an_independent_high_accuracy_integration():
    # h_N and T fix only two of the three attitude freedoms (the angle about h_N is free), so
    # the whole quaternion is checked against scipy's DOP853 at rtol 1e-13 on the plain (β, ω)
    # ODE (its own error: ~1e-12, judged by its ‖β‖ drift of 3e-13). RKMK4 at h = 10 ms over
    # 20 s: measured 2.9e-10 (1.8e-11 at 5 ms, the fourth-order ratio 16); bound 2e-9
    from scipy.integrate import solve_ivp

    beta0 = att.principal_rotation_to_quaternion([0.0, 0.6, 0.8], 0.5)
    w0 = W_PRINCIPAL[0] @ R.T
    inverse = np.linalg.inv(INERTIA)

    def rhs(_, x):
        b, w = x[:4], x[4:]
        return np.concatenate([att.omega_matrix(w) @ b, inverse @ -np.cross(w, INERTIA @ w)])

    t = np.linspace(0.0, 20.0, 2001)
    ref = solve_ivp(
        rhs,
        (0.0, 20.0),
        np.concatenate([beta0, w0]),
        method="DOP853",
        rtol=1e-13,
        atol=1e-14,
        t_eval=t,
    ).y.T
    beta, w = propagate(beta0, w0, INERTIA, t)
    assert np.abs(beta - ref[:, :4]).max() <= 2e-9
    assert np.abs(w - ref[:, 4:]).max() <= 2e-9


@pytest.mark.numerics
def test_propagator_is_of_fourth_order():
    beta0 = np.array([1.0, 0.0, 0.0, 0.0])
    w0 = W_PRINCIPAL @ R.T
    errors = []
    for h in (0.04, 0.02):
        t = np.linspace(0.0, 10.0, round(10.0 / h) + 1)
        _, w = propagate(beta0, w0, INERTIA, t)
        exact = rb.euler_poinsot_rates(MOMENTS, W_PRINCIPAL, t[-1:])[:, 0]
        errors.append(np.abs(w[:, -1] @ R - exact).max())
    assert 12 < errors[0] / errors[1] < 20  # 2⁴ = 16 for a fourth-order method


@pytest.mark.numerics
def test_constant_principal_torque_from_rest_is_the_single_axis_rotation():
    inertia = np.diag(MOMENTS)
    torque = np.array([[0.0, 0.0, 30.0], [0.0, -20.0, 0.0]])  # N·m about axes 3 and 2
    beta0 = att.principal_rotation_to_quaternion([0.0, 0.6, 0.8], 0.5)
    t = np.linspace(0.0, 5.0, 51)
    beta, w = propagate(beta0, np.zeros(3), inertia, t, torque=torque)
    alpha = torque / MOMENTS  # rad/s²
    assert np.abs(w - alpha[:, None, :] * t[:, None]).max() <= 1e-13
    # φ = α t²/2 about the torque axis, after the initial attitude; RK4 is exact here because
    # θ̇ = ω (θ ∥ ω) is a polynomial of degree 1: round-off only
    exact = att.quaternion_multiply(
        att.quaternion_exp(alpha[:, None, :] * t[:, None] ** 2 / 2), beta0
    )
    assert np.abs(beta - exact).max() <= 1e-13


@pytest.mark.numerics
def test_torque_law_reading_the_attitude_changes_momentum_as_applied():
    # a torque fixed in inertial space, u_B = C(β) u_N, read by a callable at the RK stages:
    # h_N(t) = h_N(0) + u_N t exactly, whatever the tumble
    u_N = np.array([2.0, -1.0, 0.5])
    t = np.linspace(0.0, 10.0, 1001)
    beta0 = np.array([1.0, 0.0, 0.0, 0.0])
    w0 = W_PRINCIPAL @ R.T

    def torque(tt, beta, w):
        return att.quaternion_to_dcm(beta) @ u_N

    beta, w = propagate(beta0, w0, INERTIA, t, torque=torque)
    h = rb.angular_momentum_inertial(beta, w, INERTIA)
    expected = h[:, :1] + u_N * t[:, None]
    # RKMK4 at h = 10 ms over 10 s: the state error (~1e-10 relative) bounds this
    assert np.abs(h - expected).max() <= 1e-9 * np.abs(h).max()


def test_cases_along_several_leading_axes_are_independent():
    # a (2, 3) grid of cases, each with its own inertia scale and rates, equals the cases run
    # one by one: the batch axis carries no coupling (bit-for-bit is not claimed: the BLAS
    # kernel may differ with the batch size)
    rng = np.random.default_rng(3)
    w0 = rng.standard_normal((2, 3, 3))
    inertia = INERTIA * rng.uniform(0.5, 2.0, (2, 3, 1, 1))
    t = np.linspace(0.0, 2.0, 201)
    beta, w = propagate([1.0, 0.0, 0.0, 0.0], w0, inertia, t)
    assert beta.shape == (2, 3, 201, 4)
    for i, j in np.ndindex(2, 3):
        b1, w1 = propagate([1.0, 0.0, 0.0, 0.0], w0[i, j], inertia[i, j], t)
        assert np.abs(beta[i, j] - b1).max() <= 1e-14 and np.abs(w[i, j] - w1).max() <= 1e-14


@pytest.mark.parametrize(
    "call, field",
    [
        (
            lambda: propagate([1, 0, 0, 0], [0, 0, 1], np.diag([1, -1, 1]), [0, 1]),
            "inertia: must be positive definite",
        ),
        (
            lambda: propagate([1, 0, 0, 0], [0, 0, 1], [[1, 2, 0], [0, 1, 0], [0, 0, 1]], [0, 1]),
            "inertia: must be symmetric",
        ),
        (
            lambda: propagate([1, 0, 0, 0], [0, 0, 1], np.eye(3), [0, 1, 1]),
            "t: must be a 1-D strictly increasing",
        ),
        (
            lambda: propagate([2, 0, 0, 0], [0, 0, 1], np.eye(3), [0, 1]),
            "beta0: must be a unit quaternion",
        ),
        (
            lambda: propagate([1, 0, 0, 0], [0, np.nan, 1], np.eye(3), [0, 1]),
            "w0: must be finite",
        ),
        (
            lambda: propagate([1, 0, 0, 0], [0, 0, 1], np.eye(3), [0, 1], torque=[1, 2]),
            "torque: last axes must have shape (3,)",
        ),
        (
            lambda: propagate(
                [1, 0, 0, 0], np.ones((2, 3)), np.ones((3, 1, 1)) * np.eye(3), [0, 1]
            ),
            "beta0, w0, inertia, torque: leading (case) axes must broadcast",
        ),
        (
            lambda: rb.euler_poinsot_rates([1, 1, 2], [1, 1, 1], [0, 1]),
            "moments: principal moments must be distinct",
        ),
        (lambda: rb.euler_poinsot_rates([1, 2, 3], [0, 0, 1], [0, 1]), "w0: a pure spin"),
        (
            lambda: rb.euler_poinsot_rates([1, 2, 3], [0, 1, 0], [0, 1]),
            "w0: a pure spin about the intermediate axis",
        ),
        (
            lambda: propagate(
                [1, 0, 0, 0], [0, 0, 1], np.eye(3), [0, 1], torque=lambda t, b, w: np.zeros(2)
            ),
            "torque(t, beta, w): last axes must have shape (3,)",
        ),
        (
            lambda: propagate(
                [1, 0, 0, 0],
                np.ones((2, 3)),
                np.eye(3),
                [0, 1],
                torque=lambda t, b, w: np.zeros((5, 3)),
            ),
            "torque(t, beta, w): must return shape (2, 3)",
        ),
    ],
)
def test_bad_input_names_the_field(call, field):
    with pytest.raises(ValueError, match=re.escape(field)):
        call()
