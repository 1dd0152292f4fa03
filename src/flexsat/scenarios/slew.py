"""Slew scenarios (``kind: slew``): a frequency-shaped optimal three-axis slew of a flexible
spacecraft with gain-scheduled perturbation feedback, judged against
the EPS slew study c. 1989 goals.

The method of the EPS slew study c. 1989 (after Chun, Turner & Juang 1987): a rigid-body optimal
nominal maneuver (:func:`~flexsat.maneuvers.three_axis_slew.three_axis_slew`, the TPBVP solved
by continuation) is applied open loop to the flexible plant, and perturbation feedback designed
on a reduced flexible model linearised along the nominal (frequency-shaped LQR with cross
weight, gains interpolated in time, disturbance feedforward, optionally the point forces with
force/torque decoupling) corrects it::

    kind: slew
    name: EPS 10 s slew, EPS slew study c. 1989 cases A-C
    case: eps
    plant: {n_modes: 45}
    maneuver:
      target: {euler123: ["1 rad", "1 rad", "1 rad"]}
      duration: "10 s"
      break_frequency: "2.5 rad/s"
    controller: {modes: 10, linearization_points: 21}
    simulation: {duration: "12.5 s", control_rate: "100 Hz"}
    runs:
      - label: "A: torquers only"
        weights: {attitude: 1000, rate: 1000, modes: 1, torque: 50}
        break_frequency: "2.5 rad/s"

Every scenario also runs the nominal torque alone (the run ``open loop``): the deflection goal
compares each run with it.

A run may plan its torque history over the whole maneuver (:mod:`flexsat.design.planned_slew`:
the nominal plus a sine-series correction bringing the design modes to rest at T at the least
torque energy, or the least peak, within a torque limit), flown alone or under the run's
perturbation law designed along the planned trajectory::

      - label: planned
        shaping: {kind: planned, basis: 30, objective: energy, torque_limit: "34.4 kN m",
                  feedback: false}     # weights and break_frequency then not needed
      - label: planned + feedback
        weights: {attitude: 1000, rate: 1000, modes: 1, torque: 1000}
        break_frequency: "5 rad/s"
        shaping: {kind: planned}       # feedforward: none (the plan carries its modal load)

``basis`` sines per axis (default 30), ``objective`` ``energy`` or ``peak``, ``torque_limit``
on every axis (optional), ``samples`` where the limit holds (default 16 × basis + 1),
``iterations`` relinearisations (default 4). ``forces`` (``none``, ``all`` or a list such as
``[66Z, 60Z]``, the plant's force actuators as the run's ``forces`` names them) plans point
forces beside the torque, each its own sine series, with ``force_limit`` on every force
(optional; required with ``objective: peak``, together with ``torque_limit``) and
``force_weight`` w_F (m², default 1: the energy is ∫‖Δτ‖² + w_F‖F‖² dt). Flown with the
feedback on top, the run's own ``forces`` must include the planned ones (the law adds its
force perturbations to the plan's). The plan's numbers (peak torques, active limits
and their multipliers, the KKT residual, the terminal residual by iteration, or the least peak
when the limit cannot be met) are in the result's notes.

The simulated (truth) plant may depart from the case's plant, which stays the design model —
the nominal maneuver and every perturbation design use the case's plant; only the plant they
are flown on changes (a dispersion of the truth, as a Monte Carlo draws it)::

    truth:
      inertia_scale: [1.03, 0.97, 1.01]   # principal moments of J × these (or one factor)
      frequency_scale: 0.95               # elastic frequencies Ω × this (or one per mode)
      damping: 0.004                      # modal damping ratio ζ (or one per mode)
    sensors: {rate: {noise: "1e-5 rad/s"}, attitude: {noise: 1.0e-5}}

The inertia is scaled in its principal axes, J' = R diag(s λ) Rᵀ with J = R diag(λ) Rᵀ, so it
stays symmetric; one that violates the triangle inequality, or that the modes' rotational
participation Δ then exceeds (J' − ΔᵀΔ not positive definite), is refused under
``truth.inertia_scale``. ``sensors`` puts a sensor (noise, bias, quantum, range in the
channel's unit: ``attitude`` is the quaternion, dimensionless; ``rate`` rad/s) on an output the
laws read; its noise is drawn from ``simulation.seed``. The goal verdicts ``angle_goal_met``,
``deflection_goal_met`` and ``goals_met`` (both) are metrics of every run (``metrics.json``),
so a Monte Carlo requirement can address them (``runs['A: torquers'].goals_met: {min: 1}``).

The nominal maneuver and the perturbation designs are kept for the last few nominal setups
(:func:`nominal_design`, keyed by the document's fields they depend on): the cases of a
Monte Carlo of the truth on one worker design once.

``plant`` holds the keyword arguments of the case's flexible plant (:meth:`plant`, which must
build a
:class:`~flexsat.dynamics.flexible_spacecraft.FlexibleSpacecraft`). Weights are the diagonal
of Q over [attitude error (rad), rate (rad/s), modal amplitudes, modal rates] and of D over
[normalized torques (rad/s², the torque divided by the inertia as in the paper), forces (N)],
SI numbers; one value fills its block.
"""

