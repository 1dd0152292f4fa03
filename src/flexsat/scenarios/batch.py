"""Sweep and Monte Carlo scenarios (``kind: sweep``, ``kind: montecarlo``): many cases of one
scenario, in chunks on dask, streamed to a zarr store, with statistics.

A batch names a target scenario file and its parameters in one of two ways.

Any scenario, any run: ``parameters:`` keyed by field paths of the target document
(``plant.tip_mass``, ``runs['PD'].gains.K``, ``station.inertia[0]``; a path has a ``.`` or a
``[``), ``run:`` one of its runs or left out for all. Each case is the target document with the
values written in, validated by its kind and run by the scenario runner, on the dask workers;
every case's document is validated before any runs (:mod:`flexsat.scenarios.batch_cases`)::

    kind: montecarlo
    name: station inertia dispersed
    scenario: space_station_cmg.yaml
    run: preferred
    parameters:
      station.inertia[2]: {distribution: normal, mean: "58.57e6 slug*ft**2", sd: "1e6 slug*ft**2"}
    cases: 100

The Law II fast path: ``parameters:`` keyed by the names below, the target a maneuver scenario
and ``run:`` one of its Control Law II runs (
``lyapunov_tracker``: the slews of Junkins, Pollock & Rahman 1990 Att. 3 that the
TAMU trade studies and robustness
sets are about), the parameters to vary and how::

    kind: montecarlo
    name: TAMU Law II, dispersed hub inertia and tip mass
    scenario: tamu_40deg.yaml          # relative to this file
    run: Law II
    parameters:
      hub_inertia: {distribution: normal, mean: "50 ozf*in*s**2", sd: "2 ozf*in*s**2"}
      tip_mass: {distribution: uniform, low: "0 kg", high: "0.01 kg"}
    cases: 1000
    seed: 0
    requirements:
      settling_time_s: {max: "8 s"}
    execution: {chunk_size: 250}

``kind: sweep`` takes grid axes (``{values: [...]}`` or ``{low:, high:, n:}``, full factorial,
the first axis slowest) or bounds (``{low:, high:}``) with ``sampling: latin_hypercube`` or
``sobol`` and ``cases``, or ``sampling: saltelli`` with ``cases`` the base points (a power of
2; n (d + 2) cases run) for Sobol' first-order and total indices of every metric;
``kind: montecarlo`` takes distributions (normal, uniform, lognormal, truncated_normal;
:mod:`flexsat.design.parameter_space`) sampled per case from the seed.
The fast path's parameters are those of :class:`~flexsat.design.batch_runner.HubManeuverBuilder`
(:data:`PARAMETER_UNITS`): the maneuver (``alpha``, ``u_max``, ``duration``), the Law II gains
(``g1``, ``g2``, ``g3``), the plant (``hub_inertia``, ``EI``, ``damping``, ``tip_mass``,
``tip_inertia``), the bearing friction (``friction_coulomb``, ``friction_viscous``) and the
hardware (``saturation``, the torque limit; ``encoder_resolution``; ``gyro_noise`` and
``strain_noise``, 1σ per sample; ``random_torque``, 1σ), e.g.
``saturation: {low: "300 ozf*in", high: "500 ozf*in", n: 3}``; the others keep the maneuver
scenario's values. Its chunks are one batched, compiled call each.

Execution (:func:`~flexsat.design.batch_runner.run_batch`): chunks of ``chunk_size`` cases, each
one batched core call, scheduled on dask in-process, on ``workers`` local processes or on the
cluster at ``scheduler``; the store is ``store`` (relative to this file) or, by default, a
directory in the system's temporary folder named after the run's fingerprint, so running the
same scenario again resumes it. Metrics are the engine's maneuver metrics on the fast path and
the numbers of the target kind's metrics records otherwise; a requirement on a metric in
degrees (``overshoot_deg``) is compared in degrees, one on a metric the engine does not name
takes a plain number in the metric's own unit.
"""

