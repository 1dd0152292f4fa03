"""``kind: design``: a design-optimisation problem as data — a registered reference problem,
its variables with bounds and units, the objective, the constraints, the optimiser, and an
optional Pareto front (issue 23 deliverables 1 and 4).

::

    kind: design
    name: hub-boom co-design, mass against LQ cost
    problem: hub_boom_codesign          # a name of REFERENCE_PROBLEMS (or model:, below)
    parameters: {hub_inertia: 0.4 kg*m**2}  # the reference's own fields, with units (optional)
    variables:                          # bounds and start, with units (optional per variable)
      t: {start: 2 mm, lower: 0.5 mm, upper: 3 mm}
      D: {start: 40 mm, lower: 10 mm, upper: 60 mm}
    objective: lq_cost                  # a response of the problem, minimised
    constraints:                        # response >= min and/or <= max, in its unit
      - {response: frequency_hz, min: 6 Hz}
      - {response: mass, max: 0.3 kg}
    optimizer: {method: slsqp, compare: trust-constr}
    pareto: {secondary: mass, points: 40, starts: 3}

Instead of ``problem:``, a ``model:`` section with an inline finite-element model (the
``model: {fe: ...}`` of a simulation scenario) makes the problem your own structure: its
variables name a section (``{section: boom, property: thickness, lower: .., upper: ..}``) or a
lumped mass (``{lumped_mass: 105, property: mass, ...}``) of the model, and its responses are
``mass``, ``frequency_hz_<k>`` and ``separation_hz_<i>_<j>`` with analytic gradients
(:mod:`flexsat.scenarios.design_model`, :mod:`flexsat.design.structure_problem`).
``parameters:`` take units (:mod:`flexsat.scenarios.design_parameters`).

The reference supplies the responses (with their analytic gradients), the variables and their
default starts and bounds; the constraints are those the document lists (the reference's own
are not added: a document without a frequency floor has none). The optimum is one
:func:`~flexsat.design.optimize.optimize_design` with its KKT check (and,
with ``optimizer.compare``, a second optimiser from the same start, reported beside it). The
Pareto front is :func:`flexsat.design.pareto.run_front` of the problem as written (its
variables and constraints; the objective is the front's primary response, ``pareto.secondary``
the other), a batch on dask into a zarr store that a second run resumes; the report's front is
:func:`~flexsat.design.pareto.front_table` of it. ``metrics.json`` holds one record per
optimiser (objective, responses, design, KKT residual, active set, multipliers, its iteration
history and, where the problem describes its designs, their modes, gains and poles), one for
the start and one per front point; the page is drawn by :mod:`flexsat.report.design_problem`.
"""

from __future__ import annotations

import hashlib
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, ClassVar, Literal, Self

import numpy as np
import xarray as xr
from pydantic import Field, model_validator

from flexsat.cases.agrawal_bang_codesign import AgrawalBangCodesign
from flexsat.cases.tamu_codesign import TamuCodesign
from flexsat.design.optimization_problem import (
    Constraint,
    DesignProblem,
    DesignVariable,
    Objective,
)
from flexsat.design.optimize import METHODS, OptimizationResult, optimize_design
from flexsat.design.reference_problems import CantileverTube, HubBoomCodesign
from flexsat.input_checks import FieldError
from flexsat.report.page import ReportedResult, ResultTable
from flexsat.scenarios.design_model import model_problem
from flexsat.scenarios.design_parameters import reference_parameters
from flexsat.scenarios.errors import Problem, ScenarioError, locate
from flexsat.scenarios.fields import Document, SchemaSection, in_unit, integer_in
from flexsat.scenarios.kind import Run, ScenarioKind
from flexsat.scenarios.models import ModelSection, model_label
from flexsat.units import FloatArray, to_si

if TYPE_CHECKING:
    from flexsat.design.pareto import FrontSetup
    from flexsat.report.interactive import Plot

