"""Controllability tools (flexsat.analysis.controllability) on textbook cases and bad inputs."""

import numpy as np
import pytest

import control
from flexsat.analysis import (
    controllability_matrix,
    controllability_rank,
    is_stabilizable,
    pbh_test,
    repeated_frequency_test,
)
from flexsat.control import lqr


def test_double_integrator_is_controllable_from_the_force():
    A, B = [[0, 1], [0, 0]], [[0], [1]]
    assert controllability_rank(A, B) == 2
    assert pbh_test(A, B).size == 0
    np.testing.assert_array_equal(controllability_matrix(A, B), control.ctrb(A, B))
    # from the position only, the rate is still reached (A B = 0): rank 1, λ = 0 uncontrollable
    assert controllability_rank(A, [[1], [0]]) == 1
    np.testing.assert_allclose(pbh_test(A, [[1], [0]]), [0.0])


def test_round_off_entries_do_not_upset_the_balanced_pbh_test():
    """A rigid attitude model linearised at a nominal rate of 1e-28 rad/s (the boundary value
    ω(0) = 0 of an optimal slew evaluated in floating point) plus a damped mode: the 1e-28
    couplings are round-off of A's scale. Balancing them up by 1e31 made λ = 0 look
    uncontrollable; the test judges the model as it is, stabilizable."""
    A = np.zeros((8, 8))
    A[:3, 3:6] = np.eye(3)
    A[6, 7], A[7, 6], A[7, 7] = 1.0, -400.0, -0.2
    A[1, 2], A[2, 1] = 1.6e-28, -1.6e-28  # -ω_nom × δα
    B = np.zeros((8, 3))
    B[3:6] = np.eye(3)
    B[7] = [0.1, 0.2, 0.3]
    assert is_stabilizable(A, B)
    lqr(A, B, np.eye(8), np.eye(3))
    # still strict: without the rate input on one axis, λ = 0 is uncontrollable
    assert not is_stabilizable(A, B[:, :2])


def test_pbh_failure_finds_the_uncontrollable_mode_and_stabilizability():
    """Diagonal A, input only on the first state: the second eigenvalue is uncontrollable;
    stabilizable iff it is stable."""
    B = [[1.0], [0.0]]
    np.testing.assert_allclose(pbh_test(np.diag([1.0, 2.0]), B), [2.0])
    assert controllability_rank(np.diag([1.0, 2.0]), B) == 1
    assert not is_stabilizable(np.diag([1.0, 2.0]), B)
    np.testing.assert_allclose(pbh_test(np.diag([1.0, -2.0]), B), [-2.0])
    assert is_stabilizable(np.diag([1.0, -2.0]), B)
    # an undamped uncontrollable oscillator (Re λ = 0) is not stabilizable
    A = np.block([[np.zeros((2, 2)), np.eye(2)], [-np.diag([4.0, 9.0]), np.zeros((2, 2))]])
    Bo = np.array([[0.0], [0.0], [1.0], [0.0]])
    np.testing.assert_allclose(pbh_test(A, Bo), [-3j, 3j], atol=1e-12)
    assert not is_stabilizable(A, Bo)


