"""Staged design studies (``kind: design_study``): model → modes → actuator placement → law
design → simulation runs → dispersions, each stage cached by fingerprint
(:mod:`flexsat.design.stages`).

::

    kind: design_study
    name: EPS, H2 force placement, LQR and PD slews
    cache: .flexsat-cache            # optional; default under the system's temporary folder
    model: {case: eps, n_modes: 30}  # or your own: {file: ...} or {fe: ...}
    modes: {n_modes: 12, damping: 0.005}
    placement:
      torque_node: 95
      candidates: {nodes: [69, 66, 63, 60, 88], axes: [x, y, z]}
      number: 3
      criterion: h2
      disturbance_node: 95
      outputs: [69, 66]
    laws:
      - {label: PD, type: pd, bandwidth: "0.1 rad/s", damping: 0.8}
      - label: LQR
        type: lqr
        modes: 6
        weights: {attitude: 1e4, rate: 1e4, modes: 1, torque: 1e-4, force: 1e-2}
    simulation: {duration: "60 s", control_rate: "20 Hz"}
    runs:
      - {label: PD slew, law: PD, initial: {euler123: ["10 deg", 0, 0]}}
    dispersions:                     # optional: the nominal laws flown on dispersed truths
      parameters: {modes.damping: {distribution: lognormal, median: 0.005, gsd: 1.5}}
      cases: 200
      requirements: {final_attitude_error_rad: {max: "1 mrad"}}

Stages
------
model
    The section made a :class:`~flexsat.structures.modal_model.ModalModel` by one function,
    :func:`modal_model_of`: a built-in case's finite-element model solved for ``n_modes``
    elastic modes (the modal solve, the costly step), or the user's own free-free structure
    with the keys of a simulation scenario's ``model:`` (:mod:`flexsat.scenarios.models`): a
    ModalModel netCDF, NASTRAN or UFF file (its content is fingerprinted, not its name) or an
    inline finite-element description (``fe``).
modes
    The modes the design keeps: the first ``n_modes`` elastic ones and/or those up to
    ``max_frequency``, with ``damping`` replacing the model's (one ratio or one per kept
    elastic mode); the rigid-body modes are kept (the spacecraft carries them as its rigid
    motion).
placement
    ``number`` point-force actuators along body axes chosen among ``candidates`` by the EPS
    study's H2 energy or Kim & Junkins' α (:mod:`flexsat.scenarios.design_placement`), each
    with a collocated displacement sensor; the ``outputs`` displacements are recorded in
    every run.
laws
    Each law designed on the spacecraft of the kept modes with the placed forces
    (:mod:`flexsat.scenarios.design_laws`): PD, LQR or PPF.
runs
    Each run simulates a law on that spacecraft from ``initial`` (a rest-to-rest slew back to
    the reference attitude) through the one engine (:class:`~flexsat.scenarios.kind.Simulation`).

Every stage's fingerprint holds its section and its upstream stages' fingerprints: changing a
law recomputes that law and its runs, never the modal solve; changing the model recomputes
everything. The report shows every stage, fresh or from the cache.

Dispersions
-----------
``dispersions:`` (optional, :mod:`flexsat.scenarios.design_dispersions`) is the last stage: a
Monte Carlo of the design. The laws designed on the nominal model above fly on each case's
dispersed truth (the model and modes rebuilt from its values, the placement kept nominal), so
the probabilities it reports measure the design's robustness. Its cases run through the batch
machinery (chunks on dask, a zarr store, resume); its fingerprint leaves out the requirements,
so changing a threshold re-reads the store. A sweep or Monte Carlo over this document is also
possible, each case the whole study with other values (laws redesigned per case), reusing the
cached stages upstream of what it changes (:func:`stage_plan` gives a case's stages and
fingerprints without running anything).
"""

from __future__ import annotations

import functools
import json
import time
from collections.abc import Callable, Generator
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, Literal, Self

import numpy as np
from pydantic import ConfigDict, Field, model_validator

