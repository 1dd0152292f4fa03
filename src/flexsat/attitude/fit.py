r"""Attitude from matched star directions: Davenport's q-method and the QUEST covariance
(Junkins, Pollock & Rahman 1990 §2.3.4: the attitude follows once the imaged stars are identified).

Wahba's problem: find the rotation C (inertial to body) minimising
:math:`\tfrac12\sum_i w_i |b_i - C r_i|^2` for body directions b_i, catalogue directions r_i and
weights w_i = 1/σ_i². With :math:`B = \sum_i w_i b_i r_i^T`, :math:`S = B + B^T`,
:math:`\sigma = \operatorname{tr} B` and :math:`z = [B_{23} - B_{32}, B_{31} - B_{13},
B_{12} - B_{21}]^T`, the optimal Euler parameters β (scalar first, the convention of
:func:`flexsat.dynamics.attitude.quaternion_to_dcm`) are the eigenvector of the largest
eigenvalue of Davenport's matrix (Shuster & Oh, "Three-axis attitude determination from vector
observations", J. Guid. Control 4(1), 1981, eqs. 41–48; Markley & Crassidis, *Fundamentals of
Spacecraft Attitude Determination and Control*, 2014, eq. 5.17):

.. math::

    K = \begin{bmatrix} \sigma & z^T \\ z & S - \sigma I \end{bmatrix}.

The covariance of the small body-axis rotation error δθ (C_est = (I − [δθ×]) C_true) under the
QUEST measurement model (each b_i a unit vector with isotropic tangential noise σ_i per axis) is
(Shuster & Oh 1981, eq. 69; Markley & Crassidis eq. 5.45)

.. math::

    P_{\theta\theta} = \Big[\sum_i \sigma_i^{-2}\,(I - b_i b_i^T)\Big]^{-1}.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from flexsat.dynamics.attitude import quaternion_to_dcm
from flexsat.input_checks import FieldError
from flexsat.units import FloatArray

__all__ = ["q_method", "quest_covariance", "rotation_error"]


def _check_vectors(
    body: npt.ArrayLike, reference: npt.ArrayLike, sigma: npt.ArrayLike
) -> tuple[FloatArray, FloatArray, FloatArray]:
    b = np.asarray(body, float)
    r = np.asarray(reference, float)
    if b.ndim != 2 or b.shape[1] != 3 or r.shape != b.shape:
        raise FieldError(
            "body",
            "body and reference directions must both have shape (n, 3), got "
            f"{b.shape} and {r.shape}",
        )
    if b.shape[0] < 2:
        raise FieldError(
            "body", f"an attitude needs at least 2 non-parallel directions, got {b.shape[0]}"
        )
    if not (np.all(np.isfinite(b)) and np.all(np.isfinite(r))):
        raise FieldError("body", "directions must be finite")
    s = np.broadcast_to(np.asarray(sigma, float), (b.shape[0],))
    if not np.all(np.isfinite(s)) or np.any(s <= 0):
        raise FieldError("sigma", f"direction noise must be finite and > 0, got {sigma!r}")
    b = b / np.linalg.norm(b, axis=1, keepdims=True)
    r = r / np.linalg.norm(r, axis=1, keepdims=True)
    return b, r, s


def quest_covariance(body: npt.ArrayLike, sigma: npt.ArrayLike) -> FloatArray:
    """P = [Σ σ_i⁻² (I − b_i b_iᵀ)]⁻¹ (3, 3), rad² (module docstring).

    Raises
    ------
    ValueError
        When the directions are all parallel (the rotation about them is unobservable).
    """
    b, _, s = _check_vectors(body, body, sigma)
    w = 1.0 / s**2
    info = np.sum(w) * np.eye(3) - np.einsum("i,ij,ik->jk", w, b, b)
    if np.linalg.cond(info) > 1e12:
        raise FieldError(
            "body",
            "the directions are parallel; the rotation about them is "
            "unobservable (information matrix singular)",
        )
    return np.linalg.inv(info)


def q_method(
    body: npt.ArrayLike, reference: npt.ArrayLike, sigma: npt.ArrayLike = 1.0
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """(C_bn, β, P): the attitude minimising Wahba's loss, its Euler parameters (β0 >= 0) and
    the QUEST covariance of the body-axis error angles (module docstring).

    Parameters
    ----------
    body, reference : array_like (n, 3)
        Measured directions in body axes and their catalogue directions (inertial).
    sigma : float or array_like (n,)
        1σ direction noise per axis of each measurement, rad (weights 1/σ²).
    """
    b, r, s = _check_vectors(body, reference, sigma)
    w = 1.0 / s**2
    B = np.einsum("i,ij,ik->jk", w, b, r)
    S = B + B.T
    tr = np.trace(B)
    z = np.array([B[1, 2] - B[2, 1], B[2, 0] - B[0, 2], B[0, 1] - B[1, 0]])
    K = np.empty((4, 4))
    K[0, 0], K[0, 1:], K[1:, 0], K[1:, 1:] = tr, z, z, S - tr * np.eye(3)
    vals, vecs = np.linalg.eigh(K)
    beta = vecs[:, -1]
    beta = beta if beta[0] >= 0 else -beta
    return quaternion_to_dcm(beta), beta, quest_covariance(b, s)


def rotation_error(estimate: npt.ArrayLike, truth: npt.ArrayLike) -> FloatArray:
    """Body-axis small rotation δθ (..., 3), rad, with C_est = exp(−[δθ×]) C_true: the rotation
    vector of C_true C_estᵀ (exact, not only to first order)."""
    E = np.asarray(truth, float) @ np.swapaxes(np.asarray(estimate, float), -1, -2)
    # the rotation vector of E: axis from the skew part, angle from the trace
    v = 0.5 * np.stack(
        [E[..., 1, 2] - E[..., 2, 1], E[..., 2, 0] - E[..., 0, 2], E[..., 0, 1] - E[..., 1, 0]], -1
    )
    s = np.linalg.norm(v, axis=-1)
    c = 0.5 * (np.trace(E, axis1=-2, axis2=-1) - 1.0)
    angle = np.arctan2(s, c)
    scale = np.where(s > 1e-300, angle / np.where(s > 1e-300, s, 1.0), 1.0)
    return -v * scale[..., None]
