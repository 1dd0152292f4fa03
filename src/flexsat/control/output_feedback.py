"""Symmetric collocated output feedback with Cholesky-parameterised gains (minimum sensitivity).

Source: Junkins & Kim 1990, *First and Second Order Sensitivity of the Singular Value
Decomposition*, J. Astronautical Sciences 38(1), 1990 (Att. 5 of Junkins, Pollock & Rahman 1990),
Att. 5 "Example: Minimum Sensitivity Symmetric Output Feedback Gain Design".

Plant and law (Eqs. 28-29)::

    M ẍ + C ẋ + K x = D u,        u = −(G1 Dᵀ x + G2 Dᵀ ẋ) = −(G1 y + G2 ẏ),  y = Dᵀ x

With G1, G2 symmetric positive semidefinite the closed loop is stable whatever the model error
(collocated, no observer). The gains are parameterised by lower-triangular Cholesky factors with
squared diagonals (Eqs. 30-32)::

    G1 = L1 L1ᵀ, G2 = L2 L2ᵀ,  (L1)_ii = q_ii², (L1)_ij = q_ij (i > j), likewise L2 with r
    p = [q11 q21 … q_m1 q22 … q_mm r11 r21 … r_mm]ᵀ      (m(m + 1) parameters)

so every real p gives admissible gains. Closed loop (Eqs. 34-38): M ẍ + C̄ ẋ + K̄ x = 0 with
C̄ = C + D G2 Dᵀ, K̄ = K + D G1 Dᵀ, in first-order form B ż = A z, z = (x, ẋ),
A = [[0, M], [−K̄, −C̄]], B = diag(M, M). The performance index is the condition number of the
modal matrix normalised by φ_iᵀ B φ_i = 1 (Eqs. 40-41, 46); its gradient (and Hessian) follow
from :mod:`flexsat.analysis.sensitivity`. :func:`design_minimum_sensitivity` runs the homotopy
optimizer of :mod:`flexsat.analysis.homotopy` with the frequency equalities and ζω bounds of
Eqs. 47-49.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, TypeAlias

import numpy as np
import scipy.linalg as sla

from flexsat.analysis.homotopy import HomotopyResult, homotopy_minimize
from flexsat.analysis.sensitivity import (
    GAP_RTOL,
    eig_derivatives,
    eigensolve,
    eigenvector_condition_derivatives,
)
from flexsat.input_checks import FieldError, require_finite

if TYPE_CHECKING:
    import numpy.typing as npt

    from flexsat.analysis.sensitivity import ComplexArray
    from flexsat.units import FloatArray

IntArray: TypeAlias = "npt.NDArray[np.intp]"

SOURCE = "Junkins, Pollock & Rahman 1990, Att. 5 Eqs. 28-49, Example 1"

#: Att. 5 Example 1: "6th order, 4 outputs, 2 inputs", as printed
EXAMPLE1: dict[str, Any] = {
    "M": [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
    "K": [[20.0, -10.0, 0.0], [-10.0, 30.0, -20.0], [0.0, -20.0, 20.0]],
    "D": [[1.0, 0.0], [0.0, 0.0], [0.0, 1.0]],
    "C": [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]],
    # converged gains
    "G1": [[1.1591, 0.0253], [0.0253, 1.0557]],
    "G2": [[2.2539, 0.2834], [0.2834, 2.6918]],
    "G1_fro": 1.5682,
    "G2_fro": 3.5336,
    # Table 1 (open loop) and Table 2 (closed loop)
    "open_loop_omega": [1.4447, 4.4721, 6.9219],
    "open_loop_condition": 9.4903,
    "closed_loop_eigenvalues": [
        complex(-0.8833, 1.4447),
        complex(-1.0574, 4.4721),
        complex(-0.5322, 6.7872),
    ],
    "closed_loop_zeta_omega": [0.7532, 1.0189, 0.5306],
    "closed_loop_condition": 8.1291,
    # the design problem: ω_1, ω_2 held at their open-loop values, ω_i ζ_i >= 0.3 (i = 1, 2),
    # start G1 = G2 = I; "10 homotopy steps, 3-4 minimum-norm corrections each"
    "decay_bound": 0.3,
}


# -- Cholesky parameterisation, Eqs. 30-32 -----------------------------------------------------
def _tril_columnwise(m: int) -> tuple[IntArray, IntArray]:
    """(row, column) of the lower triangle in the order q11 q21 … q_m1 q22 … q_mm."""
    cols, rows = np.triu_indices(m)
    return rows, cols


def n_parameters(n_inputs: int) -> int:
    """m(m + 1): the length of p for m inputs (two triangles of m(m + 1)/2)."""
    return n_inputs * (n_inputs + 1)


def _params(p: npt.ArrayLike, m: int) -> FloatArray:
    flat = require_finite(p, "p").reshape(-1)
    if flat.size != n_parameters(m):
        raise FieldError(
            "p",
            f"must have m(m + 1) = {n_parameters(m)} entries for m = {m} inputs, got {flat.size}",
        )
    return flat


def _factor(q: FloatArray, m: int) -> FloatArray:
    rows, cols = _tril_columnwise(m)
    L = np.zeros((m, m))
    L[rows, cols] = np.where(rows == cols, q**2, q)
    return L


def cholesky_gains(p: npt.ArrayLike, n_inputs: int) -> tuple[FloatArray, FloatArray]:
    """G1 = L1 L1ᵀ and G2 = L2 L2ᵀ from p (Att. 5 Eqs. 30-32; squared diagonals)."""
    m = _inputs(n_inputs)
    q = _params(p, m)
    h = q.size // 2
    L1, L2 = _factor(q[:h], m), _factor(q[h:], m)
    return L1 @ L1.T, L2 @ L2.T


def cholesky_parameters(G1: npt.ArrayLike, G2: npt.ArrayLike) -> FloatArray:
    """Inverse of :func:`cholesky_gains`: p with q_ii = √(L_ii) > 0, q_ij = L_ij.

    Raises
    ------
    ValueError
        A gain that is not symmetric positive definite (a semidefinite gain has no unique
        Cholesky factor with positive diagonal).
    """
    g1, g2 = _gain(G1, "G1"), _gain(G2, "G2")
    if g1.shape != g2.shape:
        raise FieldError("G2", f"must have the shape of G1 {g1.shape}, got {g2.shape}")
    m = g1.shape[0]
    rows, cols = _tril_columnwise(m)
    out = []
    for name, G in (("G1", g1), ("G2", g2)):
        try:
            L = np.linalg.cholesky(G)
        except np.linalg.LinAlgError:
            raise FieldError(
                name,
                "must be positive definite to have a Cholesky factor "
                f"(eigenvalues {np.linalg.eigvalsh(G).tolist()})",
            ) from None
        v = L[rows, cols]
        diag = rows == cols
        v[diag] = np.sqrt(v[diag])
        out.append(v)
    return np.concatenate(out)


def cholesky_gain_derivatives(
    p: npt.ArrayLike, n_inputs: int
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """∂G/∂p_k and ∂²G/∂p_k∂p_l of the parameterisation (Eqs. 30-32).

    Returns
    -------
    dG1, dG2 : (P, m, m) ndarray
        dG = dL Lᵀ + L dLᵀ with dL = E_ij (off-diagonal q_ij) or 2 q_ii E_ii (diagonal).
    d2G1, d2G2 : (P, P, m, m) ndarray
        dL_k dL_lᵀ + dL_l dL_kᵀ, plus 2(E_ii Lᵀ + L E_ii) when k = l is a diagonal q_ii.
    """
    m = _inputs(n_inputs)
    flat = _params(p, m)
    P, h = flat.size, flat.size // 2
    rows, cols = _tril_columnwise(m)
    dG = np.zeros((2, P, m, m))
    d2G = np.zeros((2, P, P, m, m))
    for half in (0, 1):
        q = flat[half * h : (half + 1) * h]
        L = _factor(q, m)
        dL = np.zeros((h, m, m))
        dL[np.arange(h), rows, cols] = np.where(rows == cols, 2 * q, 1.0)
        sl = slice(half * h, (half + 1) * h)
        dG[half, sl] = dL @ L.T + L @ dL.transpose(0, 2, 1)
        outer = np.einsum("kij,lmj->klim", dL, dL)
        block = outer + outer.transpose(1, 0, 2, 3)
        for a in np.flatnonzero(rows == cols):
            E = np.zeros((m, m))
            E[rows[a], cols[a]] = 2.0
            block[a, a] += E @ L.T + L @ E.T
        d2G[half, sl, sl] = block
    return dG[0], dG[1], d2G[0], d2G[1]


# -- the plant and its closed loop -------------------------------------------------------------
def _inputs(n_inputs: object) -> int:
    if isinstance(n_inputs, bool) or not isinstance(n_inputs, (int, np.integer)) or n_inputs < 1:
        raise FieldError("n_inputs", f"must be a positive integer, got {n_inputs!r}")
    return int(n_inputs)


def _gain(value: npt.ArrayLike, field: str, m: int | None = None) -> FloatArray:
    G = require_finite(value, field)
    if G.ndim != 2 or G.shape[0] != G.shape[1]:
        raise FieldError(field, f"must be a square matrix, got shape {G.shape}")
    if m is not None and G.shape != (m, m):
        raise FieldError(field, f"must be {m}x{m} (one row per input), got shape {G.shape}")
    scale = max(1.0, float(np.abs(G).max()))
    if not np.allclose(G, G.T, rtol=0, atol=1e-12 * scale):
        raise FieldError(field, "must be symmetric (Att. 5 Eq. 29)")
    low = float(np.linalg.eigvalsh(0.5 * (G + G.T)).min())
    if low < -1e-12 * scale:
        raise FieldError(
            field,
            f"must be positive semidefinite (smallest eigenvalue {low:.3g})"
            "; the collocated law is guaranteed stable only for G >= 0",
        )
    return 0.5 * (G + G.T)


def _square(value: npt.ArrayLike, field: str, n: int | None = None) -> FloatArray:
    A = require_finite(value, field)
    if A.ndim != 2 or A.shape[0] != A.shape[1]:
        raise FieldError(field, f"must be a square matrix, got shape {A.shape}")
    if n is not None and A.shape[0] != n:
        raise FieldError(field, f"must be {n}x{n} like M, got shape {A.shape}")
    return A


@dataclass(frozen=True)
class FeedbackSensitivity:
    """Closed-loop quantities and their derivatives with respect to the Cholesky parameters p.

    Attributes
    ----------
    condition_number : float
        κ = σ_max/σ_min of the normalised closed-loop modal matrix (Eq. 46).
    gradient : (P,) ndarray
        ∂κ/∂p.
    hessian : (P, P) ndarray or None
        ∂²κ/∂p_k∂p_l (``order=2``; Eqs. 27 and 44).
    omega, zeta_omega : (n_modes,) ndarray
        ω_i = Im λ_i and ζ_iω_i = Im λ_i (−Re λ_i)/|λ_i| of the oscillatory modes (Im λ > 0),
        ascending ω (Eqs. 47-49).
    omega_gradient, zeta_omega_gradient : (n_modes, P) ndarray
        Their Jacobians, from ∂λ/∂p (Eq. 42).
    eigenvalues : (2n,) complex
        All closed-loop eigenvalues, sorted by |Im λ| then Im λ (descending) then Re λ.
    """

    condition_number: float
    gradient: FloatArray
    hessian: FloatArray | None
    omega: FloatArray
    zeta_omega: FloatArray
    omega_gradient: FloatArray
    zeta_omega_gradient: FloatArray
    eigenvalues: ComplexArray


class SymmetricOutputFeedback:
    """Collocated plant M ẍ + C ẋ + K x = D u under u = −(G1 Dᵀx + G2 Dᵀẋ) (Att. 5 Eqs. 28-38).

    Parameters
    ----------
    M : (n, n) array_like
        Mass matrix (non-singular; symmetric positive definite in the paper).
    K : (n, n) array_like
        Stiffness.
    D : (n, m) array_like
        Actuator influence; the sensors are collocated (y = Dᵀx).
    C : (n, n) array_like, optional
        Open-loop damping; default zero.

    Attributes
    ----------
    n_dof, n_inputs, n_parameters : int
    """

    def __init__(
        self,
        M: npt.ArrayLike,
        K: npt.ArrayLike,
        D: npt.ArrayLike,
        C: npt.ArrayLike | None = None,
    ) -> None:
        self.M = _square(M, "M")
        n = self.M.shape[0]
        self.K = _square(K, "K", n)
        influence = require_finite(D, "D")
        if influence.ndim == 1:
            influence = influence[:, None]
        if influence.ndim != 2 or influence.shape[0] != n:
            raise FieldError(
                "D",
                f"must be an ({n}, m) matrix (one column per input), got shape {influence.shape}",
            )
        self.D = influence
        self.C = np.zeros((n, n)) if C is None else _square(C, "C", n)
        if np.linalg.cond(self.M) > 1e12:
            raise FieldError("M", "must be non-singular")
        self.n_dof, self.n_inputs = n, influence.shape[1]
        self.n_parameters = n_parameters(self.n_inputs)

    @classmethod
    def example1(cls) -> SymmetricOutputFeedback:
        """Att. 5 Example 1: M = I3, K = [[20,−10,0],[−10,30,−20],[0,−20,20]], D = [e1 e3],
        C = 0 (Att. 5 "Example: Minimum Sensitivity Symmetric Output Feedback Gain Design")."""
        return cls(EXAMPLE1["M"], EXAMPLE1["K"], EXAMPLE1["D"], EXAMPLE1["C"])

    # -- gains ------------------------------------------------------------------------------
    def gains(self, p: npt.ArrayLike) -> tuple[FloatArray, FloatArray]:
        """(G1, G2) of the Cholesky parameters p (Eqs. 30-32)."""
        return cholesky_gains(p, self.n_inputs)

    def parameters(self, G1: npt.ArrayLike, G2: npt.ArrayLike) -> FloatArray:
        """Cholesky parameters p of positive definite (G1, G2)."""
        return cholesky_parameters(_gain(G1, "G1", self.n_inputs), _gain(G2, "G2", self.n_inputs))

    # -- closed loop ------------------------------------------------------------------------
    def pencil(self, G1: npt.ArrayLike, G2: npt.ArrayLike) -> tuple[FloatArray, FloatArray]:
        """A and B of B ż = A z: A = [[0, M], [−K̄, −C̄]], B = diag(M, M) (Eqs. 34-38)."""
        return self._pencil(_gain(G1, "G1", self.n_inputs), _gain(G2, "G2", self.n_inputs))

    def _pencil(self, G1: FloatArray, G2: FloatArray) -> tuple[FloatArray, FloatArray]:
        D, M = self.D, self.M
        Z = np.zeros_like(M)
        A = np.block([[Z, M], [-(self.K + D @ G1 @ D.T), -(self.C + D @ G2 @ D.T)]])
        return A, sla.block_diag(M, M)

    def stiffness_damping(
        self, G1: npt.ArrayLike, G2: npt.ArrayLike
    ) -> tuple[FloatArray, FloatArray]:
        """K̄ = K + D G1 Dᵀ and C̄ = C + D G2 Dᵀ (Eqs. 34-35)."""
        g1, g2 = _gain(G1, "G1", self.n_inputs), _gain(G2, "G2", self.n_inputs)
        return self.K + self.D @ g1 @ self.D.T, self.C + self.D @ g2 @ self.D.T

    def eigenvalues(self, G1: npt.ArrayLike, G2: npt.ArrayLike) -> ComplexArray:
        """All 2n closed-loop eigenvalues, by |Im λ|, then Im λ descending, then Re λ."""
        return _sorted(sla.eigvals(*self.pencil(G1, G2)))

    def modes(self, G1: npt.ArrayLike, G2: npt.ArrayLike) -> tuple[FloatArray, FloatArray]:
        """(ω_i, ζ_iω_i) of the oscillatory modes, ascending ω (Tables 1-2 of Att. 5).

        ω = Im λ, ζ = −Re λ/|λ|, so ζω = Im λ (−Re λ)/|λ|, not −Re λ.
        """
        lam = self.eigenvalues(G1, G2)
        lam = lam[lam.imag > 0]
        return lam.imag, lam.imag * -lam.real / np.abs(lam)

    def condition_number(
        self, G1: npt.ArrayLike, G2: npt.ArrayLike, *, gap_rtol: float = GAP_RTOL
    ) -> float:
        """κ(Φ) = σ_max/σ_min of the closed-loop modal matrix, φ_iᵀ B φ_i = 1 (Eqs. 40-41, 46).

        Plain (non-conjugate) transpose normalisation, which reproduces Att. 5 Tables 1-2
        (9.4903, 8.1291). Raises ValueError for repeated (defective) eigenvalues.
        """
        _, phi, _ = eigensolve(*self.pencil(G1, G2), gap_rtol=gap_rtol)
        return float(np.linalg.cond(phi))

    def undamped_frequencies(self) -> FloatArray:
        """Zero-gain undamped natural frequencies √eig(K, M), rad/s, ascending."""
        w2 = sla.eigvals(self.K, self.M).real
        return np.sqrt(np.clip(np.sort(w2), 0.0, None))

    # -- sensitivities ----------------------------------------------------------------------
    def pencil_derivatives(self, p: npt.ArrayLike) -> tuple[FloatArray, FloatArray]:
        """∂A/∂p_k (P, 2n, 2n) and ∂²A/∂p_k∂p_l (P, P, 2n, 2n); B does not depend on p."""
        dG1, dG2, d2G1, d2G2 = cholesky_gain_derivatives(p, self.n_inputs)
        n, D = self.n_dof, self.D
        P = dG1.shape[0]
        dA = np.zeros((P, 2 * n, 2 * n))
        dA[:, n:, :n] = -np.einsum("ia,kab,jb->kij", D, dG1, D)
        dA[:, n:, n:] = -np.einsum("ia,kab,jb->kij", D, dG2, D)
        d2A = np.zeros((P, P, 2 * n, 2 * n))
        d2A[:, :, n:, :n] = -np.einsum("ia,klab,jb->klij", D, d2G1, D)
        d2A[:, :, n:, n:] = -np.einsum("ia,klab,jb->klij", D, d2G2, D)
        return dA, d2A

    def sensitivity(
        self, p: npt.ArrayLike, *, order: int = 1, gap_rtol: float = GAP_RTOL, strict: bool = True
    ) -> FeedbackSensitivity:
        """κ and the mode frequencies/decay rates at p with their analytic derivatives.

        Chain of Att. 5: ∂A/∂p from Eqs. 30-35, eigenvector derivatives (Eqs. 42-44), then
        SVD sensitivities of Φ (Eqs. 15, 27).

        Parameters
        ----------
        p : (m(m + 1),) array_like
            Cholesky parameters.
        order : {1, 2}
            2 adds the Hessian of κ.
        gap_rtol : float
            Relative gap below which eigenvalues or singular values count as repeated.
        strict : bool
            When σ_max or σ_min of the modal matrix is repeated, κ is not differentiable: raise
            ValueError (default), or, with ``strict=False``, return NaN for its gradient (and
            Hessian) while keeping κ and the eigenvalue derivatives (the optimizer then treats
            the point as a failed step).

        Raises
        ------
        ValueError
            Bad p, repeated closed-loop eigenvalues, or (``strict``) a repeated extreme singular
            value.
        """
        flat = _params(p, self.n_inputs)
        A, B = self._pencil(*self.gains(flat))
        dA, second = self.pencil_derivatives(flat)
        d2A = second if order == 2 else None
        try:
            out = eigenvector_condition_derivatives(
                A, dA, B, None, d2A, None, order=order, gap_rtol=gap_rtol
            )
            if len(out) == 4:  # order 2
                kappa, grad, hess, eig = out
            else:
                kappa, grad, eig = out
                hess = None
        except ValueError as exc:
            if strict or not str(exc).startswith("singular values"):
                raise
            eig = eig_derivatives(A, dA, B, None, d2A, None, order=order, gap_rtol=gap_rtol)
            kappa = float(np.linalg.cond(eig.right))
            grad = np.full(flat.size, np.nan)
            hess = np.full((flat.size, flat.size), np.nan) if order == 2 else None
        lam = eig.eigenvalues
        upper = np.flatnonzero(lam.imag > 0)
        upper = upper[np.argsort(lam.imag[upper])]
        lu = lam[upper]
        dl = eig.eigenvalue_gradient[:, upper].T  # (modes, P)
        x, y, r = lu.real, lu.imag, np.abs(lu)
        zw = y * -x / r
        # ∂(−x y/r) = (−y³ ∂x − x³ ∂y) / r³
        dzw = (-(y**3)[:, None] * dl.real - (x**3)[:, None] * dl.imag) / (r**3)[:, None]
        return FeedbackSensitivity(kappa, grad, hess, y, zw, dl.imag.copy(), dzw, _sorted(lam))


def _sorted(lam: ComplexArray) -> ComplexArray:
    """By |Im λ| (conjugates together despite rounding), then Im λ > 0 first, then Re λ."""
    scale = max(float(np.abs(lam).max()), np.finfo(float).tiny)
    return lam[np.lexsort((lam.real, -lam.imag, np.round(np.abs(lam.imag) / scale, 10)))]


# -- minimum-sensitivity design, Att. 5 Eqs. 46-49 + Appendix ----------------------------------
@dataclass(frozen=True)
class FeedbackDesign:
    """Result of :func:`design_minimum_sensitivity`.

    Attributes
    ----------
    G1, G2 : (m, m) ndarray
        Designed gains.
    parameters : (P,) ndarray
        Their Cholesky parameters.
    condition_number : float
    omega, zeta_omega : ndarray
        Closed-loop (ω_i, ζ_iω_i) of all oscillatory modes.
    result : HomotopyResult
        The optimizer's record (path, active set, messages).
    """

    G1: FloatArray
    G2: FloatArray
    parameters: FloatArray
    condition_number: float
    omega: FloatArray
    zeta_omega: FloatArray
    result: HomotopyResult


def _mode_map(value: Mapping[int, float] | None, field: str) -> dict[int, float]:
    if value is None:
        return {}
    if not isinstance(value, dict):
        raise FieldError(
            field, f"must be a mapping {{mode number (0-based): value}}, got {type(value).__name__}"
        )
    out = {}
    for key, val in value.items():
        if isinstance(key, bool) or not isinstance(key, (int, np.integer)) or key < 0:
            raise FieldError(field, f"mode numbers must be integers >= 0, got {key!r}")
        out[int(key)] = float(require_finite(val, f"{field}[{key}]"))
    return out


def design_minimum_sensitivity(
    plant: SymmetricOutputFeedback,
    *,
    frequencies: Mapping[int, float] | None = None,
    decay_bounds: Mapping[int, float] | None = None,
    start: tuple[npt.ArrayLike, npt.ArrayLike] | None = None,
    order: int = 1,
    **options: Any,
) -> FeedbackDesign:
    """Minimise the closed-loop modal condition number over symmetric gains (Att. 5 Eqs. 46-49).

    Objective κ(Φ) (Eq. 46) with analytic gradient; equality constraints ω_i(p) = ω_i0 (Eq. 48)
    and inequalities ω_iζ_i(p) >= T_i (Eq. 49); solved with :func:`homotopy_minimize` from the
    start gains (default G1 = G2 = I, as in the paper).

    Parameters
    ----------
    plant : SymmetricOutputFeedback
    frequencies : dict {mode: ω_target}, optional
        Oscillatory closed-loop modes (0-based, ascending ω) whose ω = Im λ is prescribed.
    decay_bounds : dict {mode: T}, optional
        Lower bounds on ζω = Im λ (−Re λ)/|λ|.
    start : (G1, G2), optional
        Positive definite start gains; default identities.
    order : {1, 2}
        Passed to the sensitivity chain (2 also evaluates the Hessian, for checking only).
    **options
        Passed to :func:`homotopy_minimize` (``gamma_step``, ``min_gamma_step``, ``max_steps``,
        ``weight``, ``tol``…). For large, stiff models the computed eigenvalues carry noise of
        order eps·‖B⁻¹A‖ (about 1e-9 rad/s for the 42-state Draper/RPL model); raise ``tol``
        above it (e.g. 1e-7) or the corrections cannot converge.

    Notes
    -----
    Minimising a ratio of extreme singular values tends to make σ_min (or σ_max) coalesce,
    where κ is not differentiable (the SVD formulas need distinct values). Such points are
    treated as failed steps, so the objective homotopy stops near them.

    Returns
    -------
    FeedbackDesign

    Examples
    --------
    Example 1 of Att. 5:

    >>> plant = SymmetricOutputFeedback.example1()
    >>> w = plant.undamped_frequencies()
    >>> design = design_minimum_sensitivity(plant, frequencies={0: w[0], 1: w[1]},
    ...                                     decay_bounds={0: 0.3, 1: 0.3})  # doctest: +SKIP
    """
    if not isinstance(plant, SymmetricOutputFeedback):
        raise FieldError("plant", f"must be a SymmetricOutputFeedback, got {type(plant).__name__}")
    freq = _mode_map(frequencies, "frequencies")
    decay = _mode_map(decay_bounds, "decay_bounds")
    m = plant.n_inputs
    if start is None:
        start = (np.eye(m), np.eye(m))
    if not isinstance(start, (tuple, list)) or len(start) != 2:
        raise FieldError(
            "start", f"must be a pair (G1, G2) of {m}x{m} gains, got {type(start).__name__}"
        )
    G1s, G2s = start
    p0 = plant.parameters(G1s, G2s)
    f_modes, f_targets = list(freq), np.array(list(freq.values()))
    d_modes, d_bounds = list(decay), np.array(list(decay.values()))
    needed = max(f_modes + d_modes, default=-1) + 1
    cache: dict[bytes, FeedbackSensitivity] = {}

    def sens(p: FloatArray) -> FeedbackSensitivity:
        key = np.asarray(p, float).tobytes()
        if key not in cache:
            if len(cache) > 32:
                cache.clear()
            s = plant.sensitivity(p, order=order, strict=False)
            if s.omega.size < needed:
                raise FieldError(
                    "frequencies",
                    f"the closed loop has only {s.omega.size} "
                    f"oscillatory modes, the constraints need {needed}",
                )
            cache[key] = s
        return cache[key]

    kw: dict[str, Any] = dict(gradient=lambda p: sens(p).gradient)
    if f_modes:
        kw.update(
            equality=lambda p: sens(p).omega[f_modes],
            equality_target=f_targets,
            equality_jacobian=lambda p: sens(p).omega_gradient[f_modes],
        )
    if d_modes:
        kw.update(
            inequality=lambda p: sens(p).zeta_omega[d_modes],
            inequality_bound=d_bounds,
            inequality_jacobian=lambda p: sens(p).zeta_omega_gradient[d_modes],
        )
    result = homotopy_minimize(lambda p: sens(p).condition_number, p0, **kw, **options)
    G1, G2 = plant.gains(result.p)
    s = plant.sensitivity(result.p, strict=False)
    return FeedbackDesign(
        G1, G2, result.p.copy(), s.condition_number, s.omega, s.zeta_omega, result
    )


__all__ = [
    "EXAMPLE1",
    "SOURCE",
    "FeedbackDesign",
    "FeedbackSensitivity",
    "SymmetricOutputFeedback",
    "cholesky_gain_derivatives",
    "cholesky_gains",
    "cholesky_parameters",
    "design_minimum_sensitivity",
    "n_parameters",
]
