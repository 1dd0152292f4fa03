"""The ``hardware:`` section and the cable spring of a maneuver scenario
(flexsat.scenarios.hardware_section): units at the boundary (Hz and rad/s, A/V and V/V, a
delay in seconds or samples), one ``field.path: rule`` per bad input, the run with the section
equal to the Python API's run with the same hardware, and the cable's steady state."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import yaml

from flexsat.cases.tamu import tamu_hardware
from flexsat.scenarios import (
    ScenarioError,
    default_scenario,
    load_scenario,
    prepare_scenario,
    run_scenario,
)
from flexsat.scenarios.hardware_section import HardwareSpec, describe_hardware
from flexsat.sim import simulate
from flexsat.sim.hardware import ReactionWheel

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def small(**changes) -> dict:
    """The default scenario (TAMU, Law I and Law II) with 3 modes and a 1 s run."""
    data = yaml.safe_load(default_scenario().yaml_text)
    data["model"]["n_modes"] = 3
    data["simulation"]["duration"] = "1 s"
    data.update(changes)
    return data


def load_problems(data: dict) -> list[str]:
    with pytest.raises(ScenarioError) as info:
        load_scenario(yaml.safe_dump(data))
    return [str(p) for p in info.value.problems]


def prepare_problems(data: dict) -> list[str]:
    with pytest.raises(ScenarioError) as info:
        prepare_scenario(load_scenario(yaml.safe_dump(data)))
    return [str(p) for p in info.value.problems]


# -- units ----------------------------------------------------------------------------------------
def test_frequencies_in_hz_or_rad_s_never_confused():
    two_pi = 2 * math.pi
    for corner, hz in (("10 Hz", 10.0), (f"{10 * two_pi!r} rad/s", 10.0), (10, 10.0)):
        spec = HardwareSpec(filters={"root_torque": {"corner": corner}})
        # to_si applies 2π between rad/s and Hz; a bare number is the field's unit, Hz
        assert spec.filters["root_torque"].corner == pytest.approx(hz, rel=1e-14)
    spec = HardwareSpec(amplifiers={"torque": {"bandwidth": "3141.592653589793 rad/s"}})
    assert spec.amplifiers["torque"].bandwidth == pytest.approx(500.0, rel=1e-14)
    spec = HardwareSpec(wheels={"torque": {"inertia": 1e-3, "max_speed": "3000 rpm"}})
    assert spec.wheels["torque"].max_speed == pytest.approx(100 * math.pi, rel=1e-14)


def test_gain_unit_follows_the_mode():
    current = HardwareSpec(amplifiers={"torque": {"gain": "1.2 A/V"}})
    assert current.amplifiers["torque"].gain == pytest.approx(1.2)
    wheel = {"inertia": 1e-3, "amplifier": {"mode": "voltage", "gain": "2 V/V"}}
    assert HardwareSpec(wheels={"torque": wheel}).wheels["torque"].amplifier.gain == 2.0
    bad = small(
        hardware={
            "wheels": {"torque": {**wheel, "amplifier": {"mode": "voltage", "gain": "2 A/V"}}}
        }
    )
    assert any(p.startswith("hardware.wheels.torque.amplifier.gain:") for p in load_problems(bad))


def test_a_delay_in_seconds_is_converted_to_samples_of_the_control_period():
    spec = HardwareSpec(delay=f"{1000 / 75!r} ms")  # one period at 75 Hz
    assert spec.build(1 / 75).delay == 1.0  # snapped: within 1e-9 of a whole sample
    assert HardwareSpec(delay="20 ms").build(1 / 75).delay == pytest.approx(1.5)
    assert HardwareSpec(delay_samples=2).build(1 / 75).delay == 2.0
    assert HardwareSpec(preset="ideal").build(0.01) is None
    assert HardwareSpec().build(0.01) is None


def test_the_tamu_preset_and_keys_beside_it():
    hw = HardwareSpec(preset="tamu").build(1 / 75)
    assert hw == tamu_hardware()  # the Python API's preset, field for field
    own = HardwareSpec(
        preset="tamu",
        filters={"root_torque": {"type": "bessel", "order": 4, "corner": "20 Hz"}},
        delay_samples=0,
    ).build(1 / 75)
    f = own.filters["root_torque"]
    assert (f.kind, f.order, f.corner) == ("bessel", 4, 20.0)
    assert own.delay == 0.0 and own.actuators == tamu_hardware().actuators
    wheel = HardwareSpec(preset="tamu", wheels={"torque": {"inertia": "2e-3 kg*m^2"}})
    assert isinstance(wheel.build(0.01).actuators["torque"], ReactionWheel)
    text = describe_hardware(hw)
    assert "10 Hz" in text and "12 A" in text and "delay 1 samples" in text
    assert describe_hardware(None) == "ideal (no hardware)"


# -- refusals by field path -----------------------------------------------------------------------
@pytest.mark.parametrize(
    "hardware, path",
    [
        ({"filters": {"root_torque": {"corner": "10 s"}}}, "hardware.filters.root_torque.corner"),
        ({"filters": {"root_torque": {"corner": -1}}}, "hardware.filters.root_torque.corner"),
        (
            {"filters": {"root_torque": {"corner": 10, "order": 11}}},
            "hardware.filters.root_torque.order",
        ),
        (
            {"filters": {"root_torque": {"corner": 10, "type": "cheby"}}},
            "hardware.filters.root_torque.type",
        ),
        ({"filters": {"root_torque": {"order": 2}}}, "hardware.filters.root_torque.corner"),
        (
            {"amplifiers": {"torque": {"current_limit": "12 V"}}},
            "hardware.amplifiers.torque.current_limit",
        ),
        ({"amplifiers": {"torque": {"mode": "voltage"}}}, "hardware.amplifiers.torque.mode"),
        ({"amplifiers": {"torque": {"gain": 0}}}, "hardware.amplifiers.torque.gain"),
        ({"wheels": {"torque": {"inertia": 0}}}, "hardware.wheels.torque.inertia"),
        (
            {"wheels": {"torque": {"inertia": 1e-3, "coulomb": -1}}},
            "hardware.wheels.torque.coulomb",
        ),
        (
            {"wheels": {"torque": {"inertia": 1e-3}}, "amplifiers": {"torque": {}}},
            "hardware.wheels.torque",
        ),
        ({"delay": "1 ms", "delay_samples": 1}, "hardware.delay"),
        ({"delay_samples": -1}, "hardware.delay_samples"),
        ({"delay": "2 Hz"}, "hardware.delay"),
        ({"preset": "ideal", "delay_samples": 1}, "hardware.preset"),
        ({"preset": "nasa"}, "hardware.preset"),
        ({"colour": 1}, "hardware.colour"),
    ],
)
def test_bad_hardware_is_refused_at_its_field(hardware, path):
    problems = load_problems(small(hardware=hardware))
    assert any(p.startswith(path + ":") for p in problems), problems


def test_bad_cable_is_refused_at_its_field():
    data = small()
    data["disturbances"]["cable"] = {"constant": "1 N"}
    assert any(p.startswith("disturbances.cable.constant:") for p in load_problems(data))
    data["disturbances"]["cable"] = {
        "profile": [{"angle": "1 deg", "torque": 0}, {"angle": "0 deg", "torque": 0}]
    }
    assert any(p.startswith("disturbances.cable.profile:") for p in load_problems(data))


def test_channels_the_plant_or_the_law_lacks_are_refused_before_any_run():
    data = small(hardware={"filters": {"tip_deflection": {"corner": "10 Hz"}}})
    problems = prepare_problems(data)
    # both runs' laws read theta, theta_dot, root_torque only
    assert any(
        p.startswith("hardware.filters.tip_deflection: the law does not read") for p in problems
    )
    data = small()
    data["runs"][1]["hardware"] = {"filters": {"gyro": {"corner": "10 Hz"}}}
    problems = prepare_problems(data)
    assert problems[0].startswith("runs['Law II'].hardware.filters.gyro: the HubAppendage")
    data["runs"][1]["hardware"] = {"wheels": {"torque": {"inertia": 1e-3, "rate_output": "x"}}}
    problems = prepare_problems(data)
    assert problems[0].startswith("runs['Law II'].hardware.wheels.torque.rate_output:")


# -- runs -----------------------------------------------------------------------------------------
def test_a_run_with_the_section_is_the_python_api_run_with_that_hardware():
    """examples/tamu_hardware.yaml cut to 3 modes and 2 s: the ideal run is the plan's run
    without hardware and the hardware run is simulate(...) with tamu_hardware(), bit for bit;
    the report names each run's hardware."""
    data = yaml.safe_load((EXAMPLES / "tamu_hardware.yaml").read_text())
    data["model"]["n_modes"] = 3
    data["simulation"]["duration"] = "2 s"
    scenario = load_scenario(yaml.safe_dump(data))
    result = run_scenario(scenario)
    plan = prepare_scenario(scenario)
    ideal, hw = plan.controllers
    assert plan.run_config(ideal).hardware is None
    direct = simulate(
        plan.model, plan.controllers[hw], replace(plan.config, hardware=tamu_hardware())
    )
    ds = result.dataset()
    for name in ("theta", "torque", "root_torque"):
        np.testing.assert_array_equal(ds[name].sel(run=hw).values, direct.dataset[name].values[0])
    alone = simulate(plan.model, plan.controllers[ideal], plan.config)
    np.testing.assert_array_equal(
        ds["theta"].sel(run=ideal).values, alone.dataset["theta"].values[0]
    )
    # the delay shows: the hardware run's applied torque differs from the ideal's
    assert not np.array_equal(ds["torque"].sel(run=hw).values, ds["torque"].sel(run=ideal).values)
    assert "computation delay 1 samples" in ds.attrs["hardware"]
    html = result.sections(ds, [])
    assert "<h2>Hardware</h2>" in html and "ideal (no hardware)" in html


