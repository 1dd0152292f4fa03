"""Gramians of modal systems: closed forms (Kim & Junkins Att. 4 Eq. 25, corrected signs;
per-pair solves; Gawronski) against Bartels–Stewart, and the finite-horizon Van Loan Gramian
against quadrature. Tolerances are the ones stated in flexsat.analysis.gramians."""

import numpy as np
import pytest
import scipy.linalg as sla
from scipy.integrate import quad_vec

from flexsat.analysis.gramians import (
    finite_horizon_gramian,
    gawronski_gramians,
    gramian_residual,
    lyapunov_gramian,
    modal_controllability_gramian,
    modal_gramian,
    modal_observability_gramian,
    modal_state_matrices,
)

pytestmark = pytest.mark.numerics  # tolerances near round-off: re-run on other BLAS kernels

RTOL_CLOSED_FORM = 1e-10  # analytic vs solve_continuous_lyapunov (observed 1e-15 … 1e-12)
RTOL_QUADRATURE = 1e-9  # finite horizon vs adaptive quadrature


def rel(a, b):
    return np.linalg.norm(a - b) / np.linalg.norm(b)


@pytest.fixture
def modal_system():
    """8 modes over two decades, with one close pair (5.0, 5.05 rad/s), mixed damping."""
    rng = np.random.default_rng(4)
    w = np.array([0.7, 1.9, 5.0, 5.05, 12.0, 30.0, 55.0, 90.0])
    z = np.array([0.002, 0.01, 0.005, 0.02, 0.03, 0.001, 0.05, 0.01])
    B = rng.normal(size=(8, 3))
    Cq = rng.normal(size=(2, 8))
    Cv = rng.normal(size=(2, 8))
    return w, z, B, Cq, Cv


# ------------------------------------------------------------------------------------------------
# closed forms against Lyapunov
def test_kim_junkins_closed_form_matches_lyapunov(modal_system):
    w, z, B, _, _ = modal_system
    A, Bz, _ = modal_state_matrices(w, z, B)
    X = modal_controllability_gramian(w, z, B)
    Xref = sla.solve_continuous_lyapunov(A, -Bz @ Bz.T)
    assert rel(X, Xref) < RTOL_CLOSED_FORM
    assert gramian_residual(A, Bz, X) < 1e-13
    assert np.allclose(X, X.T, rtol=0, atol=0)


def test_closed_form_diagonal_and_att4_layout(modal_system):
    w, z, B, _, _ = modal_system
    n = w.size
    X = modal_controllability_gramian(w, z, B)
    W = np.diag(B @ B.T)
    # notes §3.1: [X_ηη]_ii = W_ii/(4ζω³), [X_η̇η̇]_ii = W_ii/(4ζω), [X_ηη̇]_ii = 0
    assert np.allclose(np.diag(X)[:n], W / (4 * z * w**3), rtol=1e-14)
    assert np.allclose(np.diag(X)[n:], W / (4 * z * w), rtol=1e-14)
    assert np.allclose(np.diag(X[:n, n:]), 0.0, atol=0)


def test_printed_signs_of_eq25_are_wrong():
    """With the OCR's "−" signs Δ_ii = 0 and the numerator 0: X_ii = 0/0 (the print is wrong)."""
    w, z = np.array([2.0]), np.array([0.01])
    s_printed = z * w - z * w
    delta_printed = 0.0 - 4 * w * w * s_printed * (z * w - z * w)
    assert delta_printed[0] == 0 and s_printed[0] == 0
    X = modal_controllability_gramian(w, z, [[1.0]])
    assert np.isfinite(X).all() and X[0, 0] == pytest.approx(1 / (4 * 0.01 * 8))


def test_one_mode_textbook_values():
    """ẍ + 2ζωẋ + ω²x = u: X = diag(1/(4ζω³), 1/(4ζω))."""
    X = modal_controllability_gramian([2.0], [0.05], [1.0])
    assert np.allclose(X, np.diag([1 / (4 * 0.05 * 8), 1 / (4 * 0.05 * 2)]), rtol=1e-15)


def test_pair_determinant_is_att4_delta(modal_system):
    from flexsat.analysis.gramians import _pair_systems

    w, z, *_ = modal_system
    wi, wj, zi, zj = w[:, None], w[None, :], z[:, None], z[None, :]
    delta = (wi**2 - wj**2) ** 2 + 4 * wi * wj * (zi * wi + zj * wj) * (zi * wj + zj * wi)
    for kind in ("controllability", "observability"):
        assert np.allclose(np.linalg.det(_pair_systems(w, z, kind)), delta, rtol=1e-9)


