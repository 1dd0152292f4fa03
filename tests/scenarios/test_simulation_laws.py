"""The laws a simulation run names (:mod:`flexsat.scenarios.simulation_laws`): a target's
Euler angles become the quaternion of the closed form; the attitude laws are built with that
target (no torque at it, at rest); the LQR law's gain is the Riccati solution of the plant's
linear part (checked against the double integrator's closed form); bad weights and targets are
refused naming the field (the open loop runs in tests/scenarios/test_simulation.py)."""

from __future__ import annotations

import numpy as np
import pytest

from flexsat.dynamics.plant import Channel
from flexsat.scenarios.simulation_laws import (
    BUILTIN_LAWS,
    AttitudeTarget,
    LawContext,
    simulation_laws,
    target_quaternion,
)

EPS = np.finfo(float).eps


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_a_single_axis_euler_target_is_the_half_angle_quaternion(axis):
    # a rotation θ about one body axis: β = [cos θ/2, sin θ/2 e_axis] (Euler parameters,
    # scalar first), to round-off of the DCM round trip
    theta = 0.7
    angles = [0.0, 0.0, 0.0]
    angles[axis] = theta
    beta = target_quaternion({"euler123": angles})
    expect = np.zeros(4)
    expect[0] = np.cos(theta / 2)
    expect[1 + axis] = np.sin(theta / 2)
    np.testing.assert_allclose(beta * np.sign(beta[0]), expect, atol=10 * EPS)
    assert target_quaternion({}) is None
    # the section object reads the same, with units
    section = AttitudeTarget(euler123=["0 deg", "0 deg", f"{np.rad2deg(theta)} deg"])
    np.testing.assert_allclose(
        abs(section.quaternion()), abs(target_quaternion({"euler123": [0, 0, theta]})), atol=1e-15
    )


@pytest.mark.parametrize(
    "target, message",
    [
        ({"spin": 1}, "target.spin: not a target"),
        ({"euler123": [1, 2]}, "target.euler123: three angles"),
        ({"euler123": [0, 0, 0], "attitude": [1, 0, 0, 0]}, "target: give euler123 or attitude"),
        ({"euler123": ["1 s", 0, 0]}, "target.euler123"),
    ],
)
def test_bad_targets_are_named(target, message):
    with pytest.raises(ValueError, match=message):
        target_quaternion(target)


def test_both_target_forms_are_refused_by_the_section():
    with pytest.raises(ValueError, match="give euler123 or attitude, not both"):
        AttitudeTarget(euler123=[0, 0, 0], attitude=[1, 0, 0, 0])


@pytest.mark.parametrize("name", ["gibbs_lyapunov", "mrp_pd", "quaternion_pd"])
def test_an_attitude_law_turns_to_its_target_and_rests_there(name):
    law_class = BUILTIN_LAWS[name]
    gains = {
        "gibbs_lyapunov": {"k": 1000.0, "A": 50.0},
        "mrp_pd": {"K": 100.0, "P": 1000.0},
        "quaternion_pd": {"Kp": 100.0, "Kd": 1000.0},
    }[name]
    target = AttitudeTarget(euler123=[0.0, 0.0, 0.5])
    law = law_class.from_scenario(
        law_class.Parameters(**gains), LawContext(plant=None, dt=0.1, target=target)
    )
    beta_t = target.quaternion()
    np.testing.assert_allclose(abs(law.beta_target), abs(beta_t), atol=1e-15)
    rest = np.zeros(3)
    np.testing.assert_allclose(law.torque(beta_t, rest), 0.0, atol=1e-9)
    # away from it, a restoring torque about the slew axis (z), of the sign that turns toward
    # +0.5 rad
    torque = law.torque(np.array([1.0, 0.0, 0.0, 0.0]), rest)
    assert torque[2] > 0 and np.allclose(torque[:2], 0.0, atol=1e-9)


class DoubleIntegrator:
    """What the LQR law reads of a plant: its linear part and its input channels
    (θ̈ = u: A = [[0, 1], [0, 0]], B = [0, 1]ᵀ)."""

    inputs = (Channel("torque", "N*m", 1, "torque"),)

    def linear_part(self):
        return np.array([[0.0, 1.0], [0.0, 0.0]]), np.array([[0.0], [1.0]])


def test_lqr_gain_is_the_double_integrators_closed_form():
    # with Q = diag(q1, q2), R = r the Riccati solution gives
    # K = [√(q1/r), √(q2/r + 2√(q1/r))] (e.g. Anderson & Moore, Optimal Control, §3.3)
    q1, q2, r = 4.0, 1.0, 0.25
    law_class = BUILTIN_LAWS["lqr"]
    law = law_class.from_scenario(
        law_class.Parameters(state_weights=[q1, q2], input_weights=r),
        LawContext(plant=DoubleIntegrator(), dt=0.1),
    )
    k1 = np.sqrt(q1 / r)
    k2 = np.sqrt(q2 / r + 2.0 * k1)
    x = np.array([[0.3, -0.2]])
    u, _ = law(0.0, {"state": x}, {})
    u = u["torque"] if isinstance(u, dict) else u
    np.testing.assert_allclose(np.ravel(u), [-(k1 * 0.3 - k2 * 0.2)], rtol=1e-10)


