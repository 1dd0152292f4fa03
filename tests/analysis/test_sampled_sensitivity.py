"""Claims about the discrete adjoint of a sampled loop (``analysis.sampled_sensitivity``).

References: closed forms (a double integrator's ZOH maps, a one-state loop's dJ/dK, dJ/da,
dJ/db), and five-point central differences of the same functions. Finite-difference budget:
step δ along a random direction of unit-order entries (δ = 1e-4 for these 1-6 state problems
with ‖A h‖ ≲ 1); truncation δ⁴|J⁽⁵⁾|/30 ≲ 1e-15 |J| and round-off ≈ 1.5 ε_J |J| / δ with
ε_J ≈ 1e-13 (expm, the Riccati/Stein solves) i.e. ≲ 2e-9 |J|: both below the issue-23
acceptance bound 1e-6, taken relative to max(|dJ|, 1e-3 |J|) (the scale under which the
difference's own round-off dominates).
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla

from flexsat.analysis.sampled_sensitivity import (
    dlqr_gain_adjoint,
    loop_adjoint,
    smooth_peak,
    soft_settling,
    terminal_energy,
    terminal_error,
    zoh_adjoint,
    zoh_maps,
)
from flexsat.input_checks import FieldError

ACCEPT = 1e-6


def central(f, h):
    return (-f(2 * h) + 8 * f(h) - 8 * f(-h) + f(-2 * h)) / (12.0 * h)


def rel(a, b, J=0.0):
    return abs(a - b) / max(abs(b), 1e-3 * abs(J), 1e-300)


def record(phi, gamma, K, x0, r, N):
    """The loop's record by the plain recursion (a test reference for the adjoint only)."""
    X = np.empty((N + 1, x0.size))
    U = np.empty((N, K.shape[0]))
    X[0] = x0
    for k in range(N):
        U[k] = -K @ (X[k] - r)
        X[k + 1] = phi @ X[k] + gamma @ U[k]
    return X, U


def test_zoh_maps_double_integrator():
    """Φ = [[1, h], [0, 1]], Γ = [h²/2, h] exactly (the block exponential's series ends)."""
    h = 0.02
    phi, gamma = zoh_maps([[0.0, 1.0], [0.0, 0.0]], [[0.0], [1.0]], h)
    np.testing.assert_allclose(phi, [[1.0, h], [0.0, 1.0]], rtol=0, atol=1e-16)
    np.testing.assert_allclose(gamma[:, 0], [h * h / 2, h], rtol=1e-15, atol=0)


def test_one_state_loop_closed_form():
    """x_{k+1} = c x_k, c = φ − γK, J = ½ x_N² = ½ c^{2N} x₀²: dJ/dK = −N γ c^{2N−1} x₀²,
    dJ/da, dJ/db through φ = e^{ah}, γ = b (e^{ah} − 1)/a; relative 1e-12 (a few ε·N)."""
    a, b, h, K, N, x0 = -0.7, 1.3, 0.05, 0.8, 60, 0.9
    phi, gamma = zoh_maps([[a]], [[b]], h)
    e = np.exp(a * h)
    assert phi[0, 0] == pytest.approx(e, rel=1e-15)
    assert gamma[0, 0] == pytest.approx(b * (e - 1) / a, rel=1e-14)
    X, U = record(phi, gamma, np.array([[K]]), np.array([x0]), np.zeros(1), N)
    mv = terminal_energy(X, U, np.eye(1))
    adj = loop_adjoint(phi, gamma, np.array([[K]]), X, U, mv.dX, mv.dU)
    c = e - b * (e - 1) / a * K
    assert mv.value == pytest.approx(0.5 * c ** (2 * N) * x0**2, rel=1e-13)
    dJdc = N * c ** (2 * N - 1) * x0**2
    assert adj.dK[0, 0] == pytest.approx(-dJdc * gamma[0, 0], rel=1e-12)
    assert adj.dx0[0] == pytest.approx(c ** (2 * N) * x0, rel=1e-12)
    dA, dB = zoh_adjoint([[a]], [[b]], h, adj.dphi, adj.dgamma)
    dphi_da, dgamma_da = h * e, b * (a * h * e - (e - 1)) / a**2
    assert dA[0, 0] == pytest.approx(dJdc * (dphi_da - K * dgamma_da), rel=1e-12)
    assert dB[0, 0] == pytest.approx(dJdc * (-K * (e - 1) / a), rel=1e-12)


