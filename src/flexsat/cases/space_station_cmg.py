r"""Space-station attitude control and CMG momentum management (Vadali, Oh & Walker, space-station
example, Junkins, Pollock & Rahman 1990, Att. 13).

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
   by :func:`flexsat.sim.simulate` in the continuous-law mode (w the configuration's exogenous
   input; the triple of :func:`attitude_simulation`), from 1° on each axis (the paper's initial
   errors), w the design disturbance (Eq. 11) or the AERO1 substitute.
3. **CMG loop** (the paper runs it separately: the attitude bandwidth is ~0.01 rad/s): the
   pseudo-inverse steering :math:`C\dot\sigma = T`,
   :math:`T = [u_1 + n h_3,\ u_2,\ u_3 - n h_1]/h_r` (Att. 13 "Space Station Example"), from
   a chosen σ(0), stopped at the first singular set: one plant, the station with its gimbals
   (:class:`~flexsat.dynamics.station_gimbals.StationWithGimbals`), under one law, the attitude
   feedback with the steering of the momentum it demands
   (:class:`~flexsat.control.cmg_steering.StationMomentumSteering`), run by
   :func:`flexsat.sim.simulate` with the engine's stop condition on det(CCᵀ) (the triple of
   :func:`cmg_simulation`). The attitude loop is the same ODE rerun beside the gimbals.

Default maxima: attitude 1° (the initial error), rate 0.02 deg/s (the station's rate
requirement, §8.1), momentum 2000 ft-lb-s and its integral 2000 ft-lb-s × 100 s, filter states
θ_max/(kn)² and θ_max/(kn) (the filter's response α = θ/(kn)² to a constant θ). They keep the
momentum inside the four-CMG envelope (3.15 h_r = 11,040 ft-lb-s) for the design disturbance;
the singularity time from σ(0) = 0 depends on them (docs/cmg.md gives a scan).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, TypeAlias

import numpy as np

from flexsat.cases.cmg_pyramid import gimbal_set
from flexsat.control.cmg_steering import StationMomentumSteering
from flexsat.control.lqr import lqr
from flexsat.control.scheduled import ScheduledStateFeedback
from flexsat.dynamics import cmg
from flexsat.dynamics.cmg import GimbalRun
from flexsat.dynamics.space_station import (
    SpaceStation,
    StationData,
    aero_substitute,
    design_disturbance,
)
from flexsat.dynamics.station_gimbals import StationWithGimbals
from flexsat.input_checks import FieldError, require_positive_scalar
from flexsat.sim import simulate
from flexsat.sim.config import SimConfig, StopCondition
from flexsat.units import to_si_array

if TYPE_CHECKING:
    import numpy.typing as npt
    import xarray as xr

    from flexsat.units import FloatArray, QuantityLike

    #: one axis group's design: (A, B, E, state names, K, closed-loop poles)
    AxisDesign: TypeAlias = tuple[
        FloatArray, FloatArray, FloatArray, list[str], FloatArray, npt.NDArray[np.complex128]
    ]

__all__ = [
    "BrysonMaxima",
    "StationDesign",
    "StationRun",
    "attitude_simulation",
    "cmg_loop",
    "cmg_simulation",
    "design",
    "gimbal_history",
    "simulate_attitude",
    "station_run",
    "DISTURBANCES",
    "PAPER_STATION",
]

#: Table 2 of the paper, as published
PAPER_STATION = StationData(
    ("5.28e6 slug*ft**2", "10.80e6 slug*ft**2", "58.57e6 slug*ft**2"), 0.0011, "3500 lbf*ft*s"
)
#: disturbance models: the design model Eq. (11), or it plus the stated AERO1 substitute
DISTURBANCES = ("design", "aero_substitute")


@dataclass(frozen=True)
class BrysonMaxima:
    """Anticipated maxima of the LQR states (module docstring), SI after construction."""

    # the fields hold SI floats; the defaults are quantities that __post_init__ converts
    attitude: float = "1 deg"  # type: ignore[assignment]
    rate: float = "0.02 deg/s"  # type: ignore[assignment]
    momentum: float = "2000 lbf*ft*s"  # type: ignore[assignment]
    momentum_integral: float = "2e5 lbf*ft*s**2"  # type: ignore[assignment]

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

    def scales(self, names: Sequence[str], n: float) -> FloatArray:
        """D = the maxima of the states ``names`` of :mod:`flexsat.dynamics.space_station`."""
        out = []
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
    A: FloatArray,
    B: FloatArray,
    names: Sequence[str],
    maxima: BrysonMaxima,
    n: float,
    axis: str,
) -> tuple[FloatArray, npt.NDArray[np.complex128]]:
    """The LQR gain K of x' = A x + B u with Bryson weights (the states scaled by their
    ``maxima``, unit weights), and the closed-loop poles; a refusal names ``axis``."""
    D = maxima.scales(names, n)
    try:
        K_s = lqr(A / D[:, None] * D[None, :], B / D[:, None], np.eye(len(D)), np.eye(B.shape[1]))[
            0
        ]
    except ValueError as err:
        raise FieldError(axis, f"{err}") from None
    K = K_s / D[None, :]
    return K, np.linalg.eigvals(A - B @ K).astype(complex)


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
    out = []
    for axis, model in (("pitch_filters", plant.pitch), ("roll_yaw_filters", plant.roll_yaw)):
        A, B, E, names = model
        K, poles = _lqr_bryson(A, B, names, maxima, n, axis)
        out.append((A, B, E, names, K, poles))
    return StationDesign(data, maxima, out[0], out[1], plant)


@dataclass(frozen=True)
class StationRun:
    """Attitude-loop history: times ``t`` (n_t,); ``attitude`` (roll, pitch, yaw) rad,
    ``momentum`` h (n_t, 3) N m s, ``torque`` u (n_t, 3) N m, ``disturbance`` w (n_t, 3) N m;
    and what made it (``disturbance_model``, ``initial_attitude`` rad), which the CMG loops
    rerun with the gimbals (:func:`cmg_simulation`)."""

    design: StationDesign
    t: FloatArray
    attitude: FloatArray
    momentum: FloatArray
    torque: FloatArray
    disturbance: FloatArray
    disturbance_model: str
    initial_attitude: float


def _loop_settings(
    station: StationDesign,
    duration: QuantityLike,
    disturbance: str,
    initial_attitude: QuantityLike,
    n_out: int,
) -> tuple[float, FloatArray, Callable[[float], dict[str, FloatArray]], int]:
    """Duration (s), the initial station state (1 angle on each axis), the disturbance as an
    exogenous input and the sample count, checked."""
    if disturbance not in DISTURBANCES:
        raise FieldError("disturbance", f"must be one of {DISTURBANCES}, got {disturbance!r}")
    tf = require_positive_scalar(duration, "duration", "s")
    th0 = to_si_array(initial_attitude, "rad", "initial_attitude")
    if th0.ndim != 0 or not np.isfinite(th0):
        raise FieldError("initial_attitude", f"one finite angle, got {initial_attitude!r}")
    if isinstance(n_out, bool) or not isinstance(n_out, (int, np.integer)) or n_out < 2:
        raise FieldError("n_out", f"must be an integer >= 2, got {n_out!r}")
    data = station.data
    wfun = design_disturbance if disturbance == "design" else aero_substitute
    plant = station.plant
    npitch = plant.n_pitch
    z0 = np.zeros(plant.nx)
    z0[0] = z0[npitch] = z0[npitch + 4] = float(th0)

    def exogenous(t: float) -> dict[str, FloatArray]:
        return {"disturbance": wfun(t, data)}

    return tf, z0, exogenous, int(n_out)


def attitude_simulation(
    station: StationDesign,
    duration: QuantityLike,
    disturbance: str = "design",
    initial_attitude: QuantityLike = "1 deg",
    n_out: int = 1001,
) -> tuple[SpaceStation, ScheduledStateFeedback, SimConfig, dict[str, Any]]:
    """What :func:`simulate_attitude` simulates (module docstring, step 2): the station, the
    constant state feedback u = −Kx, the continuous-law configuration with the disturbance as
    its exogenous input (recorded at ``n_out`` times over ``duration``) and the options of
    :func:`flexsat.sim.simulate`."""
    tf, z0, exogenous, n = _loop_settings(station, duration, disturbance, initial_attitude, n_out)
    law = ScheduledStateFeedback([0.0], station.gain[None], "state", "torque")
    # the loop is linear and slow (poles <= 0.006 rad/s): rtol 1e-10 leaves its states
    # accurate far beyond what the gimbal integration (rtol 1e-10) resolves
    config = SimConfig(
        duration=tf,
        control_rate=(n - 1) / tf,
        substeps=1,
        law_mode="continuous",
        rtol=1e-10,
        atol=1e-14,
        exogenous=exogenous,
    )
    return station.plant, law, config, {"initial_state": z0}


def station_run(
    station: StationDesign, dataset: xr.Dataset, disturbance: str, initial_attitude: float
) -> StationRun:
    """The recorded run of :func:`attitude_simulation` (``dataset`` of its
    :class:`~flexsat.sim.recording.SimResult`) as a :class:`StationRun`."""
    return StationRun(
        station,
        dataset["time"].values,
        dataset["attitude"].values[0],
        dataset["momentum"].values[0],
        dataset["torque"].values[0],
        dataset["disturbance_disturbance"].values[0],
        disturbance,
        float(initial_attitude),
    )


def simulate_attitude(
    station: StationDesign,
    duration: QuantityLike,
    disturbance: str = "design",
    initial_attitude: QuantityLike = "1 deg",
    n_out: int = 1001,
) -> StationRun:
    """The closed attitude/momentum loop (module docstring, step 2) over ``duration`` s:
    :func:`flexsat.sim.simulate` on :func:`attitude_simulation`."""
    plant, law, config, options = attitude_simulation(
        station, duration, disturbance, initial_attitude, n_out
    )
    th0 = float(options["initial_state"][0])
    result = simulate(plant, law, config, **options)
    return station_run(station, result.dataset, disturbance, th0)


def cmg_simulation(
    station: StationDesign,
    duration: QuantityLike,
    disturbance: str,
    initial_attitude: QuantityLike,
    sigma0: npt.ArrayLike,
    threshold: float = 1e-6,
    n_out: int = 1001,
) -> tuple[StationWithGimbals, StationMomentumSteering, SimConfig, dict[str, Any]]:
    """What :func:`cmg_loop` simulates (module docstring, step 3): the station with its
    gimbals, the attitude law with the pseudo-inverse steering of the momentum it demands, the
    continuous-law configuration stopped at the first singular set (det(CCᵀ) <= ``threshold``)
    and the options of :func:`flexsat.sim.simulate`.

    Raises
    ------
    ValueError
        Naming the field: a bad duration, disturbance, angle, sample count, threshold, or a
        gimbal set ``sigma0`` that starts singular.
    """
    tf, z0, exogenous, n = _loop_settings(station, duration, disturbance, initial_attitude, n_out)
    plant = StationWithGimbals(station.plant)
    sig0 = gimbal_set(sigma0, plant.n_units, "sigma0")
    thr = float(require_positive_scalar(threshold, "threshold"))
    if cmg.gain(sig0, plant.skew, plant.n_units) <= thr:
        raise FieldError(
            "sigma0",
            "starts singular (det CCᵀ <= threshold); the pseudo-inverse cannot steer from it",
        )
    names = station.plant.names
    law = StationMomentumSteering(
        station.gain,
        (names.index("h1"), names.index("h2"), names.index("h3")),
        station.data.orbit_rate,
        station.data.rotor_momentum,
        plant.skew,
        plant.n_units,
    )
    ns, d, nu = plant.n_station, plant.skew, plant.n_units

    def gain_margin(_t: FloatArray, x: FloatArray) -> FloatArray:
        # x (k, n_cases, n_x): the lowest gain of the batch
        return np.asarray(cmg.gain(x[..., ns:], d, nu), float).min(axis=-1) - thr

    config = SimConfig(
        duration=tf,
        control_rate=(n - 1) / tf,
        substeps=1,
        law_mode="continuous",
        rtol=1e-10,
        atol=1e-14,
        stop=StopCondition(gain_margin, f"singular set (det CCᵀ <= {thr:g})", touches=True),
        exogenous=exogenous,
    )
    return plant, law, config, {"initial_state": np.concatenate([z0, sig0])}


def gimbal_history(plant: StationWithGimbals, dataset: xr.Dataset) -> GimbalRun:
    """The gimbals of a recorded run of :func:`cmg_simulation` as a
    :class:`~flexsat.dynamics.cmg.GimbalRun` (momentum in rotor momenta; ``singular`` when
    it stopped at a singular set)."""
    sig = dataset["gimbal_angles"].values[0]
    d, n = plant.skew, plant.n_units
    singular = bool(dataset.attrs["stopped"])
    t = dataset["time"].values
    return GimbalRun(t, sig, cmg.momentum(sig, d, n), cmg.gain(sig, d, n), singular)


def cmg_loop(
    run: StationRun, sigma0: npt.ArrayLike, threshold: float = 1e-6, n_out: int = 1001
) -> GimbalRun:
    """Pseudo-inverse gimbal steering of the momentum the attitude loop of ``run`` demands, from
    σ0 (module docstring, step 3), stopped at the first singular set:
    :func:`flexsat.sim.simulate` on :func:`cmg_simulation` (the attitude loop rerun with the
    gimbals)."""
    plant, law, config, options = cmg_simulation(
        run.design,
        float(run.t[-1]),
        run.disturbance_model,
        run.initial_attitude,
        sigma0,
        threshold,
        n_out,
    )
    return gimbal_history(plant, simulate(plant, law, config, **options).dataset)
