"""Report of a design study (``kind: design_study``): every stage -- what it computed, whether it
came from the stage cache, its fingerprint and its key numbers -- then the runs' metrics and
figures.

``results.nc`` holds the runs over ``(run, time[, component])`` (the recorded channels of the
flexible spacecraft: ``attitude``, ``euler123``, ``rate``, ``torque``, ``force_<node><AXIS>``,
``displacement_<node><AXIS>``), the attitude each run's law turns to (``target_attitude``,
over ``run`` and ``attitude_component``), the run metrics over ``run`` and the kept modes
(``frequency_hz``, ``damping`` over ``mode``, rigid modes first); its attributes name every
stage's fingerprint and origin (``stage_model``: ``<sha256> (fresh)``). A study with
dispersions adds ``dispersions.json`` (probabilities with confidence intervals, percentiles,
sensitivity) and ``dispersions.zarr`` (every case's parameters and metrics).
"""

from __future__ import annotations

import html
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from flexsat.report.display import metric_label
from flexsat.report.page import format_metric, html_table, images_html

if TYPE_CHECKING:
    import xarray as xr

    from flexsat.design.stages import StageRecord


class DesignStudyReport(Protocol):
    """What this report reads of a study's result
    (:class:`flexsat.scenarios.design_study.DesignStudyResult`; ``dispersions`` its
    :class:`~flexsat.scenarios.design_dispersions.DispersionsResult` or None)."""

    @property
    def records(self) -> Sequence[StageRecord]: ...
    @property
    def dispersions(self) -> Any: ...
    def metrics_records(self) -> list[dict[str, Any]]: ...


def _dispersions_section(dispersions: Any) -> str:
    """What the Monte Carlo measured (the nominal design on dispersed spacecraft), the
    parameters, then the batch report's requirement, percentile and sensitivity tables."""
    from flexsat.report.batch import statistics_tables

    if dispersions is None:
        return ""
    esc = html.escape
    n = len(next(iter(dispersions.metrics.values())))
    rows = [
        (
            path,
            dispersions.units[path] or "-",
            format_metric(float(np.min(values))),
            format_metric(float(np.median(values))),
            format_metric(float(np.max(values))),
        )
        for path, values in dispersions.table.items()
    ]
    runs = ", ".join(esc(run) for run in dispersions.runs)
    return f"""<h2>Dispersions</h2>
<p>{n} cases. The placement and the laws are those designed on the <b>nominal</b> model (the
stages above); each case builds its spacecraft from its dispersed values (the model and its
modes re-solved when the model is dispersed, the truth's inertia, frequencies and damping
departures applied) and flies the nominal laws on that <b>dispersed truth</b> with the study's
sensors and disturbances, its noise its own (runs: {runs}). The probabilities below are
those of this design meeting each requirement on a spacecraft built within the dispersions:
its robustness, not that of a law redesigned per case.</p>
{html_table(("parameter", "SI unit", "least", "median", "greatest"), rows)}
{statistics_tables(dispersions.summary, dispersions.sensitivity)}
"""


def write_dispersions(dispersions: Any, folder: Path) -> None:
    """``dispersions.json`` (the runs flown, the parameters' SI units, per metric its summary
    and percentiles, per requirement the probability of meeting it with its confidence
    interval, the sensitivity rankings; NaN as null) and a copy of the cases' zarr store,
    ``dispersions.zarr``; nothing without dispersions."""
    import shutil

    from flexsat.report.json_data import dumps

    if dispersions is None:
        return
    data = {
        "cases": len(next(iter(dispersions.metrics.values()))),
        "runs": list(dispersions.runs),
        "units": dispersions.units,
        **dispersions.summary,
        "sensitivity": dispersions.sensitivity,
    }
    (folder / "dispersions.json").write_text(dumps(data), encoding="utf-8")
    shutil.copytree(dispersions.store, folder / "dispersions.zarr")


def dispersion_figures(dispersions: Any, folder: Path) -> list[str]:
    """Each dispersed metric's histogram and CDF with its requirement lines and the convergence
    of the probability estimates (:mod:`flexsat.report.batch`); none without dispersions."""
    from flexsat.report.batch import convergence_figure, distribution_figures

    if dispersions is None:
        return []
    return distribution_figures(
        dispersions.summary, dispersions.metrics, folder
    ) + convergence_figure(dispersions.summary, folder)


