r"""H∞ suboptimal output feedback by the two-Riccati formulas, with γ found by bisection.

For the plant of :mod:`~flexsat.control.generalized_plant` with D11 = 0, D22 = 0, D12 of full
column rank, D21 of full row rank and the rank conditions on the imaginary axis (Doyle, Glover,
Khargonekar & Francis, "State-space solutions to standard H2 and H∞ control problems", IEEE
Transactions on Automatic Control 34(8), 1989, 831–847; with the cross terms
D12ᵀC1 and B1D21ᵀ and general D12ᵀD12, D21D21ᵀ kept, as in Zhou, Doyle & Glover, *Robust and
Optimal Control*, Prentice Hall, 1996, Chapters 16–17), a compensator with
:math:`\|T_{zw}\|_\infty < \gamma` exists iff

1. the Riccati equation
   :math:`A^TX + XA - (XB + S_1)\,\mathcal R_1^{-1}(B^TX + S_1^T) + C_1^TC_1 = 0`, with
   :math:`B = [B_1\; B_2]`, :math:`\mathcal R_1 = \operatorname{diag}(-\gamma^2 I, D_{12}^TD_{12})`,
   :math:`S_1 = [0\;\; C_1^TD_{12}]`, has a stabilizing solution :math:`X_\infty \succeq 0`;
2. its dual, :math:`AY + YA^T - (YC^T + S_2)\,\mathcal R_2^{-1}(CY + S_2^T) + B_1B_1^T = 0`,
   :math:`C = [C_1; C_2]`, :math:`\mathcal R_2 = \operatorname{diag}(-\gamma^2 I, D_{21}D_{21}^T)`,
   :math:`S_2 = [0\;\; B_1D_{21}^T]`, has one, :math:`Y_\infty \succeq 0`;
3. :math:`\rho(X_\infty Y_\infty) < \gamma^2`.

Then the central compensator is the observer of the worst-case disturbance
:math:`\hat w = \gamma^{-2}B_1^TX_\infty\hat x`:

.. math::

    \dot{\hat x} = A\hat x + B_1\hat w + B_2 u + Z_\infty L_\infty(C_2\hat x + D_{21}\hat w - y),
    \qquad u = F_\infty\hat x,

    F_\infty = -(D_{12}^TD_{12})^{-1}(B_2^TX_\infty + D_{12}^TC_1), \quad
    L_\infty = -(Y_\infty C_2^T + B_1D_{21}^T)(D_{21}D_{21}^T)^{-1}, \quad
    Z_\infty = (I - \gamma^{-2}Y_\infty X_\infty)^{-1}.

The Riccati equations are solved by ``scipy.linalg.solve_continuous_are`` with the indefinite
weight :math:`\mathcal R` (generalized Schur method on the extended pencil), and a solution is
accepted only when its residual is at round-off, its closed loop is stable and it is positive
semi-definite. The optimal γ is bracketed by bisection (:func:`hinfsyn`): the upper end starts
at the H∞ norm of the closed loop with the H2-optimal compensator (any γ above the norm a
compensator achieves is feasible) and the bracket [γ_lower, γ] shrinks until
γ − γ_lower <= rtol γ; the compensator returned is the central one at γ, so its achieved norm
lies in [γ_opt, γ) ⊂ [γ_lower, γ]. python-control's ``hinfsyn`` computes the same through
slycot (SB10AD).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import scipy.linalg as sla

from flexsat.analysis.norms import hinf_norm
from flexsat.control.generalized_plant import GeneralizedPlant, closed_loop
from flexsat.control.h2_synthesis import SynthesisCompensator, as_generalized_plant, h2syn
from flexsat.input_checks import FieldError

if TYPE_CHECKING:
    import control as ct
    from flexsat.units import FloatArray

__all__ = [
    "HinfCentral",
    "HinfController",
    "HinfSynthesis",
    "InfeasibleGamma",
    "hinf_central",
    "hinfsyn",
]

#: relative Riccati residual above which a solution is not accepted
RESIDUAL_TOL = 1e-8


class InfeasibleGamma(FieldError):
    """No compensator reaches ‖T_zw‖∞ < γ (the message names the condition that fails)."""


@dataclass(frozen=True)
class HinfCentral:
    """The central compensator at one γ (module docstring).

    Attributes
    ----------
    controller : control.StateSpace
        K (y → u, u = K y).
    gamma : float
    X, Y : ndarray
        X∞ and Y∞.
    F, L : ndarray
        F∞ and L∞.
    """

    controller: ct.StateSpace
    gamma: float
    X: FloatArray
    Y: FloatArray
    F: FloatArray
    L: FloatArray


def _riccati(
    A: FloatArray,
    B: FloatArray,
    Q: FloatArray,
    R: FloatArray,
    S: FloatArray,
    what: str,
) -> FloatArray:
    """Stabilizing solution of AᵀX + XA − (XB + S)R⁻¹(BᵀX + Sᵀ) + Q = 0 with R indefinite,
    checked (residual, stability, X ⪰ 0), or InfeasibleGamma naming ``what``."""
    try:
        X = sla.solve_continuous_are(A, B, Q, R, s=S)
    except (np.linalg.LinAlgError, ValueError) as exc:
        raise InfeasibleGamma("gamma", f"{what}: no stabilizing solution ({exc})") from None
    if not np.all(np.isfinite(X)):
        raise InfeasibleGamma("gamma", f"{what}: no finite stabilizing solution")
    X = 0.5 * (X + X.T)
    XBS = X @ B + S
    quad = XBS @ np.linalg.solve(R, XBS.T)
    AtX = A.T @ X
    res = np.linalg.norm(AtX + AtX.T - quad + Q)
    scale = 2 * np.linalg.norm(AtX) + np.linalg.norm(quad) + np.linalg.norm(Q)
    if res > RESIDUAL_TOL * max(scale, np.finfo(float).tiny):
        raise InfeasibleGamma(
            "gamma", f"{what}: the Riccati solution has relative residual {res / scale:.2e}"
        )
    Acl = A - B @ np.linalg.solve(R, XBS.T)
    if np.max(np.linalg.eigvals(Acl).real) >= 0:
        raise InfeasibleGamma("gamma", f"{what}: the Riccati solution is not stabilizing")
    lam = np.linalg.eigvalsh(X)
    if lam.size and lam.min() < -1e-9 * max(1.0, float(np.abs(lam).max())):
        raise InfeasibleGamma(
            "gamma",
            f"{what}: the stabilizing solution is not positive semi-definite "
            f"(eigenvalue {lam.min():.3g})",
        )
    return np.asarray(X, float)


def hinf_central(P: GeneralizedPlant, gamma: float) -> HinfCentral:
    r"""The central compensator with ‖T_zw‖∞ < γ (module docstring).

    Raises
    ------
    InfeasibleGamma
        When γ <= γ_opt: the condition (X∞, Y∞ or the coupling ρ(X∞Y∞) < γ²) that fails.
    FieldError
        A non-positive γ or a plant outside the assumptions.
    """
    import control as ct

    if not (isinstance(gamma, float | int) and np.isfinite(gamma) and gamma > 0):
        raise FieldError("gamma", f"must be a positive finite number, got {gamma!r}")
    g = float(gamma)
    P.require_regular(need_d11_zero=True)
    A, B1, B2, C1, C2 = P.A, P.B1, P.B2, P.C1, P.C2
    D12, D21 = P.D12, P.D21
    n, nw, nu, nz, ny = P.sizes
    R1, R2 = D12.T @ D12, D21 @ D21.T
    X = _riccati(
        A,
        np.hstack([B1, B2]),
        C1.T @ C1,
        sla.block_diag(-(g**2) * np.eye(nw), R1),
        np.hstack([np.zeros((n, nw)), C1.T @ D12]),
        "X∞ (state feedback)",
    )
    Y = _riccati(
        A.T,
        np.hstack([C1.T, C2.T]),
        B1 @ B1.T,
        sla.block_diag(-(g**2) * np.eye(nz), R2),
        np.hstack([np.zeros((n, nz)), B1 @ D21.T]),
        "Y∞ (output injection)",
    )
    rho = float(np.max(np.abs(np.linalg.eigvals(X @ Y))))
    if rho >= g**2 * (1 - 1e-9):
        raise InfeasibleGamma(
            "gamma", f"coupling: ρ(X∞Y∞) = {rho:.6g} is not below γ² = {g**2:.6g}"
        )
    F = -np.linalg.solve(R1, B2.T @ X + D12.T @ C1)
    L = -np.linalg.solve(R2.T, (Y @ C2.T + B1 @ D21.T).T).T
    Z = np.linalg.inv(np.eye(n) - Y @ X / g**2)
    W = B1.T @ X / g**2  # worst-case disturbance gain, ŵ = W x̂
    Ak = A + B1 @ W + B2 @ F + Z @ L @ (C2 + D21 @ W)
    controller = ct.ss(
        Ak,
        -Z @ L,
        F,
        np.zeros((nu, ny)),
        states=[f"x_hat[{i}]" for i in range(n)],
        inputs=list(P.measurement_names),
        outputs=list(P.control_names),
        name="hinf",
    )
    return HinfCentral(controller, g, X, Y, np.asarray(F, float), np.asarray(L, float))


@dataclass(frozen=True)
class HinfSynthesis:
    """Result of :func:`hinfsyn`.

    Attributes
    ----------
    controller : control.StateSpace
        The central compensator at ``gamma`` (u = K y).
    gamma : float
        Upper end of the final bracket: a γ the compensator meets.
    gamma_lower : float
        Lower end: γ_opt > gamma_lower (infeasible, or 0).
    achieved : float
        ‖T_zw‖∞ of the closed loop with ``controller`` (:func:`~flexsat.analysis.norms.hinf_norm`).
    central : HinfCentral
        X∞, Y∞, F∞, L∞ at ``gamma``.
    iterations : int
        Bisection steps taken.
    plant : GeneralizedPlant
    """

    controller: ct.StateSpace
    gamma: float
    gamma_lower: float
    achieved: float
    central: HinfCentral
    iterations: int
    plant: GeneralizedPlant


def hinfsyn(
    P: GeneralizedPlant | ct.StateSpace,
    nmeas: int | None = None,
    ncon: int | None = None,
    rtol: float = 1e-4,
    gamma_max: float | None = None,
) -> HinfSynthesis:
    r"""Near-optimal H∞ compensator by bisection on γ (module docstring).

    Parameters
    ----------
    P : GeneralizedPlant or control.StateSpace
        Continuous; a StateSpace is partitioned like python-control's ``hinfsyn(P, nmeas,
        ncon)``.
    nmeas, ncon : int, optional
        Number of measurements (last outputs) and controls (last inputs) of a StateSpace.
    rtol : float
        Relative width of the final bracket, in (0, 0.5).
    gamma_max : float, optional
        Upper end to start from (default: 1.01 × the norm the H2 compensator achieves).

    Returns
    -------
    HinfSynthesis

    Raises
    ------
    FieldError
        Bad rtol / gamma_max, or a plant outside the assumptions.
    InfeasibleGamma
        When ``gamma_max`` is given and is infeasible.
    """
    if not (isinstance(rtol, float | int) and 0 < rtol < 0.5):
        raise FieldError("rtol", f"must be a number in (0, 0.5), got {rtol!r}")
    G = as_generalized_plant(P, nmeas, ncon)
    G.require_regular(need_d11_zero=True)
    if gamma_max is None:
        h2 = h2syn(G)
        hi = 1.01 * hinf_norm(closed_loop(G, h2.controller), field="H2 closed loop").value
        # feasible in exact arithmetic (the H2 compensator reaches below it); should round-off
        # refuse it, the upper end is doubled a few times before giving up
        for _ in range(8):
            try:
                best = hinf_central(G, hi)
                break
            except InfeasibleGamma:
                hi *= 2.0
        else:
            best = hinf_central(G, hi)
    else:
        if not (isinstance(gamma_max, float | int) and np.isfinite(gamma_max) and gamma_max > 0):
            raise FieldError("gamma_max", f"must be a positive number, got {gamma_max!r}")
        hi = float(gamma_max)
        best = hinf_central(G, hi)
    lo = 0.0
    steps = 0
    while hi - lo > rtol * hi:
        mid = 0.5 * (lo + hi) if lo == 0.0 or hi > 4 * lo else float(np.sqrt(lo * hi))
        steps += 1
        try:
            best = hinf_central(G, mid)
        except InfeasibleGamma:
            lo = mid
        else:
            hi = mid
    achieved = hinf_norm(closed_loop(G, best.controller), field="H∞ closed loop").value
    return HinfSynthesis(best.controller, hi, lo, achieved, best, steps, G)


class HinfController(SynthesisCompensator):
    """An H∞ compensator as a flexsat law (a continuous
    :class:`~flexsat.control.state_space_compensator.StateSpaceCompensator`, run through its
    exact zero-order-hold equivalent at the control period).

    Parameters
    ----------
    synthesis : HinfSynthesis
        The design (:func:`hinfsyn`), kept as ``.synthesis``.
    dt : float, str or Quantity
        Control period, s.
    measurements, commands : sequence of str or Channel, optional
        The plant channels y and u are (default the generalized plant's names of y and u).
    references : mapping {channel: value}, optional
        Set points subtracted from the measurements.
    """

    synthesis_type = HinfSynthesis
    designer = "hinfsyn"
