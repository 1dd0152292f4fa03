r"""Space-station attitude control and CMG momentum management (Vadali, Oh & Walker, space-station
example, Junkins, Pollock & Rahman 1990, L4533-L4830).

Three steps, as in the paper:

1. **LQR design** (pitch and roll/yaw separately) on the LVLH model of
   :mod:`flexsat.dynamics.space_station` with Bryson weights: Q diagonal with
   :math:`x_i^2 Q_{ii} = 1` at the anticipated maximum x_i of each state, R = I (torque in
   N m). The paper does not print its maxima; :class:`BrysonMaxima` holds ours (defaults
   below). The Riccati equation is solved in the coordinates x̃ = D⁻¹x, D = diag(maxima), where
   Q̃ = I: the same gain K = K̃D⁻¹ (S = D⁻¹S̃D⁻¹), without the 1e13 spread of the raw
   weights that would otherwise fail the solver's residual check.
2. **Attitude loop**: the plant :class:`~flexsat.dynamics.space_station.SpaceStation` under the
   state feedback u = −Kx (a constant
   :class:`~flexsat.control.scheduled.ScheduledStateFeedback`), closed x' = (A − BK)x + Ew(t)
   in the engine's continuous-law mode (:func:`flexsat.sim.continuous.run`, w the exogenous
   input), from 1° on each axis (the paper's initial errors), w the design disturbance
   (Eq. 11) or the AERO1 substitute.
3. **CMG loop**, separately (the paper's justification: the attitude bandwidth is ~0.01 rad/s):
   the pseudo-inverse steering :math:`C\dot\sigma = T`,
   :math:`T = [u_1 + n h_3,\ u_2,\ u_3 - n h_1]/h_r` (L4717–L4720), from a chosen σ(0), stopped
   at the first singular set (:func:`flexsat.cases.cmg_pyramid.integrate_gimbals`).

Default maxima: attitude 1° (the initial error), rate 0.02 deg/s (the station's rate
requirement, §8.1), momentum 2000 ft-lb-s and its integral 2000 ft-lb-s × 100 s, filter states
θ_max/(kn)² and θ_max/(kn) (the filter's response α = θ/(kn)² to a constant θ). They keep the
momentum inside the four-CMG envelope (3.15 h_r = 11,040 ft-lb-s) for the design disturbance;
the singularity time from σ(0) = 0 depends on them (docs/cmg.md gives a scan).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from flexsat.cases.cmg_pyramid import integrate_gimbals
from flexsat.control.lqr import lqr
from flexsat.control.scheduled import ScheduledStateFeedback
from flexsat.dynamics.space_station import (
    SpaceStation,
    StationData,
    aero_substitute,
    design_disturbance,
)
from flexsat.input_checks import require_positive_scalar
from flexsat.sim import continuous
from flexsat.units import QuantityLike, to_si, to_si_array

if TYPE_CHECKING:
    from flexsat.dynamics.cmg import GimbalRun
    from flexsat.units import FloatArray

#: one axis group's design: A, B, E, state names, the gain K and the closed-loop poles
AxisDesign = tuple[np.ndarray, np.ndarray, np.ndarray, list[str], np.ndarray, np.ndarray]

__all__ = [
    "BrysonMaxima",
    "StationDesign",
    "StationRun",
    "design",
    "simulate_attitude",
    "cmg_loop",
    "DISTURBANCES",
    "PAPER_STATION",
]

#: Table 2 of the paper (L4684–L4688), as published
PAPER_STATION = StationData(
    (
        to_si("5.28e6 slug*ft**2", "kg*m**2"),
        to_si("10.80e6 slug*ft**2", "kg*m**2"),
        to_si("58.57e6 slug*ft**2", "kg*m**2"),
    ),
    0.0011,
    to_si("3500 lbf*ft*s", "N*m*s"),
)
#: disturbance models: the design model Eq. (11), or it plus the stated AERO1 substitute
DISTURBANCES = ("design", "aero_substitute")


@dataclass(frozen=True)
class BrysonMaxima:
    """Anticipated maxima of the LQR states (module docstring), SI after construction."""

    attitude: float = to_si("1 deg", "rad")
    rate: float = to_si("0.02 deg/s", "rad/s")
    momentum: float = to_si("2000 lbf*ft*s", "N*m*s")
    momentum_integral: float = to_si("2e5 lbf*ft*s**2", "N*m*s**2")

    def __post_init__(self) -> None:
        for name, unit in (
            ("attitude", "rad"),
            ("rate", "rad/s"),
            ("momentum", "N*m*s"),
            ("momentum_integral", "N*m*s**2"),
        ):
            object.__setattr__(
                self, name, require_positive_scalar(getattr(self, name), f"maxima.{name}", unit)
            )

    def scales(self, names: Sequence[str], n: float) -> np.ndarray:
        """D = the maxima of the states ``names`` of :mod:`flexsat.dynamics.space_station`
        (``n`` the orbit rate, rad/s, for the filter states)."""
        out: list[float] = []
        for name in names:
            if name.startswith("theta") and "filter" in name:
                k = int(name.split("_filter_")[1].split("n")[0])
                out.append(self.attitude / (k * n) ** (1 if name.endswith("rate") else 2))
            elif name.startswith("theta"):
                out.append(self.rate if name.endswith("rate") else self.attitude)
            elif name.startswith("omega"):
                out.append(self.rate)
            elif name.endswith("integral"):
                out.append(self.momentum_integral)
            else:
                out.append(self.momentum)
        return np.array(out)


@dataclass(frozen=True)
class StationDesign:
    """The two LQR designs, (A, B, E, names, K, closed-loop poles) per axis group, and the
    plant they were made on."""

    data: StationData
    maxima: BrysonMaxima
    pitch: AxisDesign
    roll_yaw: AxisDesign
    plant: SpaceStation

    @property
    def poles(self) -> np.ndarray:
        return np.concatenate([self.pitch[5], self.roll_yaw[5]])

    @property
    def gain(self) -> np.ndarray:
        """K (3, n_x) of u = −K x on the plant's state: u2 from the pitch design, u1 and u3
        from the roll/yaw design."""
        npitch = self.plant.n_pitch
        K = np.zeros((3, self.plant.nx))
        K[1, :npitch] = self.pitch[4][0]
        K[[0, 2], npitch:] = self.roll_yaw[4]
        return K


def _lqr_bryson(
    A: np.ndarray, B: np.ndarray, names: Sequence[str], maxima: BrysonMaxima, n: float, axis: str
) -> tuple[np.ndarray, np.ndarray]:
    D = maxima.scales(names, n)
    try:
        K_s = lqr(A / D[:, None] * D[None, :], B / D[:, None], np.eye(len(D)), np.eye(B.shape[1]))[
            0
        ]
    except ValueError as err:
        raise ValueError(f"{axis}: {err}") from None
    K = K_s / D[None, :]
    return K, np.linalg.eigvals(A - B @ K)


def design(
    data: StationData = PAPER_STATION,
    maxima: BrysonMaxima | None = None,
    pitch_filters: Sequence[int] = (1, 2),
    roll_yaw_filters: Sequence[int] = (2,),
) -> StationDesign:
    """LQR gains of the pitch and roll/yaw loops (module docstring, step 1)."""
    maxima = BrysonMaxima() if maxima is None else maxima
    n = data.orbit_rate
    plant = SpaceStation(data, pitch_filters, roll_yaw_filters)
    out: list[AxisDesign] = []
    for axis, model in (("pitch_filters", plant.pitch), ("roll_yaw_filters", plant.roll_yaw)):
        A, B, E, names = model
        K, poles = _lqr_bryson(A, B, names, maxima, n, axis)
        out.append((A, B, E, names, K, poles))
    return StationDesign(data, maxima, out[0], out[1], plant)


@dataclass(frozen=True)
class StationRun:
    """Attitude-loop history: times ``t`` (n_t,); ``attitude`` (roll, pitch, yaw) rad,
    ``momentum`` h (n_t, 3) N m s, ``torque`` u (n_t, 3) N m, ``disturbance`` w (n_t, 3) N m;
    ``demand(t)`` the CMG loop's T(t) in units of h_r per second."""

    design: StationDesign
    t: np.ndarray
    attitude: np.ndarray
    momentum: np.ndarray
    torque: np.ndarray
    disturbance: np.ndarray
    solution: Callable[[float], FloatArray] = field(repr=False)

    def demand(self, t: float) -> np.ndarray:
        """T = [u1 + n h3, u2, u3 − n h1] / h_r at time t (L4717–L4720), (3,)."""
        _, (h1, h2, h3), (u1, u2, u3) = _parts(self.design, self.solution(t))
        n = self.design.data.orbit_rate
        return np.array([u1 + n * h3, u2, u3 - n * h1]) / self.design.data.rotor_momentum