@pytest.mark.parametrize(
    "weights, message",
    [
        ({"state_weights": [1.0, -1.0]}, "gains.state_weights: one weight >= 0 or 2 of them"),
        ({"state_weights": [1.0, 1.0, 1.0]}, "gains.state_weights: one weight >= 0 or 2"),
        ({"state_weights": 1.0, "input_weights": np.nan}, "gains.input_weights"),
    ],
)
def test_lqr_weights_are_refused_by_field(weights, message):
    law_class = BUILTIN_LAWS["lqr"]
    with pytest.raises(ValueError, match=message):
        law_class.from_scenario(
            law_class.Parameters(**weights), LawContext(plant=DoubleIntegrator(), dt=0.1)
        )


def test_the_registry_starts_with_the_built_in_laws():
    laws = simulation_laws()
    assert list(laws)[: len(BUILTIN_LAWS)] == list(BUILTIN_LAWS)
    assert all(laws[name] is law for name, law in BUILTIN_LAWS.items())


ATTITUDE_LQG = """
kind: simulation
name: test
case: eps
plant: {model: rigid}
initial: {euler123: ["10 deg", 0, 0]}
simulation: {duration: "60 s", control_rate: "10 Hz"}
runs:
  - label: lqg
    law: attitude_lqg
    gains:
      coordinates: mrp
      state_weights: [1e8, 1e8, 1e8, 1e6, 1e6, 1e6]
      process_noise: 1e6
      measurement_noise: [1e-6, 1e-6, 1e-6, 1e-4, 1e-4, 1e-4]
    target: {euler123: [0, 0, "5 deg"]}
"""


def test_the_attitude_lqg_is_designed_on_the_plants_linearisation_and_slews():
    """``law: attitude_lqg`` builds AttitudeLQG.design on linearize_attitude(plant) with the
    diagonal weights and noise intensities and the run's target (the same gains, bit for bit),
    and the scenario's 10° + 5° slew of the rigid EPS settles (within 0.5° by 20 s, within
    0.01° at 60 s)."""
    from flexsat.control import AttitudeLQG
    from flexsat.dynamics import RigidSpacecraft, linearize_attitude
    from flexsat.scenarios import load_scenario, run_scenario

    plant = RigidSpacecraft(np.diag([2000.0, 3000.0, 4000.0]))
    law_class = BUILTIN_LAWS["attitude_lqg"]
    parameters = law_class.Parameters(
        coordinates="quaternion",
        state_weights=[1e8] * 3 + [1e6] * 3,
        input_weights=2.0,
        process_noise=1e6,
        measurement_noise=[1e-6] * 3 + [1e-4] * 3,
    )
    target = AttitudeTarget(euler123=[0.0, 0.0, 0.5])
    law = law_class.from_scenario(parameters, LawContext(plant=plant, dt=0.1, target=target))
    direct = AttitudeLQG.design(
        linearize_attitude(plant, "quaternion"),
        np.diag([1e8] * 3 + [1e6] * 3),
        2.0 * np.eye(3),
        1e6 * np.eye(3),
        np.diag([1e-6] * 3 + [1e-4] * 3),
        0.1,
        beta_target=target.quaternion(),
    )
    np.testing.assert_array_equal(law.K, direct.K)
    np.testing.assert_array_equal(law.L, direct.L)
    np.testing.assert_array_equal(law.beta_target, direct.beta_target)
    assert law.linearization.coordinates == "quaternion"

    result = run_scenario(load_scenario(ATTITUDE_LQG))
    metrics = result.metrics_records()[0]
    assert metrics["final_pointing_error_deg"] < 0.01
    assert metrics["pointing_settling_time_s"] < 20.0


@pytest.mark.parametrize(
    "change, message",
    [
        (("coordinates: mrp", "coordinates: gibbs"), "coordinates: must be one of"),
        (("process_noise: 1e6", "process_noise: [1, 2]"), "gains.process_noise: one weight"),
        (("measurement_noise: [1e-6, ", "measurement_noise: ["), "gains.measurement_noise"),
    ],
)
def test_attitude_lqg_mistakes_name_the_field(change, message):
    from flexsat.scenarios import ScenarioError, load_scenario, run_scenario

    text = ATTITUDE_LQG.replace(*change)
    assert text != ATTITUDE_LQG
    with pytest.raises(ScenarioError, match=message):
        run_scenario(load_scenario(text))
