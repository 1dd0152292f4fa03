r"""Attitude kinematics: Euler parameters, direction cosines, 1-2-3 Euler angles, Gibbs and
modified Rodrigues parameters, on arrays with a leading case axis.

Conventions (EPS slew study c. 1989, "Simulation Results" and Eqs. 9–11; Schaub & Junkins,
*Analytical Mechanics of Space
Systems*, 4th ed., Ch. 3):

* Euler parameters (quaternion) scalar first, :math:`\beta = [\beta_0, \beta_1, \beta_2,
  \beta_3]`, :math:`\beta_0 = \cos(\phi/2)`, :math:`\beta_i = l_i \sin(\phi/2)` for the
  principal rotation of angle :math:`\phi` about the unit axis :math:`l`;
* the direction cosine matrix C maps inertial to body components, :math:`v_B = C v_N`;
* 1-2-3 Euler angles: :math:`C = R_3(\theta_3) R_2(\theta_2) R_1(\theta_1)`, with
  :math:`R_k(\theta)` the frame rotation about axis k (``R1 = [[1,0,0],[0,c,s],[0,-s,c]]``);
* ω is the body angular velocity in body components.

Every function takes arrays whose last axis (or two) is the representation, ``(..., 4)``,
``(..., 3)`` or ``(..., 3, 3)``, and works on all leading (case) axes at once.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from flexsat.input_checks import FieldError, require_numeric

if TYPE_CHECKING:
    import numpy.typing as npt

    from flexsat.units import FloatArray

__all__ = [
    "require_shape",
    "case_shape",
    "require_quaternion",
    "UNIT_TOL",
    "SINGULAR_TOL",
    "cross_matrix",
    "omega_matrix",
    "quaternion_rate_matrix",
    "quaternion_to_dcm",
    "dcm_to_quaternion",
    "euler123_to_dcm",
    "euler123_to_quaternion",
    "dcm_to_euler123",
    "principal_rotation_to_quaternion",
    "quaternion_to_principal_rotation",
    "quaternion_multiply",
    "quaternion_exp",
    "quaternion_to_gibbs",
    "gibbs_to_quaternion",
    "quaternion_to_mrp",
    "mrp_to_quaternion",
    "mrp_shadow",
    "gibbs_rate",
    "mrp_rate",
]

#: allowed departure of ‖β‖ from 1, of CᵀC from I and of ‖axis‖ from 1: an input computed in
#: double precision is unit to ~1e-15; 1e-9 still accepts data stored with 10 significant digits
#: and refuses anything that was never normalised.
UNIT_TOL = 1e-9
#: smallest |β0| (Gibbs) or 1 + β0 (MRP) accepted: the parameters are β_i / β0 or
#: β_i / (1 + β0), so their relative round-off is ~eps / SINGULAR_TOL ≤ 2e-8 at this bound.
SINGULAR_TOL = 1e-8


def require_shape(value: npt.ArrayLike, field: str, shape: tuple[int, ...]) -> FloatArray:
    """``value`` as a finite float array whose trailing axes are ``shape``."""
    arr = require_numeric(value, field)
    if arr.ndim < len(shape) or arr.shape[arr.ndim - len(shape) :] != shape:
        raise FieldError(
            field,
            f"last axes must have shape {shape} (leading axes are cases), got shape {arr.shape}",
        )
    return arr


def case_shape(**fields: tuple[int, ...]) -> tuple[int, ...]:
    """The common leading (case) shape of the named arrays' leading axes, or a clear error."""
    try:
        return np.broadcast_shapes(*fields.values())
    except ValueError:
        got = ", ".join(f"{name} {shape}" for name, shape in fields.items())
        raise ValueError(
            f"{', '.join(fields)}: leading (case) axes must broadcast, got {got}"
        ) from None


def require_quaternion(beta: npt.ArrayLike, field: str = "beta") -> FloatArray:
    """``beta`` as a float array (..., 4) of unit Euler parameters (to :data:`UNIT_TOL`)."""
    b = require_shape(beta, field, (4,))
    err = np.abs(np.linalg.norm(b, axis=-1) - 1.0)
    if np.any(err > UNIT_TOL):
        raise FieldError(
            field,
            f"must be a unit quaternion (| ‖β‖ − 1 | <= {UNIT_TOL:g}), "
            f"largest departure {err.max():.3g}",
        )
    return b