from __future__ import annotations

import tempfile
from collections.abc import Callable, Generator
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, Literal, Self, get_args

import numpy as np
from pydantic import Field, field_validator, model_validator

from flexsat import limits
from flexsat.input_checks import FieldError
from flexsat.report.page import ReportedResult
from flexsat.scenarios.errors import Problem, ScenarioError, locate
from flexsat.scenarios.fields import Document, SchemaSection, integer_in
from flexsat.scenarios.kind import Run, ScenarioKind

if TYPE_CHECKING:
    import xarray as xr

    from flexsat.design.batch_runner import BatchProgress, HubManeuverBuilder
    from flexsat.design.monte_carlo_statistics import Requirement
    from flexsat.design.parameter_space import GridSpace, ParameterSpace, SampleTable, SobolDesign
    from flexsat.scenarios.maneuver import Scenario

#: the SI unit of every parameter a batch can vary (HubManeuverBuilder's columns)
PARAMETER_UNITS = {
    "alpha": "",
    "u_max": "N*m",
    "duration": "s",
    "g1": "N*m/rad",
    "g2": "N*m*s/rad",
    "g3": "",
    "hub_inertia": "kg*m**2",
    "EI": "N*m**2",
    "damping": "",
    "tip_mass": "kg",
    "tip_inertia": "kg*m**2",
    "friction_coulomb": "N*m",
    "friction_viscous": "N*m*s/rad",
    "saturation": "N*m",
    "encoder_resolution": "rad",
    "gyro_noise": "rad/s",
    "strain_noise": "N*m",
    "random_torque": "N*m",
}

#: sampling of a sweep's bounds or a Monte Carlo's distributions
Sampling = Literal["grid", "random", "latin_hypercube", "sobol", "saltelli"]
SAMPLINGS: tuple[str, ...] = get_args(Sampling)


class ExecutionSpec(SchemaSection):
    """How the chunks run (:func:`~flexsat.design.batch_runner.run_batch`)."""

    chunk_size: Annotated[int, integer_in(1, limits.MAX_SAMPLES)] = 1000
    workers: Annotated[int | None, integer_in(1, 256, optional=True)] = None
    scheduler: str | None = None
    retries: Annotated[int, integer_in(0, 100)] = 2

    @model_validator(mode="after")
    def _one_place(self) -> Self:
        if self.workers is not None and self.scheduler is not None:
            raise FieldError(
                "execution",
                "give workers (a local cluster) or scheduler (an existing cluster), not both",
            )
        return self


def _check_entry_values(parameters: dict[str, Any]) -> None:
    """Each parameter's values of the right shape before they are read: ``distribution`` a
    name, ``values`` a list of numbers or quantities, every other key (mean, sd, low, high, n,
    ...) one number or quantity string: a list or a mapping where one value belongs is refused
    by name here (the parameter space would otherwise hash it, as a distribution name, or
    broadcast it)."""
    for name, entry in parameters.items():
        if not isinstance(entry, dict):
            continue  # space_from_spec refuses a non-mapping by name
        for key, value in entry.items():
            path = f"parameters.{name}.{key}"
            if key == "distribution":
                if not isinstance(value, str):
                    raise FieldError(path, f"must be a distribution name (a string), got {value!r}")
            elif key == "values":
                if not isinstance(value, list) or any(
                    isinstance(v, (list, dict, bool)) or v is None for v in value
                ):
                    raise FieldError(
                        path, f"must be a list of numbers or quantities, got {value!r}"
                    )
            elif isinstance(value, (list, dict, bool)) or value is None:
                raise FieldError(path, f"must be one number or quantity, got {value!r}")