__all__ = [
    "REFERENCE_PROBLEMS",
    "ConfiguredProblem",
    "DesignKind",
    "DesignResult",
    "DesignScenario",
]

#: the reference problems a ``design`` scenario names: class, units of the variables and of
#: the responses (SI)
REFERENCE_PROBLEMS: dict[str, tuple[type, dict[str, str], dict[str, str]]] = {
    "hub_boom_codesign": (
        HubBoomCodesign,
        {"t": "m", "D": "m"},
        {
            "lq_cost": "",
            "mass": "kg",
            "frequency_hz": "Hz",
            "residual_energy": "J",
            "pointing_error_sq": "rad**2",
            "peak_torque": "N*m",
            "soft_settling": "s",
        },
    ),
    "cantilever_tube": (CantileverTube, {"t": "m", "D": "m"}, {"mass": "kg", "omega": "rad/s"}),
    "tamu_codesign": (
        TamuCodesign,
        {"thickness_ratio": "", "g1": "N*m/rad", "g2": "N*m*s/rad", "alpha": ""},
        {
            "soft_settling": "s",
            "itse": "rad**2*s**2",
            "appendage_mass": "kg",
            "decay_rate": "1/s",
            "frequency_hz": "Hz",
        },
    ),
    # the gains of pair i's filter tuned to mode j (N m per unit strain) and, with
    # parameters.tune_filters, the tuning ratios; the placement is parameters.selection
    "agrawal_bang_ppf_codesign": (
        AgrawalBangCodesign,
        {
            **{f"g{i}{j}": "N*m" for i in (1, 2, 3) for j in (1, 2, 3)},
            **{f"nu{i}{j}": "" for i in (1, 2, 3) for j in (1, 2, 3)},
        },
        {
            "h2": "m/N/s**0.5",
            "effort_1": "N*m",
            "effort_2": "N*m",
            "effort_3": "N*m",
            "stiffness_margin": "",
        },
    ),
}

Quantity = str | float | int


class VariableSpec(SchemaSection):
    """Start and bounds of one variable, each in the variable's unit (a bare number is SI);
    with a ``model:``, what it varies: a ``section``, a ``material`` or the ``lumped_mass`` at a
    node, its
    ``property`` and, for an inertia, its ``axis`` (:mod:`flexsat.scenarios.design_model`)."""

    start: Quantity | None = None
    lower: Quantity | None = None
    upper: Quantity | None = None
    section: str | None = None
    material: str | None = None
    lumped_mass: Annotated[int | None, integer_in(-(2**31), 2**31 - 1, optional=True)] = None
    property: str | None = None
    axis: Literal["x", "y", "z"] | None = None


#: the keys of a variable that name what it varies in a ``model:``
MODEL_VARIABLE_KEYS = ("section", "material", "lumped_mass", "property", "axis")


class ConstraintSpec(SchemaSection):
    """``response >= min`` and/or ``response <= max`` (in the response's unit)."""

    response: str
    min: Quantity | None = None
    max: Quantity | None = None

    @model_validator(mode="after")
    def _a_bound(self) -> Self:
        if self.min is None and self.max is None:
            raise FieldError("min", "give min, max or both")
        return self


class OptimizerSpec(SchemaSection):
    method: Literal["slsqp", "trust-constr", "ipopt", "homotopy"] = "slsqp"
    compare: Literal["slsqp", "trust-constr", "ipopt", "homotopy"] | None = None
    tol: float = Field(1e-12, gt=0.0)
    max_iterations: Annotated[int, integer_in(1, 100_000)] = 500


class ParetoSpec(SchemaSection):
    """The front: ``objective`` against ``secondary`` (module docstring)."""

    secondary: str
    scalarisation: Literal["epsilon", "weighted"] = "epsilon"
    points: Annotated[int, integer_in(1, 10_000)] = 40
    starts: Annotated[int, integer_in(1, 1000)] = 3
    seed: Annotated[int, integer_in(0)] = 0
    chunk_size: Annotated[int, integer_in(1)] = 10
    workers: Annotated[int | None, integer_in(1, 1024, optional=True)] = None
    scheduler: str | None = None
    store: str | None = None
    kkt_tol: Annotated[float, in_unit("", positive=True)] = 1e-6


