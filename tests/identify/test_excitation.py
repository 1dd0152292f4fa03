"""Synthetic vibration tests (flexsat.identify.excitation) against modal theory."""

import numpy as np
import pytest

from flexsat.cases import tamu_grid
from flexsat.identify import Channel, harmonic_shaker, simulate_test


@pytest.fixture(scope="module")
def grid():
    return tamu_grid().modal_model(6, damping=0.02)


def test_harmonic_steady_state_is_the_modal_frf(grid):
    """Shaker at node 1 (z) between modes 1 and 2; after the transient (ζ = 0.02, > 40 time
    constants of mode 1) the displacement amplitude at node 13 equals |Σ φ_o φ_i /
    (ω_i² − ω² + 2jζω_iω)| to 1 % (the 1 % covers the residual transient and sampling)."""
    f = 1.5
    w = 2 * np.pi * f
    sensor = Channel("displacement", 13, "z")
    meas = simulate_test(grid, harmonic_shaker(1, "z", 2.0, f), [sensor], 400.0, 100.0)
    tail = meas.outputs[0, -int(20 * 100 / f):]  # last 20 periods
    amplitude = 0.5 * np.ptp(tail)
    phi_i = grid.force_input(1, "z")
    phi_o = grid.displacement_output(13, "z")
    wi, zi = grid.frequencies, grid.damping
    frf = np.sum(phi_o * phi_i / (wi**2 - w**2 + 2j * zi * wi * w))
    assert amplitude == pytest.approx(2.0 * abs(frf), rel=1e-2)


def test_noise_is_the_stated_fraction_of_the_channel_rms(grid):
    sensor = Channel("displacement", 13, "z")
    clean = simulate_test(grid, harmonic_shaker(1, "z", 2.0, 1.5), [sensor], 60.0, 100.0)
    noisy = simulate_test(grid, harmonic_shaker(1, "z", 2.0, 1.5), [sensor], 60.0, 100.0,
                          noise=0.05, seed=3)
    rms = np.sqrt(np.mean(clean.outputs[0] ** 2))
    # 6000 samples: the sample std is within 5 % of the target with overwhelming probability
    assert np.std(noisy.outputs[0] - clean.outputs[0]) == pytest.approx(0.05 * rms, rel=0.05)


def test_bad_tests_are_refused(grid):
    with pytest.raises(ValueError, match=r"^sensors: must be a non-empty list"):
        simulate_test(grid, harmonic_shaker(1, "z", 1.0, 1.0), [], 1.0, 100.0)
    with pytest.raises(ValueError, match=r"^excitation: must be an Excitation"):
        simulate_test(grid, [], [Channel("displacement", 1, "z")], 1.0, 100.0)
