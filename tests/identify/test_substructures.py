"""The substructure parameterisation (:mod:`flexsat.identify.structural.substructures`):
blocks from an FE builder, modal energy distribution (Att. 7 Table 1), and the model's
eigen-solve against exact eigenvalue bounds.  The frame is the portal frame of
tests/identify/conftest.py, the arm that of tests/att7_arm.py."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest

from att7_arm import EPS, arm_model, eigenvalue_roundoff
from flexsat.identify.structural import (
    modal_energy_distribution,
)

pytestmark = pytest.mark.numerics  # tolerances near round-off: re-run on other BLAS kernels


def test_blocks_sum_to_assembly(frame, frame_builder):
    a = frame_builder(np.ones(3), np.ones(3))
    assert np.allclose(frame.K(), a.K.toarray(), rtol=0, atol=1e-6 * abs(a.K).max())
    assert np.allclose(frame.M(), a.M.toarray(), rtol=0, atol=1e-9 * abs(a.M).max())
    assert np.abs(frame.K0).max() == 0.0 and np.abs(frame.M0).max() == 0.0


def test_modal_energy_distribution_sums_to_one(frame):
    w, phi = frame.modes(n_modes=6)
    e = modal_energy_distribution(frame.K_blocks, frame.M_blocks, phi, w)
    assert e["kinetic"].shape == (6, 3) and e["strain"].shape == (6, 3)
    assert np.allclose(e["kinetic"].sum(1), 1.0) and np.allclose(e["strain"].sum(1), 1.0)
    assert np.all(e["kinetic"] >= -1e-12) and np.all(e["strain"] >= -1e-12)
    # mass-normalised modes of the full model: kinetic shares are the raw phi^T M_g phi
    raw = np.array([np.einsum("ij,ik,kj->j", phi, Mg, phi) for Mg in frame.M_blocks]).T
    assert np.allclose(raw, e["kinetic"])


def _exact_eigenvalue_enclosure(K, M, X):
    """Guaranteed bounds [lo, hi] on the eigenvalues of the stored pencil (K, M).

    ``X`` holds approximations of all n eigenvectors.  In exact rational arithmetic: Rayleigh
    quotients rho_j and residuals r_j = K x_j - rho_j M x_j, eps_j = ||r_j||_{M^-1} /
    ||x_j||_M.  Each interval rho_j +- eps_j holds an eigenvalue (Weinberger); if the n
    intervals are disjoint each holds exactly one, the j-th.  Kato-Temple with the neighbours'
    interval ends (a, b) then tightens it: rho - eps^2/(b - rho) <= lambda <= rho + eps^2/(rho - a).
    Independent of the solver and of the BLAS kernel (the M^-1 norm needs only a few digits).
    """
    Kq = [[Fraction(v) for v in row] for row in K]
    Mq = [[Fraction(v) for v in row] for row in M]
    rho, eps2 = np.zeros(len(K)), np.zeros(len(K))
    for j in range(len(K)):
        x = [Fraction(v) for v in X[:, j]]
        Kx = [sum(a * b for a, b in zip(row, x)) for row in Kq]
        Mx = [sum(a * b for a, b in zip(row, x)) for row in Mq]
        xMx = sum(a * b for a, b in zip(x, Mx))
        r = sum(a * b for a, b in zip(x, Kx)) / xMx
        res = np.array([float(a - r * b) for a, b in zip(Kx, Mx)])
        rho[j], eps2[j] = float(r), res @ np.linalg.solve(M, res) / float(xMx)
    order = np.argsort(rho)
    rho, eps2 = rho[order], eps2[order]
    e = np.sqrt(eps2)
    assert np.all(rho[1:] - e[1:] > rho[:-1] + e[:-1]), "residual intervals overlap"
    below = np.r_[-np.inf, (rho + e)[:-1]]
    above = np.r_[(rho - e)[1:], np.inf]
    ulp = np.spacing(rho)  # float(Fraction) rounds rho to nearest: widen by one ulp
    return rho - eps2 / (above - rho) - ulp, rho + eps2 / (rho - below) + ulp


def test_arm_subset_modes_match_the_exact_pencil_to_its_conditioning():
    """``modes(n_modes=5)`` and the full solve give the arm's eigenvalues (spanning 5e-4 .. 4e7)
    each to its own round-off (:func:`eigenvalue_roundoff`), checked against exact bounds."""
    arm, _ = arm_model()
    K, M = arm.K(), arm.M()
    w_all, phi_all = arm.modes()
    lo, hi = _exact_eigenvalue_enclosure(K, M, phi_all)
    assert np.all(hi - lo <= 4 * EPS * hi)  # the enclosure is as sharp as float64
    assert hi[-1] / lo[0] > 1e10
    w5, phi5 = arm.modes(n_modes=5)
    floor = eigenvalue_roundoff(K, M, phi5)
    # the base-spring mode is 1e-3 of the normwise floor eps lambda_max / lambda_1 (1e-5)
    assert floor[0] < 1e-2 * EPS * hi[-1] / lo[0] and floor[0] > 1e3 * EPS
    for lam in (w5**2, w_all[:5] ** 2):
        assert np.all(lam >= lo[:5] * (1 - floor)) and np.all(lam <= hi[:5] * (1 + floor))
    # the same for the shifted-scaled model the identification starts from
    p0, q0 = 0.9 * np.ones(4), 1.1 * np.ones(4)
    w_start, phi_start = arm.modes(p0, q0, n_modes=5)
    lo0, hi0 = _exact_eigenvalue_enclosure(arm.K(p0), arm.M(q0), arm.modes(p0, q0)[1])
    floor0 = eigenvalue_roundoff(arm.K(p0), arm.M(q0), phi_start)
    assert np.all(w_start**2 >= lo0[:5] * (1 - floor0))
    assert np.all(w_start**2 <= hi0[:5] * (1 + floor0))
