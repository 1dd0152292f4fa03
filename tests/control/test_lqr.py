"""LQR: gains equal python-control's, large lightly damped models solve to a small residual,
discrete and continuous designs agree for small dt, the NPS sanity value, and one clear error
per bad-input rule."""

import logging
import pickle

import numpy as np
import pytest
import scipy.linalg

import control
from flexsat.cases import nps
from flexsat.control import RiccatiSolution, dlqr, lqr
from flexsat.control.lqr import care_residual, dare_residual, uncontrollable_modes

pytestmark = pytest.mark.numerics  # tolerances near round-off: re-run on other BLAS kernels


def random_problem(seed, cross=False):
    rng = np.random.default_rng(seed)
    n, m = int(rng.integers(2, 11)), int(rng.integers(1, 4))
    A = rng.standard_normal((n, n))
    B = rng.standard_normal((n, m))
    X = rng.standard_normal((n, n))
    Q = X @ X.T + np.eye(n)
    Y = rng.standard_normal((m, m))
    R = Y @ Y.T + np.eye(m)
    N = 0.2 * rng.standard_normal((n, m)) if cross else None
    return A, B, Q, R, N


def modal_model(n_modes, zeta=0.002, n_inputs=2, seed=0, top=100.0):
    """Lightly damped modal model: a rigid-body mode then elastic modes 0.1 … top rad/s."""
    rng = np.random.default_rng(seed)
    w = np.concatenate([[0.0], np.geomspace(0.1, top, n_modes - 1)])
    m = n_modes
    A = np.block([[np.zeros((m, m)), np.eye(m)], [-np.diag(w**2), -np.diag(2 * zeta * w)]])
    B = np.vstack([np.zeros((m, n_inputs)), rng.standard_normal((m, n_inputs))])
    return A, B


@pytest.mark.parametrize("seed", range(20))
@pytest.mark.parametrize("cross", [False, True])
def test_gains_equal_python_control(seed, cross, schur_error_bound):
    A, B, Q, R, N = random_problem(seed, cross)
    args = (A, B, Q, R) if N is None else (A, B, Q, R, N)
    K, S, E = lqr(*args)
    K2, S2, E2 = control.lqr(*args)
    # both solutions carry the Schur method's error (conftest): their difference twice that
    tol = 2 * schur_error_bound(S)
    assert np.abs(K - K2).max() <= tol * np.linalg.norm(K, 2)
    assert np.abs(S - S2).max() <= tol * np.linalg.norm(S, 2)
    assert max(np.abs(E2 - e).min() for e in E) < 1e-8 * np.abs(E2).max()
    assert lqr(*args).residual <= schur_error_bound(S)


@pytest.mark.parametrize("seed", range(20))
@pytest.mark.parametrize("cross", [False, True])
def test_discrete_gains_equal_python_control(seed, cross, schur_error_bound):
    A, B, Q, R, N = random_problem(seed, cross)
    Ad = scipy.linalg.expm(0.1 * A)
    args = (Ad, B, Q, R) if N is None else (Ad, B, Q, R, N)
    K, S, E = dlqr(*args)
    K2, S2, _ = control.dlqr(*args)
    tol = 2 * schur_error_bound(S)  # the symplectic pencil: same bound (conftest)
    assert np.abs(K - K2).max() <= tol * np.linalg.norm(K, 2)
    assert np.abs(S - S2).max() <= tol * np.linalg.norm(S, 2)
    assert np.abs(E).max() < 1
    assert dlqr(*args).residual <= schur_error_bound(S)


def test_200_state_lightly_damped_modal_model():
    """Issue acceptance: relative Riccati residual <= 1e-10 (the term-scaled ρ_c)."""
    A, B = modal_model(100)
    sol = lqr(A, B, np.eye(200), np.eye(2))
    assert sol.residual <= 1e-10
    assert sol.poles.real.max() < 0
    rel, rel_q, absolute = care_residual(A, B, np.eye(200), np.eye(2), sol.solution)
    assert (rel, rel_q, absolute) == (sol.residual, sol.residual_q, sol.absolute_residual)


def test_residual_detects_a_wrong_solution(schur_error_bound):
    A, B, Q, R, _ = random_problem(1)
    sol = lqr(A, B, Q, R)
    assert care_residual(A, B, Q, R, 1.01 * sol.solution)[0] > 1e-4
    Ad = scipy.linalg.expm(0.1 * A)
    dsol = dlqr(Ad, B, Q, R)
    assert dare_residual(Ad, B, Q, R, dsol.solution)[0] <= schur_error_bound(dsol.solution)
    assert dare_residual(Ad, B, Q, R, 1.01 * dsol.solution)[0] > 1e-4


