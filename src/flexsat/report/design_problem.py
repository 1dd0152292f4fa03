r"""Report of a design optimisation (``kind: design``, issue 23 deliverable 7): the path each
optimiser took, the optimum's active set with its multipliers and KKT residuals, the starting
design beside the final one, and the Pareto front.

The page, in order:

- **Optimum**: one column per optimiser (objective, every response, the design, KKT residual,
  iterations, evaluations, active set, every multiplier);
- **Active set and KKT residuals**: each active constraint and bound of each optimum with its
  value g(x) (the minimisation form g ≤ 0: ``response − max``, ``min − response``,
  ``lower − x``, ``x − upper``) and its multiplier λ ≥ 0 in SI (unit: the objective's over the
  constraint's), then the four KKT residuals (stationarity, primal, dual, complementarity, in
  the problem's scaled units) and their maximum (:mod:`flexsat.design.kkt`);
- **Starting design beside the final design**: the variables and every response at the start
  and at each optimum, then, for a problem that describes its designs
  (:func:`flexsat.design.describe.describe_design`), the structure's modes and the controller's
  gains and closed-loop poles at each;
- **Pareto front** (with a ``pareto:`` section): the front's table and a figure of f₁ against
  f₂ (the optimum marked) beside the trade rate λ_ε = −df₁*/dε, the ε-constraint's multiplier
  (a static PNG, embedded);
- **Figures** (interactive, :mod:`flexsat.report.interactive`, one toggle per optimiser): the
  scaled objective f/scale_f and the largest scaled constraint or bound violation at each
  iterate, and every design variable along the iterations normalised to its bounds,
  (x − lower)/(upper − lower) (x/scale for a variable without two finite bounds).

The history of each optimiser (iteration, objective, scaled objective, largest violation, the
design) is data too: ``metrics.json`` holds it in each optimum's record (``history``, with the
described features under ``described``; a ``start`` record holds the start), and
``results.nc`` as ``history_*`` variables over (``run``, ``iteration``) padded with NaN after
``history_length``, and ``described_*`` over (``design``, element) — complex poles as
``_real`` and ``_imag`` parts.

References
----------
H. W. Kuhn and A. W. Tucker, "Nonlinear programming", Proceedings of the Second Berkeley
Symposium on Mathematical Statistics and Probability, University of California Press, 1951,
481–492 (the conditions); J. Nocedal and S. J. Wright, *Numerical Optimization*, 2nd ed.,
Springer, 2006, Thm. 12.1 and §12.8 (the conditions in minimisation form; a multiplier as the
optimum's sensitivity to its constraint); Y. Y. Haimes, L. S. Lasdon and D. A. Wismer, "On a
bicriterion formulation of the problems of integrated system identification and system
optimization", IEEE Transactions on Systems, Man, and Cybernetics SMC-1(3), 1971, 296–297
(the ε-constraint method).
"""

from __future__ import annotations

import html
import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from flexsat.design.describe import DISCIPLINES, DesignFeature, describe_design
from flexsat.report.interactive import Curve, Plot
from flexsat.report.page import html_table, images_html

if TYPE_CHECKING:
    import xarray as xr

    from flexsat.design.optimization_problem import DesignProblem
    from flexsat.design.optimize import OptimizationResult
    from flexsat.units import FloatArray

__all__ = [
    "VIOLATION_FLOOR",
    "ConfiguredReference",
    "DesignProblemReport",
    "active_rows",
    "described",
    "draw_figures",
    "history_data",
    "history_dataset",
    "optimum_data",
    "plots",
    "sections",
    "start_record",
]

#: a violation of 0 is drawn at this value on the logarithmic violation axis
VIOLATION_FLOOR = 1e-16

#: the line styles of the design variables in the history figure, in variable order
_STYLES = ("solid", "dashed", "dotted", "dashdot")


class ConfiguredReference(Protocol):
    """What the report reads of the configured problem
    (:class:`flexsat.scenarios.design_problem.ConfiguredProblem`)."""

    @property
    def reference(self) -> Any: ...
    @property
    def units(self) -> tuple[tuple[str, str], ...]: ...
    def responses(self, x: FloatArray) -> dict[str, tuple[float, FloatArray]]: ...
    def problem(self) -> DesignProblem: ...


