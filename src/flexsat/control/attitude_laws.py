r"""Three-axis attitude regulation laws with their Lyapunov functions, on arrays with a leading
case axis.

The attitude error is the rotation of the body B relative to a fixed target frame R,
:math:`\beta_{err} = \beta(B/R) = \beta(B/N) \otimes \beta(R/N)^*` in the composition of
:func:`flexsat.dynamics.attitude.quaternion_multiply` (:math:`C(B/R) = C(B/N)\,C(R/N)^T`), so
its vector part is in body components. The target is at rest, so the body rate ω relative to R
is the inertial body rate, and the closed loop is Euler's equations
:math:`I\dot\omega = -\omega\times I\omega + u` with the kinematics of the error.

* :class:`GibbsLyapunovLaw`, Junkins, Att. 3 §II Eqs. 1–4 (Junkins, Pollock &
  Rahman 1990), Gibbs (classical Rodrigues) parameters q of the error:

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

* :class:`QuaternionPD`, the quaternion proportional-derivative law (Wie, Weiss & Arapostathis,
  J. Guid. Control Dyn. 12(3), 1989; Schaub & Junkins §8.2), on the short rotation
  (δβ0 >= 0):

  .. math::

      u = -K_p\,\delta\beta_{1:3}\,\mathrm{sign}(\delta\beta_0) - K_d(\omega - \omega_{ref}),
      \qquad V = \tfrac12\omega^T I\omega + 2K_p(1 - |\delta\beta_0|), \qquad
      \dot V = -\omega^T K_d\,\omega

  (scalar K_p, ω_ref = 0), because :math:`\delta\dot\beta_0 = -\tfrac12\delta\beta_{1:3}^T
  \omega`. The sign makes the torque turn the body the short way: δβ and −δβ are the same
  attitude, and without it the body would unwind a full turn from half the error set.

Every law is a :class:`flexsat.control.base.Controller`: it reads the plant's ``attitude``
(Euler parameters, (n_cases, 4)) and ``rate`` (body rate, rad/s, (n_cases, 3)) channels and
writes ``torque`` (body components, N·m, (n_cases, 3)), the channels of
:class:`flexsat.dynamics.rigid_spacecraft.RigidSpacecraft` and
:class:`flexsat.dynamics.flexible_spacecraft.FlexibleSpacecraft`. Gains and targets carry
leading case axes (one per case); they are checked and broadcast once, at construction, and the
per-sample call does arithmetic only. :meth:`torque` is the same law as a function of (β, ω),
the torque argument of :func:`flexsat.dynamics.rigid_body.propagate` through
``lambda t, beta, w: law.torque(beta, w)``.
"""

from __future__ import annotations

from abc import abstractmethod
from collections.abc import Mapping
from dataclasses import Field, dataclass, field
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from flexsat.control.base import Controller
from flexsat.dynamics.attitude import (
    SINGULAR_TOL,
    case_shape,
    require_quaternion,
    require_shape,
)
from flexsat.dynamics.rigid_body import require_inertia
from flexsat.input_checks import FieldError, require_finite, require_positive, set_si

if TYPE_CHECKING:
    import numpy.typing as npt

    from flexsat.units import FloatArray

__all__ = ["GibbsLyapunovLaw", "MRPLaw", "QuaternionPD", "error_quaternion"]

_IDENTITY = (1.0, 0.0, 0.0, 0.0)


def error_quaternion(beta: npt.ArrayLike, beta_target: npt.ArrayLike) -> FloatArray:
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
    b = require_quaternion(beta)
    r = require_quaternion(beta_target, "beta_target")
    case_shape(beta=b.shape[:-1], beta_target=r.shape[:-1])
    return _error(b, r)


def _error(b: FloatArray, r: FloatArray) -> FloatArray:
    # β ⊗ r* written out (Schaub & Junkins Eq. 3.105 with r* = [r0, −r_v])
    out = np.empty(np.broadcast_shapes(b.shape, r.shape))
    bv, rv = b[..., 1:], r[..., 1:]
    out[..., 0] = b[..., 0] * r[..., 0] + np.sum(bv * rv, axis=-1)
    out[..., 1:] = r[..., 0:1] * bv - b[..., 0:1] * rv + np.cross(bv, rv)
    return out


def _per_axis(value: npt.ArrayLike, name: str) -> FloatArray:
    value = np.asarray(value, float)
    if value.ndim and value.shape[-1] != 3:
        raise FieldError(
            name,
            "per-axis gains must be a scalar or have last axis 3 (body "
            f"axes 1, 2, 3; leading axes are cases), got shape {value.shape}",
        )
    return value