def test_residual_is_logged(caplog):
    A, B, Q, R, _ = random_problem(2)
    with caplog.at_level(logging.DEBUG, logger="flexsat.control.lqr"):
        lqr(A, B, Q, R)
        dlqr(scipy.linalg.expm(0.1 * A), B, Q, R)
    messages = [r.getMessage() for r in caplog.records]
    assert any(m.startswith("lqr:") and "relative Riccati residual" in m for m in messages)
    assert any(m.startswith("dlqr:") for m in messages)


def test_result_unpacks_like_python_control():
    A, B, Q, R, _ = random_problem(4)
    sol = lqr(A, B, Q, R)
    assert isinstance(sol, RiccatiSolution) and len(sol) == 3
    K, S, E = sol
    assert K is sol.gain and S is sol.solution and E is sol.poles
    assert "residual" in repr(sol)
    back = pickle.loads(pickle.dumps(sol))
    np.testing.assert_array_equal(back.gain, sol.gain)
    assert back.residual == sol.residual and len(back) == 3


def test_discrete_design_converges_to_continuous_for_small_dt():
    """dlqr of the ZOH plant with weights Q dt, R dt → the continuous gain as dt → 0 (O(dt))."""
    A, B = modal_model(4, zeta=0.01, n_inputs=1, top=3.0)
    Q, R = np.eye(8), np.eye(1)
    K = lqr(A, B, Q, R).gain
    errors = []
    for dt in (1e-2, 1e-3):
        n = A.shape[0]
        E = scipy.linalg.expm(np.block([[A, B], [np.zeros((1, n + 1))]]) * dt)
        Kd = dlqr(E[:n, :n], E[:n, n:], Q * dt, R * dt).gain
        errors.append(np.abs(Kd - K).max() / np.abs(K).max())
    assert errors[1] < 2e-3
    assert errors[0] / errors[1] > 5  # first order in dt


def test_nps_position_gain_sanity_value(schur_error_bound):
    """Seed 001 §3: R_xx(1,1) = 1, R_uu = 7 gives the θ gain √(1/7) = 0.378 for any modal data
    (θ is a pure integrator). Weights of L375: θ, θ' 1; q1, q2 and rates 0.5; others 0.1."""
    sys = nps().to_statespace()
    w = np.full(14, 0.1)
    w[[0, 7]] = 1.0
    w[[1, 2, 8, 9]] = 0.5
    sol = lqr(sys.A, sys.B, np.diag(w), 7.0)
    assert sol.gain[0, 0] == pytest.approx(np.sqrt(1 / 7), rel=1e-9)
    assert round(sol.gain[0, 0], 3) == 0.378
    assert sol.poles.real.max() < 0
    assert sol.residual <= schur_error_bound(sol.solution)


# ------------------------------------------------------------------------------------------------
# bad inputs: one test per rule
A2 = np.array([[0.0, 1.0], [0.0, 0.0]])
B2 = np.array([[0.0], [1.0]])


def test_non_square_A():
    with pytest.raises(ValueError, match="A: must be a non-empty square matrix"):
        lqr(np.ones((2, 3)), B2, np.eye(2), 1.0)


def test_non_finite_A():
    with pytest.raises(ValueError, match="A: must be finite"):
        lqr([[0.0, np.nan], [0.0, 0.0]], B2, np.eye(2), 1.0)


def test_mismatched_B():
    with pytest.raises(ValueError, match=r"B: must have shape \(n, m\) with n = 2"):
        lqr(A2, np.ones((3, 1)), np.eye(2), 1.0)


def test_Q_wrong_shape():
    with pytest.raises(ValueError, match="Q: must have shape"):
        lqr(A2, B2, np.eye(3), 1.0)


def test_Q_not_symmetric():
    with pytest.raises(ValueError, match="Q: must be symmetric"):
        lqr(A2, B2, [[1.0, 0.5], [0.0, 1.0]], 1.0)


def test_Q_indefinite():
    with pytest.raises(ValueError, match="Q: must be positive semi-definite"):
        lqr(A2, B2, np.diag([1.0, -1.0]), 1.0)


def test_R_indefinite():
    B = np.eye(2)
    with pytest.raises(ValueError, match="R: must be symmetric positive definite"):
        lqr(A2, B, np.eye(2), np.diag([1.0, -1.0]))


