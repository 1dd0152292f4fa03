r"""Steering laws of a single-gimbal CMG pyramid as controllers (Vadali, Oh & Walker,
Eqs. 3–7, in Junkins, Pollock & Rahman 1990), for the plant
:class:`~flexsat.dynamics.gimbal_cluster.GimbalCluster` (σ̇ = u) in the engine's continuous-law
mode.

* :class:`PseudoInverseSteering`: the torque law :math:`\dot\sigma = C^T(CC^T + \alpha I)^{-1}
  \dot h_{cmd}`, :math:`\dot h_{cmd} = -\tau(t)` (Eq. 7; α > 0 the singularity-robust inverse,
  Eq. 17), optionally with null motion toward a set σ_f beside it,
  :math:`+\,[I - C^T(CC^T + \alpha_n I)^{-1}C]\,k(\sigma_f - \sigma)` (Eq. 13-15);
* :class:`NullMotionSteering`: the reorientation :math:`\dot\sigma = [I - C^T(CC^T + \alpha
  I)^{-1}C]\,k(\sigma_f - \sigma)` (Eq. 13-17), V = ½|σ_f − σ|² falling as
  V' = −k(σ_f − σ)ᵀτ(σ_f − σ) <= 0 (Eq. 16).

* :class:`StationMomentumSteering`: the space station's attitude law u = −Kx and the
  pseudo-inverse steering of the momentum it demands,
  :math:`C\dot\sigma = T = [u_1 + n h_3,\ u_2,\ u_3 - n h_1]/h_r` (Att. 13 "Space Station
  Example"), for the plant
  :class:`~flexsat.dynamics.station_gimbals.StationWithGimbals`.

They read ``gimbal_angles`` (rad) and write ``gimbal_rates`` (rad/s); the kernels are those of
:mod:`flexsat.dynamics.cmg` (momenta in rotor momenta h, torques in h per second).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, TypeAlias

import numpy as np

from flexsat.control.base import Controller
from flexsat.dynamics import cmg
from flexsat.input_checks import FieldError, require_finite, require_positive_scalar

if TYPE_CHECKING:
    import numpy.typing as npt

    from flexsat.units import FloatArray

#: the spacecraft torque as given: a constant 3-vector or a callable t (s) -> 3-vector
TorqueHistory: TypeAlias = "npt.ArrayLike | Callable[[float], npt.ArrayLike]"


def _weight(value: float, field: str) -> float:
    """A nonnegative weight or gain (α, k), checked when the law is made, not at its first
    call inside a run."""
    out = float(require_finite(value, field))
    if out < 0:
        raise FieldError(field, f"must be >= 0, got {value!r}")
    return out


__all__ = ["NullMotionSteering", "PseudoInverseSteering", "StationMomentumSteering"]


def _torque_history(torque: TorqueHistory) -> Callable[[float], FloatArray]:
    """``torque`` (a constant 3-vector or a callable t -> 3-vector, h per second) as a checked
    t -> (3,): a bad callable fails at t = 0, before any run, and is checked at every call."""
    if not callable(torque):
        tq = require_finite(torque, "torque")
        if tq.shape != (3,):
            raise FieldError("torque", f"must have 3 components, got shape {tq.shape}")
        return lambda _t: tq

    def torque_at(t: float) -> FloatArray:
        value = require_finite(torque(t), "torque")
        if value.shape != (3,):
            raise FieldError(
                "torque",
                f"the callable must return 3 components, got shape {value.shape} at t = {t!r} s",
            )
        return value

    torque_at(0.0)
    return torque_at


class _GimbalLaw(Controller):
    reads: tuple[str, ...] = ("gimbal_angles",)
    writes: tuple[str, ...] = ("gimbal_rates",)

    def __init__(self, skew: float | str, n_units: int) -> None:
        cmg.pyramid_axes(n_units, skew)  # checks both
        self.skew = float(require_finite(skew, "skew", "rad"))
        self.n_units = int(n_units)

    def _batched(self) -> list[tuple[int, ...]]:
        return [()]  # one law for every case


class PseudoInverseSteering(_GimbalLaw):
    """The torque law (module docstring).

    Parameters
    ----------
    torque : array_like (3,) or callable
        Torque on the spacecraft, h per second: a constant or ``t -> (3,)`` (t in s).
    skew, n_units
        The pyramid (:func:`flexsat.dynamics.cmg.pyramid_axes`).
    alpha : float
        Singularity-robust weight (>= 0; 0 the pseudo-inverse).
    null_target : array_like (n,), optional
        Null motion toward this set beside the torque law, gain ``null_gain`` (1/s, >= 0),
        projector weight ``null_alpha`` (>= 0).
    """

    def __init__(
        self,
        torque: TorqueHistory,
        skew: float | str = cmg.SKEW,
        n_units: int = 4,
        alpha: float = 0.0,
        null_target: npt.ArrayLike | None = None,
        null_gain: float = 1.0,
        null_alpha: float = 0.0,
    ) -> None:
        super().__init__(skew, n_units)
        self.torque_at = _torque_history(torque)
        self.alpha = _weight(alpha, "alpha")
        _, self.a, self.b = cmg.pyramid_axes(self.n_units, self.skew)
        self.null_target: FloatArray | None = None
        if null_target is not None:
            target = require_finite(null_target, "null_target", "rad")
            if target.shape != (self.n_units,):
                raise FieldError(
                    "null_target", f"one gimbal set ({self.n_units},), got shape {target.shape}"
                )
            self.null_target = target
        self.null_gain = _weight(null_gain, "null_gain")
        self.null_alpha = _weight(null_alpha, "null_alpha")

    def __call__(
        self, t: float, y: Mapping[str, FloatArray], state: dict[str, FloatArray]
    ) -> tuple[FloatArray, dict[str, FloatArray]]:
        sig = y["gimbal_angles"]
        torque = self.torque_at(t)
        if self.null_target is None:
            return cmg.steer(sig, torque, self.a, self.b, self.alpha), state
        rates = cmg.steering_with_null_motion(
            sig,
            torque,
            self.null_target,
            self.null_gain,
            self.skew,
            self.n_units,
            self.alpha,
            self.null_alpha,
        )
        return rates, state


class NullMotionSteering(_GimbalLaw):
    """The null-motion reorientation toward ``target`` (module docstring).

    Parameters
    ----------
    target : array_like (n,)
        σ_f, rad.
    gain_k : float
        k, 1/s (> 0).
    skew, n_units
        The pyramid.
    alpha : float
        Weight of the projector (>= 0; the paper's ≈ 0.001 carries the motion through singular
        sets).
    """

    def __init__(
        self,
        target: npt.ArrayLike,
        gain_k: float = 1.0,
        skew: float | str = cmg.SKEW,
        n_units: int = 4,
        alpha: float = 1e-3,
    ) -> None:
        super().__init__(skew, n_units)
        self.sigma_target = require_finite(target, "sigma_target", "rad")
        if self.sigma_target.shape != (self.n_units,):
            raise FieldError(
                "sigma_target",
                f"one gimbal set ({self.n_units},), got shape {self.sigma_target.shape}",
            )
        self.gain_k = float(require_finite(gain_k, "gain_k", "1/s"))
        if self.gain_k <= 0:
            raise FieldError("gain_k", f"must be > 0, got {gain_k!r}")
        self.alpha = _weight(alpha, "alpha")

    def __call__(
        self, t: float, y: Mapping[str, FloatArray], state: dict[str, FloatArray]
    ) -> tuple[FloatArray, dict[str, FloatArray]]:
        sig = y["gimbal_angles"]
        tau = cmg.null_projector(sig, self.skew, self.n_units, self.alpha)
        return np.einsum("...ij,...j->...i", tau, self.gain_k * (self.sigma_target - sig)), state


class StationMomentumSteering(_GimbalLaw):
    r"""The station's attitude law and its CMG loop as one law (module docstring): reads the
    station ``state`` x and ``gimbal_angles`` σ, writes ``torque`` u = −Kx (N m) and
    ``gimbal_rates`` σ̇ = Cᵀ(CCᵀ + αI)⁻¹T with

    .. math::

        T = [u_1 + n h_3,\ u_2,\ u_3 - n h_1] / h_r

    the rate of the cluster momentum in body axes that delivers u in the rotating LVLH frame
    (Eq. 10 and "Space Station Example" of Vadali, Oh & Walker, Att. 13 of Junkins, Pollock &
    Rahman 1990).

    Parameters
    ----------
    gain : array_like (3, n_x)
        K of u = −Kx on the station's state (N m per state unit).
    momentum_rows : sequence of 3 int
        Where h1, h2, h3 (N m s) sit in the station's state.
    orbit_rate : float
        n, rad/s (> 0).
    rotor_momentum : float
        h_r of one rotor, N m s (> 0).
    skew, n_units
        The pyramid.
    alpha : float
        Singularity-robust weight (>= 0; 0 the pseudo-inverse).
    """

    reads = ("state", "gimbal_angles")
    writes = ("torque", "gimbal_rates")

    def __init__(
        self,
        gain: npt.ArrayLike,
        momentum_rows: tuple[int, int, int],
        orbit_rate: float,
        rotor_momentum: float,
        skew: float | str = cmg.SKEW,
        n_units: int = 4,
        alpha: float = 0.0,
    ) -> None:
        super().__init__(skew, n_units)
        self.gain = require_finite(gain, "gain")
        if self.gain.ndim != 2 or self.gain.shape[0] != 3:
            raise FieldError("gain", f"must be K of shape (3, n_x), got {self.gain.shape}")
        rows = np.asarray(momentum_rows)
        if (
            rows.shape != (3,)
            or rows.dtype.kind not in "iu"
            or not (np.all(rows >= 0) and np.all(rows < self.gain.shape[1]))
        ):
            raise FieldError(
                "momentum_rows",
                f"must be 3 state indices below {self.gain.shape[1]}, got {momentum_rows!r}",
            )
        self.rows = rows
        self.orbit_rate = require_positive_scalar(orbit_rate, "orbit_rate", "rad/s")
        self.rotor_momentum = require_positive_scalar(rotor_momentum, "rotor_momentum", "N*m*s")
        self.alpha = _weight(alpha, "alpha")
        _, self.a, self.b = cmg.pyramid_axes(self.n_units, self.skew)

    def demand(self, x: FloatArray) -> tuple[FloatArray, FloatArray]:
        """u = −Kx (N m) and T (rotor momenta per second) of the states x (..., n_x)."""
        u = -np.einsum("ij,...j->...i", self.gain, x)
        h = x[..., self.rows]
        n = self.orbit_rate
        T = np.stack([u[..., 0] + n * h[..., 2], u[..., 1], u[..., 2] - n * h[..., 0]], axis=-1)
        return u, T / self.rotor_momentum

    def __call__(
        self, t: float, y: Mapping[str, FloatArray], state: dict[str, FloatArray]
    ) -> tuple[dict[str, FloatArray], dict[str, FloatArray]]:
        u, T = self.demand(y["state"])
        # the kernels take the torque on the spacecraft, −ḣ
        rates = cmg.steer(y["gimbal_angles"], -T, self.a, self.b, self.alpha)
        return {"torque": u, "gimbal_rates": rates}, state
