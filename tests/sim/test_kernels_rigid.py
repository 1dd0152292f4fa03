"""The rigid step of the three-axis kernel (flexsat.sim.kernels_rigid): its coefficients
against their series (Bernoulli numbers) and libm, a lane's numbers independent of its
neighbours, and the step against the Python RKMK4 step (flexsat.dynamics.rigid_body).

Tolerances. exp(θ)'s polynomials truncate below x¹⁰/10! < 3e-17 and Horner's rule rounds
a few ulps: 4 eps against libm's cos and sinc (each within an ulp). dexpinv's coefficient
c(θ) = (1 − x cot x)/|θ|²: the series branch (|θ| < 0.02) truncates below 7e-16 relative
(its next term a⁶/1209600 against 1/12), the closed form loses eps / (x²/3) to the
cancellation of 1 − x cot x ≈ x²/3. The whole step differs from the Python one by the order
of the sums and these coefficients: a few ulps of the state per step (bound 16 eps · steps).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from flexsat.dynamics.rigid_body import dexpinv, euler_acceleration, rkmk4_step
from flexsat.sim.kernels_rigid import (
    EXP_HALF_ANGLE,
    SERIES_ANGLE,
    exp_coefficients,
    rigid_steps,
    series_coefficient,
)

W = 8  # the kernel's lanes per group
EPS = np.finfo(float).eps


@njit(cache=False)
def _coefficients(t):
    c, q0, s = np.empty(W), np.empty(W), np.empty(W)
    series_coefficient(t, c, W)
    exp_coefficients(t, q0, s, W)
    return c, q0, s


@njit(cache=False)
def _steps(x, w, J, Jinv, h, substeps, k):
    S = np.empty((32, W))
    for _ in range(k):
        rigid_steps(x, w, J, Jinv, h, substeps, S, W)


def _c_series(a):
    """c(θ) = Σ_k |B_2k| a^(2k−2) / (2k)!, |θ| = a, to k = 7 (truncation < 1e-19 at 0.3)."""
    bern = [1 / 6, 1 / 30, 1 / 42, 1 / 30, 5 / 66, 691 / 2730, 7 / 6]
    return sum(b * a ** (2 * k) / math.factorial(2 * k + 2) for k, b in enumerate(bern))


def test_coefficients_against_their_series_and_libm():
    # angles on both sides of each threshold, one lane each
    angles = np.array([1e-6, 0.01, 0.0199, 0.0201, 0.05, 0.19, 0.21, 0.3])
    assert angles.min() < SERIES_ANGLE < angles.max() and (angles / 2 > EXP_HALF_ANGLE).any()
    axis = np.array([0.48, -0.6, 0.64])  # unit
    t = np.ascontiguousarray(axis[:, None] * angles[None, :])
    c, q0, s = _coefficients(t)
    a = np.sqrt(np.sum(t * t, axis=0))
    np.testing.assert_allclose(q0, np.cos(a / 2), rtol=4 * EPS, atol=0)
    np.testing.assert_allclose(s, 0.5 * np.sinc(a / (2 * np.pi)), rtol=4 * EPS, atol=0)
    for ci, ai in zip(c, a):
        x = ai / 2
        tol = 8 * EPS if ai < SERIES_ANGLE else 4 * EPS * (1 + 3 / x**2)
        assert abs(ci - _c_series(ai)) <= tol * _c_series(ai), (ai, ci)


def _lanes(v):
    return np.ascontiguousarray(np.repeat(np.asarray(v, float)[..., None], W, -1))


def _state(rng, rate):
    beta = rng.standard_normal(4)
    return np.concatenate([beta / np.linalg.norm(beta), rate * rng.standard_normal(3)])


def test_a_lane_is_the_same_whatever_its_neighbours():
    """Eight lanes, rates from slow (the series and polynomials) to fast (libm's tan, cos,
    sinc for some stages), against each state run in all eight lanes: bit for bit."""
    rng = np.random.default_rng(5)
    J = np.array([[120.0, 3.0, -2.0], [3.0, 150.0, 4.0], [-2.0, 4.0, 200.0]])
    states = np.stack([_state(rng, r) for r in np.geomspace(1e-4, 8.0, W)], axis=1)
    torque = rng.standard_normal((3, W))
    mixed = states.copy()
    _steps(mixed, torque, _lanes(J), _lanes(np.linalg.inv(J)), 0.05, 4, 20)
    for lane in range(W):
        alone = np.ascontiguousarray(np.repeat(states[:, lane : lane + 1], W, 1))
        w = np.ascontiguousarray(np.repeat(torque[:, lane : lane + 1], W, 1))
        _steps(alone, w, _lanes(J), _lanes(np.linalg.inv(J)), 0.05, 4, 20)
        assert np.array_equal(alone[:, 0], mixed[:, lane]), lane


def test_the_step_against_the_python_rkmk4_step():
    rng = np.random.default_rng(6)
    J = np.array([[120.0, 3.0, -2.0], [3.0, 150.0, 4.0], [-2.0, 4.0, 200.0]])
    Jinv = np.linalg.inv(J)
    states = np.stack([_state(rng, r) for r in np.geomspace(1e-4, 8.0, W)], axis=1)
    torque = rng.standard_normal((3, W))
    h, substeps, k = 0.05, 4, 20
    got = states.copy()
    _steps(got, torque, _lanes(J), _lanes(Jinv), h / substeps, substeps, k)
    beta, w = states[:4].T.copy(), states[4:].T.copy()
    u = torque.T

    def rates(tau, theta, omega):
        return dexpinv(theta, omega), euler_acceleration(omega, J, Jinv, u)

    for _ in range(k * substeps):
        beta, w = rkmk4_step(beta, w, h / substeps, rates)
        beta = beta / np.linalg.norm(beta, axis=-1, keepdims=True)
    want = np.concatenate([beta, w], axis=1).T
    scale = np.abs(want).max(axis=0)
    assert np.all(np.abs(got - want) <= 16 * EPS * k * substeps * scale), np.abs(got - want).max()
