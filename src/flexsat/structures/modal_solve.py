r"""Lowest natural modes of K φ = λ M φ (λ = ω²) by shift-invert Lanczos, with checks.

Method
------
The pencil is solved in shift-invert form, (K - σM)^{-1} M φ = ν φ with λ = σ + 1/ν, by
:func:`scipy.sparse.linalg.eigsh` (ARPACK, implicitly restarted Lanczos, one sparse
factorisation of K - σM with a symmetric minimum-degree ordering), or, when at most
``DENSE_LIMIT`` = 200 dofs carry mass, by a dense generalized symmetric eigensolver on the same
pencil after exact static condensation of the massless dofs.  The default shift is negative,
σ = -1e-10 λ_s with λ_s = max_i K_ii / M_ii (a Rayleigh quotient, so λ_s <= λ_max): K - σM is
then positive definite even when K is singular (rigid-body modes), with a condition number
near 1e10 (six orders above round-off), and σ lies below every eigenvalue, so the computed
modes are the lowest.  A larger |σ| clusters the shift-inverted eigenvalues 1/(λ - σ) of long
slender models (a 1000-element free beam: 50 s at σ = -1e-6 λ_s, 0.2 s at -1e-10 λ_s).
K - σM (σ < 0) is factorised as L D L^T without pivoting: a pivot below 1e-13 of its diagonal
entry means a mechanism that carries no mass, and negative pivots count the eigenvalues below
σ (Sylvester's law of inertia), i.e. buckling under compressive preloads; both are errors.
The Ritz vectors are refined by a final Rayleigh-Ritz step on the computed subspace, so
``Φ^T M Φ = I`` to round-off; each mode is signed so that its largest component is positive.

Near-zero modes
---------------
A computed eigenvalue is *near zero* when |λ| <= 1e-6 λ_e (its frequency is below 0.1 % of
the first elastic frequency), where λ_e is the lowest computed eigenvalue above the round-off
floor 1e-14 λ_s (rigid-body eigenvalues, as Rayleigh quotients of the computed vectors,
come out below 1e-16 λ_s; the first elastic eigenvalue of a 1000-element free beam is
3e-13 λ_s).  When ``rigid_body_modes = r`` is given, exactly r near-zero modes must be found
(one extra mode is computed to check this); they are replaced by the M-orthonormalised
rigid-body vectors (Cholesky of R^T M R, so the first is a pure x translation) when r of those
vectors are null vectors of K, otherwise kept as computed; their ω is set to 0 and the elastic
modes are made M-orthogonal to them.

Checks
------
Both matrices finite and symmetric (max |A - A^T| <= 1e-10 max |A|).  M positive
semi-definite: its Jacobi-scaled form D^{-1/2} M D^{-1/2} + 1e-8 I is factorised as
L D L^T (SuperLU without pivoting) and must have only positive pivots (Sylvester's law of
inertia: a negative pivot means an eigenvalue of the scaled M below -1e-8).  Rows of M with a
zero diagonal must be entirely zero (massless dofs are allowed; they have infinite frequency).
A computed eigenvalue below minus the near-zero threshold (buckling) is an error.
"""

from __future__ import annotations

from typing import TypeAlias

import numpy as np
import numpy.typing as npt
import scipy.linalg
import scipy.sparse as sp
from scipy.sparse.linalg import LinearOperator, SuperLU, eigsh, splu

from flexsat.input_checks import FieldError, require_count, require_finite
from flexsat.units import FloatArray

__all__ = ["check_mass_matrix", "factor_positive_definite", "solve_modes"]

SYMMETRY_RTOL = 1e-10
MASS_PSD_DELTA = 1e-8
SHIFT_RTOL = 1e-10
ROUNDOFF_RTOL = 1e-14
NEAR_ZERO_RTOL = 1e-6
DENSE_LIMIT = 200
_TINY_PIVOT = 1e-13  # LDL^T pivot / diagonal entry below which K - σM counts as singular
_INFINITE_NU = 1e-14  # shift-invert eigenvalues ν below this times max ν are massless dofs

