r"""Discrete adjoint sensitivities of metrics of a sampled-data loop (issue 23, deliverable 2).

The loop is a continuous LTI plant :math:`\dot x = A x + B u` under a law sampled every h with
a zero-order hold,

.. math::

    x_{k+1} = \Phi x_k + \Gamma u_k, \qquad u_k = -K (x_k - r) + u^{ff}_k, \qquad
    \begin{bmatrix}\Phi & \Gamma\\ 0 & I\end{bmatrix}
      = \exp\Big(h \begin{bmatrix} A & B\\ 0 & 0\end{bmatrix}\Big)

(one block exponential: C. F. Van Loan, "Computing integrals involving the matrix
exponential", IEEE Trans. Automatic Control 23(3), 1978; I. Najfeld and T. F. Havel,
"Derivatives of the matrix exponential and their computation", Advances in Applied
Mathematics 16(3), 1995), for k = 0 … N−1, and a metric J(x_0 … x_N, u_0 … u_{N−1}) of the
whole record. With the partials a_k = ∂J/∂x_k, b_k = ∂J/∂u_k the discrete adjoint
(Y. Cao, S. Li, L. Petzold and R. Serban, "Adjoint sensitivity analysis for
differential-algebraic equations: the adjoint DAE system and its numerical solution", SIAM J.
Scientific Computing 24(3), 2003, §2, in its discrete form) is one backward sweep

.. math::

    \lambda_N = a_N, \qquad \mu_k = b_k + \Gamma^T \lambda_{k+1}, \qquad
    \lambda_k = a_k - K^T \mu_k + \Phi^T \lambda_{k+1},

and the gradient with respect to every matrix of the loop is a contraction with the record:

.. math::

    \frac{\partial J}{\partial \Phi} = \sum_k \lambda_{k+1} x_k^T, \quad
    \frac{\partial J}{\partial \Gamma} = \sum_k \lambda_{k+1} u_k^T, \quad
    \frac{\partial J}{\partial K} = -\sum_k \mu_k (x_k - r)^T, \quad
    \frac{\partial J}{\partial r} = K^T \sum_k \mu_k, \quad
    \frac{\partial J}{\partial x_0} = \lambda_0, \quad
    \frac{\partial J}{\partial u^{ff}_k} = \mu_k

(:func:`loop_adjoint`). The ZOH maps are pulled back to (A, B) by the Fréchet derivative of the
exponential: with M = h[[A, B], [0, 0]] and E = h[[dA, dB], [0, 0]], [dΦ, dΓ] is the top block
row of L(M, E), and ⟨G, L(M, E)⟩ = ⟨L(Mᵀ, G), E⟩, so one Fréchet evaluation (A. H. Al-Mohy and
N. J. Higham, "Computing the Fréchet derivative of the matrix exponential, with an application
to condition number estimation", SIAM J. Matrix Analysis and Applications 30(4), 2009;
``scipy.linalg.expm_frechet``) serves every parameter (:func:`zoh_adjoint`).

A discrete LQR gain K = (R + ΓᵀSΓ)⁻¹ΓᵀSΦ of (Φ, Γ, Q, R) is differentiated through the Riccati
equation: holding the optimal K fixed (stationarity) the Joseph form S = Q + KᵀRK + A_cᵀSA_c,
A_c = Φ − ΓK, gives the Stein (discrete Lyapunov) equation dS = A_cᵀ dS A_c + M with
M = dQ + KᵀdRK + dA_cᵀSA_c + A_cᵀS dA_c, dA_c = dΦ − dΓK, and

.. math::

    dK = (R + \Gamma^T S \Gamma)^{-1}\big[d\Gamma^T S A_c + \Gamma^T S\, dA_c - dR\,K
         + \Gamma^T dS\, A_c\big]

(C. S. Kenney and A. J. Laub, "Condition estimates for matrix functions", SIAM J. Matrix
Analysis and Applications 10(2), 1989, for the perturbation of the Riccati solution by a
Lyapunov solve; B. D. O. Anderson and J. B. Moore, *Optimal Control: Linear Quadratic
Methods*, Prentice Hall 1990, §2.4 for the discrete Riccati equation). Its adjoint needs one
Stein solve for every parameter at once: with H = (R + ΓᵀSΓ)⁻ᵀ ∂J/∂K and Z = A_c Z A_cᵀ +
sym(Γ H A_cᵀ), ∂J/∂Q = Z, ∂J/∂R = sym(KZKᵀ − HKᵀ), G_c = SΓH + 2SA_cZ, ∂J/∂Φ = G_c,
∂J/∂Γ = SA_cHᵀ − G_cKᵀ (:func:`dlqr_gain_adjoint`).

Metrics (each returns its value and the partials ∂J/∂X, ∂J/∂U, plus the partials with respect
to its own weights, which a caller chains when they depend on the design):

* :func:`terminal_energy` ½ x_Nᵀ W x_N (the residual modal vibration energy at T with
  W = diag(Ω², I) on the elastic modes);
* :func:`terminal_error` (cᵀx_N − target)² (the pointing error at T squared);
* :func:`smooth_peak` (Σ_k u_k^p)^{1/p}, p even: max|u| ≤ ‖u‖_p ≤ N^{1/p} max|u|;
* :func:`soft_settling` h Σ_k ½(1 + tanh((e_k² − b²)/(4wb²))), e_k = cᵀx_k − target: the
  time spent outside the band |e| ≤ b with a smoothed edge (e² − b² ≈ 2b(|e| − b) near the edge,
  so w is the relative width of the edge as in :mod:`flexsat.cases.tamu_codesign`, where
  |e| itself is used).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from scipy.linalg import expm, expm_frechet, solve_discrete_lyapunov

from flexsat.input_checks import FieldError, require_finite, require_positive
from flexsat.units import FloatArray

if TYPE_CHECKING:
    import numpy.typing as npt

__all__ = [
    "GainAdjoint",
    "LoopAdjoint",
    "MetricValue",
    "dlqr_gain_adjoint",
    "loop_adjoint",
    "smooth_peak",
    "soft_settling",
    "terminal_energy",
    "terminal_error",
    "zoh_adjoint",
    "zoh_maps",
]


def _block(A: FloatArray, B: FloatArray, h: float) -> FloatArray:
    n, m = B.shape
    M = np.zeros((n + m, n + m))
    M[:n, :n] = A
    M[:n, n:] = B
    return h * M


def _check_plant(
    A: npt.ArrayLike, B: npt.ArrayLike, h: npt.ArrayLike
) -> tuple[FloatArray, FloatArray, float]:
    Af, Bf = require_finite(A, "A"), require_finite(B, "B")
    if Af.ndim != 2 or Af.shape[0] != Af.shape[1] or Af.shape[0] < 1:
        raise FieldError("A", f"must be a square (n, n) matrix, got shape {Af.shape}")
    if Bf.ndim != 2 or Bf.shape[0] != Af.shape[0]:
        raise FieldError("B", f"must have shape ({Af.shape[0]}, m), got {Bf.shape}")
    return Af, Bf, float(require_positive(h, "h", "s"))


def zoh_maps(A: npt.ArrayLike, B: npt.ArrayLike, h: npt.ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Φ = e^{Ah}, Γ = ∫₀ʰ e^{As} ds B from one block exponential (module docstring).

    Parameters
    ----------
    A : (n, n) array_like
    B : (n, m) array_like
    h : float
        Sample period, s.
    """
    Af, Bf, hf = _check_plant(A, B, h)
    n = Af.shape[0]
    E = expm(_block(Af, Bf, hf))
    return E[:n, :n], E[:n, n:]