class DesignProblemReport(Protocol):
    """What the report reads of a ``design`` result
    (:class:`flexsat.scenarios.design_problem.DesignResult`)."""

    @property
    def scenario(self) -> Any: ...
    @property
    def configured(self) -> ConfiguredReference: ...
    @property
    def optima(self) -> tuple[OptimizationResult, ...]: ...
    @property
    def front(self) -> dict[str, FloatArray] | None: ...
    def optimum_records(self) -> list[dict[str, Any]]: ...
    def front_records(self) -> list[dict[str, Any]]: ...


def _label(r: OptimizationResult) -> str:
    return f"optimum ({r.method})"


def _fmt(value: Any) -> str:
    if isinstance(value, bool) or value is None:
        return "n/a" if value is None else str(value)
    if isinstance(value, complex):
        sign = "+" if value.imag >= 0 else "−"
        return f"{value.real:.6g} {sign} {abs(value.imag):.6g}j"
    if isinstance(value, (float, np.floating)):
        return f"{float(value):.6g}" if np.isfinite(value) else "n/a"
    return str(value)


def _start(result: DesignProblemReport) -> FloatArray:
    """The start every optimiser began from (its first history entry)."""
    return np.asarray(result.optima[0].history[0].x, dtype=float)


# -- data --------------------------------------------------------------------------------------
def history_data(problem: DesignProblem, r: OptimizationResult) -> dict[str, Any]:
    """The path of one optimiser as plain data: ``iteration``, ``objective`` (SI),
    ``scaled_objective`` (f / scale_f), ``max_violation`` (largest scaled constraint or bound
    violation) and ``x`` (variable name -> its values, SI), one element per iterate."""
    fs = problem.objective.scale
    return {
        "iteration": [h.iteration for h in r.history],
        "objective": [float(h.objective) for h in r.history],
        "scaled_objective": [float(h.objective / fs) for h in r.history],
        "max_violation": [float(h.max_violation) for h in r.history],
        "x": {name: [float(h.x[k]) for h in r.history] for k, name in enumerate(r.names)},
    }


def described(result: DesignProblemReport) -> dict[str, dict[str, DesignFeature]]:
    """``describe`` of the problem at the start and at each optimum: design label
    (``"start"``, ``"optimum (<method>)"``) -> feature name -> feature; empty mappings for a
    problem that does not describe its designs."""
    reference = result.configured.reference
    out = {"start": describe_design(reference, _start(result))}
    for r in result.optima:
        out[_label(r)] = describe_design(reference, r.x)
    return out


def optimum_data(result: DesignProblemReport) -> list[dict[str, Any]]:
    """The optima's metrics records with their ``history`` and ``described`` features."""
    problem = result.configured.problem()
    features = described(result)
    records = []
    for rec, r in zip(result.optimum_records(), result.optima):
        extra = {
            "history": history_data(problem, r),
            "described": {k: f.as_data() for k, f in features[_label(r)].items()},
        }
        records.append({**rec, **extra})
    return records


def start_record(result: DesignProblemReport) -> dict[str, Any]:
    """The start as a record: ``run`` = ``"start"``, every response, the design (``x_<name>``)
    and its described features."""
    x0 = _start(result)
    rec: dict[str, Any] = {"run": "start"}
    rec.update({name: v for name, (v, _) in result.configured.responses(x0).items()})
    rec.update({f"x_{n}": float(v) for n, v in zip(result.optima[0].names, x0)})
    rec["described"] = {k: f.as_data() for k, f in described(result)["start"].items()}
    return rec


def _slug(name: str) -> str:
    return re.sub(r"[^0-9a-zA-Z]+", "_", name).strip("_").lower()


