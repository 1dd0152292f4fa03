"""Report of a CMG scenario (``kind: cmg`` or ``kind: cmg_station``): ``metrics.json``,
``results.nc``, figures and ``index.html``.

``kind: cmg``: per run the gimbal angles, the gain det(CCᵀ) and the momentum against the
envelope along the demand, and the V1–V8 table (published against computed).
``results.nc`` holds over ``run`` × ``sample``: ``time`` (s), ``gimbal_angles`` (rad),
``momentum`` (rotor momenta), ``gain`` (NaN past the end of a run stopped at a singular set,
which holds fewer samples), and ``initial_angles``, ``outcome``.

``kind: cmg_station``: the attitude (roll, pitch, yaw), the CMG momentum and the torques of the
attitude loop against time, and per run the gimbal angles and the gain (NaN after a singular
stop). ``results.nc``: ``attitude`` (rad), ``cmg_momentum`` (N m s), ``torque``,
``disturbance`` (N m) over ``time`` × ``axis``; ``gimbal_angles``, ``gain`` over ``run`` ×
``time``. Open with ``xarray.open_dataset(path, engine="h5netcdf")``.
"""

from __future__ import annotations

import html
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np
from matplotlib.figure import Figure

from flexsat.report.display import metric_label
from flexsat.report.page import format_metric, html_table

if TYPE_CHECKING:
    import xarray as xr

    from flexsat.cases.space_station_cmg import StationRun
    from flexsat.dynamics.cmg import GimbalRun
    from flexsat.units import FloatArray


class CmgRunReport(Protocol):
    """What this report reads of one run of a ``kind: cmg`` result
    (:class:`flexsat.scenarios.cmg.CmgRun`)."""

    @property
    def label(self) -> str: ...
    @property
    def gimbals(self) -> GimbalRun: ...
    @property
    def sigma0(self) -> FloatArray: ...
    @property
    def direction(self) -> FloatArray | None: ...
    @property
    def outcome(self) -> str: ...


class CmgReport(Protocol):
    """What this report reads of a ``kind: cmg`` result
    (:class:`flexsat.scenarios.cmg.CmgResult`)."""

    @property
    def runs(self) -> Sequence[CmgRunReport]: ...
    @property
    def table(self) -> Sequence[tuple[str, str, float, float, str]]: ...
    @property
    def notes(self) -> Sequence[str]: ...
    def metrics_records(self) -> list[dict[str, Any]]: ...


class StationReport(Protocol):
    """What this report reads of a ``kind: cmg_station`` result
    (:class:`flexsat.scenarios.cmg.StationResult`)."""

    @property
    def station(self) -> StationRun: ...
    @property
    def notes(self) -> Sequence[str]: ...


_FT_LB_S = 1.3558179483314006  # N m s per ft-lb-s: the station's plots are in the paper's units


def _gimbal_figure(ds: xr.Dataset, path: Path, time_of: Callable[[Any], FloatArray]) -> None:
    runs = ds["run"].values
    fig = Figure(figsize=(9, 2.6 * len(runs) + 0.6), layout="constrained")
    axes = np.atleast_2d(fig.subplots(len(runs), 2, squeeze=False))
    fig.suptitle("gimbal angles (left) and gain det(CCᵀ) (right)")
    for (a, b), run in zip(axes, runs):
        t = time_of(run)
        sig = np.rad2deg(ds["gimbal_angles"].sel(run=run).values)
        for k in range(sig.shape[1]):
            a.plot(t, sig[:, k], label=f"σ{k + 1}")
        b.semilogy(t, ds["gain"].sel(run=run).values, color="k")
        a.set(title=str(run), ylabel="deg")
        b.set(title=str(run), ylabel="det(CCᵀ)")
        for ax in (a, b):
            ax.title.set_fontsize("small")
            ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize="x-small", ncols=4)
    axes[-1, 0].set(xlabel="time (s)")
    axes[-1, 1].set(xlabel="time (s)")
    fig.savefig(path, dpi=100)


