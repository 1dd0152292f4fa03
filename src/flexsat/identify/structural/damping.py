"""Damping scalings from measured eigenvalues: Creamer-Junkins (Junkins, Pollock & Rahman
1990, Att. 7 Eqs. 10-24), :func:`identify_damping`, and the exact damped eigenvalues of a
model (:func:`damped_eigenvalues`).

First-order perturbation of the state-space eigenproblem about the undamped model gives
``lambda_r ~= i w_0r - (1/2) phi_0r^T C phi_0r`` with mass-normalised ``phi_0r`` (Eq. 23): the
measured real parts ``sigmabar_r`` give the linear least-squares problem (Eq. 24)
``sum_k r_k phi_0r^T C_k phi_0r = -2 sigmabar_r - phi_0r^T C0 phi_0r`` in configuration
space (no 2n-dimensional eigenproblem).  The blocks ``C_k`` need only the right coupling
pattern; their magnitudes may be off by orders of magnitude (the scalings absorb them).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from flexsat.identify.structural.least_squares import solve_scalings
from flexsat.identify.structural.substructures import (
    SubstructureModel,
    require_model,
    start_scalings,
)
from flexsat.identify.structural.validation import (
    ComplexArray,
    IntArray,
    as_array_like,
    check_indices,
    check_mode_indices,
)
from flexsat.input_checks import (
    FieldError,
    require_count,
    require_numeric,
)
from flexsat.structures.modal_solve import Matrix
from flexsat.units import FloatArray

__all__ = [
    "DampingIdentification",
    "damped_eigenvalues",
    "identify_damping",
]


@dataclass(frozen=True)
class DampingIdentification:
    """Result of :func:`identify_damping`.

    Attributes
    ----------
    r : (R,) damping scalings; covariance : (R, R).
    predicted_real_parts : (m,) first-order ``-(1/2) phi^T C(r) phi`` of the measured modes.
    eigenvalues : (m,) complex eigenvalues of the identified damped model (exact state-space
        solve, for checking the first-order theory).
    mode_indices : (m,) model mode paired with each measured eigenvalue.
    """

    r: FloatArray
    covariance: FloatArray
    predicted_real_parts: FloatArray
    eigenvalues: ComplexArray
    mode_indices: IntArray


def damped_eigenvalues(K: Matrix, M: Matrix, C: Matrix, n_modes: int | None = None) -> ComplexArray:
    """Eigenvalues of ``M x'' + C x' + K x = 0`` with positive imaginary part, by frequency."""
    Kd = require_numeric(as_array_like(K), "K", "matrix")
    if Kd.ndim != 2 or Kd.shape[0] != Kd.shape[1] or Kd.size == 0:
        raise FieldError("K", f"must be a non-empty square matrix, got shape {Kd.shape}")
    n = Kd.shape[0]
    Md, Cd = (require_numeric(as_array_like(A), name, "matrix") for A, name in ((M, "M"), (C, "C")))
    for A, name in ((Md, "M"), (Cd, "C")):
        if A.shape != (n, n):
            raise FieldError(name, f"must be {n}x{n} like K, got shape {A.shape}")
    try:
        np.linalg.cholesky((Md + Md.T) / 2.0)
    except np.linalg.LinAlgError:
        raise FieldError("M", "must be positive definite (a mass on every dof)") from None
    count = None if n_modes is None else require_count(n_modes, "n_modes")
    Minv = np.linalg.inv(Md)
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-Minv @ Kd, -Minv @ Cd]])
    lam = np.linalg.eigvals(A).astype(complex)
    lam = lam[lam.imag > 0]
    lam = lam[np.argsort(lam.imag)]
    return lam if count is None else lam[:count]