def test_R_singular():
    with pytest.raises(ValueError, match="R: must be symmetric positive definite"):
        lqr(A2, np.eye(2), np.eye(2), np.diag([1.0, 0.0]))


def test_R_not_symmetric():
    with pytest.raises(ValueError, match="R: must be symmetric"):
        lqr(A2, np.eye(2), np.eye(2), [[1.0, 0.5], [0.0, 1.0]])


def test_N_wrong_shape():
    with pytest.raises(ValueError, match="N: must have shape"):
        lqr(A2, B2, np.eye(2), 1.0, np.ones((2, 2)))


def test_joint_weight_indefinite():
    with pytest.raises(ValueError, match=r"N: the joint weight .* Q − N R⁻¹ Nᵀ"):
        lqr(A2, B2, np.eye(2), 1.0, [[2.0], [0.0]])


def test_unstabilizable_pair():
    A = np.diag([1.0, -1.0])
    with pytest.raises(ValueError, match=r"\(A, B\) is not stabilizable: eigenvalue\(s\) 1"):
        lqr(A, [[0.0], [1.0]], np.eye(2), 1.0)
    with pytest.raises(ValueError, match=r"\(A, B\) is not stabilizable"):
        dlqr(np.diag([1.5, 0.5]), [[0.0], [1.0]], np.eye(2), 1.0)
    assert uncontrollable_modes(A, [[0.0], [1.0]]) == [1.0]
    assert uncontrollable_modes(A, [[1.0], [0.0]]) == []


def test_rigid_mode_uncontrollable():
    """A double integrator with no input on it: the zero eigenvalue is not stabilizable."""
    A = np.zeros((4, 4))
    A[0, 1] = 1.0
    A[2, 3] = 1.0
    A[3, 2] = -4.0
    B = np.array([[0.0], [0.0], [0.0], [1.0]])
    with pytest.raises(ValueError, match="not stabilizable"):
        lqr(A, B, np.eye(4), 1.0)


def test_undetectable_pair():
    A = np.diag([1.0, -1.0])
    with pytest.raises(ValueError, match="not detectable: eigenvalue"):
        lqr(A, [[1.0], [1.0]], np.diag([0.0, 1.0]), 1.0)
    # a marginal (rigid) mode the weight does not see has no stabilizing solution either
    with pytest.raises(ValueError, match="not detectable"):
        lqr(A2, B2, np.zeros((2, 2)), 1.0)


def test_string_input():
    with pytest.raises(ValueError, match="R: must be a numeric matrix"):
        lqr(A2, B2, np.eye(2), "7")


# ------------------------------------------------------------------------------------------------
# scale-aware stabilizability / detectability (modes spanning 0.1 … 1,000 rad/s)


def wide_modal_model(**kwargs):
    """200 states: rigid mode + 99 modes 0.1 … 1,000 rad/s, ζ = 0.001, one actuator touching
    every mode (‖A‖ ~ 1e6 while the low eigenvalues are 0.01 apart)."""
    return modal_model(100, zeta=0.001, n_inputs=1, top=1000.0, **kwargs)


def test_wide_lightly_damped_modal_model_solves():
    A, B = wide_modal_model()
    assert uncontrollable_modes(A, B) == []
    assert uncontrollable_modes(A.T, np.eye(200)) == []
    K, S, E = sol = lqr(A, B, np.eye(200), 1.0)
    assert K.shape == (1, 200) and np.all(np.isfinite(S))
    assert E.real.max() < 0
    # backward error of the solve: ~n ε per term (module docstring), here a few 1e-12
    assert sol.residual < 200 * 1e3 * np.finfo(float).eps
    # controllability does not depend on the input's unit
    assert uncontrollable_modes(A, 1e-9 * B) == []


@pytest.mark.parametrize("mode", [0, 1, 50, 99])
def test_wide_model_with_an_uncontrollable_marginal_mode_is_refused(mode):
    """Mode 0 is the rigid mode (λ = 0, defective), the others are made undamped (λ = ±iω, ω =
    0.1, 10, 1,000 rad/s) and cut from the actuator: not stabilizable, named by its eigenvalue;
    left damped (ζ = 0.001), the same cut mode is stable and the pair stabilizable."""
    A, B = wide_modal_model()
    m = 100
    w = np.sqrt(-A[m + mode, mode])
    B[m + mode] = 0.0
    if mode:
        assert uncontrollable_modes(A, B) == []  # stable, merely uncontrollable
        assert lqr(A, B, np.eye(200), 1.0).poles.real.max() < 0
        A[m + mode, m + mode] = 0.0
    bad = uncontrollable_modes(A, B)
    assert len(bad) == 1 and abs(abs(bad[0]) - w) <= 1e-12 * max(w, 1.0)
    with pytest.raises(
        ValueError,
        match=rf"^\(A, B\) is not stabilizable: eigenvalue\(s\) "
        rf"0\+{w:.4g}j of A are not controllable from B$",
    ):
        lqr(A, B, np.eye(200), 1.0)


