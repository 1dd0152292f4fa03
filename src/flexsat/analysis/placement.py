r"""Actuator-placement measures and candidate-set search.

Measures
--------
* :func:`modal_controllability`, :func:`hamdan_nayfeh`: Hamdan & Nayfeh's modal
  controllability, the angle between the left eigenvector :math:`q_i` and each input column
  :math:`b_j` and the gross measure :math:`\rho_i` (Att. 4 Eqs. 2–3; Y. Kim
  and J. L. Junkins, "A Measure of Controllability for Actuator Placement", AIAA GNC 1990).
* :func:`modal_cost`: Skelton's modal cost analysis, :math:`V = \mathrm{tr}(Q C X C^T)` split
  into component costs :math:`V_i` (Att. 4 Eqs. 4–7, 20–27).
* :func:`kim_junkins_index`: :math:`\alpha = \sum_i (V_i/V) \rho_i^2` (Att. 4 Eq. 28),
  with the analytic modal Gramian of Att. 4 Eq. (25) in corrected signs (the paper prints
  "−" where "+" holds).
* :func:`gawronski_index`: Gawronski's H2 (or Hankel) placement index per actuator and mode,
  :math:`\sigma_{ki} = w_{ki} \|G_{ki}\| / \|G\|` (W. Gawronski, *Advanced Structural Dynamics
  and Active Control of Structures*, 2004, §5.3 and Ch. 8).
* :func:`h2_placement`, :func:`h2_actuator_ranking`: the H2 ranking of the EPS slew
  study c. 1989 (NASA Langley Earth Pointing Satellite report section), Eqs. (1)–(8) (as
  reconstructed by the developers from the text [RECON]), made to work with rigid-body modes.
  The paper's EPS study (its candidates, outputs and published top 5) is
  :mod:`flexsat.cases.eps_placement`.

Search
------
:func:`exhaustive`, :func:`greedy` and :func:`exchange` live in
:mod:`flexsat.analysis.placement_search` and are re-exported here, beside the scores they
search with (:func:`kim_junkins_score`).

State convention: :math:`z = (\eta, \dot\eta)` as in :mod:`flexsat.analysis.gramians`.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, TypeAlias, TypeVar

import numpy as np
import numpy.typing as npt
import scipy.linalg as sla

from flexsat.analysis.gramians import (
    finite_horizon_gramian,
    lyapunov_gramian,
    modal_controllability_gramian,
    modal_inputs,
    modal_outputs,
    modal_parameters,
    modal_state_matrices,
    require_damped,
)
from flexsat.analysis.placement_search import (
    MAX_EXHAUSTIVE_SETS,
    Score,
    SearchResult,
    Selection,
    exchange,
    exhaustive,
    greedy,
)
from flexsat.input_checks import FieldError, require_count, require_finite, require_positive
from flexsat.units import FloatArray

if TYPE_CHECKING:
    from flexsat.structures.modal_model import ModalModel

__all__ = [
    "MAX_EXHAUSTIVE_SETS",
    "RIGID_TREATMENTS",
    "GawronskiIndex",
    "H2Placement",
    "H2Ranking",
    "KimJunkins",
    "ModalControllability",
    "ModalCost",
    "SearchResult",
    "actuator_candidates",
    "exchange",
    "exhaustive",
    "gawronski_index",
    "greedy",
    "h2_actuator_ranking",
    "h2_placement",
    "hamdan_nayfeh",
    "kim_junkins_index",
    "kim_junkins_score",
    "modal_controllability",
    "modal_cost",
]

#: How :func:`h2_actuator_ranking` treats rigid-body modes.
RIGID_TREATMENTS = ("project", "keep")
_FORMS = ("first_order", "second_order")

ComplexArray: TypeAlias = npt.NDArray[np.complex128]
#: a candidate's label (a key of a mapping of candidates)
_Label = TypeVar("_Label", bound=Hashable)


# ------------------------------------------------------------------------------------------------
# Hamdan–Nayfeh modal controllability
@dataclass(frozen=True)
class ModalControllability:
    r"""Hamdan–Nayfeh measures (Att. 4 Eqs. 2–3).

    Attributes
    ----------
    cos_theta : ndarray (n, m)
        :math:`\cos\theta_{ij} = |q_i^H b_j| / (\|q_i\| \|b_j\|)`, mode (or eigenvalue) i, input j.
        0 for an input column that is identically zero.
    rho : ndarray (n,)
        Gross measure :math:`\rho_i = \|f_i\|`, :math:`f_i^T = q_i^H B / \|q_i\|`, i.e. the rows
        of :math:`F = (\cos\Theta)\,\mathrm{diag}(\|b_j\|)` (the paper is ambiguous: cos Θ is
        modes × inputs).
    eigenvalues : ndarray (n,) complex
        The eigenvalue of each row (for modal systems the one with Im λ >= 0).
    """

    cos_theta: FloatArray
    rho: FloatArray
    eigenvalues: ComplexArray


def modal_controllability(
    omega: npt.ArrayLike,
    zeta: float | npt.ArrayLike,
    B: npt.ArrayLike,
    form: str = "first_order",
) -> ModalControllability:
    r"""Hamdan–Nayfeh measures of a modal system in closed form (one row per mode).

    ``form="first_order"`` (Att. 4, Section IV): the left eigenvector of mode i of the modal A
    of Eq. (16) has entries only at :math:`\eta_i` and :math:`\dot\eta_i`,
    :math:`q_i \propto (\lambda_i + 2\zeta_i\omega_i,\; 1)`, and
    :math:`|\lambda_i + 2\zeta_i\omega_i| = \omega_i` for ζ < 1, so with :math:`B = [0; \bar D]`

    .. math::

        \cos\theta_{ij} = \frac{|\bar D_{ij}|}{\sqrt{1 + \omega_i^2}\; \|\bar D_{:j}\|}, \qquad
        \rho_i = \frac{\|\bar D_{i:}\|}{\sqrt{1 + \omega_i^2}}.

    Both conjugate eigenvalues give the same values (the paper is ambiguous on Eq. 28: one per
    mode). A rigid mode (ω = 0, a Jordan block) has the single left eigenvector (0, 1): the same
    formula. The :math:`\sqrt{1+\omega^2}` mixes η and η̇, so ρ depends on the time unit
    (here s): the measures are not invariant under non-orthogonal scaling, as Att. 4 warns.

    ``form="second_order"`` (Hamdan & Nayfeh's second-order version, to which Att. 4 Eq. 15
    refers): the left eigenvectors of :math:`\ddot\eta + \Omega^2 \eta = \bar D u` are the unit
    vectors, :math:`\cos\theta_{ij} = |\bar D_{ij}| / \|\bar D_{:j}\|`, :math:`\rho_i =
    \|\bar D_{i:}\|`.

    Parameters
    ----------
    omega, zeta : array_like (n,)
        rad/s and damping ratios (ζ < 1).
    B : array_like (n, m) or (n,)
        Modal input matrix :math:`\bar D = \Phi^T D`.
    form : {"first_order", "second_order"}
    """
    w, z = modal_parameters(omega, zeta)
    Bm = modal_inputs(B, w.size)
    if form not in _FORMS:
        raise FieldError("form", f"must be one of {_FORMS}, got {form!r}")
    if np.any(z >= 1):
        raise FieldError(
            "zeta",
            "the closed form needs underdamped modes (ζ < 1); use hamdan_nayfeh(A, B) "
            f"for others, got max ζ = {z.max():.3g}",
        )
    lam = -z * w + 1j * w * np.sqrt(1 - z**2)
    qnorm = np.sqrt(1 + w**2) if form == "first_order" else np.ones_like(w)
    bnorm = np.linalg.norm(Bm, axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        cos = np.abs(Bm) / (qnorm[:, None] * bnorm[None, :])
    cos = np.where(bnorm[None, :] > 0, cos, 0.0)
    rho = np.linalg.norm(Bm, axis=1) / qnorm
    return ModalControllability(cos_theta=cos, rho=rho, eigenvalues=lam)


def hamdan_nayfeh(A: npt.ArrayLike, B: npt.ArrayLike) -> ModalControllability:
    r"""Hamdan–Nayfeh measures of a general first-order system (Att. 4 Eqs. 2–3, 17).

    The left eigenvectors :math:`A^T q_i = \lambda_i q_i` come from
    :func:`scipy.linalg.eig`; one row per eigenvalue, ordered by :math:`|\mathrm{Im}\,\lambda|`
    then Im λ. The measures do not depend on the scaling of :math:`q_i` (so the normalisation
    of Eq. 18 plays no role). For a defective A (rigid-body modes: a double zero eigenvalue)
    the computed eigenvectors are only accurate to about √ε; use :func:`modal_controllability`
    for modal systems.
    """
    A = require_finite(A, "A")
    if A.ndim != 2 or A.shape[0] != A.shape[1] or A.shape[0] == 0:
        raise FieldError("A", f"must be a non-empty square matrix, got shape {A.shape}")
    B = require_finite(B, "B")
    B = B[:, None] if B.ndim == 1 else B
    if B.ndim != 2 or B.shape[0] != A.shape[0]:
        raise FieldError("B", f"must have shape ({A.shape[0]}, m), got {B.shape}")
    lam, vl = sla.eig(A, left=True, right=False)
    order = np.lexsort((lam.imag, np.abs(lam.imag)))
    lam, q = lam[order], np.conj(vl[:, order])  # Aᵀ q = λ q
    proj = np.abs(q.conj().T @ B)  # |q_iᴴ b_j|
    qn = np.linalg.norm(q, axis=0)
    bn = np.linalg.norm(B, axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        cos = proj / (qn[:, None] * bn[None, :])
    cos = np.where(bn[None, :] > 0, cos, 0.0)
    return ModalControllability(
        cos_theta=cos, rho=np.linalg.norm(proj, axis=1) / qn, eigenvalues=lam
    )


# ------------------------------------------------------------------------------------------------
# modal cost (Skelton) and the Kim–Junkins index
@dataclass(frozen=True)
class ModalCost:
    r"""Skelton's modal cost decomposition (Att. 4 Eqs. 5–6, 26–27).

    Attributes
    ----------
    total : float
        :math:`V = \mathrm{tr}(Q C X C^T)` (Eq. 5).
    costs : ndarray (n,)
        :math:`V_i = V_{\eta_i} + V_{\dot\eta_i}` (Eq. 26); they add up to V.
    displacement, velocity : ndarray (n,)
        :math:`V_{\eta_i} = [X C^T Q C]_{ii}` and :math:`V_{\dot\eta_i} = [X C^T Q C]_{n+i,n+i}`
        (Eq. 6; Eq. 27 when the outputs are either displacements or velocities).
    gramian : ndarray (2n, 2n)
        The controllability Gramian X used.
    """

    total: float
    costs: FloatArray
    displacement: FloatArray
    velocity: FloatArray
    gramian: FloatArray = field(repr=False)

    @property
    def fractions(self) -> FloatArray:
        """Normalised modal costs :math:`V_i / V`."""
        return self.costs / self.total


def _weight(Q: float | npt.ArrayLike | None, p: int) -> FloatArray:
    if Q is None:
        return np.eye(p)
    Q = require_finite(Q, "Q")
    if Q.ndim == 0:
        Q = np.full(p, float(Q))
    if Q.ndim == 1:
        Q = np.diag(Q)
    if Q.shape != (p, p):
        raise FieldError("Q", f"must be a scalar, (p,) or (p, p) with p = {p}, got {Q.shape}")
    if np.max(np.abs(Q - Q.T), initial=0.0) > 1e-12 * max(np.abs(Q).max(), 1.0):
        raise FieldError("Q", "must be symmetric")
    if np.linalg.eigvalsh(0.5 * (Q + Q.T)).min() < -1e-12 * max(np.abs(Q).max(), 1.0):
        raise FieldError("Q", "must be positive semi-definite")
    return Q


def modal_cost(
    omega: npt.ArrayLike,
    zeta: float | npt.ArrayLike,
    B: npt.ArrayLike,
    Cq: npt.ArrayLike | None = None,
    Cv: npt.ArrayLike | None = None,
    Q: float | npt.ArrayLike | None = None,
    horizon: float | None = None,
) -> ModalCost:
    r"""Modal cost analysis of the unit-impulse output energy (Att. 4 Eqs. 4–7, 20–27).

    .. math::

        V = \int_0^{T} y^T Q y\, dt = \mathrm{tr}(Q C X C^T), \qquad
        V_{x_k} = [X C^T Q C]_{kk}, \qquad V_i = V_{\eta_i} + V_{\dot\eta_i},

    for the impulse response of every input (Eq. 4), :math:`y = C_q\eta + C_v\dot\eta`.
    X is the infinite-horizon Gramian of Att. 4 Eq. (25) (``horizon=None``; every mode needs
    ζω > 0) or the finite-horizon Gramian over [0, T] (``horizon=T``; rigid-body modes
    allowed), :func:`flexsat.analysis.gramians.finite_horizon_gramian`.

    Parameters
    ----------
    omega, zeta : array_like (n,)
    B : array_like (n, m)
        Modal input matrix.
    Cq, Cv : array_like (p, n), optional
        Output rows on η and η̇ (at least one).
    Q : None, float, array_like (p,) or (p, p)
        Output weight (default identity).
    horizon : float, optional
        Finite horizon T, s.
    """
    w, z = modal_parameters(omega, zeta)
    n = w.size
    Bm = modal_inputs(B, n)
    Cq, Cv = modal_outputs(Cq, Cv, n)
    Qw = _weight(Q, Cq.shape[0])
    if horizon is None:
        X = modal_controllability_gramian(w, z, Bm)
    else:
        A, Bz, _ = modal_state_matrices(w, z, Bm)
        assert Bz is not None  # B was given
        X = finite_horizon_gramian(A, Bz, horizon)
    C = np.hstack([Cq, Cv])
    parts = np.einsum("ij,ji->i", X, C.T @ Qw @ C)
    total = float(np.trace(Qw @ C @ X @ C.T))
    return ModalCost(
        total=total,
        costs=parts[:n] + parts[n:],
        displacement=parts[:n],
        velocity=parts[n:],
        gramian=X,
    )


@dataclass(frozen=True)
class KimJunkins:
    r"""The Kim–Junkins measure of controllability (Att. 4 Eq. 28).

    Attributes
    ----------
    alpha : float
        :math:`\alpha = \sum_i (V_i/V)\rho_i^2`.
    contributions : ndarray (n,)
        :math:`(V_i/V)\rho_i^2`, one per mode.
    rho : ndarray (n,)
        Gross modal controllability (first-order form).
    cost : ModalCost
    """

    alpha: float
    contributions: FloatArray
    rho: FloatArray
    cost: ModalCost


def kim_junkins_index(
    omega: npt.ArrayLike,
    zeta: float | npt.ArrayLike,
    B: npt.ArrayLike,
    Cq: npt.ArrayLike | None = None,
    Cv: npt.ArrayLike | None = None,
    Q: float | npt.ArrayLike | None = None,
    horizon: float | None = None,
) -> KimJunkins:
    r"""Kim & Junkins' output measure of controllability, Att. 4 Eq. (28).

    .. math::

        \alpha = \sum_{i=1}^{n} \frac{V_i}{V}\, \rho_i^2,

    with :math:`\rho_i` from :func:`modal_controllability` (first-order form, Eqs. 2–3 and 17)
    and :math:`V_i/V` from :func:`modal_cost` (Eqs. 20–27, analytic Gramian of Eq. 25 with the
    corrected signs). The sum runs over the n modes, one eigenvector per conjugate pair. The
    inputs B enter twice: through ρ and through the impulse responses that define :math:`V_i`.

    Parameters as :func:`modal_cost`. Raises ValueError if V = 0 (no input reaches the output).
    """
    cost = modal_cost(omega, zeta, B, Cq, Cv, Q, horizon)
    if not cost.total > 0:
        raise ValueError(
            "B, Cq, Cv: the output cost V is 0 (no input reaches the outputs); α is undefined"
        )
    rho = modal_controllability(omega, zeta, B).rho
    contrib = cost.fractions * rho**2
    return KimJunkins(alpha=float(contrib.sum()), contributions=contrib, rho=rho, cost=cost)


# ------------------------------------------------------------------------------------------------
# Gawronski's placement index
@dataclass(frozen=True)
class GawronskiIndex:
    r"""Gawronski's placement indices.

    Attributes
    ----------
    sigma : ndarray (n_modes, m)
        :math:`\sigma_{ki}` of actuator k for mode i, stored [mode i, actuator k].
    actuator : ndarray (m,)
        Actuator importance :math:`\sigma_k = (\sum_i \sigma_{ki}^2)^{1/2}`.
    mode : ndarray (n_modes,)
        Mode importance :math:`(\sum_k \sigma_{ki}^2)^{1/2}`.
    norm : str
        "h2" or "hankel".
    """

    sigma: FloatArray
    actuator: FloatArray
    mode: FloatArray
    norm: str


def gawronski_index(
    omega: npt.ArrayLike,
    zeta: float | npt.ArrayLike,
    B: npt.ArrayLike,
    Cq: npt.ArrayLike | None = None,
    Cv: npt.ArrayLike | None = None,
    weights: float | npt.ArrayLike | None = None,
    norm: str = "h2",
) -> GawronskiIndex:
    r"""Gawronski's H2 (or Hankel) actuator placement index per actuator and mode.

    For mode i and actuator k (column k of :math:`\bar D`), with the output vector
    :math:`\|c_i\|^2 = \|c_{q,i}\|^2/\omega_i^2 + \|c_{v,i}\|^2` (Gawronski Property 5.1):

    .. math::

        \|G_{ki}\|_2 = \frac{|\bar D_{ik}|\,\|c_i\|}{2\sqrt{\zeta_i\omega_i}}, \quad
        \|G\|_2 = \Big(\sum_i \|G_i\|_2^2\Big)^{1/2}, \quad
        \sigma_{ki} = w_{ki}\frac{\|G_{ki}\|_2}{\|G\|_2};

    Hankel: :math:`\gamma_{ki} = |\bar D_{ik}|\,\|c_i\| / (4\zeta_i\omega_i)`, normalised by
    :math:`\max_i \gamma_i` (the approximate Hankel norm of the whole system). The per-mode
    norms are exact for one mode; the sums over modes neglect the cross-mode terms (the
    well-separated-mode approximation of :func:`flexsat.analysis.gramians.gawronski_gramians`).
    With unit weights the H2 indices satisfy :math:`\sum_{k,i}\sigma_{ki}^2 = 1`.

    Parameters
    ----------
    omega, zeta : array_like (n,)
        Every mode needs ζω > 0 (drop rigid modes first).
    B : array_like (n, m)
        Modal input matrix of the m candidate actuators (evaluated all together).
    Cq, Cv : array_like (p, n), optional
    weights : array_like (n, m) or (m,), optional
        :math:`w_{ki}` (default 1).
    norm : {"h2", "hankel"}
    """
    w, z = modal_parameters(omega, zeta)
    n = w.size
    Bm = modal_inputs(B, n)
    Cq, Cv = modal_outputs(Cq, Cv, n)
    require_damped(w, z, "gawronski_index")
    if norm not in ("h2", "hankel"):
        raise FieldError("norm", f"must be 'h2' or 'hankel', got {norm!r}")
    c = np.sqrt(np.sum(Cq**2, axis=0) / w**2 + np.sum(Cv**2, axis=0))
    if norm == "h2":
        G = np.abs(Bm) * (c / (2 * np.sqrt(z * w)))[:, None]
        total = np.sqrt(np.sum(G**2))
    else:
        G = np.abs(Bm) * (c / (4 * z * w))[:, None]
        total = np.max(np.linalg.norm(Bm, axis=1) * c / (4 * z * w))
    if not total > 0:
        raise ValueError("B, Cq, Cv: no actuator reaches the outputs (system norm 0)")
    if weights is not None:
        wts = require_finite(weights, "weights")
        try:
            wts = np.broadcast_to(wts, G.shape)
        except ValueError:
            raise FieldError(
                "weights", f"must broadcast to (n_modes, m) = {G.shape}, got {np.shape(weights)}"
            ) from None
        G = G * wts
    sigma = G / total
    return GawronskiIndex(
        sigma=sigma,
        actuator=np.linalg.norm(sigma, axis=0),
        mode=np.linalg.norm(sigma, axis=1),
        norm=norm,
    )


# ------------------------------------------------------------------------------------------------
# EPS slew study c. 1989 H2 placement, Eqs. (1)–(8)
@dataclass(frozen=True)
class H2Placement:
    r"""Solution of the H2 placement problem of EPS slew study c. 1989 Eqs. (1)–(8).

    Attributes
    ----------
    X : ndarray (N, N)
        Stabilising solution of the CARE (Eq. 4).
    F : ndarray (m, N)
        Optimal gain :math:`F = -B^T X`.
    Wc, Wo : ndarray (N, N)
        Closed-loop Gramians of Eqs. (7) and (8).
    beta2 : float
        Minimal cost :math:`\beta^2 = \mathrm{tr}(b^T X b)` (Eq. 5 [RECON]).
    y_norm2, u_norm2 : float
        :math:`\|y\|_2^2 = \mathrm{tr}(C W_c C^T)` (Eq. 6) and
        :math:`\|u\|_2^2 = \mathrm{tr}(F W_c F^T)` (Eq. 7); :math:`\beta^2 = \gamma^2\|y\|^2 +
        \|u\|^2`.
    energy : ndarray (m,)
        :math:`f_i W_c f_i^T` (f_i row i of F): the energy of control input i; sums to
        :math:`\|u\|^2` (a reading of the paper's "the total energy in each control input").
    printed : ndarray (m,)
        :math:`b_i^T W_o b_i` (Eq. 8 as printed: control energy of an impulse through actuator i).
    gamma : float
    """

    X: FloatArray = field(repr=False)
    F: FloatArray = field(repr=False)
    Wc: FloatArray = field(repr=False)
    Wo: FloatArray = field(repr=False)
    beta2: float
    y_norm2: float
    u_norm2: float
    energy: FloatArray
    printed: FloatArray
    gamma: float


def h2_placement(
    A: npt.ArrayLike, B: npt.ArrayLike, b: npt.ArrayLike, C: npt.ArrayLike, gamma: float = 1.0
) -> H2Placement:
    r"""EPS slew study c. 1989, Eqs. (1)–(8): full-information H2 control and per-actuator energies.

    .. math::

        \dot x = A x + B u + b w, \quad z = [\gamma C x;\; u] \qquad (2)–(3)

        A^T X + X A - X B B^T X + \gamma^2 C^T C = 0, \quad F = -B^T X \qquad (4)

        \beta^2 = \mathrm{tr}(b^T X b) = \gamma^2 \|y\|_2^2 + \|u\|_2^2 \qquad (5)

        (A + BF) W_c + W_c (A + BF)^T + b b^T = 0, \quad \|y\|_2^2 = \mathrm{tr}(C W_c C^T),
        \quad \|u\|_2^2 = \mathrm{tr}(F W_c F^T) \qquad (6)–(7)

        (A + BF)^T W_o + W_o (A + BF) + F^T F = 0, \quad \|u_i\|_2^2 = b_i^T W_o b_i \qquad (8)

    Eq. (7)'s source term is :math:`b b^T` (a misprint repaired; printed "BBᵀ"). Eq. (8) is
    offered both as printed (``printed``) and as :math:`f_i W_c f_i^T` (``energy``), which adds
    up to :math:`\|u\|^2`; they rank differently in general (the paper is ambiguous here).

    Needs (A, B) stabilisable and (A, C) detectable: with rigid-body modes both hold only if
    the actuators can move and the outputs can see every rigid motion. Otherwise the CARE has
    no stabilising solution and a ValueError says so (see :func:`h2_actuator_ranking`).

    Parameters
    ----------
    A : array_like (N, N)
    B : array_like (N, m)
        Candidate actuators, all at once.
    b : array_like (N,) or (N, k)
        Disturbance input(s).
    C : array_like (p, N)
        Performance outputs y.
    gamma : float
        Output weight γ > 0 (not given in the paper).
    """
    A = require_finite(A, "A")
    if A.ndim != 2 or A.shape[0] != A.shape[1] or A.shape[0] == 0:
        raise FieldError("A", f"must be a non-empty square matrix, got shape {A.shape}")
    N = A.shape[0]
    B = require_finite(B, "B")
    B = B[:, None] if B.ndim == 1 else B
    b = require_finite(b, "b")
    b = b[:, None] if b.ndim == 1 else b
    C = require_finite(C, "C")
    C = C[None, :] if C.ndim == 1 else C
    for name, M, ax in (("B", B, 0), ("b", b, 0), ("C", C, 1)):
        if M.ndim != 2 or M.shape[ax] != N:
            raise FieldError(
                name, f"must have {N} {'rows' if ax == 0 else 'columns'}, got shape {M.shape}"
            )
    g = float(require_positive(gamma, "gamma"))
    try:
        X = sla.solve_continuous_are(A, B, g**2 * C.T @ C, np.eye(B.shape[1]))
    except (np.linalg.LinAlgError, ValueError) as exc:
        raise ValueError(
            "A, B, C: the H2 Riccati equation (EPS slew study c. 1989 Eq. 4) has no "
            "stabilising solution: "
            "(A, B) must be stabilisable and (A, C) detectable. With rigid-body modes the "
            "candidates must move and the outputs see every rigid motion, or project the "
            f"rigid modes out (rigid='project'). ({exc})"
        ) from None
    X = 0.5 * (X + X.T)
    F = -B.T @ X
    Acl = A + B @ F
    lam = np.linalg.eigvals(Acl)
    if lam.real.max() >= 0:
        raise ValueError(
            f"A, B, C: the H2 closed loop is not stable (max Re λ = {lam.real.max():.3g}); "
            "(A, B) is not stabilisable or (A, C) not detectable"
        )
    Wc = lyapunov_gramian(Acl, b)
    Wo = lyapunov_gramian(Acl, F, kind="observability")
    energy = np.einsum("ij,jk,ik->i", F, Wc, F)
    printed = np.einsum("ji,jk,ki->i", B, Wo, B)
    return H2Placement(
        X=X,
        F=F,
        Wc=Wc,
        Wo=Wo,
        beta2=float(np.trace(b.T @ X @ b)),
        y_norm2=float(np.trace(C @ Wc @ C.T)),
        u_norm2=float(np.trace(F @ Wc @ F.T)),
        energy=energy,
        printed=printed,
        gamma=g,
    )


@dataclass(frozen=True)
class H2Ranking:
    """Candidate actuators ranked by the EPS slew study c. 1989 Eq. (8) energy, largest first.

    Attributes
    ----------
    ranking : tuple of str
        Candidate labels, best first (by ``measure``).
    scores : dict
        label -> the ranking measure.
    energy, printed : dict
        label -> :math:`f_i W_c f_i^T` and label -> :math:`b_i^T W_o b_i`.
    placement : H2Placement
    measure : str
        "energy" or "printed".
    rigid : str
        "project" or "keep".
    n_modes, n_rigid : int
        Modes in the model and how many of them are rigid (ω <= ``rigid_frequency``).
    """

    ranking: tuple[Hashable, ...]
    scores: dict[Hashable, float]
    energy: dict[Hashable, float]
    printed: dict[Hashable, float]
    placement: H2Placement = field(repr=False)
    measure: str
    rigid: str
    n_modes: int
    n_rigid: int

    def top(self, k: int = 5) -> tuple[Hashable, ...]:
        return self.ranking[: require_count(k, "k")]


def _vectors(
    items: Mapping[_Label, npt.ArrayLike] | npt.ArrayLike, n: int, field_name: str
) -> tuple[list[_Label] | list[int], FloatArray]:
    """Labels and columns (n, k) from a mapping label -> vector (n,) or an (n, k) array."""
    if isinstance(items, Mapping):
        if not items:
            raise FieldError(field_name, "must not be empty")
        labels = list(items)
        cols = [require_finite(items[k], f"{field_name}[{k!r}]") for k in labels]
        for k, v in zip(labels, cols):
            if v.shape != (n,):
                raise FieldError(f"{field_name}[{k!r}]", f"must have shape ({n},), got {v.shape}")
        return labels, np.column_stack(cols)
    arr = modal_inputs(items, n, field_name)
    return list(range(arr.shape[1])), arr


def h2_actuator_ranking(
    model: ModalModel,
    actuators: Mapping[_Label, npt.ArrayLike] | npt.ArrayLike,
    disturbance: npt.ArrayLike,
    outputs: npt.ArrayLike,
    gamma: float = 1.0,
    rigid: str = "project",
    measure: str = "energy",
    velocity_outputs: npt.ArrayLike | None = None,
    rigid_frequency: float | None = None,
) -> H2Ranking:
    r"""Rank candidate actuators of a :class:`~flexsat.structures.modal_model.ModalModel` by
    EPS slew study c. 1989 Eqs. (1)–(8) (:func:`h2_placement` with every candidate in B at once).

    Rigid-body modes (ω <= ``rigid_frequency``, default ``ModalModel.RIGID_FREQUENCY``):

    * ``rigid="project"`` (default): the rigid modes are projected out, i.e. the H2 problem is
      posed on the elastic modal states only. The mass-normalised elastic modes are
      M-orthogonal to the rigid ones, so the elastic subsystem is decoupled from the rigid one
      and this is exact for the vibration, not a truncation. Why: the ranking is "on modal
      energy" ("Actuator Placement") with "only the modal state equations" ("Actuator
      Placement"), and the rigid attitude is
      the torquers' task (the slew and perturbation controllers). With the rigid modes in the
      infinite-horizon cost, an impulse of the CG torquers leaves the body spinning, the
      outputs (node displacements) grow without bound unless the *force* candidates stop the
      rotation, and the ranking then measures moment arm about the CG rather than vibration
      control.
    * ``rigid="keep"``: all modes (rigid ω set to exactly 0). Works only when the candidates
      control and the outputs observe every rigid motion (else ValueError from the Riccati
      equation); offered to show the difference.

    A finite-horizon Gramian (:func:`flexsat.analysis.gramians.finite_horizon_gramian`) is not
    used here: Eqs. (4)–(8) are infinite-horizon (a steady Riccati solution and closed-loop
    Lyapunov equations), and once the rigid modes are out, or stabilised by the feedback,
    every Gramian in them exists.

    Parameters
    ----------
    model : ModalModel
    actuators : mapping label -> modal input vector (n_modes,), or array (n_modes, m)
        The candidates, e.g. from :func:`actuator_candidates`.
    disturbance : array_like (n_modes,) or (n_modes, k)
        Modal input of the disturbance w (e.g. ``model.torque_input(95, ["x", "y", "z"])``).
    outputs : array_like (p, n_modes)
        Displacement output rows (e.g. ``model.displacement_output``).
    gamma : float
        γ of Eq. (1) (not given in the paper; the ranking's sensitivity to it is documented in
        docs/placement.md).
    rigid : {"project", "keep"}
    measure : {"energy", "printed"}
        Ranking measure of Eq. (8) (see :class:`H2Placement`).
    velocity_outputs : array_like (p, n_modes), optional
        Output rows on η̇, added to ``outputs``.
    rigid_frequency : float, optional
        rad/s.
    """
    from flexsat.structures.modal_model import RIGID_FREQUENCY

    if rigid not in RIGID_TREATMENTS:
        raise FieldError("rigid", f"must be one of {RIGID_TREATMENTS}, got {rigid!r}")
    if measure not in ("energy", "printed"):
        raise FieldError("measure", f"must be 'energy' or 'printed', got {measure!r}")
    n = model.n_modes
    labels, Bm = _vectors(actuators, n, "actuators")
    bd = modal_inputs(disturbance, n, "disturbance")
    Cq, Cv = modal_outputs(outputs, velocity_outputs, n)
    wr = RIGID_FREQUENCY if rigid_frequency is None else float(rigid_frequency)
    is_rigid = model.frequencies <= wr
    keep = ~is_rigid if rigid == "project" else np.ones(n, dtype=bool)
    if not keep.any():
        raise FieldError("model", "no elastic mode left after projecting out the rigid modes")
    w = np.where(is_rigid, 0.0, model.frequencies)[keep]
    zeta = np.where(is_rigid, 0.0, model.damping)[keep]
    A, Bz, Cz = modal_state_matrices(w, zeta, Bm[keep], Cq[:, keep], Cv[:, keep])
    _, bz, _ = modal_state_matrices(w, zeta, bd[keep])
    assert Bz is not None and bz is not None and Cz is not None  # all three were given
    result = h2_placement(A, Bz, bz, Cz, gamma)
    energy = dict(zip(labels, result.energy.tolist()))
    printed = dict(zip(labels, result.printed.tolist()))
    scores = energy if measure == "energy" else printed
    ranking = tuple(sorted(labels, key=lambda k: -scores[k]))
    return H2Ranking(
        ranking=ranking,
        scores=scores,
        energy=energy,
        printed=printed,
        placement=result,
        measure=measure,
        rigid=rigid,
        n_modes=int(keep.sum()),
        n_rigid=int(is_rigid.sum()),
    )


# ------------------------------------------------------------------------------------------------
# candidates and their score
#: default label suffix of each candidate kind: a force along an axis is the paper's "69X", a
#: torque about it "69RX" (R for rotation, as the structural rotational dofs rx, ry, rz), so the
#: two at one node never share a label
_KIND_MARK = {"force": "", "torque": "R"}


def actuator_candidates(
    model: ModalModel,
    nodes: Sequence[int],
    axes: Sequence[str] = ("x", "y", "z"),
    kind: str | Sequence[str] = "force",
    label: Callable[[str, int, str], str] | None = None,
) -> dict[str, FloatArray]:
    """Candidate actuators at ``nodes`` along/about ``axes`` as label -> modal input vector.

    ``kind`` is "force" (:meth:`ModalModel.force_input`), "torque"
    (:meth:`ModalModel.torque_input`) or both, ``("force", "torque")``. Default labels: node,
    then "R" for a torque, then the upper-case axis: "69X" (force along x), "69RX" (torque
    about x). A ``label(kind, node, axis)`` of your own must tell every candidate apart: two
    candidates with one label are refused, never one silently replacing the other.
    """
    kinds = (kind,) if isinstance(kind, str) else tuple(kind)
    if not kinds or any(k not in _KIND_MARK for k in kinds) or len(set(kinds)) != len(kinds):
        raise FieldError("kind", f"must be 'force', 'torque' or both (each once), got {kind!r}")
    label = label or (lambda kind, node, axis: f"{node}{_KIND_MARK[kind]}{str(axis).upper()}")
    out: dict[str, FloatArray] = {}
    origin: dict[str, str] = {}
    for k in kinds:
        fn = model.force_input if k == "force" else model.torque_input
        for node in nodes:
            for axis in axes:
                key = label(k, node, axis)
                if key in out:
                    raise FieldError(
                        "label",
                        f"the {origin[key]} and the {k} {node}{axis} are both labelled "
                        f"{key!r}; give labels that tell them apart",
                    )
                out[key], origin[key] = fn(node, axis), f"{k} {node}{axis}"
    return out


def kim_junkins_score(
    model: ModalModel,
    actuators: Mapping[_Label, npt.ArrayLike],
    Cq: npt.ArrayLike | None = None,
    Cv: npt.ArrayLike | None = None,
    Q: float | npt.ArrayLike | None = None,
) -> Score:
    """Score function for the searches: selection (labels of ``actuators``) -> α of
    :func:`kim_junkins_index` on ``model`` (its frequencies and damping)."""
    if not isinstance(actuators, Mapping) or not actuators:
        raise FieldError("actuators", "must be a non-empty mapping label -> modal input vector")
    w, z = model.frequencies, model.damping
    cols: dict[Hashable, FloatArray] = {
        k: require_finite(v, f"actuators[{k!r}]") for k, v in actuators.items()
    }

    def score(selection: Selection) -> float:
        B = np.column_stack([cols[k] for k in selection])
        return kim_junkins_index(w, z, B, Cq, Cv, Q).alpha

    return score
