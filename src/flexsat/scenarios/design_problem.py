"""``kind: design``: a design-optimisation problem as data — a registered reference problem,
its variables with bounds and units, the objective, the constraints, the optimiser, and an
optional Pareto front (issue 23 deliverables 1 and 4).

::

    kind: design
    name: hub-boom co-design, mass against LQ cost
    problem: hub_boom_codesign          # a name of REFERENCE_PROBLEMS
    parameters: {hub_inertia: 0.4}      # the reference's own fields, SI (optional)
    variables:                          # bounds and start, with units (optional per variable)
      t: {start: 2 mm, lower: 0.5 mm, upper: 3 mm}
      D: {start: 40 mm, lower: 10 mm, upper: 60 mm}
    objective: lq_cost                  # a response of the problem, minimised
    constraints:                        # response >= min and/or <= max, in its unit
      - {response: frequency_hz, min: 6 Hz}
      - {response: mass, max: 0.3 kg}
    optimizer: {method: slsqp, compare: trust-constr}
    pareto: {secondary: mass, points: 40, starts: 3}

The reference supplies the responses (with their analytic gradients), the variables and their
default starts and bounds; the constraints are those the document lists (the reference's own
are not added: a document without a frequency floor has none). The optimum is one
:func:`~flexsat.design.optimize.optimize_design` with its KKT check (and,
with ``optimizer.compare``, a second optimiser from the same start, reported beside it). The
Pareto front is :func:`flexsat.design.pareto.run_front` of the problem as written (its
variables and constraints; the objective is the front's primary response, ``pareto.secondary``
the other), a batch on dask into a zarr store that a second run resumes; the report's front is
:func:`~flexsat.design.pareto.front_table` of it. ``metrics.json`` holds one record per
optimiser (objective, responses, design, KKT residual, active set, multipliers) and one per
front point.
"""

from __future__ import annotations

import hashlib
import html
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any, ClassVar, Literal, Self

import numpy as np
import xarray as xr
from pydantic import Field, model_validator

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
from flexsat.scenarios.errors import Problem, ScenarioError, locate
from flexsat.scenarios.fields import Document, SchemaSection, in_unit, integer_in
from flexsat.scenarios.kind import Run, ScenarioKind
from flexsat.units import FloatArray, to_si

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
        {"lq_cost": "", "mass": "kg", "frequency_hz": "Hz"},
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
}

Quantity = str | float | int