from __future__ import annotations

import hashlib
import json
import re
from collections import OrderedDict
from collections.abc import Generator
from dataclasses import dataclass
from typing import TYPE_CHECKING, Annotated, Any, Literal, Self

import numpy as np
from pydantic import Field, field_validator, model_validator

from flexsat import limits
from flexsat.catalog import get_case
from flexsat.design.slew_weights import SlewWeights, nominal_histories, rim_nodes, slew_run_metrics
from flexsat.input_checks import FieldError
from flexsat.report.page import ReportedResult
from flexsat.scenarios.datasets import concat_runs
from flexsat.scenarios.errors import Problem, ScenarioError, item_path, locate
from flexsat.scenarios.fields import (
    Document,
    SchemaSection,
    check_unique_labels,
    given_fields,
    in_unit,
    integer_in,
)
from flexsat.scenarios.kind import Run, ScenarioKind, Simulation
from flexsat.scenarios.simulation import ChannelSensorSpec, SimulationSettings, target_quaternion
from flexsat.scenarios.slew_planned import (
    PlannedShapingSpec,
    force_channels,
    plan_for_run,
    plan_note,
)
from flexsat.sim.slew_goals import euler_angle_error

if TYPE_CHECKING:
    import xarray as xr

    from flexsat.control.base import Controller
    from flexsat.dynamics.flexible_spacecraft import FlexibleSpacecraft
    from flexsat.maneuvers.three_axis_slew import ThreeAxisSlew
    from flexsat.report.interactive import Plot
    from flexsat.sim import SimConfig, SimResult

#: one weight, or one per component of its block
Weights = float | list[float]

OPEN_LOOP = "open loop"

#: the maneuver's fields by the names :func:`~flexsat.maneuvers.three_axis_slew` gives them
_MANEUVER_FIELDS = {
    "omega_b": "break_frequency",
    "zeta_b": "shaping_damping",
    "Q": "rate_weight",
}
#: the run's fields by the names :func:`~flexsat.control.perturbation_design` gives them
_DESIGN_FIELDS = {
    "omega_b": "break_frequency",
    "zeta_b": "shaping_damping",
    "n_points": "controller.linearization_points",
    "Q": "weights",
    "D": "weights",
}


class SlewManeuverSpec(SchemaSection):
    """The nominal rigid-body maneuver (EPS slew study c. 1989 Eqs. 9–21)."""

    target: dict[str, Any]
    duration: Annotated[float, in_unit("s", positive=True)]
    break_frequency: Annotated[float, in_unit("rad/s", positive=True)]
    shaping_damping: float = Field(0.0, ge=0.0)
    rate_weight: float = Field(0.0, ge=0.0)

    @field_validator("target")
    @classmethod
    def _rotation(cls, target: dict[str, Any]) -> dict[str, Any]:
        if not target:
            raise FieldError(
                "target",
                "give euler123 (three angles) or attitude (a unit quaternion, scalar first)",
            )
        beta = target_quaternion(target)
        assert beta is not None  # of a target that is not empty
        if beta.shape != (4,) or abs(np.linalg.norm(beta) - 1.0) > 1e-9:
            raise FieldError(
                "target.attitude",
                "must be a unit quaternion (4 values, norm 1 to "
                f"1e-9), got {np.round(beta, 12).tolist()}",
            )
        return target