from flexsat import limits
from flexsat.design.stages import (
    Stage,
    StageCache,
    StageRecord,
    canonical_json,
    file_digest,
    read_arrays,
    write_arrays,
)
from flexsat.input_checks import FieldError
from flexsat.report.page import ReportedResult
from flexsat.scenarios.design_dispersions import (
    DispersionsResult,
    DispersionsSpec,
    check_dispersions,
    dispersions_stage,
    dispersions_steps,
    run_dispersions,
)
from flexsat.scenarios.design_laws import (
    LawSpec,
    StudySection,
    design_law,
    law_controller,
    law_summary,
)
from flexsat.scenarios.design_placement import (
    PlacementResult,
    PlacementSpec,
    place_actuators,
    read_placement,
    spacecraft,
    write_placement,
)
from flexsat.scenarios.errors import Problem, ScenarioError, item_path, locate
from flexsat.scenarios.fields import (
    Document,
    check_unique_labels,
    given_fields,
    in_unit,
    integer_in,
)
from flexsat.scenarios.kind import Run, ScenarioKind, Simulation
from flexsat.scenarios.models import ModelSection
from flexsat.scenarios.simulation import (
    ChannelDisturbanceSpec,
    ChannelSensorSpec,
    SimulationSettings,
    channel_config,
)
from flexsat.scenarios.slew import TruthSpec, apply_truth

if TYPE_CHECKING:
    import xarray as xr

    from flexsat.dynamics.flexible_spacecraft import FlexibleSpacecraft
    from flexsat.sim import SimConfig, SimResult
    from flexsat.structures.modal_model import ModalModel

Value = float | int | str | list[Any]


def _eps_modal_model(options: dict[str, Any], n_modes: int) -> ModalModel:
    from flexsat.cases.eps import eps

    return eps(**options).modal_model(n_modes)


#: the built-in cases whose finite-element model gives a free-free spacecraft, by name
MODEL_CASES = {"eps": _eps_modal_model}