def zoh_adjoint(
    A: npt.ArrayLike,
    B: npt.ArrayLike,
    h: npt.ArrayLike,
    G_phi: npt.ArrayLike,
    G_gamma: npt.ArrayLike,
) -> tuple[FloatArray, FloatArray]:
    """(∂J/∂A, ∂J/∂B) from (∂J/∂Φ, ∂J/∂Γ) by one Fréchet derivative of the exponential.

    ⟨G, L(M, E)⟩ = ⟨L(Mᵀ, G), E⟩ with G = [[G_Φ, G_Γ], [0, 0]] and E = h[[dA, dB], [0, 0]],
    so ∂J/∂[A, B] = h · (top block row of L(Mᵀ, G)) (module docstring; Al-Mohy & Higham 2009).
    """
    Af, Bf, hf = _check_plant(A, B, h)
    n, m = Bf.shape
    Gp, Gg = require_finite(G_phi, "G_phi"), require_finite(G_gamma, "G_gamma")
    if Gp.shape != (n, n) or Gg.shape != (n, m):
        raise FieldError("G_phi", f"G_phi, G_gamma must have shapes {(n, n)}, {(n, m)}")
    G = np.zeros((n + m, n + m))
    G[:n, :n] = Gp
    G[:n, n:] = Gg
    L = expm_frechet(_block(Af, Bf, hf).T, G, compute_expm=False)
    return hf * L[:n, :n], hf * L[:n, n:]