Triple = tuple[float, float, float]


def _parts(design: StationDesign, z: np.ndarray) -> tuple[Triple, Triple, Triple]:
    """(attitude θ1, θ2, θ3), (momentum h1, h2, h3), (torque u1, u2, u3) of the state z."""
    npitch = design.pitch[0].shape[0]
    xp, xr = z[:npitch], z[npitch:]
    u2 = -(design.pitch[4] @ xp)[0]
    u1, u3 = -(design.roll_yaw[4] @ xr)
    return (xr[0], xp[0], xr[4]), (xr[2], xp[2], xr[6]), (u1, u2, u3)


def simulate_attitude(
    station: StationDesign,
    duration: QuantityLike,
    disturbance: str = "design",
    initial_attitude: QuantityLike = "1 deg",
    n_out: int = 1001,
) -> StationRun:
    """The closed attitude/momentum loop (module docstring, step 2) over ``duration`` s."""
    if disturbance not in DISTURBANCES:
        raise ValueError(f"disturbance: must be one of {DISTURBANCES}, got {disturbance!r}")
    tf = require_positive_scalar(duration, "duration", "s")
    th0 = to_si_array(initial_attitude, "rad", "initial_attitude")
    if th0.ndim != 0 or not np.isfinite(th0):
        raise ValueError(f"initial_attitude: one finite angle, got {initial_attitude!r}")
    data = station.data
    wfun = design_disturbance if disturbance == "design" else aero_substitute
    plant = station.plant
    npitch = plant.n_pitch
    z0 = np.zeros(plant.nx)
    z0[0] = z0[npitch] = z0[npitch + 4] = float(th0)
    # the loop is linear and slow (poles <= 0.006 rad/s): rtol 1e-10 leaves the demand T
    # accurate far beyond what the gimbal integration (rtol 1e-10) resolves
    t = np.linspace(0.0, tf, n_out)
    loop = continuous.run(
        plant,
        ScheduledStateFeedback([0.0], station.gain[None], "state", "torque"),
        t,
        z0,
        rtol=1e-10,
        atol=1e-14,
        exogenous=lambda tk: {"disturbance": wfun(tk, data)},
    )

    def solution(tk: float) -> FloatArray:
        return loop.solution(tk)[..., 0, :]

    parts = [_parts(station, z) for z in loop.states[0]]
    att, h, u = (np.array([p[i] for p in parts]) for i in range(3))
    return StationRun(station, t, att, h, u, wfun(t, data), solution)


def cmg_loop(
    run: StationRun, sigma0: npt.ArrayLike, threshold: float = 1e-6, n_out: int = 1001
) -> GimbalRun:
    """Pseudo-inverse gimbal steering for the run's demand T(t) from σ0 (module docstring,
    step 3), stopped at the first singular set: a :class:`flexsat.dynamics.cmg.GimbalRun`
    (gimbal momentum in units of h_r)."""
    return integrate_gimbals(
        sigma0, lambda t: -run.demand(t), run.t[-1], threshold=threshold, n_out=n_out
    )
