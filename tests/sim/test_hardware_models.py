"""The hardware pieces (flexsat.sim.hardware_models): filters' corners and poles, the exact
ZOH against an independent discretisation, companion blocks, limits, bad input."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import cont2discrete

from flexsat.input_checks import FieldError
from flexsat.sim.hardware_models import (
    Amplifier,
    AntiAliasFilter,
    ReactionWheel,
    companion_blocks,
    zoh,
)


def test_filter_corner_and_dc_gain():
    # −3 dB at the corner for both kinds (norm "mag"), unit gain at DC: the filter's definition
    for kind in ("butterworth", "bessel"):
        f = AntiAliasFilter(10.0, 4, kind)
        h = f.frequency_response(np.array([0.0, 10.0]))
        assert abs(h[0] - 1) < 1e-12
        assert abs(abs(h[1]) - 2**-0.5) < 1e-9


def test_zoh_against_scipy():
    # Van Loan's block exponential against scipy's zero-order hold (an independent
    # implementation of the same integral): equal to round-off of the exponential
    A, B, C = AntiAliasFilter(10.0, 4, "bessel").matrices()
    Phi, Gam = zoh(A, B, 0.01)
    Ad, Bd, *_ = cont2discrete((A, B, C, np.zeros((1, 1))), 0.01, method="zoh")
    np.testing.assert_allclose(Phi, Ad, atol=1e-13)
    np.testing.assert_allclose(Gam, Bd, atol=1e-13 * np.abs(Bd).max())


def test_companion_blocks_of_a_butterworth():
    # T⁻¹ A T block-diagonal with the companion blocks (ω, ζ) of the poles: Butterworth poles
    # lie on the circle of the corner with ζ = sin(π/8), sin(3π/8) at order 4
    A = AntiAliasFilter(10.0, 4).matrices()[0]
    T, Ti, w, z = companion_blocks(A)
    L = Ti @ A @ T
    for i in range(2):
        blk = np.array([[0.0, 1.0], [-(w[i] ** 2), -2 * z[i] * w[i]]])
        np.testing.assert_allclose(
            L[2 * i : 2 * i + 2, 2 * i : 2 * i + 2], blk, atol=1e-9 * w[i] ** 2
        )
    assert np.abs(L[:2, 2:]).max() < 1e-9 * np.abs(L).max()
    np.testing.assert_allclose(w, 2 * np.pi * 10.0, rtol=1e-12)
    np.testing.assert_allclose(sorted(z), np.sin([np.pi / 8, 3 * np.pi / 8]), rtol=1e-12)
    assert companion_blocks(AntiAliasFilter(10.0, 3).matrices()[0]) is None  # a real pole


def test_limits():
    # current mode: K_t min(I_max, gain V_dac); voltage mode: K_t min(V_max, gain V_dac) / R;
    # the back-EMF's no-load speed V_max / K_e (TAMU: 12 A of 52.77 oz-in/A is 633 oz-in)
    amp = Amplifier("current", 1.2, "12 A", torque_constant="52.77 ozf*in/A", dac_range="10 V")
    assert amp.torque_limit() == pytest.approx(12 * 52.77 * 0.00706155181, rel=1e-6)
    v = Amplifier("voltage", voltage_limit=24.0, gain=2.0, dac_range=10.0)
    assert v.torque_limit(2.0, 0.1) == pytest.approx(0.1 * 20.0 / 2.0)
    wheel = ReactionWheel(0.01, back_emf=0.05, amplifier=v)
    assert wheel.no_load_speed == pytest.approx(20.0 / 0.05)


def test_bad_pieces_are_refused_naming_the_field():
    with pytest.raises(FieldError, match="order"):
        AntiAliasFilter(10.0, 0)
    with pytest.raises(FieldError, match="kind"):
        AntiAliasFilter(10.0, 2, "chebyshev")
    with pytest.raises(FieldError, match="corner"):
        AntiAliasFilter(-1.0)
    with pytest.raises(FieldError, match="mode"):
        Amplifier("torque")
    with pytest.raises(FieldError, match="amplifier.gain"):
        Amplifier(gain=0.0)
    with pytest.raises(FieldError, match="wheel.inertia"):
        ReactionWheel(0.0)
    with pytest.raises(FieldError, match="wheel.amplifier"):
        ReactionWheel(1.0, amplifier="fast")  # type: ignore[arg-type]