def random_loop(seed=1, n=6, m=2, N=40, h=0.05):
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    B = rng.standard_normal((n, m))
    phi, gamma = zoh_maps(A, B, h)
    Q, R = np.eye(n), np.eye(m)
    S = sla.solve_discrete_are(phi, gamma, Q, R)
    K = np.linalg.solve(R + gamma.T @ S @ gamma, gamma.T @ S @ phi)
    return rng, A, B, Q, R, h, N, rng.standard_normal(n), 0.1 * rng.standard_normal(n), K


def test_zoh_adjoint_matches_differences():
    """⟨G_Φ, dΦ⟩ + ⟨G_Γ, dΓ⟩ = ⟨∂J/∂A, dA⟩ + ⟨∂J/∂B, dB⟩ for random G and directions."""
    rng, A, B, *_ = random_loop()
    h = 0.05
    Gp, Gg = rng.standard_normal(A.shape), rng.standard_normal(B.shape)
    dA, dB = zoh_adjoint(A, B, h, Gp, Gg)
    EA, EB = rng.standard_normal(A.shape), rng.standard_normal(B.shape)

    def f(s):
        phi, gamma = zoh_maps(A + s * EA, B + s * EB, h)
        return float(np.sum(Gp * phi) + np.sum(Gg * gamma))

    assert rel(np.sum(dA * EA) + np.sum(dB * EB), central(f, 1e-4), f(0.0)) <= ACCEPT


def metrics_of(X, U, h, which):
    n = X.shape[1]
    c = np.linspace(1.0, 0.2, n)
    if which == "energy":
        return terminal_energy(X, U, np.diag(np.arange(1.0, n + 1)))
    if which == "error":
        return terminal_error(X, U, c, 0.3)
    if which == "peak":
        return smooth_peak(X, U, 8)
    e0 = X[:, :] @ c
    band = 0.3 * float(np.max(np.abs(e0)))  # the record crosses the band's edge
    return soft_settling(X, U, c, 0.0, band, 0.2, h)


@pytest.mark.parametrize("which", ["energy", "error", "peak", "settling"])
def test_loop_adjoint_matches_differences(which):
    """∂J/∂(Φ, Γ, K, x₀, r) of each metric against differences of the recursion's metric."""
    rng, A, B, Q, R, h, N, x0, r, K = random_loop()
    phi, gamma = zoh_maps(A, B, h)
    X, U = record(phi, gamma, K, x0, r, N)
    mv = metrics_of(X, U, h, which)
    adj = loop_adjoint(phi, gamma, K, X, U, mv.dX, mv.dU, r)
    band = None
    if which == "settling":  # keep the band fixed while the record moves
        c = np.linspace(1.0, 0.2, X.shape[1])
        band = 0.3 * float(np.max(np.abs(X @ c)))
    dirs = {
        name: rng.standard_normal(v.shape)
        for name, v in (("phi", phi), ("gamma", gamma), ("K", K), ("x0", x0), ("r", r))
    }

    def J(s, name):
        args = {"phi": phi, "gamma": gamma, "K": K, "x0": x0, "r": r}
        args[name] = args[name] + s * dirs[name]
        Xs, Us = record(args["phi"], args["gamma"], args["K"], args["x0"], args["r"], N)
        if band is None:
            return metrics_of(Xs, Us, h, which).value
        c = np.linspace(1.0, 0.2, Xs.shape[1])
        return soft_settling(Xs, Us, c, 0.0, band, 0.2, h).value

    grads = {"phi": adj.dphi, "gamma": adj.dgamma, "K": adj.dK, "x0": adj.dx0, "r": adj.dr}
    for name, G in grads.items():
        fd = central(lambda s, name=name: J(s, name), 1e-5)
        assert rel(float(np.sum(G * dirs[name])), fd, mv.value) <= ACCEPT, name


