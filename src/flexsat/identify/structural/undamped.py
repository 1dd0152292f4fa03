"""Undamped structural identification of stiffness and mass scalings: Creamer-Junkins
(Junkins, Pollock & Rahman 1990, Att. 7 Eqs. 1-9), :func:`identify_undamped`.

The model (:class:`~flexsat.identify.structural.substructures.SubstructureModel`) is
``K(p) = K0 + sum_k p_k K_k``, ``M(q) = M0 + sum_k q_k M_k``.

1. Measured frequencies ``wbar_r`` and mode shapes ``psibar_r`` (measured, or approximated
   by the current model's modes).  The shapes have an unknown scale: ``phi_r =
   sqrt(alpha_r) psibar_r`` (Eq. 4).
2. Mass scalings from a few measured FRF elements (Eqs. 5–6 with Eq. 9a): the normalisation
   factors are written through the mass, ``alpha_r = 1 / psibar_r^T M(q) psibar_r`` (Eq.
   7a, i = j), and Eq. 5 is fitted in ``q`` by Gauss-Newton, together with the optional
   rigid-body term ``a1/w^2`` and residual ``a2``; the current model's prediction of the
   unmeasured modes is subtracted from the FRF first (the iteration of Att. 7
   "Identification of Undamped Structures").
3. Stiffness scalings from Eq. 9b, ``psibar_i^T K psibar_j = delta_ij wbar_j^2/alpha_j``,
   linear least squares; with the current model's shapes the diagonal rows are exactly the
   Gauss-Newton step on the eigenvalues, since ``d(lambda_i)/dp_k = phi_i^T K_k phi_i`` and
   ``d(lambda_i)/dq_k = -lambda_i phi_i^T M_k phi_i`` (closed-form sensitivities of
   mass-normalised modes).  The model is re-solved and the steps repeated.

Scale constraint.  Frequencies and shapes alone are unchanged by ``(K, M) -> c (K, M)``, so
only the stiffness-to-mass ratio is identifiable from them.  The absolute scale enters only
through the modal normalisation ``alpha`` (Eq. 4), which the FRF supplies (Eqs. 5–6; Att. 7
advantage 1: "the FRF gives a unique scaling").  Without an FRF the mass scalings are held
at their start values (``alpha_i = 1 / psibar_i^T M(q) psibar_i``: the mass is the known
scale) and only the stiffness scalings are identified.

Departures from the paper's sequence, both found necessary on the Example 1 arm (model
shapes, 4 mass groups): (a) the paper fits each ``alpha_r`` separately (Eq. 6) and then
``q`` from them (Eq. 9a); a weakly participating mode then gets a wrong, even negative,
``alpha_r`` that the mass rows take at full weight, and the iteration diverged.  Fitting
``q`` directly weights each mode by its real share of the FRF.  (b) With model-predicted
shapes a mass change also moves the shapes, the unmeasured modes and, through Eq. 9b, the
stiffness; the mass step differentiates all of these (Nelson mode derivatives), otherwise
it diverged even from 0.01 % off the true model.  ``a2`` is off by default: with the
unmeasured modes predicted by the model it only absorbs the scale information of
quasi-static FRF points.

Off-diagonal rows of Eq. 9 carry information only when the shapes are measured; with
model-predicted shapes they are identities of the current model that would wrongly freeze the
mode shapes, so they are used only with ``measured_shapes`` (override:
``off_diagonal``).

All matrices may be dense arrays or scipy sparse matrices; the eigen-solves are dense (models up
to a few thousand dofs).  Errors are ``ValueError`` naming the field.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from flexsat.analysis.sensitivity import modal_derivatives
from flexsat.identify.structural.least_squares import solve_scalings
from flexsat.identify.structural.substructures import (
    SubstructureModel,
    require_model,
    start_scalings,
)
from flexsat.identify.structural.validation import (
    FrfElement,
    FrfItem,
    FrfRows,
    IntArray,
    check_frf,
    check_indices,
    check_iterations,
    check_mode_indices,
    check_shapes,
)
from flexsat.input_checks import (
    FieldError,
    require_finite,
    require_numeric,
)
from flexsat.units import FloatArray

__all__ = [
    "UndampedIdentification",
    "identify_undamped",
]


def _model_frf(
    K: FloatArray,
    M: FloatArray,
    items: Sequence[FrfItem],
    K_blocks: Sequence[FloatArray] = (),
    M_blocks: Sequence[FloatArray] = (),
) -> list[FrfRows]:
    """Receptance elements of a model at the FRF points (direct solve), with gradients.

    ``h = e_j^T Z^-1 e_k`` with ``Z = K - w^2 M``; ``dh/dp_g = -u^T K_g v`` and ``dh/dq_g = w^2
    u^T M_g v`` with ``u = Z^-1 e_j``, ``v = Z^-1 e_k`` (``dZ^-1 = -Z^-1 dZ Z^-1``).  Returns a
    list of (values (N,), dh/dp (N, len(K_blocks)), dh/dq (N, len(M_blocks))).
    """
    out = []
    for j, k, w, _ in items:
        h = np.empty(w.size)
        hp, hq = np.empty((w.size, len(K_blocks))), np.empty((w.size, len(M_blocks)))
        for i, wi in enumerate(w):
            E = np.zeros((K.shape[0], 2))
            E[j, 0] = E[k, 1] = 1.0
            u, v = np.linalg.solve(K - wi**2 * M, E).T
            h[i] = u[k]
            hp[i] = [-(u @ Kg @ v) for Kg in K_blocks]
            hq[i] = [wi**2 * (u @ Mg @ v) for Mg in M_blocks]
        out.append((h, hp, hq))
    return out


@dataclass(frozen=True)
class UndampedIdentification:
    """Result of :func:`identify_undamped`.

    Attributes
    ----------
    p, q : identified stiffness and mass scalings.
    covariance : ((P+Q), (P+Q)) covariance of ``(p, q)`` (zeros for held parameters).
    frequencies : (m,) model frequencies of the measured modes after identification, rad/s.
    alpha : (m,) modal normalisation factors of the last pass.
    iterations : passes made; history : list of (p, q) per pass; converged : bool.
    """

    p: FloatArray
    q: FloatArray
    covariance: FloatArray
    frequencies: FloatArray
    alpha: FloatArray
    iterations: int
    converged: bool
    history: list[tuple[FloatArray, FloatArray]]


def _pair_modes(
    omega_model: FloatArray,
    phi_model: FloatArray,
    measured_w: FloatArray,
    measured_shapes: FloatArray | None,
    mode_indices: npt.ArrayLike | None,
) -> IntArray:
    if mode_indices is not None:
        return np.asarray(mode_indices, int)
    if measured_shapes is None:
        return np.arange(measured_w.size)
    # match each measured shape to the model mode of largest MAC
    num = (measured_shapes.T @ phi_model) ** 2
    den = np.outer(np.sum(measured_shapes**2, 0), np.sum(phi_model**2, 0))
    idx = np.argmax(num / den, axis=1)
    if len(set(idx.tolist())) != idx.size:
        return np.arange(measured_w.size)
    return idx


def _eq5(
    model: SubstructureModel,
    p: FloatArray,
    q: FloatArray,
    wbar: FloatArray,
    items: Sequence[FrfItem],
    idx: IntArray,
    psi_meas: FloatArray | None,
    free_p: IntArray,
    free_q: IntArray,
) -> list[FrfRows]:
    """Right side of Eq. 5 for the current model, with its gradients.

    ``known + sum_r psibar_jr psibar_kr / (mu_r (wbar_r^2 - w^2))`` where ``known = h_model -
    sum_r phi_jr phi_kr / (lambda_r - w^2)`` is the current model's prediction of the unmeasured
    modes (the iteration of Att. 7 "Identification of Undamped Structures"),
    ``mu_r = psibar_r^T M(q) psibar_r = 1/alpha_r`` (Eq. 7a,
    i = j) and ``psibar`` the measured shapes (fixed) or the model's ``phi`` (``mu = 1``).
    The gradient with respect to the free ``(p, q)`` is exact: model FRF gradient (see
    :func:`_model_frf`) and the measured modes' ``d lambda``, ``d phi`` by Nelson's method.

    Returns, per FRF element: value (N,), gradient (N, Pf + Qf), d value / d wbar (N, m).
    """
    K, M = model.K(p), model.M(q)
    n = model.n_dofs
    Kb = [model.K_blocks[g] for g in free_p]
    Mb = [model.M_blocks[g] for g in free_q]
    zeros = [np.zeros((n, n))]
    md = modal_derivatives(
        K, M, np.array(Kb + zeros * len(Mb)), np.array(zeros * len(Kb) + Mb), modes=idx
    )
    lam, phi, dlam, dphi = md.eigenvalues, md.modes, md.eigenvalue_gradient, md.mode_gradient
    psi = phi if psi_meas is None else psi_meas
    mu = np.einsum("ij,ik,kj->j", psi, M, psi)
    E = np.array([np.einsum("ij,ik,kj->j", psi, Mg, psi) for Mg in Mb]).T
    out = []
    for i, ((j, k, w, _), (hm, hp, hq)) in enumerate(zip(items, _model_frf(K, M, items, Kb, Mb))):
        d_meas = wbar[None, :] ** 2 - w[:, None] ** 2
        if np.any(np.abs(d_meas) < 1e-9 * wbar.max() ** 2):
            raise FieldError(f"frf[{i}].omegas", "a point coincides with a natural frequency")
        d_model = lam[None, :] - w[:, None] ** 2
        pp = phi[j] * phi[k]
        dpp = dphi[:, j, :] * phi[k] + phi[j] * dphi[:, k, :]
        grad = np.hstack([hp, hq]) - (1.0 / d_model) @ dpp.T + (pp / d_model**2) @ dlam.T
        qq = psi[j] * psi[k] / mu
        value = hm - (pp / d_model).sum(axis=1) + (qq / d_meas).sum(axis=1)
        if psi_meas is None:
            grad += (1.0 / d_meas) @ dpp.T
        else:
            grad[:, len(Kb) :] -= (qq / mu / d_meas) @ E
        out.append((value, grad, -qq * 2.0 * wbar[None, :] / d_meas**2))
    return out


def _mass_step(
    model: SubstructureModel,
    psi: FloatArray,
    items: Sequence[FrfItem],
    rows_eq5: Sequence[FrfRows],
    q: FloatArray,
    free_q: IntArray,
    q_prior: FloatArray,
    prior_sd: float | None,
    frf_sd: float,
    pairs_off: Sequence[tuple[int, int]],
    rigid_body: bool,
    residual: bool,
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, int]:
    """One Gauss-Newton step of the joint Eq. 5-6 / 9a fit of the mass scalings.

    ``rows_eq5`` holds per FRF element the residual of Eq. 5 (see :func:`_eq5`), its gradient
    with respect to the free mass scalings and that of the residual with respect to ``wbar``;
    the FRF rows are fitted together with ``a1, a2`` (Eq. 6), the Eq. 9a rows ``i != j``
    (``pairs_off``) and the prior rows.  Returns the step on ``free_q``; its gains with respect
    to the data (frequencies, FRF values, prior values); the relative FRF residuals and their
    degrees of freedom.
    """
    Mq = model.M(q)
    mu = np.einsum("ij,ik,kj->j", psi, Mq, psi)
    nf, Qf = len(items), free_q.size
    n_extra = (int(rigid_body) + int(residual)) * nf
    rows, rhs, sd_rows, r_wbar = [], [], [], []
    for i, ((_, _, w, h), (r, J, dr_dw)) in enumerate(zip(items, rows_eq5)):
        extra = np.zeros((w.size, n_extra))
        if rigid_body:
            extra[:, i] = 1.0 / w**2
        if residual:
            extra[:, (nf if rigid_body else 0) + i] = 1.0
        rows.append(np.hstack([J, extra]))
        rhs.append(r)
        sd_rows.append(frf_sd * np.maximum(np.abs(h), 1e-12 * np.abs(h).max()))
        r_wbar.append(dr_dw)
    n_frf = sum(r.size for r in rhs)
    if pairs_off:
        # Eq. 9a, i != j, in the normalised form psi_i^T M psi_j sqrt(alpha_i alpha_j) = 0,
        # counted like a relative FRF error (as Eq. 9b's rows count like relative w^2 errors)
        s = np.array([1.0 / np.sqrt(mu[i] * mu[j]) for i, j in pairs_off])
        A_off = (
            np.array(
                [[psi[:, i] @ model.M_blocks[g] @ psi[:, j] for g in free_q] for i, j in pairs_off]
            )
            * s[:, None]
        )
        rows.append(np.hstack([A_off, np.zeros((len(pairs_off), n_extra))]))
        rhs.append(-np.array([psi[:, i] @ Mq @ psi[:, j] for i, j in pairs_off]) * s)
        sd_rows.append(np.full(len(pairs_off), frf_sd))
    if prior_sd is not None:
        # Tikhonov rows: the a-priori scalings as pseudo-measurements (Att. 6 Eq. 12, 0_p)
        rows.append(np.hstack([np.eye(Qf), np.zeros((Qf, n_extra))]))
        rhs.append(q_prior[free_q] - q[free_q])
        sd_rows.append(np.full(Qf, prior_sd))
    A, b, sd = np.vstack(rows), np.concatenate(rhs), np.concatenate(sd_rows)
    x, cov, res, _ = solve_scalings(A, b, 1.0 / sd, "mass scalings")
    gain = (cov @ (A.T / sd**2))[:Qf]  # d(step)/d(right side)
    g_w = gain[:, :n_frf] @ np.vstack(r_wbar)
    g_prior = gain[:, A.shape[0] - Qf :] if prior_sd is not None else np.zeros((Qf, 0))
    return (
        x[:Qf],
        g_w,
        gain[:, :n_frf],
        g_prior,
        res[:n_frf] * frf_sd,
        max(n_frf - Qf - n_extra, 0),
    )


def identify_undamped(
    model: SubstructureModel,
    measured_frequencies: npt.ArrayLike,
    measured_shapes: npt.ArrayLike | None = None,
    frf: FrfElement | Sequence[FrfElement] | None = None,
    p0: npt.ArrayLike | None = None,
    q0: npt.ArrayLike | None = None,
    fixed_stiffness: npt.ArrayLike = (),
    fixed_mass: npt.ArrayLike = (),
    frequency_sigma: float | npt.ArrayLike | None = None,
    frf_sigma: float | None = None,
    mass_prior_sigma: float | None = None,
    mode_indices: npt.ArrayLike | None = None,
    off_diagonal: bool | None = None,
    rigid_body: bool = False,
    residual: bool = False,
    n_iter: int = 30,
    tol: float = 1e-10,
    identify_mass: bool | None = None,
) -> UndampedIdentification:
    """Iterated least-squares identification of the stiffness and mass scalings (Eqs. 1–9).

    What identifies what: frequencies and shapes fix only the stiffness-to-mass ratio, since
    ``(K, M) -> c (K, M)`` leaves them unchanged; the FRF fixes the absolute scale through the
    modal normalisation ``alpha_r`` (Eqs. 4–5).  Each pass, with ``psibar`` the measured shapes
    or the current model's modes:

    1. Mass scalings (Eqs. 5–6 and 9a jointly): one Gauss-Newton step of the FRF fit with
       ``alpha_r(q) = 1 / psibar_r^T M(q) psibar_r`` (Eq. 7a, i = j, put into Eq. 5), together
       with ``a1, a2`` and, with measured shapes, the Eq. 9a rows ``i != j``.  A mode counts
       with its actual share of the FRF; ``alpha`` of a weakly participating mode is never
       estimated on its own (the separate Eq. 6 fit, :func:`fit_modal_normalization`, can give
       such a mode a wildly wrong or negative ``alpha``, and Eq. 9a then diverges).  With
       model-predicted shapes the step also differentiates what a mass change does to the shapes
       and to the unmeasured modes, along the path on which Eq. 9b re-fits the stiffness to the
       measured frequencies (``dp/dq`` from the linearised Eq. 9b; the FRF gradient
       ``dh/dx = -u^T (dZ/dx) v``).  Without that term the iteration is unstable for a mass
       group the FRF sees mainly through the mode shapes (the Example 1 tip inertia: it
       diverged even from 0.01 % off the true model).
    2. Stiffness scalings (Eq. 9b) with ``alpha_r = alpha_r(q)`` of the new mass, i.e.
       ``psibar_i^T K(p) psibar_i = wbar_i^2 psibar_i^T M(q) psibar_i``.

    Without an FRF the mass scalings are held (the mass is the known scale).  With
    ``mass_prior_sigma`` the start mass scalings enter as pseudo-measurements (Tikhonov
    regularisation, Att. 6 Eq. 12 ``0_p``) for mass groups the FRF observes weakly.

    Parameters
    ----------
    model : SubstructureModel
    measured_frequencies : (m,) rad/s, > 0, of the lowest modes (or of ``mode_indices``).
    measured_shapes : (n, m), optional
        Measured shapes on all dofs (any scale).  Default: the current model's modes, refreshed
        every pass (Att. 7 Examples 1–2).
    frf : (j, k, omegas, values) or list, optional
        Measured receptance elements (real, away from resonance).  Needed to identify the mass
        scalings; without it they are held.
    p0, q0 : start scalings (default 1).  fixed_stiffness, fixed_mass : indices held at start.
    frequency_sigma : (m,) or scalar, optional
        Standard deviation of the measured frequencies, rad/s.
    frf_sigma : float, optional
        Relative standard deviation of the FRF values (e.g. 0.005 for 0.5 %).
    mass_prior_sigma : float, optional
        Standard deviation of the mass scalings about ``q0``; needs ``frf_sigma`` (the prior is
        weighted against it).
    mode_indices : model mode numbers (0-based) of the measured modes; default by order (or by
        MAC with measured shapes).
    off_diagonal : use the i != j rows of Eq. 9 (default: only with measured shapes).
    rigid_body, residual : FRF fit terms ``a1/w^2`` and ``a2`` (Eq. 5); ``a2`` is off by
        default (see the module notes).
    identify_mass : default: True when an FRF is given.

    Returns
    -------
    UndampedIdentification
        ``covariance`` propagates the frequency, FRF and prior standard deviations linearly
        through the last pass (shapes counted exact); a standard deviation not given is
        estimated from the residual scatter (zero covariance for an exact fit).
    """
    model = require_model(model)
    P, Q, n = model.n_stiffness, model.n_mass, model.n_dofs
    wbar = require_finite(measured_frequencies, "measured_frequencies", "rad/s")
    if wbar.ndim > 1 or wbar.size == 0 or np.any(wbar <= 0):
        raise FieldError("measured_frequencies", "must be a non-empty vector of values > 0 rad/s")
    wbar = wbar.ravel()
    m = wbar.size
    if m > n:
        raise FieldError("measured_frequencies", f"{m} modes but the model has {n} dofs")
    n_iter, tol = check_iterations(n_iter, tol)
    mode_indices = check_mode_indices(mode_indices, m, n)
    psi_meas = None
    if measured_shapes is not None:
        psi_meas = check_shapes(measured_shapes, "measured_shapes")
        if psi_meas.shape != (n, m):
            raise FieldError("measured_shapes", f"must have shape ({n}, {m}), got {psi_meas.shape}")
    items = check_frf(frf, n)
    identify_mass = bool(items) if identify_mass is None else bool(identify_mass)
    if identify_mass and not items:
        raise FieldError(
            "identify_mass",
            "the mass scalings need an FRF (the absolute scale; "
            "frequencies and shapes are unchanged by scaling K and M together)",
        )
    if off_diagonal is None:
        off_diagonal = psi_meas is not None
    p = start_scalings(model, p0, P, "p0")
    q = start_scalings(model, q0, Q, "q0")
    q_prior = q.copy()
    free_p = np.setdiff1d(np.arange(P), check_indices(fixed_stiffness, P, "fixed_stiffness"))
    held_q = check_indices(fixed_mass, Q, "fixed_mass")
    free_q = np.setdiff1d(np.arange(Q), held_q) if identify_mass else np.array([], int)
    if free_p.size == 0 and free_q.size == 0:
        raise FieldError(
            "fixed_stiffness",
            "every parameter is fixed (with fixed_mass, or the mass held without an FRF)",
        )
    sig_w = None
    if frequency_sigma is not None:
        sig = require_finite(frequency_sigma, "frequency_sigma", "rad/s")
        if sig.ndim > 1 or (sig.ndim == 1 and sig.size != m):
            raise FieldError(
                "frequency_sigma", f"must be a scalar or {m} values (one per mode), got {sig.shape}"
            )
        sig_w = np.broadcast_to(sig, (m,)).astype(float)
        if np.any(sig_w <= 0):
            raise FieldError("frequency_sigma", "must be > 0")
    for name, value in (("frf_sigma", frf_sigma), ("mass_prior_sigma", mass_prior_sigma)):
        if value is not None and (np.ndim(value) != 0 or float(require_numeric(value, name)) <= 0):
            raise FieldError(name, "must be a scalar > 0")
    if mass_prior_sigma is not None and frf_sigma is None:
        raise FieldError(
            "mass_prior_sigma",
            "needs frf_sigma (the prior is weighted against the FRF's standard deviation)",
        )
    pairs = [(i, i) for i in range(m)]
    pairs_off = [(i, j) for i in range(m) for j in range(i + 1, m)] if off_diagonal else []
    pairs += pairs_off
    n_rows = len(pairs)
    limits = [("stiffness", free_p.size)]
    if mass_prior_sigma is None:
        limits.append(("mass", free_q.size))
    for name, count in limits:
        if count > n_rows:
            raise FieldError(
                "measured_frequencies",
                f"{n_rows} equations for {count} {name} parameters: "
                "more parameters than data (Att. 7 needs m(m+1)/2 > parameters with measured "
                "shapes, m >= parameters without): measure more modes or fix parameters",
            )
    ii = np.array([i for i, _ in pairs])
    jj = np.array([j for _, j in pairs])
    rel = np.ones(m) if sig_w is None else 2.0 * sig_w / wbar
    frf_sd = 1.0 if frf_sigma is None else float(frf_sigma)

    history, converged = [(p.copy(), q.copy())], False
    for it in range(1, n_iter + 1):  # noqa: B007 - the last count is reported
        K = model.K(p)
        w_model, phi_model = model.modes(p, q)
        idx = _pair_modes(w_model, phi_model, wbar, psi_meas, mode_indices)
        psi = psi_meas if psi_meas is not None else phi_model[:, idx]
        mu = np.einsum("ij,ik,kj->j", psi, model.M(q), psi)
        # --- Eq. 9b system: rows, weights and the gain d(p)/d(right side) -----------------
        # row weights: relative residuals (a low mode counts as much as a high one); with
        # frequency_sigma, 1/SD of the right side (row i=i: wbar^2/alpha, SD 2 wbar sigma/alpha)
        weights_k = (
            np.sqrt(1.0 / (mu[ii] * mu[jj])) / (wbar[ii] * wbar[jj]) / np.sqrt(rel[ii] * rel[jj])
        )
        A_k = np.array(
            [[psi[:, i] @ model.K_blocks[g] @ psi[:, j] for g in free_p] for i, j in pairs]
        ).reshape(n_rows, free_p.size)
        Kfix = K - sum((p[g] * model.K_blocks[g] for g in free_p), np.zeros((n, n)))
        kfix = np.array([psi[:, i] @ Kfix @ psi[:, j] for i, j in pairs])
        gain_k = np.zeros((free_p.size, n_rows))
        if free_p.size:
            # (A^T W A)^-1 and the identifiability checks now; the right side needs the new q
            _, c_k, _, dof_k = solve_scalings(A_k, -kfix, weights_k, "stiffness scalings")
            gain_k = c_k @ (A_k.T * weights_k**2)
        db_dw = np.zeros((n_rows, m))  # right side of Eq. 9b: wbar_i^2 mu_i(q) - ...
        db_dw[np.arange(m), np.arange(m)] = 2.0 * wbar * mu
        E = np.array(
            [np.einsum("ij,ik,kj->j", psi, model.M_blocks[g], psi) for g in free_q]
        ).T.reshape(m, free_q.size)
        db_dq = np.zeros((n_rows, free_q.size))
        db_dq[:m] = wbar[:, None] ** 2 * E
        # --- Eqs. 5-6 and 9a jointly: mass scalings ------------------------------------------
        q_new = q.copy()
        if free_q.size:
            # gradients along the path on which Eq. 9b keeps the measured frequencies:
            # dp = D dq with D = d(p)/d(q) of the linearised Eq. 9b
            D, G_w = gain_k @ db_dq, gain_k @ db_dw
            rows_eq5 = [
                (
                    h - value,
                    grad[:, : free_p.size] @ D + grad[:, free_p.size :],
                    -d_wbar - grad[:, : free_p.size] @ G_w,
                )
                for (*_, h), (value, grad, d_wbar) in zip(
                    items, _eq5(model, p, q, wbar, items, idx, psi_meas, free_p, free_q)
                )
            ]
            dq, g_qw, g_qh, g_qprior, rel_frf, dof_frf = _mass_step(
                model,
                psi,
                items,
                rows_eq5,
                q,
                free_q,
                q_prior,
                mass_prior_sigma,
                frf_sd,
                pairs_off,
                rigid_body,
                residual,
            )
            q_new[free_q] += dq
        # --- Eq. 9b: stiffness scalings, alpha_i = 1 / psibar_i^T M(q_new) psibar_i ---------
        p_new = p.copy()
        if free_p.size:
            b = -kfix + db_dq @ (q_new - q)[free_q] if free_q.size else -kfix.copy()
            b[:m] += wbar**2 * mu
            p_new[free_p] = gain_k @ b
            res_k = (b - A_k @ p_new[free_p]) * weights_k
        # scalings must stay positive (K, M definite): shorten a step that leaves them
        dp, dq_all, t = p_new - p, q_new - q, 1.0
        while t > 1e-6 and (np.any(p + t * dp <= 0) or np.any(q + t * dq_all <= 0)):
            t *= 0.5
        if t <= 1e-6:
            raise ValueError(
                "identification diverged: the least-squares step makes a scaling "
                f"non-positive (p={p_new}, q={q_new}); fix weakly observed "
                "parameters (see modal_energy_distribution)"
            )
        p_new, q_new = p + t * dp, q + t * dq_all
        step = max(np.abs(p_new - p).max(), np.abs(q_new - q).max() if Q else 0.0)
        p, q = p_new, q_new
        history.append((p.copy(), q.copy()))
        if step < tol:
            converged = True
            break

    # --- covariance: the last pass's estimates as linear functions of the data -------------
    # data d = (wbar, FRF values, prior values); S = d(p, q)/d(d); cov = S diag(sd_d^2) S^T
    n_h = sum(h.size for *_, h in items) if free_q.size else 0
    n_pr = free_q.size if mass_prior_sigma is not None else 0
    S = np.zeros((P + Q, m + n_h + n_pr))
    sd = np.zeros(m + n_h + n_pr)
    if free_q.size:
        S[np.ix_(P + free_q, np.arange(m))] = g_qw
        S[np.ix_(P + free_q, m + np.arange(n_h))] = g_qh
        if n_pr:
            S[np.ix_(P + free_q, m + n_h + np.arange(n_pr))] = g_qprior
            sd[m + n_h :] = mass_prior_sigma
        s_h = (
            frf_sigma
            if frf_sigma is not None
            else (np.sqrt(rel_frf @ rel_frf / dof_frf) if dof_frf > 0 else 0.0)
        )
        sd[m : m + n_h] = s_h * np.concatenate([np.abs(h) for *_, h in items])
    if free_p.size:
        # Eq. 9b's right side depends on wbar directly and through the new q
        S[np.ix_(free_p, np.arange(m))] = gain_k @ db_dw
        if free_q.size:
            S[free_p] += gain_k @ db_dq @ S[P + free_q]
        if sig_w is not None:
            sd[:m] = sig_w
        elif dof_k > 0:
            # weighted rows are relative eigenvalue errors: SD(w)/w = SD(w^2) / (2 w^2)
            sd[:m] = 0.5 * wbar * np.sqrt(res_k @ res_k / dof_k)
    cov = (S * sd**2) @ S.T
    w_final, phi_final = model.modes(p, q)
    idx = _pair_modes(w_final, phi_final, wbar, psi_meas, mode_indices)
    return UndampedIdentification(p, q, cov, w_final[idx], 1.0 / mu, it, converged, history)
