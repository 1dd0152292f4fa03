import numpy as np
import pytest

from flexsat.sim.sensors import Sensors, least_squares_derivative_weights


@pytest.mark.parametrize("window,order", [(2, 1), (8, 1), (8, 2), (12, 3)])
def test_least_squares_differentiator_is_exact_for_polynomials_of_its_order(window, order):
    dt = 1 / 75
    w = least_squares_derivative_weights(window, order, dt)
    t = dt * (np.arange(window) - (window - 1)) + 3.0  # newest sample at t = 3
    coeffs = np.arange(1, order + 2) * 0.3
    p = np.polynomial.Polynomial(coeffs)
    assert w @ p(t) == pytest.approx(p.deriv()(3.0), rel=1e-10)


def test_encoder_quantizes_to_its_resolution():
    s = Sensors(encoder_resolution=np.radians(0.01))
    th = np.radians(np.array([0.004, 0.006, 40.0049]))
    assert np.allclose(np.degrees(s.quantize(th)), [0.0, 0.01, 40.0], atol=1e-12)


def test_gyro_and_strain_noise_have_their_standard_deviation():
    """The planar preset puts the gyro noise on theta_dot and the strain noise on root_torque
    (sim.channels.resolve_channels); each scales its standard normals."""
    from flexsat.cases import tamu
    from flexsat.sim import SimConfig
    from flexsat.sim.channels import resolve_channels

    s = Sensors(rate="gyro", gyro_noise=0.01, strain_noise=0.2)
    sensors, _, _ = resolve_channels(tamu(n_modes=2).model(), SimConfig(duration=1.0, sensors=s))
    noise = np.random.default_rng(0).standard_normal((20000, 2))
    rate = sensors["theta_dot"].measure(np.ones(20000), noise[:, 0])
    root = sensors["root_torque"].measure(np.zeros(20000), noise[:, 1])
    # 20000 samples: the sample std is within 3 % with overwhelming probability
    assert np.std(rate) == pytest.approx(0.01, rel=0.03)
    assert np.mean(rate) == pytest.approx(1.0, abs=1e-3)
    assert np.std(root) == pytest.approx(0.2, rel=0.03)


def test_bad_sensor_settings():
    with pytest.raises(ValueError, match=r"^rate: must be 'ideal', 'ls_filter' or 'gyro'"):
        Sensors(rate="tacho")
    with pytest.raises(ValueError, match=r"^rate_filter: need order >= 1 and window >= order"):
        Sensors(rate="ls_filter", rate_window=2, rate_order=2)
    with pytest.raises(ValueError, match=r"^gyro_noise: must be >= 0"):
        Sensors(gyro_noise=-1.0)