def _cable_run(cable: dict) -> tuple[float, float, float]:
    """(final θ, kp, target) of the TAMU hub (3 modes, no friction, noise or saturation)
    held at 0 by a PD law (kp = 16 N m/rad, kd = 8 N m s/rad) with ``cable`` on the hub."""
    data = small()
    data["simulation"] = {
        "duration": "90 s",
        "control_rate": "75 Hz",
        "integration_step": "3.34 ms",
        "seed": 0,
    }
    data["sensors"] = {}
    data["actuator"] = {}
    data["disturbances"] = {"cable": cable}
    data["maneuver"] = {"angle": "0 deg"}  # held at rest: the cable alone moves the hub
    data["runs"] = [{"label": "PD", "law": "pd", "gains": {"kp": 16, "kd": 8}}]
    scenario = load_scenario(yaml.safe_dump(data))
    plan = prepare_scenario(scenario)
    theta = run_scenario(scenario).dataset()["theta"].values[0]
    return float(theta[-1]), float(plan.controllers["PD"].kp), scenario.maneuver.angle


def test_cable_steady_state_is_td_over_k():
    """Eq. 23, θ_ss − θ_t = T_D / k_p; a linear spring k about 0: θ_ss = (k_p θ_t + T_D) /
    (k_p + k); a tabulated profile of that line gives the same run. At equilibrium the net
    torque on the whole (hub and appendages) vanishes, so the appendages do not enter. The
    tolerance is the transient left after 90 s: the slowest closed-loop pole is the rigid
    one, s² + (kd/I) s + kp/I with I = 15.6 kg m², ζω_n = kd / 2I = 0.256 /s, so the offset's
    own step response is within e^{−0.256 · 90} ≈ 1e-10 of its final value (rel 1e-6)."""
    td, k = 1e-3, 0.05
    final, kp, target = _cable_run({"constant": f"{td} N*m"})
    assert final - target == pytest.approx(td / kp, rel=1e-6)
    final, kp, target = _cable_run({"constant": f"{td} N*m", "stiffness": f"{k} N*m/rad"})
    expected = (kp * target + td) / (kp + k)
    assert final == pytest.approx(expected, rel=1e-6)
    angles = [-1.0, 1.0]  # rad: the line τ = T_D − k θ over the slew, held outside
    profile = [{"angle": a, "torque": td - k * a} for a in angles]
    tabulated, _, _ = _cable_run({"profile": profile})
    assert tabulated == pytest.approx(expected, rel=1e-6)


