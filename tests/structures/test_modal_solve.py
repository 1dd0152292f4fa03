"""The shift-invert eigen-solver and its checks, on matrices built here (spring-mass chains,
random pencils), against dense LAPACK solutions and closed forms.

Both code paths are exercised: dense (<= DENSE_LIMIT dofs) and ARPACK (larger).  Eigenvalues
are compared with scipy.linalg.eigh at rtol 1e-9 (ARPACK at full precision plus Rayleigh-Ritz:
observed ~1e-13); mass orthonormality at 1e-12.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.linalg
import scipy.sparse as sp

from flexsat.structures import check_mass_matrix, solve_modes
from flexsat.structures.modal_solve import DENSE_LIMIT

pytestmark = pytest.mark.numerics  # tolerances near round-off: re-run on other BLAS kernels


def chain(n, k=1000.0, m=2.0, grounded=True, masses=None):
    """Spring-mass chain: n masses, n (grounded) or n - 1 springs."""
    main = np.full(n, 2 * k)
    main[-1] = k
    if not grounded:
        main[0] = k
    K = sp.diags([main, -k * np.ones(n - 1), -k * np.ones(n - 1)], [0, 1, -1], format="csr")
    M = sp.diags(np.full(n, m) if masses is None else masses, format="csr")
    return K, M


def random_pencil(n, seed=0):
    rng = np.random.default_rng(seed)
    B = sp.random(n, n, density=4 / n, random_state=rng) + sp.eye(n)
    K = (B @ B.T).tocsr()
    C = sp.random(n, n, density=2 / n, random_state=rng)
    M = (C @ C.T + sp.diags(rng.uniform(1, 2, n))).tocsr()
    return K, M


@pytest.mark.parametrize("n", [60, 3 * DENSE_LIMIT])
def test_lowest_modes_match_dense_lapack(n):
    K, M = random_pencil(n)
    omegas, shapes = solve_modes(K, M, 8)
    lam = scipy.linalg.eigh(K.toarray(), M.toarray(), eigvals_only=True)[:8]
    assert omegas**2 == pytest.approx(lam, rel=1e-9)
    assert np.abs(shapes.T @ M @ shapes - np.eye(8)).max() < 1e-12
    assert np.abs(K @ shapes - M @ shapes * omegas**2).max() < 1e-8 * abs(K).max()
    largest = shapes[np.argmax(np.abs(shapes), axis=0), np.arange(8)]
    assert np.all(largest > 0)


@pytest.mark.parametrize("n", [60, 3 * DENSE_LIMIT])
def test_shift_returns_modes_nearest_to_it(n):
    K, M = random_pencil(n, seed=1)
    lam = scipy.linalg.eigh(K.toarray(), M.toarray(), eigvals_only=True)
    shift = 0.5 * (lam[20] + lam[21])
    expected = np.sort(lam[np.argsort(np.abs(lam - shift))[:4]])
    omegas, _ = solve_modes(K, M, 4, shift=shift)
    assert omegas**2 == pytest.approx(expected, rel=1e-9)


def test_grounded_chain_closed_form():
    """Fixed-free chain of n equal masses and springs: w_j = 2 sqrt(k/m) sin((2j-1) pi / (4n+2))."""
    n, k, m = 300, 1000.0, 2.0
    omegas, _ = solve_modes(*chain(n, k, m), 5)
    j = np.arange(1, 6)
    exact = 2 * math.sqrt(k / m) * np.sin((2 * j - 1) * math.pi / (4 * n + 2))
    assert omegas == pytest.approx(exact, rel=1e-9)


@pytest.mark.parametrize("n", [5, 3 * DENSE_LIMIT])
def test_massless_dofs_are_allowed(n):
    """Masses only at the ends of a free chain of n - 1 springs in series: one elastic mode,
    omega^2 = k_eff (1/m1 + 1/m2), k_eff = k / (n - 1); the other dofs have infinite frequency."""
    k, m1, m2 = 1000.0, 2.0, 3.0
    masses = np.zeros(n)
    masses[0], masses[-1] = m1, m2
    K, M = chain(n, k, grounded=False, masses=masses)
    omegas, shapes = solve_modes(K, M, 2, rigid_body_modes=1, rigid_vectors=np.ones((n, 1)))
    assert omegas[0] == 0.0
    assert omegas[1] == pytest.approx(math.sqrt(k / (n - 1) * (1 / m1 + 1 / m2)), rel=1e-9)
    assert np.allclose(shapes[:, 0], 1 / math.sqrt(m1 + m2), rtol=1e-14)
    with pytest.raises(ValueError, match="n_modes: .*(finite frequency|carrying mass)"):
        solve_modes(K, M, 3)


def test_rigid_mode_kept_as_computed_without_rigid_vectors():
    K, M = chain(250, grounded=False)
    omegas, shapes = solve_modes(K, M, 3, rigid_body_modes=1)
    assert omegas[0] == 0.0 and omegas[1] > 0
    assert np.ptp(shapes[:, 0]) < 1e-8 * np.abs(shapes[:, 0]).max()  # uniform translation
    assert np.abs(shapes.T @ M @ shapes - np.eye(3)).max() < 1e-12


def test_rigid_count_errors():
    K, M = chain(50, grounded=False)
    with pytest.raises(ValueError, match="rigid_body_modes: expected 2 near-zero .* found 1"):
        solve_modes(K, M, 4, rigid_body_modes=2)
    with pytest.raises(ValueError, match="mechanism: 1 near-zero mode.* clamped"):
        solve_modes(K, M, 4, clamped=True)
    Kg, Mg = chain(50)
    with pytest.raises(ValueError, match="mechanism: 1 near-zero modes but rigid_body_modes=0"):
        solve_modes(K, M, 4, rigid_body_modes=0)
    assert solve_modes(Kg, Mg, 2, rigid_body_modes=0)[0][0] > 0


@pytest.mark.parametrize("n", [20, 3 * DENSE_LIMIT])
def test_massless_mechanism_is_singular(n):
    masses = np.ones(n)
    masses[-1] = 0.0
    K, M = chain(n, masses=masses)
    K = K.tolil()
    K[-1, -1], K[-1, -2], K[-2, -1] = 0.0, 0.0, 0.0  # last dof: no stiffness, no mass
    K[-2, -2] = 1000.0
    with pytest.raises(ValueError, match="stiffness matrix: K - σM is singular"):
        solve_modes(K.tocsr(), M, 2)


@pytest.mark.parametrize("n", [20, 3 * DENSE_LIMIT])
def test_negative_stiffness_is_buckling(n):
    K, M = chain(n)
    K = K - sp.diags(np.r_[np.zeros(n - 1), 2000.0])
    with pytest.raises(ValueError, match="stiffness matrix: 1 negative eigenvalue.*buckles"):
        solve_modes(K.tocsr(), M, 2)


@pytest.mark.parametrize("n", [20, 3 * DENSE_LIMIT])
def test_mass_matrix_checks(n):
    K, M = chain(n)
    check_mass_matrix(M)
    bad = M.tolil()
    bad[0, 1] = 0.5
    with pytest.raises(ValueError, match="mass matrix: must be symmetric"):
        solve_modes(K, bad.tocsr(), 2)
    bad[1, 0] = 3.0  # symmetric, positive diagonal, indefinite
    bad[0, 1] = 3.0
    with pytest.raises(ValueError, match="mass matrix: must be positive semi-definite"):
        check_mass_matrix(bad.tocsr())
    bad = M.tolil()
    bad[2, 2] = -1e-9
    with pytest.raises(ValueError, match="mass matrix: indefinite \\(negative diagonal"):
        check_mass_matrix(bad.tocsr())
    bad[2, 2], bad[2, 3], bad[3, 2] = 0.0, 0.1, 0.1
    with pytest.raises(ValueError, match="mass matrix: indefinite \\(a row with zero diagonal"):
        check_mass_matrix(bad.tocsr())
    with pytest.raises(ValueError, match="mass matrix: all zero"):
        check_mass_matrix(sp.csr_matrix((n, n)))
    bad = M.tolil()
    bad[1, 1] = np.nan
    with pytest.raises(ValueError, match="mass matrix: must be finite"):
        check_mass_matrix(bad.tocsr())


def test_argument_errors():
    K, M = chain(10)
    for value in (0, 1.5, True, "3"):
        with pytest.raises(ValueError, match="n_modes: must be a"):
            solve_modes(K, M, value)
    with pytest.raises(ValueError, match=r"n_modes: must be <= the number of active dofs \(10\)"):
        solve_modes(K, M, 11)
    for value in (-1, 2.5, True):
        with pytest.raises(ValueError, match="rigid_body_modes: must be an integer >= 0"):
            solve_modes(K, M, 2, rigid_body_modes=value)
    with pytest.raises(ValueError, match="shift: must be finite"):
        solve_modes(K, M, 2, shift=float("inf"))
    with pytest.raises(ValueError, match="stiffness matrix: must be symmetric"):
        solve_modes(K + sp.csr_matrix(([1.0], ([0], [1])), shape=(10, 10)), M, 2)
    with pytest.raises(ValueError, match="mass matrix: shape"):
        solve_modes(K, sp.eye(9, format="csr"), 2)