# -- document -------------------------------------------------------------------------------------
class ModelSpec(ModelSection):
    """The structure: a built-in case's finite-element model (``case``, its ``options`` and
    ``n_modes``), or the user's own, with the keys of a simulation scenario's ``model:``
    (:mod:`flexsat.scenarios.models`: ``file`` -- netCDF, NASTRAN, UFF -- or ``fe``)."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)

    case: str | None = None
    options: dict[str, Any] = Field(default_factory=dict)
    n_modes: Annotated[int, integer_in(1, limits.MAX_MODES)] = 30

    @model_validator(mode="after")
    def _one_source(self) -> Self:
        if self.case is None:
            if self.options or "n_modes" in self.model_fields_set:
                raise FieldError("options", "options and n_modes apply to a case, not to a model")
            if self.hub_appendage is not None:
                raise FieldError(
                    "hub_appendage",
                    "a design study designs a three-axis spacecraft: give its free-free model "
                    "as file or fe (a hub with appendages is a single-axis plant)",
                )
            return self.check_source()
        for key in ModelSection.model_fields:
            if getattr(self, key) is not None:
                raise FieldError(key, "applies to a model of your own, not to a case")
        if self.case not in MODEL_CASES:
            raise FieldError(
                "case",
                f"{self.case!r} has no free-free finite-element model here; cases with one: "
                f"{', '.join(MODEL_CASES)} (or give file or fe)",
            )
        return self


class ModesSpec(StudySection):
    """The modes the design keeps and their damping."""

    n_modes: Annotated[int | None, integer_in(1, limits.MAX_MODES, optional=True)] = None
    max_frequency: Annotated[float | None, in_unit("Hz", positive=True)] = None
    damping: float | list[float] | None = None


class InitialSpec(StudySection):
    """The attitude and rate a run starts from (at rest, undeformed, unless ``rate``)."""

    euler123: Value | None = None
    attitude: Value | None = None
    rate: Value | None = None


class DesignRunSpec(StudySection):
    """One simulation of a designed law."""

    label: str
    law: str
    initial: InitialSpec = Field(default_factory=InitialSpec)


class DesignStudyScenario(Document):
    """A validated design study (module docstring)."""

    kind: Literal["design_study"]
    name: str
    cache: str | None = None
    model: ModelSpec
    modes: ModesSpec = Field(default_factory=ModesSpec)
    placement: PlacementSpec
    laws: list[LawSpec] = Field(min_length=1, max_length=limits.MAX_RUNS)
    simulation: SimulationSettings
    truth: TruthSpec = Field(default_factory=TruthSpec)
    sensors: dict[str, ChannelSensorSpec] = Field(default_factory=dict)
    disturbances: dict[str, ChannelDisturbanceSpec] = Field(default_factory=dict)
    runs: list[DesignRunSpec] = Field(min_length=1, max_length=limits.MAX_RUNS)
    dispersions: DispersionsSpec | None = None

    @model_validator(mode="after")
    def _references(self) -> Self:
        check_unique_labels(self.runs)
        if self.dispersions is not None:
            check_dispersions(self)
        labels = [law.label for law in self.laws]
        for label in labels:
            if labels.count(label) > 1:
                raise FieldError("laws", f"duplicate label {label!r}; each law needs its own label")
        for index, run in enumerate(self.runs):
            if run.law not in labels:
                raise FieldError(
                    f"runs{item_path(index, run.label)}.law",
                    f"{run.law!r} is not a law of the study (its laws: {', '.join(labels)})",
                )
        nyquist = np.pi * self.simulation.control_rate
        for index, law in enumerate(self.laws):
            path = f"laws{item_path(index, law.label)}"
            if law.type == "ppf" and self.placement.number == 0:
                raise FieldError(
                    f"{path}.type", "PPF needs placed force actuators (placement.number >= 1)"
                )
            if law.type != "perturbation":
                continue
            assert law.maneuver is not None and law.break_frequency is not None
            for field, value in (
                ("maneuver.break_frequency", law.maneuver.break_frequency),
                ("break_frequency", law.break_frequency),
            ):
                # the nominal torque is played back and the feedback sampled at the control
                # rate: a break above its Nyquist frequency shapes what neither can produce
                if value > nyquist:
                    raise FieldError(
                        f"{path}.{field}",
                        f"must be at most the control's Nyquist frequency π × "
                        f"simulation.control_rate = {nyquist:.4g} rad/s, got {value:.4g} rad/s",
                    )
            if self.simulation.duration < law.maneuver.duration:
                raise FieldError(
                    "simulation.duration",
                    f"must cover the maneuver of law {law.label!r} "
                    f"({law.maneuver.duration:g} s), got {self.simulation.duration:g} s",
                )
        slews = {law.label for law in self.laws if law.type == "perturbation"}
        for index, run in enumerate(self.runs):
            if run.law in slews and run.initial.model_fields_set:
                raise FieldError(
                    f"runs{item_path(index, run.label)}.initial",
                    f"law {run.law!r} flies its maneuver from rest at the reference attitude; "
                    "give no initial values",
                )
        return self

    @property
    def cache_folder(self) -> Path | None:
        """The cache folder the document names (relative to its folder), or None."""
        return None if self.cache is None else self.folder / self.cache


# -- the model, the one place a section becomes a ModalModel ---------------------------------------
def modal_model_of(spec: ModelSpec, folder: Path) -> ModalModel:
    """The :class:`~flexsat.structures.modal_model.ModalModel` of a ``model:`` section.

    Raises
    ------
    ValueError
        Naming the field (``file``, a case input, ``n_modes``).
    """

    if spec.case is not None:
        try:
            return MODEL_CASES[spec.case](spec.options, spec.n_modes)
        except FieldError as exc:  # a case input is a field of ``options``
            field = exc.field if exc.field == "n_modes" else f"options.{exc.field}"
            raise FieldError(field, exc.rule) from None
    return spec.modal_model(folder)


def _model_section(spec: ModelSpec, folder: Path) -> dict[str, Any]:
    """What the model stage depends on: the section, and its files' content."""
    section = spec.model_dump(mode="json")
    for key in ("file", "op4"):
        name = getattr(spec, key)
        if name is not None:
            path = Path(name) if Path(name).is_absolute() else folder / name
            if not path.is_file():
                raise FieldError(key, f"no such file: {path}")
            section[f"{key}_sha256"] = file_digest(path)
    return section


