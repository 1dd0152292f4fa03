r"""The dispersions stage of a design study: a Monte Carlo of the designed laws flown on
dispersed spacecraft.

::

    dispersions:
      parameters:                                   # paths in the study document
        model.fe.materials.aluminium.E: {distribution: normal, mean: "70 GPa", sd: "1.75 GPa"}
        model.fe.masses[1].mass: {distribution: uniform, low: "0.9 kg", high: "1.1 kg"}
        modes.damping: {distribution: lognormal, median: 0.005, gsd: 1.5}
      cases: 200
      seed: 0
      runs: [slew]                                  # the runs flown (leave out: all)
      requirements:
        final_attitude_error_rad: {max: "1 mrad"}
        peak_displacement_m: {max: "5 mm"}
      execution: {chunk_size: 10, workers: 2}
      store: dispersions.zarr                       # optional, relative to the file

Semantics: design on the nominal, fly on the truth
--------------------------------------------------
The placement and the laws are those of the **nominal** study (its cached stages): they are
what the engineer designed and would fly. Each case builds the **dispersed truth** -- the
``model:``, ``modes:`` and ``truth:`` sections with the case's values (the modal solve redone
when the model changes, the kept modes and their damping, then the truth's departures:
principal moments, elastic frequencies, damping ratios, :func:`~flexsat.scenarios.slew.
apply_truth`) -- keeps the nominal placement (the forces sit where they were placed) and flies
every named run's nominal law on it, from the run's (possibly dispersed) initial state, for
the (possibly dispersed) duration, with the study's ``sensors`` and ``disturbances`` (their
noise from the case's own seed). When no parameter is under ``model``, every case reuses the
nominal modal solve (the same numbers as solving it again, tested) instead of repeating it.
The probability of meeting a requirement is then the probability that *this design* meets it
on a spacecraft built within the dispersions: its robustness, not that of a law redesigned for
every case. A law that reads modal coordinates (LQR, the perturbation feedback) reads the
truth's kept modes by index, each with the sign of the nominal mode's shape
(:func:`~flexsat.scenarios.design_flight.align_modes`: a re-solve may return a mode with the
other sign, which the law would feed back reversed); where dispersions make two modes cross,
the law meets them swapped, as it would in flight.

Direct cases and compiled batches
---------------------------------
When every parameter is under ``truth`` (:data:`DIRECT_SECTIONS`) a case is the nominal
spacecraft (built once per worker) with its own departures: no case document is written or
validated and no plant rebuilt (:meth:`DispersedCases.setup`). Every chunk's cases fly in
compiled batches (:func:`~flexsat.scenarios.design_flight.fly_cases`): consecutive cases with
the same settings stacked into one dispersed plant, one lane each of the three-axis kernel, the
perturbation feedback through its linear form. A direct study's chunk defaults to
:data:`DIRECT_CHUNK_SIZE` cases.

The parameters, their distributions with units, ``cases``, ``seed``, ``requirements`` and
``execution`` are those of ``kind: montecarlo`` (:mod:`flexsat.scenarios.batch`, the same
schema and the same code: :func:`~flexsat.scenarios.batch.parameter_space`,
:class:`~flexsat.scenarios.batch.ExecutionSpec`). A path must lead into the truth: ``model``,
``modes``, ``truth``, ``sensors``, ``disturbances``, ``simulation`` (not its ``control_rate``:
the laws are sampled at the nominal one, nor its ``seed``: each case's is written there) or a
run's ``initial``; a law's or the placement's values are the design, refused by name.

Metrics (:func:`~flexsat.scenarios.design_study.run_metrics` of each run flown, the attitude
error from the run's law's target): with one run each under its own name
(``final_attitude_error_rad``), with several under ``runs['label'].name``, as in a batch over
a scenario document (:func:`~flexsat.scenarios.batch_cases.case_metrics`); a requirement on
another name is refused before anything runs. Thresholds take units (rad, m, N m, N).

Execution: the cases run through the batch machinery
(:func:`~flexsat.design.batch_runner.run_batch`): chunks on dask, a zarr store, resume after an
interruption. :class:`DispersedCases` is the case builder; every case's document (a direct
case: its ``truth`` section, and the first case's whole document) is validated
(:class:`~flexsat.scenarios.batch_cases.DocumentCases`) and the truth of each parameter's
extreme draws built (a modulus or a mass made negative, an inertia violating the triangle
inequality is refused by name) before any case runs. A case depends on (seed, index) alone and
flies in its own lane, so results do not depend on the chunking or the workers, and a case
equals :func:`dispersed_case` of its index (the case flown alone) bit for bit.

Cache: the stage's fingerprint holds the section without ``requirements``, ``execution`` and
``store`` (which change no case) and the fingerprints of the runs flown (each holding its law,
the placement, the modes and the model); the default store is named after it in the study's
cache folder. Changing a requirement threshold re-reads the store (every chunk done, none run)
and recomputes only the statistics.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, Self, cast

import numpy as np
from pydantic import Field, field_validator, model_validator

from flexsat import limits
from flexsat.design.stages import Stage, StageCache, StageRecord, canonical_json
from flexsat.input_checks import FieldError
from flexsat.scenarios.batch import ExecutionSpec, parameter_space
from flexsat.scenarios.batch_cases import DOCUMENT_CHUNK_SIZE, DocumentCases
from flexsat.scenarios.design_flight import (
    CaseSetup,
    dispersed_spacecraft,
    fly_cases,
    inertia_margins,
    nominal_setup,
)
from flexsat.scenarios.design_laws import StudySection
from flexsat.scenarios.errors import ScenarioError, item_path, locate
from flexsat.scenarios.fields import integer_in
from flexsat.scenarios.slew import TruthSpec, apply_truth

if TYPE_CHECKING:
    from flexsat.control.base import Controller
    from flexsat.design.monte_carlo_statistics import Requirement
    from flexsat.dynamics.flexible_spacecraft import FlexibleSpacecraft
    from flexsat.scenarios.design_placement import PlacementResult
    from flexsat.structures.modal_model import ModalModel

#: the SI unit of each run metric (:func:`flexsat.scenarios.design_study.run_metrics`)
METRIC_UNITS = {
    "final_attitude_error_rad": "rad",
    "peak_torque_N_m": "N*m",
    "peak_displacement_m": "m",
    "final_displacement_m": "m",
    "peak_force_N": "N",
}
#: the sections of the study a dispersion may vary (module docstring)
TRUTH_SECTIONS = ("model", "modes", "truth", "sensors", "disturbances", "simulation", "runs")
#: the sections whose dispersion the cases apply to the nominal spacecraft directly (module
#: docstring: no case document, no rebuilt plant)
DIRECT_SECTIONS = ("truth",)
#: the default chunk of a study whose parameters are all under :data:`DIRECT_SECTIONS`: its
#: cases run in compiled batches (a few ms a case), a document case builds its own plant first
DIRECT_CHUNK_SIZE = 250
#: fields of ``simulation`` that are not dispersions, and why
FIXED_SIMULATION = {
    "simulation.control_rate": "the laws are designed and sampled at the nominal control rate",
    "simulation.seed": "each case's noise seed is written there from dispersions.seed",
}


class DispersionsSpec(StudySection):
    """The ``dispersions:`` section (module docstring)."""

    parameters: dict[str, dict[str, Any]] = Field(min_length=1)
    cases: Annotated[int, integer_in(1, limits.MAX_CASES)]
    seed: Annotated[int, integer_in(0, limits.MAX_SEED)] = 0
    runs: list[str] | None = Field(None, min_length=1)
    requirements: dict[str, dict[str, Any]] = Field(default_factory=dict)
    execution: ExecutionSpec = Field(default_factory=ExecutionSpec)
    store: str | None = None

    @field_validator("parameters")
    @classmethod
    def _parameters(cls, parameters: dict[str, dict[str, Any]]) -> dict[str, dict[str, Any]]:
        from flexsat.design.parameter_space import GridSpace
        from flexsat.scenarios.batch_cases import is_document_path

        for path in parameters:
            field = f"parameters.{path}"
            root = path.split(".")[0].split("[")[0]
            if not is_document_path(path) or root not in TRUTH_SECTIONS:
                raise FieldError(
                    field,
                    "a dispersion varies the truth the designed laws fly on: a path into "
                    f"{', '.join(TRUTH_SECTIONS[:-1])} or a run's initial "
                    "(the laws and the placement are the design, kept nominal)",
                )
            if root == "runs" and ".initial" not in path:
                raise FieldError(field, "of a run, only its initial state is a dispersion")
            if path in FIXED_SIMULATION:
                raise FieldError(field, f"not a dispersion: {FIXED_SIMULATION[path]}")
        if isinstance(parameter_space(parameters), GridSpace):
            raise FieldError(
                "parameters",
                "dispersions are distributions sampled at random (normal, uniform, lognormal, "
                "truncated_normal), not grid axes",
            )
        return parameters

    @model_validator(mode="after")
    def _chunks(self) -> Self:
        if "chunk_size" not in self.execution.model_fields_set:
            # a document case is a modal solve and a simulation (0.1-5 s): the document
            # batches' chunks; a direct case is a lane of a compiled batch
            size = DIRECT_CHUNK_SIZE if is_direct(self) else DOCUMENT_CHUNK_SIZE
            self.execution = self.execution.model_copy(update={"chunk_size": size})
        return self

    def flown(self, labels: list[str]) -> list[str]:
        """The labels of the runs flown, in the study's order (``labels``: all its runs).

        Raises
        ------
        FieldError
            ``dispersions.runs``: a label that is no run of the study.
        """
        if self.runs is None:
            return list(labels)
        for label in self.runs:
            if label not in labels:
                raise FieldError(
                    "dispersions.runs",
                    f"{label!r} is not a run of the study (its runs: {', '.join(labels)})",
                )
        return [label for label in labels if label in self.runs]

    def requirement_list(self, metrics: list[str]) -> list[Requirement]:
        """The requirements, each in its metric's SI unit (:data:`METRIC_UNITS`).

        Raises
        ------
        FieldError
            ``dispersions.requirements.<metric>``: not one of ``metrics``, or a threshold that
            is not one ``max:`` or ``min:`` quantity of the metric's unit.
        """
        from flexsat.design.monte_carlo_statistics import requirement_from_spec

        out = []
        for metric, entry in self.requirements.items():
            path = f"dispersions.requirements.{metric}"
            if metric not in metrics:
                raise FieldError(path, f"unknown metric; the runs' metrics: {', '.join(metrics)}")
            unit = METRIC_UNITS[metric.rsplit(".", 1)[-1]]
            out.append(requirement_from_spec(metric, entry, unit, path))
        return out


def section_of(path: str) -> str:
    """The study section a parameter path leads into (``truth.damping`` → ``truth``)."""
    return path.split(".")[0].split("[")[0]


def is_direct(spec: DispersionsSpec) -> bool:
    """Whether every parameter is under :data:`DIRECT_SECTIONS`: each case is then the nominal
    spacecraft with its own truth departures, flown without a case document (module
    docstring)."""
    return all(section_of(path) in DIRECT_SECTIONS for path in spec.parameters)


def metric_names(runs: list[str], forces: bool) -> list[str]:
    """The metrics of a case flying ``runs`` (module docstring); ``forces``: placed forces."""
    names = [m for m in METRIC_UNITS if forces or m != "peak_force_N"]
    if len(runs) == 1:
        return names
    return [f"runs[{run!r}].{m}" for run in runs for m in names]


@dataclass(frozen=True)
class DispersedCases:
    """The case builder of the dispersions stage, handed to
    :func:`~flexsat.design.batch_runner.run_batch` (module docstring).

    Attributes
    ----------
    cases : DocumentCases
        The nominal study's document without ``dispersions`` and the varied fields: what
        writes, validates and names a case's document.
    runs : tuple of str
        The runs flown.
    placement : PlacementResult
        The nominal placement.
    laws : dict of str to dict of str to ndarray
        The nominal law designs' arrays.
    key : str
        The stage's fingerprint (it fixes everything above).
    model : ModalModel or None
        The nominal solve, which every case reuses when no parameter is under ``model``
        (:func:`disperses_model`); None: each case solves its own.
    law_of : dict of str to str
        The law of each run flown.
    reference : ModalModel or None
        The nominal kept modes, whose signs each re-solved truth's modes take
        (:func:`~flexsat.scenarios.design_flight.align_modes`); None: the solver's signs.
    direct : bool
        Every parameter is under :data:`DIRECT_SECTIONS` (:func:`is_direct`).
    """

    cases: DocumentCases
    runs: tuple[str, ...]
    placement: PlacementResult
    laws: dict[str, dict[str, np.ndarray]]
    key: str
    model: ModalModel | None = None
    law_of: dict[str, str] = field(default_factory=dict)
    direct: bool = False
    reference: ModalModel | None = None

    @property
    def parameter_names(self) -> tuple[str, ...]:
        """The table's columns: the parameters' paths."""
        return self.cases.parameter_names

    def describe(self) -> str:
        """The stage's fingerprint (part of the store's)."""
        return f"design study dispersions {self.key}"

    def setup(self, values: Mapping[str, float], seed: int, index: int) -> CaseSetup:
        """The truth, settings and initial states of the case ``index`` with ``values`` (SI,
        by path) and noise ``seed``: the nominal spacecraft with the case's ``truth`` section
        (direct), else the case's document validated and its spacecraft built.

        Raises
        ------
        ScenarioError
            Named by the parameter, the case index and its values.
        """
        from flexsat.scenarios.design_study import flight_config, flown_plant
        from flexsat.scenarios.fields import given_fields

        try:
            if self.direct:
                nominal = nominal_setup(self)
                truth = self.truth_of(values)
                plant = apply_truth(truth, nominal.plant)
                return CaseSetup(plant, nominal.config, nominal.initial, "nominal")
            scenario: Any = self.cases.scenario(values, seed)
            plant = flown_plant(
                scenario,
                dispersed_spacecraft(scenario, self.placement, self.model, self.reference),
            )
            config = flight_config(scenario, plant)
            initial = {}
            for i, run in enumerate(scenario.runs):
                if run.label in self.runs:
                    try:
                        initial[run.label] = plant.state_from(**given_fields(run.initial))
                    except ValueError as exc:
                        path = f"runs{item_path(i, run.label)}.initial"
                        raise ScenarioError([locate(path, exc)]) from None
            group = canonical_json(
                {
                    "simulation": scenario.simulation.model_dump(mode="json", exclude={"seed"}),
                    "sensors": {k: v.model_dump(mode="json") for k, v in scenario.sensors.items()},
                    "disturbances": {
                        k: v.model_dump(mode="json") for k, v in scenario.disturbances.items()
                    },
                    "initial": {k: v.tolist() for k, v in initial.items()},
                }
            )
            return CaseSetup(plant, config, initial, group)
        except ScenarioError as exc:
            raise ScenarioError(self.cases.problems(index, values, exc)) from None

    def truth_of(self, values: Mapping[str, float]) -> TruthSpec:
        """The ``truth`` section of a direct case: the nominal's with ``values`` written in
        (each in the unit its entry is given in, as in a case document) and validated.

        Raises
        ------
        ScenarioError
            ``truth.<field>``: a value the section refuses.
        """
        from flexsat.scenarios.document_paths import with_values
        from flexsat.scenarios.slew import TruthSpec

        written = {p.path: p.value(values[p.path]) for p in self.cases.parameters}
        section = with_values({"truth": self.cases.data.get("truth", {})}, written)["truth"]
        try:
            return TruthSpec.model_validate(section)
        except ValueError as exc:
            raise ScenarioError([locate("truth", exc)]) from None

    def controllers(self, plant: FlexibleSpacecraft, dt: float) -> dict[str, Controller]:
        """Each flown run's nominal law (by run label) on a spacecraft of the study's channels
        and modes, sampled at ``dt``."""
        from flexsat.scenarios.design_laws import LawSpec, law_controller

        specs = {
            entry["label"]: LawSpec.model_validate(entry)
            for entry in self.cases.data["laws"]
            if entry["label"] in set(self.law_of.values())
        }
        return {
            label: law_controller(
                specs[self.law_of[label]], self.laws[self.law_of[label]], plant, dt
            )
            for label in self.runs
        }

    def fly(
        self, values: Sequence[Mapping[str, float]], seeds: np.ndarray, start: int
    ) -> dict[str, np.ndarray]:
        """The metrics of the cases ``start ..`` with ``values`` and noise ``seeds``
        (:func:`fly_cases`)."""
        from flexsat.sim import SimulationDiverged
        from flexsat.sim.engine import offset_cases

        setups = [self.setup(v, int(s), start + k) for k, (v, s) in enumerate(zip(values, seeds))]
        controllers = self.controllers(setups[0].plant, setups[0].config.dt)
        try:
            return fly_cases(self, setups, np.asarray(seeds, np.int64), controllers)
        except SimulationDiverged as exc:
            raise offset_cases(exc, start) from None

    def case(self, values: Mapping[str, float], seed: int, index: int) -> dict[str, float]:
        """The metrics of the case ``index`` with ``values`` (SI, by path) and noise ``seed``,
        flown alone.

        Raises
        ------
        ScenarioError
            Named by the parameter, the case index and its values.
        """
        rows = self.fly([values], np.array([seed], np.int64), index)
        return {name: float(v[0]) for name, v in rows.items()}

    def check(self, table: Mapping[str, np.ndarray]) -> None:
        """Before any case runs: every case's document validated and the truth
        (:func:`dispersed_spacecraft`) of the least and greatest draw of each parameter of the
        model or the modes built; for direct cases, every case's ``truth`` section validated,
        the case's document of the first case, and the truth of the least and greatest draw of
        each parameter and of the cases nearest to breaking the inertia's rules (triangle
        inequality, J − ΔᵀΔ positive definite) built.

        Raises
        ------
        ScenarioError
            Naming the parameter, the case index and the rule.
        """
        n = len(next(iter(table.values())))
        names = self.parameter_names

        def values_of(index: int) -> dict[str, float]:
            return {p: float(table[p][index]) for p in names}

        if self.direct:
            self.cases.check({p: table[p][:1] for p in names})
            nominal = nominal_setup(self)
            scales = np.ones((n, 3))
            for index in range(n):
                try:
                    truth = self.truth_of(values_of(index))
                except ScenarioError as exc:
                    raise ScenarioError(self.cases.problems(index, values_of(index), exc)) from None
                scales[index] = np.broadcast_to(np.asarray(truth.inertia_scale, float), 3)
            extremes = {int(np.argmin(table[p])) for p in names} | {
                int(np.argmax(table[p])) for p in names
            }
            extremes |= set(inertia_margins(nominal.plant, scales))
            for index in sorted(extremes):
                self.setup(values_of(index), 0, index)
            return
        self.cases.check(table)
        structural = [p for p in names if section_of(p) in ("model", "modes")]
        extremes = {int(np.argmin(table[p])) for p in structural} | {
            int(np.argmax(table[p])) for p in structural
        }
        for index in sorted(extremes):
            try:
                dispersed_spacecraft(
                    self.cases.scenario(values_of(index), 0),
                    self.placement,
                    self.model,
                    self.reference,
                )
            except ScenarioError as exc:
                raise ScenarioError(self.cases.problems(index, values_of(index), exc)) from None

    def run_chunk(
        self,
        extract: Any,
        parameters: Mapping[str, np.ndarray],
        start: int,
        base_seed: int,
        histories: tuple[str, ...] = (),
    ) -> dict[str, np.ndarray]:
        """The cases ``start .. start + n`` (:meth:`fly`): {``metric_`` name: (n,)}, an empty
        ``time`` and each case's ``seed`` (``extract`` is unused: the metrics are the
        study's)."""
        from flexsat.scenarios.batch_cases import document_seeds

        if histories:
            raise FieldError("histories", "the dispersions of a design study keep metrics only")
        n = len(next(iter(parameters.values())))
        seeds = document_seeds(base_seed, np.arange(start, start + n))
        values = [{p: float(parameters[p][k]) for p in self.parameter_names} for k in range(n)]
        rows = self.fly(values, seeds, 0)
        out = {f"metric_{name}": v for name, v in rows.items()}
        out["time"] = np.empty(0)
        out["seed"] = seeds
        return out


