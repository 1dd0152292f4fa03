"""A reaction-wheel array on three-axis spacecraft (flexsat.sim.wheel_array) in the loop of
the one engine: the total angular momentum (body + wheels) conserved to the integrator's
error, each wheel's speed limit respected, and a 4-wheel pyramid slew equal to the ideal-torque
slew where the wheels' gyroscopic torque vanishes."""

from __future__ import annotations

import numpy as np
import pytest

from flexsat.control.attitude_laws import QuaternionPD
from flexsat.control.playback import Playback
from flexsat.dynamics import FlexibleSpacecraft, RigidSpacecraft
from flexsat.dynamics import attitude as att
from flexsat.input_checks import FieldError
from flexsat.sim import SimConfig, simulate
from flexsat.sim.hardware import Hardware
from flexsat.sim.wheel_array import ReactionWheelArray, WheelArrayPlant, pyramid_axes
from modal_models import coupled_modal

#: the pyramid of the four-wheel arrays: half-angle 54.74° (the axes equally spaced in angle)
PYRAMID = pyramid_axes(np.arccos(1 / np.sqrt(3)))
J_BODY = np.array([[10.0, 0.5, 0.0], [0.5, 12.0, 0.0], [0.0, 0.0, 8.0]])


def test_the_distribution_is_the_pseudo_inverse():
    arr = ReactionWheelArray(PYRAMID, 0.05)
    P = arr.distribution
    G = PYRAMID
    # G⁺ = Gᵀ (G Gᵀ)⁻¹ (independent formula), and G G⁺ = I: the body gets the law's torque
    np.testing.assert_allclose(P, G.T @ np.linalg.inv(G @ G.T), atol=1e-14)
    np.testing.assert_allclose(G @ P, np.eye(3), atol=1e-14)
    # minimum norm: any other r with G r = c is longer (a null-space component added)
    c = np.array([0.3, -0.2, 0.1])
    null = np.linalg.svd(G)[2][-1]
    assert np.linalg.norm(P @ c) < np.linalg.norm(P @ c + 0.1 * null)


@pytest.mark.parametrize(
    "kwargs, field",
    [
        ({"axes": np.eye(3)[:, :2], "inertia": 1.0}, "axes"),
        ({"axes": 2 * np.eye(3), "inertia": 1.0}, "axes"),
        ({"axes": np.array([[1, 1, 0, 0], [0, 0, 1, 1], [0, 0, 0, 0.0]]), "inertia": 1.0}, "axes"),
        ({"axes": PYRAMID, "inertia": 0.0}, "inertia"),
        ({"axes": PYRAMID, "inertia": [1.0, 1.0]}, "inertia"),
        ({"axes": PYRAMID, "inertia": 1.0, "max_speed": -1.0}, "max_speed"),
        ({"axes": PYRAMID, "inertia": 1.0, "viscous": -1.0}, "viscous"),
    ],
    ids=["two_wheels", "not_unit", "rank_2", "no_inertia", "inertia_count", "speed", "viscous"],
)
def test_bad_arrays_are_refused_naming_the_field(kwargs, field):
    with pytest.raises(FieldError) as info:
        ReactionWheelArray(**kwargs)
    assert info.value.field == field


def test_an_array_needs_a_three_axis_torque():
    from flexsat.cases.nps import nps
    from flexsat.dynamics.hub_appendage import HubAppendage  # noqa: F401  (a planar plant)

    with pytest.raises(FieldError) as info:
        WheelArrayPlant(nps().model(), "torque", ReactionWheelArray(PYRAMID, 0.05))
    assert info.value.field == "actuators[torque]"


def _momentum_drift(plant, x0, substeps, torque_scale):
    """max |H(t) − H(0)| over a 10 s run of piecewise-constant body-torque commands (no
    external torque: the wheels only), and |H(0)|."""
    arr = ReactionWheelArray(PYRAMID, 0.05 * torque_scale, viscous=1e-3 * torque_scale)
    values = np.tile(torque_scale * np.array([[0.2, -0.1, 0.05]]), (100, 1))
    values[50:] *= -1.5
    hw = Hardware(actuators={"torque": arr})
    config = SimConfig(10.0, 10.0, substeps=substeps, hardware=hw)
    run = simulate(
        plant, Playback(values, 0.1, "torque"), config, initial_state=x0, record_states=True
    )
    H = hw.plant_for(plant).momentum(run.dataset["state"].values[0])
    return np.abs(H - H[0]).max(), np.linalg.norm(H[0])


