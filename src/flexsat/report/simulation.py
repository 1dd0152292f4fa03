"""Report of a simulation scenario (``kind: simulation``): ``metrics.json``, ``results.nc``, one
PNG per recorded channel and ``index.html`` (:func:`flexsat.report.page.write_report`; this
module draws the figures and the page's sections).

``results.nc`` holds every recorded channel over ``(run, time)`` or, for a vector channel,
``(run, time, <channel>_component)``, with its ``units`` attribute (SI), the metrics over
``run`` and the attributes ``scenario_name``, ``case``, ``case_source`` and ``scenario_yaml``.
Open it with ``xarray.open_dataset(path, engine="h5netcdf")``.
"""

from __future__ import annotations

import html
import re
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from matplotlib.figure import Figure

from flexsat.report.page import metric_rows

if TYPE_CHECKING:
    import xarray as xr

#: at most this many time-history figures (a plant with many output channels records them all
#: in results.nc; the page shows the first ones)
MAX_FIGURES = 24


def _histories(ds: xr.Dataset) -> tuple[list[str], list[str]]:
    """(plotted, idle): the recorded time histories worth a figure, measured and output
    channels before inputs, a command only where it differs from the applied input (an
    actuator acted on it); and the channels that are zero throughout every run (idle
    actuators), named on the page instead of plotted."""
    timed = [str(name) for name, var in ds.data_vars.items() if "time" in var.dims]
    commands = [n for n in timed if n.endswith("_command")]
    inputs = {n[: -len("_command")] for n in commands}
    idle = [n for n in timed if not np.any(ds[n].values)]
    plotted = [n for n in timed if n not in idle and n not in commands and n not in inputs]
    for name in sorted(inputs, key=timed.index):
        if name not in idle:
            plotted.append(name)
            command = f"{name}_command"
            if not np.array_equal(ds[command].values, ds[name].values):
                plotted.append(command)
    return plotted[:MAX_FIGURES], [n for n in idle if not n.endswith("_command")]


def _file(name: str) -> str:
    return re.sub(r"[^A-Za-z0-9_]+", "_", name) + ".png"


def _plot(ds: xr.Dataset, name: str, path: Path) -> None:
    var = ds[name]
    fig = Figure(figsize=(7, 3.4), layout="constrained")
    ax = fig.add_subplot()
    t = ds["time"].values
    extra = [d for d in var.dims if d not in ("run", "time")]
    for i, label in enumerate(ds["run"].values):
        values = var.sel(run=label).transpose("time", *extra).values
        values = values.reshape(len(t), -1)
        for j in range(values.shape[1]):
            suffix = f"[{j}]" if values.shape[1] > 1 else ""
            ax.plot(
                t,
                values[:, j],
                color=f"C{i}",
                linestyle=("-", "--", ":", "-.")[j % 4],
                label=f"{label}{suffix}",
            )
    unit = var.attrs.get("units", "")
    ax.set(title=name, xlabel="time (s)", ylabel=f"{name} ({unit})" if unit else name)
    ax.grid(alpha=0.3)
    ax.legend(fontsize="small", ncols=2)
    fig.savefig(path, dpi=100)


def _html(
    records: list[dict[str, Any]], names: list[str], units: dict[str, str], idle: list[str]
) -> str:
    esc = html.escape
    head = "".join(f"<th>{esc(r['run'])}</th>" for r in records)

    def label(metric: str) -> str:
        unit = units.get(metric, "")
        return f"{metric} ({unit})" if unit and not metric.endswith(("_deg", "_s")) else metric

    rows = (
        "".join(
            f"<tr><td>{esc(label(metric))}</td>"
            + "".join(f"<td>{v}</td>" for v in values)
            + "</tr>"
            for metric, values in metric_rows(records)
            if not any(metric.endswith("_" + n) for n in idle)
        )
        if records and len(records[0]) > 1
        else ""
    )
    quiet = (
        (
            "<p>Zero throughout every run (not plotted): "
            + ", ".join(f"<code>{esc(n)}</code>" for n in idle)
            + ".</p>"
        )
        if idle
        else ""
    )
    images = "".join(f'<figure><img src="{_file(n)}" alt="{esc(n)}"></figure>' for n in names)
    return f"""<h2>Metrics</h2>
<table><tr><th>metric</th>{head}</tr>{rows}</table>
<h2>Time histories</h2>
{quiet}
{images}
"""


def draw_figures(ds: xr.Dataset, folder: Path) -> list[str]:
    """One figure per recorded time history worth one (:func:`_histories`); the file names."""
    names, _ = _histories(ds)
    for name in names:
        _plot(ds, name, folder / _file(name))
    return [_file(n) for n in names]


def sections(records: list[dict[str, Any]], ds: xr.Dataset) -> str:
    """The page's metrics (idle channels' left out) and time histories."""
    names, idle = _histories(ds)
    units = {
        str(k): str(v.attrs.get("units", "")) for k, v in ds.data_vars.items() if v.dims == ("run",)
    }
    return _html(records, names, units, idle)


__all__ = ["MAX_FIGURES", "draw_figures", "sections"]
