"""The loop figure of flexsat.analysis.frequency_plots: its axes, labels with units and lines."""

from __future__ import annotations

import math

import numpy as np
import pytest

import control as ct
from flexsat.analysis.frequency_domain import Loop
from flexsat.analysis.frequency_plots import loop_figure

#: values drawn are float64 copies of the computed response: equal to round-off of |·|, angle
RTOL = 1e-12


def _siso() -> Loop:
    """L(s) = 2 / (s (s + 1)), broken at "torque" (closed loop A of 1 + L = 0)."""
    L = ct.ss([[0.0, 1.0], [0.0, -1.0]], [[0.0], [2.0]], [[1.0, 0.0]], 0.0)
    return Loop(L, "torque", np.array([[0.0, 1.0], [-2.0, -1.0]]), ("theta", "theta_dot"), 0.0)


def _mimo() -> Loop:
    """Two decoupled axes, L = diag(2, 8) / (s (s + 1)), broken at the input."""
    A = np.kron(np.eye(2), [[0.0, 1.0], [0.0, -1.0]])
    B = np.array([[0.0, 0.0], [2.0, 0.0], [0.0, 0.0], [0.0, 8.0]])
    C = np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]])
    L = ct.ss(A, B, C, 0.0, inputs=["torque[0]", "torque[1]"], outputs=["u[0]", "u[1]"])
    states = ("theta[0]", "theta_dot[0]", "theta[1]", "theta_dot[1]")
    return Loop(L, "input", A - B @ C, states, 0.0)


W = np.geomspace(0.05, 50.0, 40)


def test_four_axes_with_frequency_labels_in_the_unit_asked():
    for unit, scale in (("rad/s", 1.0), ("Hz", 1 / (2 * math.pi))):
        fig = loop_figure(_siso(), omega_rad_s=W, frequency_unit=unit, title="hub")
        mag, nyq, ph, sv = fig.axes
        assert mag.get_ylabel() == "|L|" and ph.get_ylabel() == "phase of L (deg)"
        assert ph.get_xlabel() == sv.get_xlabel() == f"frequency ({unit})"
        assert nyq.get_title() == "Nyquist" and fig.get_suptitle() == "hub"
        assert np.allclose(mag.lines[0].get_xdata(), W * scale, rtol=RTOL, atol=0)


def test_the_lines_are_the_loop_s_phase_nyquist_and_sensitivities():
    """Phase of L = 2/(jω(jω+1)) is −90° − atan ω; the Nyquist curve is (Re L, Im L); σ̄(S) of
    a SISO loop is 1/|1 + L| and σ̄(T) = |L|/|1 + L| (computed here by hand)."""
    fig = loop_figure(_siso(), omega_rad_s=W)
    _, nyq, ph, sv = fig.axes
    s = 1j * W
    L = 2 / (s * (s + 1))
    assert np.allclose(ph.lines[0].get_ydata(), -90 - np.degrees(np.arctan(W)), rtol=RTOL)
    x, y = nyq.lines[0].get_data()
    assert np.allclose(x + 1j * y, L, rtol=RTOL)
    by_label = {line.get_label(): line.get_ydata() for line in sv.lines}
    assert np.allclose(by_label["σ̄(S)"], 1 / np.abs(1 + L), rtol=1e-10)  # a 2-state feedback
    assert np.allclose(by_label["σ̄(T)"], np.abs(L / (1 + L)), rtol=1e-10)  # realisation: cond ε


def test_a_multiloop_figure_draws_each_channel_and_both_singular_values():
    """Two channels on the Bode axes (labelled by input), no Nyquist (refused in words), and
    σ̄, σ_min of the diagonal L: the larger and smaller of 8 and 2 over |jω (jω + 1)|."""
    fig = loop_figure(_mimo(), omega_rad_s=W)
    mag, nyq, _, sv = fig.axes
    assert [line.get_label() for line in mag.lines[:2]] == ["torque[0]", "torque[1]"]
    assert not nyq.axison and "one channel" in nyq.texts[0].get_text()
    by_label = {line.get_label(): line.get_ydata() for line in sv.lines}
    base = 1 / np.abs(1j * W * (1j * W + 1))
    assert np.allclose(by_label["σ̄(L)"], 8 * base, rtol=1e-10)
    assert np.allclose(by_label["σ_min(L)"], 2 * base, rtol=1e-10)


def test_drawing_a_figure_opens_no_pyplot_window():
    """A bare matplotlib Figure: not registered with pyplot's figure manager (no window, not
    kept alive by pyplot), drawn on a non-GUI canvas. (python-control itself imports pyplot,
    so "pyplot not imported" is not a claim this module can make.)"""
    import matplotlib.pyplot as plt
    from matplotlib.backend_bases import FigureCanvasBase

    before = plt.get_fignums()
    fig = loop_figure(_siso(), omega_rad_s=W)
    assert plt.get_fignums() == before
    assert type(fig.canvas) is FigureCanvasBase


def test_an_unknown_frequency_unit_is_refused_by_name():
    from flexsat.input_checks import FieldError

    with pytest.raises(FieldError, match="frequency_unit.*'rad/s' or 'Hz'"):
        loop_figure(_siso(), frequency_unit="rpm")