class DesignScenario(Document):
    """The ``design`` document (module docstring)."""

    kind: Literal["design"] = "design"
    name: str = Field(min_length=1)
    case: str = ""
    problem: str | None = None
    model: ModelSection | None = None
    parameters: dict[str, Any] = Field(default_factory=dict)
    variables: dict[str, VariableSpec] = Field(default_factory=dict)
    objective: str
    constraints: list[ConstraintSpec] = Field(default_factory=list)
    optimizer: OptimizerSpec = Field(default_factory=OptimizerSpec)
    pareto: ParetoSpec | None = None

    @model_validator(mode="after")
    def _names(self) -> Self:
        if (self.problem is None) == (self.model is None):
            raise FieldError(
                "problem",
                f"give problem (one of {', '.join(REFERENCE_PROBLEMS)}) or model (your own "
                "inline finite-element model), one of them",
            )
        if self.model is not None:
            _, _, responses = model_problem(self)  # variables and response names, by path
            what = "your model"
        else:
            responses = self._reference_names()
            what = str(self.problem)
        rule = f"must be a response of {what} ({', '.join(responses)})"
        if self.objective not in responses:
            raise FieldError("objective", f"{rule}, got {self.objective!r}")
        for i, c in enumerate(self.constraints):
            if c.response not in responses:
                raise FieldError(f"constraints[{i}].response", f"{rule}, got {c.response!r}")
        if self.pareto is not None:
            if self.pareto.secondary not in responses:
                raise FieldError("pareto.secondary", f"{rule}, got {self.pareto.secondary!r}")
            if self.pareto.secondary == self.objective:
                raise FieldError("pareto.secondary", "must differ from objective")
        ConfiguredProblem.from_scenario(self).problem()  # bounds, units and parameters
        return self

    @property
    def source_label(self) -> str:
        """What the problem is built on: ``reference problem <name>`` or the model's label."""
        if self.model is not None:
            return model_label(self.model)
        return f"reference problem {self.problem}"

    def _reference_names(self) -> dict[str, str]:
        """The responses of the reference problem; its variables and parameters checked."""
        if self.problem not in REFERENCE_PROBLEMS:
            raise FieldError(
                "problem", f"must be one of {', '.join(REFERENCE_PROBLEMS)}, got {self.problem!r}"
            )
        cls, var_units, responses = REFERENCE_PROBLEMS[self.problem]
        reference_parameters(self.problem, cls, self.parameters)
        for key, spec in self.variables.items():
            if key not in var_units:
                raise FieldError(
                    f"variables.{key}",
                    f"not a variable of {self.problem} ({', '.join(var_units)})",
                )
            for name in MODEL_VARIABLE_KEYS:
                if getattr(spec, name) is not None:
                    raise FieldError(
                        f"variables.{key}.{name}", "names a part of a model: (not a reference)"
                    )
        return responses


