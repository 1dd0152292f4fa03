"""Report of a scenario run: ``metrics.json``, ``results.nc``, PNG plots and ``index.html``.

``results.nc`` (netCDF4/HDF5 written by xarray's h5netcdf engine, no pickle) is one dataset with
dims ``(run, time)``:

- coordinates ``run`` (the run labels, strings) and ``time`` (s);
- the time histories of :class:`flexsat.sim.SimResult` over ``(run, time)`` -- ``theta``,
  ``theta_dot``, ``theta_ref``, ``theta_dot_ref``, ``torque_command``, ``torque``,
  ``disturbance_torque``, ``friction_torque``, ``root_torque``, ``root_torque_measured``,
  ``tip_deflection``, ``energy``, ``vibration_energy`` -- each with a ``units`` attribute (SI);
- the metrics over ``run`` (``settling_time_s``, ``overshoot_deg``, ... ; NaN = not settled or
  not applicable);
- global attributes ``scenario_name``, ``case``, ``case_source``, ``scenario_yaml`` (the scenario
  as given), ``control_rate_Hz`` and ``settling_band_rad``.

Open it with ``xarray.open_dataset(path, engine="h5netcdf")``.
"""

from __future__ import annotations

import html
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from flexsat.report.publish import write_atomically, write_metrics_and_results
from flexsat.scenarios.runner import ScenarioResult


@dataclass(frozen=True)
class _Plot:
    """One figure: ``variable`` (and its ``reference``, dashed) of every run against time."""

    file: str
    title: str
    variable: str
    ylabel: str
    scale: float = 1.0
    reference: str | None = None


PLOTS = (
    _Plot("hub_angle.png", "Hub angle", "theta", "angle (deg)", np.degrees(1.0), "theta_ref"),
    _Plot(
        "hub_rate.png", "Hub rate", "theta_dot", "rate (deg/s)", np.degrees(1.0), "theta_dot_ref"
    ),
    _Plot("torque.png", "Applied hub torque", "torque", "torque (N m)"),
    _Plot(
        "tip_deflection.png", "Appendage tip deflection", "tip_deflection", "deflection (mm)", 1e3
    ),
    _Plot(
        "vibration_energy.png",
        "Vibration energy of the appendages",
        "vibration_energy",
        "energy (J)",
    ),
)


def format_metric(value: float | None) -> str:
    """A metric for display: 4 significant digits, ``n/a`` for None (not settled/applicable)."""
    return "n/a" if value is None else f"{value:.4g}"


def html_table(headings, rows) -> str:
    """An HTML table: a heading row, then one row per item of ``rows`` (cells shown with
    ``str``, every text escaped)."""
    esc = html.escape
    head = "".join(f"<th>{esc(str(h))}</th>" for h in headings)
    body = "".join(
        "<tr>" + "".join(f"<td>{esc(str(c))}</td>" for c in row) + "</tr>" for row in rows
    )
    return f"<table><tr>{head}</tr>{body}</table>"


def metric_rows(records: list[dict]) -> list[tuple[str, list[str]]]:
    """Metrics table, one row per metric and one formatted column per run of ``records``."""
    names = [key for key in records[0] if key != "run"]
    return [(name, [format_metric(r[name]) for r in records]) for name in names]


#: the report pages' style sheet
STYLE = """<style>
body { font-family: sans-serif; margin: 2em auto; max-width: 60em; }
table { border-collapse: collapse; margin-bottom: 1em; }
th, td { border: 1px solid #bbb; padding: 0.2em 0.6em; text-align: right; }
td:first-child { text-align: left; font-family: monospace; }
img { max-width: 100%; }
pre { background: #f4f4f4; padding: 1em; overflow-x: auto; }
</style>"""


def report_page(result, body: str, title: str = "flexsat report", case: str | None = None) -> str:
    """A report's index.html: the heading, the scenario and its case (``case``, default the
    scenario's) with the case's source, ``body`` (HTML), and the scenario as given."""
    esc = html.escape
    case = result.scenario.case if case is None else case
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>{esc(title)}: {esc(result.scenario.name)}
</title>
{STYLE}</head>
<body>
<h1>{esc(title)}</h1>
<p><b>Scenario:</b> {esc(result.scenario.name)}<br><b>Case:</b> {esc(case)}
({esc(result.case_source)})</p>
{body}
<h2>Scenario</h2>
<pre>{esc(result.scenario.yaml_text)}</pre>
</body></html>
"""


def _plot(ds, spec: _Plot, path: Path) -> None:
    fig = Figure(figsize=(7, 3.6), layout="constrained")
    ax = fig.add_subplot()
    t = ds["time"].values
    for i, label in enumerate(ds["run"].values):
        color = f"C{i}"
        ax.plot(t, spec.scale * ds[spec.variable].sel(run=label).values, color=color, label=label)
        if spec.reference is not None:
            ax.plot(
                t,
                spec.scale * ds[spec.reference].sel(run=label).values,
                color=color,
                linestyle="--",
                linewidth=1,
                label=f"{label} reference",
            )
    ax.set(title=spec.title, xlabel="time (s)", ylabel=spec.ylabel)
    ax.grid(alpha=0.3)
    ax.legend(fontsize="small")
    fig.savefig(path, dpi=110)


def _html(result: ScenarioResult, records: list[dict]) -> str:
    esc = html.escape
    head = "".join(f"<th>{esc(r['run'])}</th>" for r in records)
    rows = "".join(
        f"<tr><td>{esc(metric)}</td>" + "".join(f"<td>{v}</td>" for v in values) + "</tr>"
        for metric, values in metric_rows(records)
    )
    images = "".join(f'<figure><img src="{p.file}" alt="{esc(p.title)}"></figure>' for p in PLOTS)
    return report_page(
        result,
        f"""<h2>Metrics</h2>
<p>n/a: not settled within the band, or not applicable.</p>
<table><tr><th>metric</th>{head}</tr>{rows}</table>
<h2>Time histories</h2>
{images}""",
    )


def _write_all(result: ScenarioResult, folder: Path) -> None:
    records, ds = write_metrics_and_results(result, folder)
    for spec in PLOTS:
        _plot(ds, spec, folder / spec.file)
    (folder / "index.html").write_text(_html(result, records), encoding="utf-8")


def write_report(result: ScenarioResult, out_dir) -> Path:
    """Write the report of ``result`` as the folder ``out_dir``, whole or not at all
    (:func:`flexsat.report.publish.write_atomically`).

    Parameters
    ----------
    result : ScenarioResult
    out_dir : str or Path
        Created if needed; an earlier report there is replaced as a whole (a folder holding
        other files is refused).

    Returns
    -------
    Path
        ``out_dir``, resolved.

    Raises
    ------
    flexsat.report.publish.OutputError
        When the folder cannot be written (disk full, read-only, ...); ``out_dir`` is unchanged.
    """
    return write_atomically(out_dir, lambda folder: _write_all(result, folder))


__all__ = ["PLOTS", "STYLE", "format_metric", "html_table", "metric_rows", "write_report"]
