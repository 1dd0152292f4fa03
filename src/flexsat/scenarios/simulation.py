"""Simulation scenarios (``kind: simulation``): any case's plant under any law, per channel.

Where a maneuver scenario (:mod:`flexsat.scenarios.maneuver`) slews a single-axis hub, a
simulation scenario runs whichever plant a case builds (:meth:`plant` of the case object: a
three-axis spacecraft, a structure with point actuators, a beam in orbit) under a law that reads
and writes named channels, with sensors, actuators and disturbances given per channel::

    kind: simulation
    name: EPS rigid-body slew under the Gibbs-parameter Lyapunov law
    case: eps
    plant: {model: rigid}
    initial: {euler123: ["0 deg", "0 deg", "0 deg"]}
    simulation: {duration: "120 s", control_rate: "10 Hz"}
    sensors: {rate: {noise: "1e-5 rad/s"}}
    actuators: {torque: {saturation: "200 N*m"}}
    runs:
      - label: Gibbs law
        law: gibbs_lyapunov
        gains: {k: "4000 N*m*s/rad", A: "800 N*m"}
        target: {euler123: ["1 rad", "1 rad", "1 rad"]}

``plant`` holds the keyword arguments of the case's plant builder, ``initial`` the named initial
values its plant understands (:meth:`~flexsat.dynamics.plant.Plant.state_from`). Channel
values take the channel's unit (a number in SI, a quantity string, or a list of them for a
vector channel). Problems are reported, before anything runs, as ``field.path: rule`` lines of
one :class:`~flexsat.scenarios.ScenarioError`.
"""

from __future__ import annotations

import functools
import inspect
import re
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from pydantic import Field, field_validator, model_validator

from flexsat import limits
from flexsat.catalog import CASES, get_case
from flexsat.scenarios.datasets import SimulatedRuns
from flexsat.scenarios.errors import Problem, ScenarioError, item_path, locate
from flexsat.scenarios.fields import (
    Document,
    _given,
    _Section,
    check_unique_labels,
    count,
    quantity,
)
from flexsat.scenarios.kind import Run, ScenarioKind, Simulation

#: a value as written in YAML: a number, a quantity string, or a (nested) list of them
Value = float | int | str | list[Any]


class SimulationSettings(_Section):
    """Run length, control rate, integrator substeps per control period and the noise seed."""

    duration: quantity("s")
    control_rate: quantity("Hz")
    substeps: count(1, limits.MAX_SUBSTEPS, optional=True) = None
    seed: count(0, limits.MAX_SEED, optional=True) = None


class ChannelSensorSpec(_Section):
    """A sensor on one output channel (values in the channel's unit)."""

    noise: Value | None = None
    bias: Value | None = None
    quantum: Value | None = None
    range: Value | None = None


class ChannelActuatorSpec(_Section):
    """An actuator on one input channel (values in the channel's unit, per second for the rate
    limit)."""

    saturation: Value | None = None
    rate_limit: Value | None = None
    scale: Value | None = None
    bias: Value | None = None


class ImpulseSpec(_Section):
    time: quantity("s")
    impulse: Value


class ChannelDisturbanceSpec(_Section):
    """A disturbance on one input channel: Gaussian (1σ, held over each control period) and
    impulses (the channel's unit × s)."""

    random: Value | None = None
    impulses: list[ImpulseSpec] = Field(default_factory=list, max_length=limits.MAX_SAMPLES)


# -- laws ----------------------------------------------------------------------------------------
@dataclass(frozen=True)
class _SimulationLaw:
    gains: tuple[str, ...]
    required: tuple[str, ...]
    targets: bool
    build: Callable[..., Any]


def target_quaternion(target: dict) -> np.ndarray | None:
    """Euler parameters of a target given as ``euler123`` (rad) or ``attitude``; None if empty."""
    from flexsat.dynamics.attitude import dcm_to_quaternion, euler123_to_dcm
    from flexsat.units import to_si_array

    if not target:
        return None
    unknown = set(target) - {"euler123", "attitude"}
    if unknown:
        raise ValueError(
            f"target.{sorted(unknown)[0]}: not a target (give euler123 (rad) or "
            "attitude (a unit quaternion, scalar first))"
        )
    if len(target) > 1:
        raise ValueError("target: give euler123 or attitude, not both")
    if "euler123" in target:
        angles = to_si_array(target["euler123"], "rad", "target.euler123")
        if angles.shape != (3,):
            raise ValueError(f"target.euler123: three angles, got shape {angles.shape}")
        return dcm_to_quaternion(euler123_to_dcm(angles))
    return to_si_array(target["attitude"], "", "target.attitude")


def _attitude_law(name: str):
    """Builder of the attitude law ``flexsat.control.<name>`` from its gains (named as the
    class's fields) and target; the class is imported when a run is built."""

    def build(run: SimulationRunSpec, plant, dt: float):
        import flexsat.control

        beta = target_quaternion(run.target)
        extra = {} if beta is None else {"beta_target": beta}
        return getattr(flexsat.control, name)(**run.gains, **extra)

    return build


