"""Star tracker as a sensor of the three-axis rigid body (issue 14 part 4): the measured
attitude's error has the covariance calibrated from the full identification pipeline."""

import numpy as np
import pytest

from flexsat.attitude.fit import rotation_error
from flexsat.attitude.star_camera import StarCamera
from flexsat.attitude.star_catalog import synthetic_sky
from flexsat.attitude.star_tracker import ARCSEC, StarTracker, random_attitudes
from flexsat.control.base import Controller
from flexsat.dynamics.attitude import dcm_to_quaternion, quaternion_to_dcm
from flexsat.dynamics.plant import Channel
from flexsat.dynamics.rigid_spacecraft import RigidSpacecraft
from flexsat.sim import SimConfig, simulate
from flexsat.sim.star_sensor import StarTrackerSensor


def test_measured_attitude_errors_have_the_stated_covariance():
    P = np.array([[4.0, 1.0, 0.0], [1.0, 2.0, 0.5], [0.0, 0.5, 9.0]]) * ARCSEC**2
    s = StarTrackerSensor(covariance=P).bind(Channel("attitude", "", size=4))
    rng = np.random.default_rng(0)
    C = random_attitudes(20000, seed=1)
    beta = dcm_to_quaternion(C)
    meas = s.measure(beta, rng.standard_normal((20000, 4)))
    err = rotation_error(quaternion_to_dcm(meas), C)
    # 20000 samples: a covariance entry's sampling sd is <= sqrt(2/20000) = 1 % of the variances
    np.testing.assert_allclose(np.cov(err, rowvar=False), P, atol=0.04 * np.max(P))
    np.testing.assert_allclose(np.linalg.norm(meas, axis=1), 1.0, atol=1e-14)


class Recorder(Controller):
    """Zero torque; keeps every measured attitude."""

    reads = ("attitude",)
    writes = ("torque",)
    target = 0.0

    def __init__(self):
        self.seen = []

    def __call__(self, t, y, state):
        self.seen.append(np.array(y["attitude"]))
        return np.zeros(y["attitude"].shape[:-1] + (3,)), state


def test_star_tracker_on_the_rigid_body_calibrated_from_the_pipeline():
    cams = (StarCamera(), StarCamera(mounting=(0, "90 deg", 0)))
    tracker = StarTracker(cams, synthetic_sky(6.5, seed=0))
    sensor = StarTrackerSensor.from_tracker(tracker, n=150, seed=3)
    assert sensor.identification_rate == 1.0
    sig = np.sqrt(np.diag(sensor.covariance))
    assert np.all(sig < 1 * ARCSEC) and np.all(sig > 0.05 * ARCSEC)  # sub-arcsecond, not zero

    plant = RigidSpacecraft(np.diag([100.0, 200.0, 300.0]))
    x0 = plant.state_from(euler123=[0.3, -0.2, 0.1], rate=[0.01, -0.02, 0.005])
    law = Recorder()
    cfg = SimConfig(
        duration=20.0, control_rate=10.0, substeps=2, channel_sensors={"attitude": sensor}
    )
    r = simulate(plant, law, cfg, n_cases=1, initial_state=x0, record_states=True)
    X = r.dataset["state"].values[0]
    meas = np.concatenate(law.seen)
    truth = X[: meas.shape[0], :4]
    err = rotation_error(quaternion_to_dcm(meas), quaternion_to_dcm(truth))
    # 200 samples: each axis's sd within 25 % (> 3 sampling sd of sqrt(1/400) = 5 %)
    np.testing.assert_allclose(np.std(err, 0), sig, rtol=0.25)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(covariance=np.eye(2)), "covariance: give a"),
        (dict(covariance=[[1, 2, 0], [0, 1, 0], [0, 0, 1]]), "covariance: must be symmetric"),
        (dict(covariance=-np.eye(3)), "positive semi-definite"),
        (dict(covariance="-1 arcsec"), "covariance: give a"),
        (dict(covariance="1 arcsec", identification_rate=0), "identification_rate"),
    ],
)
def test_bad_star_sensor_input(kwargs, match):
    with pytest.raises(ValueError, match=match):
        StarTrackerSensor(**kwargs)


def test_star_sensor_only_on_the_attitude_channel():
    with pytest.raises(
        ValueError, match="sensors\\[rate\\]: a star tracker measures the attitude channel"
    ):
        StarTrackerSensor(covariance="1 arcsec").bind(Channel("rate", "rad/s", size=3))
    s = StarTrackerSensor(covariance="1 arcsec")
    np.testing.assert_allclose(np.sqrt(np.diag(s.covariance)), ARCSEC, rtol=1e-12)