def by_document_path(parameters: dict[str, Any]) -> bool:
    """Whether the parameters are field paths of the target document (the general path) rather
    than names of the Law II fast path (:data:`PARAMETER_UNITS`); the two do not mix."""
    from flexsat.scenarios.batch_cases import is_document_path

    paths = [name for name in parameters if is_document_path(str(name))]
    names = [name for name in parameters if not is_document_path(str(name))]
    if paths and names:
        raise FieldError(
            f"parameters.{names[0]}",
            f"field paths ({paths[0]}) and Law II parameter names ({names[0]}) cannot be mixed; "
            f"give every parameter by its field path in the scenario "
            f"(e.g. runs['Law II'].gains.g1)",
        )
    return bool(paths)


def _units(parameters: dict[str, dict[str, Any]]) -> dict[str, str]:
    """The SI unit of each parameter: the fast path's, or the unit a path's values are written
    in (dimensionless for plain numbers; :func:`~flexsat.scenarios.batch_cases.written_unit`)."""
    from flexsat.scenarios.batch_cases import written_unit
    from flexsat.scenarios.document_paths import parse_path

    if not by_document_path(parameters):
        return PARAMETER_UNITS
    units = {}
    for path, entry in parameters.items():
        field = f"parameters.{path}"
        parse_path(path, field)
        unit = written_unit(entry, field) if isinstance(entry, dict) else None
        units[path] = unit[1] if unit else ""
    return units


def parameter_space(
    parameters: dict[str, dict[str, Any]], units: dict[str, str] | None = None
) -> ParameterSpace | GridSpace:
    """The parameter space of a ``parameters:`` section (each entry's values checked first), in
    ``units`` or the units its entries are written in.

    Raises
    ------
    FieldError
        ``parameters.<name>...``: a value of the wrong shape, an unknown distribution, a unit
        of another dimension.
    """
    from flexsat.design.parameter_space import space_from_spec

    _check_entry_values(parameters)
    return space_from_spec(parameters, units or _units(parameters))


def _metric_unit(metric: str, engine_only: bool) -> str:
    """The unit of an engine metric; unless ``engine_only``, also of a run's engine metric (its
    name after the last ``.``: ``runs['PD'].overshoot_deg`` is an ``overshoot_deg``), any
    other name taken as a plain number."""
    from flexsat.sim.metrics import METRIC_UNITS

    base = metric if engine_only else metric.rsplit(".", 1)[-1]
    if base in METRIC_UNITS:
        return METRIC_UNITS[base]
    if engine_only:
        raise FieldError(
            f"requirements.{metric}", f"unknown metric; metrics: {', '.join(METRIC_UNITS)}"
        )
    return ""


def requirements_of(spec: dict[str, Any], engine_only: bool = True) -> list[Requirement]:
    """The :class:`~flexsat.design.monte_carlo_statistics.Requirement` s of a ``requirements:``
    dict, each in its metric's unit (degrees for the ``_deg`` metrics; a plain number for a
    metric the engine does not name, accepted unless ``engine_only``: the metrics of a batch
    over a scenario document are known when its first case has run)."""
    from flexsat.design.monte_carlo_statistics import Requirement, requirement_from_spec
    from flexsat.design.parameter_space import si_scalar

    out: list[Requirement] = []
    for metric, entry in spec.items():
        unit = _metric_unit(metric, engine_only)
        path = f"requirements.{metric}"
        if unit.startswith("deg"):  # the metric is in degrees: compare the threshold in degrees
            if (
                not isinstance(entry, dict)
                or len(entry) != 1
                or next(iter(entry)) not in ("max", "min")
            ):
                raise FieldError(path, f"give exactly one of max: or min:, got {entry!r}")
            key, value = next(iter(entry.items()))
            si = "rad" if unit == "deg" else "rad/s"
            threshold = float(np.degrees(si_scalar(value, si, f"{path}.{key}")))
            out.append(Requirement(metric, "<=" if key == "max" else ">=", threshold, ""))
        else:
            out.append(requirement_from_spec(metric, entry, unit.replace(" ", "*"), path))
    return out


