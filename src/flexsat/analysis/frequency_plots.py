"""Bode, Nyquist and singular-value figures of a loop, through one helper.

:func:`loop_figure` draws the data of :func:`~flexsat.analysis.frequency_domain.
frequency_response` (nothing is recomputed by matplotlib): the Bode magnitude and phase of each
SISO entry of L, the Nyquist curve of a SISO loop (with −1 and the unit circle), and the
singular values of L, S and T. Built on :class:`matplotlib.figure.Figure` (no pyplot state, no
display needed); frequencies on the axes in rad/s or Hz as asked, the unit in the label.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from flexsat.analysis.frequency_domain import default_grid, frequency_response
from flexsat.input_checks import FieldError

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from flexsat.analysis.frequency_domain import Loop

__all__ = ["loop_figure"]

FREQUENCY_AXES = {"rad/s": 1.0, "Hz": 1.0 / (2.0 * math.pi)}


def loop_figure(
    loop: Loop,
    omega_rad_s: np.ndarray | None = None,
    frequency_unit: str = "rad/s",
    title: str | None = None,
    **figure_kwargs: Any,
) -> Figure:
    """Bode (magnitude, phase), Nyquist and σ(L), σ(S), σ(T) of a loop on one figure.

    Parameters
    ----------
    loop : Loop
    omega_rad_s : array, optional
        Frequencies, rad/s (default the loop's grid, up to π/dt for a sampled loop).
    frequency_unit : {"rad/s", "Hz"}
        Unit of the frequency axes (the label says it).
    title : str, optional
    **figure_kwargs
        Passed to :class:`matplotlib.figure.Figure` (``figsize``, ``dpi``).
    """
    from matplotlib.figure import Figure

    if frequency_unit not in FREQUENCY_AXES:
        raise FieldError("frequency_unit", f"must be 'rad/s' or 'Hz', got {frequency_unit!r}")
    scale = FREQUENCY_AXES[frequency_unit]
    L = loop.transfer
    w = default_grid(L) if omega_rad_s is None else np.asarray(omega_rad_s, float)
    resp = frequency_response(L, omega_rad_s=w)
    f = w * scale
    fig = Figure(figsize=figure_kwargs.pop("figsize", (11, 8)), **figure_kwargs)
    ax_mag, ax_nyq, ax_ph, ax_sv = fig.subplots(2, 2).ravel()
    m = L.ninputs
    for i in range(m):
        label = L.input_labels[i] if m > 1 else loop.break_point
        ax_mag.loglog(f, resp.magnitude()[:, i, i], label=label)
        ax_ph.semilogx(f, resp.phase_deg()[:, i, i], label=label)
    ax_mag.axhline(1.0, color="0.5", lw=0.8)
    ax_mag.set_ylabel("|L|")
    ax_ph.axhline(-180.0, color="0.5", lw=0.8)
    ax_ph.set_ylabel("phase of L (deg)")
    ax_ph.set_xlabel(f"frequency ({frequency_unit})")
    ax_mag.legend(fontsize="small")
    if m == 1:
        G = resp.values[:, 0, 0]
        ax_nyq.plot(G.real, G.imag, label="L")
        ax_nyq.plot(G.real, -G.imag, ls="--", lw=0.8, color="C0")
        t = np.linspace(0, 2 * math.pi, 361)
        ax_nyq.plot(np.cos(t), np.sin(t), color="0.6", lw=0.8)
        ax_nyq.plot([-1], [0], "r+", ms=12)
        ax_nyq.set_xlim(-3, 2)
        ax_nyq.set_ylim(-2.5, 2.5)
        ax_nyq.set_aspect("equal")
        ax_nyq.set_title("Nyquist")
    else:
        ax_nyq.set_axis_off()
        ax_nyq.text(0.5, 0.5, "Nyquist: break the loop at one channel", ha="center")
    for name, sys in (("L", L), ("S", loop.sensitivity()), ("T", loop.complementary_sensitivity())):
        sv = frequency_response(sys, omega_rad_s=w).singular_values()
        ax_sv.loglog(f, sv[:, 0], label=f"σ̄({name})")
        if sv.shape[1] > 1:
            ax_sv.loglog(f, sv[:, -1], ls="--", label=f"σ_min({name})")
    ax_sv.set_xlabel(f"frequency ({frequency_unit})")
    ax_sv.legend(fontsize="small")
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    return fig
