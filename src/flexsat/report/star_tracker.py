"""Report of a star-tracker scenario (``kind: star_tracker``): ``metrics.json``,
``results.nc``, figures and ``index.html`` with the identification table (Junkins,
Pollock & Rahman 1990 §2.3.4).

``results.nc`` holds, over ``run`` and ``attitude``: the body-axis error angles ``error``
(arcsec, NaN where the identification was rejected), ``accepted``, ``correct`` and
``n_stars``; the first attitude's frames as ``example_pixels`` (camera × star × (column,
row)) and ``example_status`` (1 matched, 0 true star deleted, −1 false star, 2 wrong match);
and the table's columns per run. Open it with ``xarray.open_dataset(path, engine="h5netcdf")``.
"""

from __future__ import annotations

import html
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np
from matplotlib.figure import Figure

from flexsat.report.page import format_metric

if TYPE_CHECKING:
    import xarray as xr


class NotedResult(Protocol):
    """A result with notes for the reader (:class:`flexsat.scenarios.star_tracker.
    StarTrackerResult`)."""

    @property
    def notes(self) -> tuple[str, ...]: ...


#: table columns: (metric, heading)
COLUMNS = (
    ("attitudes", "attitudes"),
    ("identification_rate", "correct"),
    ("accepted_rate", "accepted"),
    ("wrong_accepted", "wrong accepted"),
    ("mean_stars", "stars kept (mean)"),
    ("min_triplets", "triplets (min)"),
    ("error_std_x_arcsec", "σ x (″)"),
    ("error_std_y_arcsec", "σ y (″)"),
    ("error_std_z_arcsec", "σ z (″)"),
    ("quest_sigma_x_arcsec", "σ_QUEST x (″)"),
    ("quest_sigma_y_arcsec", "σ_QUEST y (″)"),
    ("quest_sigma_z_arcsec", "σ_QUEST z (″)"),
    ("nees_mean", "mean δθᵀP⁻¹δθ (3 ideal)"),
)
#: the sky plot's marker per example_status value: (label, marker, colour)
_STATUS = {
    1.0: ("matched", "o", "C2"),
    0.0: ("true star, deleted", "s", "0.6"),
    -1.0: ("false star", "x", "C3"),
    2.0: ("wrong match", "D", "k"),
}


def _histograms(ds: xr.Dataset, path: Path) -> None:
    fig = Figure(figsize=(9, 3.2), layout="constrained")
    axes = fig.subplots(1, 3, sharey=True)
    fig.suptitle(f"attitude error per body axis (tolerance {ds.attrs['tolerance_arcsec']:g}″)")
    err = ds["error"].values
    lim = np.nanmax(np.abs(err)) if np.isfinite(err).any() else 1.0
    bins = np.linspace(-lim, lim, 41)
    for k, (ax, axis) in enumerate(zip(axes, ds["axis"].values)):
        for i, run in enumerate(ds["run"].values):
            e = err[i, :, k]
            e = e[np.isfinite(e)]
            if e.size:
                ax.hist(
                    e,
                    bins=bins,
                    histtype="step",
                    color=f"C{i}",
                    label=f"{run} (σ = {np.std(e):.2g}″)",
                )
        ax.set(xlabel=f"error about {axis} (arcsec)", title=f"axis {axis}")
        ax.grid(alpha=0.3)
        if ax.get_legend_handles_labels()[0]:  # nothing to label when nothing was accepted
            ax.legend(fontsize="xx-small")
    axes[0].set(ylabel="attitudes")
    fig.savefig(path, dpi=100)


def _sky(ds: xr.Dataset, run: str, path: Path) -> None:
    cams = ds["camera"].values
    fig = Figure(figsize=(3.6 * len(cams), 3.9), layout="constrained")
    axes = np.atleast_1d(fig.subplots(1, len(cams)))
    fig.suptitle(f"first frame of {run}: detector images")
    n_pix = ds.attrs["n_pixels"]
    for ax, c in zip(axes, cams):
        px = ds["example_pixels"].sel(run=run, camera=c).values
        st = ds["example_status"].sel(run=run, camera=c).values
        for value, (label, marker, colour) in _STATUS.items():
            sel = st == value
            if sel.any():
                style: dict[str, Any] = (
                    dict(facecolors="none", edgecolors=colour)
                    if marker in "osD"
                    else dict(c=colour)
                )  # an 'x' has no face: its colour is c
                ax.scatter(px[sel, 0], px[sel, 1], marker=marker, s=22, label=label, **style)
        ax.set(
            xlim=(0, n_pix),
            ylim=(0, n_pix),
            aspect="equal",
            title=f"camera {c}",
            xlabel="column (pixel)",
            ylabel="row (pixel)",
        )
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize="xx-small", loc="upper right")
    fig.savefig(path, dpi=100)


def _table(records: list[dict[str, Any]]) -> str:
    esc = html.escape
    head = "".join(f"<th>{esc(h)}</th>" for _, h in COLUMNS)
    rows: list[str] = []
    for r in records:
        cells = "".join(f"<td>{format_metric(r.get(k))}</td>" for k, _ in COLUMNS)
        rows.append(f"<tr><td>{esc(r['run'])}</td>{cells}</tr>")
    return f"<table><tr><th>run</th>{head}</tr>{''.join(rows)}</table>"


def draw_figures(ds: xr.Dataset, folder: Path) -> list[str]:
    """The error histograms and every run's sky into ``folder``; the file names."""
    figures = ["errors.png"]
    _histograms(ds, folder / figures[0])
    for i, run in enumerate(ds["run"].values):
        figures.append(f"sky_{i + 1}.png")
        _sky(ds, run, folder / figures[-1])
    return figures


def sections(result: NotedResult, records: list[dict[str, Any]], figures: list[str]) -> str:
    """The page's identification table, notes and figures."""
    esc = html.escape
    images = "".join(f'<figure><img src="{f}" alt="{esc(f)}"></figure>' for f in figures)
    notes = "".join(f"<li>{esc(n)}</li>" for n in result.notes)
    body = f"""<h2>Identification (Junkins, Pollock & Rahman 1990 §2.3.4: sub-5″
    attitude from star patterns)</h2>
<p>Correct: accepted with every kept star its true catalogue star; wrong accepted: accepted
with at least one wrong star (the paper's claim: never). σ: standard deviation of the error
angles over the accepted attitudes; σ_QUEST: mean predicted 1σ.</p>
<div style="overflow-x:auto">{_table(records)}</div>
<ul>{notes}</ul>
<h2>Figures</h2>
{images}
"""
    return body


__all__ = ["COLUMNS", "NotedResult", "draw_figures", "sections"]