class BatchScenario(Document):
    """A validated sweep or Monte Carlo scenario (module docstring)."""

    kind: Literal["sweep", "montecarlo"]
    name: str
    scenario: str
    run: str | None = None
    parameters: dict[str, dict[str, Any]]
    sampling: Sampling | None = None
    cases: Annotated[int | None, integer_in(1, limits.MAX_SAMPLES, optional=True)] = None
    seed: Annotated[int, integer_in(0, limits.MAX_SEED)] = 0
    requirements: dict[str, dict[str, Any]] = Field(default_factory=dict)
    histories: list[str] = Field(default_factory=list, max_length=16)
    execution: ExecutionSpec = Field(default_factory=ExecutionSpec)
    store: str | None = None

    @field_validator("parameters")
    @classmethod
    def _parameters(cls, parameters: dict[str, dict[str, Any]]) -> dict[str, dict[str, Any]]:
        parameter_space(parameters)
        return parameters

    @model_validator(mode="after")
    def _design(self) -> Self:
        from flexsat.design.parameter_space import GridSpace

        general = by_document_path(self.parameters)
        requirements_of(self.requirements, engine_only=not general)
        if not general and self.run is None:
            raise FieldError("run", "required: the Control Law II run the parameters vary")
        if general and self.histories:
            raise FieldError(
                "histories", "a batch over a scenario document's field paths keeps metrics only"
            )

        grid = isinstance(parameter_space(self.parameters), GridSpace)
        sampling: Sampling = self.sampling or (
            "grid" if grid else "random" if self.kind == "montecarlo" else "latin_hypercube"
        )
        if grid != (sampling == "grid"):
            raise FieldError(
                "sampling",
                f"{sampling!r} needs "
                + (
                    "grid axes (values: or low/high/n)"
                    if sampling == "grid"
                    else "bounds (low/high) or distributions, not grid axes"
                ),
            )
        if self.kind == "montecarlo" and sampling != "random":
            raise FieldError(
                "sampling",
                "a montecarlo samples its distributions at random, "
                f"got {sampling!r} (use kind: sweep for grids and designs)",
            )
        if sampling != "grid" and self.cases is None:
            raise FieldError("cases", f"required with sampling {sampling!r}")
        if sampling == "saltelli" and self.cases is not None and self.cases & (self.cases - 1):
            raise FieldError(
                "cases", f"the Saltelli design takes a power of 2 base points, got {self.cases}"
            )
        if sampling == "grid" and self.cases is not None:
            raise FieldError("cases", "a grid has as many cases as its points; leave cases out")
        self.sampling = sampling
        if general and "chunk_size" not in self.execution.model_fields_set:
            from flexsat.scenarios.batch_cases import DOCUMENT_CHUNK_SIZE

            self.execution = self.execution.model_copy(update={"chunk_size": DOCUMENT_CHUNK_SIZE})
        # the case count, from the axes' lengths or the sizes given: before any table is built
        n_cases = case_count(self)
        if n_cases > limits.MAX_CASES:
            field = "parameters" if sampling == "grid" else "cases"
            space = parameter_space(self.parameters)
            if isinstance(space, GridSpace):  # sampling "grid"
                what = f"the grid of {' × '.join(map(str, space.shape))}"
            elif sampling == "saltelli":
                what = (
                    f"the Saltelli design of {self.cases} base points × "
                    f"({len(self.parameters)} parameters + 2)"
                )
            else:
                what = "the sample"
            raise FieldError(
                field,
                f"{what} has {n_cases:,} cases, above the limit {limits.MAX_CASES:,} "
                f"(flexsat.limits.MAX_CASES); split the study or sample it more sparsely",
            )
        if self.requirements and self.kind != "montecarlo":
            raise FieldError(
                "requirements", "belong to a montecarlo (a probability of meeting them)"
            )
        return self