def _dcm(dcm: npt.ArrayLike, field: str = "dcm") -> FloatArray:
    C = require_shape(dcm, field, (3, 3))
    err = np.abs(C @ np.swapaxes(C, -1, -2) - np.eye(3)).max(axis=(-2, -1), initial=0.0)
    if np.any(err > UNIT_TOL):
        raise FieldError(
            field,
            f"must be orthonormal (max |C Cᵀ − I| <= {UNIT_TOL:g}), "
            f"largest departure {err.max():.3g}",
        )
    if np.any(np.linalg.det(C) < 0):
        raise FieldError(field, "must be a proper rotation (det C = +1), got a reflection")
    return C


def cross_matrix(v: npt.ArrayLike) -> FloatArray:
    r"""The skew-symmetric matrix :math:`[\tilde v]` with :math:`[\tilde v] x = v \times x`.

    Parameters
    ----------
    v : array_like, shape (..., 3)

    Returns
    -------
    ndarray, shape (..., 3, 3)
    """
    v = require_shape(v, "v", (3,))
    z = np.zeros(v.shape[:-1])
    x, y, w = v[..., 0], v[..., 1], v[..., 2]
    return np.stack(
        [np.stack([z, -w, y], -1), np.stack([w, z, -x], -1), np.stack([-y, x, z], -1)], -2
    )


def omega_matrix(w: npt.ArrayLike) -> FloatArray:
    r"""Ω(ω) of the Euler-parameter kinematics :math:`\dot\beta = \Omega(\omega)\beta`
    (EPS slew study c. 1989 Eq. 11; Schaub & Junkins Eq. 3.104), the ½ included:

    .. math::

        \Omega(\omega) = \tfrac12 \begin{bmatrix} 0 & -\omega_1 & -\omega_2 & -\omega_3 \\
        \omega_1 & 0 & \omega_3 & -\omega_2 \\ \omega_2 & -\omega_3 & 0 & \omega_1 \\
        \omega_3 & \omega_2 & -\omega_1 & 0 \end{bmatrix}.

    Parameters
    ----------
    w : array_like, shape (..., 3)
        Body angular velocity, body components (rad/s).

    Returns
    -------
    ndarray, shape (..., 4, 4)
    """
    w = require_shape(w, "w", (3,))
    z = np.zeros(w.shape[:-1])
    w1, w2, w3 = w[..., 0], w[..., 1], w[..., 2]
    rows = [[z, -w1, -w2, -w3], [w1, z, w3, -w2], [w2, -w3, z, w1], [w3, w2, -w1, z]]
    return 0.5 * np.stack([np.stack(r, -1) for r in rows], -2)


def quaternion_rate_matrix(beta: npt.ArrayLike) -> FloatArray:
    r"""B(β) with :math:`\dot\beta = B(\beta)\,\omega = \Omega(\omega)\beta`
    (EPS slew study c. 1989 Eq. 11,
    Schaub & Junkins Eq. 3.104), the ½ included:

    .. math::

        B(\beta) = \tfrac12 \begin{bmatrix} -\beta_1 & -\beta_2 & -\beta_3 \\
        \beta_0 & -\beta_3 & \beta_2 \\ \beta_3 & \beta_0 & -\beta_1 \\
        -\beta_2 & \beta_1 & \beta_0 \end{bmatrix}.

    Parameters
    ----------
    beta : array_like, shape (..., 4)
        Euler parameters, scalar first (not required to be unit: the map is linear).

    Returns
    -------
    ndarray, shape (..., 4, 3)
    """
    b = require_shape(beta, "beta", (4,))
    b0, b1, b2, b3 = (b[..., i] for i in range(4))
    rows = [[-b1, -b2, -b3], [b0, -b3, b2], [b3, b0, -b1], [-b2, b1, b0]]
    return 0.5 * np.stack([np.stack(r, -1) for r in rows], -2)


