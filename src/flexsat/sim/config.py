"""Run settings of a simulation and the resource checks made before a run starts."""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from flexsat import limits
from flexsat.input_checks import FieldError, require_count, require_positive, set_si
from flexsat.sim.actuators import TorqueActuator
from flexsat.sim.channels import (
    ChannelActuator,
    ChannelDisturbance,
    ChannelSensor,
    noise_columns,
    resolve_channels,
)
from flexsat.sim.disturbances import BearingFriction, Impulses, RandomTorque
from flexsat.sim.hardware import Hardware
from flexsat.sim.recording import CHUNK
from flexsat.sim.sensors import Sensors

if TYPE_CHECKING:
    from flexsat.dynamics.plant import Plant
    from flexsat.units import FloatArray

#: how the law meets the plant: held samples of a digital law, or a continuous state feedback
LAW_MODES = ("sampled", "continuous")


@dataclass(frozen=True)
class StopCondition:
    """Where a continuous-law run ends before its duration: the first time ``margin`` reaches 0.

    Parameters
    ----------
    margin : callable
        ``margin(t, x)`` with t (k,) s and the states x (k, n_cases, n_x) -> (k,): positive
        while the run may go on (e.g. det(CCᵀ) − threshold of a CMG cluster, which the
        pseudo-inverse steering cannot pass).
    reason : str
        What reaching it means, recorded with the stop (``"singular set (det CCᵀ <= 1e-06)"``).
    terminal : bool
        End the run there (default); False runs on and only records the first time.
    touches : bool
        The margin may touch zero without changing sign (a product of squares, such as
        det(CCᵀ) where the steering passes a singular set with finite rates): between the
        integrator's steps its dense output is then scanned, 8 points a step, and every sampled
        local minimum refined, since a sign-change event alone misses a dip narrower than a
        step.
    """

    margin: Callable[[FloatArray, FloatArray], FloatArray]
    reason: str
    terminal: bool = True
    touches: bool = False

    def __post_init__(self) -> None:
        if not callable(self.margin):
            raise FieldError("stop.margin", f"must be callable margin(t, x), got {self.margin!r}")
        if not isinstance(self.reason, str) or not self.reason:
            raise FieldError("stop.reason", f"must be a nonempty string, got {self.reason!r}")


