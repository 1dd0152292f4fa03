"""Report of a maneuver scenario: ``metrics.json``, ``results.nc``, PNG plots and ``index.html``
(written by :func:`flexsat.report.page.write_report`; this module draws the figures and the
page's sections).

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
from typing import TYPE_CHECKING, Any

import numpy as np
from matplotlib.figure import Figure

from flexsat.report.page import metric_rows

if TYPE_CHECKING:
    import xarray as xr


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


def _plot(ds: xr.Dataset, spec: _Plot, path: Path) -> None:
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


def draw_figures(ds: xr.Dataset, folder: Path) -> list[str]:
    """Draw :data:`PLOTS` of the runs in ``ds`` into ``folder``; their file names."""
    for spec in PLOTS:
        _plot(ds, spec, folder / spec.file)
    return [spec.file for spec in PLOTS]


def sections(records: list[dict[str, Any]], figures: list[str]) -> str:
    """The page's metrics table (a column per run) and time histories."""
    esc = html.escape
    head = "".join(f"<th>{esc(r['run'])}</th>" for r in records)
    rows = "".join(
        f"<tr><td>{esc(metric)}</td>" + "".join(f"<td>{v}</td>" for v in values) + "</tr>"
        for metric, values in metric_rows(records)
    )
    titles = {p.file: p.title for p in PLOTS}
    images = "".join(
        f'<figure><img src="{f}" alt="{esc(titles.get(f, f))}"></figure>' for f in figures
    )
    return f"""<h2>Metrics</h2>
<p>n/a: not settled within the band, or not applicable.</p>
<table><tr><th>metric</th>{head}</tr>{rows}</table>
<h2>Time histories</h2>
{images}"""


__all__ = ["PLOTS", "draw_figures", "sections"]