@dataclass(frozen=True)
class ConfiguredProblem:
    """A reference problem with the scenario's variables, objective and constraints (SI): a
    :class:`~flexsat.design.pareto.BicriteriaReference` (picklable, for dask workers).

    Attributes
    ----------
    reference : the reference problem instance
    variables : tuple of DesignVariable values as (name, start, lower, upper, scale, unit)
    objective : str
    constraints : tuple of (response, min or None, max or None), SI
    """

    reference: Any
    variables: tuple[tuple[str, float, float, float, float, str], ...]
    objective: str
    constraints: tuple[tuple[str, float | None, float | None], ...]
    units: tuple[tuple[str, str], ...]

    @classmethod
    def from_scenario(cls, scenario: DesignScenario) -> ConfiguredProblem:
        reference: Any
        if scenario.model is not None:
            reference, var_units, responses = model_problem(scenario)
        else:
            assert scenario.problem is not None  # DesignScenario: problem or model
            kind, var_units, responses = REFERENCE_PROBLEMS[scenario.problem]
            parameters = reference_parameters(scenario.problem, kind, scenario.parameters)
            named = {scenario.objective, *(c.response for c in scenario.constraints)}
            if scenario.pareto is not None:
                named.add(scenario.pareto.secondary)
            # a reference whose simulated responses cost a run computes them only when named
            if named & set(getattr(kind, "MANEUVER_RESPONSES", ())):
                parameters.setdefault("maneuver", True)
            try:
                reference = kind(**parameters)
            except FieldError as exc:
                path = (
                    exc.field if exc.field.startswith("parameters") else f"parameters.{exc.field}"
                )
                raise FieldError(path, exc.rule) from None
            except (TypeError, ValueError) as exc:
                raise FieldError("parameters", str(exc)) from None
        base = reference.problem()
        variables = []
        for v in base.variables:
            spec = scenario.variables.get(v.name, VariableSpec())
            unit = var_units[v.name]
            start, lower, upper = (
                default if q is None else to_si(q, unit, f"variables.{v.name}.{key}")
                for key, q, default in (
                    ("start", spec.start, v.value),
                    ("lower", spec.lower, v.lower),
                    ("upper", spec.upper, v.upper),
                )
            )
            where = f"variables.{v.name}"
            if v.lower > 0 and not lower > 0:  # a positive quantity (a wall, a gain)
                raise FieldError(f"{where}.lower", f"must be > 0, got {lower} {unit}")
            if not lower < upper:
                raise FieldError(f"{where}.lower", f"must be < upper, got [{lower}, {upper}]")
            if not lower <= start <= upper:
                raise FieldError(f"{where}.start", f"{start} is outside [{lower}, {upper}]")
            variables.append((v.name, start, lower, upper, float(v.scale or 1.0), unit))
        constraints = []
        for i, c in enumerate(scenario.constraints):
            unit = responses[c.response]
            lo = None if c.min is None else to_si(c.min, unit, f"constraints[{i}].min")
            hi = None if c.max is None else to_si(c.max, unit, f"constraints[{i}].max")
            if lo is not None and hi is not None and not lo < hi:
                raise FieldError(f"constraints[{i}].min", f"must be < max, got [{lo}, {hi}]")
            constraints.append((c.response, lo, hi))
        return cls(
            reference,
            tuple(variables),
            scenario.objective,
            tuple(constraints),
            tuple(responses.items()),
        )

    def responses(self, x: FloatArray) -> dict[str, tuple[float, FloatArray]]:
        out = self.reference.responses(x)
        return {k: (float(v[0]), np.asarray(v[1], dtype=float)) for k, v in out.items()}

    def response(self, name: str, sign: float = 1.0, offset: float = 0.0) -> Any:
        def value(x: FloatArray) -> tuple[float, FloatArray]:
            v, g = self.responses(x)[name]
            return sign * (v - offset), sign * g

        return value

    def problem(self) -> DesignProblem:
        variables = tuple(
            DesignVariable(n, s, lo, hi, scale=sc, unit=u) for n, s, lo, hi, sc, u in self.variables
        )
        x0 = np.array([v.value for v in variables])
        r0 = self.responses(x0)
        units = dict(self.units)
        cons = []
        for name, lo, hi in self.constraints:
            for bound, sign, label in ((lo, -1.0, ">="), (hi, 1.0, "<=")):
                if bound is not None:
                    scale = abs(bound) or abs(r0[name][0]) or 1.0
                    cons.append(
                        Constraint(
                            f"{name} {label} {bound:.6g}",
                            self.response(name, sign, bound),
                            scale=scale,
                            unit=units[name],
                        )
                    )
        f0 = abs(r0[self.objective][0]) or 1.0
        objective = Objective(
            self.objective, self.response(self.objective), scale=f0, unit=units[self.objective]
        )
        return DesignProblem(variables, objective, tuple(cons))