@dataclass(frozen=True)
class SimConfig:
    """Run settings shared by every case of a batch.

    Parameters
    ----------
    duration : float             run length, s
    control_rate : float         controller sample rate, Hz (TAMU: 75 Hz)
    substeps : int               integrator substeps per control period when the plant has
                                 nonlinear terms (friction, stiffening) or its own integrator;
                                 ignored for a linear run and raised where an input force needs
                                 it (:func:`stable_substeps`)
    actuator, sensors, friction, random_torque, impulses
                                 the single-axis presets (channels ``torque``, ``theta``,
                                 ``theta_dot``, ``root_torque``; :mod:`flexsat.sim.channels`)
    channel_sensors, channel_actuators, channel_disturbances : dict
                                 per-channel pieces by channel name
                                 (:class:`~flexsat.sim.channels.ChannelSensor`, ...); they
                                 override a preset on the same channel
    settling_band : float        |θ − θ_f| band for the settling time, rad
    seed : int                   base seed; case i uses seed + i unless seeds are given
    law_mode : {"sampled", "continuous"}
                                 ``sampled``: the law runs at ``control_rate`` and its commands
                                 are held (a digital controller); ``continuous``: a static law
                                 evaluated inside the integrator at every stage, the states
                                 recorded at ``control_rate`` (:mod:`flexsat.sim.continuous`)
    rtol, atol : float           local error tolerances of the continuous mode's adaptive
                                 DOP853 integrator (unused when sampled)
    stop : StopCondition, optional
                                 continuous mode: where the run ends early (or, not terminal,
                                 the first time recorded); the dataset's ``stop_time`` and
                                 ``stop_reason`` attributes say where and why
    exogenous : callable, optional
                                 continuous mode: a known input history t -> {input channel:
                                 values} added to the law's commands (a disturbance torque of
                                 time, :func:`flexsat.sim.continuous.run`)
    hardware : Hardware, optional
                                 sampled mode: reaction wheels, amplifiers, anti-alias filters
                                 and the computation delay (:mod:`flexsat.sim.hardware`)

    Notes
    -----
    ``duration``, ``control_rate`` and ``settling_band`` take a number in SI, a pint Quantity or
    a unit string (``"15 s"``, ``"75 Hz"``, ``"0.5 deg"``) and are stored in SI.
    """

    duration: float
    control_rate: float = 75.0
    substeps: int = 4
    actuator: TorqueActuator = field(default_factory=TorqueActuator)
    sensors: Sensors = field(default_factory=Sensors)
    friction: BearingFriction = field(default_factory=BearingFriction)
    random_torque: RandomTorque = field(default_factory=RandomTorque)
    impulses: Impulses = field(default_factory=Impulses)
    settling_band: float = np.radians(0.5)
    seed: int = 0
    channel_sensors: dict[str, ChannelSensor] = field(default_factory=dict)
    channel_actuators: dict[str, ChannelActuator] = field(default_factory=dict)
    channel_disturbances: dict[str, ChannelDisturbance] = field(default_factory=dict)
    law_mode: str = "sampled"
    rtol: float = 1e-10
    atol: float = 1e-12
    stop: StopCondition | None = None
    exogenous: Callable[[float], Mapping[str, Any]] | None = None
    hardware: Hardware | None = None

    def __post_init__(self) -> None:
        if self.law_mode not in LAW_MODES:
            raise FieldError("law_mode", f"must be one of {LAW_MODES}, got {self.law_mode!r}")
        for name, ok, rule in (
            ("stop", self.stop is None or isinstance(self.stop, StopCondition), "a StopCondition"),
            (
                "exogenous",
                self.exogenous is None or callable(self.exogenous),
                "a callable t -> {channel: values}",
            ),
        ):
            if not ok:
                raise FieldError(name, f"must be {rule}, got {getattr(self, name)!r}")
            if getattr(self, name) is not None and self.law_mode != "continuous":
                raise FieldError(
                    name,
                    "only in law_mode='continuous' (the sampled mode holds commands "
                    "over a period and has no event location)",
                )
        if self.hardware is not None:
            if not isinstance(self.hardware, Hardware):
                raise FieldError("hardware", f"must be a Hardware, got {self.hardware!r}")
            if self.law_mode != "sampled":
                raise FieldError("hardware", "only in law_mode='sampled' (a digital controller)")
        set_si(self, "rtol", require_positive, "")
        set_si(self, "atol", require_positive, "")
        set_si(self, "duration", require_positive, "s")
        set_si(self, "control_rate", require_positive, "Hz")
        set_si(self, "settling_band", require_positive, "rad")
        require_count(self.substeps, "substeps")
        if not limits.is_integral(self.seed) or not 0 <= self.seed <= limits.MAX_SEED:
            raise FieldError(
                "seed", f"must be an integer in [0, {limits.MAX_SEED}], got {self.seed!r}"
            )
        limits.check_count(
            self.duration * self.control_rate,
            limits.MAX_SAMPLES,
            "duration",
            "control samples (duration × control_rate)",
            "shorten the run or lower the control rate",
        )
        limits.check_count(
            self.substeps, limits.MAX_SUBSTEPS, "substeps", "integrator substeps per control period"
        )
        for name, kind in (
            ("channel_sensors", ChannelSensor),
            ("channel_actuators", ChannelActuator),
            ("channel_disturbances", ChannelDisturbance),
        ):
            pieces = getattr(self, name)
            if not isinstance(pieces, dict) or not all(
                isinstance(k, str) and isinstance(v, kind) for k, v in pieces.items()
            ):
                raise FieldError(name, f"must map channel names to {kind.__name__}, got {pieces!r}")

    @property
    def dt(self) -> float:
        return 1.0 / self.control_rate

    @property
    def n_steps(self) -> int:
        return int(round(self.duration * self.control_rate))


#: largest h λ allowed for an explicitly integrated input force (friction); ETD2RK is stable
#: for h λ <= 2
FRICTION_STEP_LIMIT = 1.5


def force_rates(
    plant: Plant, disturbances: Mapping[str, ChannelDisturbance]
) -> list[tuple[str, float]]:
    """(channel, λ) of each input force with a ``max_slope``: the damping rate
    λ = max|∂f/∂y| · |C_y B_j| of the force f(y) of output y on input j (for the bearing,
    (c1/ε + c2) (M⁻¹)_θθ: inside |θ'| < ε the regularised friction is a stiff damper)."""
    _, B = plant.linear_part()
    out: list[tuple[str, float]] = []
    for name, d in disturbances.items():
        slope = getattr(d.force, "max_slope", None)
        if d.force is None or slope is None:
            continue
        # a disturbance with a force names its driving output (ChannelDisturbance refuses one
        # without)
        assert d.force_output is not None
        mats = plant.output_matrices(d.force_output)
        if mats is None:
            continue
        C, j = mats[0], plant.input_slices[name].start
        gain = np.abs(np.einsum("...pi,...i->...p", C, B[..., :, j])).max()
        out.append((name, float(slope * gain)))
    return out


