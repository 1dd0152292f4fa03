"""Weighted least squares of the structural identification
(:mod:`flexsat.identify.structural.least_squares`): checked against the normal equations solved
independently, on badly scaled columns, and refused by name when the data cannot determine the
scalings."""

from __future__ import annotations

import numpy as np
import pytest

from flexsat.identify.structural.least_squares import solve_scalings
from flexsat.input_checks import FieldError

pytestmark = pytest.mark.numerics  # tolerances near round-off: re-run on other BLAS kernels

EPS = np.finfo(float).eps


def test_solution_covariance_and_residuals_match_the_normal_equations():
    rng = np.random.default_rng(7)
    A = rng.normal(size=(8, 3))
    b = rng.normal(size=8)
    w = rng.uniform(0.5, 2.0, 8)
    x, cov, res, dof = solve_scalings(A, b, w, "p")
    normal = A.T @ ((w**2)[:, None] * A)
    x_ref = np.linalg.solve(normal, A.T @ (w**2 * b))
    # error bound of a backward-stable solve: cond(normal) x eps, with a factor 100 of headroom
    tol = 100 * np.linalg.cond(normal) * EPS
    assert np.allclose(x, x_ref, rtol=tol, atol=tol * np.abs(x_ref).max())
    assert np.allclose(cov, np.linalg.inv(normal), rtol=tol, atol=tol * np.abs(cov).max())
    assert np.allclose(res, w * (b - A @ x), rtol=0, atol=tol * np.abs(w * b).max())
    assert dof == 5
    # the residual is orthogonal to the weighted columns (least-squares optimality)
    assert np.abs((w[:, None] * A).T @ res).max() <= tol * np.abs(w * b).max() * 8


def test_columns_twelve_decades_apart_are_equilibrated():
    rng = np.random.default_rng(8)
    A = rng.normal(size=(6, 2)) * np.array([1e6, 1e-6])
    x_true = np.array([2e-6, -3e6])  # both columns carry O(1) of the data
    x, cov, res, dof = solve_scalings(A, A @ x_true, np.ones(6), "q")
    # consistent data: exact up to cond(equilibrated A) x eps (the raw A has cond ~ 1e12)
    scale = np.linalg.norm(A, axis=0)
    tol = 100 * np.linalg.cond(A / scale) * EPS
    assert np.allclose(x, x_true, rtol=tol, atol=0)
    assert np.abs(res).max() <= tol * np.abs(A @ x_true).max()
    # two unit columns: both diagonal entries of the inverse are 1/(1 - c^2), so the ratio is
    # the squared ratio of the column norms
    assert cov[1, 1] / cov[0, 0] == pytest.approx((scale[0] / scale[1]) ** 2, rel=1e-6)


@pytest.mark.parametrize(
    "A, message",
    [
        (np.ones((1, 2)), "1 equations for 2 parameters: more parameters than data"),
        (np.array([[1.0, 0.0], [2.0, 0.0], [3.0, 0.0]]), "parameters [1] do not affect"),
        (np.array([[1.0, 2.0], [2.0, 4.0], [3.0, 6.0]]), "not identifiable"),
    ],
    ids=["too-few-rows", "zero-column", "collinear-columns"],
)
def test_undetermined_scalings_refused_by_name(A, message):
    with pytest.raises(FieldError) as err:
        solve_scalings(A, np.ones(A.shape[0]), np.ones(A.shape[0]), "stiffness scalings")
    assert err.value.field == "stiffness scalings"
    assert message in str(err.value)