def history_dataset(result: DesignProblemReport) -> xr.Dataset:
    """The histories and the described features as a dataset (module docstring)."""
    import xarray as xr

    problem = result.configured.problem()
    runs = [_label(r) for r in result.optima]
    n = max(len(r.history) for r in result.optima)
    names = list(result.optima[0].names)
    f = np.full((len(runs), n), np.nan)
    v = np.full((len(runs), n), np.nan)
    x = np.full((len(runs), n, len(names)), np.nan)
    for i, r in enumerate(result.optima):
        k = len(r.history)
        f[i, :k] = [h.objective for h in r.history]
        v[i, :k] = [h.max_violation for h in r.history]
        x[i, :k] = np.array([h.x for h in r.history])
    ds = xr.Dataset(
        {
            "history_objective": (("run", "iteration"), f),
            "history_scaled_objective": (("run", "iteration"), f / problem.objective.scale),
            "history_max_violation": (("run", "iteration"), v),
            "history_x": (("run", "iteration", "variable"), x),
            "history_length": ("run", np.array([len(r.history) for r in result.optima])),
        },
        coords={"run": runs, "iteration": np.arange(n), "variable": names},
    )
    features = described(result)
    designs = list(features)
    if any(features.values()):
        ds = ds.assign_coords(design=designs)
    for name in dict.fromkeys(k for fs in features.values() for k in fs):
        present = [fs[name] for fs in features.values() if name in fs]
        size = max(p.values.size for p in present)
        slug = _slug(name)
        parts = ("real", "imag") if any(p.is_complex for p in present) else ("",)
        for part in parts:
            data = np.full((len(designs), size), np.nan)
            for i, fs in enumerate(features.values()):
                if name in fs:
                    vals = fs[name].values
                    vals = getattr(vals, part) if part else vals
                    data[i, : vals.size] = vals
            key = f"described_{slug}" + (f"_{part}" if part else "")
            ds[key] = (("design", f"{slug}_element"), data)
            ds[key].attrs.update(units=present[0].unit, long_name=name, note=present[0].note)
    return ds


# -- tables ------------------------------------------------------------------------------------
def _ratio_unit(numerator: str, denominator: str) -> str:
    if not denominator:
        return numerator or "-"
    wrapped = f"({denominator})" if any(c in denominator for c in "*/ ") else denominator
    return f"{numerator or '1'}/{wrapped}"


def active_rows(problem: DesignProblem, r: OptimizationResult) -> list[tuple[str, ...]]:
    """One row per active constraint or bound of ``r``: optimiser, name, kind, g(x) (SI, ≤ 0
    form), multiplier λ (SI, minimisation convention), λ's unit — in the order of
    ``r.active`` (the KKT report's)."""
    fu = problem.objective.unit
    constraints = {c.name: c for c in problem.constraints}
    variables = {v.name: (k, v) for k, v in enumerate(problem.variables)}
    rows: list[tuple[str, ...]] = []
    for name in r.active:
        lam = r.multipliers[name]
        if name in constraints:
            kind, g, unit = "constraint", r.constraints[name], constraints[name].unit
        else:
            var, side = name.split(" ", 1)
            k, v = variables[var]
            if side == ">= lower":
                kind, g = "lower bound", v.lower - float(r.x[k])
            else:
                kind, g = "upper bound", float(r.x[k]) - v.upper
            unit = v.unit
        rows.append((_label(r), name, kind, _fmt(g), _fmt(lam), _ratio_unit(fu, unit)))
    return rows


def _kkt_section(problem: DesignProblem, optima: Sequence[OptimizationResult]) -> str:
    rows = [row for r in optima for row in active_rows(problem, r)]
    active = (
        html_table(("optimiser", "active", "kind", "g(x) (≤ 0)", "λ (≥ 0)", "unit of λ"), rows)
        if rows
        else "<p>No constraint or bound is active at any optimum.</p>"
    )
    residuals = html_table(
        (
            "optimiser",
            "KKT residual",
            "stationarity",
            "primal",
            "dual",
            "complementarity",
            "rank",
            "active",
        ),
        [
            (
                _label(r),
                *(
                    _fmt(getattr(r.kkt, k))
                    for k in ("residual", "stationarity", "primal", "dual", "complementarity")
                ),
                str(r.kkt.rank),
                str(len(r.active)),
            )
            for r in optima
        ],
    )
    return (
        "<h2>Active set and KKT residuals</h2>\n<p>Minimisation convention: minimise f subject "
        "to g(x) ≤ 0 (a bound <i>min</i> is written min − response ≤ 0, a variable's bounds "
        "lower − x ≤ 0 and x − upper ≤ 0); ∇f + Σ λᵢ ∇gᵢ = 0 with λᵢ ≥ 0 on the active set "
        "(Kuhn &amp; Tucker 1951). The multipliers are recomputed at the optimum by least "
        "squares on the active gradients, not taken from the optimiser, and are shown in SI: "
        "λ is the rate at which the objective would fall if the constraint were relaxed by "
        "one unit. Residuals are in the problem's scaled units; the KKT residual is the "
        "largest of the four.</p>\n" + active + "\n" + residuals
    )


