"""Synthetic vibration tests on the engine (:mod:`flexsat.sim.vibration_test`): a one-sample
hammer gives the Markov parameters of the zero-order-hold discretisation (checked against
scipy's ``cont2discrete``, an independent matrix exponential); the recorded shaker input is the
sine averaged over each sample (closed form); noise is the stated fraction of the channel RMS,
seeded; the ADC step leaves integer multiples of it; bad tests are refused naming the field."""

import numpy as np
import pytest
from scipy.signal import cont2discrete

from flexsat.cases import tamu_grid
from flexsat.identify import Channel, harmonic_shaker, impulse_hammer, random_force
from flexsat.identify.excitation import sensor_matrices
from flexsat.sim.vibration_test import simulate_test


@pytest.fixture(scope="module")
def grid():
    return tamu_grid().modal_model(6, damping=0.02)


def test_a_one_sample_hammer_gives_the_zoh_markov_parameters(grid):
    # the default hammer is one sample wide: its average over [0, Δt) is 2F/π (a half-sine of
    # peak F), zero after, so y_0 = D u_0 and y_k = C A_d^(k−1) Γ u_0 (k >= 1), A_d = e^{AΔt},
    # Γ = ∫e^{As}ds B: computed here by scipy's zoh discretisation, not the engine's φ1 kernel
    fs, force = 100.0, 3.0
    sensors = [Channel.at("displacement", 13, "z"), Channel.at("acceleration", 7, "z")]
    hammer = impulse_hammer(1, "z", force)
    meas = simulate_test(grid, hammer, sensors, 2.0, fs)
    A, B, C, D = sensor_matrices(grid, sensors, [hammer.channel])
    Ad, Gd, Cd, Dd, _ = cont2discrete((A, B, C, D), 1.0 / fs, method="zoh")
    u0 = 2.0 * force / np.pi
    n = meas.outputs.shape[1]
    expect = np.empty((len(sensors), n))
    x = Gd[:, 0] * u0
    expect[:, 0] = Dd[:, 0] * u0
    for k in range(1, n):
        expect[:, k] = Cd @ x
        x = Ad @ x
    scale = np.abs(expect).max(axis=1, keepdims=True)
    # two exponentials of a 12-state system (‖AΔt‖ ~ 1): agreement to ~1e-12 of each channel
    np.testing.assert_allclose(meas.outputs / scale, expect / scale, rtol=0, atol=1e-10)
    np.testing.assert_allclose(meas.inputs[0], np.r_[u0, np.zeros(n - 1)], atol=1e-15)
    np.testing.assert_allclose(meas.abscissa, np.arange(n) / fs, rtol=1e-15)


def test_the_recorded_shaker_input_is_the_sine_averaged_over_each_sample(grid):
    # with oversample 4 the engine runs at 4 fs; the recorded input is the mean over each
    # sample of F sin(ωt): F (cos ωt_k − cos ω(t_k + Δt)) / (ωΔt)
    fs, f, F = 50.0, 3.0, 2.0
    meas = simulate_test(
        grid,
        harmonic_shaker(1, "z", F, f),
        [Channel.at("displacement", 13, "z")],
        1.0,
        fs,
        oversample=4,
    )
    t, w, dt = meas.abscissa, 2 * np.pi * f, 1.0 / fs
    np.testing.assert_allclose(
        meas.inputs[0],
        F * (np.cos(w * t) - np.cos(w * (t + dt))) / (w * dt),
        rtol=1e-12,
        atol=1e-14,
    )
    assert meas.attrs["oversample"] == 4


def test_quantization_leaves_multiples_of_the_adc_step_and_seeds_repeat(grid):
    sensor = [Channel.at("displacement", 13, "z")]
    q = 1e-6
    runs = [
        simulate_test(grid, random_force(1, "z", 1.0), sensor, 2.0, 100.0, 0.01, q, seed=s)
        for s in (5, 5, 6)
    ]
    np.testing.assert_allclose(runs[0].outputs / q, np.round(runs[0].outputs / q), atol=1e-6)
    np.testing.assert_array_equal(runs[0].outputs, runs[1].outputs)
    np.testing.assert_array_equal(runs[0].inputs, runs[1].inputs)
    assert not np.array_equal(runs[0].inputs, runs[2].inputs)
    assert runs[0].attrs["seed"] == 5 and runs[0].attrs["noise"] == 0.01


@pytest.mark.parametrize(
    "kwargs, field",
    [
        ({"duration": 0.01}, "duration: gives 1 sample"),
        ({"sample_rate": -1.0}, "sample_rate"),
        ({"noise": -0.1}, "noise"),
        ({"oversample": 0}, "oversample"),
        ({"quantization": 0.0}, "quantization"),
    ],
)
def test_bad_settings_are_named(grid, kwargs, field):
    args = {"duration": 1.0, "sample_rate": 100.0, **kwargs}
    with pytest.raises(ValueError, match=field):
        simulate_test(
            grid, harmonic_shaker(1, "z", 1.0, 1.0), [Channel.at("displacement", 1, "z")], **args
        )


def test_noise_is_the_stated_fraction_of_the_channel_rms(grid):
    sensor = Channel.at("displacement", 13, "z")
    clean = simulate_test(grid, harmonic_shaker(1, "z", 2.0, 1.5), [sensor], 60.0, 100.0)
    noisy = simulate_test(
        grid, harmonic_shaker(1, "z", 2.0, 1.5), [sensor], 60.0, 100.0, noise=0.05, seed=3
    )
    rms = np.sqrt(np.mean(clean.outputs[0] ** 2))
    # 6000 samples: the sample std is within 5 % of the target with overwhelming probability
    assert np.std(noisy.outputs[0] - clean.outputs[0]) == pytest.approx(0.05 * rms, rel=0.05)


def test_bad_tests_are_refused(grid):
    with pytest.raises(ValueError, match=r"^sensors: must be a non-empty list"):
        simulate_test(grid, harmonic_shaker(1, "z", 1.0, 1.0), [], 1.0, 100.0)
    with pytest.raises(ValueError, match=r"^excitation: must be an Excitation"):
        simulate_test(grid, [], [Channel.at("displacement", 1, "z")], 1.0, 100.0)
