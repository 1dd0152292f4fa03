import numpy as np
import pytest

from flexsat.sim.metrics import maneuver_metrics


def test_overshoot_is_measured_in_the_direction_of_motion():
    t = np.linspace(0, 1, 5)
    theta = np.array([[0.0, 0.5, 1.2, 1.0, 1.0], [0.0, -0.5, -1.1, -1.0, -1.0]])
    z = np.zeros_like(theta)
    m = maneuver_metrics(t, theta, z, z, z, z, z, np.zeros(2), np.array([1.0, -1.0]), None, 0.05)
    assert m["overshoot_deg"] == pytest.approx(np.degrees([0.2, 0.1]))
    assert np.isnan(m["residual_energy_at_T_J"]).all()


def test_channel_metrics_of_a_three_axis_run():
    """Peaks (norm of a vector channel), finals of scalar outputs, RMS of inputs; the pointing
    error is the principal angle 2 arccos|β_t·β| of the error quaternion."""
    from flexsat.sim.metrics import channel_metrics

    t = np.linspace(0.0, 10.0, 11)
    angle = np.where(t < 5.0, np.radians(10.0), np.radians(0.1))  # settles at t = 5 s
    beta = np.stack([np.cos(angle / 2), np.sin(angle / 2), 0 * t, 0 * t], axis=-1)[None]
    torque = np.zeros((1, 11, 3))
    torque[0, :, 0] = 3.0
    torque[0, 2, 1] = 4.0
    gap = np.linspace(1.0, -2.0, 11)[None]
    metrics, units = channel_metrics(
        {"attitude": beta, "torque": torque, "gap": gap},
        {"torque": "N*m", "gap": "m"},
        ["attitude", "gap"],
        ["torque"],
        t,
        np.array([[1.0, 0, 0, 0]]),
        np.radians(0.5),
    )
    assert metrics["peak_torque"][0] == 5.0 and units["peak_torque"] == "N*m"
    np.testing.assert_allclose(metrics["rms_torque"][0], np.sqrt((11 * 9 + 16) / 11))
    assert metrics["peak_gap"][0] == 2.0 and metrics["final_gap"][0] == -2.0
    np.testing.assert_allclose(metrics["final_pointing_error_deg"][0], 0.1, rtol=1e-9)
    assert metrics["pointing_settling_time_s"][0] == 5.0
    assert "peak_attitude" not in metrics