class ControllerSpec(SchemaSection):
    """The reduced design model and the gain schedule."""

    modes: Annotated[int, integer_in(1, 500)] = 10
    linearization_points: Annotated[int, integer_in(1, 1000)] = 11


class GoalsSpec(SchemaSection):
    """The goals of EPS slew study c. 1989 "Simulation Results"
    (:class:`~flexsat.sim.slew_goals.SlewGoals`)."""

    angle_fraction: float = Field(0.03, gt=0.0, le=1.0)
    evaluation: float = Field(1.25, ge=1.0)
    deflection_ratio: float = Field(10.0, gt=0.0)


#: one dimensionless factor, or one per component
Factors = float | list[float]


def _positive_factors(value: Factors, field: str, count: int | None = None) -> Factors:
    """``value`` if every factor is finite and positive (and, for a list, ``count`` long when
    ``count`` is given)."""
    values = value if isinstance(value, list) else [value]
    if isinstance(value, list) and count is not None and len(value) != count:
        raise FieldError(field, f"give one factor or {count}, got {len(value)}")
    for i, v in enumerate(values):
        if not (np.isfinite(v) and v > 0.0):
            item = f"item {i} " if isinstance(value, list) else ""
            raise FieldError(field, f"{item}must be a finite number > 0, got {v!r}")
    return value


class TruthSpec(SchemaSection):
    """The simulated plant's departures from the case's plant (module docstring)."""

    inertia_scale: Factors = 1.0
    frequency_scale: Factors = 1.0
    damping: Factors | None = None

    @field_validator("inertia_scale")
    @classmethod
    def _inertia(cls, value: Factors) -> Factors:
        return _positive_factors(value, "inertia_scale", 3)

    @field_validator("frequency_scale")
    @classmethod
    def _frequencies(cls, value: Factors) -> Factors:
        return _positive_factors(value, "frequency_scale")

    @field_validator("damping")
    @classmethod
    def _damping(cls, value: Factors | None) -> Factors | None:
        values = value if isinstance(value, list) else [value]
        for i, v in enumerate(values):
            if v is not None and not (np.isfinite(v) and v >= 0.0):
                item = f"item {i} " if isinstance(value, list) else ""
                raise FieldError("damping", f"{item}must be a finite damping ratio >= 0, got {v!r}")
        return value


class SlewWeightsSpec(SchemaSection):
    """Diagonal weights of the perturbation design (module docstring)."""

    attitude: Weights
    rate: Weights
    modes: Weights
    mode_rates: Weights | None = None
    torque: Weights
    force: Weights | None = None


class SlewRunSpec(SchemaSection):
    """One closed-loop run: its weights, shaping, forces and feedforward (or a planned torque
    history, flown alone or under the feedback)."""

    label: str
    weights: SlewWeightsSpec | None = None
    break_frequency: Annotated[float | None, in_unit("rad/s", positive=True)] = None
    shaping_damping: float = Field(0.0, ge=0.0)
    forces: Literal["none", "all"] | list[str] = "none"
    decouple: bool = False
    feedforward: Literal["none", "constant", "time-varying"] = "constant"
    shaping: PlannedShapingSpec | None = None

    @property
    def has_feedback(self) -> bool:
        """The run flies a perturbation law (not a planned torque alone)."""
        return self.shaping is None or self.shaping.feedback

    @field_validator("label")
    @classmethod
    def _not_open_loop(cls, label: str) -> str:
        if label == OPEN_LOOP:
            raise FieldError(
                "label",
                f"{OPEN_LOOP!r} names the nominal torque alone, which every "
                "slew scenario runs; choose another label",
            )
        return label

    @model_validator(mode="after")
    def _force_weights(self) -> Self:
        if self.has_feedback:
            for name in ("weights", "break_frequency"):
                if getattr(self, name) is None:
                    raise FieldError(
                        name,
                        "required for a perturbation law (leave it out only with "
                        "shaping.feedback: false, a planned torque flown alone)",
                    )
        if self.shaping is not None:
            if not self.shaping.feedback and (self.forces != "none" or self.decouple):
                raise FieldError(
                    "forces",
                    "a plan flown alone has no feedback forces (plan them with "
                    "shaping.forces, or give shaping.feedback: true)",
                )
            if "feedforward" in self.model_fields_set and self.feedforward != "none":
                raise FieldError(
                    "feedforward",
                    "must be none with a planned torque: the plan carries the modal load "
                    "of its own torque (its modal motion is the feedback's reference), "
                    f"got {self.feedforward!r}",
                )
            self.feedforward = "none"
        if self.weights is None:
            return self
        if self.forces != "none" and self.weights.force is None:
            raise FieldError("weights.force", "required when the run uses forces")
        if self.decouple and self.forces == "none":
            raise FieldError(
                "decouple",
                "needs forces (decoupling keeps the forces' net moment "
                "about the centre of mass zero)",
            )
        return self