@dataclass(frozen=True)
class LoopAdjoint:
    """Gradients of a metric of the sampled loop (module docstring).

    Attributes
    ----------
    dphi, dgamma, dK : ∂J/∂Φ (n, n), ∂J/∂Γ (n, m), ∂J/∂K (m, n)
    dx0, dr : ∂J/∂x₀ (n,), ∂J/∂r (n,)
    du_ff : ∂J/∂u^ff_k (N, m), the total sensitivity μ_k to the command at sample k
    costate : λ_0 … λ_N (N + 1, n)
    """

    dphi: FloatArray
    dgamma: FloatArray
    dK: FloatArray
    dx0: FloatArray
    dr: FloatArray
    du_ff: FloatArray
    costate: FloatArray


def loop_adjoint(
    phi: FloatArray,
    gamma: FloatArray,
    K: FloatArray,
    X: FloatArray,
    U: FloatArray,
    dX: FloatArray,
    dU: FloatArray,
    r: FloatArray | None = None,
) -> LoopAdjoint:
    """The backward sweep of the discrete adjoint and the contractions (module docstring).

    Parameters
    ----------
    phi, gamma : (n, n), (n, m)
        ZOH maps (:func:`zoh_maps`).
    K : (m, n)
        State-feedback gain, u_k = −K(x_k − r) + u^ff_k.
    X, U : (N + 1, n), (N, m)
        The record of the loop (from :func:`flexsat.sim.simulate`).
    dX, dU : (N + 1, n), (N, m)
        Partials of the metric ∂J/∂x_k, ∂J/∂u_k.
    r : (n,), optional
        State reference (default 0).
    """
    n, m = gamma.shape
    N = U.shape[0]
    for name, arr, shape in (
        ("K", K, (m, n)),
        ("X", X, (N + 1, n)),
        ("dX", dX, (N + 1, n)),
        ("dU", dU, (N, m)),
    ):
        if arr.shape != shape:
            raise FieldError(name, f"must have shape {shape}, got {arr.shape}")
    ref = np.zeros(n) if r is None else np.asarray(r, float)
    closed_t = (phi - gamma @ K).T
    drive = dX[:N] - dU @ K  # a_k − Kᵀ b_k, as rows
    lam = np.empty((N + 1, n))
    lam[N] = dX[N]
    for k in range(N - 1, -1, -1):
        lam[k] = drive[k] + closed_t @ lam[k + 1]
    mu = dU + lam[1:] @ gamma  # rows μ_kᵀ
    return LoopAdjoint(
        dphi=lam[1:].T @ X[:N],
        dgamma=lam[1:].T @ U,
        dK=-(mu.T @ (X[:N] - ref)),
        dx0=lam[0].copy(),
        dr=K.T @ mu.sum(axis=0),
        du_ff=mu,
        costate=lam,
    )


@dataclass(frozen=True)
class GainAdjoint:
    """∂J/∂(Φ, Γ, Q, R) of a metric through a discrete LQR gain (:func:`dlqr_gain_adjoint`)."""

    dphi: FloatArray
    dgamma: FloatArray
    dQ: FloatArray
    dR: FloatArray


def dlqr_gain_adjoint(
    phi: FloatArray,
    gamma: FloatArray,
    R: FloatArray,
    S: FloatArray,
    K: FloatArray,
    G_K: FloatArray,
) -> GainAdjoint:
    """Pull ∂J/∂K back to (Φ, Γ, Q, R) through the discrete Riccati equation (module
    docstring): one Stein solve Z = A_c Z A_cᵀ + sym(Γ H A_cᵀ).

    Parameters
    ----------
    phi, gamma : the discrete plant;  R : (m, m) input weight
    S, K : the stabilising Riccati solution and the gain K = (R + ΓᵀSΓ)⁻¹ΓᵀSΦ
    G_K : (m, n) ∂J/∂K
    """
    Ac = phi - gamma @ K
    H = np.linalg.solve((R + gamma.T @ S @ gamma).T, G_K)
    Y = gamma @ H @ Ac.T
    Z = solve_discrete_lyapunov(Ac, 0.5 * (Y + Y.T))
    Z = 0.5 * (Z + Z.T)
    Gc = S @ gamma @ H + 2.0 * S @ Ac @ Z
    dR = K @ Z @ K.T - H @ K.T
    return GainAdjoint(
        dphi=Gc,
        dgamma=S @ Ac @ H.T - Gc @ K.T,
        dQ=Z,
        dR=0.5 * (dR + dR.T),
    )


@dataclass(frozen=True)
class MetricValue:
    """A metric's value, its partials ∂J/∂X (N + 1, n) and ∂J/∂U (N, m), and ∂J/∂(its own
    weights) by name (``weights``), for a caller whose weights depend on the design."""

    value: float
    dX: FloatArray
    dU: FloatArray
    weights: dict[str, FloatArray]