# -- running -------------------------------------------------------------------------------------
@dataclass(frozen=True)
class BatchResult(ReportedResult):
    """A batch run: the scenario, the parameter table, the store and its dataset, the
    statistics (``summary``: requirements, metric summaries and convergence; ``sensitivity``:
    the parameters' ranking per metric)."""

    scenario: BatchScenario
    target: Any
    table: dict[str, np.ndarray]
    units: dict[str, str]
    store: Path
    summary: dict[str, Any]
    sensitivity: dict[str, dict[str, Any]]
    wall_s: float
    chunks_run: int
    chunks_skipped: int
    case_source: str
    surfaces: dict[str, np.ndarray] | None = None

    def dataset(self) -> xr.Dataset:
        from flexsat.design.batch_runner import open_results

        return open_results(self.store)

    def metrics_records(self) -> list[dict[str, Any]]:
        """One row per metric (its 5 %, 50 % and 95 % percentiles) and per requirement (the
        probability of meeting it, between its confidence bounds): the CLI's table."""
        rows: list[dict[str, Any]] = []
        for name, m in self.summary["metrics"].items():
            p = m["percentiles"]
            rows.append(
                {
                    "run": name,
                    "p5": _finite(p.get("5")),
                    "median": _finite(p.get("50")),
                    "p95": _finite(p.get("95")),
                    "not_finite": m["n_nan"],
                }
            )
        for r in self.summary["requirements"]:
            rows.append(
                {
                    "run": f"P({r['metric']} {r['relation']} {r['threshold']:g})",
                    "p5": _finite(r["low"]),
                    "median": _finite(r["probability"]),
                    "p95": _finite(r["high"]),
                    "not_finite": 0,
                }
            )
        return rows

    def report_case(self) -> str:
        return str(getattr(self.target, "case", self.target.name))

    def write_data(self, folder: Path, ds: xr.Dataset) -> None:
        from flexsat.report.batch import write_data

        write_data(self, ds, folder)

    def figures(self, folder: Path, ds: xr.Dataset) -> list[str]:
        from flexsat.report.batch import draw_figures

        return draw_figures(self, ds, folder)

    def sections(self, ds: xr.Dataset, figures: list[str]) -> str:
        from flexsat.report.batch import sections

        return sections(self, ds, figures)


def _finite(value: float | None) -> float | None:
    """A JSON-ready number: NaN and inf become None."""
    return None if value is None or not np.isfinite(value) else float(value)


def _target(scenario: BatchScenario) -> Any:
    """The target scenario, loaded and validated (its problems named under ``scenario``)."""
    from flexsat.scenarios import load_scenario

    path = Path(scenario.scenario)
    path = path if path.is_absolute() else scenario.folder / path
    try:
        return load_scenario(path)
    except ScenarioError as exc:
        raise ScenarioError([Problem("scenario", str(p)) for p in exc.problems]) from None


def _maneuver(scenario: BatchScenario, target: Any) -> Scenario:
    """The fast path's target: a maneuver scenario."""
    from flexsat.scenarios.maneuver import Scenario

    if not isinstance(target, Scenario):
        raise ScenarioError(
            [
                Problem(
                    "",
                    f"{scenario.scenario!r} is a {target.kind} scenario; a batch of Law II "
                    "parameters varies a maneuver scenario (give field paths to vary "
                    "another kind: plant.tip_mass, runs['PD'].gains.K)",
                )
            ]
        )
    return target


def _source(target: Any) -> str:
    """What the report cites: the target's case, else the target itself."""
    from flexsat.cases import get_case
    from flexsat.references import cite

    try:
        return cite(get_case(target.case).source)
    except (AttributeError, KeyError, ValueError):  # no case, or not a published one
        return f"the {target.kind} scenario {target.name!r}"


