"""Report of an identification scenario: ``identification.json``, ``results.nc``, plots, HTML.

``results.nc`` (h5netcdf, no pickle) holds, with SI units attributes:

- over ``mode``: ``true_hz``, ``era_hz``, ``era_hz_std``, ``a_priori_hz``, ``updated_hz`` and the
  damping ratios ``true_damping``, ``era_damping``, ``era_damping_std``, ``a_priori_damping``,
  ``updated_damping``;
- over ``(output, input, frequency)``: the FRFs ``frf_measured``, ``frf_a_priori``,
  ``frf_updated`` as real and imaginary parts (``*_re``, ``*_im``) and ``frf_coherence`` over
  ``(output, frequency)``;
- over ``(video_mode, model_mode)``: ``mac_a_priori``, ``mac_updated``; ``video_shapes`` over
  ``(target, video_mode)``;
- over ``substructure``: ``a_priori_factor``, ``p``, ``p_std``, ``updated_factor``.

Open it with ``xarray.open_dataset(path, engine="h5netcdf")``.
"""

from __future__ import annotations

import html
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np
import xarray as xr
from matplotlib.figure import Figure

from flexsat.netcdf import write_netcdf
from flexsat.report.json_data import dumps
from flexsat.report.page import html_table
from flexsat.text import format_optional

if TYPE_CHECKING:
    from flexsat.cases.identification_campaign import CampaignResult

__all__ = [
    "FIGURES",
    "IdentificationReport",
    "dataset",
    "draw_figures",
    "sections",
    "write_data",
]


class IdentificationReport(Protocol):
    """What this report reads of an identification result
    (:class:`flexsat.scenarios.identification.IdentificationResult`; ``scenario`` is its
    document)."""

    @property
    def scenario(self) -> Any: ...
    @property
    def campaign(self) -> CampaignResult: ...
    @property
    def case_source(self) -> str: ...


#: figure files and captions
FIGURES = (
    ("frf.png", "FRF overlays: measured (H1), a-priori and updated model"),
    ("mac.png", "MAC of the video mode shapes against the a-priori and updated models"),
    ("frequencies.png", "Frequency errors against the truth, before and after the update"),
)


def dataset(result: IdentificationReport) -> xr.Dataset:
    """The campaign as one dataset (module docstring)."""
    c = result.campaign
    m = c.modes
    mode_vars = {
        k: (
            "mode",
            np.asarray(m[k], float),
            {"units": "Hz" if k.endswith("hz") or k.endswith("hz_std") else "1"},
        )
        for k in (
            "true_hz",
            "era_hz",
            "era_hz_std",
            "a_priori_hz",
            "updated_hz",
            "true_damping",
            "era_damping",
            "era_damping_std",
            "a_priori_damping",
            "updated_damping",
        )
    }
    frf_dims = ("output", "input", "frequency")
    frf_vars: dict[str, Any] = {}
    for name, arr in (
        ("frf_measured", c.frf_measured),
        ("frf_a_priori", c.frf_a_priori),
        ("frf_updated", c.frf_updated),
    ):
        frf_vars[name + "_re"] = (frf_dims, arr.real, {"units": "rad/(N*m)"})
        frf_vars[name + "_im"] = (frf_dims, arr.imag, {"units": "rad/(N*m)"})
    names = list(c.substructures)
    sc = c.scalings
    ds = xr.Dataset(
        {
            **mode_vars,
            **frf_vars,
            "frf_coherence": (("output", "frequency"), c.frf_coherence, {"units": "1"}),
            "mac_a_priori": (("video_mode", "model_mode"), c.mac_a_priori, {"units": "1"}),
            "mac_updated": (("video_mode", "model_mode"), c.mac_updated, {"units": "1"}),
            "video_shapes": (("target", "video_mode"), c.video_shapes, {"units": "1"}),
            "a_priori_factor": ("substructure", [sc[n]["a_priori"] for n in names]),
            "p": ("substructure", [sc[n]["p"] for n in names]),
            "p_std": ("substructure", [sc[n]["p_std"] for n in names]),
            "updated_factor": ("substructure", [sc[n]["updated"] for n in names]),
        },
        coords={
            "mode": np.arange(1, len(m["era_hz"]) + 1),
            "frequency": ("frequency", c.frf_frequencies, {"units": "Hz"}),
            "output": list(c.frf_outputs),
            "input": list(c.frf_inputs),
            "target": list(c.target_nodes),
            "substructure": names,
        },
    )
    ds.attrs.update(
        scenario_name=result.scenario.name,
        case=result.scenario.case,
        case_source=result.case_source,
        scenario_yaml=result.scenario.yaml_text,
    )
    return ds