class VariableSpec(SchemaSection):
    """Start and bounds of one variable, each in the variable's unit (a bare number is SI)."""

    start: Quantity | None = None
    lower: Quantity | None = None
    upper: Quantity | None = None


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
    problem: str
    parameters: dict[str, Any] = Field(default_factory=dict)
    variables: dict[str, VariableSpec] = Field(default_factory=dict)
    objective: str
    constraints: list[ConstraintSpec] = Field(default_factory=list)
    optimizer: OptimizerSpec = Field(default_factory=OptimizerSpec)
    pareto: ParetoSpec | None = None

    @model_validator(mode="after")
    def _names(self) -> Self:
        if self.problem not in REFERENCE_PROBLEMS:
            raise FieldError(
                "problem", f"must be one of {', '.join(REFERENCE_PROBLEMS)}, got {self.problem!r}"
            )
        cls, var_units, responses = REFERENCE_PROBLEMS[self.problem]
        fields = getattr(cls, "__dataclass_fields__", {})
        for key in self.parameters:
            if key not in fields or key.startswith("_"):
                known = ", ".join(k for k in fields if not k.startswith("_"))
                raise FieldError(
                    f"parameters.{key}", f"not a parameter of {self.problem} ({known})"
                )
        for key in self.variables:
            if key not in var_units:
                raise FieldError(
                    f"variables.{key}",
                    f"not a variable of {self.problem} ({', '.join(var_units)})",
                )
        rule = f"must be a response of {self.problem} ({', '.join(responses)})"
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
        kind, var_units, responses = REFERENCE_PROBLEMS[scenario.problem]
        try:
            reference = kind(**scenario.parameters)
        except FieldError as exc:
            raise FieldError(f"parameters.{exc.field}", exc.rule) from None
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
        return self.scenario.case or self.scenario.problem

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
        return self.optimum_records() + self.front_records()

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
            problem=self.scenario.problem,
            pareto_store=self.store or "",
        )
        return ds

    def figures(self, folder: Path, ds: xr.Dataset) -> list[str]:
        """The Pareto front (f₂ against f₁, the optimum marked) and the trade rate λ_ε."""
        if self.front is None or self.scenario.pareto is None:
            return []
        from matplotlib.figure import Figure

        units = dict(self.configured.units)
        f1, f2 = self.scenario.objective, self.scenario.pareto.secondary
        fig = Figure(figsize=(9, 3.4), layout="constrained")
        ax, rate = fig.subplots(1, 2)
        ax.plot(self.front["secondary"], self.front["primary"], "o-", ms=3, label="front")
        best = self.optima[0]
        r = self.configured.responses(best.x)
        ax.plot(r[f2][0], r[f1][0], "s", color="C3", label=f"optimum ({best.method})")
        ax.set(xlabel=f"{f2} ({units[f2] or '-'})", ylabel=f"{f1} ({units[f1] or '-'})")
        ax.set_title("Pareto front")
        ax.grid(alpha=0.3)
        ax.legend(fontsize="small")
        if np.isfinite(self.front["epsilon_multiplier"]).any():
            rate.semilogy(self.front["secondary"], self.front["epsilon_multiplier"], "o-", ms=3)
            rate.set(xlabel=f"{f2} ({units[f2] or '-'})", ylabel="λ_ε = −d f₁*/dε")
            rate.set_title("trade rate (ε-constraint multiplier)")
            rate.grid(alpha=0.3)
        else:
            rate.set_axis_off()
        fig.savefig(folder / "pareto_front.png", dpi=100)
        return ["pareto_front.png"]

    def sections(self, ds: xr.Dataset, figures: list[str]) -> str:
        esc = html.escape

        def table(records: list[dict[str, Any]], title: str) -> str:
            if not records:
                return ""
            keys = [k for k in records[0] if k != "run"]
            head = "".join(f"<th>{esc(k)}</th>" for k in ["", *keys])
            body = "".join(
                "<tr>"
                + f"<td>{esc(str(r['run']))}</td>"
                + "".join(f"<td>{esc(_fmt(r.get(k)))}</td>" for k in keys)
                + "</tr>"
                for r in records
            )
            return f"<h2>{esc(title)}</h2><table><tr>{head}</tr>{body}</table>"

        note = (
            "<p>KKT residual: the largest of stationarity, primal, dual and complementarity "
            "residuals in scaled units (minimisation convention, multipliers >= 0 for "
            "g <= 0).</p>"
        )
        out = table(self.optimum_records(), "Optimum") + note
        if self.front is not None and self.scenario.pareto is not None:
            p = self.scenario.pareto
            out += table(
                self.front_records(),
                f"Pareto front: {self.scenario.objective} against {p.secondary} "
                f"({p.scalarisation}, {p.points} levels x {p.starts} starts)",
            )
        images = "".join(f'<figure><img src="{esc(f)}" alt="{esc(f)}"></figure>' for f in figures)
        return out + images


def _fmt(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:.6g}"
    return str(value)


def _default_store(scenario: DesignScenario) -> Path:
    digest = hashlib.sha256(scenario.yaml_text.encode()).hexdigest()[:20]
    return Path(tempfile.gettempdir()) / f"flexsat-pareto-{digest}.zarr"


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
        from flexsat.design.pareto import FrontSetup, front_table, run_front

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
            path = Path(p.store) if p.store else _default_store(scenario)
            if not path.is_absolute():
                path = scenario.folder / path
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

            def front_run() -> dict[str, FloatArray]:
                run_front(
                    setup,
                    path,
                    points=p.points,
                    starts=p.starts,
                    base_seed=p.seed,
                    chunk_size=p.chunk_size,
                    workers=p.workers,
                    scheduler=p.scheduler,
                )
                return front_table(path, kkt_tol=p.kkt_tol)

            front = yield Run("pareto front", front_run, path="pareto")
            store = str(path)
        return DesignResult(
            scenario,
            f"reference problem {scenario.problem}",
            configured,
            tuple(optima),
            front,
            store,
        )
