"""The maneuver kind (``kind: maneuver``): build the case, the controllers and the
configuration, refuse a run beyond :mod:`flexsat.limits` (stage 2 of the validation), then
simulate each run."""

from __future__ import annotations

from collections.abc import Callable, Generator
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, TypeVar

from flexsat.cases import get_case
from flexsat.control import Controller
from flexsat.dynamics.hub_appendage import HubAppendage
from flexsat.dynamics.hybrid import HybridPlant
from flexsat.input_checks import FieldError
from flexsat.references import cite
from flexsat.scenarios.datasets import SimulatedRuns
from flexsat.scenarios.errors import Problem, ScenarioError, item_path, locate
from flexsat.scenarios.fields import given_fields
from flexsat.scenarios.kind import Run, ScenarioKind, Simulation
from flexsat.scenarios.laws import MANEUVER_LAWS, CaseContext
from flexsat.scenarios.maneuver import GainsSpec, PolesSpec, RunSpec, Scenario
from flexsat.sim import SimConfig
from flexsat.sim.engine import check_resources

if TYPE_CHECKING:
    import xarray as xr

    from flexsat.report.controller_summary import LawSummary
    from flexsat.report.interactive import Plot

T = TypeVar("T")


@dataclass(frozen=True)
class ScenarioPlan:
    """A fully validated maneuver scenario, ready to run.

    Attributes
    ----------
    scenario : Scenario
    case : object
        The built case (e.g. :class:`flexsat.cases.tamu.TamuCase`).
    model : HubAppendage
    config : SimConfig
    controllers : dict of str to Controller
        One controller per run, by label, in the scenario's order.
    configs : dict of str to SimConfig
        Each run's configuration: ``config`` with the run's hardware (none: ``config``).
    """

    scenario: Scenario
    case: Any
    model: HubAppendage
    config: SimConfig
    controllers: dict[str, Controller]
    configs: dict[str, SimConfig] = field(default_factory=dict)

    def run_config(self, label: str) -> SimConfig:
        """The configuration of run ``label``."""
        return self.configs.get(label, self.config)


def _with_hardware(
    scenario: Scenario,
    model: HubAppendage,
    config: SimConfig,
    controllers: dict[str, Controller],
) -> dict[str, SimConfig]:
    """Each run's configuration with its hardware (section built, channels checked against
    the model and the run's law).

    Raises
    ------
    ScenarioError
        Every hardware problem, at the section's field path.
    """
    import dataclasses

    from flexsat.scenarios.hardware_section import check_hardware

    problems: list[Problem] = []
    configs: dict[str, SimConfig] = {}
    for index, (label, law) in enumerate(controllers.items()):
        path, spec = scenario.run_hardware(index)
        if spec is None:
            continue
        try:
            hardware = spec.build(config.dt)
        except ValueError as exc:
            problems.append(locate(path, exc))
            continue
        if hardware is None:
            continue
        found = check_hardware(hardware, spec, model, law, path)
        if found:
            problems.extend(found)
            continue
        try:
            configs[label] = dataclasses.replace(config, hardware=hardware)
        except ValueError as exc:
            problems.append(locate(path, exc))
    if problems:  # a document-level section's problem once, not once per run
        raise ScenarioError(list(dict.fromkeys(problems)))
    return configs


def _build_case(scenario: Scenario) -> tuple[Any, HubAppendage]:
    """(case, model); a refused value is placed in ``model`` or ``case_overrides`` by the
    field its error names."""
    try:
        case = get_case(scenario.case).builder(**scenario.case_parameters)
        return case, case.model()
    except ValueError as exc:
        field = getattr(exc, "field", None)
        if field is not None and field in given_fields(scenario.model):
            raise ScenarioError([locate("model", exc)]) from None
        if field is not None and field in scenario.case_overrides:
            raise ScenarioError([locate("case_overrides", exc)]) from None
        raise ScenarioError([Problem("case_overrides", str(exc))]) from None
    except (ArithmeticError, RuntimeError) as exc:
        # the model's numerics (overflow, root finding) fail on values far outside a physical
        # range that the case's own rules do not bound
        raise ScenarioError(
            [
                Problem(
                    "case_overrides",
                    f"the {scenario.case} model cannot be built from these values "
                    f"({type(exc).__name__}: {exc}); give physically sensible values",
                )
            ]
        ) from None


def _build_controller(index: int, run: RunSpec, ctx: CaseContext) -> Controller:
    """The run's controller; a refused value is placed in the run's reference, gains or poles
    by the field its error names."""
    path = "runs" + item_path(index, run.label)
    reference = None
    if run.reference is not None:
        try:
            reference = run.reference.build(ctx.angle, ctx.reference_inertia)
        except ValueError as exc:
            raise ScenarioError([locate(path + ".reference", exc)]) from None
    try:
        return MANEUVER_LAWS[run.law].build(run, ctx, reference)
    except ValueError as exc:
        field = getattr(exc, "field", None)
        section = next(
            (
                name
                for name, spec in (("gains", GainsSpec), ("poles", PolesSpec))
                if field in spec.model_fields
            ),
            None,
        )
        raise ScenarioError([locate(f"{path}.{section}" if section else path, exc)]) from None
    except (ArithmeticError, RuntimeError) as exc:
        raise ScenarioError(
            [
                Problem(
                    path,
                    f"the {run.law} law cannot be designed from these values "
                    f"({type(exc).__name__}: {exc})",
                )
            ]
        ) from None


def _collect(problems: list[Problem], build: Callable[..., T], *args: Any) -> T | None:
    """``build(*args)``, or None with its ScenarioError problems appended to ``problems``."""
    try:
        return build(*args)
    except ScenarioError as exc:
        problems.extend(exc.problems)
        return None