def _frf_figure(c: CampaignResult, path: Path) -> None:
    q, r = c.frf_measured.shape[:2]
    # the six best-coupled pairs (by the updated model), strongest first: a symmetric input
    # and an antisymmetric gauge give only noise
    strength = np.median(np.abs(c.frf_updated), axis=2)
    order = np.argsort(-strength, axis=None)[: min(6, q * r)]
    pairs = [tuple(int(v) for v in np.unravel_index(k, (q, r))) for k in order]
    fig = Figure(figsize=(9, 2.4 * ((len(pairs) + 1) // 2)), layout="constrained")
    axes = fig.subplots((len(pairs) + 1) // 2, 2, squeeze=False).ravel()
    f = c.frf_frequencies
    for ax, (i, a) in zip(axes, pairs):
        ax.semilogy(f, np.abs(c.frf_measured[i, a]), color="0.4", lw=1, label="measured (H1)")
        ax.semilogy(f, np.abs(c.frf_a_priori[i, a]), "C3--", lw=1, label="a priori")
        ax.semilogy(f, np.abs(c.frf_updated[i, a]), "C0", lw=1, label="updated")
        ax.set(
            title=f"{c.frf_outputs[i]} / {c.frf_inputs[a]}", xlabel="frequency (Hz)", ylabel="|H|"
        )
        ax.grid(alpha=0.3)
    for ax in axes[len(pairs) :]:
        ax.set_visible(False)
    axes[0].legend(fontsize="small")
    fig.savefig(path, dpi=100)


def _mac_figure(c: CampaignResult, path: Path) -> None:
    fig = Figure(figsize=(9, 3.6), layout="constrained")
    if c.mac_updated.size == 0:
        fig.text(0.5, 0.5, "no video test: no measured mode shapes", ha="center")
        fig.savefig(path, dpi=100)
        return
    for ax, mat, title in zip(
        fig.subplots(1, 2), (c.mac_a_priori, c.mac_updated), ("a-priori model", "updated model")
    ):
        im = ax.imshow(mat, vmin=0, vmax=1, cmap="viridis")
        ax.set(title=f"MAC, video shapes vs {title}", xlabel="model mode", ylabel="video mode")
        ax.set_xticks(range(mat.shape[1]), [str(k + 1) for k in range(mat.shape[1])])
        ax.set_yticks(range(mat.shape[0]), [str(k + 1) for k in range(mat.shape[0])])
        fig.colorbar(im, ax=ax, shrink=0.8)
    fig.savefig(path, dpi=100)


def _frequency_figure(c: CampaignResult, path: Path) -> None:
    m = c.modes
    k = np.arange(1, len(m["era_hz"]) + 1)
    known = None not in m["true_hz"]  # measured data: compare with the ERA values
    ref = np.asarray(m["true_hz"] if known else m["era_hz"], float)
    fig = Figure(figsize=(7, 3.4), layout="constrained")
    ax = fig.add_subplot()
    for key, style, label in (
        ("a_priori_hz", "C3s--", "a priori"),
        ("era_hz", "ko", "ERA"),
        ("updated_hz", "C0^-", "updated"),
    ):
        if known or key != "era_hz":
            ax.plot(k, 100 * (np.asarray(m[key]) / ref - 1), style, label=label)
    ax.set(xlabel="mode", ylabel=f"error against the {'truth' if known else 'ERA'} (%)", xticks=k)
    ax.axhline(0, color="0.6", lw=0.8)
    ax.grid(alpha=0.3)
    ax.legend(fontsize="small")
    fig.savefig(path, dpi=100)


def _pct(a: float, b: float | None) -> str:
    return "" if b is None else f"{100 * (a / b - 1):+.3f} %"


def _camera_html(c: CampaignResult) -> str:
    """The calibration and triangulation summary of a simulated video test (none for recorded
    data, whose video arrives already triangulated)."""
    cal, tri = c.calibration, c.triangulation
    if not cal or not tri:
        return ""
    return f"""<h2>Cameras and triangulation</h2>
<p>{cal["n_cameras"]} cameras calibrated from {len(c.target_nodes)} targets with a-priori
positions; parameters {html.escape(", ".join(cal["parameters"]))}; largest calibration error
{cal["max_abs_normalised_error"]:.2f} σ (σ₀² = {cal["sigma0_squared"]:.3f}).
Triangulated z over {tri["fields"]} fields: rms error {1e3 * tri["rms_error_z_m"]:.3f} mm against
a predicted {1e3 * tri["predicted_sigma_z_m"]:.3f} mm from centroid noise
({1e3 * tri["predicted_sigma_z_with_cameras_m"]:.3f} mm for an absolute position, with the
calibration covariance, Att. 6 Eqs. 34–37); peak motion
{1e3 * tri["peak_displacement_m"]:.1f} mm.</p>"""


def sections(result: IdentificationReport) -> str:
    """The page: frequencies, damping, scalings, wheel gains, the camera rig, the figures."""
    c, esc = result.campaign, html.escape
    m = c.modes
    freq_rows = [
        (
            k + 1,
            format_optional(m["true_hz"][k], ".5f"),
            f"{m['era_hz'][k]:.5f} ± {m['era_hz_std'][k]:.1e}",
            format_optional(m["video_hz"][k], ".5f"),
            format_optional(m["okid_hz"][k], ".5f"),
            f"{m['a_priori_hz'][k]:.5f} ({_pct(m['a_priori_hz'][k], m['true_hz'][k])})",
            f"{m['updated_hz'][k]:.5f} ({_pct(m['updated_hz'][k], m['true_hz'][k])})",
        )
        for k in range(len(m["era_hz"]))
    ]
    damp_rows = [
        (
            k + 1,
            format_optional(m["true_damping"][k], ".5f"),
            f"{m['era_damping'][k]:.5f} ± {m['era_damping_std'][k]:.1e}",
            f"{m['a_priori_damping'][k]:.5f}",
            f"{m['updated_damping'][k]:.5f}",
        )
        for k in range(len(m["era_hz"]))
    ]
    sc_rows = [
        (n, f"{v['a_priori']:.4f}", f"{v['p']:.5f} ± {v['p_std']:.1e}", f"{v['updated']:.5f}")
        for n, v in c.scalings.items()
    ]
    gain_html = ""
    if c.wheel_gains:
        rows = [
            (
                n,
                format_optional(v["true"], ".4f"),
                f"{v['identified']:.5f} ± {v['std']:.1e}",
                _pct(v["identified"], v["true"]),
            )
            for n, v in c.wheel_gains.items()
        ]
        gain_html = (
            "<h2>Reaction-wheel torque constants (Att. 6 Eq. 7)</h2>\n<p>Delivered over "
            "commanded torque: the true value (in a simulation) and the one identified "
            "with the structure from the FRFs.</p>\n"
            + html_table(("wheel", "true", "identified", "error"), rows)
        )
    u = c.update
    upd_text = (
        (
            "Att. 6 differential correction, frequencies, damping ratios and "
            f"{u['frf_points']} FRF points"
            if u["method"] == "differential_correction"
            else "Att. 7 Creamer-Junkins, frequencies then eigenvalue real parts"
        )
        + f", {u['iterations']} iterations"
        + ("" if u["converged"] else ", NOT converged")
    )
    images = "".join(
        f'<figure><img src="{f}" alt="{esc(t)}"><figcaption>{esc(t)}</figcaption></figure>'
        for f, t in FIGURES
    )
    return f"""<h2>Natural frequencies (Hz)</h2>
<p>Truth: the simulated structure. ERA: hammer test (strain gauges and accelerometers), ± its
first-order standard deviation. Video: ERA on triangulated target motion. OKID: reaction-wheel
random-torque test. A priori and updated: the model before and after the update (error against
the truth).</p>
{html_table(("mode", "truth", "ERA", "video", "OKID", "a priori", "updated"), freq_rows)}
<h2>Damping ratios</h2>
<p>A priori: Att. 6 Eq. 15, C = 2 ζ₁ω₁ M. Updated: Rayleigh damping C = r₁ M + r₂ K fitted to
the measured damping; r = {esc(np.array2string(c.damping_scalings, precision=5))}.</p>
{html_table(("mode", "truth", "ERA", "a priori", "updated"), damp_rows)}
<h2>Substructure stiffness scalings</h2>
<p>Update: {esc(upd_text)}. Factors on the case's nominal stiffness (the truth, in a
simulation): the a-priori one, the identified scaling p of the a-priori block (± 1σ), and the
updated one (a priori × p; in a simulation, 1 means recovered).</p>
{html_table(("substructure", "a priori", "p", "updated"), sc_rows)}
{gain_html}
{_camera_html(c)}
{images}
"""


def write_data(result: IdentificationReport, ds: xr.Dataset, folder: Path) -> None:
    """``identification.json`` (the campaign's numbers) and ``results.nc`` (``ds``)."""
    c = result.campaign
    summary = {
        "scenario": result.scenario.name,
        "case": result.scenario.case,
        "modes": c.modes,
        "scalings": c.scalings,
        "update": c.update,
        "wheel_gains": c.wheel_gains,
        "damping_scalings": c.damping_scalings,
        "calibration": c.calibration,
        "triangulation": c.triangulation,
        "mac_a_priori": c.mac_a_priori,
        "mac_updated": c.mac_updated,
    }
    (folder / "identification.json").write_text(dumps(summary), encoding="utf-8")
    write_netcdf(ds, folder / "results.nc")


def draw_figures(campaign: CampaignResult, folder: Path) -> list[str]:
    """:data:`FIGURES` of the campaign into ``folder``; their file names."""
    _frf_figure(campaign, folder / "frf.png")
    _mac_figure(campaign, folder / "mac.png")
    _frequency_figure(campaign, folder / "frequencies.png")
    return [f for f, _ in FIGURES]