def dispersions_stage(scenario: Any, runs: list[Stage]) -> Stage:
    """The stage of ``scenario.dispersions`` downstream of the ``runs`` it flies (module
    docstring: requirements, execution and the store are not part of it)."""
    spec = scenario.dispersions
    section = spec.model_dump(mode="json", exclude={"requirements", "execution", "store"})
    return Stage.of("dispersions", "dispersions", section, runs)


def disperses_model(spec: DispersionsSpec) -> bool:
    """Whether a parameter is under ``model`` (each case then solves its own structure)."""
    return any(section_of(path) == "model" for path in spec.parameters)


def case_builder(
    scenario: Any,
    stage: Stage,
    placement: PlacementResult,
    laws: Mapping[str, Any],
    model: ModalModel | None = None,
    modes: ModalModel | None = None,
) -> DispersedCases:
    """The :class:`DispersedCases` of ``scenario`` (a validated design study with
    ``dispersions``) with its nominal ``placement`` and law designs (``laws``: label →
    LawDesign), the nominal solve ``model`` the cases reuse when none of them changes the
    model section (ignored otherwise) and the nominal kept ``modes`` whose signs a re-solved
    truth takes (:func:`~flexsat.scenarios.design_flight.align_modes`).

    Raises
    ------
    ScenarioError
        A path that is not a field of the study (nearest named) or a unit of another dimension.
    """
    from flexsat.scenarios.batch_cases import document_parameter
    from flexsat.scenarios.documents import parse_document

    spec = scenario.dispersions
    data = parse_document(scenario.yaml_text)
    data.pop("dispersions")
    try:
        varied = tuple(
            document_parameter(path, entry, data) for path, entry in spec.parameters.items()
        )
    except FieldError as exc:
        raise ScenarioError([locate("dispersions", exc)]) from None
    flown = spec.flown([run.label for run in scenario.runs])
    law_of = {run.label: run.law for run in scenario.runs if run.label in flown}
    return DispersedCases(
        cases=DocumentCases("design_study", data, scenario.folder, varied, "simulation.seed"),
        runs=tuple(flown),
        placement=placement,
        laws={label: dict(laws[label].arrays) for label in sorted(set(law_of.values()))},
        key=stage.key,
        model=None if disperses_model(spec) else model,
        law_of=law_of,
        direct=is_direct(spec),
        reference=modes if disperses_model(spec) else None,
    )