def stable_substeps(
    plant: Plant,
    friction: BearingFriction | Mapping[str, ChannelDisturbance],
    dt: float,
    requested: int,
) -> int:
    """Substeps per control period: the requested number, raised where needed so that the
    explicitly integrated input forces stay stable (h λ <= FRICTION_STEP_LIMIT, λ from
    :func:`force_rates`).

    ``friction`` is a :class:`BearingFriction` (the planar preset on ``torque``, driven by
    ``theta_dot``) or a dict of bound :class:`~flexsat.sim.channels.ChannelDisturbance` s.
    """
    if isinstance(friction, BearingFriction):
        if not friction.active:
            return requested
        friction = {"torque": ChannelDisturbance(force=friction, force_output="theta_dot")}
    substeps = requested
    for _name, rate in force_rates(plant, friction):
        needed = dt * rate / FRICTION_STEP_LIMIT
        # compared as a float first: a near-zero smoothing makes it too large for an int
        limits.check_count(
            needed,
            limits.MAX_SUBSTEPS,
            "friction",
            f"a stable integration of the friction (damping rate {rate:.3g} 1/s "
            f"below the smoothing speed) needs substeps per control period",
            "lower coulomb or viscous, raise smoothing or the control rate",
        )
        substeps = max(substeps, math.ceil(needed))
    return substeps


def run_substeps(
    plant: Plant, config: SimConfig, disturbances: Mapping[str, ChannelDisturbance]
) -> int:
    """Integrator substeps of a run: 1 for a linear plant without input forces (the exact
    step), else the requested number raised for stability (:func:`stable_substeps`)."""
    forced = any(d.force is not None for d in disturbances.values())
    if getattr(plant, "step", None) is not None:
        return config.substeps
    if not (plant.nonlinear or forced):
        return 1
    return stable_substeps(plant, disturbances, config.dt, config.substeps)


def recorded_values(plant: Plant) -> int:
    """Histories kept per case and sample with the default recording (at most): the recorded
    outputs, the references θ_ref, θ'_ref (a plant with ``theta``), command, applied input,
    disturbance and input force per input, the recorded measurements, energy and vibration
    energy."""
    width = {c.name: c.size for c in plant.outputs}
    n = sum(width[k] for k in plant.recorded) + 4 * plant.n_inputs
    n += 2 * ("theta" in width) + sum(
        width[k] for k in getattr(plant, "recorded_measurements", ()) if k in width
    )
    return n + 1 + hasattr(plant, "vibration_energy")


def check_resources(
    plant: Plant,
    config: SimConfig,
    n_cases: int = 1,
    record_states: bool = False,
    disturbances: Mapping[str, ChannelDisturbance] | None = None,
) -> int:
    """Check that a run fits the limits of :mod:`flexsat.limits` before it starts.

    Parameters
    ----------
    plant, config
        As for :func:`simulate`.
    n_cases : int
        Batch size.
    record_states : bool
        Whether the full state history is kept.
    disturbances : dict, optional
        The channel disturbances already bound (:func:`resolve_channels`); bound here if not.

    Returns
    -------
    int
        The integrator substeps per control period (:func:`run_substeps`).

    Raises
    ------
    ValueError
        ``"field: ... above the limit ..."`` for too many cases, substeps, integrator steps or
        too much memory.
    """
    limits.check_count(
        n_cases, limits.MAX_CASES, "n_cases", "cases in one batch", "split the batch"
    )
    if disturbances is None:
        _, _, disturbances = resolve_channels(plant, config)
    substeps = run_substeps(plant, config, disturbances)
    n = config.n_steps + 1
    limits.check_count(
        n * substeps,
        limits.MAX_INTEGRATOR_STEPS,
        "duration",
        f"integrator steps ({n} control samples × {substeps} substeps)",
        "shorten the run or lower the control rate or the substeps",
    )
    # the histories (kept once: the dataset holds views of the loop's arrays), the states
    # when recorded, and the loop's chunk of states and noise
    values = recorded_values(plant) + (plant.nx if record_states else 0)
    width = sum(s.stop - s.start for s in noise_columns(plant).values())
    buffer = limits.memory_estimate(min(CHUNK, n), n_cases, plant.nx + width)
    limits.check_memory(
        limits.memory_estimate(n, n_cases, values) + buffer,
        "duration",
        f"a run of {n} samples × {n_cases} cases × {values} values (and a "
        f"{min(CHUNK, n)}-sample buffer of {plant.nx + width})",
    )
    return substeps