class _AttitudeLaw(Controller):
    """What the three laws share: channels, the case shape of their parameters (checked once)
    and the per-sample call on the measured ``attitude`` and ``rate``."""

    reads = ("attitude", "rate")
    writes = ("torque",)
    #: fields whose last axis is a body axis or a quaternion component, not a case axis
    _VECTORS: tuple[str, ...] = ()
    # the dataclass machinery of the subclasses (typeshed's DataclassInstance)
    __dataclass_fields__: ClassVar[dict[str, Field[Any]]]
    beta_target: npt.ArrayLike
    _field_cases: dict[str, tuple[int, ...]]
    _case_shape: tuple[int, ...]

    def _finish(self) -> None:
        """Check the target quaternion and the case axes of every field against each other;
        keep the case shape."""
        object.__setattr__(self, "beta_target", require_quaternion(self.beta_target, "beta_target"))
        shapes: dict[str, tuple[int, ...]] = {}
        for name in self.__dataclass_fields__:
            shape = np.shape(getattr(self, name))
            shapes[name] = shape[:-1] if name in self._VECTORS and shape else shape
        object.__setattr__(self, "_field_cases", shapes)
        object.__setattr__(self, "_case_shape", case_shape(**shapes))
        object.__setattr__(self, "target", self.beta_target)

    @property
    def n_cases(self) -> int:
        return int(np.prod(self._case_shape))

    def _measured(self, beta: npt.ArrayLike, w: npt.ArrayLike) -> tuple[FloatArray, FloatArray]:
        """β and ω checked and their case axes checked against the law's (for the public
        functions of (β, ω); the per-sample call trusts the engine's shapes)."""
        b = require_quaternion(beta)
        rate = require_shape(w, "w", (3,))
        case_shape(beta=b.shape[:-1], w=rate.shape[:-1], **self._field_cases)
        return b, rate

    def __call__(
        self, t: float, y: Mapping[str, FloatArray], state: dict[str, FloatArray]
    ) -> tuple[FloatArray, dict[str, FloatArray]]:
        """The torque command (N·m, body components, (n_cases, 3)) from the measured
        ``attitude`` and ``rate``; the law has no internal state."""
        return self._torque(np.asarray(y["attitude"], float), np.asarray(y["rate"], float)), state

    def torque(self, beta: npt.ArrayLike, w: npt.ArrayLike) -> FloatArray:
        """The torque u (N·m, body components, shape (..., 3)) at attitude β, rate ω (checked)."""
        return self._torque(*self._measured(beta, w))

    @abstractmethod
    def _torque(self, beta: FloatArray, w: FloatArray) -> FloatArray:
        """The law's torque at checked β (..., 4) and ω (..., 3)."""

    @staticmethod
    def _kinetic(w: FloatArray, inertia: npt.ArrayLike) -> FloatArray:
        J = require_inertia(inertia)
        return 0.5 * np.einsum("...i,...ij,...j->...", w, J, w)


@dataclass(frozen=True)
class GibbsLyapunovLaw(_AttitudeLaw):
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

    k: float | FloatArray
    A: float | FloatArray
    beta_target: npt.ArrayLike = field(default=_IDENTITY)
    _VECTORS = ("k", "beta_target")

    def __post_init__(self) -> None:
        set_si(self, "k", require_positive, "N*m*s/rad")
        _per_axis(self.k, "k")
        set_si(self, "A", require_positive, "N*m")
        self._finish()

    def gibbs(self, beta: npt.ArrayLike) -> FloatArray:
        """Gibbs parameters q = l tan(φ/2) of the error (shape (..., 3)); refused at 180°."""
        e = _error(np.asarray(beta, float), np.asarray(self.beta_target, float))
        if np.any(np.abs(e[..., 0]) < SINGULAR_TOL):
            raise FieldError(
                "attitude",
                "the Gibbs law is singular at a 180° error (|β0| < "
                f"{SINGULAR_TOL:g}); start below 180°, where U keeps the motion",
            )
        return e[..., 1:] / e[..., :1]

    def _torque(self, beta: FloatArray, w: FloatArray) -> FloatArray:
        q = self.gibbs(beta)
        A = np.asarray(self.A)[..., None]
        return -(self.k * w + A * q * (1 + np.sum(q * q, axis=-1))[..., None])

    def lyapunov(self, beta: npt.ArrayLike, w: npt.ArrayLike, inertia: npt.ArrayLike) -> FloatArray:
        r"""U = ½ ωᵀIω + A qᵀq (J), Att. 3 Eq. 2."""
        b, rate = self._measured(beta, w)
        q = self.gibbs(b)
        return self._kinetic(rate, inertia) + self.A * np.sum(q * q, axis=-1)

    def lyapunov_rate(self, w: npt.ArrayLike) -> FloatArray:
        r""":math:`\dot U = -\sum_i k_i\omega_i^2` (W) along the closed loop, Att. 3 Eq. 4."""
        rate = require_shape(w, "w", (3,))
        return -np.sum(self.k * rate * rate, axis=-1)