def _records(X: npt.ArrayLike, U: npt.ArrayLike) -> tuple[FloatArray, FloatArray]:
    Xf, Uf = require_finite(X, "X"), require_finite(U, "U")
    if Xf.ndim != 2 or Uf.ndim != 2 or Xf.shape[0] != Uf.shape[0] + 1:
        raise FieldError("X", f"X (N + 1, n) and U (N, m) expected, got {Xf.shape}, {Uf.shape}")
    return Xf, Uf


def terminal_energy(X: npt.ArrayLike, U: npt.ArrayLike, W: npt.ArrayLike) -> MetricValue:
    """½ x_Nᵀ W x_N (W symmetric PSD), e.g. the residual modal energy; ``weights["W"]`` =
    ½ x_N x_Nᵀ."""
    Xf, Uf = _records(X, U)
    Wf = require_finite(W, "W")
    if Wf.shape != (Xf.shape[1],) * 2 or not np.allclose(Wf, Wf.T, rtol=0, atol=0):
        raise FieldError("W", f"must be a symmetric ({Xf.shape[1]}, {Xf.shape[1]}) matrix")
    xN = Xf[-1]
    dX = np.zeros_like(Xf)
    dX[-1] = Wf @ xN
    return MetricValue(
        0.5 * float(xN @ Wf @ xN), dX, np.zeros_like(Uf), {"W": 0.5 * np.outer(xN, xN)}
    )


def terminal_error(
    X: npt.ArrayLike, U: npt.ArrayLike, c: npt.ArrayLike, target: float
) -> MetricValue:
    """(cᵀx_N − target)², e.g. the hub pointing error at T squared; ``weights["c"]`` = 2e x_N."""
    Xf, Uf = _records(X, U)
    cf = require_finite(c, "c")
    if cf.shape != (Xf.shape[1],):
        raise FieldError("c", f"must have shape ({Xf.shape[1]},), got {cf.shape}")
    e = float(cf @ Xf[-1]) - float(target)
    dX = np.zeros_like(Xf)
    dX[-1] = 2.0 * e * cf
    return MetricValue(e * e, dX, np.zeros_like(Uf), {"c": 2.0 * e * Xf[-1]})


def smooth_peak(X: npt.ArrayLike, U: npt.ArrayLike, p: int = 16) -> MetricValue:
    """‖u‖_p = (Σ_k Σ_j u_kj^p)^{1/p}, p even >= 2: max|u| ≤ ‖u‖_p ≤ (N m)^{1/p} max|u|."""
    Xf, Uf = _records(X, U)
    if isinstance(p, bool) or not isinstance(p, int) or p < 2 or p % 2:
        raise FieldError("p", f"must be an even integer >= 2, got {p!r}")
    peak = float(np.max(np.abs(Uf)))
    if peak == 0.0:
        return MetricValue(0.0, np.zeros_like(Xf), np.zeros_like(Uf), {})
    s = Uf / peak  # scaled against overflow: ‖u‖_p = peak ‖u/peak‖_p
    total = float(np.sum(s**p))
    value = peak * total ** (1.0 / p)
    dU = total ** (1.0 / p - 1.0) * s ** (p - 1)
    return MetricValue(value, np.zeros_like(Xf), dU, {})


def soft_settling(
    X: npt.ArrayLike,
    U: npt.ArrayLike,
    c: npt.ArrayLike,
    target: float,
    band: float,
    width: float,
    h: float,
) -> MetricValue:
    """h Σ_{k=0}^{N} ½(1 + tanh((e_k² − b²)/(4 w b²))), e_k = cᵀx_k − target (module
    docstring); ``weights["c"]`` = Σ_k ∂J/∂e_k x_k."""
    Xf, Uf = _records(X, U)
    cf = require_finite(c, "c")
    if cf.shape != (Xf.shape[1],):
        raise FieldError("c", f"must have shape ({Xf.shape[1]},), got {cf.shape}")
    b = float(require_positive(band, "band"))
    w = float(require_positive(width, "width"))
    hf = float(require_positive(h, "h", "s"))
    e = Xf @ cf - float(target)
    arg = (e * e - b * b) / (4.0 * w * b * b)
    th = np.tanh(arg)
    value = hf * float(np.sum(0.5 * (1.0 + th)))
    de = hf * 0.5 * (1.0 - th * th) * (2.0 * e) / (4.0 * w * b * b)
    return MetricValue(value, de[:, None] * cf[None, :], np.zeros_like(Uf), {"c": de @ Xf})
