"""Report of a sweep or Monte Carlo scenario (``kind: sweep`` / ``montecarlo``):
``summary.json``, the zarr store ``results.zarr`` (a copy of the run's store), figures and
``index.html``.

``summary.json``: the scenario's name and kind, the case count, per metric its summary
(mean, sd, min, max, percentiles, NaN count, convergence of the percentiles against N), per
requirement the probability of meeting it with its confidence interval and its convergence, and
per metric the parameters' sensitivity ranking (NaN and inf written as null). ``results.zarr``:
``metric_*`` over ``case``, ``param_*`` (SI), ``seed``, ``done`` and any ``history_*``; open it
with ``xarray.open_zarr(path)``. Figures: a sweep over two grid axes gets a contour map of every
metric over them (one axis: a line per metric); a Monte Carlo gets each metric's histogram and
CDF with the requirement lines, and the convergence of each probability estimate with its
confidence band against N. A sweep over exactly (α, u_max) also gets the Junkins,
Pollock & Rahman 1990 trade surfaces
(Att. 3 Figs. 5-7: T, E(T), μ_max; :func:`~flexsat.scenarios.batch.trade_surfaces`), also in
``summary.json``.

The files are the same for the same scenario however it ran: the wall time and how many chunks
a run found already done in its store (a resumed run) vary between identical runs, so they stay
on the result (``wall_s``, ``chunks_run``, ``chunks_skipped``) and out of ``summary.json`` and
``index.html``.
"""

from __future__ import annotations

import html
import shutil
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np
from matplotlib.figure import Figure

from flexsat.report.display import metric_label
from flexsat.report.json_data import dumps
from flexsat.report.page import images_html
from flexsat.units import to_si

if TYPE_CHECKING:
    import xarray as xr


class BatchReport(Protocol):
    """What this report reads of a batch result (:class:`flexsat.scenarios.batch.BatchResult`;
    ``scenario`` is its :class:`~flexsat.scenarios.batch.BatchScenario`)."""

    @property
    def scenario(self) -> Any: ...
    @property
    def table(self) -> dict[str, np.ndarray]: ...
    @property
    def units(self) -> dict[str, str]: ...
    @property
    def store(self) -> Path: ...
    @property
    def summary(self) -> dict[str, Any]: ...
    @property
    def sensitivity(self) -> dict[str, dict[str, Any]]: ...
    @property
    def wall_s(self) -> float: ...
    @property
    def chunks_run(self) -> int: ...
    @property
    def chunks_skipped(self) -> int: ...
    @property
    def surfaces(self) -> dict[str, np.ndarray] | None: ...


def _metrics(ds: xr.Dataset) -> dict[str, np.ndarray]:
    return {
        str(k)[len("metric_") :]: ds[k].values
        for k in sorted(map(str, ds.data_vars))
        if str(k).startswith("metric_")
    }


def _grid_axes(result: BatchReport) -> list[tuple[str, np.ndarray]]:
    """The swept parameters of a grid, first axis slowest, with their distinct values."""
    if result.scenario.sampling != "grid":
        return []
    return [(name, np.unique(values)) for name, values in result.table.items()]


def _contours(result: BatchReport, metrics: dict[str, np.ndarray], folder: Path) -> list[str]:
    axes = _grid_axes(result)
    files: list[str] = []
    if len(axes) not in (1, 2):
        return files
    for name, values in metrics.items():
        fig = Figure(figsize=(6.5, 4.2), layout="constrained")
        ax = fig.add_subplot()
        if len(axes) == 2:
            (xn, xv), (yn, yv) = axes
            z = values.reshape(len(xv), len(yv)).T
            if np.isfinite(z).sum() >= 4 and np.nanmax(z) > np.nanmin(z):
                cs = ax.contourf(xv, yv, z, levels=12)
                fig.colorbar(cs, ax=ax, label=name)
            else:
                ax.text(0.5, 0.5, "constant or not finite", ha="center", transform=ax.transAxes)
            ax.set(
                xlabel=f"{xn} ({result.units[xn] or '-'})",
                ylabel=f"{yn} ({result.units[yn] or '-'})",
                title=name,
            )
        else:
            ((xn, xv),) = axes
            ax.plot(xv, values, "o-")
            ax.set(xlabel=f"{xn} ({result.units[xn] or '-'})", ylabel=name)
            ax.grid(alpha=0.3)
        file = f"surface_{name}.png"
        fig.savefig(folder / file, dpi=100)
        files.append(file)
    return files