def stage_plan(scenario: DesignStudyScenario) -> dict[str, Stage]:
    """Every stage of ``scenario`` with its fingerprint, by path (``model``, ``modes``,
    ``placement``, ``laws['LQR']``, ``runs['a']``), in order; nothing is computed.

    Raises
    ------
    ScenarioError
        For a model file that cannot be read.
    """
    try:
        model_section = _model_section(scenario.model, scenario.folder)
    except ValueError as exc:
        raise ScenarioError([locate("model", exc)]) from None
    model = _stage("model", "model", "model", model_section, [])
    modes = _stage("modes", "modes", "modes", scenario.modes.model_dump(mode="json"), [model])
    placement = _stage(
        "placement", "placement", "placement", scenario.placement.model_dump(mode="json"), [modes]
    )
    stages = {"model": model, "modes": modes, "placement": placement}
    laws = {}
    for index, law in enumerate(scenario.laws):
        path = f"laws{item_path(index, law.label)}"
        section = law.model_dump(mode="json")
        if law.type == "perturbation":  # tabulated on the control grid
            section["control_rate"] = scenario.simulation.control_rate
        laws[law.label] = stages[path] = _stage(
            "law", f"law {law.label!r}", path, section, [placement]
        )
    settings = scenario.simulation.model_dump(mode="json")
    flown_on = flight_sections(scenario)
    for index, run in enumerate(scenario.runs):
        path = f"runs{item_path(index, run.label)}"
        section = {"run": run.model_dump(mode="json", exclude={"label"}), "simulation": settings}
        section.update(flown_on)
        stages[path] = _stage("run", f"run {run.label!r}", path, section, [laws[run.law]])
    if scenario.dispersions is not None:
        flown = scenario.dispersions.flown([run.label for run in scenario.runs])
        stages["dispersions"] = dispersions_stage(
            scenario,
            [
                stages[f"runs{item_path(index, run.label)}"]
                for index, run in enumerate(scenario.runs)
                if run.label in flown
            ],
        )
    return stages


def flight_sections(scenario: DesignStudyScenario) -> dict[str, Any]:
    """The ``truth``, ``sensors`` and ``disturbances`` sections a run depends on, those given
    only (a study without them keeps the fingerprints it had before they existed)."""
    out: dict[str, Any] = {}
    for name in ("truth", "sensors", "disturbances"):
        if name in scenario.model_fields_set:
            out[name] = getattr(scenario, name)
            out[name] = (
                out[name].model_dump(mode="json")
                if name == "truth"
                else {k: v.model_dump(mode="json") for k, v in out[name].items()}
            )
    return out


def flown_plant(scenario: Any, plant: FlexibleSpacecraft) -> FlexibleSpacecraft:
    """The spacecraft a run flies on: ``plant`` (the kept modes with the placed forces) with
    the ``truth`` section's departures (:func:`flexsat.scenarios.slew.apply_truth`)."""
    return apply_truth(scenario.truth, plant)


def flight_config(scenario: Any, plant: FlexibleSpacecraft) -> SimConfig:
    """The simulation settings with the ``sensors`` and ``disturbances`` bound to ``plant``'s
    channels (:func:`flexsat.scenarios.simulation.channel_config`).

    Raises
    ------
    ScenarioError
        ``sensors.<channel>...`` or ``disturbances.<channel>...`` by path, or ``simulation``.
    """
    return channel_config(scenario, plant, "design study")