@pytest.mark.numerics
def test_dlqr_gain_adjoint_matches_differences():
    """⟨G_K, dK⟩ of the discrete LQR gain through (Φ, Γ, Q, R), one Stein solve, against
    differences of K from scipy's DARE (ε_K ≈ 1e-13 relative: the round-off term ≲ 2e-9)."""
    rng, A, B, Q, R, h, *_ = random_loop(seed=3)
    phi, gamma = zoh_maps(A, B, h)
    S = sla.solve_discrete_are(phi, gamma, Q, R)

    def gain(p, g, q, r_):
        s = sla.solve_discrete_are(p, g, q, r_)
        return np.linalg.solve(r_ + g.T @ s @ g, g.T @ s @ p)

    K = gain(phi, gamma, Q, R)
    GK = rng.standard_normal(K.shape)
    adj = dlqr_gain_adjoint(phi, gamma, R, S, K, GK)
    sym = lambda M: M + M.T  # noqa: E731
    dirs = {
        "phi": rng.standard_normal(phi.shape),
        "gamma": rng.standard_normal(gamma.shape),
        "Q": sym(rng.standard_normal(Q.shape)),
        "R": sym(rng.standard_normal(R.shape)),
    }
    grads = {"phi": adj.dphi, "gamma": adj.dgamma, "Q": adj.dQ, "R": adj.dR}
    for name, G in grads.items():

        def f(s, name=name):
            args = {"phi": phi, "gamma": gamma, "Q": Q, "R": R}
            args[name] = args[name] + s * dirs[name]
            return float(np.sum(GK * gain(args["phi"], args["gamma"], args["Q"], args["R"])))

        assert rel(float(np.sum(G * dirs[name])), central(f, 1e-4), f(0.0)) <= ACCEPT, name


def test_smooth_peak_bounds():
    """max|u| ≤ ‖u‖_p ≤ (N m)^{1/p} max|u|, and ‖u‖_p → max|u| as p grows."""
    rng = np.random.default_rng(5)
    U = rng.standard_normal((200, 1))
    X = np.zeros((201, 2))
    peak = float(np.max(np.abs(U)))
    for p in (4, 16, 64):
        v = smooth_peak(X, U, p).value
        assert peak <= v <= 200 ** (1 / p) * peak * (1 + 1e-15)
    assert smooth_peak(X, U, 256).value == pytest.approx(peak, rel=200 ** (1 / 256) - 1)


def test_soft_settling_counts_samples_outside_band():
    """As the edge width w → 0 the surrogate counts h × (samples with |e| > b), exactly so for
    samples farther than a few w b from the edge (tanh saturates to 1 − 2e⁻²ˣ)."""
    h, b = 0.1, 0.5
    e = np.array([2.0, 1.0, 0.7, 0.2, -0.9, 0.1, 0.0])
    X = np.column_stack([e, np.zeros_like(e)])
    U = np.zeros((e.size - 1, 1))
    v = soft_settling(X, U, [1.0, 0.0], 0.0, b, 1e-3, h).value
    assert v == pytest.approx(h * 4, abs=1e-12)


def test_terminal_metrics_values():
    X = np.array([[0.0, 0.0], [1.0, 2.0]])
    U = np.zeros((1, 1))
    assert terminal_energy(X, U, np.diag([3.0, 1.0])).value == pytest.approx(0.5 * (3 + 4))
    assert terminal_error(X, U, [1.0, 1.0], 1.0).value == pytest.approx(4.0)


@pytest.mark.parametrize(
    ("call", "field"),
    [
        (lambda: zoh_maps([[1.0, 0.0]], [[1.0]], 0.1), "A"),
        (lambda: zoh_maps([[1.0]], [[1.0]], -0.1), "h"),
        (lambda: zoh_maps([[np.nan]], [[1.0]], 0.1), "A"),
        (lambda: smooth_peak(np.zeros((3, 1)), np.ones((2, 1)), 3), "p"),
        (lambda: terminal_energy(np.zeros((3, 2)), np.ones((2, 1)), np.eye(3)), "W"),
        (lambda: terminal_error(np.zeros((3, 2)), np.ones((5, 1)), [1, 0], 0.0), "X"),
        (lambda: soft_settling(np.zeros((3, 2)), np.ones((2, 1)), [1, 0], 0, -1, 0.1, 0.1), "band"),
    ],
    ids=["A-shape", "h-negative", "A-nan", "p-odd", "W-shape", "records", "band"],
)
def test_bad_input_named(call, field):
    with pytest.raises(FieldError) as info:
        call()
    assert info.value.field == field
