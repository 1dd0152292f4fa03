"""Preparing and running a maneuver scenario: build the case, the controllers and the
configuration, refuse a run beyond :mod:`flexsat.limits` (stage 2 of the validation), then
simulate each run."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import xarray as xr

from flexsat.cases import get_case
from flexsat.control import Controller
from flexsat.dynamics.hub_appendage import HubAppendage
from flexsat.references import cite
from flexsat.scenarios.errors import ScenarioError, _head, _item, _locate
from flexsat.scenarios.fields import _given
from flexsat.scenarios.laws import _LAWS, _CaseContext
from flexsat.scenarios.maneuver import GainsSpec, PolesSpec, RunSpec, Scenario
from flexsat.sim import SimConfig, SimResult, SimulationDiverged, simulate
from flexsat.sim.engine import check_resources


@dataclass(frozen=True)
class ScenarioPlan:
    """A fully validated scenario, ready to run.

    Attributes
    ----------
    scenario : Scenario
    case : object
        The built case (e.g. :class:`flexsat.cases.tamu.TamuCase`).
    model : HubAppendage
    config : SimConfig
    controllers : dict of str to Controller
        One controller per run, by label, in the scenario's order.
    """

    scenario: Scenario
    case: Any
    model: HubAppendage
    config: SimConfig
    controllers: dict[str, Controller]


def _build_case(scenario: Scenario):
    """(case, model); problems are located in ``model`` or ``case_overrides``."""
    try:
        case = get_case(scenario.case).builder(**scenario.case_parameters)
        return case, case.model()
    except ValueError as exc:
        message = str(exc)
        head = _head(message)
        if head in _given(scenario.model):
            raise ScenarioError([_locate("model", message)]) from None
        if head in scenario.case_overrides:
            raise ScenarioError([_locate("case_overrides", message)]) from None
        raise ScenarioError([f"case_overrides: {message}"]) from None
    except (ArithmeticError, RuntimeError) as exc:
        # the model's numerics (overflow, root finding) fail on values far outside a physical
        # range that the case's own rules do not bound
        raise ScenarioError(
            [
                f"case_overrides: the {scenario.case} model cannot be built from "
                f"these values ({type(exc).__name__}: {exc}); give physically "
                "sensible values"
            ]
        ) from None


def _build_controller(index: int, run: RunSpec, ctx: _CaseContext) -> Controller:
    """The run's controller; problems are located in the run's reference, gains or poles."""
    path = "runs" + _item(index, run.label)
    reference = None
    if run.reference is not None:
        try:
            reference = run.reference.build(ctx.angle, ctx.reference_inertia)
        except ValueError as exc:
            raise ScenarioError([_locate(path + ".reference", str(exc))]) from None
    try:
        return _LAWS[run.law].build(run, ctx, reference)
    except ValueError as exc:
        head = _head(str(exc))
        section = next(
            (
                name
                for name, spec in (("gains", GainsSpec), ("poles", PolesSpec))
                if head in spec.model_fields
            ),
            None,
        )
        raise ScenarioError([_locate(f"{path}.{section}" if section else path, str(exc))]) from None
    except (ArithmeticError, RuntimeError) as exc:
        raise ScenarioError(
            [
                f"{path}: the {run.law} law cannot be designed from these values "
                f"({type(exc).__name__}: {exc})"
            ]
        ) from None


def _collect(problems: list[str], build: Callable, *args):
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
    problems: list[str] = []
    built = _collect(problems, _build_case, scenario)
    controllers: dict[str, Controller] = {}
    if built is not None:
        case, model = built
        ctx = _CaseContext(
            scenario.maneuver.angle,
            case.reference_inertia,
            model.appendage_inertia,
            int(model.n_appendages),
            model,
            scenario.sim_config().dt,
        )
        for index, run in enumerate(scenario.runs):
            controllers[run.label] = _collect(problems, _build_controller, index, run, ctx)
    config = scenario.sim_config()
    if built is not None and not problems:
        _collect(problems, _check_resources, model, config, controllers)
    if problems:
        raise ScenarioError(problems)
    return ScenarioPlan(scenario, case, model, config, controllers)


#: the scenario field a resource message of :func:`flexsat.sim.config.check_resources` blames
_RESOURCE_FIELDS = {
    "friction": "disturbances.friction",
    "duration": "simulation.duration",
    "n_cases": "runs",
    "substeps": "simulation.integration_step",
}


def _check_resources(model, config: SimConfig, controllers: dict[str, Controller]) -> None:
    """Refuse runs beyond :mod:`flexsat.limits`; every run's history is kept until the report
    is written, so the memory estimate counts the cases of all runs together."""
    try:
        check_resources(model, config, sum(c.n_cases for c in controllers.values()))
    except ValueError as exc:
        message, head = str(exc), _head(str(exc))
        located = (
            _RESOURCE_FIELDS[head] + message[len(head) :]
            if head in _RESOURCE_FIELDS
            else f"simulation: {message}"
        )
        raise ScenarioError([located]) from None


@dataclass(frozen=True)
class ScenarioResult:
    """The runs of a scenario.

    Attributes
    ----------
    scenario : Scenario
    labels : tuple of str
        Run labels, in the scenario's order.
    results : tuple of SimResult
        One single-case result per run (every run uses the same noise seed).
    case_source : str
        Where the case's data come from (:attr:`flexsat.cases.CaseInfo.source`).
    """

    scenario: Scenario
    labels: tuple[str, ...]
    results: tuple[SimResult, ...]
    case_source: str

    def metrics_records(self) -> list[dict]:
        """One JSON-ready dict per run: ``"run"`` (the label) and the metrics (NaN -> None)."""
        return [
            row
            for label, result in zip(self.labels, self.results)
            for row in result.metrics_records([label])
        ]

    def dataset(self) -> xr.Dataset:
        """All runs in one dataset, dims (run, time); ``run`` holds the labels.

        Attributes: ``scenario_name``, ``case``, ``case_source``, ``scenario_yaml`` and those of
        the simulation (``control_rate_Hz``, ``settling_band_rad``).
        """
        runs = [r.dataset.isel(case=0, drop=True) for r in self.results]
        ds = xr.concat(
            runs,
            dim="run",
            data_vars="all",
            coords="minimal",
            compat="override",
            join="exact",
            combine_attrs="override",
        )
        ds = ds.assign_coords(run=("run", list(self.labels)))
        ds.attrs.update(
            scenario_name=self.scenario.name,
            case=self.scenario.case,
            case_source=self.case_source,
            scenario_yaml=self.scenario.yaml_text,
        )
        return ds


def run_scenario(
    scenario: Scenario, progress: Callable[[str], None] | None = None
) -> ScenarioResult:
    """Validate the whole scenario, then simulate each run.

    Parameters
    ----------
    scenario : Scenario
    progress : callable, optional
        Called with each run's label just before it is simulated.

    Raises
    ------
    ScenarioError
        Before any run, if :func:`prepare_scenario` finds problems.
    SimulationDiverged
        If a run diverges (the message starts with the run, ``runs['Law I']: ...``); no result
        is returned.
    """
    plan = prepare_scenario(scenario)
    results = []
    for index, (label, controller) in enumerate(plan.controllers.items()):
        if progress is not None:
            progress(label)
        try:
            results.append(simulate(plan.model, controller, plan.config))
        except SimulationDiverged as exc:
            raise SimulationDiverged(
                f"runs{_item(index, label)}: {exc}", exc.cases, exc.time, exc.cause
            ) from None
    return ScenarioResult(
        scenario, tuple(plan.controllers), tuple(results), cite(get_case(scenario.case).source)
    )


__all__ = ["ScenarioPlan", "ScenarioResult", "prepare_scenario", "run_scenario"]