class SlewScenario(Document):
    """A validated slew scenario (module docstring)."""

    kind: Literal["slew"]
    name: str
    case: str
    plant: dict[str, Any] = Field(default_factory=dict)
    truth: TruthSpec = Field(default_factory=TruthSpec)
    sensors: dict[str, ChannelSensorSpec] = Field(default_factory=dict)
    maneuver: SlewManeuverSpec
    controller: ControllerSpec = Field(default_factory=ControllerSpec)
    simulation: SimulationSettings
    goals: GoalsSpec = Field(default_factory=GoalsSpec)
    runs: list[SlewRunSpec] = Field(min_length=1, max_length=limits.MAX_RUNS)

    @field_validator("case")
    @classmethod
    def _known_case(cls, name: str) -> str:
        from flexsat.scenarios.simulation import simulation_cases

        get_case(name)
        if name not in simulation_cases():
            raise FieldError(
                "case",
                f"{name!r} builds no plant to slew; cases with one: "
                f"{', '.join(simulation_cases())}",
            )
        return name

    @model_validator(mode="after")
    def _checks(self) -> Self:
        check_unique_labels(self.runs)
        # the nominal torque is played back and the feedback runs at the control rate: a
        # shaping break above its Nyquist frequency π f_c shapes what neither can produce
        nyquist = np.pi * self.simulation.control_rate
        breaks = [("maneuver.break_frequency", self.maneuver.break_frequency)] + [
            (f"runs{item_path(i, r.label)}.break_frequency", r.break_frequency)
            for i, r in enumerate(self.runs)
            if r.break_frequency is not None
        ]
        for field, value in breaks:
            if value > nyquist:
                raise FieldError(
                    field,
                    f"must be at most the control's Nyquist frequency π × "
                    f"simulation.control_rate = {nyquist:.4g} rad/s, got {value:.4g} rad/s",
                )
        if self.simulation.duration < self.goals.evaluation * self.maneuver.duration:
            raise FieldError(
                "simulation.duration",
                f"must reach {self.goals.evaluation:g} × the "
                f"maneuver duration ({self.goals.evaluation * self.maneuver.duration:g}"
                f" s) where the goals are evaluated, got "
                f"{self.simulation.duration:g} s",
            )
        return self


