"""Report of a slew scenario (``kind: slew``): ``metrics.json``, ``results.nc`` and
``index.html`` with the goals table and the figures of EPS slew study c. 1989, interactive
(:func:`plots`; :func:`draw_figures` draws the same as PNG files, for documents).

``results.nc`` holds every run (the nominal torque alone first, as ``open loop``) over
``(run, time[, component])``: the recorded channels of the flexible plant (``attitude``,
``euler123``, ``rate``, ``torque``, ``force_<node><AXIS>``, ``displacement_<node><AXIS>``), the
Euler-angle error against the nominal maneuver ``euler123_error``, the rim deflections
``rim_deflection_<node>`` (norm of the node's displacement), the nominal ``nominal_torque`` and
``nominal_euler123`` over ``time``, and the goal metrics over ``run``. Global attributes: the
scenario (``scenario_yaml``), the maneuver time ``duration_s`` and the goals. Open it with
``xarray.open_dataset(path, engine="h5netcdf")``.

The figures follow the paper's (EPS slew study c. 1989 Figs. 3–17): the
nominal torques and Euler angles, the
Euler-angle errors of every run with the goal band at 1.25 T, the rim deflections of the
antenna nodes open against closed loop, the torque perturbations and the point forces.
"""

from __future__ import annotations

import functools
import html
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np
from matplotlib.figure import Figure

from flexsat.report.interactive import Curve, Plot
from flexsat.report.page import format_metric

if TYPE_CHECKING:
    import xarray as xr
    from matplotlib.axes import Axes

#: a panel of a runs plot: its y label and a run label's values
Panel = tuple[str, Callable[[Any], np.ndarray]]


class SlewReport(Protocol):
    """What this report reads of a slew result (:class:`flexsat.scenarios.slew.SlewResult`)."""

    @property
    def labels(self) -> tuple[str, ...]: ...
    @property
    def notes(self) -> tuple[str, ...]: ...
    def attributes(self) -> dict[str, float]: ...


#: goal table columns: (metric, heading, verdict metric or None)
GOAL_COLUMNS = (
    ("angle_error_mrad", "Euler error at 1.25 T (mrad)", "angle_goal_met"),
    ("deflection_ratio_after", "rim deflection open/closed from 1.25 T", "deflection_goal_met"),
    ("deflection_ratio_slew", "rim deflection open/closed during the slew", None),
    ("peak_rim_deflection_after_m", "peak rim deflection from 1.25 T (m)", None),
    ("peak_torque_perturbation_Nm", "peak torque perturbation (N m)", None),
    ("peak_force_N", "peak force (N)", None),
)


def _figure(rows: int, title: str) -> tuple[Figure, np.ndarray]:
    fig = Figure(figsize=(8, 2.4 * rows + 0.6), layout="constrained")
    fig.suptitle(title)
    return fig, fig.subplots(rows, 1, sharex=True, squeeze=False)[:, 0]


def _mark(ax: Axes, ds: xr.Dataset) -> None:
    """The maneuver time T and the evaluation time 1.25 T."""
    T = ds.attrs["duration_s"]
    ax.axvline(T, color="0.5", linewidth=0.8)
    ax.axvline(ds.attrs["goal_evaluation"] * T, color="0.5", linewidth=0.8, linestyle="--")
    ax.grid(alpha=0.3)


def _nominal(ds: xr.Dataset, path: Path) -> None:
    fig, (a, b) = _figure(2, "nominal maneuver (open-loop rigid-body optimum)")
    t = ds["time"].values
    for j, axis in enumerate("xyz"):
        a.plot(t, 1e-3 * ds["nominal_torque"].values[:, j], label=f"{axis}")
        b.plot(t, ds["nominal_euler123"].values[:, j], label=f"θ{j + 1}")
    a.set(ylabel="torque (kN m)")
    b.set(ylabel="1-2-3 angle (rad)", xlabel="time (s)")
    for ax in (a, b):
        _mark(ax, ds)
        ax.legend(fontsize="small")
    fig.savefig(path, dpi=100)