def builder_of(scenario: BatchScenario, maneuver: Scenario) -> HubManeuverBuilder:
    """The :class:`~flexsat.design.batch_runner.HubManeuverBuilder` of the named Law II run."""
    from flexsat.control import LyapunovTracker
    from flexsat.design.batch_runner import HubManeuverBuilder
    from flexsat.maneuvers import SmoothBangBang
    from flexsat.scenarios.maneuver_kind import prepare_scenario

    plan = prepare_scenario(maneuver)
    if scenario.run not in plan.controllers:
        raise ScenarioError(
            [
                Problem(
                    "run",
                    f"{scenario.run!r} is not a run of the scenario (its runs: "
                    f"{', '.join(plan.controllers)})",
                )
            ]
        )
    law = plan.controllers[scenario.run]
    if not isinstance(law, LyapunovTracker):
        raise ScenarioError(
            [
                Problem(
                    "run",
                    f"{scenario.run!r} uses {type(law).__name__}; a batch varies "
                    "a Control Law II run (law: lyapunov_tracker)",
                )
            ]
        )
    ref, model = law.reference, plan.model
    if not isinstance(ref, SmoothBangBang):  # the builder remakes it from alpha and u_max
        raise ScenarioError(
            [
                Problem(
                    "run",
                    f"{scenario.run!r} tracks a {type(ref).__name__} reference; a batch varies "
                    "a smooth_bang_bang reference (bang_bang is smooth_bang_bang with alpha: 0)",
                )
            ]
        )
    return HubManeuverBuilder(
        params=model.params,
        n_modes=model.n_modes,
        config=plan.run_config(scenario.run),
        angle=float(ref.angle),
        reference_inertia=float(ref.inertia),
        u_max=float(ref.u_max),
        g1=float(law.g1),
        g2=float(law.g2),
        g3=float(law.g3),
        alpha=float(ref.alpha),
        stiffening=bool(model.stiffening),
    )


def _cases(scenario: BatchScenario) -> int:
    assert scenario.cases is not None  # BatchScenario requires cases of every sampling but grid
    return scenario.cases


def _table(
    scenario: BatchScenario, units: dict[str, str] | None = None
) -> SampleTable | SobolDesign:
    from flexsat.design.parameter_space import GridSpace

    space = parameter_space(scenario.parameters, units)
    if isinstance(space, GridSpace):
        table = space.table()
    elif scenario.sampling == "saltelli":
        return space.sobol_design(_cases(scenario), scenario.seed)
    elif scenario.sampling == "random":
        table = space.sample(_cases(scenario), scenario.seed)
    elif scenario.sampling == "latin_hypercube":
        table = space.latin_hypercube(_cases(scenario), scenario.seed)
    else:
        table = space.sobol_sequence(_cases(scenario), scenario.seed)
    return table


def case_count(scenario: BatchScenario) -> int:
    """The number of cases: the grid's points or ``cases``."""
    from flexsat.design.parameter_space import GridSpace

    space = parameter_space(scenario.parameters)
    if isinstance(space, GridSpace):
        return space.size
    if scenario.sampling == "saltelli":  # n_base (d + 2) cases for first-order and total
        return _cases(scenario) * (len(scenario.parameters) + 2)
    return _cases(scenario)


def default_store(fingerprint: str) -> Path:
    """A directory in the system's temporary folder named after the run's fingerprint
    (:func:`flexsat.design.batch_runner.fingerprint`: the scenario texts, the parameter table,
    the seed, the histories, the case builder and the store layout): the same run resumes it,
    while a changed setup or a flexsat that fills stores differently starts a store of its own
    instead of meeting a store it must refuse."""
    return Path(tempfile.gettempdir()) / f"flexsat-batch-{fingerprint[:20]}.zarr"