# -- running -------------------------------------------------------------------------------------
@dataclass(frozen=True)
class SlewResult(ReportedResult):
    """The runs of a slew scenario: the nominal maneuver, the open-loop run (the nominal torque
    alone) and every closed-loop run, with the goal metrics of each.

    Attributes
    ----------
    scenario : SlewScenario
    labels : tuple of str
        ``open loop`` then the scenario's runs.
    results : tuple of flexsat.sim.SimResult
    nominal : flexsat.maneuvers.three_axis_slew.ThreeAxisSlew
    goals : dict of str to (n_runs,) arrays
        :func:`~flexsat.sim.slew_goals.slew_goal_metrics` of every run (units in
        ``goal_units``).
    goal_units : dict of str to str
    case_source : str
    notes : tuple of str
        What the reader should know about the runs (design choices the scenario left open).
    """

    scenario: SlewScenario
    labels: tuple[str, ...]
    results: tuple[SimResult, ...]
    nominal: ThreeAxisSlew
    goals: dict[str, np.ndarray]
    goal_units: dict[str, str]
    case_source: str
    notes: tuple[str, ...] = ()

    def attributes(self) -> dict[str, float]:
        g = self.scenario.goals
        return {
            "duration_s": self.scenario.maneuver.duration,
            "goal_angle_fraction": g.angle_fraction,
            "goal_evaluation": g.evaluation,
            "goal_deflection_ratio": g.deflection_ratio,
            "goal_angle_tolerance_mrad": float(self.goals["angle_tolerance_mrad"][0]),
        }

    def metrics_records(self) -> list[dict[str, Any]]:
        """One JSON-ready dict per run: ``"run"`` and the goal metrics (NaN, inf -> None)."""
        records = []
        for i, label in enumerate(self.labels):
            row: dict[str, Any] = {"run": label}
            for name, values in self.goals.items():
                v = values[i]
                row[name] = (
                    bool(v)
                    if isinstance(v, (bool, np.bool_))
                    else (float(v) if np.isfinite(v) else None)
                )
            records.append(row)
        return records

    def dataset(self) -> xr.Dataset:
        """Every run in one dataset (:mod:`flexsat.report.slew` lists its variables)."""
        ds = concat_runs(self.results, self.labels)
        t = ds["time"].values
        nominal_torque, nominal_angles = nominal_histories(self.nominal, t)
        ds["nominal_torque"] = (("time", "torque_component"), nominal_torque, {"units": "N*m"})
        ds["nominal_euler123"] = (("time", "euler123_component"), nominal_angles, {"units": "rad"})
        ds["euler123_error"] = (
            ("run", "time", "euler123_component"),
            euler_angle_error(ds["euler123"].transpose("run", "time", ...).values, nominal_angles),
            {"units": "rad"},
        )
        ds["torque_perturbation"] = (
            ("run", "time", "torque_component"),
            ds["torque"].transpose("run", "time", ...).values - nominal_torque,
            {"units": "N*m"},
        )
        for node in rim_nodes(ds):
            parts = np.stack(
                [ds[f"displacement_{node}{a}"].transpose("run", "time").values for a in "XYZ"], -1
            )
            ds[f"rim_deflection_{node}"] = (
                ("run", "time"),
                np.linalg.norm(parts, axis=-1),
                {"units": "m"},
            )
        for name, values in self.goals.items():
            ds[name] = ("run", np.asarray(values), {"units": self.goal_units.get(name, "")})
        ds.attrs.update(
            scenario_name=self.scenario.name,
            case=self.scenario.case,
            case_source=self.case_source,
            scenario_yaml=self.scenario.yaml_text,
            **self.attributes(),
        )
        return ds

    def plots(self, ds: xr.Dataset) -> list[Plot]:
        from flexsat.report.slew import plots

        return plots(ds)

    def sections(self, ds: xr.Dataset, figures: list[str]) -> str:
        from flexsat.report.slew import sections

        return sections(self, self.metrics_records(), figures)


def _weights(
    run: SlewRunSpec, index: int, n_modes: int, n_forces: int
) -> tuple[np.ndarray, np.ndarray]:
    """(Q, D) of a run, diagonal, over [δα, δω, δη, δη̇] and [torque/I, forces]."""
    assert run.weights is not None  # required of a run with feedback
    try:
        q, d = SlewWeights(**run.weights.model_dump()).diagonals(n_modes, n_forces)
    except ValueError as exc:
        raise ScenarioError([locate(f"runs{item_path(index, run.label)}.weights", exc)]) from None
    return np.diag(q), np.diag(d)


def _forces(run: SlewRunSpec, index: int, plant: FlexibleSpacecraft) -> list[str]:
    """The run's force channels, by the plant's names (``69X`` -> ``force_69X``)."""
    return force_channels(run.forces, f"runs{item_path(index, run.label)}.forces", plant)


def _case_plant(scenario: SlewScenario) -> FlexibleSpacecraft:
    """The case's flexible plant as given (the design model's and the nominal truth)."""
    from flexsat.dynamics.flexible_spacecraft import FlexibleSpacecraft
    from flexsat.scenarios.simulation import build_plant

    plant = build_plant(scenario)
    if not isinstance(plant, FlexibleSpacecraft):
        raise ScenarioError(
            [
                Problem(
                    "plant",
                    f"the {scenario.case} plant with these options is a "
                    f"{type(plant).__name__}; a slew needs a flexible spacecraft "
                    "(model: flexible)",
                )
            ]
        )
    outputs = {c.name for c in plant.outputs}
    nodes = {n[len("displacement_") : -1] for n in outputs if n.startswith("displacement_")}
    if not any(all(f"displacement_{n}{a}" in outputs for a in "XYZ") for n in nodes):
        # the deflection goal compares rim deflections: refused now, not after every run
        raise ScenarioError(
            [
                Problem(
                    "plant.rim_nodes" if "rim_nodes" in scenario.plant else "plant",
                    f"the {scenario.case} plant with these options records no rim displacement "
                    "along X, Y and Z (outputs displacement_<node>X/Y/Z), so the deflection "
                    "goal cannot be judged; give at least one rim node",
                )
            ]
        )
    if scenario.controller.modes > plant.n_modes:
        raise ScenarioError(
            [
                Problem(
                    "controller.modes",
                    f"at most the plant's {plant.n_modes} elastic "
                    f"modes, got {scenario.controller.modes}",
                )
            ]
        )
    return plant