def _runs_plot(
    ds: xr.Dataset, title: str, path: Path, panels: list[Panel], band: float | None = None
) -> None:
    """One panel per (ylabel, values of a run) pair, every run in its colour; ``band`` draws
    ±band (the goal's tolerance)."""
    fig, axes = _figure(len(panels), title)
    t = ds["time"].values
    for ax, (ylabel, values) in zip(axes, panels):
        for i, label in enumerate(ds["run"].values):
            ax.plot(t, values(label), color=f"C{i}", label=str(label))
        if band is not None:
            for level in (band, -band):
                ax.axhline(level, color="r", linewidth=0.8, linestyle=":")
        ax.set(ylabel=ylabel)
        _mark(ax, ds)
    axes[0].legend(fontsize="small", ncols=2)
    axes[-1].set(xlabel="time (s)")
    fig.savefig(path, dpi=100)


def _run_values(
    ds: xr.Dataset, name: str, scale: float, column: int | None, label: Any
) -> np.ndarray:
    values = ds[name].sel(run=label).values
    return scale * (values if column is None else values[:, column])


def _components(ds: xr.Dataset, variable: str, scale: float, unit: str) -> list[Panel]:
    """Panels of a vector variable's x, y, z components."""
    return [
        (f"{axis} ({unit})", functools.partial(_run_values, ds, variable, scale, j))
        for j, axis in enumerate("xyz")
    ]


def _scalars(
    ds: xr.Dataset, names: list[str], prefix: str, scale: float, ylabel: str
) -> list[Panel]:
    """Panels of scalar variables; ``ylabel`` formats each name without ``prefix``."""
    return [
        (
            ylabel.format(name[len(prefix) :]),
            functools.partial(_run_values, ds, name, scale, None),
        )
        for name in names
    ]


def _goal_table(records: list[dict[str, Any]], open_loop: str) -> str:
    esc = html.escape
    head = "".join(f"<th>{esc(h)}</th>" for _, h, _ in GOAL_COLUMNS)
    rows: list[str] = []
    for r in records:
        cells: list[str] = []
        for metric, _, verdict in GOAL_COLUMNS:
            value = r.get(metric)
            text = "–" if value is None else format_metric(value)
            if verdict == "deflection_goal_met" and r["run"] == open_loop:
                text += " (reference)"  # the open loop is what the goal compares with
            elif verdict is not None and r.get(verdict) is not None:
                met = bool(r[verdict])
                text += (
                    ' <b style="color:#080">PASS</b>' if met else ' <b style="color:#b00">FAIL</b>'
                )
            cells.append(f"<td>{text}</td>")
        rows.append(f"<tr><td>{esc(r['run'])}</td>{''.join(cells)}</tr>")
    return f"<table><tr><th>run</th>{head}</tr>{''.join(rows)}</table>"


def sections(result: SlewReport, records: list[dict[str, Any]], figures: list[str]) -> str:
    """The page's goals (against the open loop, the first run), notes and figures."""
    esc = html.escape
    ds_attrs = result.attributes()
    images = "".join(f'<figure><img src="{f}" alt="{esc(f)}"></figure>' for f in figures)
    static = f"<h2>Figures</h2>\n{images}\n" if images else ""
    goals = (
        f"Euler-angle error below {100 * ds_attrs['goal_angle_fraction']:g} % of the "
        f"commanded angle ({ds_attrs['goal_angle_tolerance_mrad']:g} mrad) at "
        f"{ds_attrs['goal_evaluation']:g} T; rim deflection from "
        f"{ds_attrs['goal_evaluation']:g} T on below "
        f"1/{ds_attrs['goal_deflection_ratio']:g} of the open-loop one (EPS slew study c. 1989 "
        "'Simulation Results'). The open-loop run is the nominal torque alone."
    )
    notes = "".join(f"<li>{esc(n)}</li>" for n in result.notes)
    return f"""<h2>Goals</h2>
<p>{esc(goals)}</p>
{_goal_table(records, result.labels[0])}
<ul>{notes}</ul>
{static}"""