def _run_batch(
    scenario: BatchScenario, progress: Callable[[str], None] | None = None
) -> BatchResult:
    """Build the case builder (the Law II fast path's, or the target document's:
    :func:`~flexsat.scenarios.batch_cases.document_cases`), run every case into the store
    (resuming it), then compute the statistics.

    Raises
    ------
    ScenarioError
        For a target scenario, run or path that cannot be varied, a case its kind refuses
        (before any case runs), a sampling the space refuses, a scheduler that does not
        answer, a store of another scenario.
    """
    from flexsat.design.batch_runner import fingerprint, maneuver_metrics, run_batch
    from flexsat.design.monte_carlo_statistics import (
        MIN_RANKING_CASES,
        monte_carlo_summary,
        sample_sensitivity,
        sobol_indices,
    )
    from flexsat.design.parameter_space import SobolDesign
    from flexsat.scenarios.batch_cases import case_metrics, document_cases
    from flexsat.sim import SimulationDiverged

    target = _target(scenario)
    build: Any
    if by_document_path(scenario.parameters):
        build = document_cases(
            target, scenario.run, scenario.parameters, tuple(scenario.requirements)
        )
        units: dict[str, str] | None = {p.path: p.unit for p in build.parameters}
        extract: Callable[[Any], Any] = case_metrics
    else:
        build = builder_of(scenario, _maneuver(scenario, target))
        units, extract = None, maneuver_metrics
    try:
        sampled = _table(scenario, units)
    except ValueError as exc:
        raise ScenarioError([locate("sampling", exc)]) from None
    design, table = (
        (sampled, sampled.table) if isinstance(sampled, SobolDesign) else (None, sampled)
    )
    setup_text = scenario.yaml_text + "\0" + target.yaml_text
    histories = tuple(scenario.histories)
    if scenario.store is None:
        store = default_store(
            fingerprint(setup_text, table.values, scenario.seed, histories, build.describe())
        )
    else:
        store = Path(scenario.store)
        store = store if store.is_absolute() else scenario.folder / store

    def report(p: BatchProgress) -> None:
        if progress is not None:
            progress(
                f"{p.cases_done}/{p.cases_total} cases, {p.cases_per_s:.0f} cases/s, "
                f"ETA {p.eta_s:.0f} s"
            )

    e = scenario.execution
    try:
        summary = run_batch(
            build,
            table.values,
            store,
            extract=extract,
            base_seed=scenario.seed,
            chunk_size=e.chunk_size,
            histories=histories,
            setup_text=setup_text,
            workers=e.workers,
            scheduler=e.scheduler,
            retries=e.retries,
            progress=report,
        )
    except (SimulationDiverged, ScenarioError):
        raise  # a result, not an input error (the runner names the run); or named already
    except ValueError as exc:
        raise ScenarioError([locate("", exc)]) from None
    from flexsat.design.batch_runner import open_results

    ds = open_results(store)
    # by name: a zarr store lists its arrays in no fixed order, and the summary's order is
    # part of the files two identical runs must write alike
    metrics = {
        str(k)[len("metric_") :]: ds[k].values
        for k in sorted(map(str, ds.data_vars))
        if str(k).startswith("metric_")
    }
    stats = monte_carlo_summary(
        metrics, requirements_of(scenario.requirements, engine_only=units is None)
    )
    sensitivity: dict[str, dict[str, Any]] = {}
    for name, values in metrics.items():
        finite = np.isfinite(values)
        if finite.sum() < MIN_RANKING_CASES or np.ptp(values[finite]) == 0:
            continue  # constant, or too few values (a maneuver that rarely settles): no ranking
        if design is not None:
            if finite.all():  # Sobol' indices need every case (a NaN is not a value)
                sensitivity[name] = sobol_indices(
                    design, values, name, seed=scenario.seed
                ).as_dict()
        else:
            sensitivity[name] = sample_sensitivity(table, values, name).as_dict()
    return BatchResult(
        scenario,
        target,
        table.values,
        dict(table.units),
        store,
        stats,
        sensitivity,
        summary.wall_s,
        summary.chunks_run,
        summary.chunks_skipped,
        _source(target),
        None if units is not None else trade_surfaces(scenario, build),
    )