#: a stiffness or mass matrix as accepted: scipy sparse or dense
Matrix: TypeAlias = sp.spmatrix | sp.sparray | npt.ArrayLike


def _check_matrix(A: Matrix, name: str) -> sp.csr_matrix:
    """Finite and symmetric (relative tolerance SYMMETRY_RTOL) sparse matrix."""
    A = sp.csr_matrix(A, dtype=float)
    if A.shape[0] != A.shape[1]:
        raise FieldError(name, f"must be square, got shape {A.shape}")
    if not np.all(np.isfinite(A.data)):
        raise FieldError(name, "must be finite (no NaN or inf)")
    size = np.abs(A.data).max(initial=0.0)
    asym = np.abs((A - A.T).data).max(initial=0.0)
    if asym > SYMMETRY_RTOL * size:
        raise FieldError(
            name, f"must be symmetric, max |A - A^T| = {asym:.3g} > {SYMMETRY_RTOL:g} max |A|"
        )
    return A


def _symmetric_lu(A: Matrix, pivoting: bool) -> SuperLU:
    """SuperLU factors of a symmetric matrix: symmetric minimum-degree ordering of A + A^T;
    without pivoting (pivoting=False) they are A = L D L^T with D = diag(U)."""
    if pivoting:
        return splu(sp.csc_matrix(A), permc_spec="MMD_AT_PLUS_A")
    return splu(
        sp.csc_matrix(A),
        permc_spec="MMD_AT_PLUS_A",
        diag_pivot_thresh=0.0,
        options=dict(SymmetricMode=True),
    )


def _ldl_pivots(A: Matrix) -> FloatArray | None:
    """Pivots of A = L D L^T (no pivoting, symmetric ordering), or None if that fails."""
    try:
        lu = _symmetric_lu(A, pivoting=False)
    except RuntimeError:
        return None
    if np.any(lu.perm_r != lu.perm_c):
        return None
    return lu.U.diagonal()


def check_mass_matrix(M: Matrix) -> sp.csr_matrix:
    """Validate a mass matrix: finite, symmetric, positive semi-definite, not zero.

    Raises
    ------
    ValueError
        ``mass matrix: ...`` naming the violated rule.
    """
    M = _check_matrix(M, "mass matrix")
    d = M.diagonal()
    if np.any(d < 0):
        i = int(np.argmin(d))
        raise ValueError(f"mass matrix: indefinite (negative diagonal {d[i]:.3g} at dof {i})")
    massive = d > 0
    if not np.any(massive):
        raise ValueError("mass matrix: all zero (no mass anywhere)")
    if abs(M[~massive]).sum() > 0:
        raise ValueError(
            "mass matrix: indefinite (a row with zero diagonal has off-diagonal terms)"
        )
    s = sp.diags(1.0 / np.sqrt(d[massive]))
    scaled = s @ M[massive][:, massive] @ s + MASS_PSD_DELTA * sp.eye(int(massive.sum()))
    pivots = _ldl_pivots(scaled)
    if pivots is None or np.any(pivots <= 0):
        count = "" if pivots is None else f" ({int(np.sum(pivots <= 0))} negative pivots)"
        raise ValueError(f"mass matrix: must be positive semi-definite, it is indefinite{count}")
    return M


def _eigen_scale(K: sp.csr_matrix, M: sp.csr_matrix) -> float:
    """λ_s = max K_ii / M_ii over dofs with mass."""
    dk, dm = K.diagonal(), M.diagonal()
    scale = float(np.max(dk[dm > 0] / dm[dm > 0]))
    if not scale > 0:
        raise ValueError("stiffness matrix: zero on every dof with mass")
    return scale


