r"""Pareto fronts of a two-objective design problem, by ε-constraint or weighted sums, on dask.

A *bicriteria reference* is a design problem with named responses: an object with
``responses(x) -> {name: (value, gradient)}`` (SI, the gradient w.r.t. the design vector) and
``problem() -> DesignProblem`` (the variables, their bounds and starting values, and the
constraints every design must meet: :class:`~flexsat.design.reference_problems.HubBoomCodesign`
with its first-frequency floor). Of two responses f₁ (``primary``) and f₂ (``secondary``):

* **ε-constraint** (Y. Y. Haimes, L. S. Lasdon and D. A. Wismer, "On a bicriterion formulation
  of the problems of integrated system identification and system optimization", IEEE Trans.
  Syst. Man Cybern. SMC-1(3), 296-297, 1971; K. Miettinen, *Nonlinear Multiobjective
  Optimization*, Kluwer 1999, §4.1):

  .. math::

      \min_x f_1(x) \quad\text{s.t.}\quad f_2(x) - \varepsilon \le 0,\ g(x) \le 0 ,

  whose optimum, when the ε-constraint is active with a positive multiplier λ_ε, is a Pareto
  point and λ_ε = −df₁*/dε is the local slope of the front (the trade rate);
* **weighted sum** (Miettinen §3.1), for comparison:
  min (1 − w) f₁/f₁⁰ + w f₂/f₂⁰ s.t. g ≤ 0 (f⁰ the values at the problem's start), which finds
  only the convex part of a front.

The levels: f₂ runs over the open interval between its two anchors, f₂^min = min f₂ s.t. g ≤ 0
and f₂ at argmin f₁ s.t. g ≤ 0 (:func:`front_levels`): ε_k = f₂^min + (k + ½)Δ/n, k = 0..n−1,
each strictly inside so that the ε-constraint binds and the feasible set is not a single point;
the weights are w_k = (k + ½)/n.

Multi-start: start 0 is the problem's starting design; start j >= 1 is uniform in the variable
bounds, drawn from ``numpy.random.SeedSequence(base_seed, spawn_key=(j,))`` — the same starts
for every level, and a start depends on its index alone.

Execution: a front is a batch (:func:`flexsat.design.batch_runner.run_batch`) whose cases are
levels × starts — the parameter table has the columns ``level`` and ``start`` — with
:class:`FrontCases` as the case builder running each case as one
:func:`~flexsat.design.optimize.optimize_design` (its KKT check included). The batch runner's
guarantees therefore hold: results stream to a zarr store, an interrupted run resumes, and a
case's numbers do not depend on the chunking or the worker count (each case is a deterministic
optimisation of its own problem: a front point equals the point run alone, :func:`solve_case`).
:func:`front_table` reads a store back: per level the best start among those the optimiser
called converged with a KKT residual within tolerance, then the nondominated ones.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from flexsat.design.batch_runner import BatchProgress, BatchSummary, open_results, run_batch
from flexsat.design.batch_seeds import case_seeds
from flexsat.design.optimization_problem import Constraint, DesignProblem, Objective
from flexsat.design.optimize import METHODS, OptimizationResult, optimize_design
from flexsat.input_checks import FieldError
from flexsat.units import FloatArray

__all__ = [
    "SCALARISATIONS",
    "BicriteriaReference",
    "FrontCases",
    "FrontSetup",
    "front_levels",
    "front_metrics",
    "front_table",
    "nondominated",
    "run_front",
    "solve_case",
]

SCALARISATIONS = ("epsilon", "weighted")


class BicriteriaReference(Protocol):
    """A design problem with named responses (module docstring)."""

    def responses(self, x: FloatArray) -> Mapping[str, tuple[float, FloatArray]]: ...

    def problem(self) -> DesignProblem: ...


@dataclass(frozen=True)
class FrontSetup:
    """What a front is made of: the reference, its two objectives, the scalarisation and the
    optimiser.

    Attributes
    ----------
    reference : BicriteriaReference
    primary : str
        The response minimised (f₁, e.g. ``"lq_cost"``).
    secondary : str
        The response bounded by ε or weighted (f₂, e.g. ``"mass"``).
    scalarisation : {"epsilon", "weighted"}
    method : str
        An :func:`~flexsat.design.optimize.optimize_design` method.
    tol, max_iterations, active_tol : as :func:`~flexsat.design.optimize.optimize_design`
    """

    reference: Any
    primary: str
    secondary: str
    scalarisation: str = "epsilon"
    method: str = "slsqp"
    tol: float = 1e-12
    max_iterations: int = 500
    active_tol: float = 1e-6

    def __post_init__(self) -> None:
        for name in ("responses", "problem"):
            if not callable(getattr(self.reference, name, None)):
                raise FieldError("reference", f"needs a method {name}() (BicriteriaReference)")
        known = tuple(self.reference.responses(self.reference.problem().x0))
        for name in ("primary", "secondary"):
            if getattr(self, name) not in known:
                raise FieldError(
                    name,
                    f"must be a response of the problem ({', '.join(known)}), "
                    f"got {getattr(self, name)!r}",
                )
        if self.primary == self.secondary:
            raise FieldError("secondary", "must differ from primary")
        if self.scalarisation not in SCALARISATIONS:
            raise FieldError(
                "scalarisation", f"must be one of {SCALARISATIONS}, got {self.scalarisation!r}"
            )
        if self.method not in METHODS:
            raise FieldError("method", f"must be one of {METHODS}, got {self.method!r}")

    def describe(self) -> str:
        """The setup as text (the batch fingerprint's builder part)."""
        return (
            f"FrontSetup({self.reference!r}, primary={self.primary!r}, "
            f"secondary={self.secondary!r}, scalarisation={self.scalarisation!r}, "
            f"method={self.method!r}, tol={self.tol!r}, max_iterations={self.max_iterations!r},"
            f" active_tol={self.active_tol!r})"
        )

    def response(self, name: str) -> Callable[[FloatArray], tuple[float, FloatArray]]:
        def value(x: FloatArray) -> tuple[float, FloatArray]:
            v, g = self.reference.responses(x)[name]
            return float(v), np.asarray(g, dtype=float)

        return value

    def single(self, name: str) -> DesignProblem:
        """min ``name`` subject to the reference's constraints (an anchor of the front)."""
        base = self.reference.problem()
        f0 = abs(self.response(name)(base.x0)[0]) or 1.0
        return DesignProblem(
            base.variables, Objective(name, self.response(name), scale=f0), base.constraints
        )

    def problem(self, level: float) -> DesignProblem:
        """The scalarised problem at ``level`` (ε, SI, or the weight w in (0, 1))."""
        base = self.reference.problem()
        x0 = base.x0
        f1, f2 = self.response(self.primary), self.response(self.secondary)
        s1, s2 = abs(f1(x0)[0]) or 1.0, abs(f2(x0)[0]) or 1.0
        if self.scalarisation == "epsilon":
            eps = float(level)

            def cap(x: FloatArray) -> tuple[float, FloatArray]:
                v, g = f2(x)
                return v - eps, g

            cons = (
                *base.constraints,
                Constraint(f"{self.secondary} <= epsilon", cap, scale=abs(eps) or s2),
            )
            return DesignProblem(base.variables, Objective(self.primary, f1, scale=s1), cons)
        w = float(level)
        if not 0.0 < w < 1.0:
            raise FieldError("level", f"a weight must lie in (0, 1), got {level!r}")

        def blend(x: FloatArray) -> tuple[float, FloatArray]:
            (v1, g1), (v2, g2) = f1(x), f2(x)
            return (1 - w) * v1 / s1 + w * v2 / s2, (1 - w) * g1 / s1 + w * g2 / s2

        return DesignProblem(
            base.variables, Objective(f"weighted sum w={w:g}", blend), base.constraints
        )

    def start(self, index: int, base_seed: int) -> FloatArray:
        """Start ``index`` (module docstring), SI."""
        base = self.reference.problem()
        if index == 0:
            return base.x0
        lo, hi = base.lower, base.upper
        if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))):
            raise FieldError("starts", "random starts need finite bounds on every variable")
        ss = np.random.SeedSequence(int(base_seed), spawn_key=(int(index),))
        u = np.random.default_rng(ss).random(lo.size)
        return np.asarray(lo + u * (hi - lo), dtype=float)


