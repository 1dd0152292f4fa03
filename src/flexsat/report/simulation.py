"""Report of a simulation scenario (``kind: simulation``): ``metrics.json``, ``results.nc`` and
``index.html`` with the metrics and an interactive figure per recorded channel
(:func:`flexsat.report.page.write_report`; this module describes the figures and the page's
sections).

``results.nc`` holds every recorded channel over ``(run, time)`` or, for a vector channel,
``(run, time, <channel>_component)``, with its ``units`` attribute (SI), the metrics over
``run`` and the attributes ``scenario_name``, ``case``, ``case_source`` and ``scenario_yaml``.
Open it with ``xarray.open_dataset(path, engine="h5netcdf")``.
"""

from __future__ import annotations

import html
from typing import TYPE_CHECKING, Any

import numpy as np

from flexsat.report.interactive import Curve, Plot
from flexsat.report.page import metric_rows, metrics_html

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


#: the dash of a vector channel's component j (cycled)
_STYLES = ("solid", "dashed", "dotted", "dashdot")


def _plot(ds: xr.Dataset, name: str) -> Plot:
    var = ds[name]
    t = ds["time"].values
    extra = [d for d in var.dims if d not in ("run", "time")]
    curves = []
    for label in map(str, ds["run"].values):
        values = var.sel(run=label).transpose("time", *extra).values.reshape(len(t), -1)
        for j in range(values.shape[1]):
            suffix = f"[{j}]" if values.shape[1] > 1 else ""
            curves.append(Curve(label, f"{label}{suffix}", t, values[:, j], _STYLES[j % 4]))
    unit = var.attrs.get("units", "")
    return Plot(name, "time (s)", f"{name} ({unit})" if unit else name, tuple(curves))


def _html(records: list[dict[str, Any]], units: dict[str, str], idle: list[str]) -> str:
    esc = html.escape
    shown = [
        metric
        for metric, _ in metric_rows(records)
        if not any(metric.endswith("_" + n) for n in idle)
    ]
    table = (
        metrics_html([{k: r[k] for k in ("run", *shown)} for r in records], units)
        if records and shown
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
    return f"""<h2>Metrics</h2>
{table}
{quiet}
"""


def plots(ds: xr.Dataset) -> list[Plot]:
    """One figure per recorded time history worth one (:func:`_histories`), every run in it."""
    names, _ = _histories(ds)
    return [_plot(ds, name) for name in names]


def sections(records: list[dict[str, Any]], ds: xr.Dataset) -> str:
    """The page's metrics (idle channels' left out, each with its unit) and the idle
    channels."""
    _, idle = _histories(ds)
    units = {
        str(k): str(v.attrs.get("units", "")) for k, v in ds.data_vars.items() if v.dims == ("run",)
    }
    return _html(records, units, idle)


__all__ = ["MAX_FIGURES", "plots", "sections"]