def _per_mode(value: Factors, n_modes: int, field: str) -> np.ndarray:
    """One value per elastic mode from one value or a list of ``n_modes``."""
    if isinstance(value, list) and len(value) != n_modes:
        raise ScenarioError(
            [
                Problem(
                    field,
                    f"give one value or {n_modes} (the plant's elastic modes), got {len(value)}",
                )
            ]
        )
    return np.broadcast_to(np.asarray(value, float), (n_modes,))


def truth_plant(scenario: SlewScenario, plant: FlexibleSpacecraft) -> FlexibleSpacecraft:
    """The simulated plant: ``plant`` with the ``truth`` section's departures (module
    docstring), ``plant`` itself where there are none.

    The principal moments λ of J (ascending) are scaled, J' = R diag(s λ) Rᵀ; the elastic
    frequencies Ω' = s_Ω Ω; the damping ratios replaced (the modal damping 2ζΩ' formed with the
    new frequencies, :meth:`~flexsat.dynamics.flexible_spacecraft.FlexibleSpacecraft.
    with_parameters`).

    Raises
    ------
    ScenarioError
        Under ``truth.<field>``: a list of another length than the modes, an inertia violating
        the triangle inequality or exceeded by the modes' participation.
    """
    return apply_truth(scenario.truth, plant)


def apply_truth(spec: TruthSpec, plant: FlexibleSpacecraft) -> FlexibleSpacecraft:
    """``plant`` with the departures of a ``truth:`` section ``spec`` (:func:`truth_plant`),
    ``plant`` itself where there are none.

    Raises
    ------
    ScenarioError
        Under ``truth.<field>`` (:func:`truth_plant`).
    """
    changes: dict[str, np.ndarray] = {}
    scale = np.broadcast_to(np.asarray(spec.inertia_scale, float), (3,))
    if np.any(scale != 1.0):
        moments, axes = np.linalg.eigh(plant.inertia)
        inertia = (axes * (scale * moments)) @ axes.T
        changes["inertia"] = 0.5 * (inertia + inertia.T)
    n = plant.n_modes
    frequency_scale = _per_mode(spec.frequency_scale, n, "truth.frequency_scale")
    if np.any(frequency_scale != 1.0):
        changes["frequencies"] = frequency_scale * np.sqrt(plant.stiffness)
    if spec.damping is not None:
        changes["damping"] = _per_mode(spec.damping, n, "truth.damping")
    if not changes:
        return plant
    fields = {"inertia": "inertia_scale", "frequencies": "frequency_scale", "damping": "damping"}
    try:
        return plant.with_parameters(**changes)
    except FieldError as exc:
        field = fields.get(exc.field.split("[")[0], exc.field)
        raise ScenarioError([Problem(f"truth.{field}", exc.rule)]) from None


def _sim_config(scenario: SlewScenario, truth: FlexibleSpacecraft) -> SimConfig:
    """The simulation settings with the ``sensors`` bound to the truth's output channels."""
    from flexsat.sim import SimConfig
    from flexsat.sim.channels import ChannelSensor, resolve_channels

    outputs = [c.name for c in truth.outputs]
    sensors = {}
    for name, spec in scenario.sensors.items():
        if name not in outputs:
            raise ScenarioError(
                [
                    Problem(
                        f"sensors.{name}",
                        f"the plant has no output channel {name!r} (its channels: "
                        f"{', '.join(outputs)})",
                    )
                ]
            )
        try:
            sensors[name] = ChannelSensor(**given_fields(spec))
        except ValueError as exc:
            raise ScenarioError([locate(f"sensors.{name}", exc)]) from None
    try:
        config = SimConfig(**given_fields(scenario.simulation), channel_sensors=sensors)
        resolve_channels(truth, config)  # each sensor's values in its channel's unit
    except FieldError as exc:  # sensors[rate].noise, as the engine names it
        raise ScenarioError(
            [Problem(re.sub(r"^sensors\[(\w+)\]", r"sensors.\1", exc.field), exc.rule)]
        ) from None
    except ValueError as exc:
        raise ScenarioError([Problem("simulation", f"{exc}")]) from None
    return config