def _lqr(run: SimulationRunSpec, plant, dt: float):
    """Constant LQR state feedback on the plant's linear part, reading its ``state`` output."""
    from flexsat.control import ScheduledStateFeedback, lqr

    A, B = plant.linear_part()
    n, m = B.shape
    Q = _weights(run.gains["state_weights"], n, "gains.state_weights")
    R = _weights(run.gains.get("input_weights", 1.0), m, "gains.input_weights")
    K, _, _ = lqr(A, B, Q, R)
    return ScheduledStateFeedback([0.0], K[None], "state", [c.name for c in plant.inputs])


def _weights(value, size: int, field: str) -> np.ndarray:
    w = np.atleast_1d(np.asarray(value, float))
    if w.size == 1:
        w = np.full(size, float(w[0]))
    if w.shape != (size,) or not np.all(np.isfinite(w)) or np.any(w < 0):
        raise ValueError(f"{field}: one weight >= 0 or {size} of them, got {np.shape(value)}")
    return np.diag(w)


def _open_loop(run: SimulationRunSpec, plant, dt: float):
    import control
    from flexsat.control import StateSpaceCompensator

    m = plant.n_inputs
    p = plant.outputs[0]
    system = control.ss([], [], [], np.zeros((m, p.size)))
    return StateSpaceCompensator(system, [p.name], [c.name for c in plant.inputs], dt=dt)


#: the laws a simulation run names, with their gains (the builders import the control package
#: when a run is built, so reading a scenario does not)
SIMULATION_LAWS: dict[str, _SimulationLaw] = {
    "gibbs_lyapunov": _SimulationLaw(
        ("k", "A"), ("k", "A"), True, _attitude_law("GibbsLyapunovLaw")
    ),
    "mrp_pd": _SimulationLaw(("K", "P"), ("K", "P"), True, _attitude_law("MRPLaw")),
    "quaternion_pd": _SimulationLaw(
        ("Kp", "Kd"), ("Kp", "Kd"), True, _attitude_law("QuaternionPD")
    ),
    "lqr": _SimulationLaw(("state_weights", "input_weights"), ("state_weights",), False, _lqr),
    "open_loop": _SimulationLaw((), (), False, _open_loop),
}


class SimulationRunSpec(_Section):
    """One closed-loop run: a law (:data:`SIMULATION_LAWS`), its gains and its target."""

    label: str
    law: Literal[tuple(sorted(SIMULATION_LAWS))]
    gains: dict[str, Value] = Field(default_factory=dict)
    target: dict[str, Value] = Field(default_factory=dict)

    @model_validator(mode="after")
    def _law_inputs(self):
        law = SIMULATION_LAWS[self.law]
        for name in self.gains:
            if name not in law.gains:
                known = ", ".join(law.gains) or "none"
                raise ValueError(
                    f"gains.{name}: not a gain of law {self.law!r} (its gains: {known})"
                )
        missing = [g for g in law.required if g not in self.gains]
        if missing:
            raise ValueError(f"gains.{missing[0]}: required by law {self.law!r}")
        if self.target and not law.targets:
            raise ValueError(f"target: law {self.law!r} takes no target")
        return self


class SimulationScenario(Document):
    """A validated simulation scenario (module docstring)."""

    kind: Literal["simulation"]
    name: str
    case: str
    plant: dict[str, Value | bool | dict[str, Any]] = Field(default_factory=dict)
    initial: dict[str, Value] = Field(default_factory=dict)
    simulation: SimulationSettings
    sensors: dict[str, ChannelSensorSpec] = Field(default_factory=dict)
    actuators: dict[str, ChannelActuatorSpec] = Field(default_factory=dict)
    disturbances: dict[str, ChannelDisturbanceSpec] = Field(default_factory=dict)
    runs: list[SimulationRunSpec] = Field(min_length=1, max_length=limits.MAX_RUNS)

    @field_validator("case")
    @classmethod
    def _known_case(cls, name: str) -> str:
        get_case(name)
        if name not in simulation_cases():
            raise ValueError(
                f"case: {name!r} builds no plant to simulate; cases with one: "
                f"{', '.join(simulation_cases())}"
            )
        return name

    @model_validator(mode="after")
    def _labels(self):
        check_unique_labels(self.runs)
        return self


@functools.cache
def simulation_cases() -> tuple[str, ...]:
    """Cases whose builder's object has a ``plant`` method (read from the builder's return
    annotation, so no case is built)."""
    import typing

    names = []
    for name, info in CASES.items():
        kind = typing.get_type_hints(info.builder).get("return")
        if callable(getattr(kind, "plant", None)):
            names.append(name)
    return tuple(names)