def quaternion_to_dcm(beta: npt.ArrayLike) -> FloatArray:
    r"""Direction cosine matrix C(β), :math:`v_B = C v_N` (Schaub & Junkins Eq. 3.98):

    .. math::

        C = \begin{bmatrix}
        \beta_0^2+\beta_1^2-\beta_2^2-\beta_3^2 & 2(\beta_1\beta_2+\beta_0\beta_3) &
        2(\beta_1\beta_3-\beta_0\beta_2) \\
        2(\beta_1\beta_2-\beta_0\beta_3) & \beta_0^2-\beta_1^2+\beta_2^2-\beta_3^2 &
        2(\beta_2\beta_3+\beta_0\beta_1) \\
        2(\beta_1\beta_3+\beta_0\beta_2) & 2(\beta_2\beta_3-\beta_0\beta_1) &
        \beta_0^2-\beta_1^2-\beta_2^2+\beta_3^2 \end{bmatrix}.

    Parameters
    ----------
    beta : array_like, shape (..., 4)
        Unit Euler parameters (| ‖β‖ − 1 | <= :data:`UNIT_TOL`).

    Returns
    -------
    ndarray, shape (..., 3, 3)
    """
    b = require_quaternion(beta)
    b0, b1, b2, b3 = (b[..., i] for i in range(4))
    s0, s1, s2, s3 = b0 * b0, b1 * b1, b2 * b2, b3 * b3
    rows = [
        [s0 + s1 - s2 - s3, 2 * (b1 * b2 + b0 * b3), 2 * (b1 * b3 - b0 * b2)],
        [2 * (b1 * b2 - b0 * b3), s0 - s1 + s2 - s3, 2 * (b2 * b3 + b0 * b1)],
        [2 * (b1 * b3 + b0 * b2), 2 * (b2 * b3 - b0 * b1), s0 - s1 - s2 + s3],
    ]
    return np.stack([np.stack(r, -1) for r in rows], -2)


def dcm_to_quaternion(dcm: npt.ArrayLike) -> FloatArray:
    r"""Euler parameters of a rotation matrix by Shepperd's method (Shepperd 1978, J. Guidance
    Control 1(3); Schaub & Junkins Eqs. 3.94–3.96), with :math:`\beta_0 \ge 0`.

    The four squares :math:`\beta_0^2 = (1 + \mathrm{tr}\,C)/4`,
    :math:`\beta_i^2 = (1 + 2C_{ii} - \mathrm{tr}\,C)/4` are formed; the largest fixes one
    parameter (never below ½, so no division by a small number, whatever the rotation, 180°
    included) and the others follow from the off-diagonal sums and differences
    :math:`4\beta_0\beta_1 = C_{23}-C_{32}`, :math:`4\beta_0\beta_2 = C_{31}-C_{13}`,
    :math:`4\beta_0\beta_3 = C_{12}-C_{21}`, :math:`4\beta_1\beta_2 = C_{12}+C_{21}`,
    :math:`4\beta_3\beta_1 = C_{31}+C_{13}`, :math:`4\beta_2\beta_3 = C_{23}+C_{32}`.

    Parameters
    ----------
    dcm : array_like, shape (..., 3, 3)
        Proper orthonormal matrices (max |C Cᵀ − I| <= :data:`UNIT_TOL`).

    Returns
    -------
    ndarray, shape (..., 4)
        Unit Euler parameters, β0 >= 0 (a rotation of exactly 180° has β0 = 0 and either sign of
        the vector part).
    """
    C = _dcm(dcm)
    tr = np.trace(C, axis1=-2, axis2=-1)
    d = np.diagonal(C, axis1=-2, axis2=-1)
    sq = (
        np.stack(
            [1 + tr, 1 + 2 * d[..., 0] - tr, 1 + 2 * d[..., 1] - tr, 1 + 2 * d[..., 2] - tr], -1
        )
        / 4
    )
    p01, p02, p03 = (
        (C[..., 1, 2] - C[..., 2, 1]) / 4,
        (C[..., 2, 0] - C[..., 0, 2]) / 4,
        (C[..., 0, 1] - C[..., 1, 0]) / 4,
    )
    p12, p13, p23 = (
        (C[..., 0, 1] + C[..., 1, 0]) / 4,
        (C[..., 2, 0] + C[..., 0, 2]) / 4,
        (C[..., 1, 2] + C[..., 2, 1]) / 4,
    )
    # products[k] holds β_k·[β0, β1, β2, β3]; divide row k by β_k = sqrt(sq_k) for the largest k
    products = np.stack(
        [
            np.stack([sq[..., 0], p01, p02, p03], -1),
            np.stack([p01, sq[..., 1], p12, p13], -1),
            np.stack([p02, p12, sq[..., 2], p23], -1),
            np.stack([p03, p13, p23, sq[..., 3]], -1),
        ],
        -2,
    )
    k = np.argmax(sq, axis=-1)
    row = np.take_along_axis(products, k[..., None, None], axis=-2)[..., 0, :]
    beta = row / np.sqrt(np.take_along_axis(sq, k[..., None], axis=-1))
    return np.where(beta[..., :1] < 0, -beta, beta)


