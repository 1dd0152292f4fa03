"""Kalman filters equal python-control's and are the dual regulators; the NPS estimator
refinement (seed 001 Eqs. 52-53) gives open-loop estimation of the truncated modes."""

import numpy as np
import pytest
import scipy.linalg

import control
from flexsat.cases import nps
from flexsat.control import (
    dkalman,
    kalman,
    lqr,
    refine_estimator,
    regulator_weighted_process_noise,
    truncate_gains,
)

pytestmark = pytest.mark.numerics  # tolerances near round-off: re-run on other BLAS kernels


def random_filter_problem(seed):
    rng = np.random.default_rng(100 + seed)
    n, p, g = int(rng.integers(2, 11)), int(rng.integers(1, 4)), int(rng.integers(1, 4))
    A = rng.standard_normal((n, n))
    G = rng.standard_normal((n, g))
    C = rng.standard_normal((p, n))
    X = rng.standard_normal((g, g))
    Qn = X @ X.T + np.eye(g)
    Y = rng.standard_normal((p, p))
    Rn = Y @ Y.T + np.eye(p)
    # process noise on every state too, so (A, G Qn^½) is stabilizable for any draw
    G = np.hstack([G, np.eye(n)])
    Qn = scipy.linalg.block_diag(Qn, 0.1 * np.eye(n))
    return A, G, C, 0.5 * (Qn + Qn.T), 0.5 * (Rn + Rn.T)


def _sym(W):
    """python-control demands symmetry to an absolute eps, so G Qn Gᵀ is passed symmetrised
    (with G = I)."""
    return 0.5 * (W + W.T)


@pytest.fixture(scope="module")
def nps_design():
    """The paper's 14-state model, weights (L375) and noise intensities (Eqs. 43-44)."""
    sys = nps().to_statespace()
    w = np.full(14, 0.1)
    w[[0, 7]] = 1.0
    w[[1, 2, 8, 9]] = 0.5
    K = lqr(sys.A, sys.B, np.diag(w), 7.0).gain
    return sys.A, sys.B, sys.C, K, np.diag([1e-7, 5e-6])


@pytest.mark.parametrize("seed", range(20))
def test_kalman_gain_equals_python_control(seed, schur_error_bound):
    A, G, C, Qn, Rn = random_filter_problem(seed)
    L, P, E = kalman(A, G, C, Qn, Rn)
    L2, P2, E2 = control.lqe(A, np.eye(len(A)), C, _sym(G @ Qn @ G.T), Rn)
    # both carry the Schur method's error (tests/control/conftest.py): the difference twice it
    tol = 2 * schur_error_bound(P)
    assert np.abs(L - L2).max() <= tol * np.linalg.norm(L, 2)
    assert np.abs(P - P2).max() <= tol * np.linalg.norm(P, 2)
    assert E.real.max() < 0
    assert kalman(A, G, C, Qn, Rn).residual <= schur_error_bound(P)


@pytest.mark.parametrize("seed", range(20))
def test_discrete_kalman_gain_equals_python_control(seed, schur_error_bound):
    A, G, C, Qn, Rn = random_filter_problem(seed)
    Ad = scipy.linalg.expm(0.1 * A)
    L, P, E = dkalman(Ad, G, C, Qn, Rn)
    L2, P2, _ = control.dlqe(Ad, np.eye(len(A)), C, _sym(G @ Qn @ G.T), Rn)
    tol = 2 * schur_error_bound(P)
    assert np.abs(L - L2).max() <= tol * np.linalg.norm(L, 2)
    assert np.abs(P - P2).max() <= tol * np.linalg.norm(P, 2)
    assert np.abs(E).max() < 1


@pytest.mark.parametrize("seed", range(5))
def test_kalman_is_the_dual_regulator(seed):
    A, G, C, Qn, Rn = random_filter_problem(seed)
    rng = np.random.default_rng(seed)
    Nn = 0.1 * rng.standard_normal((G.shape[1], C.shape[0]))
    filt = kalman(A, G, C, Qn, Rn, Nn)
    reg = lqr(A.T, C.T, G @ Qn @ G.T, Rn, G @ Nn)
    np.testing.assert_allclose(filt.gain, reg.gain.T, rtol=1e-12)
    np.testing.assert_allclose(filt.solution, reg.solution, rtol=1e-12)
    assert filt.residual == reg.residual
    # the filter Riccati equation itself, with the cross intensity
    P, L = filt.solution, filt.gain
    PCN = P @ C.T + G @ Nn
    res = A @ P + P @ A.T - PCN @ np.linalg.solve(Rn, PCN.T) + G @ Qn @ G.T
    assert np.abs(res).max() < 1e-10 * np.abs(A @ P).max()
    np.testing.assert_allclose(L, PCN @ np.linalg.inv(Rn), rtol=1e-10)


def test_identity_noise_input_by_default():
    A, G, C, Qn, Rn = random_filter_problem(3)
    W = G @ Qn @ G.T
    np.testing.assert_allclose(
        kalman(A, None, C, W, Rn).gain, kalman(A, G, C, Qn, Rn).gain, rtol=1e-10
    )


# ------------------------------------------------------------------------------------------------
# NPS refinement
def test_regulator_weighted_process_noise_is_GtBtBG():
    rng = np.random.default_rng(0)
    K, B = rng.standard_normal((1, 6)), rng.standard_normal((6, 1))
    Qxx = regulator_weighted_process_noise(K, B)
    np.testing.assert_allclose(Qxx, (B.T @ B) * K.T @ K, rtol=1e-14)
    np.testing.assert_array_equal(Qxx, Qxx.T)
    np.testing.assert_array_equal(Qxx, regulator_weighted_process_noise(-K, B))  # G = −K_R
    assert np.linalg.matrix_rank(Qxx) == 1
    with pytest.raises(ValueError, match="B: must have shape"):
        regulator_weighted_process_noise(K, np.ones((5, 1)))