def _record(label: str, cp: ConfiguredProblem, r: OptimizationResult) -> dict[str, Any]:
    rec: dict[str, Any] = {"run": label, "objective": float(r.objective)}
    rec.update({name: v for name, (v, _) in cp.responses(r.x).items()})
    rec.update({f"x_{k}": v for k, v in r.design.items()})
    # a reference may report more than its responses (the TAMU co-design: simulated settling)
    report_metrics = getattr(cp.reference, "report_metrics", None)
    if report_metrics is not None:
        rec.update(report_metrics(r.x))
    rec["kkt_residual"] = r.kkt.residual
    rec["success"] = r.success
    rec["iterations"] = r.iterations
    rec["evaluations"] = r.evaluations
    rec["active"] = "; ".join(r.active)
    rec.update({f"multiplier[{k}]": v for k, v in r.multipliers.items()})
    return rec


@dataclass(frozen=True)
class DesignResult(ReportedResult):
    """The optimum (and comparison) and the front of a ``design`` scenario."""

    report_title: ClassVar[str] = "flexsat design optimisation"

    scenario: DesignScenario
    case_source: str
    configured: ConfiguredProblem
    optima: tuple[OptimizationResult, ...]
    front: dict[str, FloatArray] | None
    store: str | None

    def report_case(self) -> str:
        return self.scenario.case or self.scenario.problem or self.scenario.source_label

    def optimum_records(self) -> list[dict[str, Any]]:
        return [_record(f"optimum ({r.method})", self.configured, r) for r in self.optima]

    def front_records(self) -> list[dict[str, Any]]:
        if self.front is None:
            return []
        n = self.front["primary"].size
        return [
            {"run": f"front {i}", **{k: float(v[i]) for k, v in self.front.items()}}
            for i in range(n)
        ]

    def metrics_records(self) -> list[dict[str, Any]]:
        """The optima (with their iteration histories and described designs), the start, and
        the front (:mod:`flexsat.report.design_problem`)."""
        from flexsat.report.design_problem import optimum_data, start_record

        return [*optimum_data(self), start_record(self), *self.front_records()]

    def console_table(self) -> ResultTable:
        """The optima, one column per optimiser (the front is in the report)."""
        recs = self.optimum_records()
        keys = [k for k in recs[0] if k != "run"]
        rows = tuple((k, *(_fmt(r[k]) for r in recs)) for k in keys)
        return ResultTable("optimum", ("metric", *(str(r["run"]) for r in recs)), rows)

    def dataset(self) -> xr.Dataset:
        recs = self.optimum_records()
        data: dict[str, Any] = {}
        for key in recs[0]:
            if key not in ("run", "active"):
                data[key] = ("run", np.array([float(r[key]) for r in recs]))
        ds = xr.Dataset(data, coords={"run": [r["run"] for r in recs]})
        ds["active"] = ("run", np.array([r["active"] for r in recs], dtype=str))
        if self.front is not None:
            for key, values in self.front.items():
                ds[f"front_{key}"] = ("point", np.asarray(values, dtype=float))
        ds.attrs.update(
            scenario_name=self.scenario.name,
            case=self.report_case(),
            case_source=self.case_source,
            scenario_yaml=self.scenario.yaml_text,
            problem=self.scenario.problem or "model",
            pareto_store=self.store or "",
        )
        from flexsat.report.design_problem import history_dataset

        return ds.merge(history_dataset(self))

    def figures(self, folder: Path, ds: xr.Dataset) -> list[str]:
        from flexsat.report.design_problem import draw_figures

        return draw_figures(self, folder)

    def sections(self, ds: xr.Dataset, figures: list[str]) -> str:
        from flexsat.report.design_problem import sections

        return sections(self, figures)

    def plots(self, ds: xr.Dataset) -> list[Plot]:
        from flexsat.report.design_problem import plots

        return plots(self)