def _feature_rows(
    features: Mapping[str, Mapping[str, DesignFeature]], discipline: str
) -> tuple[list[tuple[str, ...]], list[str]]:
    designs = list(features)
    names = dict.fromkeys(
        k for fs in features.values() for k, f in fs.items() if f.discipline == discipline
    )
    rows, notes = [], []
    for name in names:
        first = next(fs[name] for fs in features.values() if name in fs)
        if first.note:
            notes.append(f"{name}: {first.note}")
        labels = dict.fromkeys(
            lab for fs in features.values() if name in fs for lab in fs[name].labels
        )
        for label in labels:
            cells = []
            for d in designs:
                f = features[d].get(name)
                if f is None or label not in f.labels:
                    cells.append("n/a")
                else:
                    value = f.values[f.labels.index(label)]
                    cells.append(_fmt(complex(value) if f.is_complex else float(value)))
            rows.append((f"{name}: {label}" if len(labels) > 1 else name, first.unit, *cells))
    return rows, notes


def _comparison_section(result: DesignProblemReport) -> str:
    esc = html.escape
    x0 = _start(result)
    designs = ["start", *(_label(r) for r in result.optima)]
    points = [x0, *(r.x for r in result.optima)]
    problem = result.configured.problem()
    rows: list[tuple[str, ...]] = [
        (f"variable {v.name}", v.unit or "-", *(_fmt(float(p[k])) for p in points))
        for k, v in enumerate(problem.variables)
    ]
    units = dict(result.configured.units)
    values = [result.configured.responses(p) for p in points]
    rows += [
        (name, units.get(name) or "-", *(_fmt(val[name][0]) for val in values))
        for name in values[0]
    ]
    out = "<h2>Starting design beside the final design</h2>\n"
    out += html_table(("", "unit", *designs), rows)
    features = described(result)
    if not any(features.values()):
        return out + (
            "<p>This problem does not describe its designs (no <code>describe</code>): its "
            "structure and controller are not shown.</p>"
        )
    titles = {"structure": "Structure", "control": "Controller"}
    for discipline in DISCIPLINES:
        frows, notes = _feature_rows(features, discipline)
        if frows:
            out += f"<h3>{titles[discipline]}</h3>\n" + html_table(
                ("", "unit", *designs), [(r[0], r[1] or "-", *r[2:]) for r in frows]
            )
            out += "".join(f"<p><small>{esc(n)}</small></p>" for n in notes)
    return out


def _records_table(records: list[dict[str, Any]], title: str) -> str:
    if not records:
        return ""
    keys = [k for k in records[0] if k != "run"]
    rows = [(str(r["run"]), *(_fmt(r.get(k)) for k in keys)) for r in records]
    return f"<h2>{html.escape(title)}</h2>" + html_table(["", *keys], rows)