def solve_case(
    setup: FrontSetup, level: float, start: int, base_seed: int = 0
) -> OptimizationResult:
    """One front point from one start: the optimisation a batch case runs."""
    return optimize_design(
        setup.problem(level),
        setup.method,
        x0=setup.start(start, base_seed),
        tol=setup.tol,
        max_iterations=setup.max_iterations,
        active_tol=setup.active_tol,
    )


def front_metrics(setup: FrontSetup, result: OptimizationResult) -> dict[str, float]:
    """A case's stored numbers: both objectives, the design, KKT residual, the optimiser's
    verdict and the ε-constraint's multiplier (the front's slope) and activity."""
    r = setup.reference.responses(result.x)
    out = {
        "primary": float(r[setup.primary][0]),
        "secondary": float(r[setup.secondary][0]),
        "objective": float(result.objective),
        "kkt_residual": float(result.kkt.residual),
        "success": float(result.success),
        "iterations": float(result.iterations),
        "evaluations": float(result.evaluations),
    }
    for name, value in result.design.items():
        out[f"x_{name}"] = value
    cap = f"{setup.secondary} <= epsilon"
    out["epsilon_multiplier"] = float(result.multipliers.get(cap, np.nan))
    out["epsilon_active"] = float(cap in result.active)
    return out