def test_wide_model_with_an_unweighted_marginal_mode_is_undetectable():
    # the dual test: Q leaves an undamped mode at ~10 rad/s unseen (its position and rate)
    A, B = wide_modal_model()
    m, mode = 100, 50
    A[m + mode, m + mode] = 0.0
    q = np.ones(200)
    q[[mode, m + mode]] = 0.0
    w = np.sqrt(-A[m + mode, mode])
    with pytest.raises(ValueError, match=rf"is not detectable: eigenvalue\(s\) 0\+{w:.4g}j are"):
        lqr(A, B, np.diag(q), 1.0)
    q[mode] = 1.0  # weighting its position alone makes it detectable
    assert lqr(A, B, np.diag(q), 1.0).poles.real.max() < 0


# ------------------------------------------------------------------------------------------------
# a solution that does not satisfy its equation is refused


@pytest.mark.parametrize("scale", [1e50, 1e150])
def test_inaccurate_solution_is_an_error(scale):
    # stable A scaled up: the true S ~ Q/(2‖A‖) underflows in the solver, S = 0 and ρ = 1
    A = np.array([[-1.0, 2.0], [0.0, -3.0]])
    with pytest.raises(
        ValueError,
        match=r"^A: the Riccati solution is inaccurate: its relative "
        r"residual 1 exceeds the accepted 1.5e-08 \(ten times "
        r"the Schur method's error bound, within \[√ε, 1e-06\]\): "
        r"the data are too badly scaled",
    ):
        lqr(scale * A, [[0.0], [1.0]], np.eye(2), 1.0)


def test_riccati_error_bound_is_the_conditioning_of_the_schur_basis():
    """κ(U11) from S alone equals the condition number of the top block of an orthonormal basis
    of span [I; S] computed independently (QR); the bound is n ε (κ(U11) + 3)."""
    from flexsat.control.lqr import riccati_error_bound

    rng = np.random.default_rng(7)
    for spread in (1.0, 1e4, 1e8):
        G = rng.standard_normal((6, 6))
        V = np.linalg.qr(G)[0]
        S = V @ np.diag(np.geomspace(1.0, spread, 6)) @ V.T
        basis = np.linalg.qr(np.vstack([np.eye(6), S]))[0]
        kappa = np.linalg.cond(basis[:6])
        # both sides are computed to O(κ ε) relative: compared to 1e-6 for κ up to 1e8
        assert riccati_error_bound(S) == pytest.approx(
            6 * np.finfo(float).eps * (kappa + 3), rel=1e-6
        )


def test_badly_scaled_data_are_refused_not_warned():
    # ‖A‖ = 1e10 against unit B, Q, R: scipy's solution has ρ ~ 0.4 (was only logged)
    A = 1e10 * np.array([[-1.0, 2.0], [0.0, -3.0]])
    with pytest.raises(ValueError, match=r"relative residual 0\.\d+ exceeds"):
        lqr(A, [[0.0], [1.0]], np.eye(2), 1.0)
    # the same plant in a sensible time unit solves (ρ at roundoff level)
    assert lqr(A / 1e10, [[0.0], [1.0]], np.eye(2), 1.0).residual < 1e-13


def test_kalman_filter_refuses_an_inaccurate_solution():
    from flexsat.control.estimation import kalman

    A = 1e150 * np.array([[-1.0, 2.0], [0.0, -3.0]])
    with pytest.raises(ValueError, match=r"^A: the Riccati solution is inaccurate"):
        kalman(A, np.eye(2), [[1.0, 0.0]], np.eye(2), 1.0)


@pytest.mark.parametrize("field", ["A", "B", "Q", "R", "N"])
@pytest.mark.parametrize("design", [lqr, dlqr])
def test_complex_input_is_refused(design, field):
    args = dict(
        A=0.5 * np.eye(2), B=np.array([[0.0], [1.0]]), Q=np.eye(2), R=np.eye(1), N=np.zeros((2, 1))
    )
    args[field] = args[field] + 1e-3j
    with pytest.raises(ValueError, match=rf"^{field}: must be a real matrix, got a complex value"):
        design(**args)