@dataclass(frozen=True)
class MRPLaw(_AttitudeLaw):
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

    K: float | FloatArray
    P: float | FloatArray
    beta_target: npt.ArrayLike = field(default=_IDENTITY)
    _VECTORS = ("P", "beta_target")

    def __post_init__(self) -> None:
        set_si(self, "K", require_positive, "N*m")
        set_si(self, "P", require_positive, "N*m*s/rad")
        _per_axis(self.P, "P")
        self._finish()

    def mrp(self, beta: npt.ArrayLike) -> FloatArray:
        """MRPs σ = l tan(φ/4) of the error on its short rotation, |σ| <= 1 (shape (..., 3)).

        The error quaternion is taken with β0 >= 0, so 1 + β0 >= 1 and no shadow switch
        or singularity check is needed.
        """
        e = _error(np.asarray(beta, float), np.asarray(self.beta_target, float))
        e = np.where(e[..., :1] < 0, -e, e)
        return e[..., 1:] / (1 + e[..., :1])

    def _torque(self, beta: FloatArray, w: FloatArray) -> FloatArray:
        return -(np.asarray(self.K)[..., None] * self.mrp(beta) + self.P * w)

    def lyapunov(self, beta: npt.ArrayLike, w: npt.ArrayLike, inertia: npt.ArrayLike) -> FloatArray:
        r"""V = ½ ωᵀIω + 2K ln(1 + σᵀσ) (J), Schaub & Junkins Ch. 8."""
        b, rate = self._measured(beta, w)
        s = self.mrp(b)
        return self._kinetic(rate, inertia) + 2 * self.K * np.log1p(np.sum(s * s, axis=-1))

    def lyapunov_rate(self, w: npt.ArrayLike) -> FloatArray:
        r""":math:`\dot V = -\omega^T P\omega` (W) along the closed loop."""
        rate = require_shape(w, "w", (3,))
        return -np.sum(self.P * rate * rate, axis=-1)


@dataclass(frozen=True)
class QuaternionPD(_AttitudeLaw):
    r"""Quaternion PD law on the short rotation (module docstring):
    :math:`u = -K_p\,\delta\beta_{1:3}\,\mathrm{sign}(\delta\beta_0) - K_d(\omega - \omega_{ref})`.

    Parameters
    ----------
    Kp : float, array, str or pint.Quantity
        Attitude gains > 0 (N·m per unit quaternion error): a scalar or shape (..., 3).
    Kd : float, array, str or pint.Quantity
        Rate gains > 0 (N·m·s/rad): a scalar or shape (..., 3).
    beta_target : array_like, shape (..., 4)
        Unit Euler parameters of the target frame (default: the inertial frame).
    w_ref : array_like, shape (..., 3), str or pint.Quantity
        Reference body rate, rad/s (default 0: regulation to the target).
    """

    Kp: float | FloatArray
    Kd: float | FloatArray
    beta_target: npt.ArrayLike = field(default=_IDENTITY)
    w_ref: npt.ArrayLike = field(default=(0.0, 0.0, 0.0))
    _VECTORS = ("Kp", "Kd", "beta_target", "w_ref")

    def __post_init__(self) -> None:
        set_si(self, "Kp", require_positive, "N*m")
        _per_axis(self.Kp, "Kp")
        set_si(self, "Kd", require_positive, "N*m*s/rad")
        _per_axis(self.Kd, "Kd")
        w_ref = require_shape(require_finite(self.w_ref, "w_ref", "rad/s"), "w_ref", (3,))
        object.__setattr__(self, "w_ref", w_ref)
        self._finish()

    def error(self, beta: npt.ArrayLike) -> FloatArray:
        """The error quaternion on its short rotation, δβ0 >= 0 (shape (..., 4))."""
        e = _error(np.asarray(beta, float), np.asarray(self.beta_target, float))
        return np.where(e[..., :1] < 0, -e, e)

    def _torque(self, beta: FloatArray, w: FloatArray) -> FloatArray:
        return -(self.Kp * self.error(beta)[..., 1:] + self.Kd * (w - np.asarray(self.w_ref)))

    def lyapunov(self, beta: npt.ArrayLike, w: npt.ArrayLike, inertia: npt.ArrayLike) -> FloatArray:
        r"""V = ½ ωᵀIω + 2K_p(1 − |δβ0|) (J), for a scalar K_p and ω_ref = 0."""
        if np.ndim(self.Kp) and np.shape(self.Kp)[-1] == 3 or np.any(np.asarray(self.w_ref) != 0):
            raise FieldError(
                "Kp",
                "the Lyapunov function V = ½ωᵀIω + 2Kp(1 − |δβ0|) needs a "
                "gain equal on every axis and w_ref = 0",
            )
        b, rate = self._measured(beta, w)
        return self._kinetic(rate, inertia) + 2 * self.Kp * (1 - self.error(b)[..., 0])

    def lyapunov_rate(self, w: npt.ArrayLike) -> FloatArray:
        r""":math:`\dot V = -\omega^T K_d\,\omega` (W) along the closed loop (ω_ref = 0)."""
        rate = require_shape(w, "w", (3,))
        return -np.sum(self.Kd * rate * rate, axis=-1)