@dataclass(frozen=True)
class DispersionsResult:
    """The statistics of the dispersions stage.

    Attributes
    ----------
    table : dict of str to ndarray
        The parameters' values per case (SI), by path.
    units : dict of str to str
        Their SI units.
    metrics : dict of str to ndarray
        Every metric per case.
    summary : dict
        :func:`~flexsat.design.monte_carlo_statistics.monte_carlo_summary`: per metric its
        percentiles, per requirement the probability of meeting it and its confidence interval.
    sensitivity : dict
        Per metric, the parameters ranked by their rank correlation with it.
    store : Path
        The zarr store of the cases.
    chunks_run, chunks_skipped : int
        Chunks computed by this run, and found done in the store.
    runs : tuple of str
        The runs flown.
    """

    table: dict[str, np.ndarray]
    units: dict[str, str]
    metrics: dict[str, np.ndarray]
    summary: dict[str, Any]
    sensitivity: dict[str, dict[str, Any]]
    store: Path
    chunks_run: int
    chunks_skipped: int
    runs: tuple[str, ...]


def sample_table(spec: DispersionsSpec, units: Mapping[str, str]) -> Any:
    """The sampled :class:`~flexsat.design.parameter_space.SampleTable` of the cases."""
    space = parameter_space(spec.parameters, dict(units))
    return space.sample(spec.cases, spec.seed)  # type: ignore[union-attr]  # not a grid


