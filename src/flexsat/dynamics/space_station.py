r"""Linearised attitude and CMG-momentum model of the space station about LVLH, with
gravity-gradient torque, the design disturbance and periodic-disturbance filters (Vadali, Oh &
Walker, space-station example, Eq. 8–12, in Junkins, Pollock & Rahman 1990; after Wie et al.,
AIAA 88-4132).

Small roll, pitch, yaw θ1, θ2, θ3 from LVLH, body rates ω, CMG momentum h (body axes), the
internal torque u (the station feels −u) and the disturbance w:

.. math::

    I_1\dot\omega_1 + n(I_2 - I_3)\omega_3 + 3n^2(I_2 - I_3)\theta_1 = -u_1 + w_1, \quad
    I_2\ddot\theta_2 + 3n^2(I_1 - I_3)\theta_2 = -u_2 + w_2, \quad
    I_3\dot\omega_3 - n(I_2 - I_1)\omega_1 = -u_3 + w_3           \quad (8)

    \dot\theta_1 - n\theta_3 = \omega_1, \quad \dot\theta_3 + n\theta_1 = \omega_3  \quad (9)

    \dot h_1 - n h_3 = u_1, \quad \dot h_2 = u_2, \quad \dot h_3 + n h_1 = u_3       \quad (10)

(the printed "ω" of the roll equation is ω3 and the printed "ḣ1 = u2" is ḣ2: misprints).
The 3n² terms are the gravity-gradient torque. Pitch decouples from roll/yaw. Both
axes carry the integral of the CMG momentum (∫h dt: zero mean momentum, so the station settles
at its torque-equilibrium attitude) and periodic-disturbance rejection filters on the attitude,
α̈ + (kn)²α = θ (Eq. 12), one per disturbance frequency kn.

**Roll/yaw filters.** Eq. (10) already has the orbit-rate modes ±jn (the momentum turning with
LVLH). An orbit-rate filter on θ1 or θ3 adds a third mode at +jn with two inputs, and
(A, B) then fails the PBH test (geometric multiplicity 3 > 2 inputs, checked by
:func:`flexsat.control.lqr.lqr`): so the roll/yaw default has the 2n filters only, and the
orbit-rate disturbance is carried by the momentum loop. Pitch takes n and 2n.

**Disturbance.** :func:`design_disturbance` is Eq. (11) (Wie et al.'s design model). The paper
also simulates "AERO1" (variable drag, harmonics above 2n, orbit decay; Geller, private
communication), which is not given. :func:`aero_substitute` is a stated substitute, not a
reproduction: Eq. (11) plus 3n and 4n harmonics of the amplitude of Eq. (11)'s 2n term
(0.5 ft-lb, each axis) and a secular pitch torque growing by ``secular`` per orbit (default
1 ft-lb per orbit, a quarter of the pitch bias per orbit; the paper only says "a small
secular component"). Its magnitudes are assumptions, documented in docs/cmg.md.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import TYPE_CHECKING, TypeAlias

import numpy as np

from flexsat.dynamics.plant import Channel, Plant
from flexsat.input_checks import FieldError, require_finite, require_positive_scalar
from flexsat.units import to_si_array

if TYPE_CHECKING:
    from flexsat.units import FloatArray, QuantityArrayLike, QuantityLike

    #: (A, B, E, state names) of x' = A x + B u + E w (:func:`pitch_model`, :func:`roll_yaw_model`)
    LinearModel: TypeAlias = tuple[FloatArray, FloatArray, FloatArray, list[str]]

__all__ = [
    "SpaceStation",
    "StationData",
    "pitch_model",
    "roll_yaw_model",
    "design_disturbance",
    "aero_substitute",
    "FT_LB",
]

#: one foot-pound-force in N m (the paper's torque and momentum unit), from the exact
#: definitions: 1 lb = 0.45359237 kg and 1 ft = 0.3048 m (international yard and pound, 1959),
#: standard gravity 9.80665 m/s² (3rd CGPM, 1901); equal to pint's lbf·ft
#: (tests/dynamics/test_space_station.py). Written out so that importing this layer loads no
#: unit registry.
FT_LB = 0.45359237 * 9.80665 * 0.3048


@dataclass(frozen=True)
class StationData:
    """Space-station data (the paper's Table 2), SI after construction.

    Parameters
    ----------
    inertia : sequence of 3 (roll, pitch, yaw principal moments), kg m² or unit strings
        (Table 2: ``"5.28e6 slug*ft**2"`` …); products of inertia neglected (§8.4 i).
    orbit_rate : float or str
        n, rad/s (Table 2: 0.0011).
    rotor_momentum : float or str
        h per CMG, N m s (Table 2: ``"3500 lbf*ft*s"``).
    """

    inertia: tuple[float, float, float]
    orbit_rate: float
    rotor_momentum: float

    if TYPE_CHECKING:
        # what the constructor accepts (the generated __init__ at run time): quantities that
        # __post_init__ converts to the SI fields above
        def __init__(
            self,
            inertia: tuple[QuantityLike, QuantityLike, QuantityLike],
            orbit_rate: QuantityLike,
            rotor_momentum: QuantityLike,
        ) -> None: ...

    def __post_init__(self) -> None:
        if len(self.inertia) != 3:
            raise FieldError(
                "inertia", f"three principal moments (roll, pitch, yaw), got {self.inertia!r}"
            )
        moments = tuple(
            require_positive_scalar(v, f"inertia[{i}]", "kg*m**2")
            for i, v in enumerate(self.inertia)
        )
        object.__setattr__(self, "inertia", moments)
        object.__setattr__(
            self, "orbit_rate", require_positive_scalar(self.orbit_rate, "orbit_rate", "rad/s")
        )
        object.__setattr__(
            self,
            "rotor_momentum",
            require_positive_scalar(self.rotor_momentum, "rotor_momentum", "N*m*s"),
        )

    @property
    def period(self) -> float:
        """Orbit period 2π/n, s."""
        return 2.0 * np.pi / self.orbit_rate


def _filters(filters: Iterable[int], field: str) -> tuple[int, ...]:
    ks = tuple(filters)
    for k in ks:
        if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or k < 1:
            raise FieldError(
                field, f"multiples of the orbit rate must be integers >= 1, got {filters!r}"
            )
    if len(set(ks)) != len(ks):
        raise FieldError(field, f"each frequency once, got {filters!r}")
    return ks


def _add_filters(
    A: FloatArray,
    attitude_index: int,
    ks: tuple[int, ...],
    n: float,
    names: list[str],
    label: str,
) -> FloatArray:
    """Append α̈ + (kn)²α = θ (Eq. 12) for each k, driven by state ``attitude_index``."""
    size = A.shape[0]
    out = np.zeros((size + 2 * len(ks),) * 2)
    out[:size, :size] = A
    for j, k in enumerate(ks):
        i = size + 2 * j
        out[i, i + 1] = 1.0
        out[i + 1, i] = -((k * n) ** 2)
        out[i + 1, attitude_index] = 1.0
        names += [f"{label}_filter_{k}n", f"{label}_filter_{k}n_rate"]
    return out


def pitch_model(data: StationData, filters: Iterable[int] = (1, 2)) -> LinearModel:
    """Pitch axis of Eq. (8)–(10) with ∫h2 and the filters of Eq. (12).

    State [θ2, θ̇2, h2, ∫h2 dt, (α_k, α̇_k) for k in ``filters``]; input u2 (N m); disturbance
    w2 (N m).

    Returns
    -------
    A, B, E : ndarray
        x' = A x + B u + E w, shapes (n, n), (n, 1), (n, 1).
    names : list of str
    """
    ks = _filters(filters, "filters")
    I1, I2, I3 = data.inertia
    n = data.orbit_rate
    A = np.zeros((4, 4))
    A[0, 1] = 1.0
    A[1, 0] = -3.0 * n * n * (I1 - I3) / I2  # gravity gradient: I3 > I1 makes pitch unstable
    A[3, 2] = 1.0
    names = ["theta2", "theta2_rate", "h2", "h2_integral"]
    A = _add_filters(A, 0, ks, n, names, "theta2")
    B = np.zeros((A.shape[0], 1))
    E = np.zeros((A.shape[0], 1))
    B[1, 0], E[1, 0] = -1.0 / I2, 1.0 / I2
    B[2, 0] = 1.0
    return A, B, E, names


def roll_yaw_model(data: StationData, filters: Iterable[int] = (2,)) -> LinearModel:
    """Roll/yaw axes of Eq. (8)–(10) with ∫h1, ∫h3 and the filters of Eq. (12) on θ1 and θ3.

    State [θ1, ω1, h1, ∫h1, θ3, ω3, h3, ∫h3, filters on θ1, filters on θ3]; inputs (u1, u3);
    disturbances (w1, w3). An orbit-rate filter (k = 1) makes (A, B) uncontrollable (module
    docstring); :func:`flexsat.control.lqr.lqr` then says so.

    Returns
    -------
    A, B, E, names
        Shapes (n, n), (n, 2), (n, 2).
    """
    ks = _filters(filters, "filters")
    I1, I2, I3 = data.inertia
    n = data.orbit_rate
    A = np.zeros((8, 8))
    A[0, 1], A[0, 4] = 1.0, n  # θ̇1 = ω1 + nθ3      (9)
    A[4, 5], A[4, 0] = 1.0, -n  # θ̇3 = ω3 − nθ1      (9)
    A[1, 5] = -n * (I2 - I3) / I1  # (8), roll
    A[1, 0] = -3.0 * n * n * (I2 - I3) / I1  # gravity gradient, roll
    A[5, 1] = n * (I2 - I1) / I3  # (8), yaw
    A[2, 6], A[6, 2] = n, -n  # ḣ1 = nh3 + u1, ḣ3 = −nh1 + u3   (10)
    A[3, 2], A[7, 6] = 1.0, 1.0
    names = ["theta1", "omega1", "h1", "h1_integral", "theta3", "omega3", "h3", "h3_integral"]
    A = _add_filters(A, 0, ks, n, names, "theta1")
    A = _add_filters(A, 4, ks, n, names, "theta3")
    B = np.zeros((A.shape[0], 2))
    E = np.zeros((A.shape[0], 2))
    B[1, 0], E[1, 0] = -1.0 / I1, 1.0 / I1
    B[5, 1], E[5, 1] = -1.0 / I3, 1.0 / I3
    B[2, 0], B[6, 1] = 1.0, 1.0
    return A, B, E, names


def design_disturbance(t: QuantityArrayLike, data: StationData) -> FloatArray:
    """Eq. (11): w1 = w3 = 1 + sin nt + 0.5 sin 2nt, w2 = 4 + 2 sin nt + 0.5 sin 2nt ft-lb,
    in N m, shape (..., 3) (roll, pitch, yaw)."""
    tt = require_finite(t, "t", "s")
    n = data.orbit_rate
    s1, s2 = np.sin(n * tt), np.sin(2.0 * n * tt)
    roll = 1.0 + s1 + 0.5 * s2
    return FT_LB * np.stack([roll, 4.0 + 2.0 * s1 + 0.5 * s2, roll], axis=-1)


def aero_substitute(
    t: QuantityArrayLike,
    data: StationData,
    harmonic: QuantityLike = 0.5 * FT_LB,
    secular: QuantityLike = 1.0 * FT_LB,
) -> FloatArray:
    """The stated substitute for the paper's AERO1 (module docstring): Eq. (11) plus
    ``harmonic`` × (sin 3nt + sin 4nt) on each axis and a pitch torque growing by ``secular``
    per orbit (N m or unit strings; defaults 0.5 and 1 ft-lb); N m, shape (..., 3)."""
    tt = require_finite(t, "t", "s")
    a = to_si_array(harmonic, "N*m", "harmonic")
    s = to_si_array(secular, "N*m", "secular")
    if a.ndim or s.ndim or not (np.isfinite(a) and np.isfinite(s)) or a < 0 or s < 0:
        raise ValueError(
            f"harmonic, secular: one finite value >= 0 N m each, got {harmonic!r}, {secular!r}"
        )
    n = data.orbit_rate
    w = design_disturbance(tt, data)
    w = w + float(a) * (np.sin(3.0 * n * tt) + np.sin(4.0 * n * tt))[..., None]
    w[..., 1] += float(s) * tt / data.period
    return w


class SpaceStation(Plant):
    """Eq. (8)-(12) as one plant: the pitch model stacked over the roll/yaw model
    (:func:`pitch_model`, :func:`roll_yaw_model`), x = [x_pitch, x_roll_yaw].

    Parameters
    ----------
    data : StationData
    pitch_filters, roll_yaw_filters : sequence of int
        The filter frequencies (multiples k of n) of Eq. (12) on each axis group.

    Notes
    -----
    Inputs ``torque`` u = (u1, u2, u3), the CMG torque (N m; the station feels −u) and
    ``disturbance`` w = (w1, w2, w3) (N m). Outputs ``state``, ``attitude`` (θ1, θ2, θ3, rad)
    and ``momentum`` (h1, h2, h3, N m s). Linear: the engine propagates it exactly.
    """

    recorded = ("attitude", "momentum")

    def __init__(
        self,
        data: StationData,
        pitch_filters: Iterable[int] = (1, 2),
        roll_yaw_filters: Iterable[int] = (2,),
    ) -> None:
        self.data = data
        self.pitch = pitch_model(data, pitch_filters)
        self.roll_yaw = roll_yaw_model(data, roll_yaw_filters)
        self.n_pitch = self.pitch[0].shape[0]
        self.names = tuple(self.pitch[3]) + tuple(self.roll_yaw[3])
        self.inputs = (
            Channel("torque", "N*m", 3, "CMG torque u (roll, pitch, yaw); the station feels −u"),
            Channel("disturbance", "N*m", 3, "disturbance torque w (roll, pitch, yaw)"),
        )
        self.outputs = (
            Channel("state", "", self.nx, "the state vector (SI)"),
            Channel("attitude", "rad", 3, "roll, pitch, yaw θ1, θ2, θ3 from LVLH"),
            Channel("momentum", "N*m*s", 3, "CMG momentum h1, h2, h3"),
        )

    @property
    def nx(self) -> int:
        return self.n_pitch + self.roll_yaw[0].shape[0]

    def linear_part(self) -> tuple[FloatArray, FloatArray]:
        """A block-diagonal; B from u2 (pitch) and u1, u3 (roll/yaw), then E likewise from w."""
        Ap, Bp, Ep, _ = self.pitch
        Ar, Br, Er, _ = self.roll_yaw
        npitch, n = self.n_pitch, self.nx
        A = np.zeros((n, n))
        A[:npitch, :npitch], A[npitch:, npitch:] = Ap, Ar
        B = np.zeros((n, 6))
        B[:npitch, 1], B[:npitch, 4] = Bp[:, 0], Ep[:, 0]
        B[npitch:, [0, 2]], B[npitch:, [3, 5]] = Br, Er
        return A, B

    def output_matrices(self, name: str) -> tuple[FloatArray, FloatArray, FloatArray | None] | None:
        n = self.nx
        if name == "state":
            return np.eye(n), np.zeros((n, 6)), None
        rows = {"attitude": ("theta1", "theta2", "theta3"), "momentum": ("h1", "h2", "h3")}.get(
            name
        )
        if rows is None:
            return None
        return np.eye(n)[[self.names.index(k) for k in rows]], np.zeros((3, 6)), None
