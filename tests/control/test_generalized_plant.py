"""The standard generalized plant: partition of a StateSpace as python-control's hinfsyn does
it, the closed loop T_zw against python-control's own interconnection, the LQG plant's weights,
and bad partitions / blocks refused naming the field.

Tolerances: two evaluations of the same rational matrix by different sums agree to a few ulps of
the largest term, relative 1e-10 covers them with the condition of (jωI − A) at the grid."""

import numpy as np
import pytest

import control as ct
from flexsat.control.generalized_plant import (
    GeneralizedPlant,
    closed_loop,
    lqg_plant,
    matrix_sqrt,
)
from flexsat.input_checks import FieldError


def random_plant(rng, n=4, nw=3, nu=2, nz=3, ny=2):
    B = rng.normal(size=(n, nw + nu))
    C = rng.normal(size=(nz + ny, n))
    D = rng.normal(size=(nz + ny, nw + nu))
    D[nz:, nw:] = 0.0
    A = rng.normal(size=(n, n)) - 3 * np.eye(n)
    return ct.ss(A, B, C, D)


def test_partition_matches_the_blocks():
    rng = np.random.default_rng(1)
    P = random_plant(rng)
    G = GeneralizedPlant.from_statespace(P, 2, 2)
    assert G.sizes == (4, 3, 2, 3, 2)
    np.testing.assert_array_equal(np.hstack([G.B1, G.B2]), P.B)
    np.testing.assert_array_equal(np.vstack([G.C1, G.C2]), P.C)
    np.testing.assert_array_equal(G.D12, np.asarray(P.D)[:3, 3:])
    back = G.statespace()
    for M in ("A", "B", "C", "D"):
        np.testing.assert_array_equal(getattr(back, M), getattr(P, M))
    assert G.control_names == tuple(P.input_labels[3:])
    assert G.measurement_names == tuple(P.output_labels[3:])


def test_closed_loop_equals_the_lower_lft_evaluated_pointwise():
    """T_zw from the state-space formula equals P11 + P12 K (I − P22 K)⁻¹ P21 with the blocks
    of P(jω) and K(jω) evaluated by python-control (positive feedback u = K y)."""
    rng = np.random.default_rng(2)
    P = random_plant(rng)
    G = GeneralizedPlant.from_statespace(P, 2, 2)
    K = ct.ss(
        -np.eye(2) - 0.1 * rng.normal(size=(2, 2)),
        rng.normal(size=(2, 2)),
        0.3 * rng.normal(size=(2, 2)),
        0.2 * rng.normal(size=(2, 2)),
    )
    T = closed_loop(G, K)
    for w in (0.0, 0.3, 2.0, 15.0):
        Pj, Kj = P(1j * w), K(1j * w)
        P11, P12, P21, P22 = Pj[:3, :3], Pj[:3, 3:], Pj[3:, :3], Pj[3:, 3:]
        ref = P11 + P12 @ Kj @ np.linalg.solve(np.eye(2) - P22 @ Kj, P21)
        np.testing.assert_allclose(T(1j * w), ref, rtol=1e-10, atol=1e-12 * np.abs(ref).max())


def test_lqg_plant_cost_weights():
    """z = [Q^½ x; R^½ u] and w = [G Qn^½ w; Rn^½ v]: C1ᵀC1 = Q, D12ᵀD12 = R, D12ᵀC1 = 0,
    B1B1ᵀ = G Qn Gᵀ, D21D21ᵀ = Rn, B1D21ᵀ = 0 (exact up to the square roots' round-off)."""
    rng = np.random.default_rng(3)
    A = rng.normal(size=(3, 3))
    B, C = rng.normal(size=(3, 1)), rng.normal(size=(2, 3))
    M = rng.normal(size=(3, 3))
    Q, R, Qn, Rn = M @ M.T, np.array([[2.0]]), np.array([[0.5]]), np.diag([1e-2, 3e-2])
    G = lqg_plant(A, B, C, Q, R, Qn, Rn)
    np.testing.assert_allclose(G.C1.T @ G.C1, Q, rtol=1e-12, atol=1e-13 * np.abs(Q).max())
    np.testing.assert_allclose(G.D12.T @ G.D12, R, rtol=1e-14)
    np.testing.assert_array_equal(G.D12.T @ G.C1, 0.0)
    np.testing.assert_allclose(G.B1 @ G.B1.T, B @ Qn @ B.T, rtol=1e-12)
    np.testing.assert_allclose(G.D21 @ G.D21.T, Rn, rtol=1e-12)
    np.testing.assert_array_equal(G.B1 @ G.D21.T, 0.0)
    assert G.control_names == ("u[0]",) and G.measurement_names == ("y[0]", "y[1]")


def test_matrix_sqrt_is_the_symmetric_root():
    M = np.array([[4.0, 1.0], [1.0, 3.0]])
    S = matrix_sqrt(M, "Q")
    np.testing.assert_allclose(S @ S, M, rtol=1e-14)
    np.testing.assert_allclose(S, S.T)


def test_bad_input_names_the_field():
    rng = np.random.default_rng(4)
    P = random_plant(rng)
    with pytest.raises(FieldError, match="^nmeas: must be in 1"):
        GeneralizedPlant.from_statespace(P, 5, 2)
    with pytest.raises(FieldError, match="^ncon: must be an integer"):
        GeneralizedPlant.from_statespace(P, 2, 1.5)
    with pytest.raises(FieldError, match="^P: must be continuous"):
        GeneralizedPlant.from_statespace(ct.c2d(P, 0.1), 2, 2)
    D = np.asarray(P.D).copy()
    D[3:, 3:] = 1.0
    bad = GeneralizedPlant.from_statespace(ct.ss(P.A, P.B, P.C, D), 2, 2)
    with pytest.raises(FieldError, match="^P.D22: must be zero"):
        bad.require_regular(True)
    G = GeneralizedPlant.from_statespace(P, 2, 2)
    with pytest.raises(FieldError, match="^P.D11: must be zero"):
        G.require_regular(True)
    with pytest.raises(FieldError, match="^Q: must be positive semi-definite"):
        lqg_plant(np.eye(2), np.ones((2, 1)), np.ones((1, 2)), -np.eye(2), 1.0, 1.0, 1.0)