def test_repeated_eigenvalues_need_as_many_inputs_as_their_multiplicity():
    # A = I: one input can never control two states (PBH at λ = 1: rank [0, B] = 1)
    np.testing.assert_allclose(pbh_test(np.eye(2), [1.0, 1.0]), [1.0])
    assert controllability_rank(np.eye(2), [1.0, 1.0]) == 1
    assert pbh_test(np.eye(2), np.eye(2)).size == 0
    # a Jordan block is controllable from its last state
    J = [[1.0, 1.0], [0.0, 1.0]]
    assert pbh_test(J, [0.0, 1.0]).size == 0 and controllability_rank(J, [0.0, 1.0]) == 2
    # defective eigenvalue (Jordan 2 + 1 at λ = 1, computed eigenvalues split by ~√ε)
    A3 = [[1.0, 1.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
    np.testing.assert_allclose(pbh_test(A3, [0.0, 1.0, 0.0]), [1.0])
    assert pbh_test(A3, [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]).size == 0


@pytest.mark.parametrize("seed", range(6))
def test_kalman_and_pbh_agree_with_python_control_on_random_systems(seed):
    rng = np.random.default_rng(seed)
    n, m = 5, 2
    A, B = rng.normal(size=(n, n)), rng.normal(size=(n, m))
    assert controllability_rank(A, B) == np.linalg.matrix_rank(control.ctrb(A, B)) == n
    assert pbh_test(A, B).size == 0
    # make one mode uncontrollable: block-triangular in a random basis
    At = np.block(
        [[rng.normal(size=(4, 4)), rng.normal(size=(4, 1))], [np.zeros((1, 4)), np.array([[0.7]])]]
    )
    Bt = np.vstack([rng.normal(size=(4, m)), np.zeros((1, m))])
    T = rng.normal(size=(n, n))
    A2, B2 = T @ At @ np.linalg.inv(T), T @ Bt
    assert controllability_rank(A2, B2) == 4
    np.testing.assert_allclose(pbh_test(A2, B2), [0.7], rtol=1e-9)
    assert not is_stabilizable(A2, B2)


def test_repeated_frequency_test_matches_pbh_on_the_first_order_model():
    """Balas' block test for x'' + diag(κ) x = B u against PBH on [[0, I], [-diag(κ), 0]]."""
    rng = np.random.default_rng(7)
    kappa = np.array([0.0, 4.0, 4.0, 9.0, 9.0, 9.0, -1.0])  # rigid, repeated, unstable
    n = kappa.size
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-np.diag(kappa), np.zeros((n, n))]])
    for m, rows_rank in ((3, {4.0: 2, 9.0: 3}), (2, {4.0: 2, 9.0: 2})):
        B = rng.normal(size=(n, m))
        r = repeated_frequency_test(kappa, B)
        assert {g.omega_sq: g.rank for g in r.groups if g.multiplicity > 1} == rows_rank
        assert r.controllable == (pbh_test(A, np.vstack([np.zeros((n, m)), B])).size == 0)
    assert repeated_frequency_test(kappa, rng.normal(size=(n, 3))).controllable
    r = repeated_frequency_test(kappa, rng.normal(size=(n, 2)))
    assert not r.controllable and [g.modes for g in r.deficient] == [(3, 4, 5)]
    # distinct frequencies: controllable iff no row of B is zero
    B = rng.normal(size=(3, 1))
    assert repeated_frequency_test([1.0, 2.0, 3.0], B).controllable
    B[1] = 0.0
    r = repeated_frequency_test(np.diag([1.0, 2.0, 3.0]), B)
    assert not r.controllable and r.deficient[0].modes == (1,)


def test_lqr_refuses_the_problems_bainum_needs_refused():
    """The seed 002 regulators use flexsat.control.lqr; the Riccati problems without a
    stabilizing solution are refused with the reason."""
    rng = np.random.default_rng(3)
    A, B = rng.normal(size=(4, 4)), rng.normal(size=(4, 2))
    Q, R = np.diag([1.0, 2.0, 3.0, 4.0]), np.diag([1.0, 0.5])
    K, S, E = lqr(A, B, Q, R)
    K_ref, S_ref, E_ref = control.lqr(A, B, Q, R)
    np.testing.assert_allclose(K, K_ref, rtol=1e-8)
    np.testing.assert_allclose(S, S_ref, rtol=1e-8)
    assert np.all(E.real < 0)
    with pytest.raises(ValueError, match=r"^R: must be symmetric positive definite"):
        lqr(A, B, Q, np.diag([1.0, -1.0]))
    with pytest.raises(ValueError, match=r"^R: must be symmetric"):
        lqr(A, B, Q, [[1.0, 0.5], [0.0, 1.0]])
    with pytest.raises(ValueError, match=r"^Q: must be positive semi-definite"):
        lqr(A, B, np.diag([1.0, 1.0, 1.0, -1.0]), R)
    with pytest.raises(ValueError, match=r"^\(A, B\) is not stabilizable"):
        lqr(np.diag([1.0, 2.0]), [[1.0], [0.0]], np.eye(2), 1.0)
    # stabilizable (the uncontrollable mode is stable): solvable
    K, _, E = lqr(np.diag([1.0, -2.0]), [[1.0], [0.0]], np.eye(2), 1.0)
    assert np.all(E.real < 0)
    # an undamped oscillator that Q does not see has no stabilizing solution
    with pytest.raises(ValueError, match=r"is not detectable: eigenvalue\(s\) 0\+1j"):
        lqr([[0.0, 1.0], [-1.0, 0.0]], [[0.0], [1.0]], np.zeros((2, 2)), 1.0)