def sections(result: DesignProblemReport, figures: list[str]) -> str:
    """The page's sections (module docstring); ``figures``: the files of
    :func:`draw_figures`."""
    problem = result.configured.problem()
    out = _records_table(result.optimum_records(), "Optimum")
    out += _kkt_section(problem, result.optima)
    out += _comparison_section(result)
    scenario = result.scenario
    if result.front is not None and scenario.pareto is not None:
        p = scenario.pareto
        out += _records_table(
            result.front_records(),
            f"Pareto front: {scenario.objective} against {p.secondary} "
            f"({p.scalarisation}, {p.points} levels x {p.starts} starts)",
        )
        out += (
            "<p>epsilon_multiplier is the trade rate λ_ε = −df₁*/dε: how much the objective "
            "falls per unit of the secondary response allowed (Haimes, Lasdon &amp; Wismer "
            "1971).</p>"
        )
    out += images_html(figures)
    out += (
        "<p>The figures below follow each optimiser from the start: the objective scaled by "
        f"its start value, the largest scaled violation (0 drawn at {VIOLATION_FLOOR:g}) and "
        "the design variables normalised to their bounds. <code>metrics.json</code> and "
        "<code>results.nc</code> hold the same histories as numbers.</p>"
    )
    return out


# -- figures -----------------------------------------------------------------------------------
def plots(result: DesignProblemReport) -> list[Plot]:
    """The iteration-history figures (module docstring), one run per optimiser."""
    problem = result.configured.problem()
    fs = problem.objective.scale
    lo, hi, sc = problem.lower, problem.upper, problem.scale
    objective, violation, design = [], [], []
    for r in result.optima:
        run = _label(r)
        it = np.array([h.iteration for h in r.history], dtype=float)
        f = np.array([h.objective for h in r.history]) / fs
        v = np.maximum([h.max_violation for h in r.history], VIOLATION_FLOOR)
        X = np.array([h.x for h in r.history])
        objective.append(Curve(run, run, it, f))
        violation.append(Curve(run, run, it, np.asarray(v, dtype=float)))
        for k, name in enumerate(r.names):
            bounded = np.isfinite(lo[k]) and np.isfinite(hi[k])
            y = (X[:, k] - lo[k]) / (hi[k] - lo[k]) if bounded else X[:, k] / sc[k]
            tag = name if bounded else f"{name}/scale"
            style = _STYLES[k % len(_STYLES)]
            design.append(Curve(run, f"{tag} ({r.method})", it, y, style=style))
    f_label = f"{problem.objective.name} / {fs:.4g}"
    return [
        Plot("Objective along the iterations (scaled)", "iteration", f_label, tuple(objective)),
        Plot(
            "Largest constraint or bound violation (scaled)",
            "iteration",
            f"max violation (0 shown as {VIOLATION_FLOOR:g})",
            tuple(violation),
            log_y=True,
        ),
        Plot(
            "Design variables along the iterations",
            "iteration",
            "(x − lower)/(upper − lower)",
            tuple(design),
            hlines=(0.0, 1.0),
        ),
    ]


def draw_figures(result: DesignProblemReport, folder: Path) -> list[str]:
    """The Pareto front (f₁ against f₂, the optimum marked) and the trade rate λ_ε, as
    ``pareto_front.png`` in ``folder``; none without a front."""
    scenario = result.scenario
    if result.front is None or scenario.pareto is None:
        return []
    from matplotlib.figure import Figure

    front = result.front
    units = dict(result.configured.units)
    f1, f2 = scenario.objective, scenario.pareto.secondary
    fig = Figure(figsize=(9, 3.4), layout="constrained")
    ax, rate = fig.subplots(1, 2)
    ax.plot(front["secondary"], front["primary"], "o-", ms=3, label="front")
    best = result.optima[0]
    r = result.configured.responses(best.x)
    ax.plot(r[f2][0], r[f1][0], "s", color="C3", label=f"optimum ({best.method})")
    ax.set(xlabel=f"{f2} ({units[f2] or '-'})", ylabel=f"{f1} ({units[f1] or '-'})")
    ax.set_title("Pareto front")
    ax.grid(alpha=0.3)
    ax.legend(fontsize="small")
    if np.isfinite(front["epsilon_multiplier"]).any():
        rate.semilogy(front["secondary"], front["epsilon_multiplier"], "o-", ms=3)
        rate.set(xlabel=f"{f2} ({units[f2] or '-'})", ylabel="λ_ε = −d f₁*/dε")
        rate.set_title("trade rate (ε-constraint multiplier)")
        rate.grid(alpha=0.3)
    else:
        rate.set_axis_off()
    fig.savefig(folder / "pareto_front.png", dpi=100)
    return ["pareto_front.png"]