def test_general_pair_solve_any_input_matches_lyapunov(modal_system):
    w, z, _, _, _ = modal_system
    rng = np.random.default_rng(1)
    A, _, _ = modal_state_matrices(w, z)
    Bfull = rng.normal(size=(16, 2))  # inputs on η as well as η̇
    X = modal_gramian(w, z, Bfull @ Bfull.T)
    assert rel(X, sla.solve_continuous_lyapunov(A, -Bfull @ Bfull.T)) < RTOL_CLOSED_FORM
    # and the rate-only case reproduces Eq. (25)
    B = rng.normal(size=(8, 2))
    _, Bz, _ = modal_state_matrices(w, z, B)
    assert rel(modal_gramian(w, z, Bz @ Bz.T), modal_controllability_gramian(w, z, B)) < 1e-12


def test_observability_matches_lyapunov(modal_system):
    w, z, _, Cq, Cv = modal_system
    A, _, C = modal_state_matrices(w, z, Cq=Cq, Cv=Cv)
    Y = modal_observability_gramian(w, z, Cq, Cv)
    assert rel(Y, sla.solve_continuous_lyapunov(A.T, -C.T @ C)) < RTOL_CLOSED_FORM
    assert gramian_residual(A, C, Y, kind="observability") < 1e-12
    assert rel(lyapunov_gramian(A, C, "observability"), Y) < RTOL_CLOSED_FORM


def test_observability_one_mode_closed_form():
    w, z, c = 3.0, 0.02, 1.7
    Y = modal_observability_gramian([w], [z], Cq=[[c]])
    expected = np.array(
        [
            [c**2 * (1 + 4 * z**2) / (4 * z * w), c**2 / (2 * w**2)],
            [c**2 / (2 * w**2), c**2 / (4 * z * w**3)],
        ]
    )
    assert np.allclose(Y, expected, rtol=1e-13)


def test_python_control_agrees(modal_system):
    control = pytest.importorskip("control")
    w, z, B, Cq, Cv = modal_system
    A, Bz, C = modal_state_matrices(w, z, B, Cq, Cv)
    X = modal_controllability_gramian(w, z, B)
    assert rel(X, control.lyap(A, Bz @ Bz.T, method="scipy")) < RTOL_CLOSED_FORM
    pytest.importorskip("slycot")  # control.gram needs slycot (sb03md)
    sys = control.ss(A, Bz, C, np.zeros((C.shape[0], Bz.shape[1])))
    assert rel(X, np.asarray(control.gram(sys, "c"))) < 1e-8
    assert rel(modal_observability_gramian(w, z, Cq, Cv), np.asarray(control.gram(sys, "o"))) < 1e-8


# ------------------------------------------------------------------------------------------------
# Gawronski's approximation
def test_gawronski_approximation_for_separated_modes():
    w = np.array([1.0, 3.0, 8.0, 20.0])
    z = np.full(4, 0.005)
    rng = np.random.default_rng(2)
    B, Cq, Cv = rng.normal(size=(4, 2)), rng.normal(size=(3, 4)), rng.normal(size=(3, 4))
    g = gawronski_gramians(w, z, B, Cq, Cv)
    A, Bz, C = modal_state_matrices(w, z, B, Cq, Cv)
    Xc, Yo = lyapunov_gramian(A, Bz), lyapunov_gramian(A, C, "observability")
    # error O(ζ) for well-separated modes
    assert rel(g.controllability, Xc) < 0.01
    assert rel(g.observability, Yo) < 0.05
    # the controllability diagonal is exact (Eq. 25 on the diagonal)
    assert np.allclose(np.diag(g.controllability), np.diag(Xc), rtol=1e-12)
    hsv = np.sqrt(np.sort(np.linalg.eigvals(Xc @ Yo).real)[::-1])
    assert np.allclose(np.sort(np.repeat(g.hankel, 2))[::-1], hsv, rtol=0.05)
    # per-mode H2 norm is exact for one mode
    for i in range(4):
        Ai, Bi, Ci = modal_state_matrices(
            w[i : i + 1], z[i : i + 1], B[i : i + 1], Cq[:, i : i + 1], Cv[:, i : i + 1]
        )
        Xi = lyapunov_gramian(Ai, Bi)
        assert g.h2[i] == pytest.approx(np.sqrt(np.trace(Ci @ Xi @ Ci.T)), rel=1e-10)


# ------------------------------------------------------------------------------------------------
# finite horizon
def _quad(A, B, T):
    f = lambda t: (lambda P: P @ B @ B.T @ P.T)(sla.expm(A * t))  # noqa: E731
    return quad_vec(f, 0.0, T, epsrel=1e-12, epsabs=0.0)[0]


