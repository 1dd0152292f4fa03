"""Claims about the adjoint gradients of LQ and H2 costs (``analysis.riccati_sensitivity``).

Finite-difference references: the five-point central difference with step h = 1e-4 (entries of
order 1) or 1e-3 |p|; truncation h⁴ |J⁽⁵⁾|/30 ≲ 1e-14 |J| and round-off ≈ 1.5 ε_J |J|/h with
ε_J ≈ 1e-13 (Riccati/Lyapunov residuals of the Schur solvers on these 4-8 state problems),
i.e. ≲ 1e-9 |J|; both are below the issue-23 acceptance bound 1e-6, used relative to
max(|∂J|, |J|/|p|) (the scale under which the round-off of the difference itself dominates).
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla

from flexsat.analysis.fe_sensitivity import TubeSection, fe_modal_derivatives
from flexsat.analysis.riccati_sensitivity import chain_gradient, h2_norm_gradient, lq_cost_gradient
from flexsat.input_checks import FieldError
from flexsat.structures.fem import Structure
from flexsat.structures.sections import Material, Section

ACCEPT = 1e-6


def central(f, p, h):
    return (-f(p + 2 * h) + 8 * f(p + h) - 8 * f(p - h) + f(p - 2 * h)) / (12.0 * h)


def problem(seed=0, n=5, m=2):
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n)) + 0.3 * np.eye(n)  # unstable open loop
    B = rng.standard_normal((n, m))
    G = rng.standard_normal((n, n))
    Q = G @ G.T + 0.1 * np.eye(n)
    H = rng.standard_normal((m, m))
    R = H @ H.T + 0.5 * np.eye(m)
    x0 = rng.standard_normal((n, 2))
    return A, B, Q, R, x0 @ x0.T


def entrywise_fd(fun, X, h=1e-4):
    out = np.zeros_like(X)
    for idx in np.ndindex(X.shape):
        E = np.zeros_like(X)
        E[idx] = 1.0
        out[idx] = central(lambda t, E=E: fun(X + t * E), 0.0, h)
    return out


def symmetric_fd(fun, X, h=1e-4):
    """FD gradient w.r.t. a symmetric matrix, in the convention dJ = ⟨G, dX⟩ for symmetric dX."""
    out = np.zeros_like(X)
    for i, j in zip(*np.triu_indices(X.shape[0])):
        E = np.zeros_like(X)
        E[i, j] = E[j, i] = 1.0
        g = central(lambda t, E=E: fun(X + t * E), 0.0, h)
        out[i, j] = out[j, i] = g if i == j else g / 2
    return out


@pytest.mark.parametrize("discrete", [False, True])
def test_lq_cost_gradients_match_central_differences(discrete):
    A, B, Q, R, X0 = problem()
    if discrete:
        A = 0.5 * A  # keep the entries modest; (A, B) stabilisable either way

    def cost(A=A, B=B, Q=Q, R=R):
        return lq_cost_gradient(A, B, Q, R, X0, discrete=discrete).cost

    g = lq_cost_gradient(A, B, Q, R, X0, discrete=discrete)
    scale = abs(g.cost)  # |J| / |p| with entries of order 1
    for name, analytic, fd in (
        ("A", g.dA, entrywise_fd(lambda X: cost(A=X), A)),
        ("B", g.dB, entrywise_fd(lambda X: cost(B=X), B)),
        ("Q", g.dQ, symmetric_fd(lambda X: cost(Q=X), Q)),
        ("R", g.dR, symmetric_fd(lambda X: cost(R=X), R)),
    ):
        err = np.abs(analytic - fd)
        assert np.all(err <= ACCEPT * np.maximum(np.abs(fd), scale)), (name, err.max())


def test_lq_cost_equals_its_adjoint_form_and_the_riccati_residual_is_small():
    A, B, Q, R, X0 = problem(1)
    g = lq_cost_gradient(A, B, Q, R, X0)
    res = A.T @ g.S + g.S @ A - g.S @ B @ np.linalg.solve(R, B.T @ g.S) + Q
    assert np.abs(res).max() <= 1e-10 * np.abs(Q).max() * np.linalg.cond(A)
    # primal and adjoint forms of the same cost: tr(S X0) = tr((Q + KᵀRK) W), W the adjoint
    dual = float(np.sum((Q + g.K.T @ R @ g.K) * g.adjoint))
    assert g.cost == pytest.approx(dual, rel=1e-10)


def test_h2_norm_gradient_matches_central_differences():
    rng = np.random.default_rng(3)
    A = rng.standard_normal((6, 6)) - 4.0 * np.eye(6)
    B, C = rng.standard_normal((6, 2)), rng.standard_normal((3, 6))
    g = h2_norm_gradient(A, B, C)
    # the norm against a direct quadrature-free formula: tr(C L_c Cᵀ)
    Lc = sla.solve_continuous_lyapunov(A, -B @ B.T)
    assert g.norm == pytest.approx(np.sqrt(np.trace(C @ Lc @ C.T)), rel=1e-12)
    for name, analytic, fd in (
        ("A", g.dA, entrywise_fd(lambda X: h2_norm_gradient(X, B, C).norm, A)),
        ("B", g.dB, entrywise_fd(lambda X: h2_norm_gradient(A, X, C).norm, B)),
        ("C", g.dC, entrywise_fd(lambda X: h2_norm_gradient(A, B, X).norm, C)),
    ):
        err = np.abs(analytic - fd)
        assert np.all(err <= ACCEPT * np.maximum(np.abs(fd), g.norm)), (name, err.max())


def _beam(t):
    s = Structure("appendage")
    for i in range(9):
        s.add_node(i, (0.25 * i, 0.0, 0.0))
    for i in range(8):
        s.add_frame(i, i + 1, Material(70e9, 2700.0), Section.tube(0.05, t))
    s.clamp(0)
    s.add_mass(8, 1.0, inertia=(0.01, 0.5, 0.05))
    return s


def _modal_lq(omegas, shapes, force_row, zeta=0.005):
    """ẍ + 2ζΩẋ + Ω²x = Φᵀ b u, regulated with Q = I, R = 1, X0 = I (modal coordinates)."""
    n = omegas.size
    A = np.block(
        [[np.zeros((n, n)), np.eye(n)], [-np.diag(omegas**2), -np.diag(2 * zeta * omegas)]]
    )
    B = np.vstack([np.zeros((n, 1)), shapes[force_row][:, None]])
    return A, B


def test_lq_cost_gradient_through_fe_frequencies_and_shapes_matches_central_differences():
    # co-design chain: wall thickness t -> (ω_i, φ_i) by fe_modal_derivatives -> A(ω), B(φ)
    # -> J = tr(S X0) by the adjoint; against a difference of the whole pipeline
    t0, modes = 0.004, [0, 1, 2]
    s = _beam(t0)
    row = s.assemble().index(8, "uy")
    d = fe_modal_derivatives(s, [TubeSection("thickness", tuple(range(8)), 0.05, t0)], modes)
    A, B = _modal_lq(d.omegas, d.modes, row)
    n = len(modes)
    Q, R, X0 = np.eye(2 * n), np.eye(1), np.eye(2 * n)
    g = lq_cost_gradient(A, B, Q, R, X0)
    zeta = 0.005
    dA = np.zeros((1, 2 * n, 2 * n))
    dA[0, n:, :n] = -np.diag(2 * d.omegas * d.omega_gradient[0])
    dA[0, n:, n:] = -np.diag(2 * zeta * d.omega_gradient[0])
    dB = np.zeros((1, 2 * n, 1))
    dB[0, n:, 0] = d.mode_gradient[0, row]
    analytic = chain_gradient([(g.dA, dA), (g.dB, dB)])[0]

    def cost(t):
        fe = _beam(t).assemble().modes(max(modes) + 1)
        phi = fe.shapes[:, modes] * np.sign(np.einsum("ij,ij->j", fe.shapes[:, modes], d.modes))
        return lq_cost_gradient(*_modal_lq(fe.omegas[modes], phi, row), Q, R, X0).cost

    fd = central(cost, t0, 1e-3 * t0)
    assert abs(analytic - fd) <= ACCEPT * max(abs(fd), g.cost / t0)


@pytest.mark.parametrize(
    "kwargs, field",
    [
        (dict(Q=-np.eye(5)), "Q"),
        (dict(R=np.zeros((2, 2))), "R"),
        (dict(R=np.eye(3)), "R"),
        (dict(B=np.ones((4, 2))), "B"),
        (dict(A=np.full((5, 5), np.nan)), "A"),
        (dict(X0=np.ones((5, 5)) - 2 * np.eye(5)), "X0"),
    ],
)
def test_bad_lq_input_is_refused_by_name(kwargs, field):
    A, B, Q, R, X0 = problem()
    args = dict(A=A, B=B, Q=Q, R=R, X0=X0) | kwargs
    with pytest.raises(FieldError, match=field):
        lq_cost_gradient(**args)


def test_unstable_plant_has_no_h2_norm_and_is_refused():
    with pytest.raises(FieldError, match="Hurwitz"):
        h2_norm_gradient(np.eye(2), np.ones((2, 1)), np.ones((1, 2)))


def test_the_optimal_gain_is_stationary_so_its_variation_drops_out_of_the_gradient():
    # J(K) = tr(P_K X0), A_cᵀP_K + P_K A_c + Q + KᵀRK = 0: ∂J/∂K = 2 (R K − Bᵀ P_K) W = 0 at
    # the LQ gain (the envelope argument the adjoint formulas rest on)
    A, B, Q, R, X0 = problem(2)
    g = lq_cost_gradient(A, B, Q, R, X0)

    def cost(K):
        Ac = A - B @ K
        P = sla.solve_continuous_lyapunov(Ac.T, -(Q + K.T @ R @ K))
        return float(np.sum(P * X0))

    dJ_dK = entrywise_fd(cost, g.K, h=1e-4)
    assert np.abs(dJ_dK).max() <= 1e-7 * g.cost / np.abs(g.K).max()
    # and away from the optimum it is not stationary (the check can fail)
    K_off = g.K + 0.05 * np.ones_like(g.K)
    assert np.linalg.eigvals(A - B @ K_off).real.max() < 0  # still a stabilising gain
    assert np.abs(entrywise_fd(cost, K_off, h=1e-4)).max() > 1e-3 * g.cost / np.abs(g.K).max()