def _dense_pencil(
    K: sp.csr_matrix, M: sp.csr_matrix, k: int, shift: float | None, sigma0: float
) -> FloatArray:
    """The k eigenvectors nearest ``shift`` (None: lowest) of the pencil, by a dense solve.

    Massless dofs (zero rows of M) are first eliminated by exact static condensation,
    K_c = K_mm - K_ms K_ss^{-1} K_sm, and recovered as φ_s = -K_ss^{-1} K_sm φ_m.
    """
    massive = M.diagonal() > 0
    s = ~massive
    Kmm, Mm = K[massive][:, massive].toarray(), M[massive][:, massive].toarray()
    back = np.zeros((int(s.sum()), int(massive.sum())))
    if s.any():
        Ksm = K[s][:, massive]
        back = -factor_positive_definite(K[s][:, s]).solve(Ksm.toarray())
        Kmm = Kmm + Ksm.T @ back
    try:
        nu, Y = scipy.linalg.eigh(Mm, Kmm - sigma0 * Mm)
    except np.linalg.LinAlgError:  # K - σ0 M not positive definite
        eig = np.linalg.eigvalsh(Kmm - sigma0 * Mm)
        negative = int(np.sum(eig < -SYMMETRY_RTOL * np.abs(eig).max()))
        raise _buckling_error(negative) if negative else _singular_error() from None
    finite = nu > _INFINITE_NU * nu.max()
    lam, Y = sigma0 + 1.0 / nu[finite], Y[:, finite]
    if lam.size < k:
        raise FieldError(
            "n_modes",
            f"only {lam.size} modes have a finite frequency (the other dofs carry no mass)",
        )
    Y = Y[:, np.argsort(lam if shift is None else np.abs(lam - shift), kind="stable")[:k]]
    X = np.zeros((K.shape[0], k))
    X[massive], X[s] = Y, back @ Y
    return X


def factor_positive_definite(A: sp.spmatrix | sp.sparray) -> SuperLU:
    """SuperLU L D L^T factors of a matrix that must be positive definite (no pivoting).

    A pivot below 1e-13 times its diagonal entry means A is singular (a mechanism without
    mass); negative pivots count its negative eigenvalues (Sylvester's law of inertia):
    buckling modes.
    """
    try:
        lu = _symmetric_lu(A, pivoting=False)
    except RuntimeError:
        raise _singular_error() from None
    pivots = lu.U.diagonal()
    diagonal = A.diagonal()[np.argsort(lu.perm_c)]
    if np.any(lu.perm_r != lu.perm_c) or np.any(np.abs(pivots) <= _TINY_PIVOT * np.abs(diagonal)):
        raise _singular_error()
    if np.any(pivots < 0):
        raise _buckling_error(int(np.sum(pivots < 0)))
    return lu


def _singular_error() -> ValueError:
    return ValueError(
        "stiffness matrix: K - σM is singular: a mechanism that carries no mass, or a shift "
        "equal to an eigenvalue"
    )


def _buckling_error(count: int, value: float | None = None) -> ValueError:
    at = "" if value is None else f" (lowest ω² = {value:.6g} (rad/s)^2)"
    return ValueError(
        f"stiffness matrix: {count} negative eigenvalue(s){at}: the structure buckles under "
        "its compressive axial preloads"
    )


def _sparse_pencil(K: sp.csr_matrix, M: sp.csr_matrix, k: int, sigma: float) -> FloatArray:
    """k eigenvectors nearest ``sigma`` by shift-invert Lanczos (ARPACK).

    For σ < 0, K - σM must be positive definite (:func:`factor_positive_definite`); an
    eigenvalue below σ would be a buckling mode.
    """
    if sigma < 0:
        lu = factor_positive_definite(K - sigma * M)
    else:
        try:
            lu = _symmetric_lu(K - sigma * M, pivoting=True)
        except RuntimeError:
            raise _singular_error() from None
    n = K.shape[0]
    op = LinearOperator((n, n), matvec=lu.solve, dtype=float)
    v0 = lu.solve(M @ np.random.default_rng(0).standard_normal(n))  # in the range of OP
    _, X = eigsh(K, k, M=M, sigma=sigma, which="LM", OPinv=op, v0=v0)
    return X