def prepare_scenario(scenario: Scenario) -> ScenarioPlan:
    """Validate what needs the case (stage 2) and build the model and the controllers.

    Raises
    ------
    ScenarioError
        Listing every problem: case parameters, references, controller gains, and a run beyond
        the limits of :mod:`flexsat.limits` (substeps, integrator steps, memory).
    """
    problems: list[Problem] = []
    built = _collect(problems, _build_case, scenario)
    controllers: dict[str, Controller] = {}
    if built is not None:
        case, model = built
        ctx = CaseContext(
            scenario.maneuver.angle,
            case.reference_inertia,
            model.appendage_inertia,
            int(model.n_appendages),
            model,
            scenario.sim_config().dt,
        )
        for index, run in enumerate(scenario.runs):
            controller = _collect(problems, _build_controller, index, run, ctx)
            if controller is not None:  # else its problems are raised below
                controllers[run.label] = controller
    config = scenario.sim_config()
    configs: dict[str, SimConfig] | None = {}
    if built is not None and not problems:
        configs = _collect(problems, _with_hardware, scenario, model, config, controllers)
    if built is not None and not problems:
        _collect(problems, _check_resources, scenario, model, config, controllers)
    if problems:
        raise ScenarioError(problems)
    return ScenarioPlan(scenario, case, model, config, controllers, configs or {})


def _check_resources(
    scenario: Scenario,
    model: HubAppendage,
    config: SimConfig,
    controllers: dict[str, Controller],
) -> None:
    """Refuse runs beyond :mod:`flexsat.limits`; every run's history is kept until the report
    is written, so the memory estimate counts the cases of all runs together. The refused
    input is reported at the document's field it comes from (:attr:`Scenario.CONFIG_PATHS`)."""
    try:
        check_resources(model, config, sum(c.n_cases for c in controllers.values()))
    except ValueError as exc:
        path = Scenario.CONFIG_PATHS.get(exc.field) if isinstance(exc, FieldError) else None
        raise ScenarioError(
            [
                Problem(path, exc.rule)
                if path and isinstance(exc, FieldError)
                else Problem("simulation", str(exc))
            ]
        ) from None


@dataclass(frozen=True)
class ManeuverResult(SimulatedRuns):
    """The runs of a maneuver scenario (:class:`~flexsat.scenarios.datasets.SimulatedRuns`),
    with what the controller summary needs: each run's law (``laws``), the model and the
    control period (s)."""

    laws: dict[str, Controller] = field(default_factory=dict)
    model: HybridPlant | None = None
    control_period: float = 0.0
    hardware: dict[str, str] = field(default_factory=dict)

    def dataset(self) -> xr.Dataset:
        """As :meth:`SimulatedRuns.dataset`, with the attribute ``hardware``: each run's
        hardware, one ``label: description`` line per run
        (:func:`~flexsat.scenarios.hardware_section.describe_hardware`)."""
        ds = super().dataset()
        ds.attrs["hardware"] = "\n".join(f"{k}: {v}" for k, v in self.hardware.items())
        return ds

    def plots(self, ds: xr.Dataset) -> list[Plot]:
        from flexsat.report.maneuver import plots

        return plots(ds)

    def sections(self, ds: xr.Dataset, figures: list[str]) -> str:
        from flexsat.report.maneuver import sections
        from flexsat.scenarios.hardware_section import hardware_html

        return sections(self.metrics_records()) + "\n" + hardware_html(self.hardware)

    def controller_summaries(self) -> tuple[LawSummary, ...]:
        """Each law's summary on the model's linear part (a hybrid model's states labelled
        ``theta``, ``q[i]`` and their rates, its order x = [θ, q, θ', q']), at the control
        period."""
        if self.model is None or not self.laws:
            return ()
        from flexsat.dynamics.linear_model import plant_state_space
        from flexsat.report.controller_summary import summarise_laws

        plant = plant_state_space(self.model)
        if isinstance(self.model, HybridPlant):  # x = [θ, q, θ', q'] (flexsat.dynamics.hybrid)
            modes = range(1, plant.nstates // 2)
            states = ["theta", *(f"q[{i}]" for i in modes)]
            states += ["theta_dot", *(f"q_dot[{i}]" for i in modes)]
            plant = plant_state_space(self.model, states=states)
        return summarise_laws(plant, self.laws, self.control_period)


class ManeuverKind(ScenarioKind):
    """``kind: maneuver`` (the default): a case's hub slewed under one or more control laws
    (:class:`~flexsat.scenarios.maneuver.Scenario`), one simulation per run."""

    kind = "maneuver"
    document = Scenario

    def steps(self, scenario: Scenario) -> int:
        return len(scenario.runs)

    def plan(self, scenario: Scenario) -> Generator[Run, Any, ManeuverResult]:
        from flexsat.scenarios.hardware_section import describe_hardware

        prepared = prepare_scenario(scenario)
        results = []
        for index, (label, controller) in enumerate(prepared.controllers.items()):
            config = prepared.run_config(label)
            results.append(
                (
                    yield Run(
                        label,
                        Simulation(prepared.model, controller, config),
                        "runs" + item_path(index, label),
                    )
                )
            )
        return ManeuverResult(
            scenario,
            tuple(prepared.controllers),
            tuple(results),
            cite(get_case(scenario.case).source),
            laws=dict(prepared.controllers),
            model=prepared.model,
            control_period=1.0 / prepared.config.control_rate,
            hardware={
                label: describe_hardware(prepared.run_config(label).hardware)
                for label in prepared.controllers
            },
        )


__all__ = ["ManeuverKind", "ManeuverResult", "ScenarioPlan", "prepare_scenario"]