def _stage(name: str, label: str, path: str, section: Any, upstream: list[Stage]) -> Stage:
    """:meth:`Stage.of`; a value JSON cannot hold (NaN in a free-form section such as
    ``model.options``) is refused at ``path``."""
    try:
        return Stage.of(name, label, section, upstream)
    except ValueError:
        raise ScenarioError(
            [Problem(path, "every value must be finite (NaN and infinity have no fingerprint)")]
        ) from None


# -- stage computations ---------------------------------------------------------------------------
def _write_model(model: ModalModel, folder: Path) -> None:
    model.save(folder / "model.nc")


def _read_model(folder: Path) -> ModalModel:
    from flexsat.structures.modal_model import ModalModel

    return ModalModel.load(folder / "model.nc")


def _model_summary(model: ModalModel) -> dict[str, Any]:
    from flexsat.structures.modal_model import RIGID_FREQUENCY

    rigid = model.frequencies <= RIGID_FREQUENCY
    return {
        "boundary": model.boundary,
        "n_nodes": int(model.node_ids.size),
        "n_modes": int(model.n_modes),
        "n_rigid": int(rigid.sum()),
        "total_mass_kg": model.total_mass,
        "inertia_diagonal_kg_m2": np.diag(model.inertia()).tolist(),
        "frequencies_hz": model.frequencies_hz[~rigid].tolist(),
        "damping": model.damping[~rigid].tolist(),
    }


def kept_modes(model: ModalModel, spec: ModesSpec) -> ModalModel:
    """The modes stage: the rigid modes and the kept elastic ones of ``model``, damped as
    ``spec`` says.

    Raises
    ------
    ValueError
        Naming the field of ``modes``.
    """
    from flexsat.structures.modal_model import RIGID_FREQUENCY

    if model.boundary != "free":
        raise FieldError(
            "n_modes",
            f"the model is {model.boundary}; a design study needs a free-free spacecraft model",
        )
    rigid = model.frequencies <= RIGID_FREQUENCY
    elastic = np.flatnonzero(~rigid)
    keep = elastic
    if spec.n_modes is not None:
        if spec.n_modes > elastic.size:
            raise FieldError(
                "n_modes", f"at most the model's {elastic.size} elastic modes, got {spec.n_modes}"
            )
        keep = keep[: spec.n_modes]
    if spec.max_frequency is not None:
        keep = keep[model.frequencies[keep] <= 2 * np.pi * spec.max_frequency]
    if keep.size == 0:
        raise FieldError("max_frequency", "keeps no elastic mode")
    selected = np.zeros(model.n_modes, dtype=bool)
    selected[rigid] = True
    selected[keep] = True
    damping = model.damping[selected].copy()
    if spec.damping is not None:
        zeta = np.atleast_1d(np.asarray(spec.damping, float))
        if zeta.size not in (1, keep.size) or zeta.ndim != 1:
            raise FieldError(
                "damping", f"one ratio or one per kept elastic mode ({keep.size}), got {zeta.size}"
            )
        if not np.all(np.isfinite(zeta)) or np.any(zeta < 0) or np.any(zeta >= 1):
            raise FieldError("damping", f"ratios in [0, 1), got {spec.damping!r}")
        damping[np.count_nonzero(rigid) :] = zeta
    return replace(
        model,
        frequencies=model.frequencies[selected],
        damping=damping,
        shapes=model.shapes[selected],
        participation=model.participation[selected],
    )


@dataclass(frozen=True)
class LawDesign:
    """A designed law: its arrays (gains, filters, closed-loop poles) and facts."""

    arrays: dict[str, np.ndarray]
    info: dict[str, Any]


def _designed(spec: LawSpec, plant: FlexibleSpacecraft, dt: float) -> LawDesign:
    return LawDesign(*design_law(spec, plant, dt))


def _law_summary(spec: LawSpec, design: LawDesign) -> dict[str, Any]:
    return law_summary(spec, design.arrays, design.info)


def _write_law(design: LawDesign, folder: Path) -> None:
    write_arrays(folder, design.arrays, design.info)


def _read_law(folder: Path) -> LawDesign:
    return LawDesign(*read_arrays(folder))


