"""Report of a maneuver scenario: ``metrics.json``, ``results.nc`` and ``index.html`` with the
metrics, the controller summary and the interactive time histories (written by
:func:`flexsat.report.page.write_report`; this module describes the figures and the page's
sections).

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

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from flexsat.report.interactive import Curve, Plot
from flexsat.report.page import metrics_html

if TYPE_CHECKING:
    import xarray as xr


@dataclass(frozen=True)
class TimePlot:
    """One figure: ``variable`` (and its ``reference``, dashed) of every run against time."""

    title: str
    variable: str
    ylabel: str
    scale: float = 1.0
    reference: str | None = None


#: the time histories of the page, in order
PLOTS = (
    TimePlot("Hub angle", "theta", "angle (deg)", np.degrees(1.0), "theta_ref"),
    TimePlot("Hub rate", "theta_dot", "rate (deg/s)", np.degrees(1.0), "theta_dot_ref"),
    TimePlot("Applied hub torque", "torque", "torque (N m)"),
    TimePlot("Appendage tip deflection", "tip_deflection", "deflection (mm)", 1e3),
    TimePlot("Vibration energy of the appendages", "vibration_energy", "energy (J)"),
)


def _plot(ds: xr.Dataset, spec: TimePlot) -> Plot:
    t = ds["time"].values
    curves = []
    for label in map(str, ds["run"].values):
        curves.append(Curve(label, label, t, spec.scale * ds[spec.variable].sel(run=label).values))
        if spec.reference is not None:
            reference = spec.scale * ds[spec.reference].sel(run=label).values
            curves.append(Curve(label, f"{label} reference", t, reference, "dashed"))
    return Plot(spec.title, "time (s)", spec.ylabel, tuple(curves))


def plots(ds: xr.Dataset) -> list[Plot]:
    """The figures of :data:`PLOTS`, every run of ``ds`` in each."""
    return [_plot(ds, spec) for spec in PLOTS]


def sections(records: list[dict[str, Any]]) -> str:
    """The page's metrics table (a row per metric, a column per run)."""
    return f"""<h2>Metrics</h2>
<p>n/a: not settled within the band, or not applicable.</p>
{metrics_html(records)}"""


__all__ = ["PLOTS", "TimePlot", "plots", "sections"]