#: the Junkins, Pollock & Rahman 1990 trade surfaces (Att. 3 Figs. 5-7): key, title, colour scale
SURFACES = (
    ("maneuver_time_s", "maneuver time T (s), Att. 3 Eq. 16, Fig. 5", "linear"),
    ("residual_energy_J", "vibration energy E(T) of the open-loop response (J), Fig. 6", "log"),
    ("mu_max_deg_s", "Law II tracking bound μ_max (deg/s), Eq. 22, Fig. 7", "linear"),
)


def _trade_surfaces(result: BatchReport, folder: Path) -> list[str]:
    surfaces = result.surfaces
    if surfaces is None:
        return []
    from matplotlib.colors import LogNorm

    u = surfaces["u_max"] / to_si("1 ozf*in", "N*m")  # the paper's axis, oz-in
    files: list[str] = []
    for key, title, scale in SURFACES:
        z = surfaces[key]
        fig = Figure(figsize=(6.5, 4.2), layout="constrained")
        ax = fig.add_subplot()
        norm = LogNorm(max(z.min(), z.max() * 1e-8), z.max()) if scale == "log" else None
        cs = ax.contourf(surfaces["alpha"], u, z.T, levels=14, norm=norm)
        fig.colorbar(cs, ax=ax)
        ax.set(xlabel="α (rise fraction Δt/T)", ylabel="u_max (oz-in)", title=title)
        file = f"trade_{key}.png"
        fig.savefig(folder / file, dpi=100)
        files.append(file)
    return files


def distribution_figures(
    summary: dict[str, Any], metrics: dict[str, np.ndarray], folder: Path
) -> list[str]:
    """Each metric's histogram and CDF with the lines of its requirements (``summary``: a
    :func:`~flexsat.design.monte_carlo_statistics.monte_carlo_summary`), into ``folder``; the
    file names."""
    lines: dict[str, list[float]] = {}
    for r in summary["requirements"]:
        lines.setdefault(r["metric"], []).append(r["threshold"])
    files: list[str] = []
    for name, values in metrics.items():
        finite = values[np.isfinite(values)]
        if finite.size == 0:
            continue
        fig = Figure(figsize=(8, 3.2), layout="constrained")
        a, b = fig.subplots(1, 2)
        a.hist(finite, bins=min(50, max(5, int(np.sqrt(finite.size)))))
        x = np.sort(finite)
        b.step(x, np.arange(1, x.size + 1) / values.size, where="post")
        for threshold in lines.get(name, []):
            for ax in (a, b):
                ax.axvline(threshold, color="r", linestyle="--", linewidth=1)
        a.set(xlabel=name, ylabel="cases")
        b.set(xlabel=name, ylabel="fraction of cases (CDF)", ylim=(0, 1))
        for ax in (a, b):
            ax.grid(alpha=0.3)
        file = f"distribution_{name}.png"
        fig.savefig(folder / file, dpi=100)
        files.append(file)
    return files


def convergence_figure(summary: dict[str, Any], folder: Path) -> list[str]:
    """The convergence of each probability estimate of ``summary`` with its confidence band
    against N (none without requirements); the file names."""
    reqs = summary["requirements"]
    if not reqs:
        return []
    fig = Figure(figsize=(7, 3.4), layout="constrained")
    ax = fig.add_subplot()
    for i, r in enumerate(reqs):
        c = r["convergence"]
        n = np.asarray(c["n"], float)
        ax.plot(
            n,
            c["estimate"],
            color=f"C{i}",
            label=f"P({r['metric']} {r['relation']} {r['threshold']:g})",
        )
        ax.fill_between(n, c["low"], c["high"], color=f"C{i}", alpha=0.2)
    ax.set(
        xscale="log",
        xlabel="cases N",
        ylabel="probability",
        ylim=(0, 1),
        title="convergence of the estimates (confidence band)",
    )
    ax.grid(alpha=0.3)
    ax.legend(fontsize="small")
    fig.savefig(folder / "convergence.png", dpi=100)
    return ["convergence.png"]