# -- running -------------------------------------------------------------------------------------
@dataclass(frozen=True)
class SimulationResult(SimulatedRuns):
    """The runs of a simulation scenario: one :class:`flexsat.sim.SimResult` per run, in one
    dataset with dims (run, time[, component]) (:class:`~flexsat.scenarios.datasets.
    SimulatedRuns`)."""

    def figures(self, folder, ds) -> list[str]:
        from flexsat.report.simulation import draw_figures

        return draw_figures(ds, folder)

    def sections(self, ds, figures: list[str]) -> str:
        from flexsat.report.simulation import sections

        return sections(self.metrics_records(), ds)


def _located(path: str, exc: Exception) -> ScenarioError:
    return ScenarioError([locate(path, exc)])


def _build_plant(scenario: SimulationScenario):
    case = get_case(scenario.case).builder()
    builder = case.plant
    accepted = inspect.signature(builder).parameters
    for name in scenario.plant:
        if name not in accepted:
            raise ScenarioError(
                [
                    Problem(
                        f"plant.{name}",
                        f"not an option of the {scenario.case} plant "
                        f"(its options: {', '.join(accepted) or 'none'})",
                    )
                ]
            )
    try:
        return builder(**scenario.plant)
    except (ValueError, TypeError) as exc:
        raise _located("plant", exc) from None


def _config(scenario: SimulationScenario, plant):
    from flexsat.sim import SimConfig
    from flexsat.sim.channels import (
        ChannelActuator,
        ChannelDisturbance,
        ChannelSensor,
        resolve_channels,
    )

    def pieces(section: dict, kind, role: str, channels) -> dict:
        names = {c.name for c in channels}
        out = {}
        for name, spec in section.items():
            if name not in names:
                raise ScenarioError(
                    [
                        Problem(
                            f"{role}.{name}",
                            f"the {scenario.case} plant has no "
                            f"{'output' if role == 'sensors' else 'input'} channel "
                            f"{name!r} (its channels: "
                            f"{', '.join(c.name for c in channels)})",
                        )
                    ]
                )
            values = _given(spec)
            if "impulses" in values:
                impulses = values.pop("impulses")
                values["impulse_times"] = tuple(i["time"] for i in impulses)
                values["impulses"] = tuple(i["impulse"] for i in impulses)
            try:
                out[name] = kind(**values)
            except ValueError as exc:
                raise _located(f"{role}.{name}", exc) from None
        return out

    settings = _given(scenario.simulation)
    try:
        config = SimConfig(
            **settings,
            channel_sensors=pieces(scenario.sensors, ChannelSensor, "sensors", plant.outputs),
            channel_actuators=pieces(
                scenario.actuators, ChannelActuator, "actuators", plant.inputs
            ),
            channel_disturbances=pieces(
                scenario.disturbances, ChannelDisturbance, "disturbances", plant.inputs
            ),
        )
    except ValueError as exc:
        raise ScenarioError([Problem("simulation", f"{exc}")]) from None
    try:  # binding each piece to its channel converts its values to the channel's unit
        resolve_channels(plant, config)
    except ValueError as exc:
        raise ScenarioError(
            [re.sub(r"^(sensors|actuators|disturbances)\[(\w+)\]", r"\1.\2", str(exc))]
        ) from None
    return config


class SimulationKind(ScenarioKind):
    """``kind: simulation``: any case's plant under any law (module docstring), one simulation
    per run from the plant's initial state."""

    kind = "simulation"
    document = SimulationScenario

    def steps(self, scenario: SimulationScenario) -> int:
        return len(scenario.runs)

    def plan(self, scenario: SimulationScenario):
        """Build the plant, the configuration and every run's law, then simulate each run.

        Raises
        ------
        ScenarioError
            Before any run, for a plant option, initial value, channel or gain the case refuses.
        """
        from flexsat.references import cite

        plant = _build_plant(scenario)
        try:
            x0 = plant.state_from(**scenario.initial)
        except ValueError as exc:
            raise _located("initial", exc) from None
        config = _config(scenario, plant)
        laws, problems = {}, []
        for index, run in enumerate(scenario.runs):
            try:
                laws[run.label] = SIMULATION_LAWS[run.law].build(run, plant, config.dt)
            except ValueError as exc:
                problems.append(locate("runs" + item_path(index, run.label), exc))
        if problems:
            raise ScenarioError(problems)
        results = []
        for index, (label, law) in enumerate(laws.items()):
            options = {"n_cases": 1, "initial_state": x0}
            results.append(
                (
                    yield Run(
                        label,
                        Simulation(plant, law, config, options),
                        "runs" + item_path(index, label),
                    )
                )
            )
        return SimulationResult(
            scenario, tuple(laws), tuple(results), cite(get_case(scenario.case).source)
        )


__all__ = [
    "SIMULATION_LAWS",
    "SimulationResult",
    "SimulationKind",
    "SimulationScenario",
    "simulation_cases",
]