def trade_surfaces(
    scenario: BatchScenario, build: HubManeuverBuilder
) -> dict[str, np.ndarray] | None:
    """For a grid over exactly (alpha, u_max): the Junkins, Pollock & Rahman 1990 trade
    surfaces of the run's
    maneuver, computed exactly (:mod:`flexsat.design.trade_surfaces`): the maneuver time T
    (Att. 3 Eq. 16, Fig. 5), the vibration energy E(T) of the open-loop flexible response
    (Fig. 6) and the Law II tracking bound μ_max (Eq. 22, Fig. 7), each (n_alpha, n_u_max) with
    the axes; None otherwise."""
    from flexsat.design.parameter_space import GridSpace
    from flexsat.design.trade_surfaces import (
        maneuver_time_surface,
        residual_energy_surface,
        tracking_bound_surface,
    )
    from flexsat.dynamics.hub_appendage import HubAppendage

    space = parameter_space(scenario.parameters)
    if not isinstance(space, GridSpace) or sorted(a.name for a in space.axes) != ["alpha", "u_max"]:
        return None
    axes = {a.name: np.asarray(a.values, float) for a in space.axes}
    alpha, u_max = axes["alpha"], axes["u_max"]
    plant = HubAppendage(build.params, n_modes=build.n_modes)
    appendage = (build.params.total_inertia - build.params.hub_inertia) / build.params.n_appendages
    return {
        "alpha": alpha,
        "u_max": u_max,
        "maneuver_time_s": maneuver_time_surface(
            build.angle, build.reference_inertia, alpha, u_max
        ),
        "residual_energy_J": residual_energy_surface(
            plant, build.angle, build.reference_inertia, alpha, u_max
        ),
        "mu_max_deg_s": np.degrees(
            tracking_bound_surface(
                plant,
                build.angle,
                build.reference_inertia,
                alpha,
                u_max,
                build.g1,
                build.g2,
                build.g3,
                appendage,
            )
        ),
    }


class _BatchKind(ScenarioKind):
    """A batch of cases of one scenario on dask (module docstring): one run
    that announces a step as it starts and one per chunk."""

    document = BatchScenario
    runs_batches = True

    def steps(self, scenario: BatchScenario) -> int:
        import math

        return 1 + math.ceil(case_count(scenario) / scenario.execution.chunk_size)

    def plan(self, scenario: BatchScenario) -> Generator[Run, Any, BatchResult]:
        import functools

        return (
            yield Run(scenario.kind, functools.partial(_run_batch, scenario), reports_progress=True)
        )

    def with_execution(
        self, scenario: BatchScenario, workers: int | None, scheduler: str | None
    ) -> BatchScenario:
        """The scenario with ``--workers`` (a local cluster) or ``--scheduler`` (an existing
        one) in place of its ``execution:`` section."""
        if workers is None and scheduler is None:
            return scenario
        if workers is not None and scheduler is not None:
            raise ScenarioError(
                [
                    Problem(
                        "--workers/--scheduler",
                        "give one (a local cluster or an existing one), not both",
                    )
                ]
            )
        execution = scenario.execution.model_copy(
            update={"workers": workers, "scheduler": scheduler}
        )
        copy = scenario.model_copy(update={"execution": execution})
        copy._source, copy._folder = scenario._source, scenario._folder
        return copy


class SweepKind(_BatchKind):
    """``kind: sweep``: grid axes or bounds sampled by a design (module docstring)."""

    kind = "sweep"


class MonteCarloKind(_BatchKind):
    """``kind: montecarlo``: distributions sampled per case from the seed (module
    docstring)."""

    kind = "montecarlo"


__all__ = [
    "BatchResult",
    "MonteCarloKind",
    "SweepKind",
    "BatchScenario",
    "PARAMETER_UNITS",
    "SAMPLINGS",
    "builder_of",
    "case_count",
    "trade_surfaces",
    "default_store",
    "parameter_space",
    "requirements_of",
]