#: nominal setups kept by :func:`nominal_design` (a Monte Carlo of the truth needs one; a few
#: more serve a sweep over a design field without designing twice in a row)
DESIGNS_KEPT = 4
_designs: OrderedDict[str, dict[str, Any]] = OrderedDict()


def design_fingerprint(scenario: SlewScenario) -> str:
    """SHA-256 of the document fields the case's plant, the nominal maneuver and the
    perturbation designs depend on (``case``, ``plant``, ``maneuver``, ``controller``,
    ``runs``): not the truth, the sensors, the simulation or the goals."""
    fields = scenario.model_dump(
        mode="json", include={"case", "plant", "maneuver", "controller", "runs"}
    )
    return hashlib.sha256(json.dumps(fields, sort_keys=True).encode()).hexdigest()


def nominal_design(scenario: SlewScenario) -> dict[str, Any]:
    """The kept nominal setup of ``scenario`` (by :func:`design_fingerprint`; the least
    recently used dropped past :data:`DESIGNS_KEPT`): a dict filled as the scenario plans, with
    ``plant`` (the case's plant), ``design_plant``, ``nominal`` (the maneuver) and
    ``designs`` (the perturbation designs by run label). Each is deterministic in those
    fields, so a kept one is the one a fresh run would compute."""
    key = design_fingerprint(scenario)
    entry = _designs.pop(key, None)
    _designs[key] = entry = {} if entry is None else entry
    while len(_designs) > DESIGNS_KEPT:
        _designs.popitem(last=False)
    return entry


def _laws(
    scenario: SlewScenario,
    plant: FlexibleSpacecraft,
    kept: dict[str, Any],
    nominal: ThreeAxisSlew,
    config: SimConfig,
) -> dict[str, Controller]:
    """The open-loop law and every run's perturbation law (or planned torque), by label,
    designed on the case's plant (kept in ``kept["designs"]`` and ``kept["plans"]``);
    problems are gathered and located in their run."""
    from flexsat.control import NominalTorque, perturbation_design
    from flexsat.design.planned_slew import PlannedTrajectory

    dt = config.dt
    design_plant = kept["design_plant"]
    designs = kept.setdefault("designs", {})
    laws: dict[str, Controller] = {OPEN_LOOP: NominalTorque(nominal, dt)}
    problems: list[Problem] = []
    for index, run in enumerate(scenario.runs):
        try:
            reference: Any = nominal
            if run.shaping is not None:
                plan = plan_for_run(run, index, plant, kept, nominal, config)
                if not run.shaping.feedback:
                    laws[run.label] = NominalTorque(plan, dt)
                    continue
                reference = kept.setdefault("trajectories", {}).get(run.label)
                if reference is None:
                    reference = PlannedTrajectory(plan, design_plant, config)
                    kept["trajectories"][run.label] = reference
            if run.label not in designs:
                forces = _forces(run, index, design_plant)
                Q, D = _weights(run, index, design_plant.n_modes, len(forces))
                assert run.break_frequency is not None  # required of a run with feedback
                designs[run.label] = perturbation_design(
                    design_plant,
                    reference,
                    Q,
                    D,
                    run.break_frequency,
                    run.shaping_damping,
                    scenario.controller.linearization_points,
                    forces=forces,
                    decouple=run.decouple,
                )
            # checked against the case's plant: the truth shares its mode shapes, not its
            # frequencies
            laws[run.label] = designs[run.label].controller(dt, run.feedforward, plant=plant)
        except ScenarioError as exc:  # the run's forces or weights
            problems.extend(exc.problems)
        except FieldError as exc:  # named by the scenario's fields
            field = _DESIGN_FIELDS.get(exc.field, exc.field)
            where = (
                ""
                if field.startswith("controller.") or field == "simulation"
                else f"runs{item_path(index, run.label)}"
            )
            problems.append(locate(where, FieldError(field, exc.rule)))
        except ValueError as exc:
            problems.append(locate(f"runs{item_path(index, run.label)}", exc))
    if problems:
        raise ScenarioError(problems)
    return laws