def _rayleigh_ritz(
    K: sp.csr_matrix, M: sp.csr_matrix, X: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Refine a basis X: eigenpairs of (X^T K X, X^T M X), sorted ascending, M-orthonormal.

    The eigenvalues are the Rayleigh quotients of the refined vectors, not those of the small
    eigenproblem: its solve is accurate only to ~ eps max(λ) in absolute terms (a relative error
    of eps λ_max/λ on a low mode, 1e-8 on a spectrum spanning 1e8), whereas the error of a
    Rayleigh quotient is quadratic in the vector's error, which that solve keeps at
    ~ eps λ_max / gap.
    """
    Kr, Mr = X.T @ (K @ X), X.T @ (M @ X)
    try:
        _, Q = scipy.linalg.eigh((Kr + Kr.T) / 2, (Mr + Mr.T) / 2)
    except np.linalg.LinAlgError:
        raise FieldError(
            "n_modes", "more modes asked than there are dofs carrying mass (infinite frequencies)"
        ) from None
    X = X @ Q
    lam = np.einsum("ij,ij->j", X, K @ X) / np.einsum("ij,ij->j", X, M @ X)
    order = np.argsort(lam, kind="stable")
    return lam[order], X[:, order]


def _near_zero_tolerance(lam: FloatArray, scale: float) -> float:
    floor = ROUNDOFF_RTOL * scale
    above = lam[lam > floor]
    return max(floor, NEAR_ZERO_RTOL * above[0]) if above.size else floor


def _rigid_basis(
    R: FloatArray, K: sp.csr_matrix, M: sp.csr_matrix, tol: float
) -> FloatArray | None:
    """M-orthonormal basis of the rigid-body vectors that are null vectors of K, or None."""
    mass = np.einsum("ij,ij->j", R, M @ R)
    stiff = np.einsum("ij,ij->j", R, K @ R)
    keep = (mass > 0) & (np.abs(stiff) <= tol * np.where(mass > 0, mass, 1.0))
    R = R[:, keep]
    G = R.T @ (M @ R)
    try:
        C = np.linalg.cholesky(G)
    except np.linalg.LinAlgError:
        return None
    if np.min(np.diag(C)) ** 2 <= 1e-10 * np.max(np.diag(G)):
        return None
    return scipy.linalg.solve_triangular(C, R.T, lower=True).T


def _count_check(n_zero: int, n_computed: int, rigid_body_modes: int | None, clamped: bool) -> None:
    found = f"at least {n_zero}" if n_zero == n_computed else str(n_zero)
    r = rigid_body_modes
    if r is None:
        if clamped and n_zero:
            raise FieldError(
                "mechanism",
                f"{found} near-zero mode(s) in a clamped structure (a part can move "
                "without deforming: add members or clamps; or the mesh is so fine that the first "
                f"eigenvalue is below {ROUNDOFF_RTOL:g} x max(K_ii/M_ii), the resolution of the "
                "near-zero test)",
            )
    elif n_zero > r:
        raise FieldError(
            "mechanism",
            f"{found} near-zero modes but rigid_body_modes={r} (a mechanism or a "
            "disconnected part)",
        )
    elif n_zero < r:
        raise FieldError(
            "rigid_body_modes",
            f"expected {r} near-zero (rigid-body) modes, found {found} "
            "(the structure is constrained, or rigid_body_modes is wrong)",
        )


def _signed(X: FloatArray) -> FloatArray:
    """Each column multiplied by the sign of its largest-magnitude component."""
    idx = np.argmax(np.abs(X), axis=0)
    return X * np.where(X[idx, np.arange(X.shape[1])] < 0, -1.0, 1.0)


def solve_modes(
    K: Matrix,
    M: Matrix,
    n_modes: int,
    rigid_body_modes: int | None = None,
    shift: float | None = None,
    rigid_vectors: FloatArray | None = None,
    clamped: bool = False,
) -> tuple[FloatArray, FloatArray]:
    """Lowest (or nearest to ``shift``) mass-normalized modes of K φ = ω² M φ.

    Parameters
    ----------
    K, M : sparse or dense (n, n)
        Stiffness and mass matrices (symmetric; M positive semi-definite).
    n_modes : int
        Number of modes returned, 1 <= n_modes <= n.
    rigid_body_modes : int, optional
        Expected number of near-zero modes; checked, then cleaned (see module docstring).
    shift : float, optional
        Shift σ in (rad/s)^2; the modes nearest to it are returned.  Default: the lowest modes
        (σ = -1e-10 max K_ii/M_ii).
    rigid_vectors : ndarray (n, m), optional
        Candidate rigid-body vectors used to clean the near-zero modes.
    clamped : bool
        Whether the structure has clamps: then, with ``rigid_body_modes=None``, any near-zero
        mode is a mechanism.

    Returns
    -------
    omegas : ndarray (n_modes,)
        Natural frequencies, rad/s, ascending (near-zero ones exactly 0 when cleaned).
    shapes : ndarray (n, n_modes)
        Mass-normalized mode shapes.
    """
    K = _check_matrix(K, "stiffness matrix")
    M = check_mass_matrix(M)
    n = K.shape[0]
    if M.shape != K.shape:
        raise ValueError(f"mass matrix: shape {M.shape} differs from the stiffness {K.shape}")
    n_modes = require_count(n_modes, "n_modes")
    if n_modes > n:
        raise FieldError("n_modes", f"must be <= the number of active dofs ({n}), got {n_modes}")
    r = None if rigid_body_modes is None else _rigid_count(rigid_body_modes)
    if shift is not None:
        shift = float(require_finite(shift, "shift"))
    scale = _eigen_scale(K, M)
    sigma0 = -SHIFT_RTOL * scale
    k = min(n, n_modes if r is None else max(n_modes, r + 1))
    n_massive = int(np.sum(M.diagonal() > 0))
    if n_massive <= DENSE_LIMIT or k >= n_massive - 1:
        X = _dense_pencil(K, M, k, shift, sigma0)
    else:
        X = _sparse_pencil(K, M, k, sigma0 if shift is None else shift)
    lam, X = _rayleigh_ritz(K, M, X)
    tol = _near_zero_tolerance(lam, scale)
    if lam[0] < -tol:
        raise _buckling_error(int(np.sum(lam < -tol)), lam[0])
    n_zero = int(np.sum(np.abs(lam) <= tol))
    _count_check(n_zero, k, r, clamped)
    if r:
        X = _clean_rigid(K, M, X, r, rigid_vectors, tol)
        lam[:r] = 0.0
    return np.sqrt(np.maximum(lam[:n_modes], 0.0)), _signed(X[:, :n_modes])


def _rigid_count(value: int) -> int:
    number = None if isinstance(value, bool) else float(require_finite(value, "rigid_body_modes"))
    if number is None or number != int(number) or number < 0:
        raise FieldError("rigid_body_modes", f"must be an integer >= 0, got {value!r}")
    return int(number)


def _clean_rigid(
    K: sp.csr_matrix,
    M: sp.csr_matrix,
    X: FloatArray,
    r: int,
    rigid_vectors: FloatArray | None,
    tol: float,
) -> FloatArray:
    """Replace the r near-zero modes by exact rigid-body vectors; M-orthogonalise the rest."""
    basis = None if rigid_vectors is None else _rigid_basis(rigid_vectors, K, M, tol)
    rigid = basis if basis is not None and basis.shape[1] == r else X[:, :r]
    elastic = X[:, r:] - rigid @ (rigid.T @ (M @ X[:, r:]))
    elastic = elastic / np.sqrt(np.einsum("ij,ij->j", elastic, M @ elastic))
    return np.hstack([rigid, elastic])
