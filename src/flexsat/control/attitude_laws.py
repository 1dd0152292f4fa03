r"""Three-axis attitude regulation laws with their Lyapunov functions, on arrays with a leading
case axis.

The attitude error is the rotation of the body B relative to a fixed target frame R,
:math:`\beta_{err} = \beta(B/R) = \beta(B/N) \otimes \beta(R/N)^*` in the composition of
:func:`flexsat.dynamics.attitude.quaternion_multiply` (:math:`C(B/R) = C(B/N)\,C(R/N)^T`), so
its vector part is in body components. The target is at rest, so the body rate ω relative to R
is the inertial body rate, and the closed loop is Euler's equations
:math:`I\dot\omega = -\omega\times I\omega + u` with the kinematics of the error.

* :class:`GibbsLyapunovLaw`, Junkins, Att. 3 §II Eqs. 1–4 (seed 000; notes
  ``seed000_part1.md`` §2.8), Gibbs (classical Rodrigues) parameters q of the error:

  .. math::

      u_i = -[k_i\omega_i + A q_i (1 + q^Tq)], \qquad
      U = \tfrac12\omega^T I\omega + A\,q^Tq = T + A\tan^2(\phi/2), \qquad
      \dot U = -\textstyle\sum_i k_i\omega_i^2,

  because :math:`2\dot q = \omega + q\times\omega + q\,q^T\omega` gives
  :math:`\tfrac{d}{dt} q^Tq = (1 + q^Tq)\,q^T\omega` and the gyroscopic term does no work.
  U bounds tan²(φ/2) by U(0)/A, so a motion started below 180° never reaches the Gibbs
  singularity.
* :class:`MRPLaw`, the MRP proportional-derivative law (Schaub & Junkins, *Analytical
  Mechanics of Space Systems*, 4th ed., §8.3, Eqs. 8.16–8.19), with σ the modified Rodrigues
  parameters of the error taken on its short rotation (|σ| <= 1, β0 >= 0):

  .. math::

      u = -K\sigma - P\omega, \qquad
      V = \tfrac12\omega^T I\omega + 2K\ln(1 + \sigma^T\sigma), \qquad
      \dot V = -\omega^T P\omega,

  because :math:`\dot\sigma = \tfrac14[(1-\sigma^T\sigma)I + 2\tilde\sigma + 2\sigma\sigma^T]
  \omega` gives :math:`\tfrac{d}{dt}\ln(1+\sigma^T\sigma) = \tfrac12\sigma^T\omega`. V is
  continuous where σ switches to its shadow set (|σ| = 1 on both sides).

Each law is a callable ``law(t, beta, w)`` returning the body torque, the signature of the
torque argument of :func:`flexsat.dynamics.rigid_body.propagate`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from flexsat.dynamics.attitude import SINGULAR_TOL, _cases, _last, _quaternion
from flexsat.dynamics.rigid_body import _inertia
from flexsat.validation import require_positive, set_si

__all__ = ["GibbsLyapunovLaw", "MRPLaw", "error_quaternion"]

_IDENTITY = (1.0, 0.0, 0.0, 0.0)


def error_quaternion(beta, beta_target) -> np.ndarray:
    r"""β(B/R) = β(B/N) ⊗ β(R/N)*: the attitude of the body relative to the target frame.

    Parameters
    ----------
    beta : array_like, shape (..., 4)
        Unit Euler parameters of the body (inertial to body, scalar first).
    beta_target : array_like, shape (..., 4)
        Unit Euler parameters of the target frame, broadcast against ``beta``.

    Returns
    -------
    ndarray, shape (..., 4)
        Unit, with the sign of ``beta`` (either sign is the same attitude).
    """
    b = _quaternion(beta)
    r = _quaternion(beta_target, "beta_target")
    _cases(beta=b.shape[:-1], beta_target=r.shape[:-1])
    return _error(b, r)


def _error(b, r):
    # β ⊗ r* written out (Schaub & Junkins Eq. 3.105 with r* = [r0, −r_v])
    out = np.empty(np.broadcast_shapes(b.shape, r.shape))
    bv, rv = b[..., 1:], r[..., 1:]
    out[..., 0] = b[..., 0] * r[..., 0] + np.sum(bv * rv, axis=-1)
    out[..., 1:] = (r[..., 0:1] * bv - b[..., 0:1] * rv + np.cross(bv, rv))
    return out


def _per_axis(value: np.ndarray, name: str) -> np.ndarray:
    if value.ndim and value.shape[-1] != 3:
        raise ValueError(f"{name}: per-axis gains must be a scalar or have last axis 3 (body "
                         f"axes 1, 2, 3; leading axes are cases), got shape {value.shape}")
    return value


def _state(law, beta, w):
    """β and ω checked, their case axes and those of the law's gains and target broadcasting."""
    b = _quaternion(beta)
    w = _last(w, "w", (3,))
    gains = {name: np.shape(getattr(law, name)) for name in law.__dataclass_fields__}
    gains = {name: shape[:-1] if name in law._VECTORS else shape for name, shape in gains.items()}
    _cases(beta=b.shape[:-1], w=w.shape[:-1], **gains)
    return b, w