@dataclass(frozen=True)
class FrontCases:
    """The case builder of a front batch: columns ``level`` and ``start``; each case is one
    :func:`solve_case`, read by :func:`front_metrics` (a builder with its own ``run_chunk``,
    :func:`flexsat.design.batch_runner.run_chunk`)."""

    setup: FrontSetup
    parameter_names: tuple[str, ...] = ("level", "start")

    def describe(self) -> str:
        return self.setup.describe()

    def check(self, table: Mapping[str, np.ndarray]) -> None:
        if set(table) != set(self.parameter_names):
            raise FieldError("parameters", f"needs exactly the columns {self.parameter_names}")
        s = table["start"]
        if np.any(s < 0) or np.any(s != np.round(s)):
            raise FieldError("parameters['start']", "start indices must be integers >= 0")

    def run_chunk(
        self,
        extract: Any,
        parameters: Mapping[str, np.ndarray],
        start: int,
        base_seed: int,
        histories: tuple[str, ...] = (),
    ) -> dict[str, np.ndarray]:
        if histories:
            raise FieldError("histories", "a front batch keeps metrics only")
        n = len(parameters["level"])
        rows = [
            front_metrics(
                self.setup,
                solve_case(
                    self.setup,
                    float(parameters["level"][k]),
                    int(parameters["start"][k]),
                    base_seed,
                ),
            )
            for k in range(n)
        ]
        out = {f"metric_{name}": np.array([r[name] for r in rows]) for name in rows[0]}
        out["time"] = np.zeros(0)
        out["seed"] = case_seeds(base_seed, np.arange(start, start + n))
        return out


def front_levels(setup: FrontSetup, points: int) -> FloatArray:
    """The ``points`` levels of the front (module docstring): ε inside the anchors' range of
    the secondary response, or weights in (0, 1)."""
    if isinstance(points, bool) or not isinstance(points, int) or points < 1:
        raise FieldError("points", f"must be an integer >= 1, got {points!r}")
    k = np.arange(points) + 0.5
    if setup.scalarisation == "weighted":
        return k / points
    low, high = (
        optimize_design(
            setup.single(name), setup.method, tol=setup.tol, max_iterations=setup.max_iterations
        )
        for name in (setup.secondary, setup.primary)
    )
    f2 = setup.response(setup.secondary)
    lo, hi = f2(low.x)[0], f2(high.x)[0]
    if not hi > lo:
        raise FieldError(
            "secondary",
            f"the objectives do not conflict: min {setup.primary} has {setup.secondary} = {hi}"
            f" <= its minimum {lo}",
        )
    return lo + (hi - lo) * k / points