def _write_run(result: SimResult, folder: Path) -> None:
    from flexsat.netcdf import write_netcdf

    write_netcdf(result.dataset, folder / "run.nc")
    metrics = {
        name: [None if not np.isfinite(v) else float(v) for v in np.ravel(values)]
        for name, values in result.metrics.items()
    }
    (folder / "metrics.json").write_text(canonical_json(metrics), encoding="utf-8")


def _read_run(folder: Path) -> SimResult:
    import xarray as xr

    from flexsat.sim import SimResult

    with xr.open_dataset(folder / "run.nc", engine="h5netcdf") as ds:
        dataset = ds.load()
    metrics = json.loads((folder / "metrics.json").read_text(encoding="utf-8"))
    return SimResult(
        dataset, {name: np.array(values, dtype=float) for name, values in metrics.items()}
    )


#: the reference attitude (Euler parameters, scalar first)
IDENTITY = np.array([1.0, 0.0, 0.0, 0.0])


def run_metrics(result: SimResult, target: np.ndarray = IDENTITY) -> dict[str, float]:
    """Key numbers of a run (its first case, :func:`batch_metrics`)."""
    return {name: float(values[0]) for name, values in batch_metrics(result, target).items()}


def batch_metrics(result: SimResult, target: np.ndarray = IDENTITY) -> dict[str, np.ndarray]:
    """Key numbers of each case of a run, (n_cases,) each: the final attitude error angle (rad,
    the rotation 2 arccos|β_tᵀβ| from the final attitude to the law's ``target``), the peak
    torque and force, and the peak and final node displacement (m, largest over the recorded
    nodes). Each case's numbers are reductions over its own samples only."""
    ds = result.dataset
    beta = ds["attitude"].transpose("case", "time", ...).values
    cosine = np.minimum(1.0, np.abs(beta[:, -1] @ np.asarray(target, float)))

    def peak(name: str) -> np.ndarray:
        v = np.abs(ds[name].transpose("case", "time", ...).values)
        return v.reshape(v.shape[0], -1).max(axis=1)

    names = [str(name) for name in ds.data_vars if str(name).startswith("displacement_")]
    displacement = np.abs(
        np.stack([ds[name].transpose("case", "time").values for name in names], -1)
    )
    metrics = {
        "final_attitude_error_rad": 2 * np.arccos(cosine),
        "peak_torque_N_m": peak("torque"),
        "peak_displacement_m": displacement.max(axis=(1, 2)),
        "final_displacement_m": displacement[:, -1].max(axis=1),
    }
    forces = [str(name) for name in ds.data_vars if str(name).startswith("force_")]
    if forces:
        metrics["peak_force_N"] = np.max(np.stack([peak(f) for f in forces]), axis=0)
    return metrics