def _number(value: Any) -> str:
    if isinstance(value, bool) or value is None or isinstance(value, str):
        return "n/a" if value is None else str(value)
    if isinstance(value, (list, tuple)):
        if len(value) > 8:
            return ", ".join(_number(v) for v in value[:8]) + f", … ({len(value)} values)"
        return ", ".join(_number(v) for v in value)
    return format_metric(float(value))


def _stage_table(records: Sequence[StageRecord]) -> str:
    rows = [
        (
            r.stage.label,
            "cache" if r.cached else "fresh",
            f"{r.seconds:.3g}",
            r.stage.key[:16],
        )
        for r in records
    ]
    return html_table(("stage", "origin", "time (s)", "fingerprint"), rows)


def _summary_table(summary: Mapping[str, Any], skip: Sequence[str] = ()) -> str:
    rows = [(key, _number(value)) for key, value in summary.items() if key not in skip]
    return html_table(("quantity", "value"), rows) if rows else ""


def _modes_table(summary: Mapping[str, Any]) -> str:
    frequencies = summary["frequencies_hz"]
    damping = summary["damping"]
    rows = [
        (str(i + 1), f"{f:.5g}", f"{z:.4g}") for i, (f, z) in enumerate(zip(frequencies, damping))
    ]
    return html_table(("elastic mode", "frequency (Hz)", "damping ratio"), rows)


def _stage_section(record: StageRecord) -> str:
    esc = html.escape
    name, summary = record.stage.name, record.summary
    origin = "read from the stage cache" if record.cached else "computed"
    head = f"<h3>{esc(record.stage.label)} ({origin})</h3>"
    if name in ("model", "modes"):
        return head + _summary_table(summary, ("frequencies_hz", "damping")) + _modes_table(summary)
    if name == "placement":
        chosen = ", ".join(summary["selection"]) or "none"
        return (
            head
            + f"<p>Placed forces: <b>{esc(chosen)}</b>; criterion of the selection "
            + (f"{format_metric(summary['criterion_value'])}.</p>")
        )
    return head + _summary_table(summary)


def sections(result: DesignStudyReport, figures: list[str]) -> str:
    """The page: the stages table, each stage's numbers, the runs' metrics, the dispersions'
    statistics and the figures."""
    records = list(result.records)
    metrics = result.metrics_records()
    names = [key for key in metrics[0] if key != "run"]
    run_rows = [(m["run"], *(format_metric(m[k]) for k in names)) for m in metrics]
    design = "".join(_stage_section(r) for r in records if r.stage.name != "run")
    return f"""<h2>Stages</h2>
<p>Each stage is named by the fingerprint of its section and of the stages upstream of it; a
stage whose fingerprint is in the cache is read from it, not recomputed.</p>
{_stage_table(records)}
{design}
<h2>Runs</h2>
{html_table(("run", *map(metric_label, names)), run_rows)}
{_dispersions_section(result.dispersions)}
<h2>Figures</h2>
{images_html(figures)}
"""


def draw_figures(ds: xr.Dataset, folder: Path) -> list[str]:
    """The attitude error angle (from the run's law's target, 2 arccos|β_tᵀβ|) and the largest
    recorded node displacement of every run, over time, into ``folder``; the file names."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(8, 5.4), layout="constrained")
    fig.suptitle("runs")
    top, bottom = fig.subplots(2, 1, sharex=True)
    t = ds["time"].values
    names = [n for n in ds.data_vars if str(n).startswith("displacement_")]
    for label in ds["run"].values:
        run = ds.sel(run=label)
        cosine = np.clip(np.abs(run["attitude"].values @ run["target_attitude"].values), 0, 1)
        top.plot(t, np.degrees(2 * np.arccos(cosine)), label=str(label))
        peak = np.max(np.abs(np.stack([run[n].values for n in names], -1)), axis=-1)
        bottom.plot(t, 1e3 * peak, label=str(label))
    top.set_ylabel("attitude error (deg)")
    bottom.set_ylabel("largest displacement (mm)")
    bottom.set_xlabel("time (s)")
    for ax in (top, bottom):
        ax.grid(alpha=0.3)
    top.legend(fontsize="small")
    fig.savefig(folder / "runs.png", dpi=100)
    return ["runs.png"]


__all__ = [
    "DesignStudyReport",
    "dispersion_figures",
    "draw_figures",
    "sections",
    "write_dispersions",
]