# -- the simulation kind --------------------------------------------------------------------------
def _draper(**changes) -> dict:
    """examples/draper_rpl_lqr.yaml (the Draper/RPL hub, a linear structure plant) cut to 2 s."""
    data = yaml.safe_load((EXAMPLES / "draper_rpl_lqr.yaml").read_text())
    data["simulation"]["duration"] = "2 s"
    data.update(changes)
    return data


def test_the_simulation_kind_runs_its_hardware_and_cable_as_the_api_does():
    """A document-level amplifier and delay and a cable on the hub torquer: each run equals
    simulate(...) with the same Hardware and ChannelDisturbance, bit for bit."""
    from flexsat.scenarios.simulation import build_plant
    from flexsat.sim import SimConfig
    from flexsat.sim.channels import ChannelActuator, ChannelDisturbance
    from flexsat.sim.disturbances import CableSpring
    from flexsat.sim.hardware import Amplifier, Hardware

    data = _draper(
        hardware={
            "delay_samples": 1,
            "amplifiers": {"u1_hub": {"current_limit": "1 A", "torque_constant": "2 N*m/A"}},
        },
        disturbances={"u1_hub": {"cable": {"constant": "0.01 N*m", "stiffness": 0.2}}},
    )
    scenario = load_scenario(yaml.safe_dump(data))
    result = run_scenario(scenario)
    ds = result.dataset()
    plant = build_plant(scenario)
    config = SimConfig(
        2.0,
        50.0,
        channel_actuators={"u1_hub": ChannelActuator(saturation=5.0)},
        channel_disturbances={
            "u1_hub": ChannelDisturbance(
                force=CableSpring(0.01, 0.2), force_output="theta", force_name="cable"
            )
        },
        hardware=Hardware(
            actuators={"u1_hub": Amplifier(current_limit=1.0, torque_constant=2.0)}, delay=1
        ),
    )
    for label, law in result.laws.items():
        direct = simulate(plant, law, config, initial_state=plant.state_from(**scenario.initial))
        for name in ("theta", "u1_hub", "cable_u1_hub"):
            np.testing.assert_array_equal(
                ds[name].sel(run=label).values, direct.dataset[name].values[0]
            )
        # the amplifier's limit K_t · 1 A = 2 N m binds below the actuator's 5 N m
        assert np.abs(ds["u1_hub"].sel(run=label).values).max() <= 2.0 + 1e-12
    assert "computation delay 1 samples" in ds.attrs["hardware"]