# -- the kind -------------------------------------------------------------------------------------
@dataclass(frozen=True)
class DesignStudyResult(ReportedResult):
    """Every stage of a design study: its record, the kept modes, the placement, the laws and
    the runs.

    Attributes
    ----------
    scenario : DesignStudyScenario
    records : tuple of flexsat.design.stages.StageRecord
        One per stage, in order.
    modes : ModalModel
        The kept modes.
    placement : PlacementResult
    laws : dict of str to LawDesign
    results : tuple of SimResult
        One per run.
    case_source : str
    dispersions : DispersionsResult or None
        The Monte Carlo of the nominal laws on the dispersed spacecraft
        (:mod:`flexsat.scenarios.design_dispersions`).
    """

    report_title = "flexsat design study"

    scenario: DesignStudyScenario
    records: tuple[StageRecord, ...]
    modes: ModalModel
    placement: PlacementResult
    laws: dict[str, LawDesign]
    results: tuple[SimResult, ...]
    case_source: str
    dispersions: DispersionsResult | None = None

    def report_case(self) -> str:
        model = self.scenario.model
        return f"case {model.case}" if model.case is not None else f"model file {model.file}"

    def metrics_records(self) -> list[dict[str, Any]]:
        """One JSON-ready dict per run: ``"run"`` and :func:`run_metrics` (the error from its
        law's target)."""
        return [
            {"run": run.label, **run_metrics(result, self.target(run.law))}
            for run, result in zip(self.scenario.runs, self.results)
        ]

    def target(self, law: str) -> np.ndarray:
        """The attitude law ``law`` turns to (a perturbation law's maneuver target, else the
        reference attitude)."""
        return np.asarray(self.laws[law].arrays.get("beta_target", IDENTITY))

    def dataset(self) -> xr.Dataset:
        """The runs (dims run × time) with the attitude each law turns to
        (``target_attitude``), the kept modes (``frequency_hz``, ``damping`` over ``mode``)
        and every stage's fingerprint and origin in the attributes."""
        from flexsat.scenarios.datasets import add_run_metrics, concat_runs

        ds = concat_runs(self.results, [run.label for run in self.scenario.runs])
        add_run_metrics(ds, self.metrics_records())
        targets = np.stack([self.target(run.law) for run in self.scenario.runs])
        ds["target_attitude"] = (("run", "attitude_component"), targets, {"units": ""})
        ds["frequency_hz"] = ("mode", self.modes.frequencies_hz, {"units": "Hz"})
        ds["damping"] = ("mode", self.modes.damping, {"units": ""})
        ds.attrs.update(
            scenario_name=self.scenario.name,
            case=self.report_case(),
            case_source=self.case_source,
            scenario_yaml=self.scenario.yaml_text,
            placement=", ".join(self.placement.selection),
            **{
                f"stage_{r.stage.label}": f"{r.stage.key} ({'cache' if r.cached else 'fresh'})"
                for r in self.records
            },
        )
        return ds

    def write_data(self, folder: Path, ds: xr.Dataset) -> None:
        """``metrics.json`` and ``results.nc``, and with dispersions ``dispersions.json`` and
        the cases' store (:func:`flexsat.report.design_study.write_dispersions`)."""
        from flexsat.report.design_study import write_dispersions

        super().write_data(folder, ds)
        write_dispersions(self.dispersions, folder)

    def figures(self, folder: Path, ds: xr.Dataset) -> list[str]:
        from flexsat.report.design_study import dispersion_figures, draw_figures

        return draw_figures(ds, folder) + dispersion_figures(self.dispersions, folder)

    def sections(self, ds: xr.Dataset, figures: list[str]) -> str:
        from flexsat.report.design_study import sections

        return sections(self, figures)


