import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from flexsat.sim.integrators import ExponentialStepper, phi_matrices


def _system(seed=0, n=5):
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n)) - 2 * np.eye(n)
    A[:, 0] = 0.0  # singular, like the rigid-body mode
    return A, rng.standard_normal(n), rng.standard_normal((n, 2))


def test_phi_matrices_match_their_series():
    """Van Loan block exponential = (e^{hA}, h φ1, h φ2), checked against the Taylor series."""
    A, _, _ = _system()
    h = 0.1
    E, P1, P2 = phi_matrices(A, h)
    S1 = sum(np.linalg.matrix_power(h * A, j) / math.factorial(j + 1) for j in range(25))
    S2 = sum(np.linalg.matrix_power(h * A, j) / math.factorial(j + 2) for j in range(25))
    assert np.allclose(P1, h * S1, rtol=1e-13, atol=1e-15)
    assert np.allclose(P2, h * S2, rtol=1e-13, atol=1e-15)


def test_etd2rk_is_exact_for_a_constant_force():
    """With N(x) constant the scheme is the exact solution of x' = A x + B_u w + B_f N."""
    A, Bu, Bf = _system()
    N = np.array([0.3, -0.7])
    stepper = ExponentialStepper.build(A, Bu, Bf, 0.2, substeps=3)
    x0 = np.ones((1, 5))
    x1 = stepper.step(x0, np.array([1.5]), lambda x, w: np.broadcast_to(N, (x.shape[0], 2)))
    exact = solve_ivp(lambda t, x: A @ x + Bu * 1.5 + Bf @ N, (0, 0.2), x0[0],
                      rtol=1e-12, atol=1e-14).y[:, -1]
    assert np.allclose(x1[0], exact, rtol=1e-9, atol=1e-12)


def test_etd2rk_converges_at_second_order_for_a_nonlinear_force():
    A, Bu, Bf = _system(1)

    def force(x, w):
        return np.stack([np.tanh(x[:, 0]), x[:, 1] ** 2], axis=1)

    x0 = 0.5 * np.ones(5)
    exact = solve_ivp(lambda t, x: A @ x + Bf @ force(x[None], 0)[0], (0, 1.0), x0,
                      rtol=1e-12, atol=1e-14).y[:, -1]
    errors = []
    for m in (8, 16, 32):
        stepper = ExponentialStepper.build(A, Bu, Bf, 1.0, substeps=m)
        errors.append(np.abs(stepper.step(x0[None], np.zeros(1), force)[0] - exact).max())
    assert errors[0] / errors[1] == pytest.approx(4.0, rel=0.15)
    assert errors[1] / errors[2] == pytest.approx(4.0, rel=0.15)


def test_substeps_must_be_positive():
    A, Bu, Bf = _system()
    with pytest.raises(ValueError, match=r"^substeps: must be >= 1"):
        ExponentialStepper.build(A, Bu, Bf, 0.1, substeps=0)
