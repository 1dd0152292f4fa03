"""The one settling time (flexsat.analysis.settling): claims against analytic responses.

For e(t) = A e^{-t} sampled every Δt, the response leaves a band b for good at ln(A/b): the
settling time is the first sample at or after it, so within one Δt above it.
"""

import numpy as np
import pytest

from flexsat.analysis.settling import reported, settling_time

T = np.linspace(0.0, 10.0, 1001)
DT = T[1] - T[0]


def test_the_last_exit_from_an_absolute_band_per_case():
    err = np.exp(-T)[None, :] * np.array([[1.0], [-3.0]])
    ts = settling_time(T, err, 0.01)
    exact = np.log([100.0, 300.0])
    assert np.all(ts >= exact) and np.all(ts - exact <= DT)
    # a per-case band, shape (n_cases, 1): both leave 1 % of their own amplitude at ln 100
    per_case = settling_time(T, err, np.array([[0.01], [0.03]]))
    assert per_case[0] == per_case[1] == ts[0]


def test_a_band_relative_to_the_peak_is_a_fraction_of_the_largest_magnitude():
    """10 % of the peak of A e^{-t} is left at ln 10 whatever A."""
    for amplitude in (1e-3, 1.0, 250.0):
        ts = settling_time(T, amplitude * np.exp(-T), 0.1, relative_to_peak=True)
        assert np.log(10.0) <= ts <= np.log(10.0) + DT


def test_several_signals_settle_together():
    """e1 = e^{-t} in 0.01 (ln 100) and e2 = e^{-t/2} in 0.1 (2 ln 10 = ln 100 too, shifted):
    the later exit decides."""
    e1, e2 = np.exp(-T), 2 * np.exp(-T / 2)
    both = settling_time(T, (e1, e2), (0.01, 0.1))
    alone = [settling_time(T, e1, 0.01), settling_time(T, e2, 0.1)]
    assert both == max(alone)
    assert 2 * np.log(20.0) <= both <= 2 * np.log(20.0) + DT
    with pytest.raises(ValueError, match=r"^band: one per error signal \(2\), got 3"):
        settling_time(T, (e1, e2), (0.1, 0.1, 0.1))


def test_never_outside_is_the_first_time_and_never_settled_is_nan_then_none():
    assert settling_time(T + 2.0, 0.001 * np.exp(-T), 0.01) == 2.0
    not_settled = settling_time(T[:11], np.ones((1, 11)), 0.1)
    assert not_settled.shape == (1,) and np.isnan(not_settled[0])  # never the run length
    assert reported(not_settled[0]) is None
    assert reported(settling_time(T, np.exp(-T), 0.5)) == pytest.approx(0.7, abs=1e-12)
    with pytest.raises(ValueError, match=r"^error: 11 samples along its last axis for 1001"):
        settling_time(T, np.ones(11), 0.1)