def test_truncate_gains_keeps_listed_states_only():
    K = np.arange(1.0, 15.0)[None, :]
    G6 = truncate_gains(K, (0, 1, 2, 7, 8, 9))  # Eq. 53: states 1, 2, 3, 8, 9, 10 (1-based)
    np.testing.assert_array_equal(np.flatnonzero(G6[0]), [0, 1, 2, 7, 8, 9])
    np.testing.assert_array_equal(G6[0, [0, 1, 2, 7, 8, 9]], [1, 2, 3, 8, 9, 10])
    mask = np.zeros(14, bool)
    mask[[0, 7]] = True
    np.testing.assert_array_equal(np.flatnonzero(truncate_gains(K, mask)[0]), [0, 7])
    assert K[0, 5] == 6  # input untouched
    with pytest.raises(ValueError, match="keep: indices must be in 0"):
        truncate_gains(K, (0, 14))
    with pytest.raises(ValueError, match="keep: a boolean mask"):
        truncate_gains(K, np.ones(3, bool))
    with pytest.raises(ValueError, match="keep: must be state indices"):
        truncate_gains(K, (0.5, 1.0))


def test_nps_refinement_gives_near_zero_gain_rows_for_truncated_modes(nps_design):
    """Notes F10: with Q_xx = G6ᵀBᵀBG6 the Kalman rows of q3-q6 and their rates are
    (near) zero — those modes are estimated open loop — while θ, q1, q2 get large gains."""
    A, B, C, K, Rn = nps_design
    keep = np.zeros(14, bool)
    keep[[0, 1, 2, 7, 8, 9]] = True
    refined = refine_estimator(A, B, C, K, keep, Rn)
    np.testing.assert_array_equal(refined.gain[0, ~keep], 0.0)
    np.testing.assert_array_equal(refined.gain[0, keep], K[0, keep])
    rows = np.linalg.norm(refined.L, axis=1)
    assert rows[~keep].max() < 1e-3 * rows[keep].min()
    assert refined.filter.residual < 1e-10
    assert refined.filter.poles.real.max() < 0
    # the paper's first design, Q_xx = B (0.1) Bᵀ (Eq. 43), does not separate them so sharply
    plain = np.linalg.norm(kalman(A, B, C, 0.1, Rn).gain, axis=1)
    assert plain[~keep].max() / plain[keep].min() > 10 * rows[~keep].max() / rows[keep].min()
    # Eq. 52 without the truncation keeps gains on every state
    full = refine_estimator(A, B, C, K, keep, Rn, truncate=False)
    assert np.count_nonzero(full.gain) == 14


# ------------------------------------------------------------------------------------------------
# bad inputs: one per rule
A2 = np.array([[0.0, 1.0], [0.0, 0.0]])
C2 = np.array([[1.0, 0.0]])


def test_kalman_mismatched_C():
    with pytest.raises(ValueError, match=r"C: must have shape \(p, n\) with n = 2"):
        kalman(A2, None, np.ones((1, 3)), np.eye(2), 1.0)


def test_kalman_non_square_A():
    with pytest.raises(ValueError, match="A: must be a non-empty square"):
        kalman(np.ones((2, 3)), None, C2, np.eye(2), 1.0)


def test_kalman_G_shape():
    with pytest.raises(ValueError, match="G: must have shape"):
        kalman(A2, np.ones((3, 1)), C2, 1.0, 1.0)


def test_kalman_Qn_indefinite():
    with pytest.raises(ValueError, match="Qn: must be positive semi-definite"):
        kalman(A2, None, C2, np.diag([1.0, -1.0]), 1.0)


def test_kalman_Rn_indefinite():
    with pytest.raises(ValueError, match="Rn: must be symmetric positive definite"):
        kalman(A2, None, np.eye(2), np.eye(2), np.diag([1.0, -1.0]))


def test_kalman_joint_intensity_indefinite():
    with pytest.raises(ValueError, match="Nn: the joint noise intensity"):
        kalman(A2, None, C2, np.eye(2), 1.0, [[2.0], [0.0]])


def test_kalman_undetectable():
    A = np.diag([1.0, -1.0])
    with pytest.raises(ValueError, match=r"\(A, C\) is not detectable: eigenvalue\(s\) 1"):
        kalman(A, None, [[0.0, 1.0]], np.eye(2), 1.0)
    with pytest.raises(ValueError, match=r"\(A, C\) is not detectable"):
        dkalman(np.diag([1.5, 0.5]), None, [[0.0, 1.0]], np.eye(2), 1.0)


def test_kalman_unexcited_unstable_mode():
    A = np.diag([1.0, -1.0])
    with pytest.raises(ValueError, match="process noise does not excite"):
        kalman(A, [[0.0], [1.0]], [[1.0, 1.0]], 1.0, 1.0)


@pytest.mark.parametrize("field", ["A", "G", "C", "Qn", "Rn"])
@pytest.mark.parametrize("design", [kalman, dkalman])
def test_complex_input_is_refused(design, field):
    args = dict(
        A=-0.5 * np.eye(2), G=np.eye(2), C=np.array([[1.0, 0.0]]), Qn=np.eye(2), Rn=np.eye(1)
    )
    args[field] = args[field] + 1e-3j
    with pytest.raises(ValueError, match=rf"^{field}: must be a real matrix, got a complex value"):
        design(**args)
