"""Disturbance torques on the hub: bearing friction, random torque, impulses."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from flexsat.input_checks import (
    FieldError,
    require_finite,
    require_nonneg,
    require_positive,
    set_si,
)
from flexsat.sim.step import friction_torque


@dataclass(frozen=True)
class BearingFriction:
    """τ = −c1 sign(θ') − c2 θ' (Junkins, Pollock & Rahman 1990, Att. 3 Eq. 23;
    c1 ≈ 20 oz-in, c2 ≈ 0.001 oz-in s).

    The sign is regularised as tanh(θ'/ε) so the integrator sees a Lipschitz force; inside
    |θ'| < ε the bearing acts as a stiff viscous damper c1/ε, which reproduces sticking to within
    a creep rate of order ε.

    Parameters
    ----------
    coulomb : float   c1, N m
    viscous : float   c2, N m s/rad
    smoothing : float ε, rad/s

    Notes
    -----
    Each a number in SI, a pint Quantity or a unit string (``"20 ozf*in"``), stored in SI; or
    one value per case of the batch, (n_cases,) (a Monte Carlo over the friction).
    """

    coulomb: float = 0.0
    viscous: float = 0.0
    smoothing: float = 1e-3

    def __post_init__(self) -> None:
        set_si(self, "coulomb", require_nonneg, "N*m")
        set_si(self, "viscous", require_nonneg, "N*m*s/rad")
        set_si(self, "smoothing", require_positive, "rad/s")

    @property
    def active(self) -> bool:
        """Whether any case has friction."""
        return bool(np.any(np.asarray(self.coulomb) > 0) or np.any(np.asarray(self.viscous) > 0))

    @property
    def max_slope(self) -> float:
        """Largest |dτ/dθ'|, c1/ε + c2 (at θ' = 0), N m s/rad, the largest over the cases: the
        stiffness the integrator must resolve (:func:`flexsat.sim.config.stable_substeps`)."""
        return float(np.max(self.coulomb / self.smoothing + self.viscous))

    def __call__(self, rate: np.ndarray) -> np.ndarray:
        return friction_torque(rate, self.coulomb, self.viscous, self.smoothing)


@dataclass(frozen=True)
class CableSpring:
    """Position-dependent torque of the cables feeding a suspended hub:
    τ(θ) = T_D − k (θ − θ_c) + τ_tab(θ), τ_tab linear between the tabulated points and held
    at the end values outside them (Hailey, Sortun & Agrawal, "Experimental verification of
    attitude control techniques for slew maneuvers of flexible spacecraft", NPS, c. 1992:
    the NPS simulator's cable torque T_D, treated there as constant over a maneuver; under
    the PD law T = −k_p θ_e + T_D it leaves θ_ss = T_D / k_p, Eq. 23).

    Used as a :class:`~flexsat.sim.channels.ChannelDisturbance` force driven by the hub
    angle (``force_output="theta"``).

    Parameters
    ----------
    constant : float     T_D, N m
    stiffness : float    k, N m/rad (a restoring spring for k > 0)
    center : float       θ_c, rad
    angles, torques : sequences
        A tabulated profile τ_tab(θ) (rad, N m), angles strictly increasing; empty for none.
    """

    constant: float = 0.0
    stiffness: float = 0.0
    center: float = 0.0
    angles: tuple[float, ...] = ()
    torques: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        set_si(self, "constant", require_finite, "N*m")
        set_si(self, "stiffness", require_finite, "N*m/rad")
        set_si(self, "center", require_finite, "rad")
        a = (
            np.atleast_1d(require_finite(self.angles, "angles", "rad"))
            if len(self.angles)
            else np.zeros(0)
        )
        t = (
            np.atleast_1d(require_finite(self.torques, "torques", "N*m"))
            if len(self.torques)
            else np.zeros(0)
        )
        if a.shape != t.shape or a.ndim != 1 or a.size == 1:
            raise FieldError(
                "torques", f"give one torque per angle (two or more), got {t.size} for {a.size}"
            )
        if a.size and not np.all(np.diff(a) > 0):
            raise FieldError("angles", "must be strictly increasing")
        object.__setattr__(self, "angles", tuple(a.tolist()))
        object.__setattr__(self, "torques", tuple(t.tolist()))

    @property
    def max_slope(self) -> float:
        """Largest |dτ/dθ|, N m/rad (:func:`flexsat.sim.config.stable_substeps`)."""
        slope = abs(float(self.stiffness))
        if self.angles:
            slope += float(np.max(np.abs(np.diff(self.torques) / np.diff(self.angles))))
        return slope

    def __call__(self, theta: np.ndarray) -> np.ndarray:
        th = np.asarray(theta, float)
        tau = float(self.constant) - float(self.stiffness) * (th - float(self.center))
        if self.angles:
            tau = tau + np.interp(th, self.angles, self.torques)
        return np.asarray(tau, float)


@dataclass(frozen=True)
class RandomTorque:
    """Zero-mean Gaussian torque, held over each control period, 1σ = ``std`` N m (a number in
    SI, a pint Quantity or a unit string)."""

    std: float = 0.0

    def __post_init__(self) -> None:
        set_si(self, "std", require_nonneg, "N*m")


@dataclass(frozen=True)
class Impulses:
    """Angular impulses (N m s) hitting the hub at given times (s); each sequence may also be a
    pint Quantity array or a list of unit strings, stored in SI.

    Each is applied as an instantaneous momentum change at the first control sample at or after
    its time (timing error below one control period).
    """

    times: tuple[float, ...] = ()
    impulses: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        times = np.atleast_1d(require_nonneg(self.times, "impulses.times", "s"))
        impulses = np.atleast_1d(require_finite(self.impulses, "impulses.impulses", "N*m*s"))
        if times.shape != impulses.shape or times.ndim != 1:
            raise FieldError(
                "impulses", f"{impulses.size} values for {times.size} times; give one each"
            )
        object.__setattr__(self, "times", tuple(times.tolist()))
        object.__setattr__(self, "impulses", tuple(impulses.tolist()))

    def at_samples(self, n_steps: int, dt: float) -> dict[int, float]:
        """Impulse per control-sample index (:func:`impulses_at_samples`)."""
        return impulses_at_samples(self.times, self.impulses, n_steps, dt)


def impulses_at_samples(
    times: Sequence[float], impulses: Sequence[float], n_steps: int, dt: float
) -> dict[int, float]:
    """Impulse per control-sample index: each at the first sample at or after its time (a
    relative 1e-9 of dt absorbs the round-off of a time given as a multiple of dt); impulses
    on one sample add; those after the last sample are dropped."""
    out: dict[int, float] = {}
    for t, j in zip(times, impulses):
        k = int(np.ceil(t / dt - 1e-9))
        if k < n_steps:
            out[k] = out.get(k, 0.0) + j
    return out
