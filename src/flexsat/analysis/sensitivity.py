"""Eigenvalue, eigenvector and singular-value sensitivities, first and second order.

Source: Junkins & Kim, *First and Second Order Sensitivity of the Singular Value Decomposition*,
J. Astronautical Sciences 38(1), 1990 (Att. 5 of Junkins, Pollock & Rahman 1990).

Three groups of functions, all vectorised over the parameters p_1 … p_P:

- :func:`eig_derivatives`: the non-symmetric generalized problem A φ = λ B φ of Att. 5
  Eqs. 40-44 (the first-order form of a closed loop, B ż = A z). Method: **modal expansion with
  the adjoint (left) eigenvectors** of Lim, Junkins & Wang (1987) as printed in Att. 5 Eqs. 42-43,
  ∂φ_i/∂p_k = Σ_j c^k_ji φ_j. It is exact because the complete set of n eigenvectors is used. The
  normalisation is the paper's plain-transpose φ_iᵀ B φ_i = 1 with ψ_jᵀ B φ_i = δ_ij (Eqs. 40-41).
  Second order (Eq. 44, ∂²Φ/∂p_k∂p_l = Φ_l C^k + Φ ∂C^k/∂p_l) is written here as
  ∂²Φ/∂p_k∂p_l = Φ Y^{kl} with Y^{kl} solved in the same eigenbasis (see the function notes).
- :func:`modal_derivatives`: the symmetric generalized problem K φ = ω² M φ of a modal model
  (φᵀ M φ = 1), by **Nelson's method** (Nelson 1976), which needs only the modes asked for.
- :func:`svd_derivatives` and :func:`condition_number_derivatives`: singular values and vectors
  of a (complex) matrix Φ(p), Att. 5 Eqs. 15, 17-23 and the second-order Eq. 27 with the
  subscripts corrected (the print has U_jᴴ Φ V_j for U_jᴴ Φ V_i), and the 2-norm condition
  number κ = σ_1/σ_n (Eq. 46) built from them. :func:`eigenvector_condition_derivatives`
  chains the two (Att. 5 §"performance index": SVD sensitivity of the modal matrix, then
  eigenvector derivatives).

All results hold for **distinct** eigenvalues (non-defective problems) and **distinct, non-zero**
singular values only; coincident ones raise :class:`ValueError` naming the indices. Derivative
stacks have the parameter index first: ``dA[k] = ∂A/∂p_k`` of shape ``(P, n, n)`` and
``d2A[k, l] = ∂²A/∂p_k∂p_l`` of shape ``(P, P, n, n)``; a single ``(n, n)`` derivative is read as
P = 1. Every returned gradient keeps the leading parameter axis.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from flexsat.input_checks import FieldError
from flexsat.units import FloatArray

_EPS = np.finfo(float).eps

#: default relative gap below which two eigenvalues / singular values count as repeated
GAP_RTOL = 1e-10

ComplexArray = npt.NDArray[np.complex128]
IntArray = npt.NDArray[np.int_]
#: a real or complex array (the singular vectors of a real or a complex matrix)
InexactArray = npt.NDArray[np.inexact[Any]]
#: κ and its gradient, and with ``order=2`` its Hessian
ConditionDerivatives = tuple[float, FloatArray] | tuple[float, FloatArray, FloatArray]


# -- input checks ------------------------------------------------------------------------------
def _refuse_complex(value: npt.ArrayLike, field: str, allow_complex: bool) -> None:
    if allow_complex:
        return
    try:
        probe = np.asarray(value)
    except (TypeError, ValueError):
        return
    if np.iscomplexobj(probe) and np.any(probe.imag):
        raise FieldError(field, "must be real (the symmetric modal problem), got complex values")


def _matrix(
    value: npt.ArrayLike, field: str, *, square: bool = True, allow_complex: bool = True
) -> npt.NDArray[Any]:
    if isinstance(value, (str, bytes)):
        raise FieldError(field, f"must be a numeric matrix, got the string {value!r}")
    _refuse_complex(value, field, allow_complex)
    try:
        arr = np.array(value, dtype=complex if allow_complex else float)
    except (TypeError, ValueError):
        kind = "numeric" if allow_complex else "real"
        raise FieldError(field, f"must be a {kind} matrix, got {type(value).__name__}") from None
    if arr.ndim != 2 or arr.size == 0:
        raise FieldError(field, f"must be a non-empty 2-D matrix, got shape {arr.shape}")
    if square and arr.shape[0] != arr.shape[1]:
        raise FieldError(field, f"must be square, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise FieldError(field, "must be finite (no NaN or inf)")
    if allow_complex and not np.any(arr.imag):
        arr = arr.real.copy()
    return arr


def _stack(
    value: npt.ArrayLike,
    field: str,
    shape: tuple[int, ...],
    n_params: int | None = None,
    *,
    second: bool = False,
    allow_complex: bool = True,
) -> npt.NDArray[Any]:
    """A derivative stack of shape (P, *shape), or (P, P, *shape) when ``second``."""
    if isinstance(value, (str, bytes)):
        raise FieldError(field, f"must be a numeric array, got the string {value!r}")
    _refuse_complex(value, field, allow_complex)
    try:
        arr = np.array(value, dtype=complex if allow_complex else float)
    except (TypeError, ValueError):
        raise FieldError(field, f"must be a numeric array, got {type(value).__name__}") from None
    lead = 2 if second else 1
    if arr.shape == shape and not second:
        arr = arr[None]
    if arr.ndim != len(shape) + lead or arr.shape[lead:] != shape:
        want = ("(P, P, " if second else "(P, ") + ", ".join(map(str, shape)) + ")"
        raise FieldError(field, f"must have shape {want}, got {arr.shape}")
    if second and arr.shape[0] != arr.shape[1]:
        raise FieldError(field, f"the two parameter axes must agree, got shape {arr.shape}")
    if n_params is not None and arr.shape[0] != n_params:
        raise FieldError(
            field, f"expected {n_params} parameters along the first axis, got {arr.shape[0]}"
        )
    if arr.shape[0] == 0:
        raise FieldError(field, f"needs at least one parameter, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise FieldError(field, "must be finite (no NaN or inf)")
    if allow_complex and not np.any(arr.imag):
        arr = arr.real.copy()
    return arr


def _order(order: object) -> int:
    if isinstance(order, bool) or order not in (1, 2):
        raise FieldError("order", f"must be 1 or 2, got {order!r}")
    return int(order)


def _gap_rtol(value: Any) -> float:
    try:
        value = float(value)
    except (TypeError, ValueError):
        raise FieldError("gap_rtol", f"must be a number, got {value!r}") from None
    if not (np.isfinite(value) and value >= 0):
        raise FieldError("gap_rtol", f"must be finite and >= 0, got {value!r}")
    return value


def _check_distinct(
    values: npt.NDArray[Any],
    scale: float,
    gap_rtol: float,
    what: str,
    select: npt.NDArray[Any] | None = None,
) -> None:
    """Raise if two of ``values`` (or one of ``select`` and any other) are within the gap."""
    n = values.size
    diff = np.abs(values[:, None] - values[None, :])
    diff[np.arange(n), np.arange(n)] = np.inf
    if select is not None:
        diff = diff[select]
        rows = np.asarray(select)
    else:
        rows = np.arange(n)
    tol = gap_rtol * scale
    hit = np.argwhere(diff <= tol)
    if hit.size:
        i, j = int(rows[hit[0, 0]]), int(hit[0, 1])
        i, j = min(i, j), max(i, j)
        raise FieldError(
            what,
            f"{what[:-1] if what.endswith('s') else what} {i} and {j} are repeated "
            f"({values[i]:.6g} and {values[j]:.6g}, gap {abs(values[i] - values[j]):.3g} <= "
            f"{tol:.3g} = gap_rtol x scale); their derivatives are undefined (the formulas divide "
            f"by the gap)",
        )


# -- non-symmetric generalized eigenproblem, Att. 5 Eqs. 40-44 ---------------------------------
@dataclass(frozen=True)
class EigenDerivatives:
    """Eigen-solution of A φ = λ B φ and its parameter derivatives (Att. 5 Eqs. 40-44).

    Attributes
    ----------
    eigenvalues : (n,) complex
        λ_i, in the order LAPACK returns them (sort with the same index array everywhere).
    right : (n, n) complex
        Φ, columns φ_i with the plain-transpose normalisation φ_iᵀ B φ_i = 1 (Eq. 41).
    left : (n, n) complex
        Ψ with Ψᵀ B Φ = I and Ψᵀ A Φ = diag λ (Eq. 41); Aᵀ ψ_i = λ_i Bᵀ ψ_i (Eq. 40).
    eigenvalue_gradient : (P, n) complex
        ∂λ_i/∂p_k = ψ_iᵀ (A_k − λ_i B_k) φ_i (Eq. 42).
    coefficients : (P, n, n) complex
        C^k with ∂Φ/∂p_k = Φ C^k, i.e. c^k_ji of Eq. 43.
    right_gradient : (P, n, n) complex
        ∂Φ/∂p_k.
    left_coefficients, left_gradient : (P, n, n) complex
        D^k with ∂Ψ/∂p_k = Ψ D^k (d^k_ji of Eq. 43) and ∂Ψ/∂p_k.
    eigenvalue_hessian : (P, P, n) complex or None
        ∂²λ_i/∂p_k∂p_l (``order=2``).
    right_hessian : (P, P, n, n) complex or None
        ∂²Φ/∂p_k∂p_l (``order=2``, Eq. 44).
    """

    eigenvalues: ComplexArray
    right: ComplexArray
    left: ComplexArray
    eigenvalue_gradient: ComplexArray
    coefficients: ComplexArray
    right_gradient: ComplexArray
    left_coefficients: ComplexArray
    left_gradient: ComplexArray
    eigenvalue_hessian: ComplexArray | None = None
    right_hessian: ComplexArray | None = None


def _selection(value: npt.ArrayLike | None, count: int, field: str, what: str) -> npt.NDArray[Any]:
    """Indices 0 … count − 1 picked by ``value`` (all of them for None), checked."""
    if value is None:
        return np.arange(count)
    sel = np.atleast_1d(np.asarray(value))
    if sel.dtype.kind not in "iu" or sel.ndim != 1 or sel.size == 0:
        raise FieldError(field, f"must be {what}, got {value!r}")
    if np.any(sel < 0) or np.any(sel >= count):
        raise FieldError(field, f"must lie in 0 … {count - 1}, got {value!r}")
    return sel


def eigensolve(
    A: npt.ArrayLike, B: npt.ArrayLike | None = None, *, gap_rtol: float = GAP_RTOL
) -> tuple[ComplexArray, ComplexArray, ComplexArray]:
    """Eigenvalues and normalised right/left eigenvectors of A φ = λ B φ (Att. 5 Eqs. 40-41).

    Parameters
    ----------
    A : (n, n) array_like, real or complex
    B : (n, n) array_like, optional
        Non-singular; default identity.
    gap_rtol : float
        Two eigenvalues closer than ``gap_rtol · max|λ|`` are "repeated".

    Returns
    -------
    lam : (n,) complex
    Phi : (n, n) complex
        φ_iᵀ B φ_i = 1 (plain transpose, not conjugate: the convention that reproduces the
        Att. 5 condition numbers 9.4903 and 8.1291).
    Psi : (n, n) complex
        Ψᵀ B Φ = I, hence Ψᵀ A Φ = diag λ.

    Raises
    ------
    ValueError
        Bad shapes or values, singular B, repeated eigenvalues (a repeated or defective
        eigenvalue has no differentiable eigenvector), or an eigenvector with φᵀ B φ = 0, which
        the plain-transpose normalisation cannot scale.
    """
    A = _matrix(A, "A")
    n = A.shape[0]
    B = np.eye(n) if B is None else _matrix(B, "B")
    if B.shape != A.shape:
        raise FieldError("B", f"must have the shape of A {A.shape}, got {B.shape}")
    return _eigensolve(A, B, _gap_rtol(gap_rtol))


def _eigensolve(
    A: npt.NDArray[Any], B: npt.NDArray[Any], gap_rtol: float
) -> tuple[ComplexArray, ComplexArray, ComplexArray]:
    n = A.shape[0]
    if np.linalg.cond(B) > 1.0 / (n * _EPS):
        raise FieldError("B", "must be non-singular (a singular B gives infinite eigenvalues)")
    lam, phi = sla.eig(A, B)
    scale = max(float(np.abs(lam).max()), float(np.finfo(float).tiny))
    _check_distinct(lam, scale, gap_rtol, "eigenvalues")
    norm2 = np.einsum("ji,jk,ki->i", phi, B, phi)
    size = np.linalg.norm(B, 2) * np.sum(np.abs(phi) ** 2, axis=0)
    bad = np.abs(norm2) <= 1e3 * _EPS * size
    if np.any(bad):
        i = int(np.flatnonzero(bad)[0])
        raise FieldError(
            "eigenvalues",
            f"eigenvector {i} (λ = {lam[i]:.6g}) has φᵀBφ ≈ 0, so the "
            "plain-transpose normalisation φᵀBφ = 1 of Att. 5 Eq. 41 is impossible",
        )
    phi = phi / np.sqrt(norm2)
    psi = np.linalg.inv(B @ phi).T  # Ψᵀ B Φ = I
    return lam, phi, psi


def eig_derivatives(
    A: npt.ArrayLike,
    dA: npt.ArrayLike,
    B: npt.ArrayLike | None = None,
    dB: npt.ArrayLike | None = None,
    d2A: npt.ArrayLike | None = None,
    d2B: npt.ArrayLike | None = None,
    *,
    order: int = 1,
    gap_rtol: float = GAP_RTOL,
) -> EigenDerivatives:
    """Eigenvalue and eigenvector derivatives of A(p) φ = λ B(p) φ (Att. 5 Eqs. 40-44).

    Modal expansion with the adjoint eigenvectors (Lim, Junkins & Wang 1987; Att. 5 Eqs. 42-43),
    exact because all n eigenvectors are used:

    - ∂λ_i/∂p_k = ψ_iᵀ (A_k − λ_i B_k) φ_i                                   (Eq. 42)
    - ∂φ_i/∂p_k = Σ_j c^k_ji φ_j,  c^k_ji = ψ_jᵀ (A_k − λ_i B_k) φ_i / (λ_i − λ_j)  (j ≠ i)
    - c^k_ii = −[φ_iᵀ B_k φ_i + Σ_{l≠i} c^k_li φ_lᵀ (B + Bᵀ) φ_i] / φ_iᵀ(B + Bᵀ)φ_i, the
      derivative of φ_iᵀ B φ_i = 1 (Eq. 43; the denominator is 2, hence "−½")
    - ∂ψ_i/∂p_k = Σ_j d^k_ji ψ_j,  d^k_ji = ψ_iᵀ (A_k − λ_i B_k) φ_j / (λ_i − λ_j)  (j ≠ i),
      d^k_ii = −ψ_iᵀ B_k φ_i − c^k_ii (Eq. 43, with the index order of the "standard
      form", confirmed by finite differences)

    Second order (``order=2``, Eq. 44): write ∂²Φ/∂p_k∂p_l = Φ Y (so Y = C^l C^k + ∂C^k/∂p_l).
    Differentiating A_k Φ + A Φ C^k = B_k Φ Λ + B Φ C^k Λ + B Φ Λ_k and pre-multiplying by Ψᵀ
    gives Λ Y − Y Λ + R = Λ_kl with

        R = a_kl + a_k C^l + a_l C^k − b_kl Λ − b_k C^l Λ − b_l C^k Λ − b_k Λ_l − b_l Λ_k
            − C^k Λ_l − C^l Λ_k,          a_• = Ψᵀ A_• Φ,  b_• = Ψᵀ B_• Φ,

    so ∂²λ_i/∂p_k∂p_l = R_ii, Y_ji = R_ji / (λ_i − λ_j) (j ≠ i), and Y_ii follows from the
    second derivative of φ_iᵀ B φ_i = 1.

    Parameters
    ----------
    A : (n, n) array_like
    dA : (P, n, n) or (n, n) array_like
        ∂A/∂p_k.
    B : (n, n) array_like, optional
        Default identity (standard problem).
    dB : (P, n, n) array_like, optional
        ∂B/∂p_k; default zero.
    d2A, d2B : (P, P, n, n) array_like, optional
        Second derivatives (``order=2`` only); default zero (A, B affine in p).
    order : {1, 2}
    gap_rtol : float
        Relative eigenvalue gap (× max|λ|) below which eigenvalues count as repeated.

    Returns
    -------
    EigenDerivatives

    Raises
    ------
    ValueError
        Shapes, non-finite values, singular B, repeated (or defective) eigenvalues, φᵀBφ = 0.
    """
    order = _order(order)
    A = _matrix(A, "A")
    n = A.shape[0]
    B = np.eye(n) if B is None else _matrix(B, "B")
    if B.shape != A.shape:
        raise FieldError("B", f"must have the shape of A {A.shape}, got {B.shape}")
    dA = _stack(dA, "dA", (n, n))
    P = dA.shape[0]
    dB = None if dB is None else _stack(dB, "dB", (n, n), P)
    if order == 1 and (d2A is not None or d2B is not None):
        raise FieldError("d2A", "second derivatives are used only with order=2")
    d2A = None if d2A is None else _stack(d2A, "d2A", (n, n), P, second=True)
    d2B = None if d2B is None else _stack(d2B, "d2B", (n, n), P, second=True)
    lam, phi, psi = _eigensolve(A, B, _gap_rtol(gap_rtol))

    # a_k = Ψᵀ A_k Φ, b_k = Ψᵀ B_k Φ; F_k = a_k − b_k Λ (column i scaled by λ_i)
    a = np.einsum("ji,pjk,kl->pil", psi, dA, phi)
    b = None if dB is None else np.einsum("ji,pjk,kl->pil", psi, dB, phi)
    F = a if b is None else a - b * lam[None, None, :]
    dlam = np.einsum("pii->pi", F).copy()
    denom = lam[None, :] - lam[:, None]  # [j, i] = λ_i − λ_j
    np.fill_diagonal(denom, 1.0)
    C = F / denom
    idx = np.arange(n)
    C[:, idx, idx] = 0.0
    S = phi.T @ (B + B.T) @ phi  # S_li = φ_lᵀ (B + Bᵀ) φ_i
    s_diag = np.diag(S)
    nb = 0.0 if dB is None else np.einsum("ji,pjk,ki->pi", phi, dB, phi)
    C[:, idx, idx] = -(nb + np.einsum("pli,li->pi", C, S)) / s_diag
    dphi = np.einsum("ij,pjk->pik", phi, C)

    # left eigenvectors: D^k_ji = F^k_ij ... with F_ij = ψ_iᵀ(A_k − λ_i B_k)φ_j
    Fl = a if b is None else a - b * lam[None, :, None]
    Dk = Fl.transpose(0, 2, 1) / denom
    Dk[:, idx, idx] = 0.0
    bdiag = 0.0 if b is None else np.einsum("pii->pi", b)
    Dk[:, idx, idx] = -bdiag - C[:, idx, idx]
    dpsi = np.einsum("ij,pjk->pik", psi, Dk)

    hess_lam = hess_phi = None
    if order == 2:
        hess_lam, hess_phi = _second_order(lam, phi, psi, B, a, b, C, dlam, S, dB, d2A, d2B, denom)
    return EigenDerivatives(lam, phi, psi, dlam, C, dphi, Dk, dpsi, hess_lam, hess_phi)


def _second_order(
    lam: ComplexArray,
    phi: ComplexArray,
    psi: ComplexArray,
    B: npt.NDArray[Any],
    a: npt.NDArray[Any],
    b: npt.NDArray[Any] | None,
    C: ComplexArray,
    dlam: ComplexArray,
    S: npt.NDArray[Any],
    dB: npt.NDArray[Any] | None,
    d2A: npt.NDArray[Any] | None,
    d2B: npt.NDArray[Any] | None,
    denom: npt.NDArray[Any],
) -> tuple[ComplexArray, ComplexArray]:
    n = lam.size
    idx = np.arange(n)
    # R[k, l] (see eig_derivatives); Λ as a column scaling: X Λ = X * lam[None, :]
    aC = np.einsum("kij,ljm->klim", a, C)  # a_k C^l
    R = aC + aC.transpose(1, 0, 2, 3)  # a_k C^l + a_l C^k
    if d2A is not None:
        R = R + np.einsum("ji,kljm,mn->klin", psi, d2A, phi)
    if b is not None:
        bC = np.einsum("kij,ljm->klim", b, C)  # b_k C^l
        R = R - (bC + bC.transpose(1, 0, 2, 3)) * lam
        R = R - (b[:, None] * dlam[None, :, None, :] + b[None, :] * dlam[:, None, None, :])
    if d2B is not None:
        R = R - np.einsum("ji,kljm,mn->klin", psi, d2B, phi) * lam
    R = R - (C[:, None] * dlam[None, :, None, :] + C[None, :] * dlam[:, None, None, :])
    hess_lam = np.einsum("klii->kli", R).copy()
    Y = R / denom
    Y[:, :, idx, idx] = 0.0
    # Y_ii from ∂²(φ_iᵀ B φ_i)/∂p_k∂p_l = 0:
    #   Σ_j Y_ji S_ji + (C^kᵀ S C^l)_ii + (C^kᵀ s_l)_ii + (C^lᵀ s_k)_ii + φ_iᵀ B_kl φ_i = 0
    rest = np.einsum("kji,jm,lmi->kli", C, S, C)
    if dB is not None:
        s = np.einsum("ji,pjk,kl->pil", phi, dB + dB.transpose(0, 2, 1), phi)
        cs = np.einsum("kji,lji->kli", C, s)  # (C^kᵀ s_l)_ii
        rest = rest + cs + cs.transpose(1, 0, 2)
    if d2B is not None:
        rest = rest + np.einsum("ji,kljm,mi->kli", phi, d2B, phi)
    Y[:, :, idx, idx] = -(np.einsum("klji,ji->kli", Y, S) + rest) / np.diag(S)
    hess_phi = np.einsum("ij,kljm->klim", phi, Y)
    return hess_lam, hess_phi


# -- symmetric generalized eigenproblem (modal models), Nelson's method ------------------------
@dataclass(frozen=True)
class ModalDerivatives:
    """Modes of K φ = ω² M φ (φᵀ M φ = 1) and their derivatives (Nelson's method).

    Attributes
    ----------
    eigenvalues : (s,) float
        ω_i² of the selected modes.
    frequencies : (s,) float
        ω_i, rad/s (0 for a rigid mode, ω² <= gap_rtol · max ω²).
    modes : (n, s) float
        Mass-normalised φ_i.
    eigenvalue_gradient : (P, s) float
        ∂(ω_i²)/∂p_k = φ_iᵀ (K_k − ω_i² M_k) φ_i.
    frequency_gradient : (P, s) float
        ∂ω_i/∂p_k = ∂(ω_i²)/∂p_k / (2 ω_i); NaN for a rigid mode (ω = 0 is not differentiable).
    mode_gradient : (P, n, s) float
        ∂φ_i/∂p_k, keeping φᵀ M φ = 1.
    indices : (s,) int
        Mode numbers (ascending ω²) of the columns.
    """

    eigenvalues: FloatArray
    frequencies: FloatArray
    modes: FloatArray
    eigenvalue_gradient: FloatArray
    frequency_gradient: FloatArray
    mode_gradient: FloatArray
    indices: IntArray


def modal_derivatives(
    K: npt.ArrayLike,
    M: npt.ArrayLike,
    dK: npt.ArrayLike,
    dM: npt.ArrayLike | None = None,
    modes: Sequence[int] | npt.ArrayLike | None = None,
    *,
    gap_rtol: float = GAP_RTOL,
) -> ModalDerivatives:
    """Natural-frequency and mode-shape derivatives of K(p) φ = ω² M(p) φ, Nelson's method.

    For each selected mode (λ = ω², φᵀ M φ = 1) and parameter p_k:

    - ∂λ/∂p_k = φᵀ (K_k − λ M_k) φ;
    - (K − λ M) v = −(K_k − λ M_k − ∂λ/∂p_k M) φ, solved with the entry of v at the largest
      |φ_r| fixed to zero (the reduced matrix is non-singular for a simple eigenvalue);
    - ∂φ/∂p_k = v + c φ,  c = −φᵀ M v − ½ φᵀ M_k φ (from ∂(φᵀMφ)/∂p_k = 0).

    This is the symmetric special case of Att. 5 Eqs. 42-43 (ψ = φ, B = M) without the need
    for the complete modal basis; a single rigid mode (ω = 0) is allowed, repeated frequencies
    are not.

    Parameters
    ----------
    K : (n, n) array_like
        Symmetric stiffness (positive semidefinite).
    M : (n, n) array_like
        Symmetric positive definite mass.
    dK : (P, n, n) or (n, n) array_like
        ∂K/∂p_k (symmetric).
    dM : (P, n, n) array_like, optional
        ∂M/∂p_k; default zero.
    modes : int or sequence of int, optional
        Mode numbers (0-based, ascending ω²); default all.
    gap_rtol : float
        Relative gap (× max ω²) below which two ω² count as repeated.

    Returns
    -------
    ModalDerivatives
    """
    K = _matrix(K, "K", allow_complex=False)
    n = K.shape[0]
    M = _matrix(M, "M", allow_complex=False)
    if M.shape != K.shape:
        raise FieldError("M", f"must have the shape of K {K.shape}, got {M.shape}")
    for name, mat in (("K", K), ("M", M)):
        if not np.allclose(mat, mat.T, rtol=1e-10, atol=1e-12 * np.abs(mat).max()):
            raise FieldError(name, "must be symmetric")
    dK = _stack(dK, "dK", (n, n), allow_complex=False)
    P = dK.shape[0]
    dM = np.zeros_like(dK) if dM is None else _stack(dM, "dM", (n, n), P, allow_complex=False)
    gap_rtol = _gap_rtol(gap_rtol)
    try:
        lam_all, phi_all = sla.eigh(K, M)
    except np.linalg.LinAlgError:
        raise FieldError("M", "must be positive definite") from None
    sel = _selection(modes, n, "modes", "mode numbers (integers)")
    scale = max(float(np.abs(lam_all).max()), float(np.finfo(float).tiny))
    _check_distinct(lam_all, scale, gap_rtol, "eigenvalues", select=sel)
    lam, phi = lam_all[sel], phi_all[:, sel]
    dlam, dphi = nelson_derivatives(K, M, dK, dM, lam, phi)
    rigid = lam <= gap_rtol * scale
    omega = np.where(rigid, 0.0, np.sqrt(np.clip(lam, 0.0, None)))
    domega = np.where(rigid, np.nan, dlam / (2.0 * np.where(rigid, 1.0, omega)))
    return ModalDerivatives(lam, omega, phi, dlam, domega, dphi, sel)


def nelson_derivatives(
    K: Any,
    M: Any,
    dK: Sequence[Any] | npt.NDArray[Any],
    dM: Sequence[Any] | npt.NDArray[Any],
    eigenvalues: npt.ArrayLike,
    modes: npt.ArrayLike,
) -> tuple[FloatArray, FloatArray]:
    """Nelson's method for given simple eigenpairs of K φ = λ M φ (φᵀ M φ = 1).

    Nelson, R. B., "Simplified calculation of eigenvector derivatives", AIAA Journal 14(9),
    1201-1205, 1976. For each mode (λ, φ) and parameter p_k, with F = (K_k − λ M_k) φ:

    - ∂λ/∂p_k = φᵀ F;
    - (K − λ M) v = −F + (∂λ/∂p_k) M φ, solved with v_r = 0 at r = argmax |φ_r| (deleting row
      and column r leaves a non-singular matrix when λ is simple);
    - ∂φ/∂p_k = v + c φ,  c = −φᵀ M v − ½ φᵀ M_k φ (from ∂(φᵀ M φ)/∂p_k = 0).

    Only the modes asked for are needed, so the pencil may be sparse and may carry massless
    dofs (K − λ M stays non-singular off φ) and other, repeated eigenvalues (the rigid-body
    modes of a free structure, λ = 0, when λ itself is elastic). The caller checks that each λ
    is simple; this function does not see the other eigenvalues.

    Parameters
    ----------
    K, M : (n, n) ndarray or scipy sparse matrix
        Symmetric.
    dK, dM : sequences of P (n, n) ndarrays or sparse matrices
        ∂K/∂p_k and ∂M/∂p_k.
    eigenvalues : (s,) array_like
        λ_i = ω_i², (rad/s)².
    modes : (n, s) array_like
        Mass-normalised φ_i.

    Returns
    -------
    eigenvalue_gradient : (P, s) ndarray
    mode_gradient : (P, n, s) ndarray
    """
    lam = np.atleast_1d(np.asarray(eigenvalues, dtype=float))
    phi = np.asarray(modes, dtype=float)
    n, s = phi.shape
    P = len(dK)
    sparse = sp.issparse(K) or sp.issparse(M)
    dlam = np.empty((P, s))
    dphi = np.empty((P, n, s))
    for col in range(s):
        f = phi[:, col]
        Mf = M @ f
        F = np.stack([dK[k] @ f - lam[col] * (dM[k] @ f) for k in range(P)])
        dlam[:, col] = F @ f
        rhs = -(F - dlam[:, col, None] * Mf)
        r = int(np.argmax(np.abs(f)))
        keep = np.delete(np.arange(n), r)
        Z = K - lam[col] * M
        v = np.zeros((P, n))
        if sparse:
            Zr = sp.csc_matrix(Z)[keep][:, keep]
            v[:, keep] = np.atleast_2d(spla.splu(sp.csc_matrix(Zr)).solve(rhs[:, keep].T).T)
        else:
            v[:, keep] = np.linalg.solve(Z[np.ix_(keep, keep)], rhs[:, keep].T).T
        c = -(v @ Mf) - 0.5 * np.array([f @ (dM[k] @ f) for k in range(P)])
        dphi[:, :, col] = v + c[:, None] * f
    return dlam, dphi


# -- singular value decomposition, Att. 5 Eqs. 15-27 -------------------------------------------
@dataclass(frozen=True)
class SVDDerivatives:
    """Singular values/vectors of Φ(p) and their derivatives (Att. 5 Eqs. 15, 17-23, 27).

    Attributes
    ----------
    singular_values : (r,) float
        All σ of Φ, descending (r = min(m, n)).
    U : (m, m) ; V : (n, n)
        Full unitary factors, Φ = U Σ Vᴴ.
    indices : (s,) int
        The singular values differentiated (default all r).
    singular_value_gradient : (P, s) float
        ∂σ_i/∂p_k = Re G^k_ii, G^k = Uᴴ Φ_k V (Eq. 15).
    U_gradient : (P, m, s) ; V_gradient : (P, n, s)
        ∂U_i/∂p_k = Σ_j a^k_ji U_j and ∂V_i/∂p_k = Σ_j b^k_ji V_j (Eqs. 17-23), in the gauge
        b_ii = 0 (V_iᴴ ∂V_i = 0), which fixes a_ii = i Im G_ii / σ_i; for real Φ both vanish.
    singular_value_hessian : (P, P, s) float or None
        ∂²σ_i/∂p_k∂p_l (corrected Eq. 27), with ``order=2``.
    """

    singular_values: FloatArray
    U: InexactArray
    V: InexactArray
    indices: IntArray
    singular_value_gradient: FloatArray
    U_gradient: InexactArray
    V_gradient: InexactArray
    singular_value_hessian: FloatArray | None = None


def svd_derivatives(
    Phi: npt.ArrayLike,
    dPhi: npt.ArrayLike,
    d2Phi: npt.ArrayLike | None = None,
    *,
    order: int = 1,
    indices: Sequence[int] | npt.ArrayLike | None = None,
    gap_rtol: float = GAP_RTOL,
) -> SVDDerivatives:
    """First- and second-order sensitivity of the SVD Φ = U Σ Vᴴ (Att. 5 Eqs. 15-27).

    With G^k ≡ Uᴴ (∂Φ/∂p_k) V (so G^k_ji = U_jᴴ Φ_k V_i) and G^{kl} ≡ Uᴴ (∂²Φ/∂p_k∂p_l) V:

    - ∂σ_i/∂p_k = Re G^k_ii                                                  (Eq. 15)
    - ∂U_i/∂p_k = Σ_j a_ji U_j, ∂V_i/∂p_k = Σ_j b_ji V_j, for j ≠ i          (Eqs. 17-23)
      a_ji = [σ_i G_ji + σ_j conj(G_ij)] / (σ_i² − σ_j²),
      b_ji = [σ_j G_ji + σ_i conj(G_ij)] / (σ_i² − σ_j²),
      and a_ii − b_ii = i Im(G_ii)/σ_i (only the difference is fixed: phase freedom; here
      b_ii = 0).
    - corrected Eq. 27 (the print has U_jᴴ Φ V_j for U_jᴴ Φ V_i):

          ∂²σ_i/∂p_k∂p_l = Re{ G^{kl}_ii + Σ_{j≠i} [σ_i (conj(G^l_ji) G^k_ji + conj(G^l_ij) G^k_ij)
                             + σ_j (G^l_ij G^k_ji + G^l_ji G^k_ij)] / (σ_i² − σ_j²) }
                           + Im(G^l_ii) Im(G^k_ii) / σ_i

    For a rectangular Φ the sums also run over the null-space columns of the larger factor
    (σ_j = 0 there), so the formulas hold unchanged with G zero-padded to a square matrix.

    Parameters
    ----------
    Phi : (m, n) array_like, real or complex
    dPhi : (P, m, n) or (m, n) array_like
    d2Phi : (P, P, m, n) array_like, optional
        ∂²Φ/∂p_k∂p_l for ``order=2``; default zero (Φ affine in p).
    order : {1, 2}
    indices : sequence of int, optional
        Which singular values (0 = largest) to differentiate; default all. Only these need to
        be distinct and non-zero.
    gap_rtol : float
        Relative gap (× σ_1) below which two singular values count as repeated.

    Returns
    -------
    SVDDerivatives

    Raises
    ------
    ValueError
        Bad shapes/values, a selected σ repeated or zero (derivatives undefined).
    """
    order = _order(order)
    Phi = _matrix(Phi, "Phi", square=False)
    m, n = Phi.shape
    dPhi = _stack(dPhi, "dPhi", (m, n))
    P = dPhi.shape[0]
    if order == 1 and d2Phi is not None:
        raise FieldError("d2Phi", "second derivatives are used only with order=2")
    d2Phi = None if d2Phi is None else _stack(d2Phi, "d2Phi", (m, n), P, second=True)
    gap_rtol = _gap_rtol(gap_rtol)
    U, sig, Vh = np.linalg.svd(Phi, full_matrices=True)
    V = Vh.conj().T
    r = sig.size
    sel = _selection(indices, r, "indices", "integers")
    big = max(m, n)
    s_pad = np.zeros(big)
    s_pad[:r] = sig
    scale = max(float(sig[0]), float(np.finfo(float).tiny))
    zero = sig[sel] <= gap_rtol * scale
    if np.any(zero):
        i = int(sel[np.flatnonzero(zero)[0]])
        raise ValueError(
            f"singular values: σ_{i} = {sig[i]:.3g} is zero (<= gap_rtol x σ_1); "
            "its derivatives are undefined"
        )
    _check_distinct(s_pad if big > r else sig, scale, gap_rtol, "singular values", select=sel)

    G = np.zeros((P, big, big), dtype=complex)
    G[:, :m, :n] = np.einsum("ji,pjk,kl->pil", U.conj(), dPhi, V)
    sigma_i = s_pad[sel]  # (s,)
    dsig = G[:, sel, sel].real.copy()
    d2 = sigma_i[None, :] ** 2 - s_pad[:, None] ** 2  # [j, c] = σ_i² − σ_j², i = sel[c]
    d2[sel, np.arange(sel.size)] = 1.0
    Gcol = G[:, :, sel]  # [p, j, c] = G_ji
    Grow = G[:, sel, :].transpose(0, 2, 1)  # [p, j, c] = G_ij
    acoef = (sigma_i * Gcol + s_pad[:, None] * Grow.conj()) / d2
    bcoef = (s_pad[:, None] * Gcol + sigma_i * Grow.conj()) / d2
    cols = np.arange(sel.size)
    acoef[:, sel, cols] = 1j * Gcol[:, sel, cols].imag / sigma_i
    bcoef[:, sel, cols] = 0.0
    dU = np.einsum("ij,pjc->pic", U, acoef[:, :m])
    dV = np.einsum("ij,pjc->pic", V, bcoef[:, :n])

    hess = None
    if order == 2:
        w = 1.0 / d2
        w[sel, cols] = 0.0
        sj = s_pad[:, None]
        terms = sigma_i * (
            np.einsum("ljc,kjc->kljc", Gcol.conj(), Gcol)
            + np.einsum("ljc,kjc->kljc", Grow.conj(), Grow)
        ) + sj * (np.einsum("ljc,kjc->kljc", Grow, Gcol) + np.einsum("ljc,kjc->kljc", Gcol, Grow))
        hess = np.einsum("kljc,jc->klc", terms, w).real
        gii = Gcol[:, sel, cols].imag  # (P, s)
        hess += gii[None, :, :] * gii[:, None, :] / sigma_i
        if d2Phi is not None:
            hess += np.einsum("mc,klmn,nc->klc", U[:, sel].conj(), d2Phi, V[:, sel]).real
    return SVDDerivatives(sig, U, V, sel, dsig, dU, dV, hess)


def condition_number_derivatives(
    Phi: npt.ArrayLike,
    dPhi: npt.ArrayLike,
    d2Phi: npt.ArrayLike | None = None,
    *,
    order: int = 1,
    gap_rtol: float = GAP_RTOL,
) -> ConditionDerivatives:
    """2-norm condition number κ = σ_1/σ_r of Φ(p) and its gradient (and Hessian).

    From Att. 5 Eq. 15 (and Eq. 27 for ``order=2``) applied to the largest and smallest singular
    values: with g_k = ∂ln κ/∂p_k = σ_1,k/σ_1 − σ_r,k/σ_r,

        ∂κ/∂p_k = κ g_k,
        ∂²κ/∂p_k∂p_l = κ [g_k g_l + σ_1,kl/σ_1 − σ_1,k σ_1,l/σ_1² − σ_r,kl/σ_r
                          + σ_r,k σ_r,l/σ_r²].

    Only σ_1 and σ_r need to be simple and σ_r non-zero.

    Returns
    -------
    kappa : float
    gradient : (P,) float
    hessian : (P, P) float, only with ``order=2`` (then a 3-tuple is returned)
    """
    Phi = _matrix(Phi, "Phi", square=False)
    last = min(Phi.shape) - 1
    if last == 0:
        raise FieldError(
            "Phi", f"a condition number needs at least 2 singular values, got shape {Phi.shape}"
        )
    d = svd_derivatives(Phi, dPhi, d2Phi, order=order, indices=[0, last], gap_rtol=gap_rtol)
    return _kappa_from_svd(d, order)


def _kappa_from_svd(d: SVDDerivatives, order: int) -> ConditionDerivatives:
    s1, sr = d.singular_values[d.indices]
    kappa = float(s1 / sr)
    g1, gr = d.singular_value_gradient[:, 0] / s1, d.singular_value_gradient[:, 1] / sr
    g = g1 - gr
    if order == 1:
        return kappa, kappa * g
    hessian = d.singular_value_hessian
    assert hessian is not None  # svd_derivatives computes it for order=2
    h1 = hessian[:, :, 0] / s1 - np.outer(g1, g1)
    hr = hessian[:, :, 1] / sr - np.outer(gr, gr)
    return kappa, kappa * g, kappa * (np.outer(g, g) + h1 - hr)


#: what :func:`eigenvector_condition_derivatives` returns: κ, its gradient (and Hessian) and
#: the eigen-solution last
EigenConditionDerivatives = (
    tuple[float, FloatArray, EigenDerivatives]
    | tuple[float, FloatArray, FloatArray, EigenDerivatives]
)


def eigenvector_condition_derivatives(
    A: npt.ArrayLike,
    dA: npt.ArrayLike,
    B: npt.ArrayLike | None = None,
    dB: npt.ArrayLike | None = None,
    d2A: npt.ArrayLike | None = None,
    d2B: npt.ArrayLike | None = None,
    *,
    order: int = 1,
    gap_rtol: float = GAP_RTOL,
) -> EigenConditionDerivatives:
    """Condition number of the normalised modal matrix of A φ = λ B φ and its derivatives.

    The performance index of Att. 5 Eq. 46, J = σ_1(Φ)/σ_n(Φ) with φ_iᵀ B φ_i = 1, differentiated
    by the chain rule of the paper: SVD sensitivity (Eqs. 15, 27) of Φ, whose derivatives come
    from the eigenvector sensitivities (Eqs. 43-44) of :func:`eig_derivatives`.

    Returns
    -------
    kappa : float
    gradient : (P,) float
    hessian : (P, P) float, only with ``order=2``
    eig : EigenDerivatives
        The eigen-solution and its derivatives (reuse for eigenvalue constraints).
    """
    eig = eig_derivatives(A, dA, B, dB, d2A, d2B, order=order, gap_rtol=gap_rtol)
    n = eig.right.shape[0]
    if n < 2:
        raise FieldError("A", "a condition number needs n >= 2")
    svd = svd_derivatives(
        eig.right,
        eig.right_gradient,
        eig.right_hessian,
        order=order,
        indices=[0, n - 1],
        gap_rtol=gap_rtol,
    )
    return (*_kappa_from_svd(svd, order), eig)


__all__ = [
    "GAP_RTOL",
    "EigenDerivatives",
    "ModalDerivatives",
    "SVDDerivatives",
    "condition_number_derivatives",
    "eig_derivatives",
    "eigensolve",
    "eigenvector_condition_derivatives",
    "modal_derivatives",
    "nelson_derivatives",
    "svd_derivatives",
]