def _axis_rotation(angle: FloatArray, axis: int) -> FloatArray:
    """R_axis(θ): the frame rotation about body axis ``axis`` (0, 1, 2), shape (..., 3, 3)."""
    c, s = np.cos(angle), np.sin(angle)
    R = np.zeros(angle.shape + (3, 3))
    i, j = [a for a in range(3) if a != axis]
    R[..., axis, axis] = 1.0
    R[..., i, i] = c
    R[..., j, j] = c
    # R1 = [[1,0,0],[0,c,s],[0,-s,c]], R2 = [[c,0,-s],[0,1,0],[s,0,c]],
    # R3 = [[c,s,0],[-s,c,0],[0,0,1]]: the (i, j) entry is -s for R2 only
    sign = 1.0 if axis != 1 else -1.0
    R[..., i, j] = sign * s
    R[..., j, i] = -sign * s
    return R


def euler123_to_dcm(angles: npt.ArrayLike) -> FloatArray:
    r"""C of the 1-2-3 Euler angles, :math:`C = R_3(\theta_3) R_2(\theta_2) R_1(\theta_1)`
    (EPS slew study c. 1989, "Simulation Results"; Schaub & Junkins Table B.1).

    Parameters
    ----------
    angles : array_like, shape (..., 3)
        [θ1, θ2, θ3] in rad.

    Returns
    -------
    ndarray, shape (..., 3, 3)
    """
    th = require_shape(angles, "angles", (3,))
    return (
        _axis_rotation(th[..., 2], 2)
        @ _axis_rotation(th[..., 1], 1)
        @ _axis_rotation(th[..., 0], 0)
    )


def euler123_to_quaternion(angles: npt.ArrayLike) -> FloatArray:
    r"""Euler parameters of the 1-2-3 Euler angles as the product of the three elementary
    rotations, :math:`\beta = \beta_3(\theta_3) \otimes \beta_2(\theta_2) \otimes
    \beta_1(\theta_1)` with :math:`\beta_k(\theta) = [\cos(\theta/2), \sin(\theta/2)\,e_k]`
    (the rotation of :func:`euler123_to_dcm`, :math:`C = R_3 R_2 R_1`; Schaub & Junkins Eq. 3.105).

    Unlike ``dcm_to_quaternion(euler123_to_dcm(angles))``, whose sign is fixed by β0 >= 0, this
    is a smooth function of the angles: a path of angles gives a continuous path of β (what a
    continuation in the terminal angles needs). For (1, 1, 1) rad it gives
    [0.565676, 0.570941, 0.167519, 0.570941] (EPS slew study c. 1989,
    "Simulation Results"; spec F4).

    Parameters
    ----------
    angles : array_like, shape (..., 3)
        [θ1, θ2, θ3] in rad.

    Returns
    -------
    ndarray, shape (..., 4)
    """
    th = require_shape(angles, "angles", (3,))
    c, s = np.cos(th / 2), np.sin(th / 2)
    zero = np.zeros(th.shape[:-1])
    q1, q2, q3 = (
        np.stack([c[..., k]] + [s[..., k] if j == k else zero for j in range(3)], -1)
        for k in range(3)
    )
    return quaternion_multiply(q3, quaternion_multiply(q2, q1))


