"""The seed 003 slew goals (L792–L801) on histories with known answers."""

import numpy as np
import pytest

from flexsat.sim.slew_goals import SlewGoals, euler_angle_error, slew_goal_metrics

T = 10.0
t = np.linspace(0.0, 15.0, 1501)  # dt = 0.01 s: 1.25 T = 12.5 s is a sample
target = np.array([1.0, 1.0, 1.0])


def _run(error_at_eval, after_amplitude, open_amplitude=1.0):
    """Angles reaching the target with a chosen error at 12.5 s; rim deflections that are
    sinusoids of chosen amplitudes after the slew, twice as large during it."""
    angles = np.broadcast_to(target, (1, len(t), 3)).copy()
    angles[0, :, 1] += error_at_eval * (t / 12.5) ** 2  # exact at 12.5 s
    s = np.sin(2 * np.pi * 0.2422 * t)[None, :, None, None] * np.array([0.6, 0.8, 0.0])
    during = t <= T
    closed = np.where(during[None, :, None, None], 2 * after_amplitude, after_amplitude) * s
    opened = np.where(during[None, :, None, None], 2 * open_amplitude, open_amplitude) * s
    return angles, np.repeat(closed, 4, axis=2), np.repeat(opened, 4, axis=2)


def test_the_angle_goal_is_three_percent_of_the_commanded_angle_at_125_percent_of_T():
    for error, met in ((0.029, True), (0.031, False), (-0.031, False)):
        angles, closed, opened = _run(error, 0.01)
        m, units = slew_goal_metrics(t, T, angles, target, closed, opened)
        assert m["angle_error_mrad"][0] == pytest.approx(1e3 * abs(error), rel=1e-12)
        assert m["angle_error_y_mrad"][0] == pytest.approx(1e3 * abs(error), rel=1e-12)
        assert m["angle_tolerance_mrad"][0] == pytest.approx(30.0)
        assert bool(m["angle_goal_met"][0]) is met
        assert units["angle_error_mrad"] == "mrad"


def test_the_deflection_goal_compares_the_peaks_from_125_percent_of_T_with_open_loop():
    # a 0.2422 Hz sinusoid over [12.5, 15] s passes a crest (period 4.13 s, window 2.5 s > T/2),
    # so the window peak is the amplitude to the sampling error 1 - cos(π f dt) ~ 3e-5
    for amplitude, met in ((0.09, True), (0.11, False)):
        angles, closed, opened = _run(0.0, amplitude)
        m, units = slew_goal_metrics(t, T, angles, target, closed, opened)
        assert m["open_loop_rim_deflection_after_m"][0] == pytest.approx(1.0, rel=1e-4)
        assert m["deflection_ratio_after"][0] == pytest.approx(1 / amplitude, rel=1e-9)
        assert m["deflection_ratio_slew"][0] == pytest.approx(1 / amplitude, rel=1e-9)
        assert m["peak_rim_deflection_slew_m"][0] == pytest.approx(2 * amplitude, rel=1e-4)
        assert bool(m["deflection_goal_met"][0]) is met
        assert units["peak_rim_deflection_after_m"] == "m"


def test_peak_torques_perturbations_and_forces_are_reported():
    angles, closed, opened = _run(0.0, 0.05)
    nominal = np.zeros((1, len(t), 3))
    nominal[0, :, 2] = 12000.0 * np.sin(np.pi * t / 15.0)
    torque = nominal.copy()
    torque[0, 300, 1] = -3000.0
    forces = np.zeros((1, len(t), 7))
    forces[0, 500, 3] = 70.0
    m, units = slew_goal_metrics(
        t, T, angles, target, closed, opened, torque=torque, torque_nominal=nominal, forces=forces
    )
    assert m["peak_torque_z_Nm"][0] == pytest.approx(12000.0, rel=1e-4)
    assert m["peak_torque_y_Nm"][0] == 3000.0
    assert m["peak_torque_perturbation_Nm"][0] == 3000.0
    assert m["peak_force_N"][0] == 70.0
    assert units["peak_force_N"] == "N" and units["peak_torque_z_Nm"] == "N m"


def test_angle_errors_wrap_around_a_full_turn():
    e = euler_angle_error([2 * np.pi + 0.01, -0.02, np.pi - 0.01], [0.0, 0.0, -np.pi + 0.01])
    np.testing.assert_allclose(e, [0.01, -0.02, -0.02], atol=1e-14)


def test_a_record_too_short_or_a_zero_slew_is_refused():
    angles, closed, opened = _run(0.0, 0.05)
    with pytest.raises(ValueError, match=r"t: the record must span \[0, 12.5\] s"):
        slew_goal_metrics(t[:1000], T, angles[:, :1000], target, closed[:, :1000], opened[:, :1000])
    with pytest.raises(ValueError, match="target: a slew of zero angle"):
        slew_goal_metrics(t, T, angles, np.zeros(3), closed, opened)
    with pytest.raises(ValueError, match="duration"):
        slew_goal_metrics(t, -1.0, angles, target, closed, opened)
    with pytest.raises(ValueError, match="evaluation: must be >= 1"):
        SlewGoals(evaluation=0.5)
    with pytest.raises(ValueError, match="deflection_ratio"):
        SlewGoals(deflection_ratio=0.0)