def test_finite_horizon_matches_quadrature_and_lyapunov(modal_system):
    w, z, B, _, _ = modal_system
    A, Bz, _ = modal_state_matrices(w[:5], z[:5], B[:5])
    T = 2.5
    W = finite_horizon_gramian(A, Bz, T)
    assert rel(W, _quad(A, Bz, T)) < RTOL_QUADRATURE
    X = lyapunov_gramian(A, Bz)
    E = sla.expm(A * T)
    assert rel(W, X - E @ X @ E.T) < 1e-10
    # long horizon tends to the infinite-horizon Gramian: slowest decay ζω = 0.0014 → T = 2e4 s
    assert rel(finite_horizon_gramian(A, Bz, 2.0e4), X) < 1e-9


def test_finite_horizon_rigid_modes():
    """Double integrator: ∫ [t, 1]ᵀ[t, 1] dt = [[T³/3, T²/2], [T²/2, T]] (python-control's
    gram refuses this system: it is not stable)."""
    T = 7.0
    A = np.array([[0.0, 1.0], [0.0, 0.0]])
    W = finite_horizon_gramian(A, [0.0, 1.0], T)
    assert np.allclose(W, [[T**3 / 3, T**2 / 2], [T**2 / 2, T]], rtol=1e-12)
    Wo = finite_horizon_gramian(A, [[1.0, 0.0]], T, kind="observability")
    assert np.allclose(Wo, [[T, T**2 / 2], [T**2 / 2, T**3 / 3]], rtol=1e-12)


def test_finite_horizon_rigid_plus_elastic_matches_quadrature():
    w = np.array([0.0, 0.0, 1.3, 4.0, 9.0])
    z = np.array([0.0, 0.0, 0.005, 0.005, 0.005])
    B = np.random.default_rng(3).normal(size=(5, 2))
    A, Bz, _ = modal_state_matrices(w, z, B)
    W = finite_horizon_gramian(A, Bz, 10.0)
    assert rel(W, _quad(A, Bz, 10.0)) < RTOL_QUADRATURE
    assert np.linalg.eigvalsh(W).min() > -1e-10 * np.abs(W).max()
    with pytest.raises(ValueError, match="rigid-body or undamped"):
        modal_controllability_gramian(w, z, B)
    with pytest.raises(ValueError, match="finite_horizon_gramian"):
        lyapunov_gramian(A, Bz)


def test_finite_horizon_increases_with_T(modal_system):
    w, z, B, _, _ = modal_system
    A, Bz, _ = modal_state_matrices(w[:3], z[:3], B[:3])
    W1, W2 = finite_horizon_gramian(A, Bz, 1.0), finite_horizon_gramian(A, Bz, 3.0)
    assert np.linalg.eigvalsh(W2 - W1).min() > -1e-12 * np.abs(W2).max()


# ------------------------------------------------------------------------------------------------
# bad inputs
@pytest.mark.parametrize(
    "call, match",
    [
        (lambda: modal_controllability_gramian([1.0, 2.0], [0.01], [[1.0], [1.0]]), "zeta"),
        (lambda: modal_controllability_gramian([1.0, 2.0], 0.01, [[1.0]]), "B"),
        (lambda: modal_controllability_gramian([-1.0], 0.01, [1.0]), "omega"),
        (lambda: modal_controllability_gramian([1.0], 0.0, [1.0]), "rigid-body or undamped"),
        (lambda: modal_controllability_gramian([1.0], 0.01, [np.nan]), "finite"),
        (lambda: modal_controllability_gramian("1 Hz", 0.01, [1.0]), "omega"),
        (lambda: modal_gramian([1.0], 0.01, np.eye(3)), "Q"),
        (lambda: modal_gramian([1.0], 0.01, np.eye(2), kind="both"), "kind"),
        (lambda: modal_observability_gramian([1.0], 0.01), "Cq, Cv"),
        (
            lambda: modal_observability_gramian(
                [1.0, 2.0], 0.01, Cq=[[1.0, 2.0]], Cv=[[1.0, 2.0], [0, 1]]
            ),
            "same number of rows",
        ),
        (lambda: finite_horizon_gramian(np.eye(2), [1.0, 0.0], 0.0), "horizon"),
        (lambda: finite_horizon_gramian(np.eye(2), [1.0, 0.0, 0.0], 1.0), "B"),
        (lambda: finite_horizon_gramian(np.ones((2, 3)), [1.0, 0.0], 1.0), "A"),
        (lambda: lyapunov_gramian(np.eye(2), [[1.0, 0.0]], "observability"), "not asymptotically"),
        (
            lambda: gawronski_gramians([0.0, 1.0], [0.0, 0.01], [1.0, 1.0], Cq=[[1.0, 1.0]]),
            "rigid-body",
        ),
    ],
)
def test_bad_inputs(call, match):
    with pytest.raises(ValueError, match=match):
        call()
