r"""Tethered subsatellite: the three-degree-of-freedom libration and length dynamics of a point
mass on a straight massless tether below (or above) a body in a circular orbit (Vadali & Kim,
AIAA 90-1197; Junkins, Pollock & Rahman 1990, Att. 12, "Equations of Motion").

Nondimensional form (Junkins, Pollock & Rahman 1990, Att. 12 Eq. 4), τ = Ω t, λ = l/L,
T̂ = T/(mΩ²L), F̂ = F/(mΩ²L), ' = d/dτ:

.. math::

    \lambda'' - \lambda[\phi'^2 + \cos^2\phi(1+\theta')^2 - 1 + 3\cos^2\phi\cos^2\theta]
        &= -\hat T \\
    \theta'' + 2(\lambda'/\lambda - \phi'\tan\phi)(1+\theta') + 3\cos\theta\sin\theta &= 0 \\
    \phi'' + 2(\lambda'/\lambda)\phi' + \cos\phi\sin\phi[(1+\theta')^2 + 3\cos^2\theta]
        &= \hat F/\lambda

θ is the in-plane pitch, φ the out-of-plane roll (the paper calls it "yaw" once,
Att. 12 "Equations of Motion"), l the tether length, T the tension, F the
out-of-plane thrust on the subsatellite
of mass m, Ω the orbital rate and L the reference length. With the length rate as the control
(the tether-rate law, Eq. 24) the first equation is replaced by λ' = u.

The integral of motion (Eq. 8) and its rate (Eq. 9; the thrust term added):

.. math::

    V_1 = \tfrac12(\theta'^2\cos^2\phi + 3\sin^2\theta\cos^2\phi + \phi'^2 + 4\sin^2\phi),
    \qquad V_1' = -2\frac{\lambda'}{\lambda}[\theta'(1+\theta')\cos^2\phi + \phi'^2]
                  + \phi'\hat F/\lambda

so V1 is constant while the length is held and no thrust acts.

:class:`TetheredSubsatellite` is the :class:`~flexsat.dynamics.plant.Plant` of the simulation
core, in SI (state [l, θ, φ, l̇, θ̇, φ̇] with l̇ the length rate in m/s; rate control drops l̇
from the state); :class:`TetherScales` converts between the two forms. The kernels
(:func:`accelerations`, :func:`integral_of_motion`) work on nondimensional arrays with a leading
case axis; a closed-loop run is the engine's (:func:`flexsat.cases.tether.closed_loop`, on
:func:`flexsat.sim.engine.simulate`), kept as a :class:`ClosedLoopRun`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from flexsat.dynamics.plant import Channel, Plant
from flexsat.input_checks import (
    FieldError,
    require_finite,
    require_positive_scalar,
)

if TYPE_CHECKING:
    import numpy.typing as npt

    from flexsat.units import FloatArray, QuantityArrayLike, QuantityLike

__all__ = [
    "EARTH_MU",
    "EARTH_RADIUS",
    "TetherScales",
    "TetheredSubsatellite",
    "accelerations",
    "rate_control_accelerations",
    "integral_of_motion",
    "integral_of_motion_rate",
    "require_lengths",
    "MAX_ALTITUDE",
    "MIN_LENGTH",
    "ClosedLoopRun",
    "CONTROLS",
]

#: Earth's gravitational parameter, m³/s² (WGS 84), for the orbit rate of a circular orbit
EARTH_MU = 3.986004418e14
#: Earth's equatorial radius, m (WGS 84)
EARTH_RADIUS = 6378137.0
#: highest altitude of a circular Earth orbit here, m: the Earth's Hill sphere radius
#: a (m/3M)^(1/3) ≈ 1.5e9 m (1 au, Earth/Sun mass ratio 3.0e-6), beyond which the Sun, not
#: the Earth, holds the orbit
MAX_ALTITUDE = 1.5e9
#: a nondimensional length below which the tether is taken as collapsed (the plant's
#: :meth:`TetheredSubsatellite.domain_margin`: a continuous run stops there): Eq. 4's λ'/λ
#: terms are singular at λ = 0, and an adaptive integrator approaching it takes steps ~λ, never
#: arriving; 1e-4 L is 2 m of the paper's 20 km tether
MIN_LENGTH = 1e-4
#: the input modes: tension and thrust (Eqs. 4), or length rate and thrust (Eq. 24 with Eq. 4)
CONTROLS = ("tension", "rate")


def require_lengths(lam: npt.ArrayLike, field: str = "lambda") -> FloatArray:
    """``lam`` as a float array of nondimensional tether lengths, each finite and > 0 (Eq. 4
    divides by λ: a zero or negative length is no tether)."""
    arr = require_finite(lam, field)
    if np.any(arr <= 0):
        raise FieldError(field, f"the tether length must be > 0, got min {arr.min():.6g}")
    return arr


def accelerations(
    x: FloatArray, tension: float | FloatArray, thrust: float | FloatArray
) -> FloatArray:
    r"""(λ'', θ'', φ'') of Eq. 4 at nondimensional states x = [λ, θ, φ, λ', θ', φ'] (..., 6),
    tension T̂ and thrust F̂ (...,); unchecked (a kernel)."""
    lam, th, ph, dl, dth, dph = (x[..., i] for i in range(6))
    c, s, ct, st = np.cos(ph), np.sin(ph), np.cos(th), np.sin(th)
    w = 1.0 + dth
    out = np.empty(np.broadcast_shapes(x.shape, np.shape(tension) + (6,))[:-1] + (3,))
    out[..., 0] = lam * (dph * dph + c * c * w * w - 1.0 + 3.0 * c * c * ct * ct) - tension
    out[..., 1] = -2.0 * (dl / lam - dph * s / c) * w - 3.0 * ct * st
    out[..., 2] = -2.0 * (dl / lam) * dph - c * s * (w * w + 3.0 * ct * ct) + thrust / lam
    return out


def rate_control_accelerations(
    x: FloatArray, length_rate: npt.ArrayLike, thrust: float | FloatArray
) -> FloatArray:
    r"""(θ'', φ'') of Eq. 4 with the length rate λ' as the control, at nondimensional states
    x = [λ, θ, φ, θ', φ'] (..., 5); unchecked."""
    full = np.concatenate(
        [x[..., :3], np.asarray(length_rate, float)[..., None] + 0 * x[..., :1], x[..., 3:]], -1
    )
    return accelerations(full, 0.0, thrust)[..., 1:]


def integral_of_motion(
    theta: float | FloatArray,
    phi: float | FloatArray,
    theta_rate: float | FloatArray,
    phi_rate: float | FloatArray,
) -> FloatArray:
    r"""V1 of Eq. 8, :math:`\tfrac12(\theta'^2\cos^2\phi + 3\sin^2\theta\cos^2\phi + \phi'^2 +
    4\sin^2\phi)` (nondimensional rates)."""
    c2 = np.cos(phi) ** 2
    return 0.5 * (
        theta_rate**2 * c2 + 3.0 * np.sin(theta) ** 2 * c2 + phi_rate**2 + 4.0 * np.sin(phi) ** 2
    )


def integral_of_motion_rate(x: FloatArray, thrust: float | FloatArray = 0.0) -> FloatArray:
    r"""V1' of Eq. 9 with the thrust term φ'F̂/λ at x = [λ, θ, φ, λ', θ', φ']."""
    lam, ph, dl, dth, dph = x[..., 0], x[..., 2], x[..., 3], x[..., 4], x[..., 5]
    return -2.0 * dl / lam * (dth * (1.0 + dth) * np.cos(ph) ** 2 + dph**2) + dph * thrust / lam


@dataclass(frozen=True, init=False)
class TetherScales:
    """The scales of the nondimensional form: Ω, m and L (Junkins, Pollock & Rahman 1990,
    Att. 12 "Equations of Motion").

    Parameters
    ----------
    orbit_rate : float, str or Quantity, optional
        Ω, rad/s (> 0). Give it or ``altitude``.
    altitude : float, str or Quantity, optional
        Altitude of the circular orbit above the equatorial radius, m (>= 0); Ω = √(μ/(R+h)³).
    mass : float, str or Quantity
        Subsatellite mass m, kg (> 0).
    length : float, str or Quantity
        Reference tether length L, m (> 0).

    Notes
    -----
    The paper's case (Att. 12 "Tension Control Law Design Based on Decoupled Equations of Motion"):
    220 km (Ω = 0.07068 rad/min), m = 22.7 kg, L = 20 km, so
    one unit of T̂ or F̂ is mΩ²L = 0.630 N, of ∫|F̂|dτ mΩL = 534.8 N s, of λ' LΩ = 23.56 m/s.
    """

    mass: float
    length: float
    orbit_rate: float
    altitude: float | None

    # the scales arrive as numbers, Quantities or unit strings (the orbit as its rate or its
    # altitude) and are stored in SI: an explicit __init__ keeps the attributes' types apart
    # from the parameters'
    def __init__(
        self,
        mass: QuantityLike = 1.0,
        length: QuantityLike = 1.0,
        orbit_rate: QuantityLike | None = None,
        altitude: QuantityLike | None = None,
    ) -> None:
        object.__setattr__(self, "mass", require_positive_scalar(mass, "mass", "kg"))
        object.__setattr__(self, "length", require_positive_scalar(length, "length", "m"))
        if orbit_rate is not None and altitude is not None:
            raise FieldError("orbit_rate", "give the orbit rate or the altitude, not both")
        height: float | None = None
        if altitude is not None:
            given = require_finite(altitude, "altitude", "m")
            if given.ndim != 0:
                raise FieldError("altitude", f"must be one altitude, got shape {given.shape}")
            height = float(given)
            if height < 0:
                raise FieldError(
                    "altitude", f"must be >= 0 (above the Earth's surface), got {height} m"
                )
            if height > MAX_ALTITUDE:
                raise FieldError(
                    "altitude",
                    f"{height:.3g} m is beyond the Earth's Hill sphere ({MAX_ALTITUDE:.2g} m): "
                    "no circular Earth orbit there",
                )
            rate = float(np.sqrt(EARTH_MU / (EARTH_RADIUS + height) ** 3))
        elif orbit_rate is not None:
            rate = require_positive_scalar(orbit_rate, "orbit_rate", "rad/s")
        else:  # neither: the nondimensional form itself
            rate = 1.0
        object.__setattr__(self, "orbit_rate", rate)
        object.__setattr__(self, "altitude", height)
        # the nondimensional form divides by these units: each a normal, finite float
        units = {"force mΩ²L": self.force, "speed LΩ": self.speed, "impulse mΩL": self.impulse}
        for name, unit in units.items():
            if not (np.isfinite(unit) and unit >= 1e-300):  # so that 1/unit is finite too
                raise FieldError(
                    "mass",
                    f"the mass {self.mass:.3g} kg, length {self.length:.3g} m and orbit rate "
                    f"{rate:.3g} rad/s make the {name} unit {unit:.3g} (SI), beyond a float's "
                    "range",
                )

    @property
    def force(self) -> float:
        """mΩ²L, N per unit of T̂ or F̂."""
        return self.mass * self.orbit_rate**2 * self.length

    @property
    def impulse(self) -> float:
        """mΩL, N s per unit of ∫|F̂|dτ."""
        return self.mass * self.orbit_rate * self.length

    @property
    def speed(self) -> float:
        """LΩ, m/s per unit of λ'."""
        return self.length * self.orbit_rate

    @property
    def period(self) -> float:
        """Orbital period 2π/Ω, s."""
        return 2.0 * np.pi / self.orbit_rate

    def state_to_si(self, xhat: FloatArray) -> FloatArray:
        """[λ, θ, φ, (λ'), θ', φ'] → [l, θ, φ, (l̇), θ̇, φ̇] (6 or 5 entries)."""
        return np.asarray(xhat, float) * self._factors(np.shape(xhat)[-1])

    def state_from_si(self, x: FloatArray) -> FloatArray:
        """[l, θ, φ, (l̇), θ̇, φ̇] → [λ, θ, φ, (λ'), θ', φ']."""
        return np.asarray(x, float) / self._factors(np.shape(x)[-1])

    def _factors(self, n: int) -> FloatArray:
        W, L = self.orbit_rate, self.length
        if n == 6:
            return np.array([L, 1.0, 1.0, L * W, W, W])
        if n == 5:
            return np.array([L, 1.0, 1.0, W, W])
        raise FieldError(
            "state", f"must have 6 (tension control) or 5 (rate control) entries, got {n}"
        )


class TetheredSubsatellite(Plant):
    r"""Eq. 4 in SI as a plant (module docstring).

    Parameters
    ----------
    scales : TetherScales, optional
        Ω, m, L; the default (1 rad/s, 1 kg, 1 m) makes SI and nondimensional values equal.
    control : {"tension", "rate"}
        ``tension``: inputs ``tension`` (N) and ``thrust`` (N), state [l, θ, φ, l̇, θ̇, φ̇];
        ``rate``: inputs ``reel_rate`` (the commanded l̇, m/s) and ``thrust``, state
        [l, θ, φ, θ̇, φ̇].

    Notes
    -----
    In the protocol's form the kinematics (and, with rate control, l̇ = u) are the linear part;
    −T/m enters through B; the rest of the accelerations (ΩL²-scaled Eq. 4) is the nonlinear
    force with B_f selecting the three (two) acceleration rows. The engine propagates it with
    its fourth-order exponential Runge-Kutta scheme (Krogstad's, :mod:`flexsat.sim.integrators`)
    in the sampled mode, or DOP853 in the continuous-law mode; :meth:`domain_margin` ends a run
    whose tether collapses.
    """

    nonlinear = True
    #: the engine's fourth-order exponential integrator for the sampled mode (the kinematics
    #: exactly, Eq. 4's accelerations by Krogstad's scheme)
    integrator = "exp_rk4"
    #: what :meth:`domain_margin` < 0 means
    domain_rule = f"length: the tether collapsed (length below {MIN_LENGTH:g} L)"
    recorded = ("length", "pitch", "roll", "length_rate", "integral_of_motion")

    def __init__(self, scales: TetherScales | None = None, control: str = "tension") -> None:
        if control not in CONTROLS:
            raise FieldError("control", f"must be one of {CONTROLS}, got {control!r}")
        self.scales = TetherScales() if scales is None else scales
        if not isinstance(self.scales, TetherScales):
            raise FieldError("scales", f"must be a TetherScales, got {type(scales).__name__}")
        self.control = control
        first = (
            Channel("tension", "N", 1, "tether tension T (>= 0 for a tether)")
            if control == "tension"
            else Channel("reel_rate", "m/s", 1, "commanded tether length rate l̇")
        )
        self.inputs = (first, Channel("thrust", "N", 1, "out-of-plane thrust F"))
        self.outputs = (
            Channel("length", "m", 1, "tether length l"),
            Channel("pitch", "rad", 1, "in-plane pitch θ"),
            Channel("roll", "rad", 1, "out-of-plane roll φ"),
            Channel("length_rate", "m/s", 1, "tether length rate l̇"),
            Channel("pitch_rate", "rad/s", 1, "pitch rate θ̇"),
            Channel("roll_rate", "rad/s", 1, "roll rate φ̇"),
            Channel("integral_of_motion", "", 1, "V1 of Eq. 8 (nondimensional)"),
            Channel("state", "", self.nx, "the state vector (SI)"),
        )
        self.noise_channels = tuple(
            c.name for c in self.outputs if c.name not in ("state", "integral_of_motion")
        )

    @property
    def nx(self) -> int:
        return 6 if self.control == "tension" else 5

    # -- the protocol's split -----------------------------------------------------------------
    def linear_part(self) -> tuple[FloatArray, FloatArray]:
        """A: the kinematics (l̇, θ̇, φ̇ rows); B: −1/m on l̈ (tension) or 1 on l̇ (rate)."""
        n = self.nx
        A = np.zeros((n, n))
        B = np.zeros((n, 2))
        if self.control == "tension":
            A[0:3, 3:6] = np.eye(3)
            B[3, 0] = -1.0 / self.scales.mass
        else:
            A[1, 3] = A[2, 4] = 1.0
            B[0, 0] = 1.0
        return A, B

    @property
    def force_matrix(self) -> FloatArray:
        n = self.nx
        Bf = np.zeros((n, n - 3))
        Bf[3:, :] = np.eye(n - 3)
        return Bf

    def _nondimensional(
        self, x: FloatArray, u: FloatArray
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        s = self.scales
        xhat = x / s._factors(self.nx)
        return xhat, u[..., 0], u[..., 1] / s.force

    def nonlinear_force(self, x: FloatArray, u: FloatArray) -> FloatArray:
        """The accelerations of Eq. 4 in SI less the linear −T/m (module docstring)."""
        s = self.scales
        W2 = s.orbit_rate**2
        xhat, u0, Fhat = self._nondimensional(np.asarray(x, float), np.asarray(u, float))
        if self.control == "tension":
            acc = accelerations(xhat, 0.0, Fhat)
            return acc * np.array([s.length * W2, W2, W2])
        return rate_control_accelerations(xhat, u0 / s.speed, Fhat) * W2

    def rhs(self, x: FloatArray, u: FloatArray) -> FloatArray:
        """ẋ = A x + B u + B_f f(x, u), SI."""
        A, B = self.linear_part()
        return x @ A.T + u @ B.T + self.nonlinear_force(x, u) @ self.force_matrix.T

    def domain_margin(self, x: npt.ArrayLike) -> FloatArray:
        """λ − :data:`MIN_LENGTH` per case (the model holds while > 0), x (..., n_x) SI."""
        return np.asarray(x, float)[..., 0] / self.scales.length - MIN_LENGTH

    # -- outputs ---------------------------------------------------------------------------
    _ROWS = {"length": 0, "pitch": 1, "roll": 2}

    def output_matrices(self, name: str) -> tuple[FloatArray, FloatArray, FloatArray | None] | None:
        n = self.nx
        rows = dict(self._ROWS)
        rows.update(
            {"length_rate": 3, "pitch_rate": 4, "roll_rate": 5}
            if n == 6
            else {"pitch_rate": 3, "roll_rate": 4}
        )
        if name == "state":
            return np.eye(n), np.zeros((n, 2)), None
        if name == "length_rate" and n == 5:  # rate control: the commanded rate itself
            return np.zeros((1, n)), np.array([[1.0, 0.0]]), None
        if name in rows:
            return np.eye(n)[[rows[name]]], np.zeros((1, 2)), None
        return None

    def output(
        self, name: str, x: FloatArray, u: FloatArray | None = None, f_in: FloatArray | None = None
    ) -> FloatArray:
        self._size(name)
        if name == "integral_of_motion":
            xhat = np.asarray(x, float) / self.scales._factors(self.nx)
            k = 3 if self.nx == 6 else 2
            return integral_of_motion(
                xhat[..., 1], xhat[..., 2], xhat[..., k + 1], xhat[..., k + 2]
            )
        if u is None:
            u = np.zeros(np.shape(x)[:-1] + (2,))
        return super().output(name, x, u, f_in)

    def initial_state(self, n_cases: int) -> FloatArray:
        """The tether deployed to its reference length L along the local vertical, at rest,
        (n_cases, n_x) SI: the plant's rest state (a zero length is the collapsed tether, which
        :meth:`state_from` refuses and the laws divide by)."""
        x = np.zeros((n_cases, self.nx))
        x[:, 0] = self.scales.length
        return x

    def state_from(self, **values: QuantityArrayLike) -> FloatArray:
        """Initial state from ``length`` (> 0), ``pitch``, ``roll`` and their rates, SI (a
        number, a Quantity or a unit string); the length has no default."""
        x = super().state_from(**values)
        if "length" not in values and "state" not in values:
            raise FieldError("length", "the initial tether length is required (> 0)")
        require_lengths(x[0], "length")
        return x


# -- a closed-loop run ---------------------------------------------------------------------------
@dataclass(frozen=True)
class ClosedLoopRun:
    """A closed-loop tether run in the paper's nondimensional variables
    (:func:`flexsat.cases.tether.closed_loop`).

    Attributes
    ----------
    tau : (n_t,) array
        Nondimensional time τ = Ωt.
    state : (n_cases, n_t, 6) array
        [λ, θ, φ, λ', θ', φ'] (λ' is the commanded rate under rate control).
    control : (n_cases, n_t, 2) array
        (T̂ or λ', F̂) of the law along the run.
    thrust_index : (n_cases, n_t) array
        ∫₀^τ |F̂| dτ on the output grid (:func:`flexsat.control.tether_laws.thrust_index`).
    """

    tau: FloatArray
    state: FloatArray
    control: FloatArray
    thrust_index: FloatArray

    @property
    def integral_of_motion(self) -> FloatArray:
        """V1 (Eq. 8) along the run, (n_cases, n_t)."""
        x = self.state
        return integral_of_motion(x[..., 1], x[..., 2], x[..., 4], x[..., 5])