@dataclass(frozen=True)
class GibbsLyapunovLaw:
    r"""The Gibbs-parameter Lyapunov law of Junkins, Att. 3 §II Eq. 4 (module docstring):
    :math:`u_i = -[k_i\omega_i + A q_i(1 + q^Tq)]`, :math:`\dot U = -\sum_i k_i\omega_i^2`.

    Parameters
    ----------
    k : float, array, str or pint.Quantity
        Rate gains k_i > 0 (N·m·s/rad): a scalar (all axes) or shape (..., 3), leading axes
        cases.
    A : float, array, str or pint.Quantity
        Attitude gain A > 0 (N·m, the Gibbs parameters being dimensionless), shape (...).
    beta_target : array_like, shape (..., 4)
        Unit Euler parameters of the target frame (default: the inertial frame).
    """

    k: object
    A: object
    beta_target: object = field(default=_IDENTITY)
    #: fields whose last axis is not a case axis
    _VECTORS = ("k", "beta_target")

    def __post_init__(self):
        set_si(self, "k", require_positive, "N*m*s/rad")
        _per_axis(np.asarray(self.k), "k")
        set_si(self, "A", require_positive, "N*m")
        object.__setattr__(self, "beta_target", _quaternion(self.beta_target, "beta_target"))

    def gibbs(self, beta) -> np.ndarray:
        """Gibbs parameters q = l tan(φ/2) of the error (shape (..., 3)); refused at 180°."""
        e = _error(_quaternion(beta), self.beta_target)
        if np.any(np.abs(e[..., 0]) < SINGULAR_TOL):
            raise ValueError(f"beta: the Gibbs law is singular at a 180° error (|β0| < "
                             f"{SINGULAR_TOL:g}); start below 180°, where U keeps the motion")
        return e[..., 1:] / e[..., :1]

    def __call__(self, t, beta, w) -> np.ndarray:
        """The torque u (N·m, body components, shape (..., 3)) at attitude β, rate ω."""
        beta, w = _state(self, beta, w)
        q = self.gibbs(beta)
        A = np.asarray(self.A)[..., None]
        return -(self.k * w + A * q * (1 + np.sum(q * q, axis=-1))[..., None])

    def lyapunov(self, beta, w, inertia) -> np.ndarray:
        r"""U = ½ ωᵀIω + A qᵀq (J), Att. 3 Eq. 2."""
        beta, w = _state(self, beta, w)
        J = _inertia(inertia)
        q = self.gibbs(beta)
        return (0.5 * np.einsum("...i,...ij,...j->...", w, J, w)
                + self.A * np.sum(q * q, axis=-1))

    def lyapunov_rate(self, w) -> np.ndarray:
        r""":math:`\dot U = -\sum_i k_i\omega_i^2` (W) along the closed loop, Att. 3 Eq. 4."""
        w = _last(w, "w", (3,))
        return -np.sum(self.k * w * w, axis=-1)


@dataclass(frozen=True)
class MRPLaw:
    r"""MRP proportional-derivative law (Schaub & Junkins Ch. 8; module docstring):
    :math:`u = -K\sigma - P\omega`, σ the short-rotation MRPs of the error,
    :math:`\dot V = -\omega^T P\omega`.

    Parameters
    ----------
    K : float, array, str or pint.Quantity
        Attitude gain K > 0 (N·m, MRPs being dimensionless), shape (...): one per case, the
        same on every axis (a per-axis K has no Lyapunov function of this form).
    P : float, array, str or pint.Quantity
        Rate gains P_i > 0 (N·m·s/rad): a scalar or shape (..., 3) (a diagonal P).
    beta_target : array_like, shape (..., 4)
        Unit Euler parameters of the target frame (default: the inertial frame).
    """

    K: object
    P: object
    beta_target: object = field(default=_IDENTITY)
    #: fields whose last axis is not a case axis
    _VECTORS = ("P", "beta_target")

    def __post_init__(self):
        set_si(self, "K", require_positive, "N*m")
        set_si(self, "P", require_positive, "N*m*s/rad")
        _per_axis(np.asarray(self.P), "P")
        object.__setattr__(self, "beta_target", _quaternion(self.beta_target, "beta_target"))

    def mrp(self, beta) -> np.ndarray:
        """MRPs σ = l tan(φ/4) of the error on its short rotation, |σ| <= 1 (shape (..., 3)).

        The error quaternion is taken with β0 >= 0, so 1 + β0 >= 1 and no shadow switch
        or singularity check is needed.
        """
        e = _error(_quaternion(beta), self.beta_target)
        e = np.where(e[..., :1] < 0, -e, e)
        return e[..., 1:] / (1 + e[..., :1])

    def __call__(self, t, beta, w) -> np.ndarray:
        """The torque u (N·m, body components, shape (..., 3)) at attitude β, rate ω."""
        beta, w = _state(self, beta, w)
        return -(np.asarray(self.K)[..., None] * self.mrp(beta) + self.P * w)

    def lyapunov(self, beta, w, inertia) -> np.ndarray:
        r"""V = ½ ωᵀIω + 2K ln(1 + σᵀσ) (J), Schaub & Junkins Ch. 8."""
        beta, w = _state(self, beta, w)
        J = _inertia(inertia)
        s = self.mrp(beta)
        return (0.5 * np.einsum("...i,...ij,...j->...", w, J, w)
                + 2 * self.K * np.log1p(np.sum(s * s, axis=-1)))

    def lyapunov_rate(self, w) -> np.ndarray:
        r""":math:`\dot V = -\omega^T P\omega` (W) along the closed loop."""
        w = _last(w, "w", (3,))
        return -np.sum(self.P * w * w, axis=-1)