@pytest.mark.parametrize(
    "call,message",
    [
        (
            lambda: controllability_rank([[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]], [1.0, 2.0]),
            r"^A: must be a non-empty square 2-D array, got shape \(2, 3\)",
        ),
        (
            lambda: controllability_rank(np.eye(3), [[1.0], [2.0]]),
            r"^B: must have 3 rows \(A is 3x3\)",
        ),
        (lambda: pbh_test([[np.nan, 0.0], [0.0, 1.0]], [1.0, 1.0]), r"^A: must be finite"),
        (lambda: pbh_test(np.eye(2), [1.0, np.inf]), r"^B: must be finite"),
        (lambda: pbh_test("eye", [1.0]), r"^A: must be a numeric array"),
        (lambda: is_stabilizable(np.eye(2), np.zeros((2, 0))), r"^B: must have 2 rows"),
        (lambda: controllability_rank(np.eye(2), np.eye(2), tol=-1.0), r"^tol: must be >= 0"),
        (
            lambda: repeated_frequency_test([[1.0, 0.5], [0.0, 2.0]], np.eye(2)),
            r"^stiffness: must be a 1-D array or a diagonal",
        ),
        (
            lambda: repeated_frequency_test([1.0, 2.0], np.eye(3)),
            r"^B: must have 2 rows \(stiffness is 2x2\)",
        ),
        (lambda: lqr(np.eye(2), np.eye(2), np.eye(3), np.eye(2)), r"^Q: must have shape \(n, n\)"),
        (lambda: lqr(np.eye(2), np.eye(2), np.eye(2), 1.0), r"^R: must have shape \(m, m\)"),
    ],
)
def test_bad_inputs_name_the_field(call, message):
    with pytest.raises(ValueError, match=message):
        call()


@pytest.mark.numerics
def test_pbh_judges_each_mode_on_its_own_scale():
    """A rigid mode plus 99 modes from 0.1 to 1,000 rad/s (ζ = 0.001), one actuator reaching
    every mode: controllable (every modal row of B is nonzero). A single threshold on the scale
    of ‖A‖ ~ 1e6 used to call 91 of the low modes uncontrollable; the per-cluster test finds
    none, and still finds the one mode whose row of B is zeroed, at its frequency."""
    rng = np.random.default_rng(0)
    w = np.concatenate([[0.0], np.geomspace(0.1, 1000.0, 99)])
    A = np.block([[np.zeros((100, 100)), np.eye(100)], [-np.diag(w**2), -np.diag(2 * 0.001 * w)]])
    B = np.vstack([np.zeros((100, 1)), rng.standard_normal((100, 1))])
    assert pbh_test(A, B).size == 0
    assert is_stabilizable(A, B)
    for mode in (1, 50, 99):  # 0.1, ~9, 1,000 rad/s
        Bc = B.copy()
        Bc[100 + mode] = 0.0
        lam = pbh_test(A, Bc)
        expected = -0.001 * w[mode] + 1j * w[mode] * np.sqrt(1 - 0.001**2)
        # the pair ±λ of that mode, computed to the eigen-solver's ~ε‖A_balanced‖ accuracy
        np.testing.assert_allclose(
            sorted(lam, key=np.imag), [np.conj(expected), expected], rtol=1e-8
        )