def run_dispersions(
    scenario: Any,
    stage: Stage,
    placement: PlacementResult,
    laws: Mapping[str, Any],
    progress: Callable[[str], None] | None = None,
    model: Callable[[], ModalModel] | None = None,
    modes: ModalModel | None = None,
) -> tuple[DispersionsResult, StageRecord]:
    """Run the dispersions stage of ``scenario`` (module docstring): every case into the store
    (resuming it), then the statistics, and the stage's record (from the cache when no chunk
    had to run). ``model`` gives the nominal solve, which the cases reuse when no parameter is
    under ``model`` (asked for only then, and only when cases run); ``modes``, the nominal kept
    modes, whose signs each re-solved truth takes (:func:`case_builder`).

    Raises
    ------
    ScenarioError
        A parameter, a case or a requirement refused by name (before any case runs), a store of
        another study.
    """
    from flexsat.design.batch_runner import BatchProgress, fingerprint, open_results, run_batch
    from flexsat.design.batch_store import open_store_mask
    from flexsat.design.monte_carlo_statistics import (
        MIN_RANKING_CASES,
        monte_carlo_summary,
        sample_sensitivity,
    )
    from flexsat.sim import SimulationDiverged

    spec: DispersionsSpec = scenario.dispersions
    start_time = time.perf_counter()
    build = case_builder(scenario, stage, placement, laws, modes=modes)
    try:
        requirements = spec.requirement_list(
            metric_names(list(build.runs), scenario.placement.number > 0)
        )
        table = sample_table(spec, {p.path: p.unit for p in build.cases.parameters})
    except FieldError as exc:
        raise ScenarioError([locate("", exc)]) from None
    except ValueError as exc:
        raise ScenarioError([locate("dispersions", exc)]) from None
    if spec.store is not None:
        store = Path(spec.store)
        store = store if store.is_absolute() else scenario.folder / store
    else:
        store = StageCache(scenario.cache_folder).folder / f"dispersions-{stage.key[:20]}.zarr"

    def report(p: BatchProgress) -> None:
        if progress is not None:
            progress(f"dispersions: {p.cases_done}/{p.cases_total} cases, ETA {p.eta_s:.0f} s")

    e = spec.execution
    n_chunks = math.ceil(spec.cases / e.chunk_size)
    try:
        # a store with every case done is the stage's cache entry: read, neither checked nor
        # scheduled again (run_batch would check every case's document first)
        key = fingerprint(stage.key, table.values, spec.seed, (), build.describe())
        mask = open_store_mask(store, key, spec.cases)
        if mask is not None and mask.all():
            chunks_run, chunks_skipped = 0, n_chunks
            if progress is not None:
                progress(f"dispersions: {spec.cases}/{spec.cases} cases, from the store")
        else:
            if model is not None and not disperses_model(spec):
                build = replace(build, model=model())
            done = run_batch(
                cast("Callable[..., Any]", build),  # a builder with its own run_chunk
                table.values,
                store,
                extract=dict,
                base_seed=spec.seed,
                chunk_size=e.chunk_size,
                setup_text=stage.key,
                workers=e.workers,
                scheduler=e.scheduler,
                retries=e.retries,
                progress=report,
            )
            chunks_run, chunks_skipped = done.chunks_run, done.chunks_skipped
    except (SimulationDiverged, ScenarioError):
        raise
    except ValueError as exc:
        raise ScenarioError([locate("dispersions", exc)]) from None
    ds = open_results(store)
    metrics = {
        str(k)[len("metric_") :]: ds[k].values
        for k in sorted(map(str, ds.data_vars))
        if str(k).startswith("metric_")
    }
    summary = monte_carlo_summary(metrics, requirements)
    sensitivity = {}
    for name, values in metrics.items():
        finite = np.isfinite(values)
        if finite.sum() >= MIN_RANKING_CASES and np.ptp(values[finite]) > 0:
            sensitivity[name] = sample_sensitivity(table, values, name).as_dict()
    result = DispersionsResult(
        dict(table.values),
        dict(table.units),
        metrics,
        summary,
        sensitivity,
        store,
        chunks_run,
        chunks_skipped,
        build.runs,
    )
    facts: dict[str, Any] = {"cases": spec.cases, "runs": list(build.runs)}
    for r in summary["requirements"]:
        facts[f"P({r['requirement']})"] = r["probability"]
    record = StageRecord(stage, chunks_run == 0, time.perf_counter() - start_time, facts)
    return result, record