def run_front(
    setup: FrontSetup,
    store: str | Path,
    *,
    points: int = 40,
    starts: int = 3,
    base_seed: int = 0,
    chunk_size: int = 10,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: Callable[[BatchProgress], None] | None = None,
    levels: FloatArray | None = None,
) -> BatchSummary:
    """Run the front (``points`` levels × ``starts`` starts) as a batch into ``store``.

    Case i is level i // starts from start i % starts. Re-running the same call resumes an
    interrupted store; see :func:`flexsat.design.batch_runner.run_batch` for the store, the
    scheduling and the errors. ``levels``: :func:`front_levels` of the setup, when the caller
    has them already (they are part of the store's fingerprint).
    """
    if isinstance(starts, bool) or not isinstance(starts, int) or starts < 1:
        raise FieldError("starts", f"must be an integer >= 1, got {starts!r}")
    if levels is None:
        levels = front_levels(setup, points)
    elif np.shape(levels) != (points,):
        raise FieldError("levels", f"must be the {points} levels of front_levels")
    table = {
        "level": np.repeat(levels, starts),
        "start": np.tile(np.arange(starts, dtype=float), points),
    }
    # a builder with its own run_chunk is not called (run_batch's ``build`` protocol)
    builder: Any = FrontCases(setup)
    return run_batch(
        builder,
        table,
        store,
        base_seed=base_seed,
        chunk_size=chunk_size,
        workers=workers,
        scheduler=scheduler,
        setup_text=json.dumps({"points": points, "starts": starts}),
        progress=progress,
    )


def nondominated(primary: FloatArray, secondary: FloatArray) -> np.ndarray:
    """Mask of the points no other point dominates (both minimised: j dominates i when
    f₁ⱼ <= f₁ᵢ and f₂ⱼ <= f₂ᵢ with one strict)."""
    f1, f2 = np.asarray(primary, float), np.asarray(secondary, float)
    le = (f1[None, :] <= f1[:, None]) & (f2[None, :] <= f2[:, None])
    lt = (f1[None, :] < f1[:, None]) | (f2[None, :] < f2[:, None])
    return np.asarray(~np.any(le & lt, axis=1))


def front_table(store: str | Path, kkt_tol: float = 1e-6) -> dict[str, FloatArray]:
    """The front of a finished store: per level the best start (lowest scalarised objective)
    among those with ``success`` and a KKT residual <= ``kkt_tol``, then the nondominated
    points, ordered by the secondary response. Columns: ``level``, ``start``, and every metric
    (without its ``metric_`` prefix)."""
    ds = open_results(store).load()
    if not bool(ds["done"].all()):
        raise FieldError("store", f"{store} is not finished; run the same front again to resume")
    level, start = ds["param_level"].values, ds["param_start"].values
    names = [str(k) for k in ds.data_vars]
    metrics = {k[len("metric_") :]: ds[k].values for k in names if k.startswith("metric_")}
    ok = (metrics["success"] > 0) & (metrics["kkt_residual"] <= kkt_tol)
    rows = []
    for lv in np.unique(level):
        idx = np.flatnonzero((level == lv) & ok)
        if idx.size:
            rows.append(int(idx[np.argmin(metrics["objective"][idx])]))
    pick = np.array(rows, dtype=int)
    keep = pick[nondominated(metrics["primary"][pick], metrics["secondary"][pick])]
    keep = keep[np.argsort(metrics["secondary"][keep], kind="stable")]
    out = {"level": level[keep], "start": start[keep]}
    out.update({k: v[keep] for k, v in metrics.items()})
    return out