class SlewKind(ScenarioKind):
    """``kind: slew``: solve the nominal maneuver and design every run's perturbation feedback
    on the case's flexible plant, then simulate the open loop and each run on the truth plant
    (the case's plant with the ``truth`` section's departures) and evaluate the goals (module
    docstring)."""

    kind = "slew"
    document = SlewScenario

    def steps(self, scenario: SlewScenario) -> int:
        # the nominal maneuver and the open loop, then the runs
        return len(scenario.runs) + 2

    def plan(self, scenario: SlewScenario) -> Generator[Run, Any, SlewResult]:
        """The runs: the nominal maneuver (its continuation failing is reported under
        ``maneuver``), the open loop, each closed-loop run.

        Raises
        ------
        ScenarioError
            Before any simulation, for a plant option, maneuver or run the case or the design
            refuses.
        """
        from flexsat.maneuvers import three_axis_slew
        from flexsat.references import cite
        from flexsat.sim.slew_goals import SlewGoals

        kept = nominal_design(scenario)
        if "plant" not in kept:
            kept["plant"] = _case_plant(scenario)
            kept["design_plant"] = kept["plant"].reduced(scenario.controller.modes)
        plant, design_plant = kept["plant"], kept["design_plant"]
        truth = truth_plant(scenario, plant)
        config = _sim_config(scenario, truth)
        m = scenario.maneuver

        target = target_quaternion(m.target)
        assert target is not None  # the schema refuses an empty target

        def solve_nominal() -> ThreeAxisSlew:
            if "nominal" not in kept:
                try:
                    kept["nominal"] = three_axis_slew(
                        plant.inertia,
                        target,
                        m.duration,
                        m.break_frequency,
                        m.shaping_damping,
                        Q=m.rate_weight * np.eye(3),
                    )
                except FieldError as exc:  # named by the scenario's fields
                    raise FieldError(_MANEUVER_FIELDS.get(exc.field, exc.field), exc.rule) from None
            nominal: ThreeAxisSlew = kept["nominal"]
            return nominal

        nominal = yield Run("nominal maneuver", solve_nominal, "maneuver")
        laws = _laws(scenario, plant, kept, nominal, config)
        results = []
        for index, (label, law) in enumerate(laws.items()):
            run = Run(
                label,
                Simulation(truth, law, config, {"n_cases": 1}),
                f"runs{item_path(index, label)}",
            )
            results.append((yield run))

        g = scenario.goals
        goals, units = slew_run_metrics(
            results, nominal, SlewGoals(g.angle_fraction, g.evaluation, g.deflection_ratio)
        )
        t = results[0].dataset["time"].values
        notes: tuple[str, ...] = (
            f"Nominal: three-axis TPBVP by continuation in {len(nominal.history)} steps, "
            f"boundary error {nominal.boundary_error():.1e}; peak nominal torques "
            + ", ".join(
                f"{a} {abs(nominal.torque(t[t <= m.duration])[:, i]).max():,.0f} N m"
                for i, a in enumerate("xyz")
            )
            + ".",
            f"Plant: {truth.n_modes} elastic modes; design model: {design_plant.n_modes} "
            f"modes linearised at {scenario.controller.linearization_points} equally spaced "
            f"times, gains interpolated in time."
            + (
                ""
                if truth is plant
                else " Simulated on the truth plant of section truth; the nominal "
                "maneuver and the designs are those of the case's plant."
            ),
        )
        notes += tuple(
            plan_note(r.label, kept["plans"][r.label], r.shaping.torque_limit)
            for r in scenario.runs
            if r.shaping is not None
        )
        return SlewResult(
            scenario,
            tuple(laws),
            tuple(results),
            nominal,
            goals,
            units,
            cite(get_case(scenario.case).source),
            notes,
        )


__all__ = [
    "DESIGNS_KEPT",
    "OPEN_LOOP",
    "SlewKind",
    "SlewResult",
    "SlewScenario",
    "design_fingerprint",
    "nominal_design",
    "truth_plant",
    "apply_truth",
]
