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

Instead of ``case:``, a ``model:`` section brings one's own structure (a modal model file, an
inline finite-element description, a hub with appendages: :mod:`flexsat.scenarios.models`);
exactly one of the two is given, and ``plant:`` then holds the options of the model's plant
(:class:`~flexsat.scenarios.models.ModelPlantOptions`).

``plant`` holds the keyword arguments of the case's plant builder, or ``name:`` a registered
plant and its parameters (:mod:`flexsat.scenarios.simulation_plants`: a ``flexsat.plants`` plug-
in); a run's ``law`` is a registered law (:mod:`flexsat.scenarios.simulation_laws`: a built-in
or a ``flexsat.laws`` plug-in), ``gains`` and ``target`` its sections, validated by the law's
own schema. ``initial`` holds the named initial values the plant understands
(:meth:`~flexsat.dynamics.plant.Plant.state_from`). Channel values take the channel's unit (a
number in SI, a quantity string, or a list of them for a vector channel). Problems are reported,
before anything runs, as ``field.path: rule`` lines of one
:class:`~flexsat.scenarios.ScenarioError`.

A ``hardware:`` section (at the top level for every run, or in a run for that run alone) puts
amplifiers, reaction wheels, anti-alias filters and a computation delay in the loop, and
``disturbances.<channel>.cable`` a cable spring driven by an angle output
(:mod:`flexsat.scenarios.hardware_section`); a plant with its own integrator (a rigid
spacecraft's RKMK4) takes no hardware states and is refused at ``hardware``.
"""

from __future__ import annotations

import re
from collections.abc import Generator, Iterable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Annotated, Any, Literal, Self

from pydantic import (
    BaseModel,
    Field,
    ValidationInfo,
    field_serializer,
    field_validator,
    model_validator,
)

from flexsat import limits
from flexsat.catalog import get_case
from flexsat.input_checks import FieldError
from flexsat.scenarios.datasets import SimulatedRuns
from flexsat.scenarios.errors import Problem, ScenarioError, item_path, locate
from flexsat.scenarios.fields import (
    Document,
    SchemaSection,
    check_unique_labels,
    given_fields,
    in_unit,
    integer_in,
)
from flexsat.scenarios.hardware_section import (
    ChannelCableSpec,
    HardwareSpec,
    describe_hardware,
    hardware_html,
)
from flexsat.scenarios.kind import Run, ScenarioKind, Simulation
from flexsat.scenarios.models import ModelPlantOptions, ModelSection, model_label, model_plant
from flexsat.scenarios.registry import validate_section
from flexsat.scenarios.simulation_laws import (
    LawContext,
    Value,
    simulation_laws,
    target_quaternion,
)
from flexsat.scenarios.simulation_plants import PlantContext, simulation_cases, simulation_plants

if TYPE_CHECKING:
    import xarray as xr

    from flexsat.control import Controller
    from flexsat.dynamics.plant import Channel, Plant
    from flexsat.report.controller_summary import LawSummary
    from flexsat.report.interactive import Plot
    from flexsat.scenarios.slew import SlewScenario
    from flexsat.sim import SimConfig


class SimulationSettings(SchemaSection):
    """Run length, control rate, integrator substeps per control period and the noise seed."""

    duration: Annotated[float, in_unit("s")]
    control_rate: Annotated[float, in_unit("Hz")]
    substeps: Annotated[int | None, integer_in(1, limits.MAX_SUBSTEPS, optional=True)] = None
    seed: Annotated[int | None, integer_in(0, limits.MAX_SEED, optional=True)] = None


class ChannelSensorSpec(SchemaSection):
    """A sensor on one output channel (values in the channel's unit)."""

    noise: Value | None = None
    bias: Value | None = None
    quantum: Value | None = None
    range: Value | None = None


class ChannelActuatorSpec(SchemaSection):
    """An actuator on one input channel (values in the channel's unit, per second for the rate
    limit)."""

    saturation: Value | None = None
    rate_limit: Value | None = None
    scale: Value | None = None
    bias: Value | None = None


class ImpulseSpec(SchemaSection):
    time: Annotated[float, in_unit("s")]
    impulse: Value


class ChannelDisturbanceSpec(SchemaSection):
    """A disturbance on one input channel: Gaussian (1σ, held over each control period),
    impulses (the channel's unit × s) and a cable spring driven by an angle output
    (:class:`~flexsat.scenarios.hardware_section.ChannelCableSpec`, N m)."""

    random: Value | None = None
    impulses: list[ImpulseSpec] = Field(default_factory=list, max_length=limits.MAX_SAMPLES)
    cable: ChannelCableSpec | None = None


class SimulationRunSpec(SchemaSection):
    """One closed-loop run: a law (:func:`~flexsat.scenarios.simulation_laws.simulation_laws`),
    its gains and its target, held as instances of the law's ``Parameters`` and ``Target``
    once validated."""

    label: str
    law: str
    gains: Any = Field(default_factory=dict, validate_default=True)
    target: Any = Field(default_factory=dict, validate_default=True)
    hardware: HardwareSpec | None = None

    @field_validator("law")
    @classmethod
    def _known_law(cls, name: str) -> str:
        laws = simulation_laws()
        if name not in laws:
            raise FieldError("law", f"unknown law {name!r}; known: {', '.join(sorted(laws))}")
        return name

    @field_validator("gains")
    @classmethod
    def _law_gains(cls, gains: Any, info: ValidationInfo) -> Any:
        if "law" not in info.data:  # an unknown law is reported on its own
            return gains
        name = info.data["law"]
        law = simulation_laws()[name]
        return validate_section(law.Parameters, gains, f"law {name!r}", "gain", "gains")

    @field_validator("target")
    @classmethod
    def _law_target(cls, target: Any, info: ValidationInfo) -> Any:
        if "law" not in info.data:
            return target
        name = info.data["law"]
        model = getattr(simulation_laws()[name], "Target", None)
        if not target:
            return None
        if model is None:
            raise FieldError("target", f"law {name!r} takes no target")
        return validate_section(model, target, f"law {name!r}", "target", "target")


class SimulationScenario(Document):
    """A validated simulation scenario (module docstring)."""

    kind: Literal["simulation"]
    name: str
    case: str | None = None
    model: ModelSection | None = None
    plant: Any = Field(default_factory=dict, validate_default=True)
    initial: dict[str, Value] = Field(default_factory=dict)
    simulation: SimulationSettings
    sensors: dict[str, ChannelSensorSpec] = Field(default_factory=dict)
    actuators: dict[str, ChannelActuatorSpec] = Field(default_factory=dict)
    disturbances: dict[str, ChannelDisturbanceSpec] = Field(default_factory=dict)
    hardware: HardwareSpec | None = None
    runs: list[SimulationRunSpec] = Field(min_length=1, max_length=limits.MAX_RUNS)

    @field_validator("case")
    @classmethod
    def _known_case(cls, name: str | None) -> str | None:
        if name is not None:
            get_case(name)
        return name

    @field_validator("plant")
    @classmethod
    def _plant_parameters(cls, section: Any, info: ValidationInfo) -> Any:
        """The section as (name, the plant's validated Parameters), or the options of the
        plant of a ``model:`` (:class:`~flexsat.scenarios.models.ModelPlantOptions`); left as
        written when the case is unknown or builds no plant and no name is given (reported on
        the case), or when the model section is invalid (reported on it)."""
        if info.data.get("case") is None and "model" in info.data:
            if info.data["model"] is None:  # no case and no model: reported on the document
                return section
            return validate_section(
                ModelPlantOptions, section, "a model's plant", "option", "plant"
            )
        if info.data.get("case") is None:  # an invalid model section: reported there
            return section
        return named_plant(section, info.data.get("case")) or section

    @field_serializer("plant")
    def _plant_as_written(
        self, plant: dict[str, Any] | tuple[str, BaseModel] | ModelPlantOptions
    ) -> dict[str, Any]:
        """The section as a scenario gives it back: ``name`` and the parameters (SI)."""
        if isinstance(plant, dict):
            return plant
        if isinstance(plant, ModelPlantOptions):
            return plant.model_dump(exclude_defaults=True)
        name, parameters = plant
        return {"name": name, **parameters.model_dump(exclude_none=True)}

    @model_validator(mode="after")
    def _plant_and_labels(self) -> Self:
        if (self.case is None) == (self.model is None):
            raise FieldError(
                "model" if self.model is not None else "case",
                "give exactly one of case (a published system) and model (your own "
                "structure: a file, an inline finite-element model or a hub with appendages)",
            )
        if isinstance(self.plant, dict) and self.model is not None:
            return self  # the plant options of an invalid model section: reported there
        if isinstance(self.plant, dict):
            named = sorted(set(simulation_plants()) - set(simulation_cases()))
            raise FieldError(
                "case",
                f"{self.case!r} builds no plant to simulate; cases with one: "
                f"{', '.join(simulation_cases())}"
                + (f"; or name a plant (plant.name: one of {', '.join(named)})" if named else ""),
            )
        check_unique_labels(self.runs)
        return self


def named_plant(section: Any, case: str | None) -> tuple[str, BaseModel] | None:
    """A ``plant:`` section resolved in the registry (:func:`simulation_plants`): the plant's
    name (``name:``, else the case's) and its validated ``Parameters``; None when no name is
    given and ``case`` builds no plant.

    Raises
    ------
    ValueError
        ``field: rule`` for a section that is not a mapping, an unknown plant name, or a
        parameter the plant refuses (pydantic's ValidationError, located at its field).
    """
    if not isinstance(section, dict):
        raise FieldError("plant", f"a mapping of plant options, got {section!r}")
    options = dict(section)
    name = options.pop("name", None)
    plants = simulation_plants()
    if name is None:
        if case not in plants:
            return None
        name = case
    elif name not in plants:
        raise FieldError("name", f"unknown plant {name!r}; known: {', '.join(sorted(plants))}")
    parameters = validate_section(
        plants[name].Parameters, options, f"plant {name!r}", "option", "plant"
    )
    return name, parameters


# -- running -------------------------------------------------------------------------------------
@dataclass(frozen=True)
class SimulationResult(SimulatedRuns):
    """The runs of a simulation scenario: one :class:`flexsat.sim.SimResult` per run, in one
    dataset with dims (run, time[, component]) (:class:`~flexsat.scenarios.datasets.
    SimulatedRuns`), with what the controller summary needs: each run's law (``laws``), the
    plant and the control period (s)."""

    laws: dict[str, Controller] = field(default_factory=dict)
    plant: Plant | None = None
    control_period: float = 0.0
    hardware: dict[str, str] = field(default_factory=dict)

    def controller_summaries(self) -> tuple[LawSummary, ...]:
        """Each law's summary on the plant's linear part; a plant without one (nonlinear,
        dispersed) gives each law a line saying why."""
        if self.plant is None or not self.laws:
            return ()
        from flexsat.dynamics.linear_model import plant_state_space
        from flexsat.report.controller_summary import LawSummary, summarise_laws

        try:
            linear = plant_state_space(self.plant)
        except ValueError as exc:
            why = f"the plant has no linear part ({exc})"
            return tuple(LawSummary(r, type(law).__name__, why) for r, law in self.laws.items())
        return summarise_laws(linear, self.laws, self.control_period)

    def report_case(self) -> str:
        """The case the page names, or the scenario's own model."""
        return scenario_subject(self.scenario)

    def dataset(self) -> xr.Dataset:
        """As :meth:`SimulatedRuns.dataset`, the attribute ``case`` naming the scenario's own
        model when it has one."""
        ds = super().dataset()
        ds.attrs["case"] = scenario_subject(self.scenario)
        ds.attrs["hardware"] = "\n".join(f"{k}: {v}" for k, v in self.hardware.items())
        return ds

    def plots(self, ds: xr.Dataset) -> list[Plot]:
        from flexsat.report.simulation import plots

        return plots(ds)

    def sections(self, ds: xr.Dataset, figures: list[str]) -> str:
        from flexsat.report.simulation import sections

        return sections(self.metrics_records(), ds) + "\n" + hardware_html(self.hardware)


def scenario_subject(scenario: SimulationScenario) -> str:
    """What a simulation scenario simulates: its case, or its own model."""
    if scenario.model is not None:
        return model_label(scenario.model)
    return str(scenario.case)


def _located(path: str, exc: Exception) -> ScenarioError:
    return ScenarioError([locate(path, exc)])


def build_plant(scenario: SimulationScenario | SlewScenario) -> Plant:
    """The plant a simulation scenario (or a slew scenario, whose ``plant`` section is its
    case's plant options) names, built with its parameters.

    Raises
    ------
    ScenarioError
        For an option the plant refuses, or a builder that returns no Plant.
    """
    from flexsat.dynamics.plant import Plant

    model = getattr(scenario, "model", None)  # a slew scenario has a case only
    if model is not None:
        options = scenario.plant
        assert isinstance(options, ModelPlantOptions)  # validated with the model section
        try:
            return model_plant(model, options, scenario.folder)
        except FieldError as exc:
            raise ScenarioError([Problem(exc.field, exc.rule)]) from None
    assert scenario.case is not None  # the document holds a case or a model
    try:
        # a slew scenario's plant section is its case's plant options, resolved here
        resolved = (
            named_plant(scenario.plant, scenario.case)
            if isinstance(scenario.plant, dict)
            else scenario.plant
        )
        assert resolved is not None  # the document checked that its case builds a plant
        name, parameters = resolved
        plant = simulation_plants()[name].from_scenario(parameters, PlantContext(scenario.case))
    except (ValueError, TypeError) as exc:  # a builder's TypeError: an argument it refuses
        raise _located("plant", exc) from None
    if not isinstance(plant, Plant):
        raise ScenarioError(
            [
                Problem(
                    "plant",
                    f"{name!r} built a {type(plant).__name__}, not a flexsat.dynamics.Plant",
                )
            ]
        )
    return plant


def channel_config(scenario: Any, plant: Plant, subject: str | None = None) -> SimConfig:
    """The ``simulation`` settings of ``scenario`` with its ``sensors``, ``actuators`` and
    ``disturbances`` sections (those it has) bound to ``plant``'s channels, each value in its
    channel's unit (``subject`` names the plant in an error; default the scenario's case or
    model).

    Raises
    ------
    ScenarioError
        ``sensors.<channel>`` (no such output), ``disturbances.<channel>.random`` (a value the
        channel refuses), ``simulation``.
    """
    from flexsat.sim import SimConfig
    from flexsat.sim.channels import (
        ChannelActuator,
        ChannelDisturbance,
        ChannelSensor,
        resolve_channels,
    )

    def pieces(
        section: dict[str, Any], kind: type[Any], role: str, channels: Iterable[Channel]
    ) -> dict[str, Any]:
        names = {c.name for c in channels}
        out: dict[str, Any] = {}
        for name, spec in section.items():
            if name not in names:
                raise ScenarioError(
                    [
                        Problem(
                            f"{role}.{name}",
                            f"the {subject or scenario_subject(scenario)} plant has no "
                            f"{'output' if role == 'sensors' else 'input'} channel "
                            f"{name!r} (its channels: "
                            f"{', '.join(c.name for c in channels)})",
                        )
                    ]
                )
            values = given_fields(spec, exclude={"cable"})
            cable = getattr(spec, "cable", None)
            if cable is not None:
                values["force"] = cable.build()
                values["force_output"] = cable.output
                values["force_name"] = "cable"
            if "impulses" in values:
                impulses = values.pop("impulses")
                values["impulse_times"] = tuple(i["time"] for i in impulses)
                values["impulses"] = tuple(i["impulse"] for i in impulses)
            try:
                out[name] = kind(**values)
            except ValueError as exc:
                raise _located(f"{role}.{name}", exc) from None
        return out

    settings = given_fields(scenario.simulation)
    try:
        config = SimConfig(
            **settings,
            channel_sensors=pieces(
                getattr(scenario, "sensors", {}), ChannelSensor, "sensors", plant.outputs
            ),
            channel_actuators=pieces(
                getattr(scenario, "actuators", {}), ChannelActuator, "actuators", plant.inputs
            ),
            channel_disturbances=pieces(
                getattr(scenario, "disturbances", {}),
                ChannelDisturbance,
                "disturbances",
                plant.inputs,
            ),
        )
    except ValueError as exc:
        raise ScenarioError([Problem("simulation", f"{exc}")]) from None
    try:  # binding each piece to its channel converts its values to the channel's unit
        resolve_channels(plant, config)
    except FieldError as exc:  # sensors[gyro].noise, as the engine names it: sensors.gyro.noise
        path = re.sub(r"^(sensors|actuators|disturbances)\[(\w+)\]", r"\1.\2", exc.field)
        raise ScenarioError([Problem(path, exc.rule)]) from None
    except ValueError as exc:
        raise ScenarioError([Problem("simulation", str(exc))]) from None
    return config


def _run_hardware(
    scenario: SimulationScenario,
    index: int,
    plant: Plant,
    law: Controller,
    config: SimConfig,
    configs: dict[str, SimConfig],
) -> list[Problem]:
    """Run ``index``'s configuration with its hardware (its own section, else the
    document's) put in ``configs``; the problems, at the section's field path."""
    import dataclasses

    from flexsat.scenarios.hardware_section import check_hardware

    run = scenario.runs[index]
    spec, path = run.hardware, "runs" + item_path(index, run.label) + ".hardware"
    if spec is None:
        spec, path = scenario.hardware, "hardware"
    if spec is None:
        return []
    try:
        hardware = spec.build(config.dt)
    except ValueError as exc:
        return [locate(path, exc)]
    if hardware is None:
        return []
    problems = check_hardware(hardware, spec, plant, law, path, scenario.actuators)
    if not problems:
        try:
            configs[run.label] = dataclasses.replace(config, hardware=hardware)
        except ValueError as exc:
            problems.append(locate(path, exc))
    return problems


class SimulationKind(ScenarioKind):
    """``kind: simulation``: any case's plant under any law (module docstring), one simulation
    per run from the plant's initial state."""

    kind = "simulation"
    document = SimulationScenario

    def steps(self, scenario: SimulationScenario) -> int:
        return len(scenario.runs)

    def plan(self, scenario: SimulationScenario) -> Generator[Run, Any, SimulationResult]:
        """Build the plant, the configuration and every run's law, then simulate each run.

        Raises
        ------
        ScenarioError
            Before any run, for a plant option, initial value, channel or gain the case refuses
            (a law's :class:`~flexsat.input_checks.FieldError` naming one of the run's gains is
            placed under ``gains``).
        """
        from flexsat.control import Controller
        from flexsat.references import cite

        plant = build_plant(scenario)
        try:
            x0 = plant.state_from(**scenario.initial)
        except ValueError as exc:
            raise _located("initial", exc) from None
        config = channel_config(scenario, plant)
        laws: dict[str, Controller] = {}
        problems: list[Problem] = []
        for index, run in enumerate(scenario.runs):
            path = "runs" + item_path(index, run.label)
            context = LawContext(plant, config.dt, run.target)
            try:
                laws[run.label] = simulation_laws()[run.law].from_scenario(run.gains, context)
            except ValueError as exc:
                gain = getattr(exc, "field", None) in type(run.gains).model_fields
                problems.append(locate(path + ".gains" if gain else path, exc))
                continue
            if not isinstance(laws[run.label], Controller):
                problems.append(
                    Problem(
                        path,
                        f"law {run.law!r} built a {type(laws[run.label]).__name__}, "
                        "not a flexsat.control.Controller",
                    )
                )
        configs: dict[str, SimConfig] = {}
        for index, run in enumerate(scenario.runs):
            if run.label in laws:
                problems += _run_hardware(scenario, index, plant, laws[run.label], config, configs)
        if problems:  # a document-level section's problem once, not once per run
            raise ScenarioError(list(dict.fromkeys(problems)))
        results = []
        for index, (label, law) in enumerate(laws.items()):
            options: dict[str, Any] = {"n_cases": 1, "initial_state": x0}
            simulation = Simulation(plant, law, configs.get(label, config), options)
            results.append((yield Run(label, simulation, "runs" + item_path(index, label))))
        source = (
            "the scenario's own model, not a published system"
            if scenario.model is not None
            else cite(get_case(str(scenario.case)).source)
        )
        return SimulationResult(
            scenario,
            tuple(laws),
            tuple(results),
            source,
            laws=laws,
            plant=plant,
            control_period=config.dt,
            hardware={
                label: describe_hardware(configs[label].hardware if label in configs else None)
                for label in laws
            },
        )


__all__ = [
    "channel_config",
    "SimulationKind",
    "SimulationResult",
    "SimulationScenario",
    "named_plant",
    "simulation_cases",
    "target_quaternion",
]