class DesignStudyKind(ScenarioKind):
    """``kind: design_study``: the stages of the module docstring, each read from the stage
    cache when its fingerprint is there."""

    kind = "design_study"
    document = DesignStudyScenario

    def steps(self, scenario: DesignStudyScenario) -> int:
        return 3 + len(scenario.laws) + len(scenario.runs) + dispersions_steps(scenario)

    def plan(self, scenario: DesignStudyScenario) -> Generator[Run, Any, DesignStudyResult]:
        """One run per stage: the model, modes, placement and law stages are analyses, a run
        stage is a simulation when it is not in the cache."""
        from flexsat.sim import SimConfig

        stages = stage_plan(scenario)
        cache = StageCache(scenario.cache_folder)
        records: list[StageRecord] = []

        def staged(
            path: str,
            compute: Callable[[], Any],
            write: Callable[[Any, Path], None],
            read: Callable[[Path], Any],
            summary: Callable[[Any], dict[str, Any]],
        ) -> Run:
            stage = stages[path]

            def task() -> Any:
                value, record = cache.get(stage, compute, write, read, summary)
                records.append(record)
                return value

            return Run(stage.label, task, path)

        def solved() -> tuple[ModalModel, StageRecord]:
            return cache.get(
                stages["model"],
                lambda: modal_model_of(scenario.model, scenario.folder),
                _write_model,
                _read_model,
                _model_summary,
            )

        def model_stage() -> ModalModel | None:
            # with the modes in the cache the model is not read (the cases of a batch read
            # only what they recompute): its record comes from its summary
            if cache.entry(stages["modes"]).is_dir():
                record = cache.recorded(stages["model"])
                if record is not None:
                    records.append(record)
                    return None
            model, record = solved()
            records.append(record)
            return model

        raw = yield Run("model", model_stage, "model")
        model = yield staged(
            "modes",
            lambda: kept_modes(raw if raw is not None else solved()[0], scenario.modes),
            _write_model,
            _read_model,
            _model_summary,
        )
        placement = yield staged(
            "placement",
            lambda: place_actuators(model, scenario.placement),
            write_placement,
            read_placement,
            lambda p: {"selection": list(p.selection), "criterion_value": p.criterion_value},
        )
        try:
            plant = spacecraft(model, scenario.placement, placement)
        except ValueError as exc:
            raise ScenarioError([locate("placement", exc)]) from None
        try:
            config = SimConfig(**given_fields(scenario.simulation))
        except ValueError as exc:
            raise ScenarioError([Problem("simulation", f"{exc}")]) from None
        flown: FlexibleSpacecraft | None = None  # the truth the runs fly on, when one runs
        laws: dict[str, LawDesign] = {}
        for index, law in enumerate(scenario.laws):
            laws[law.label] = yield staged(
                f"laws{item_path(index, law.label)}",
                functools.partial(_designed, law, plant, config.dt),
                _write_law,
                _read_law,
                functools.partial(_law_summary, law),
            )
        specs = {law.label: law for law in scenario.laws}
        results = []
        for index, run in enumerate(scenario.runs):
            path = f"runs{item_path(index, run.label)}"
            stage = stages[path]
            start = time.perf_counter()
            found = cache.read(stage, _read_run)
            if found is not None:
                seconds = time.perf_counter() - start
                target = laws[run.law].arrays.get("beta_target", IDENTITY)
                records.append(StageRecord(stage, True, seconds, run_metrics(found, target)))
                results.append((yield Run(stage.label, lambda found=found: found, path)))
                continue
            if flown is None:
                flown = flown_plant(scenario, plant)
                run_config = flight_config(scenario, flown)
            try:
                x0 = flown.state_from(**given_fields(run.initial))
            except ValueError as exc:
                raise ScenarioError([locate(f"{path}.initial", exc)]) from None
            controller = law_controller(specs[run.law], laws[run.law].arrays, plant, config.dt)
            start = time.perf_counter()
            result = yield Run(
                stage.label,
                Simulation(flown, controller, run_config, {"n_cases": 1, "initial_state": x0}),
                path,
            )
            seconds = time.perf_counter() - start
            cache.write(stage, functools.partial(_write_run, result))
            target = laws[run.law].arrays.get("beta_target", IDENTITY)
            records.append(StageRecord(stage, False, seconds, run_metrics(result, target)))
            results.append(result)
        dispersed = None
        if scenario.dispersions is not None:

            def dispersions(progress: Callable[[str], None] | None = None) -> DispersionsResult:
                outcome, record = run_dispersions(
                    scenario,
                    stages["dispersions"],
                    placement,
                    laws,
                    progress,
                    lambda: raw if raw is not None else solved()[0],
                    model,
                )
                records.append(record)
                return outcome

            dispersed = yield Run("dispersions", dispersions, "dispersions", reports_progress=True)
        return DesignStudyResult(
            scenario,
            tuple(records),
            model,
            placement,
            laws,
            tuple(results),
            _source(scenario),
            dispersed,
        )


def _source(scenario: DesignStudyScenario) -> str:
    from flexsat.catalog import get_case
    from flexsat.references import cite

    if scenario.model.case is not None:
        return cite(get_case(scenario.model.case).source)
    return f"ModalModel file {scenario.model.file}"


__all__ = [
    "MODEL_CASES",
    "DesignStudyKind",
    "DesignStudyResult",
    "DesignStudyScenario",
    "batch_metrics",
    "flight_config",
    "flight_sections",
    "flown_plant",
    "kept_modes",
    "modal_model_of",
    "run_metrics",
    "stage_plan",
]