def _interactive(
    ds: xr.Dataset, title: str, panels: list[Panel], band: float | None = None
) -> list[Plot]:
    """A figure per panel, every run a curve, the maneuver time T and 1.25 T marked."""
    t = ds["time"].values
    T = float(ds.attrs["duration_s"])
    marks = (T, float(ds.attrs["goal_evaluation"]) * T)
    bands = () if band is None else (band, -band)
    return [
        Plot(
            f"{title}: {ylabel.split(' (')[0]}",
            "time (s)",
            ylabel,
            tuple(Curve(str(r), str(r), t, values(r)) for r in ds["run"].values),
            hlines=bands,
            vlines=marks,
        )
        for ylabel, values in panels
    ]


def plots(ds: xr.Dataset) -> list[Plot]:
    """The figures of the EPS slew study c. 1989 (module docstring), a figure per panel: the
    nominal maneuver, then per run the Euler-angle errors with the goal band, the rim
    deflections, the torque perturbations and the point forces."""
    t = ds["time"].values
    T = float(ds.attrs["duration_s"])
    marks = (T, float(ds.attrs["goal_evaluation"]) * T)
    nominal = [
        Plot(
            "nominal maneuver: torque",
            "time (s)",
            "torque (kN m)",
            tuple(
                Curve("", axis, t, 1e-3 * ds["nominal_torque"].values[:, j], color=j)
                for j, axis in enumerate("xyz")
            ),
            vlines=marks,
        ),
        Plot(
            "nominal maneuver: 1-2-3 angles",
            "time (s)",
            "1-2-3 angle (rad)",
            tuple(
                Curve("", f"θ{j + 1}", t, ds["nominal_euler123"].values[:, j], color=j)
                for j in range(3)
            ),
            vlines=marks,
        ),
    ]
    tol = ds.attrs["goal_angle_tolerance_mrad"]
    rims = [str(n) for n in ds.data_vars if str(n).startswith("rim_deflection_")]
    forces = [
        name
        for name in map(str, ds.data_vars)
        if name.startswith("force_") and not name.endswith("_command") and np.any(ds[name].values)
    ]
    return (
        nominal
        + _interactive(
            ds, "Euler-angle error", _components(ds, "euler123_error", 1e3, "mrad"), band=tol
        )
        + _interactive(
            ds, "rim deflection", _scalars(ds, rims, "rim_deflection_", 1e3, "node {} (mm)")
        )
        + _interactive(
            ds, "torque perturbation", _components(ds, "torque_perturbation", 1e-3, "kN m")
        )
        + _interactive(ds, "point force", _scalars(ds, forces, "force_", 1.0, "{} (N)"))
    )


def draw_figures(ds: xr.Dataset, folder: Path) -> list[str]:
    """The figures of the EPS slew study c. 1989 (module docstring) into ``folder``; their
    file names."""
    tol = ds.attrs["goal_angle_tolerance_mrad"]
    figures = ["nominal.png", "euler_error.png", "rim_deflection.png", "torque_perturbation.png"]
    _nominal(ds, folder / figures[0])
    _runs_plot(
        ds,
        "Euler-angle error against the nominal",
        folder / figures[1],
        _components(ds, "euler123_error", 1e3, "mrad"),
        band=tol,
    )
    rims = [str(n) for n in ds.data_vars if str(n).startswith("rim_deflection_")]
    _runs_plot(
        ds,
        "rim deflections, open against closed loop",
        folder / figures[2],
        _scalars(ds, rims, "rim_deflection_", 1e3, "node {} (mm)"),
    )
    _runs_plot(
        ds,
        "torque minus the nominal torque",
        folder / figures[3],
        _components(ds, "torque_perturbation", 1e-3, "kN m"),
    )
    forces = [
        name
        for name in map(str, ds.data_vars)
        if name.startswith("force_") and not name.endswith("_command") and np.any(ds[name].values)
    ]
    if forces:
        figures.append("forces.png")
        _runs_plot(
            ds, "point forces", folder / figures[-1], _scalars(ds, forces, "force_", 1.0, "{} (N)")
        )
    return figures


__all__ = ["GOAL_COLUMNS", "SlewReport", "draw_figures", "plots", "sections"]
