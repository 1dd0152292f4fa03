import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.linalg import expm

from flexsat.sim import engine, simulate
from flexsat.sim.integrators import ExponentialStepper, ExpRK4Stepper, phi_products
from flexsat.units import to_si

EPS = np.finfo(float).eps


def _system(seed=0, n=5):
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n)) - 2 * np.eye(n)
    A[:, 0] = 0.0  # singular, like the rigid-body mode
    return A, rng.standard_normal(n), rng.standard_normal((n, 2))


def _full_van_loan(A, h):
    """(e^{hA}, h φ1(hA), h φ2(hA)) from the full 3n × 3n block (the stepper's former
    construction): the independent reference for the products of :func:`phi_products`."""
    n = A.shape[0]
    C = np.zeros((3 * n, 3 * n))
    C[:n, :n] = A
    C[:n, n : 2 * n] = np.eye(n)
    C[n : 2 * n, 2 * n :] = np.eye(n)
    E = expm(h * C)
    return E[:n, :n], E[:n, n : 2 * n], E[:n, 2 * n :] / h


def test_phi_products_match_their_series():
    """The small block exponential = (e^{hA}, h φ1 B, h φ2 B₂), against the Taylor series
    (25 terms of a series with ‖hA‖ < 1: truncation below 1e-25)."""
    A, Bu, Bf = _system()
    h = 0.1
    B = np.column_stack([Bu, Bf])
    E, P1B, P2B = phi_products(A, h, B, 2)
    S0 = sum(np.linalg.matrix_power(h * A, j) / math.factorial(j) for j in range(25))
    S1 = sum(np.linalg.matrix_power(h * A, j) / math.factorial(j + 1) for j in range(25))
    S2 = sum(np.linalg.matrix_power(h * A, j) / math.factorial(j + 2) for j in range(25))
    assert np.allclose(E, S0, rtol=1e-13, atol=1e-15)
    assert np.allclose(P1B, h * S1 @ B, rtol=1e-13, atol=1e-15)
    assert np.allclose(P2B, h * S2 @ Bf, rtol=1e-13, atol=1e-15)


def _rigid_and_modes():
    """A free hub (rigid mode, singular A) coupled to 3 damped modes, M x'' + D x' + K x = B u."""
    M = np.array([[4.0, 0.3, 0.2, 0.1], [0.3, 1, 0, 0], [0.2, 0, 1, 0], [0.1, 0, 0, 1]])
    K = np.diag([0.0, 40.0, 900.0, 2.5e4])
    D = 0.01 * np.diag([0.0, 1, 1, 1]) * np.sqrt(K)
    Mi = np.linalg.inv(M)
    A = np.block([[np.zeros((4, 4)), np.eye(4)], [-Mi @ K, -Mi @ D]])
    Bf = np.vstack([np.zeros((4, 4)), Mi])
    return A, Bf[:, 0], Bf


def _random_stable(n=12, seed=3):
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    A -= (np.linalg.eigvals(A).real.max() + 0.5) * np.eye(n)
    return A, rng.standard_normal(n), rng.standard_normal((n, 3))


@pytest.mark.parametrize("plant", ["rigid_and_modes", "tamu_10_modes", "random_stable"])
@pytest.mark.parametrize("n_force", [0, 1, "all"])
def test_small_exponentials_equal_the_full_van_loan_construction(plant, n_force, tamu_model):
    """Every product the stepper keeps equals the one from the 3n × 3n construction.

    Bound: both are scipy's expm (backward error ~ ε) of matrices containing hA; the forward
    error of e^{hA} is at most ~ n ε ‖hA‖₁ relative (the condition number of the exponential
    is at most ‖hA‖ up to a modest factor), hence agreement to n ε max(1, ‖hA‖₁) in the 1-norm
    relative to the reference. (Measured: ≤ 8e-16 on these plants.)"""
    A, Bu, Bf = {
        "rigid_and_modes": _rigid_and_modes,
        "random_stable": _random_stable,
        "tamu_10_modes": lambda: tamu_model.state_space,
    }[plant]()
    Bf = Bf[:, : {0: 0, 1: 1, "all": Bf.shape[1]}[n_force]]
    h, substeps = 1 / 75, 3
    E0, P10, P20 = _full_van_loan(A, h / substeps)
    stepper = ExponentialStepper.build(A, Bu, Bf if n_force else None, h, substeps)
    bound = A.shape[0] * EPS * max(1.0, np.linalg.norm(h / substeps * A, 1))

    def rel(x, ref):
        return np.linalg.norm(np.atleast_2d(x - ref), 1) / np.linalg.norm(np.atleast_2d(ref), 1)

    assert rel(stepper.Et.T, E0) <= bound
    assert rel(stepper.P1u, P10 @ Bu) <= bound
    if n_force:
        assert rel(stepper.P1f.T, P10 @ Bf) <= bound
        assert rel(stepper.P2f.T, P20 @ Bf) <= bound
    else:
        assert stepper.P1f is None and stepper.P2f is None