def statistics_tables(summary: dict[str, Any], sensitivity: dict[str, dict[str, Any]]) -> str:
    """The requirements (probability, confidence interval, cases met), the metrics'
    percentiles and the sensitivity rankings of a Monte Carlo, as HTML tables."""
    esc = html.escape
    rows = "".join(
        f"<tr><td>{esc(r['metric'])} {esc(r['relation'])} {r['threshold']:g}</td>"
        f"<td>{r['probability']:.4f}</td><td>[{r['low']:.4f}, {r['high']:.4f}]</td>"
        f"<td>{r['successes']} / {r['n']}</td></tr>"
        for r in summary["requirements"]
    )
    req = (
        (
            f"<h2>Requirements</h2><table><tr><th>requirement</th><th>probability</th>"
            f"<th>{100 * summary['requirements'][0]['confidence']:g} % interval "
            f"({esc(summary['requirements'][0]['method'])})</th><th>met</th></tr>"
            f"{rows}</table>"
        )
        if summary["requirements"]
        else ""
    )
    qs = ("5", "50", "95")
    mrows = "".join(
        f"<tr><td>{esc(metric_label(name))}</td>"
        + "".join(f"<td>{_fmt(m['percentiles'].get(q))}</td>" for q in qs)
        + f"<td>{_fmt(m['mean'])}</td><td>{m['n_nan']}</td></tr>"
        for name, m in summary["metrics"].items()
    )
    met = (
        f"<h2>Metrics</h2><table><tr><th>metric</th><th>5 %</th><th>median</th><th>95 %</th>"
        f"<th>mean</th><th>not finite</th></tr>{mrows}</table>"
    )
    srows = "".join(
        f"<tr><td>{esc(metric_label(name))}</td><td>{esc(s['method'])}</td><td>"
        + ", ".join(f"{esc(p)} ({_score(s, p)})" for p in s["ranking"])
        + "</td></tr>"
        for name, s in sensitivity.items()
    )
    sens = (
        (
            f"<h2>Sensitivity</h2><p>Parameters ranked by their effect on each metric "
            f"(Sobol' total and first-order indices from a Saltelli design, else the rank "
            f"correlation of the sample).</p>"
            f"<table><tr><th>metric</th><th>method</th><th>ranking (score)</th></tr>{srows}"
            f"</table>"
        )
        if srows
        else ""
    )
    return req + met + sens


def _score(ranking: dict[str, Any], parameter: str) -> str:
    """A parameter's score in a ranking: Sobol' total and first-order indices, or the sample
    method's score."""
    if ranking["method"] == "sobol":
        i = ranking["indices"][parameter]
        return f"S_T {i['ST']:.3g} ± {i['ST_conf']:.2g}, S_1 {i['S1']:.3g}"
    return f"{ranking['scores'][parameter]['score']:.3g}"


def _fmt(value: float | None) -> str:
    return "n/a" if value is None or not np.isfinite(value) else f"{value:.5g}"


def write_data(result: BatchReport, ds: xr.Dataset, folder: Path) -> None:
    """``summary.json`` (the statistics, the sensitivity, the trade surfaces) and a copy of the
    store, ``results.zarr``."""
    summary = {
        "scenario": result.scenario.name,
        "kind": result.scenario.kind,
        "cases": int(ds.sizes["case"]),
        "sampling": result.scenario.sampling,
        **result.summary,
        "sensitivity": result.sensitivity,
        "trade_surfaces": result.surfaces,
    }
    (folder / "summary.json").write_text(dumps(summary), encoding="utf-8")
    shutil.copytree(result.store, folder / "results.zarr")


def draw_figures(result: BatchReport, ds: xr.Dataset, folder: Path) -> list[str]:
    """A sweep's trade surfaces and contours or a Monte Carlo's distributions, then the
    convergence of the estimates; the file names."""
    metrics = _metrics(ds)
    return (
        _trade_surfaces(result, folder) + _contours(result, metrics, folder)
        if result.scenario.kind == "sweep"
        else distribution_figures(result.summary, metrics, folder)
    ) + convergence_figure(result.summary, folder)


def sections(result: BatchReport, ds: xr.Dataset, figures: list[str]) -> str:
    """The page: what ran, the requirement, metric and sensitivity tables, the figures."""
    esc = html.escape
    return (
        f"<p>{int(ds.sizes['case'])} cases of "
        + (f"run <b>{esc(result.scenario.run)}</b>" if result.scenario.run else "every run")
        + " of "
        f"<code>{esc(result.scenario.scenario)}</code>, sampling "
        f"{esc(result.scenario.sampling)}.</p>"
        + statistics_tables(result.summary, result.sensitivity)
        + f"<h2>Figures</h2>{images_html(figures)}"
    )


__all__ = [
    "BatchReport",
    "convergence_figure",
    "distribution_figures",
    "draw_figures",
    "sections",
    "statistics_tables",
    "write_data",
]
