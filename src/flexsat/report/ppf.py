"""Report of a PPF scenario (``kind: ppf``): ``metrics.json``, ``results.nc``, figures and
``index.html`` with the results table and the gains of every run (Agrawal & Bang 1996 Tables 1–3).

``results.nc`` holds, over ``run``: the tip responses ``tip_response`` (response × time ×
output: the tip error of Eq. 33 along n̂_1 and n̂_2 in m, the rotation Φ of Eq. 34 in rad, for
``open loop``, ``initial gains`` and ``optimised gains``); the homotopy along ``step`` (every
converged γ, NaN-padded): ``gamma_path``, ``cost_path``, ``target_path`` (J0(γ)),
``min_eig_S_path``, ``max_re_pole_path``, ``gain_path`` (actuator × mode) and the closed-loop
poles ``pole_real_path`` / ``pole_imag_path``; the gains ``gains_initial`` and
``gains_optimised``; and the results-table columns (``J_init``, ``J_goal``, ``J_opt``,
``gamma``, ``g11`` … ``g33``, ``min_eig_S``, ``max_re_pole``, ``stable``, settling times,
``excitation``, ``goal_rule``, ``status``). Open it with
``xarray.open_dataset(path, engine="h5netcdf")``.
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

    from flexsat.cases.agrawal_bang_ppf import PPFCaseRun


class PPFReport(Protocol):
    """What this report reads of a PPF result (:class:`flexsat.scenarios.ppf.PPFResult`)."""

    @property
    def labels(self) -> tuple[str, ...]: ...
    @property
    def runs(self) -> tuple[PPFCaseRun, ...]: ...
    @property
    def notes(self) -> tuple[str, ...]: ...


#: results-table columns: (metric, heading)
RESULT_COLUMNS = (
    ("w1", "w1"),
    ("w2", "w2"),
    ("J_init", "J_init"),
    ("J_goal", "J_goal"),
    ("J_opt", "J_opt"),
    ("gamma", "γ"),
    ("min_eig_S", "min eig S (1/s²)"),
    ("max_re_pole", "max Re pole (1/s)"),
    ("stable", "stable"),
    ("tip_settling_initial_s", "tip 10 % settling, initial (s)"),
    ("tip_settling_optimised_s", "tip 10 % settling, optimised (s)"),
    ("rotation_settling_initial_s", "Φ 10 % settling, initial (s)"),
    ("rotation_settling_optimised_s", "Φ 10 % settling, optimised (s)"),
)
#: panels of a grid of per-run plots
_COLUMNS = 3


def _grid(n: int, title: str, height: float = 2.4) -> tuple[Figure, np.ndarray]:
    rows = -(-n // _COLUMNS)
    cols = min(n, _COLUMNS)
    fig = Figure(figsize=(3.6 * cols, height * rows + 0.6), layout="constrained")
    fig.suptitle(title)
    axes = np.atleast_1d(fig.subplots(rows, cols, squeeze=False).ravel())
    for ax in axes[n:]:
        ax.set_axis_off()
    return fig, axes[:n]


def _colour(i: int, n: int) -> str | tuple[float, float, float, float]:
    """Run i's colour: the default cycle up to 10 runs, tab20 beyond (distinct up to 20)."""
    if n <= 10:
        return f"C{i}"
    from matplotlib import colormaps

    return colormaps["tab20"](i % 20)


def _cost(ds: xr.Dataset, path: Path) -> None:
    fig = Figure(figsize=(8, 5.2), layout="constrained")
    a, b = fig.subplots(2, 1, sharex=True)
    fig.suptitle("homotopy: cost along γ (J0(γ) = γ J_goal + (1 − γ) J_init, Eq. 16)")
    n = ds.sizes["run"]
    for i, run in enumerate(ds["run"].values):
        r = ds.sel(run=run)
        c = _colour(i, n)
        g, J0 = r["gamma_path"].values, float(r["J_init"])
        a.plot(g, r["cost_path"].values / J0, "o-", color=c, markersize=3, label=str(run))
        a.plot(g, r["target_path"].values / J0, "x", color=c, markersize=5)
        b.plot(g, r["cost_path"].values / J0 - 1.0, "o-", color=c, markersize=3)
    a.set(ylabel="J / J_init (o: reached, x: target)")
    b.set(ylabel="J / J_init − 1", xlabel="γ")
    b.set_yscale("symlog", linthresh=1e-4)
    for ax in (a, b):
        ax.grid(alpha=0.3)
    a.legend(fontsize="x-small", ncols=2)
    fig.savefig(path, dpi=100)


