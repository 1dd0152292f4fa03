r"""Gradients of LQ and H2 costs by the adjoint method: one extra Lyapunov solve per cost.

LQ regulator, continuous time. With S the stabilising solution of the algebraic Riccati equation
AᵀS + SA − SBR⁻¹BᵀS + Q = 0, K = R⁻¹BᵀS and A_c = A − BK, the optimal cost from a random
initial state of covariance X0 is J = tr(S X0). At the optimum S also solves the closed-loop
Lyapunov equation A_cᵀS + SA_c + Q + KᵀRK = 0, and because K minimises J the gain's own variation
drops out (∂J/∂K = 0, the stationarity condition of Kleinman 1968 and Levine & Athans 1970).
Differentiating with K held and pairing with the adjoint (the closed-loop state covariance)

.. math::

    A_c W + W A_c^T + X_0 = 0

gives dJ = tr(W dE), dE = dAᵀS + S dA − K ᵀdBᵀS − S dB K + dQ + KᵀdR K, i.e. the matrix gradients

.. math::

    \frac{\partial J}{\partial A} = 2 S W,\quad
    \frac{\partial J}{\partial B} = -2 S W K^T,\quad
    \frac{\partial J}{\partial Q} = W,\quad
    \frac{\partial J}{\partial R} = K W K^T.

Discrete time (S = AᵀSA − AᵀSB(R + BᵀSB)⁻¹BᵀSA + Q, K = (R + BᵀSB)⁻¹BᵀSA, J = tr(S X0)):
the adjoint is W = A_c W A_cᵀ + X0 and ∂J/∂A = 2 S A_c W, ∂J/∂B = −2 S A_c W Kᵀ, ∂J/∂Q = W,
∂J/∂R = K W Kᵀ.

H2 norm of a stable G(s) = C (sI − A)⁻¹ B: ‖G‖² = tr(Bᵀ L_o B) = tr(C L_c Cᵀ) with the
Gramians AᵀL_o + L_o A + CᵀC = 0 and A L_c + L_c Aᵀ + BBᵀ = 0; the second Gramian is the
adjoint of the first, and ∂‖G‖²/∂A = 2 L_o L_c, ∂‖G‖²/∂B = 2 L_o B, ∂‖G‖²/∂C = 2 C L_c.

For parameters p_k with given ∂A/∂p_k etc., ∂J/∂p_k = Σ ⟨∂J/∂X, ∂X/∂p_k⟩ (Frobenius).

Sources: D. L. Kleinman, "On an iterative technique for Riccati equation computations",
IEEE Trans. Automatic Control 13(1), 114-115, 1968; W. S. Levine and M. Athans, "On the
determination of the optimal constant output feedback gains for linear multivariable systems",
IEEE Trans. Automatic Control 15(1), 44-48, 1970; B. D. O. Anderson and J. B. Moore, *Optimal
Control: Linear Quadratic Methods*, Prentice Hall 1990, ch. 3 (the LQ cost tr(S X0)); K. Zhou,
J. C. Doyle and K. Glover, *Robust and Optimal Control*, Prentice Hall 1996, §4.4 (H2 norm by
Gramians).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import scipy.linalg as sla

from flexsat.input_checks import FieldError
from flexsat.units import FloatArray

__all__ = ["H2Gradient", "LQCostGradient", "chain_gradient", "h2_norm_gradient", "lq_cost_gradient"]


def _real_matrix(
    value: npt.ArrayLike, field: str, shape: tuple[int | None, int | None]
) -> FloatArray:
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise FieldError(field, f"must be a real matrix, got {type(value).__name__}") from None
    if arr.ndim != 2 or any(s is not None and s != a for s, a in zip(shape, arr.shape)):
        want = "x".join("?" if s is None else str(s) for s in shape)
        raise FieldError(field, f"must have shape {want}, got {arr.shape}")
    if arr.size == 0 or not np.all(np.isfinite(arr)):
        raise FieldError(field, "must be non-empty and finite (no NaN or inf)")
    return arr


def _symmetric(arr: FloatArray, field: str, definite: str) -> FloatArray:
    scale = max(float(np.abs(arr).max()), np.finfo(float).tiny)
    if np.abs(arr - arr.T).max() > 1e-10 * scale:
        raise FieldError(field, "must be symmetric")
    eig = np.linalg.eigvalsh((arr + arr.T) / 2)
    if definite == "positive" and not eig.min() > 1e-14 * scale:
        raise FieldError(field, f"must be positive definite (smallest eigenvalue {eig.min():.3g})")
    if definite == "semidefinite" and eig.min() < -1e-12 * scale:
        raise FieldError(
            field, f"must be positive semidefinite (smallest eigenvalue {eig.min():.3g})"
        )
    return (arr + arr.T) / 2


@dataclass(frozen=True)
class LQCostGradient:
    """An LQ design's cost J = tr(S X0) and its gradients (adjoint method).

    Attributes
    ----------
    cost : float
    S : (n, n) Riccati solution;  K : (m, n) gain (u = −K x);  adjoint : (n, n) W
    dA, dB, dQ, dR : ∂J/∂A (n, n), ∂J/∂B (n, m), ∂J/∂Q (n, n), ∂J/∂R (m, m)
    discrete : bool
    """

    cost: float
    S: FloatArray
    K: FloatArray
    adjoint: FloatArray
    dA: FloatArray
    dB: FloatArray
    dQ: FloatArray
    dR: FloatArray
    discrete: bool


def lq_cost_gradient(
    A: npt.ArrayLike,
    B: npt.ArrayLike,
    Q: npt.ArrayLike,
    R: npt.ArrayLike,
    X0: npt.ArrayLike,
    *,
    discrete: bool = False,
) -> LQCostGradient:
    """Optimal LQ cost tr(S X0) and its gradients w.r.t. A, B, Q, R (one adjoint Lyapunov solve).

    Parameters
    ----------
    A : (n, n), B : (n, m)
        Plant, continuous (ẋ = Ax + Bu) or discrete (x⁺ = Ax + Bu); (A, B) stabilisable.
    Q : (n, n) symmetric positive semidefinite;  R : (m, m) symmetric positive definite
    X0 : (n, n) symmetric positive semidefinite
        Initial-state covariance (x0 x0ᵀ for one initial state).
    discrete : bool

    Returns
    -------
    LQCostGradient
    """
    A = _real_matrix(A, "A", (None, None))
    n = A.shape[0]
    if A.shape != (n, n):
        raise FieldError("A", f"must be square, got {A.shape}")
    B = _real_matrix(B, "B", (n, None))
    m = B.shape[1]
    Q = _symmetric(_real_matrix(Q, "Q", (n, n)), "Q", "semidefinite")
    R = _symmetric(_real_matrix(R, "R", (m, m)), "R", "positive")
    X0 = _symmetric(_real_matrix(X0, "X0", (n, n)), "X0", "semidefinite")
    try:
        S = (sla.solve_discrete_are if discrete else sla.solve_continuous_are)(A, B, Q, R)
    except (np.linalg.LinAlgError, ValueError) as exc:
        raise FieldError(
            "A", f"no stabilising Riccati solution ((A, B) stabilisable, (A, Q) detectable?): {exc}"
        ) from None
    S = (S + S.T) / 2
    if discrete:
        K = np.linalg.solve(R + B.T @ S @ B, B.T @ S @ A)
        Ac = A - B @ K
        W = sla.solve_discrete_lyapunov(Ac, X0)  # W = Ac W Acᵀ + X0
        SAW = S @ Ac @ W
    else:
        K = np.linalg.solve(R, B.T @ S)
        Ac = A - B @ K
        W = sla.solve_continuous_lyapunov(Ac, -X0)  # Ac W + W Acᵀ = −X0
        SAW = S @ W
    W = (W + W.T) / 2
    return LQCostGradient(
        cost=float(np.sum(S * X0)),
        S=S,
        K=K,
        adjoint=W,
        dA=2.0 * SAW,
        dB=-2.0 * SAW @ K.T,
        dQ=W,
        dR=K @ W @ K.T,
        discrete=bool(discrete),
    )


@dataclass(frozen=True)
class H2Gradient:
    """‖G‖₂ of a stable (A, B, C) and its gradients.

    Attributes
    ----------
    norm : float
        ‖G‖₂ = sqrt(tr(C L_c Cᵀ)).
    observability, controllability : (n, n) Gramians L_o, L_c
    dA, dB, dC : ∂‖G‖₂/∂A, ∂‖G‖₂/∂B, ∂‖G‖₂/∂C
    """

    norm: float
    observability: FloatArray
    controllability: FloatArray
    dA: FloatArray
    dB: FloatArray
    dC: FloatArray


def h2_norm_gradient(A: npt.ArrayLike, B: npt.ArrayLike, C: npt.ArrayLike) -> H2Gradient:
    """H2 norm of C (sI − A)⁻¹ B (continuous, A Hurwitz) and its gradient w.r.t. A, B, C.

    ∂‖G‖²/∂A = 2 L_o L_c, ∂‖G‖²/∂B = 2 L_o B, ∂‖G‖²/∂C = 2 C L_c (see the module notes), and
    ∂‖G‖/∂X = ∂‖G‖²/∂X / (2 ‖G‖).
    """
    A = _real_matrix(A, "A", (None, None))
    n = A.shape[0]
    if A.shape != (n, n):
        raise FieldError("A", f"must be square, got {A.shape}")
    B = _real_matrix(B, "B", (n, None))
    C = _real_matrix(C, "C", (None, n))
    alpha = float(np.linalg.eigvals(A).real.max())
    if not alpha < 0:
        raise FieldError("A", f"must be Hurwitz (the H2 norm is infinite), max Re λ = {alpha:.3g}")
    Lc = sla.solve_continuous_lyapunov(A, -B @ B.T)
    Lo = sla.solve_continuous_lyapunov(np.ascontiguousarray(A.T), -C.T @ C)
    Lc, Lo = (Lc + Lc.T) / 2, (Lo + Lo.T) / 2
    norm = float(np.sqrt(max(np.sum(Lo * (B @ B.T)), 0.0)))
    if norm == 0.0:
        raise FieldError("B", "gives a zero transfer function (the norm is not differentiable)")
    half = 1.0 / norm  # ∂‖G‖ = ∂‖G‖² / (2‖G‖), and ‖G‖² gradients carry the factor 2
    return H2Gradient(norm, Lo, Lc, half * Lo @ Lc, half * Lo @ B, half * C @ Lc)


def chain_gradient(
    pairs: list[tuple[npt.ArrayLike, npt.ArrayLike]],
) -> FloatArray:
    """∂J/∂p_k = Σ over (∂J/∂X, ∂X/∂p) pairs of the Frobenius product ⟨∂J/∂X, ∂X/∂p_k⟩.

    Parameters
    ----------
    pairs : list of (gradient (r, c), derivative stack (P, r, c))

    Returns
    -------
    (P,) ndarray
    """
    total = None
    for grad, stack in pairs:
        g = np.asarray(grad, dtype=float)
        d = np.asarray(stack, dtype=float)
        if d.ndim == 2:
            d = d[None]
        if d.shape[1:] != g.shape:
            raise FieldError(
                "pairs",
                f"a derivative stack of shape {d.shape} does not match the gradient {g.shape}",
            )
        term = np.einsum("ij,kij->k", g, d)
        if total is not None and term.shape != total.shape:
            raise FieldError(
                "pairs", "every derivative stack must have the same number of parameters"
            )
        total = term if total is None else total + term
    if total is None:
        raise FieldError("pairs", "must hold at least one (gradient, derivative) pair")
    return total