def identify_damping(
    model: SubstructureModel,
    measured_eigenvalues: npt.ArrayLike,
    p: npt.ArrayLike | None = None,
    q: npt.ArrayLike | None = None,
    mode_indices: npt.ArrayLike | None = None,
    fixed: npt.ArrayLike = (),
    r0: npt.ArrayLike | None = None,
) -> DampingIdentification:
    """Damping scalings from measured eigenvalue real parts by first-order perturbation.

    Att. 7 Eq. 24: ``sum_k r_k phi_0r^T C_k phi_0r = -2 sigmabar_r - phi_0r^T C0 phi_0r`` with
    ``phi_0r`` the mass-normalised modes of the undamped model ``K(p), M(q)`` (the identified
    one).  The first-order theory predicts no frequency shift, so only the real parts are used.

    Parameters
    ----------
    model : SubstructureModel with ``C_blocks``.
    measured_eigenvalues : (m,) complex (``sigma + i w``, ``w != 0``) or real parts only
        (sigma < 0). Complex eigenvalues, in any order, are paired with the model modes by
        natural frequency ``|lambda|``: each with the nearest elastic model mode in
        ``|ln(|lambda| / w_model)|``, which must be at most half as far as the second nearest
        (else the pairing is ambiguous: an error), one eigenvalue per mode. Real parts carry
        no frequency and are paired in order with ``mode_indices``.
    p, q : undamped scalings (e.g. from :func:`identify_undamped`).
    mode_indices : model modes of the measured eigenvalues, in their order (default: matched by
        frequency, or the lowest m for real parts); refused when the frequencies clearly
        contradict it.
    fixed : damping blocks held at ``r0`` (default 1).
    """
    model = require_model(model)
    R = model.n_damping
    if R == 0:
        raise FieldError("C_blocks", "the model has no damping blocks")
    lam = np.asarray(measured_eigenvalues)
    if isinstance(measured_eigenvalues, (str, bytes)) or lam.dtype.kind not in "biufc":
        raise FieldError("measured_eigenvalues", "must be a numeric (complex) vector")
    lam = lam.ravel().astype(complex)
    if lam.size == 0 or not np.all(np.isfinite(lam)):
        raise FieldError(
            "measured_eigenvalues", "must be a non-empty finite vector (no NaN or inf)"
        )
    sigma = lam.real
    if np.any(sigma >= 0):
        raise FieldError(
            "measured_eigenvalues", "real parts must be < 0 (a damped, stable structure)"
        )
    m = sigma.size
    r = model.check_scalings(r0, R, "r0").copy()
    free = np.setdiff1d(np.arange(R), check_indices(fixed, R, "fixed"))
    if free.size == 0:
        raise FieldError("fixed", "every damping parameter is fixed")
    if free.size > m:
        raise FieldError(
            "measured_eigenvalues",
            f"{m} eigenvalues for {free.size} damping "
            "parameters: more parameters than data (Att. 7 needs m > R)",
        )
    w0, phi = model.modes(
        start_scalings(model, p, model.n_stiffness, "p"),
        start_scalings(model, q, model.n_mass, "q"),
    )
    given = check_mode_indices(mode_indices, m, phi.shape[1])
    if np.all(lam.imag == 0):  # real parts carry no frequency: paired in order
        idx = np.arange(m) if given is None else given
        if idx.max() >= phi.shape[1]:
            raise FieldError("mode_indices", "must give one model mode per measured eigenvalue")
    elif np.any(lam.imag == 0):
        raise FieldError(
            "measured_eigenvalues",
            "give every eigenvalue as sigma + i w with w != 0 "
            "(matched to the model frequencies) or every one as its real part "
            "sigma (paired in order)",
        )
    else:
        idx = _match_modes(w0, np.abs(lam), given)
    phi = phi[:, idx]
    Cfix = model.C(r) - sum((r[g] * model.C_blocks[g] for g in free), np.zeros_like(model.C0))
    A = np.array([[phi[:, i] @ model.C_blocks[g] @ phi[:, i] for g in free] for i in range(m)])
    b = np.array([-2.0 * sigma[i] - phi[:, i] @ Cfix @ phi[:, i] for i in range(m)])
    x, c, res, dof = solve_scalings(A, b, np.ones(m), "damping scalings")
    r[free] = x
    cov = np.zeros((R, R))
    cov[np.ix_(free, free)] = c * ((res @ res / dof) if dof > 0 else 0.0)
    C = model.C(r)
    predicted = -0.5 * np.einsum("ij,ik,kj->j", phi, C, phi)
    eig = damped_eigenvalues(model.K(p), model.M(q), C)
    # pair exact eigenvalues with the undamped modes by frequency
    eig = eig[[int(np.argmin(np.abs(eig.imag - w0[i]))) for i in idx]]
    return DampingIdentification(r, cov, predicted, eig, idx)


def _match_modes(
    w_model: FloatArray, w_meas: FloatArray, mode_indices: IntArray | None = None
) -> IntArray:
    """Model mode of each measured natural frequency ``|lambda|`` (rad/s).

    Distances are ``|ln(w_meas / w_model)|`` (relative: spectra span decades) to the elastic
    model modes. A measured frequency is matched when its nearest model mode is at most half as
    far as the second nearest; otherwise it lies near the middle between two model modes and
    the pairing is ambiguous (the model may lack the measured mode). Each model mode takes at
    most one measured eigenvalue. Given ``mode_indices`` are used as the pairing, refused only
    where a clear match contradicts them (eigenvalues listed in another order).
    """
    elastic = np.flatnonzero(w_model > 0)
    if elastic.size == 0:
        raise FieldError("measured_eigenvalues", "the model has no elastic mode to match them to")
    d = np.abs(np.log(w_meas[:, None] / w_model[None, elastic]))
    order = np.argsort(d, axis=1)
    near = elastic[order[:, 0]]
    rows = np.arange(w_meas.size)
    d1 = d[rows, order[:, 0]]
    d2 = d[rows, order[:, 1]] if elastic.size > 1 else np.full(w_meas.size, np.inf)
    clear = d1 <= 0.5 * d2
    if mode_indices is not None:
        wrong = np.flatnonzero(clear & (near != mode_indices))
        if wrong.size:
            i = wrong[0]
            raise FieldError(
                "mode_indices",
                f"measured_eigenvalues[{i}] (natural frequency {w_meas[i]:.6g} "
                f"rad/s) is nearest model mode {near[i]} ({w_model[near[i]]:.6g} rad/s) but "
                f"mode_indices pairs it with mode {mode_indices[i]} "
                f"({w_model[mode_indices[i]]:.6g} rad/s): list the eigenvalues in the order of "
                "mode_indices",
            )
        return np.asarray(mode_indices, int)
    unclear = np.flatnonzero(~clear)
    if unclear.size:
        i = unclear[0]
        a, b = sorted(elastic[order[i, :2]])
        raise FieldError(
            f"measured_eigenvalues[{i}]",
            f"natural frequency {w_meas[i]:.6g} rad/s has no clearly "
            f"nearest model mode (modes {a} at {w_model[a]:.6g} and {b} at {w_model[b]:.6g} "
            "rad/s are comparably close): the model may lack this mode; give mode_indices",
        )
    k, count = np.unique(near, return_counts=True)
    if np.any(count > 1):
        k = k[count > 1][0]
        i, j = np.flatnonzero(near == k)[:2]
        raise ValueError(
            f"measured_eigenvalues[{i}] and [{j}] are both nearest model mode {k} "
            f"({w_model[k]:.6g} rad/s): one measured eigenvalue per model mode; the model "
            "may lack a mode, give mode_indices"
        )
    return near