def _checks(ds: xr.Dataset, path: Path) -> None:
    fig = Figure(figsize=(8, 5.2), layout="constrained")
    a, b = fig.subplots(2, 1, sharex=True)
    fig.suptitle("stability along γ: S of Eq. 6 and the closed-loop poles of Eq. 8")
    for i, run in enumerate(ds["run"].values):
        r = ds.sel(run=run)
        c = _colour(i, ds.sizes["run"])
        a.plot(
            r["gamma_path"].values,
            r["min_eig_S_path"].values,
            "o-",
            color=c,
            markersize=3,
            label=str(run),
        )
        b.plot(r["gamma_path"].values, r["max_re_pole_path"].values, "o-", color=c, markersize=3)
    a.set(ylabel="smallest eigenvalue of S (1/s²)")
    b.set(ylabel="largest Re(pole) (1/s)", xlabel="γ")
    for ax in (a, b):
        ax.grid(alpha=0.3)
    a.legend(fontsize="x-small", ncols=2)
    fig.savefig(path, dpi=100)


def _poles(ds: xr.Dataset, path: Path) -> None:
    runs = ds["run"].values
    fig, axes = _grid(
        len(runs),
        "closed-loop poles along γ (colour: γ; the structure's modes and the 9 filters)",
        2.8,
    )
    for ax, run in zip(axes, runs):
        r = ds.sel(run=run)
        g = np.repeat(r["gamma_path"].values[:, None], r.sizes["pole"], 1)
        keep = np.isfinite(g) & (r["pole_imag_path"].values >= 0)
        sc = ax.scatter(
            r["pole_real_path"].values[keep],
            r["pole_imag_path"].values[keep],
            c=g[keep],
            s=6,
            cmap="viridis",
            vmin=0,
            vmax=ds.attrs["gamma_stop"],
        )
        ax.set_xscale("symlog", linthresh=0.1)
        ax.set(title=str(run), xlabel="Re (1/s)", ylabel="Im (rad/s)")
        ax.title.set_fontsize("small")
        ax.grid(alpha=0.3)
    fig.colorbar(sc, ax=list(axes), label="γ", shrink=0.6)
    fig.savefig(path, dpi=100)


def _gain_paths(ds: xr.Dataset, path: Path) -> None:
    runs = ds["run"].values
    fig, axes = _grid(
        len(runs), "gains g_ij along γ (i: actuator, j: mode; colour: actuator, line: mode)"
    )
    styles = ("-", "--", ":")
    for ax, run in zip(axes, runs):
        r = ds.sel(run=run)
        for i in range(3):
            for j in range(3):
                ax.plot(
                    r["gamma_path"].values,
                    r["gain_path"].values[:, i, j],
                    linestyle=styles[j],
                    color=f"C{i}",
                    label=f"g{i + 1}{j + 1}",
                )
        ax.set(title=str(run), xlabel="γ", ylabel="gain")
        ax.title.set_fontsize("small")
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize="xx-small", ncols=3)
    fig.savefig(path, dpi=100)


def _responses(ds: xr.Dataset, run: str, path: Path) -> None:
    fig = Figure(figsize=(8, 6.4), layout="constrained")
    axes = fig.subplots(3, 1, sharex=True)
    fig.suptitle(f"tip responses: {run}")
    t = ds["time"].values
    r = ds["tip_response"].sel(run=run)
    scales = (
        (1e3, "tip error along n̂_1 (mm)"),
        (1e3, "tip error along n̂_2 (mm)"),
        (1e3, "tip rotation Φ = α + β (mrad)"),
    )
    for k, (ax, (scale, ylabel)) in enumerate(zip(axes, scales)):
        for i, response in enumerate(ds["response"].values):
            ax.plot(
                t,
                scale * r.sel(response=response).values[:, k],
                color=f"C{i}",
                linewidth=0.9,
                label=str(response),
            )
        ax.set(ylabel=ylabel)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize="small", ncols=3)
    axes[-1].set(xlabel="time (s)")
    fig.savefig(path, dpi=100)