def test_linear_tamu_run_is_unchanged_from_the_full_construction(tamu_case, monkeypatch):
    """The linear TAMU maneuver (Law II, 10 modes, no friction or noise) with the minimal
    exponential equals the run with the former 3n × 3n propagators to 1e-10 relative (the
    issue's bound for linear runs; the propagators agree to ~1e-16, measured differences of
    the histories ≤ 1e-12)."""
    cfg = tamu_case.sim_config(15.0, friction=False, noise=False)
    law = tamu_case.law_ii(
        to_si("3000 ozf*in/rad", "N*m/rad"), to_si("800 ozf*in*s/rad", "N*m*s/rad")
    )
    model = tamu_case.model()
    new = simulate(model, law, cfg, record_states=True).dataset

    class FullConstruction(ExponentialStepper):
        @classmethod
        def build(cls, A, Bu, Bf, dt, substeps=1):
            assert Bf is None  # a linear run asks for no force columns
            E, P1, _ = _full_van_loan(A, dt / substeps)
            return cls(E.T.copy(), (P1 @ Bu).T.copy(), None, None, substeps)

    monkeypatch.setattr(engine, "ExponentialStepper", FullConstruction)
    old = simulate(model, law, cfg, record_states=True).dataset
    for name in (
        "state",
        "theta",
        "torque",
        "root_torque",
        "tip_deflection",
        "energy",
        "vibration_energy",
    ):
        scale = np.abs(old[name].values).max()
        assert np.abs(new[name].values - old[name].values).max() <= 1e-10 * scale, name


def test_a_linear_stepper_refuses_a_force():
    A, Bu, _ = _system()
    stepper = ExponentialStepper.build(A, Bu, None, 0.1)
    with pytest.raises(ValueError, match=r"^force: this stepper was built without force"):
        stepper.step(np.ones((1, 5)), np.zeros(1), lambda x, w: np.zeros((1, 2)))


def test_etd2rk_is_exact_for_a_constant_force():
    """With N(x) constant the scheme is the exact solution of x' = A x + B_u w + B_f N."""
    A, Bu, Bf = _system()
    N = np.array([0.3, -0.7])
    stepper = ExponentialStepper.build(A, Bu, Bf, 0.2, substeps=3)
    x0 = np.ones((1, 5))
    x1 = stepper.step(x0, np.array([1.5]), lambda x, w: np.broadcast_to(N, (x.shape[0], 2)))
    exact = solve_ivp(
        lambda t, x: A @ x + Bu * 1.5 + Bf @ N, (0, 0.2), x0[0], rtol=1e-12, atol=1e-14
    ).y[:, -1]
    assert np.allclose(x1[0], exact, rtol=1e-9, atol=1e-12)


def test_etd2rk_converges_at_second_order_for_a_nonlinear_force():
    A, Bu, Bf = _system(1)

    def force(x, w):
        return np.stack([np.tanh(x[:, 0]), x[:, 1] ** 2], axis=1)

    x0 = 0.5 * np.ones(5)
    exact = solve_ivp(
        lambda t, x: A @ x + Bf @ force(x[None], 0)[0], (0, 1.0), x0, rtol=1e-12, atol=1e-14
    ).y[:, -1]
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


def test_phi3_product_matches_its_series():
    """h φ3(hA) B₂ from the order-3 block, against Σ h^j A^{j−3} / j! (j >= 3)."""
    A, Bu, Bf = _system()
    h, B = 0.3, np.column_stack([Bu, Bf])
    E, P1, P2, P3 = phi_products(A, h, B, 2, order=3)
    series = sum(np.linalg.matrix_power(h * A, j) / math.factorial(j + 3) for j in range(30))
    assert np.allclose(P3, h * series @ Bf, rtol=0, atol=50 * EPS * np.abs(P3).max())
    assert np.allclose(P2, phi_products(A, h, B, 2)[2], rtol=0, atol=10 * EPS)


def test_exp_rk4_is_exact_for_a_linear_plant_and_a_constant_force():
    """Krogstad's scheme reduces to the variation-of-constants formula when N is constant:
    the step equals the zero-order hold of [B_u, B_f] from one exponential to ~10 eps."""
    A, Bu, Bf = _system()
    N = np.array([0.3, -0.7])
    n, h = 5, 0.2
    stepper = ExpRK4Stepper.build(A, Bu, Bf, h, substeps=1)
    x0 = np.ones((1, n))
    x1 = stepper.step(x0, np.array([1.5]), lambda x, w: np.broadcast_to(N, (x.shape[0], 2)))
    big = np.zeros((n + 1, n + 1))
    big[:n, :n] = A
    big[:n, n] = Bu * 1.5 + Bf @ N
    exact = (expm(h * big) @ np.append(x0[0], 1.0))[:n]
    assert np.allclose(x1[0], exact, rtol=0, atol=1e-13 * np.abs(exact).max())


def test_exp_rk4_converges_at_fourth_order_on_a_known_solution():
    """Bernoulli's equation x' = −x + x² (A = −1, B_f = 1, N = x²) has the solution
    x(t) = x0 e^{−t} / (1 − x0 (1 − e^{−t})); the error at t = 1 falls 16× per halving of h
    (order 4; measured ratios 14.3, 15.2, 15.6 approaching 16), where ETD2RK's falls 4×."""
    A, Bu, Bf = np.array([[-1.0]]), np.zeros(1), np.array([[1.0]])
    x0 = 0.5
    exact = x0 * np.exp(-1.0) / (1 - x0 * (1 - np.exp(-1.0)))

    def force(x, w):
        return x**2

    errors = []
    for m in (2, 4, 8, 16):
        stepper = ExpRK4Stepper.build(A, Bu, Bf, 1.0, substeps=m)
        errors.append(abs(stepper.step(np.array([[x0]]), np.zeros(1), force)[0, 0] - exact))
    ratios = np.array(errors[:-1]) / np.array(errors[1:])
    assert np.all((ratios > 14.0) & (ratios < 18.0)), ratios
    assert errors[-1] < 1e-7