def dispersions_steps(scenario: Any) -> int:
    """The progress steps of the stage: its start and one a chunk."""
    spec = scenario.dispersions
    return 0 if spec is None else 1 + math.ceil(spec.cases / spec.execution.chunk_size)


def dispersed_case(build: DispersedCases, spec: DispersionsSpec, index: int) -> dict[str, float]:
    """The metrics of case ``index`` computed alone: its values sampled on their own (a
    function of the seed, the parameter and the index), its seed that of its index."""
    from flexsat.scenarios.batch_cases import document_seeds

    space = parameter_space(spec.parameters, {p.path: p.unit for p in build.cases.parameters})
    one = space.sample(1, spec.seed, start=index)  # type: ignore[union-attr]  # not a grid
    values = {p: float(one.values[p][0]) for p in build.parameter_names}
    seed = int(document_seeds(spec.seed, np.array([index]))[0])
    return build.case(values, seed, index)


def check_dispersions(scenario: Any) -> None:
    """The section's references to the study: its runs and the requirements' metrics.

    Raises
    ------
    FieldError
        ``dispersions.runs`` or ``dispersions.requirements.<metric>``.
    """
    spec = scenario.dispersions
    flown = spec.flown([run.label for run in scenario.runs])
    spec.requirement_list(metric_names(flown, scenario.placement.number > 0))


__all__ = [
    "DIRECT_CHUNK_SIZE",
    "DIRECT_SECTIONS",
    "METRIC_UNITS",
    "DispersedCases",
    "is_direct",
    "section_of",
    "DispersionsResult",
    "DispersionsSpec",
    "case_builder",
    "check_dispersions",
    "dispersed_case",
    "disperses_model",
    "dispersions_stage",
    "dispersions_steps",
    "metric_names",
    "run_dispersions",
    "sample_table",
]
