import numpy as np
import pytest

from flexsat.sim.metrics import maneuver_metrics, settling_time


def test_settling_time_is_the_last_exit_from_the_band():
    t = np.linspace(0, 10, 1001)
    err = np.exp(-t)[None, :] * np.array([[1.0], [-3.0]])
    ts = settling_time(t, err, 0.01)
    assert ts == pytest.approx([np.log(100), np.log(300)], abs=0.011)


def test_not_settled_is_nan_not_the_run_length():
    t = np.linspace(0, 1, 11)
    assert np.isnan(settling_time(t, np.ones((1, 11)), 0.1)[0])


def test_overshoot_is_measured_in_the_direction_of_motion():
    t = np.linspace(0, 1, 5)
    theta = np.array([[0.0, 0.5, 1.2, 1.0, 1.0], [0.0, -0.5, -1.1, -1.0, -1.0]])
    z = np.zeros_like(theta)
    m = maneuver_metrics(t, theta, z, z, z, z, z, np.zeros(2), np.array([1.0, -1.0]), None, 0.05)
    assert m["overshoot_deg"] == pytest.approx(np.degrees([0.2, 0.1]))
    assert np.isnan(m["residual_energy_at_T_J"]).all()