def dcm_to_euler123(dcm: npt.ArrayLike) -> FloatArray:
    r"""1-2-3 Euler angles of C (Schaub & Junkins Table B.1):
    :math:`\theta_1 = \operatorname{atan2}(-C_{32}, C_{33})`,
    :math:`\theta_2 = \operatorname{atan2}(C_{31}, \sqrt{C_{11}^2 + C_{21}^2})`,
    :math:`\theta_3 = \operatorname{atan2}(-C_{21}, C_{11})`.

    θ2 is taken from atan2 rather than :math:`\arcsin C_{31}` so it keeps full accuracy near
    ±90°, where the set is singular: there θ1 and θ3 are not separable and only their sum or
    difference is determined (the returned pair still reproduces C to round-off divided by
    cos θ2).

    Parameters
    ----------
    dcm : array_like, shape (..., 3, 3)

    Returns
    -------
    ndarray, shape (..., 3)
        θ1, θ3 in (−π, π], θ2 in [−π/2, π/2].
    """
    C = _dcm(dcm)
    return np.stack(
        [
            np.arctan2(-C[..., 2, 1], C[..., 2, 2]),
            np.arctan2(C[..., 2, 0], np.hypot(C[..., 0, 0], C[..., 1, 0])),
            np.arctan2(-C[..., 1, 0], C[..., 0, 0]),
        ],
        -1,
    )


def principal_rotation_to_quaternion(axis: npt.ArrayLike, angle: npt.ArrayLike) -> FloatArray:
    r"""Euler parameters of the rotation ``angle`` about the unit ``axis`` (EPS
    slew study c. 1989 Eqs. 9–10):
    :math:`\beta_0 = \cos(\phi/2)`, :math:`\beta_i = l_i \sin(\phi/2)`.

    Parameters
    ----------
    axis : array_like, shape (..., 3)
        Unit principal axis (| ‖l‖ − 1 | <= :data:`UNIT_TOL`).
    angle : array_like, shape (...)
        Principal angle φ (rad); β0 < 0 for |φ| > π (the same attitude as −β).

    Returns
    -------
    ndarray, shape (..., 4)
    """
    ax = require_shape(axis, "axis", (3,))
    phi = require_numeric(angle, "angle")
    err = np.abs(np.linalg.norm(ax, axis=-1) - 1.0)
    if np.any(err > UNIT_TOL):
        raise FieldError(
            "axis",
            f"must be a unit vector (| ‖l‖ − 1 | <= {UNIT_TOL:g}), largest "
            f"departure {err.max():.3g}",
        )
    shape = case_shape(axis=ax.shape[:-1], angle=phi.shape)
    half = phi / 2
    # one angle for many axes (or one axis for many angles) broadcasts to the common case shape
    scalar = np.broadcast_to(np.cos(half), shape)[..., None]
    vector = np.broadcast_to(ax * np.sin(half)[..., None], (*shape, 3))
    return np.concatenate([scalar, vector], -1)


def quaternion_to_principal_rotation(beta: npt.ArrayLike) -> tuple[FloatArray, FloatArray]:
    r"""Principal axis l and angle :math:`\phi = 2\,\operatorname{atan2}(\|\beta_{1:3}\|,
    \beta_0) \in [0, 2\pi]` (atan2 keeps φ accurate near 0 and π, where arccos β0 does not).

    Parameters
    ----------
    beta : array_like, shape (..., 4)
        Unit Euler parameters.

    Returns
    -------
    axis : ndarray, shape (..., 3)
        Unit axis; [1, 0, 0] for the identity rotation, whose axis is undefined.
    angle : ndarray, shape (...)
    """
    b = require_quaternion(beta)
    s = np.linalg.norm(b[..., 1:], axis=-1)
    angle = 2 * np.arctan2(s, b[..., 0])
    safe = np.where(s > 0, s, 1.0)[..., None]
    axis = np.where(s[..., None] > 0, b[..., 1:] / safe, np.array([1.0, 0.0, 0.0]))
    return axis, angle