def _results_table(records: list[dict[str, Any]], ds: xr.Dataset) -> str:
    esc = html.escape
    head = "".join(f"<th>{esc(h)}</th>" for _, h in RESULT_COLUMNS)
    gains = "".join(f"<th>g{i}{j}</th>" for i in (1, 2, 3) for j in (1, 2, 3))
    rows: list[str] = []
    for r in records:
        run = r["run"]
        cells = [
            f"<td>{esc(str(ds['excitation'].sel(run=run).values))}</td>",
            f"<td>{esc(str(ds['goal_rule'].sel(run=run).values))}</td>",
        ]
        for key, _ in RESULT_COLUMNS:
            v = r.get(key)
            cells.append(
                f"<td>{'yes' if v is True else 'NO' if v is False else format_metric(v)}</td>"
            )
        cells += [f"<td>{format_metric(r[f'g{i}{j}'])}</td>" for i in (1, 2, 3) for j in (1, 2, 3)]
        cells.append(f"<td>{esc(str(ds['status'].sel(run=run).values))}</td>")
        rows.append(f"<tr><td>{esc(run)}</td>{''.join(cells)}</tr>")
    return (
        f"<table><tr><th>run</th><th>excitation</th><th>goal</th>{head}{gains}"
        f"<th>status</th></tr>{''.join(rows)}</table>"
    )


def _gains_tables(result: PPFReport) -> str:
    """Per run, the paper's layout (rows: mode, columns: actuator), initial → optimised, with
    the published optimised gains of the same case."""
    from flexsat.cases.agrawal_bang_ppf import PUBLISHED_GAINS

    esc = html.escape
    blocks: list[str] = []
    for label, run in zip(result.labels, result.runs):
        weights = tuple(float(w) for w in run.setup.weights)  # (100.0, 100.0) == (100, 100)
        paper = next(
            (
                gains
                for (w, excitation), gains in PUBLISHED_GAINS.items()
                if w == weights and excitation == run.setup.excitation
            ),
            None,
        )
        rows: list[str] = []
        for j in range(3):
            cells = "".join(
                f"<td>{run.initial_gains.reshape(3, 3)[i, j]:.5g} → "
                f"<b>{run.gains[i, j]:.5g}</b></td>"
                for i in range(3)
            )
            if paper is not None:
                cells += "".join(f"<td>{paper[j][i]:.5g}</td>" for i in range(3))
            rows.append(f"<tr><td>g{j + 1} (mode {j + 1})</td>{cells}</tr>")
        published = (
            "<th>paper act. 1</th><th>paper act. 2</th><th>paper act. 3</th>"
            if paper is not None
            else ""
        )
        blocks.append(
            f"<h3>{esc(label)}</h3><table><tr><th></th><th>actuator 1</th>"
            f"<th>actuator 2</th><th>actuator 3</th>{published}</tr>"
            f"{''.join(rows)}</table>"
        )
    return "".join(blocks)


def sections(
    result: PPFReport, records: list[dict[str, Any]], ds: xr.Dataset, figures: list[str]
) -> str:
    """The page's results table (the Agrawal & Bang 1996 grid), gains and figures."""
    esc = html.escape
    images = "".join(f'<figure><img src="{f}" alt="{esc(f)}"></figure>' for f in figures)
    notes = "".join(f"<li>{esc(n)}</li>" for n in result.notes)
    return f"""<h2>Results (Agrawal & Bang 1996 Tables 1–3 grid)</h2>
<p>J = ½ ∫ (ζ_tᵀ Q̄ ζ_t + uᵀ Q_u u) dt (Eqs. 7, 35) by Lyapunov equations; γ: last converged
homotopy parameter; min eig S: Eq. 6; stable: the deciding check (S &gt; 0 for positive gains,
else the poles). Settling: last time the tip error |Eᵗ| or the rotation Φ exceeds 10 % of its
peak (n/a: not within the simulated time).</p>
<div style="overflow-x:auto">{_results_table(records, ds)}</div>
<ul>{notes}</ul>
<h2>Gains (rows: mode, columns: actuator; initial → optimised)</h2>
{_gains_tables(result)}
<h2>Figures</h2>
{images}
"""


def draw_figures(ds: xr.Dataset, folder: Path) -> list[str]:
    """The homotopy paths and every run's tip responses into ``folder``; the file names."""
    figures = ["cost.png", "stability.png", "poles.png", "gains.png"]
    _cost(ds, folder / figures[0])
    _checks(ds, folder / figures[1])
    _poles(ds, folder / figures[2])
    _gain_paths(ds, folder / figures[3])
    for i, run in enumerate(ds["run"].values):
        figures.append(f"response_{i + 1}.png")
        _responses(ds, run, folder / figures[-1])
    return figures


__all__ = ["PPFReport", "RESULT_COLUMNS", "draw_figures", "sections"]