def _envelope_figure(result: CmgReport, ds: xr.Dataset, path: Path) -> None:
    fig = Figure(figsize=(8, 4), layout="constrained")
    ax = fig.add_subplot()
    ax.set_title("momentum along the demand against the envelope along it (dashed)")
    for i, r in enumerate(result.runs):
        if r.direction is None:
            continue
        u = r.direction / np.linalg.norm(r.direction)
        rec = result.metrics_records()[i]
        ax.plot(r.gimbals.t, r.gimbals.h @ u, color=f"C{i % 10}", label=r.label)
        ax.axhline(rec["envelope_h"], color=f"C{i % 10}", linestyle="--", linewidth=0.8)
    ax.set(xlabel="time (s)", ylabel="uᵀh (rotor momenta)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize="x-small", ncols=2)
    fig.savefig(path, dpi=100)


def _station_figure(ds: xr.Dataset, path: Path) -> None:
    fig = Figure(figsize=(8, 8), layout="constrained")
    a, b, c = fig.subplots(3, 1, sharex=True)
    fig.suptitle("space station: attitude loop (LQR, Eq. 8–12)")
    t = ds["time"].values
    for k, axis in enumerate(ds["axis"].values):
        a.plot(t, np.rad2deg(ds["attitude"].values[:, k]), label=str(axis))
        b.plot(t, ds["cmg_momentum"].values[:, k] / _FT_LB_S, label=str(axis))
        c.plot(t, ds["torque"].values[:, k] / _FT_LB_S, label=f"u {axis}")
    hr = ds.attrs["rotor_momentum_N_m_s"] / _FT_LB_S
    b.plot(t, np.linalg.norm(ds["cmg_momentum"].values, axis=1) / _FT_LB_S, "k", label="|h|")
    b.axhline(
        2 * np.cos(np.deg2rad(54.74)) * hr,
        color="r",
        linestyle=":",
        linewidth=0.8,
        label="1.155 h_r (internal singular |h| from σ = 0 along x or y)",
    )
    a.set(ylabel="attitude (deg)")
    b.set(ylabel="CMG momentum (ft-lb-s)")
    c.set(ylabel="torque u (ft-lb)", xlabel="time (s)")
    for ax in (a, b, c):
        ax.grid(alpha=0.3)
        ax.legend(fontsize="x-small", ncols=3)
    fig.savefig(path, dpi=100)


def _metrics_html(records: list[dict[str, Any]]) -> str:
    keys = [k for k in records[0] if k != "run"]
    rows = [
        [r["run"]]
        + [
            format_metric(r.get(k)) if not isinstance(r.get(k), bool) else ("yes" if r[k] else "no")
            for k in keys
        ]
        for r in records
    ]
    return html_table(["run"] + [metric_label(k) for k in keys], rows)


def draw_cmg_figures(result: CmgReport, ds: xr.Dataset, folder: Path) -> list[str]:
    """The gimbal histories and the momentum envelope of a ``kind: cmg`` result."""
    figures = ["gimbals.png", "envelope.png"]
    _gimbal_figure(ds, folder / figures[0], lambda run: ds["time"].sel(run=run).values)
    _envelope_figure(result, ds, folder / figures[1])
    return figures


def cmg_sections(result: CmgReport, records: list[dict[str, Any]], figures: list[str]) -> str:
    """The runs, metrics, V1–V8 table and figures of a ``kind: cmg`` result."""
    v_rows = [(v, q, f"{p:g}", f"{c:.5g}", u) for v, q, p, c, u in result.table]
    outcomes = [
        (r.label, r.outcome, " ".join(f"{a:.2f}" for a in np.rad2deg(r.sigma0)))
        for r in result.runs
    ]
    images = "".join(f'<figure><img src="{f}" alt="{f}"></figure>' for f in figures)
    notes = "".join(f"<li>{html.escape(n)}</li>" for n in result.notes)
    body = f"""<h2>Runs</h2>
{html_table(["run", "outcome", "σ(0) (deg)"], outcomes)}
{_metrics_html(records)}
<h2>Validation V1–V8 (Vadali, Oh &amp; Walker, published), computed live</h2>
{html_table(["id", "quantity", "published", "computed", "unit"], v_rows)}
<ul>{notes}</ul>
<h2>Figures</h2>
{images}
"""
    return body


def draw_station_figures(ds: xr.Dataset, folder: Path) -> list[str]:
    """The attitude loop and the gimbal histories of a ``kind: cmg_station`` result."""
    figures = ["station.png", "gimbals.png"]
    _station_figure(ds, folder / figures[0])
    _gimbal_figure(ds, folder / figures[1], lambda run: ds["time"].values)
    return figures


def station_sections(
    result: StationReport, records: list[dict[str, Any]], figures: list[str]
) -> str:
    """The CMG loops (V9), the attitude loop's poles and the figures of a ``kind:
    cmg_station`` result."""
    images = "".join(f'<figure><img src="{f}" alt="{f}"></figure>' for f in figures)
    notes = "".join(f"<li>{html.escape(n)}</li>" for n in result.notes)
    poles = result.station.design.poles
    body = f"""<h2>CMG loop per initial gimbal set (V9)</h2>
<p>The paper: from σ(0) = 0 the pseudo-inverse meets a singularity "in about 720 seconds";
from [45, −45, 45, −45]° none, momentum within limits.</p>
{_metrics_html(records)}
<p>Closed-loop poles: |s| from {np.abs(poles).min():.3g} to {np.abs(poles).max():.3g} rad/s
(the paper's attitude bandwidth "of the order of .01 r/sec").</p>
<ul>{notes}</ul>
<h2>Figures</h2>
{images}
"""
    return body


__all__ = ["cmg_sections", "draw_cmg_figures", "draw_station_figures", "station_sections"]
