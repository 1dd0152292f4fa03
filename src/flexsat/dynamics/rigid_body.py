r"""Three-axis rigid body: Euler's equations, a norm-preserving step of (β, ω) (the kernel of
the plants' own step, which the engine calls) and the analytic Euler–Poinsot motion of a
torque-free asymmetric body, on arrays with a leading case axis.

Euler's equations (EPS slew study c. 1989 Eq. 12; Schaub & Junkins Eq. 4.33), body components:

.. math::

    I \dot\omega = -\omega \times I\omega + u, \qquad \dot\beta = \Omega(\omega)\,\beta

(:func:`flexsat.dynamics.attitude.omega_matrix`, Eq. 11).

The step is the Runge–Kutta–Munthe-Kaas method of order 4 (Munthe-Kaas 1999, Appl.
Numer. Math. 29; Hairer, Lubich & Wanner, *Geometric Numerical Integration*, §IV.8.2): in each
step the attitude is written β(t_n + τ) = exp(θ(τ)) ⊗ β_n with the rotation vector θ(0) = 0,
and classical RK4 integrates the vector ODE of (θ, ω),

.. math::

    \dot\theta = \Big[I + \tfrac12\tilde\theta + \frac{1}{\theta^2}
    \Big(1 - \frac{\theta}{2}\cot\frac{\theta}{2}\Big)\tilde\theta^2\Big]\,\omega

(the principal-rotation-vector kinematics, Schaub & Junkins Eq. 3.87). The step ends with the
exact exponential and one quaternion product, so β stays unit to round-off without any
renormalisation (each step adds ~1 ulp: √N·eps after N steps), while the method keeps RK4's
fourth order for the coupled motion. A plain RK4 on (β, ω) would let ‖β‖ drift at O(h⁴) per
unit time, and a midpoint exponential exp(Ω(ω̄)h) would cut the order to two.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, TypeAlias

import numpy as np
import scipy.special

from flexsat.dynamics.attitude import (
    case_shape,
    quaternion_to_dcm,
    require_shape,
)
from flexsat.input_checks import FieldError, require_numeric, require_physical_inertia
from flexsat.units import FloatArray, to_si_array

if TYPE_CHECKING:
    import numpy.typing as npt

    from flexsat.units import QuantityArrayLike

#: ``rates(tau, theta, w)`` -> (θ̇, ω̇) of one RKMK4 stage (:func:`rkmk4_step`)
StageRates: TypeAlias = Callable[[float, FloatArray, FloatArray], tuple[FloatArray, FloatArray]]

__all__ = [
    "require_inertia",
    "rkmk4_step",
    "dexpinv",
    "cross3",
    "matvec",
    "euler_acceleration",
    "euler_rates",
    "angular_momentum_inertial",
    "kinetic_energy",
    "euler_poinsot_rates",
]

#: below this rotation angle (rad) the coefficient of θ̃² in the rotation-vector kinematics is
#: its series 1/12 + θ²/720 + θ⁴/30240: the next term, θ⁶/1209600, is then < 1e-16 of 1/12,
#: while the closed form would lose ~eps/θ² to cancellation.
_SERIES_ANGLE = 0.02


def require_inertia(inertia: QuantityArrayLike, field: str = "inertia") -> FloatArray:
    r"""``inertia`` as a float array (..., 3, 3) in kg·m² (a pint Quantity or a string with
    units is converted), checked to be a physical inertia tensor: symmetric, positive definite,
    and with principal moments satisfying the triangle inequality :math:`I_a + I_b \ge I_c`
    (:func:`flexsat.input_checks.require_physical_inertia`, which structures' lumped masses use
    too)."""
    J = require_shape(to_si_array(inertia, "kg*m**2", field), field, (3, 3))
    return require_physical_inertia(J, field)


def euler_rates(
    w: npt.ArrayLike, inertia: QuantityArrayLike, torque: npt.ArrayLike | None = None
) -> FloatArray:
    r"""ω̇ from Euler's equations, :math:`\dot\omega = I^{-1}(u - \omega \times I\omega)`
    (EPS slew study c. 1989 Eq. 12).

    Parameters
    ----------
    w : array_like, shape (..., 3)
        Body angular velocity (rad/s).
    inertia : array_like, shape (..., 3, 3)
        Inertia about the centre of mass, body axes (kg·m²), symmetric positive definite.
    torque : None or array_like, shape (..., 3)
        External torque, body components (N·m); None for a torque-free body.

    Returns
    -------
    ndarray, shape (..., 3)
    """
    w = require_shape(w, "w", (3,))
    J = require_inertia(inertia)
    u = np.zeros(3) if torque is None else require_shape(torque, "torque", (3,))
    # numpy types inv() as floating[Any]: it is float64 here, so the astype copies nothing
    return euler_acceleration(w, J, np.linalg.inv(J).astype(np.float64, copy=False), u)


# The kernels below run once per RK stage on tiny arrays: no input checks (the public functions
# check once) and slicing in place of np.cross / np.stack, whose overhead dominates here.


def cross3(a: FloatArray, b: FloatArray) -> FloatArray:
    """a × b on (..., 3) arrays, unchecked."""
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    out[..., 0] = a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1]
    out[..., 1] = a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2]
    out[..., 2] = a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
    return out


def matvec(A: FloatArray, x: FloatArray) -> FloatArray:
    """A x on (..., n, k) and (..., k) arrays, unchecked."""
    return (A @ x[..., None])[..., 0]


def euler_acceleration(w: FloatArray, J: FloatArray, Jinv: FloatArray, u: FloatArray) -> FloatArray:
    """ω̇ = I⁻¹(u − ω × Iω) (Euler's equations), unchecked."""
    return matvec(Jinv, u - cross3(w, matvec(J, w)))


def dexpinv(theta: FloatArray, w: FloatArray) -> FloatArray:
    """θ̇ of the rotation-vector kinematics (module docstring), vectorised."""
    a2 = np.sum(theta * theta, axis=-1)
    c = 1 / 12 + a2 / 720 + a2 * a2 / 30240
    if a2.max(initial=0.0) >= _SERIES_ANGLE**2:  # rare: steps of one RK stage are small
        small = a2 < _SERIES_ANGLE**2
        x = np.where(small, 1.0, np.sqrt(a2) / 2)  # placeholder where the series is used
        c = np.where(small, c, (1 - x / np.tan(x)) / np.where(small, 1.0, a2))
    c = c[..., None]
    tw = cross3(theta, w)
    return w + 0.5 * tw + c * cross3(theta, tw)


def _exp(theta: FloatArray) -> FloatArray:
    """Unchecked :func:`~flexsat.dynamics.attitude.quaternion_exp`."""
    n = np.sqrt(np.sum(theta * theta, axis=-1))
    out = np.empty(theta.shape[:-1] + (4,))
    out[..., 0] = np.cos(n / 2)
    out[..., 1:] = theta * (0.5 * np.sinc(n / (2 * np.pi)))[..., None]
    return out


def _mul(q: FloatArray, p: FloatArray) -> FloatArray:
    """Unchecked :func:`~flexsat.dynamics.attitude.quaternion_multiply` (q after p)."""
    out = np.empty(np.broadcast_shapes(q.shape, p.shape))
    out[..., 0] = q[..., 0] * p[..., 0] - np.sum(q[..., 1:] * p[..., 1:], axis=-1)
    out[..., 1:] = (
        q[..., 0:1] * p[..., 1:] + p[..., 0:1] * q[..., 1:] - cross3(q[..., 1:], p[..., 1:])
    )
    return out


def rkmk4_step(
    beta: FloatArray,
    w: FloatArray,
    h: float,
    rates: StageRates,
    zero: FloatArray | None = None,
) -> tuple[FloatArray, FloatArray]:
    r"""One RKMK4 step (module docstring) of (β, ω) over h, unchecked (a kernel: the callers
    check once).

    Parameters
    ----------
    beta, w : ndarray, shapes (..., 4), (..., 3)
        State at the start of the step.
    h : float
        Step, s.
    rates : callable
        ``rates(tau, theta, w)`` -> (θ̇, ω̇) at the stage time t_n + τ, rotation vector θ of
        the stage attitude exp(θ) ⊗ β and rate ω; θ̇ is :func:`dexpinv` (θ, ω).
    zero : ndarray, optional
        Zero rotation vector of the case shape (saves an allocation per step).

    Returns
    -------
    (beta, w) after the step; β is unit to round-off (exact exponential, one product).
    """
    if zero is None:
        zero = np.zeros(np.shape(w))
    k1t, k1w = rates(0.0, zero, w)
    k2t, k2w = rates(h / 2, h / 2 * k1t, w + h / 2 * k1w)
    k3t, k3w = rates(h / 2, h / 2 * k2t, w + h / 2 * k2w)
    k4t, k4w = rates(h, h * k3t, w + h * k3w)
    theta = h / 6 * (k1t + 2 * k2t + 2 * k3t + k4t)
    return _mul(_exp(theta), beta), w + h / 6 * (k1w + 2 * k2w + 2 * k3w + k4w)


def angular_momentum_inertial(
    beta: npt.ArrayLike, w: npt.ArrayLike, inertia: QuantityArrayLike
) -> FloatArray:
    r"""Angular momentum in inertial components, :math:`h_N = C(\beta)^T I \omega` (constant
    when no external torque acts).

    Parameters
    ----------
    beta : array_like, shape (..., 4)
    w : array_like, shape (..., 3)
    inertia : array_like, shape (..., 3, 3)
        Broadcast against the leading axes of ``beta`` and ``w``.
    """
    C = quaternion_to_dcm(beta)
    h = np.einsum("...ij,...j->...i", require_inertia(inertia), require_shape(w, "w", (3,)))
    return np.einsum("...ji,...j->...i", C, h)


def kinetic_energy(w: npt.ArrayLike, inertia: QuantityArrayLike) -> FloatArray:
    r"""Rotational kinetic energy :math:`T = \tfrac12 \omega^T I \omega` (J)."""
    w = require_shape(w, "w", (3,))
    return 0.5 * np.einsum("...i,...ij,...j->...", w, require_inertia(inertia), w)


def euler_poinsot_rates(moments: npt.ArrayLike, w0: npt.ArrayLike, t: npt.ArrayLike) -> FloatArray:
    r"""Body rates of the torque-free asymmetric rigid body, in principal axes, by Jacobi
    elliptic functions (Landau & Lifshitz, *Mechanics*, §37; Schaub & Junkins §4.4).

    With the principal moments sorted, I_a < I_b < I_c, H² = |Iω|² and 2T = ωᵀIω, the body
    spins about the axis of greatest inertia ("d" = c, "n" = a) when H² > 2T I_b and about the
    axis of least inertia ("d" = a, "n" = c) when H² < 2T I_b. Then, with ε = sign ω_d(0),

    .. math::

        \omega_n = A_n \operatorname{cn}(p t + u_0), \quad
        \omega_b = \varepsilon A_b \operatorname{sn}(p t + u_0), \quad
        \omega_d = \varepsilon A_d \operatorname{dn}(p t + u_0),

        A_n^2 = \frac{2T I_d - H^2}{I_n (I_d - I_n)}, \;
        A_b^2 = \frac{2T I_d - H^2}{I_b (I_d - I_b)}, \;
        A_d^2 = \frac{H^2 - 2T I_n}{I_d (I_d - I_n)}, \;
        p^2 = \frac{(I_d - I_b)(H^2 - 2T I_n)}{I_n I_b I_d}, \;
        m = k^2 = \frac{(I_b - I_n)(2T I_d - H^2)}{(I_d - I_b)(H^2 - 2T I_n)},

    and the phase u0 = F(φ0 | m), φ0 = atan2(ε ω_b(0)/A_b, ω_n(0)/A_n) (the amplitude of u0).
    The separatrix H² = 2T I_b (m = 1) is the limit of both cases and is ill-conditioned.

    Parameters
    ----------
    moments : array_like, shape (..., 3)
        Principal moments of inertia (kg·m²), distinct (an axisymmetric body has a circular
        closed form instead), in any order along a right-handed frame: ``w0`` and the result
        are along the same axes.
    w0 : array_like, shape (..., 3)
        Initial body rates along those principal axes (rad/s), not a pure spin about one axis.
    t : array_like, shape (n_t,)
        Times after the initial one (s).

    Returns
    -------
    ndarray, shape (..., n_t, 3)
    """
    moments = require_shape(moments, "moments", (3,))
    w0 = require_shape(w0, "w0", (3,))
    t = require_numeric(t, "t")
    if t.ndim != 1:
        raise FieldError("t", f"must be a 1-D time grid, got shape {t.shape}")
    shape = case_shape(moments=moments.shape[:-1], w0=w0.shape[:-1])
    moments = np.broadcast_to(moments, shape + (3,))
    w0 = np.broadcast_to(w0, shape + (3,))
    if np.any(moments <= 0):
        raise FieldError("moments", "principal moments must be > 0")
    order = np.argsort(moments, axis=-1)
    # ω is a pseudovector: relabelling the axes by an odd permutation (a left-handed frame)
    # flips its sign, so the sorted frame sees parity·P ω and the result is mapped back alike
    o0, o1, o2 = order[..., 0], order[..., 1], order[..., 2]
    parity = np.sign((o1 - o0) * (o2 - o0) * (o2 - o1)).astype(float)[..., None]
    Is = np.take_along_axis(moments, order, -1)
    ws = parity * np.take_along_axis(w0, order, -1)
    if np.any(np.diff(Is, axis=-1) <= 1e-12 * Is[..., 2:]):
        raise FieldError("moments", "principal moments must be distinct (asymmetric body)")
    H2 = np.sum((Is * ws) ** 2, -1)
    T2 = np.sum(Is * ws * ws, -1)
    Ia, Ib, Ic = Is[..., 0], Is[..., 1], Is[..., 2]
    about_max = H2 >= T2 * Ib
    In, Id = np.where(about_max, Ia, Ic), np.where(about_max, Ic, Ia)
    wn = np.where(about_max, ws[..., 0], ws[..., 2])
    wd = np.where(about_max, ws[..., 2], ws[..., 0])
    wb = ws[..., 1]
    eps = np.where(wd >= 0, 1.0, -1.0)
    An = np.sqrt((T2 * Id - H2) / (In * (Id - In)))
    Ab = np.sqrt((T2 * Id - H2) / (Ib * (Id - Ib)))
    Ad = np.sqrt((H2 - T2 * In) / (Id * (Id - In)))
    p = np.sqrt((Id - Ib) * (H2 - T2 * In) / (In * Ib * Id))
    m = (Ib - In) * (T2 * Id - H2) / ((Id - Ib) * (H2 - T2 * In))
    if np.any(~np.isfinite(m)) or np.any(An == 0):
        raise FieldError(
            "w0",
            "a pure spin about a principal axis has no elliptic solution (the rates are constant)",
        )
    phi0 = np.arctan2(eps * wb / Ab, wn / An)
    u0 = scipy.special.ellipkinc(phi0, m)
    if not np.all(np.isfinite(u0)):  # m = 1 and φ0 = ±π/2: at rest on the separatrix
        raise FieldError(
            "w0",
            "a pure spin about the intermediate axis (an unstable equilibrium "
            "on the separatrix H² = 2T·I2) has no elliptic solution",
        )
    sn, cn, dn, _ = scipy.special.ellipj(p[..., None] * t + u0[..., None], m[..., None])
    on, ob, od = An[..., None] * cn, (eps * Ab)[..., None] * sn, (eps * Ad)[..., None] * dn
    sorted_w = np.stack(
        [np.where(about_max[..., None], on, od), ob, np.where(about_max[..., None], od, on)], -1
    )
    out = np.empty_like(sorted_w)
    np.put_along_axis(out, np.broadcast_to(order[..., None, :], out.shape), sorted_w, -1)
    return parity[..., None, :] * out