@pytest.mark.numerics
def test_total_momentum_is_conserved_to_the_integrators_error():
    """Rigid and flexible spacecraft, tumbling at ~0.1 rad/s while the wheels are driven: the
    total momentum C(β)ᵀ(Iω + h_w) (+ the elastic part) drifts only by the fourth-order
    exponential integrator's error: halving the step divides the drift by ~2⁴ = 16 (measured
    16.6 rigid, 16.1 flexible), and at 8 substeps per 0.1 s it is below 1e-11 of |H| (rigid,
    measured 1.1e-13) and 1e-10 (flexible, with modes up to 2.3 Hz: measured 7e-12)."""
    rigid = RigidSpacecraft(J_BODY)
    x0 = rigid.state([1.0, 0.0, 0.0, 0.0], [0.05, 0.1, -0.05])
    d4, h = _momentum_drift(rigid, x0, 4, 1.0)
    d8, _ = _momentum_drift(rigid, x0, 8, 1.0)
    assert 12 < d4 / d8 < 20
    assert d8 < 1e-11 * h
    flexible = FlexibleSpacecraft(coupled_modal(damping=0.02))
    x0 = flexible.initial_state(1)[0]
    x0[4:7] = [0.05, 0.1, -0.05]
    d4, h = _momentum_drift(flexible, x0, 4, 10.0)
    d8, _ = _momentum_drift(flexible, x0, 8, 10.0)
    assert 12 < d4 / d8 < 20
    assert d8 < 1e-10 * h


def _slew(hardware, degrees=30.0):
    """A rest-to-rest slew about body z of a rigid spacecraft with principal axes (the body
    axes), a quaternion PD law at 10 Hz, 40 s."""
    plant = RigidSpacecraft(np.diag([10.0, 12.0, 8.0]))
    target = att.principal_rotation_to_quaternion(np.array([0.0, 0.0, 1.0]), np.radians(degrees))
    law = QuaternionPD(Kp=4.0, Kd=8.0, beta_target=target)
    config = SimConfig(40.0, 10.0, substeps=8, hardware=hardware)
    return simulate(plant, law, config).dataset


def test_a_pyramid_slew_is_the_ideal_torque_slew_when_no_limit_binds():
    """A 30° rest-to-rest slew about the principal axis z: the law's torque stays along z,
    the wheels' momentum h_w = −∫ G G⁺ c dt = −∫ c dt along z too, so the gyroscopic torque
    ω × h_w is zero and the body moves as under the ideal torque. The two runs differ by
    their integrators only (RKMK4 and the exponential RK4, both fourth order at 12.5 ms:
    measured 6e-15); 1e-9 allowed."""
    ideal = _slew(None)
    wheels = _slew(Hardware(actuators={"torque": ReactionWheelArray(PYRAMID, 0.05)}))
    np.testing.assert_allclose(wheels["attitude"].values, ideal["attitude"].values, atol=1e-9)
    # the law's commanded torque on the body is delivered: G r = c
    c = ideal["torque"].values[0]
    r = wheels["torque_wheels"].values[0]
    np.testing.assert_allclose(r @ PYRAMID.T, c, atol=1e-9)
    # each wheel's speed relative to the body: J_w Ω_rel = −∫ r dt − J_w gᵀω (its reaction)
    assert np.abs(wheels["torque_wheel_speed"].values).max() > 1.0


def test_each_wheels_speed_limit_is_respected():
    """A 90° slew with wheels limited to 5 rad/s: a wheel at its limit gets no command that
    would speed it up, so |Ω_rel,i| exceeds the limit by at most one control period's
    acceleration, Δt max|r_i| / J_w + the body's rate change gᵀΔω (bounded with it); the limit
    binds (a wheel reaches it) and the slew is slower than without it."""
    limit, Jw, dt = 5.0, 0.05, 0.1
    free = _slew(Hardware(actuators={"torque": ReactionWheelArray(PYRAMID, Jw)}), degrees=90.0)
    capped = _slew(
        Hardware(actuators={"torque": ReactionWheelArray(PYRAMID, Jw, max_speed=limit)}),
        degrees=90.0,
    )
    speeds = capped["torque_wheel_speed"].values[0]
    r_max = np.abs(capped["torque_wheels"].values[0]).max()
    w_dot = np.abs(np.diff(capped["rate"].values[0], axis=0)).max()
    assert np.abs(free["torque_wheel_speed"].values).max() > 3 * limit  # it would bind
    assert np.abs(speeds).max() <= limit + dt * r_max / Jw + w_dot + 1e-9
    assert np.abs(speeds).max() >= limit  # it binds
    # the slew is slower: the error angle at 10 s, 2 arccos |β · β_target|, is larger
    target = att.principal_rotation_to_quaternion(np.array([0.0, 0.0, 1.0]), np.radians(90))

    def error(ds):
        return 2 * np.arccos(min(1.0, abs(float(ds["attitude"].values[0, 100] @ target))))

    assert error(capped) > error(free)