def test_the_simulation_kind_refuses_hardware_by_field_path():
    data = _draper(hardware={"filters": {"nope": {"corner": 10}}})
    problems = prepare_or_run_problems(data)
    assert problems == [
        "hardware.filters.nope: the StructuralPlant plant has no output 'nope' (its outputs: "
        "theta, rot_tips_1_3, rot_tips_2_4, theta_dot, rot_tips_1_3_dot, rot_tips_2_4_dot, state)"
    ]  # once, though both runs have it
    data = _draper()
    data["runs"][1]["hardware"] = {"amplifiers": {"u9": {}}}
    problems = prepare_or_run_problems(data)
    assert problems[0].startswith("runs['LQR, cheap hub torquer'].hardware.amplifiers.u9: ")
    data = _draper(disturbances={"u1_hub": {"cable": {"constant": "1 s"}}})
    assert load_problems(data)[0].startswith("disturbances.u1_hub.cable.constant:")
    rigid = yaml.safe_load((EXAMPLES / "eps_rigid_gibbs_slew.yaml").read_text())
    rigid["hardware"] = {"delay_samples": 1}
    problems = prepare_or_run_problems(rigid)
    # the rigid spacecraft keeps its own RKMK4 step: no hardware states on it
    assert problems[0].startswith("hardware: RigidSpacecraft: hardware needs a shared plant")


def prepare_or_run_problems(data: dict) -> list[str]:
    """The problems of a simulation document, found before its first run."""
    with pytest.raises(ScenarioError) as info:
        run_scenario(load_scenario(yaml.safe_dump(data)))
    return [str(p) for p in info.value.problems]


def test_a_wheel_array_on_the_rigid_eps_is_the_api_run():
    """examples/eps_rigid_gibbs_slew.yaml cut to 5 s with a 4-wheel pyramid on its torque
    (the channel actuator removed: the wheels' limits replace it): each run equals simulate(...)
    with the same ReactionWheelArray, to round-off; a wheel array with an actuator on its
    channel, or on a 1-wide channel, is refused at its field."""
    from flexsat.scenarios.simulation import build_plant
    from flexsat.sim import SimConfig
    from flexsat.sim.channels import ChannelSensor
    from flexsat.sim.hardware import Hardware
    from flexsat.sim.wheel_array import ReactionWheelArray, pyramid_axes

    G = pyramid_axes(math.acos(1 / math.sqrt(3)))
    data = yaml.safe_load((EXAMPLES / "eps_rigid_gibbs_slew.yaml").read_text())
    data["simulation"]["duration"] = "5 s"
    arrays = {"torque": {"axes": G.T.tolist(), "inertia": "2 kg*m^2", "max_speed": "6000 rpm"}}
    data["hardware"] = {"wheel_arrays": arrays}
    assert prepare_or_run_problems(data)[0].startswith(
        "hardware.wheel_arrays.torque: a wheel array's channel takes no actuators.torque"
    )
    del data["actuators"]
    scenario = load_scenario(yaml.safe_dump(data))
    result = run_scenario(scenario)
    ds = result.dataset()
    plant = build_plant(scenario)
    array = ReactionWheelArray(G, 2.0, max_speed=200 * math.pi)
    config = SimConfig(
        5.0,
        10.0,
        channel_sensors={"rate": ChannelSensor(noise=1e-5)},
        hardware=Hardware(actuators={"torque": array}),
    )
    x0 = plant.state_from(**scenario.initial)
    for label, law in result.laws.items():
        direct = simulate(plant, law, config, initial_state=x0)
        for name in ("attitude", "torque_wheels", "torque_wheel_speed"):
            # to round-off: an element of the wheel commands was measured 1 ulp apart
            np.testing.assert_allclose(
                ds[name].sel(run=label).values, direct.dataset[name].values[0], rtol=1e-12
            )
    assert "4 reaction wheels" in ds.attrs["hardware"]
    bad = small(hardware={"wheel_arrays": arrays})
    assert prepare_problems(bad)[0].startswith(
        "hardware.wheel_arrays.torque: a wheel array needs a torque 3 wide"
    )
    arrays["torque"]["axes"] = [[1, 0, 0], [0, 1, 0], [1, 0]]
    assert load_problems(bad)[0].startswith("hardware.wheel_arrays.torque.axes:")