def _fmt(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:.6g}"
    return str(value)


def _default_store(scenario: DesignScenario, setup: FrontSetup, levels: FloatArray) -> Path:
    """The temporary store of a front without ``store:``, named by the document, the setup it
    resolves to and the front's levels (what the store's fingerprint holds besides), so that a
    second run resumes it while a flexsat whose problem or anchors differ (a new field, another
    default, another BLAS kernel's last bits) starts its own instead of being refused."""
    h = hashlib.sha256((scenario.yaml_text + "\n" + setup.describe()).encode())
    h.update(np.ascontiguousarray(levels, dtype=np.float64).tobytes())
    return Path(tempfile.gettempdir()) / f"flexsat-pareto-{h.hexdigest()[:20]}.zarr"


class DesignKind(ScenarioKind):
    """``kind: design`` (module docstring)."""

    kind = "design"
    document = DesignScenario
    runs_batches = True

    def steps(self, scenario: DesignScenario) -> int:
        return 1 + (scenario.optimizer.compare is not None) + (scenario.pareto is not None)

    def with_execution(
        self, scenario: DesignScenario, workers: int | None, scheduler: str | None
    ) -> DesignScenario:
        """The scenario with ``--workers`` / ``--scheduler`` in its ``pareto:`` section."""
        if workers is None and scheduler is None:
            return scenario
        if scenario.pareto is None:
            raise ScenarioError(
                [Problem("--workers/--scheduler", "apply to a design with a pareto: section")]
            )
        if workers is not None and scheduler is not None:
            raise ScenarioError([Problem("--workers/--scheduler", "give one, not both")])
        pareto = scenario.pareto.model_copy(update={"workers": workers, "scheduler": scheduler})
        copy = scenario.model_copy(update={"pareto": pareto})
        copy._source, copy._folder = scenario._source, scenario._folder
        return copy

    def plan(self, scenario: DesignScenario) -> Any:
        from flexsat.design.pareto import FrontSetup, front_levels, front_table, run_front

        configured = ConfiguredProblem.from_scenario(scenario)
        opt = scenario.optimizer
        methods = [opt.method] + ([opt.compare] if opt.compare else [])
        optima = []
        for method in methods:
            assert method in METHODS

            def solve(method: str = method) -> OptimizationResult:
                return optimize_design(
                    configured.problem(), method, tol=opt.tol, max_iterations=opt.max_iterations
                )

            optima.append((yield Run(f"optimum ({method})", solve, path="optimizer")))
        front, store = None, None
        if scenario.pareto is not None:
            p = scenario.pareto
            try:
                setup = FrontSetup(
                    configured,
                    scenario.objective,
                    p.secondary,
                    scalarisation=p.scalarisation,
                    method=opt.method,
                    tol=opt.tol,
                    max_iterations=opt.max_iterations,
                )
            except FieldError as exc:
                raise ScenarioError([locate("pareto", exc)]) from None
            given = Path(p.store) if p.store else None
            if given is not None and not given.is_absolute():
                given = scenario.folder / given
            where: list[Path] = []

            def front_run() -> dict[str, FloatArray]:
                levels = front_levels(setup, p.points)
                path = given if given is not None else _default_store(scenario, setup, levels)
                where.append(path)
                run_front(
                    setup,
                    path,
                    levels=levels,
                    points=p.points,
                    starts=p.starts,
                    base_seed=p.seed,
                    chunk_size=p.chunk_size,
                    workers=p.workers,
                    scheduler=p.scheduler,
                )
                return front_table(path, kkt_tol=p.kkt_tol)

            front = yield Run("pareto front", front_run, path="pareto")
            store = str(where[-1])
        return DesignResult(
            scenario,
            scenario.source_label,
            configured,
            tuple(optima),
            front,
            store,
        )