def quaternion_multiply(second: npt.ArrayLike, first: npt.ArrayLike) -> FloatArray:
    r"""Composition of two rotations, ``first`` then ``second``: the Euler parameters β of
    :math:`C(\beta) = C(\beta'')\,C(\beta')` with β'' = ``second``, β' = ``first``
    (Schaub & Junkins Eq. 3.105; e.g. β(F/N) = β(F/B) ⊗ β(B/N)):

    .. math::

        \beta = \begin{bmatrix} \beta''_0 & -\beta''_1 & -\beta''_2 & -\beta''_3 \\
        \beta''_1 & \beta''_0 & \beta''_3 & -\beta''_2 \\
        \beta''_2 & -\beta''_3 & \beta''_0 & \beta''_1 \\
        \beta''_3 & \beta''_2 & -\beta''_1 & \beta''_0 \end{bmatrix} \beta'.

    With this product the kinematics read :math:`\dot\beta = \tfrac12 [0, \omega] \otimes
    \beta`. Inputs need not be unit (the product is bilinear), so no norm check is made.

    Parameters
    ----------
    second, first : array_like, shape (..., 4)
        Broadcast against each other.

    Returns
    -------
    ndarray, shape (..., 4)
    """
    q = require_shape(second, "second", (4,))
    p = require_shape(first, "first", (4,))
    case_shape(second=q.shape[:-1], first=p.shape[:-1])
    q0, q1, q2, q3 = (q[..., i] for i in range(4))
    p0, p1, p2, p3 = (p[..., i] for i in range(4))
    return np.stack(
        [
            q0 * p0 - q1 * p1 - q2 * p2 - q3 * p3,
            q1 * p0 + q0 * p1 + q3 * p2 - q2 * p3,
            q2 * p0 - q3 * p1 + q0 * p2 + q1 * p3,
            q3 * p0 + q2 * p1 - q1 * p2 + q0 * p3,
        ],
        -1,
    )


def quaternion_exp(theta: npt.ArrayLike) -> FloatArray:
    r"""Euler parameters of the rotation vector θ (axis θ/‖θ‖, angle ‖θ‖):
    :math:`[\cos(\|\theta\|/2), \operatorname{sinc}\cdot\theta/2]`, with the sinc evaluated
    by numpy (exact at θ = 0, no 0/0). For constant ω, β(t) = exp(ω t) ⊗ β(0).

    Parameters
    ----------
    theta : array_like, shape (..., 3)
        Rotation vector (rad).

    Returns
    -------
    ndarray, shape (..., 4)
    """
    th = require_shape(theta, "theta", (3,))
    n = np.linalg.norm(th, axis=-1)
    # sin(n/2)/n = ½ sinc(n/(2π)) with numpy's normalised sinc
    return np.concatenate(
        [np.cos(n / 2)[..., None], th * (0.5 * np.sinc(n / (2 * np.pi)))[..., None]], -1
    )


def quaternion_to_gibbs(beta: npt.ArrayLike) -> FloatArray:
    r"""Classical Rodrigues (Gibbs) parameters :math:`q_i = \beta_i / \beta_0 =
    l_i \tan(\phi/2)` (Schaub & Junkins Eq. 3.112).

    Raises
    ------
    ValueError
        At the 180° singularity: |β0| < :data:`SINGULAR_TOL` (|q| > 1e8) is refused.
    """
    b = require_quaternion(beta)
    b0 = b[..., 0]
    if np.any(np.abs(b0) < SINGULAR_TOL):
        raise FieldError(
            "beta",
            "the Gibbs vector is singular at a 180° principal rotation "
            f"(|β0| < {SINGULAR_TOL:g}); use MRPs or Euler parameters there",
        )
    return b[..., 1:] / b0[..., None]


def gibbs_to_quaternion(q: npt.ArrayLike) -> FloatArray:
    r"""Euler parameters of Gibbs parameters, β0 > 0 (Schaub & Junkins Eq. 3.113):
    :math:`\beta_0 = 1/\sqrt{1 + q^Tq}`, :math:`\beta_i = q_i/\sqrt{1 + q^Tq}`.
    """
    q = require_shape(q, "q", (3,))
    s = 1 / np.sqrt(1 + np.sum(q * q, axis=-1))[..., None]
    return np.concatenate([s, q * s], -1)


def quaternion_to_mrp(beta: npt.ArrayLike) -> FloatArray:
    r"""Modified Rodrigues parameters :math:`\sigma_i = \beta_i / (1 + \beta_0) =
    l_i \tan(\phi/4)` (Schaub & Junkins Eq. 3.142); |σ| <= 1 for β0 >= 0.

    Raises
    ------
    ValueError
        At the 360° singularity: 1 + β0 < :data:`SINGULAR_TOL` (pass −β, the same attitude).
    """
    b = require_quaternion(beta)
    den = 1 + b[..., 0]
    if np.any(den < SINGULAR_TOL):
        raise FieldError(
            "beta",
            "the MRP vector is singular at β0 = −1 (1 + β0 < "
            f"{SINGULAR_TOL:g}); pass −beta, the same attitude",
        )
    return b[..., 1:] / den[..., None]


def mrp_to_quaternion(sigma: npt.ArrayLike) -> FloatArray:
    r"""Euler parameters of MRPs (Schaub & Junkins Eq. 3.144):
    :math:`\beta_0 = (1 - \sigma^T\sigma)/(1 + \sigma^T\sigma)`,
    :math:`\beta_i = 2\sigma_i/(1 + \sigma^T\sigma)`.
    """
    s = require_shape(sigma, "sigma", (3,))
    s2 = np.sum(s * s, axis=-1)[..., None]
    return np.concatenate([(1 - s2) / (1 + s2), 2 * s / (1 + s2)], -1)


def mrp_shadow(sigma: npt.ArrayLike) -> FloatArray:
    r"""The shadow set :math:`\sigma^S = -\sigma / \sigma^T\sigma` (Schaub & Junkins Eq. 3.151):
    the same attitude, with |σ^S| <= 1 when |σ| >= 1.

    Raises
    ------
    ValueError
        For σ = 0 (the identity, whose shadow is at infinity).
    """
    s = require_shape(sigma, "sigma", (3,))
    s2 = np.sum(s * s, axis=-1)
    if np.any(s2 == 0):
        raise FieldError("sigma", "the shadow set of σ = 0 (the identity) is at infinity")
    return -s / s2[..., None]


def gibbs_rate(q: npt.ArrayLike, w: npt.ArrayLike) -> FloatArray:
    r"""Gibbs-parameter kinematics :math:`\dot q = \tfrac12 [I + \tilde q + q q^T]\,\omega`
    (Schaub & Junkins Eq. 3.124).

    Parameters
    ----------
    q : array_like, shape (..., 3)
    w : array_like, shape (..., 3)
        Body angular velocity (rad/s), broadcast against ``q``.
    """
    q = require_shape(q, "q", (3,))
    w = require_shape(w, "w", (3,))
    case_shape(q=q.shape[:-1], w=w.shape[:-1])
    return 0.5 * (w + np.cross(q, w) + q * np.sum(q * w, axis=-1)[..., None])


def mrp_rate(sigma: npt.ArrayLike, w: npt.ArrayLike) -> FloatArray:
    r"""MRP kinematics :math:`\dot\sigma = \tfrac14 [(1 - \sigma^T\sigma) I + 2\tilde\sigma +
    2\sigma\sigma^T]\,\omega` (Schaub & Junkins Eq. 3.163).

    Parameters
    ----------
    sigma : array_like, shape (..., 3)
    w : array_like, shape (..., 3)
        Body angular velocity (rad/s), broadcast against ``sigma``.
    """
    s = require_shape(sigma, "sigma", (3,))
    w = require_shape(w, "w", (3,))
    case_shape(sigma=s.shape[:-1], w=w.shape[:-1])
    s2 = np.sum(s * s, axis=-1)[..., None]
    return 0.25 * ((1 - s2) * w + 2 * np.cross(s, w) + 2 * s * np.sum(s * w, axis=-1)[..., None])
