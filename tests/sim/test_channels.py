"""Claims of the per-channel sensors, actuators and disturbances (flexsat.sim.channels): each
applies its documented formula in the channel's unit, converted to SI when bound; the planar
presets land on the hub plant's channels theta, theta_dot, root_torque and torque; a piece on a
channel the plant does not have is refused naming it."""

from dataclasses import replace

import numpy as np
import pytest

from flexsat.control.base import Controller
from flexsat.dynamics.plant import Channel, Plant
from flexsat.dynamics.rigid_spacecraft import RigidSpacecraft
from flexsat.sim import (
    BearingFriction,
    ChannelActuator,
    ChannelDisturbance,
    ChannelSensor,
    Impulses,
    RandomTorque,
    Sensors,
    SimConfig,
    TorqueActuator,
    simulate,
)
from flexsat.sim.channels import noise_column, noise_columns, resolve_channels
from flexsat.units import ureg


class Cart(Plant):
    """A unit mass pushed by a force: x = [p, v]; outputs position and the 3-wide [p, v, p+v]
    (a vector channel with a noise stream of three columns)."""

    inputs = (Channel("force", "N"),)
    outputs = (Channel("position", "m"), Channel("trio", "m", size=3))
    recorded = ("position",)
    noise_channels = ("trio", "position", "force")
    nx = 2

    def linear_part(self):
        return np.array([[0.0, 1.0], [0.0, 0.0]]), np.array([[0.0], [1.0]])

    def output_matrices(self, name):
        C = {
            "position": np.array([[1.0, 0.0]]),
            "trio": np.array([[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]),
        }[name]
        return C, np.zeros((len(C), 1)), None


@pytest.fixture(scope="module")
def hub(tamu_model):
    return tamu_model


# -- ChannelSensor ----------------------------------------------------------------------------
def test_sensor_quantizes_to_q_round_v_over_q():
    """y = q·round(v/q): every measurement is an integer multiple of q within q/2 of v (the
    round-off of q·k is ~eps·|y|, far below q/2)."""
    q = 1e-3
    s = ChannelSensor(quantum=q).bind(Channel("position", "m"))
    v = np.linspace(-0.0123, 0.0457, 1001)
    y = s.measure(v, None)
    np.testing.assert_array_equal(y, q * np.round(v / q))
    assert np.abs(y - v).max() <= q / 2 * (1 + 1e-12)
    assert len(np.unique(np.round(y / q))) == len(np.unique(y))


def test_sensor_adds_its_bias_and_scales_the_given_standard_normals():
    """y = v + bias + noise·n with n the stream's standard normals: exact (no quantum, no
    range)."""
    rng = np.random.default_rng(1)
    v, n = rng.normal(size=50), rng.standard_normal(50)
    s = ChannelSensor(noise=0.2, bias=-0.05).bind(Channel("position", "m"))
    np.testing.assert_array_equal(s.measure(v, n), v + -0.05 + 0.2 * n)


def test_a_zero_quantum_element_reads_the_value_itself():
    """A quantum per case with a zero (a case without an encoder): that case's reading is the
    value itself, the others' the quantised one (as the compiled loop's q > 0 test), not NaN."""
    s = ChannelSensor(quantum=np.array([0.25, 0.0])).bind(Channel("position", "m"))
    v = np.array([0.3, 0.3])
    assert np.array_equal(s.measure(v, None), [0.25, 0.3])


def test_sensor_order_is_bias_and_noise_then_quantum_then_range():
    """y = sat(Q(v + bias + noise·n)): the quantum acts on the biased noisy value and the range
    clips the quantized one."""
    s = ChannelSensor(noise=0.1, bias=0.3, quantum=0.25, range=1.0).bind(Channel("position", "m"))
    v = np.array([0.0, 0.1, 0.4, 2.0, -3.0])
    n = np.array([0.0, 1.0, -1.0, 0.0, 0.0])
    expected = np.clip(0.25 * np.round((v + 0.3 + 0.1 * n) / 0.25), -1.0, 1.0)
    np.testing.assert_array_equal(s.measure(v, n), expected)
    np.testing.assert_array_equal(s.measure(v, n), [0.25, 0.5, 0.5, 1.0, -1.0])


def test_sensor_range_saturates_symmetrically():
    s = ChannelSensor(range="5 mm").bind(Channel("position", "m"))
    np.testing.assert_array_equal(
        s.measure(np.array([-1.0, -0.004, 0.0, 0.004, 1.0]), None),
        [-0.005, -0.004, 0.0, 0.004, 0.005],
    )


def test_an_ideal_sensor_returns_the_truth():
    v = np.array([1.5, -2.25])
    np.testing.assert_array_equal(
        ChannelSensor().bind(Channel("position", "m")).measure(v, None), v
    )


def test_binding_converts_unit_strings_and_quantities_to_the_channel_unit():
    """An encoder of 0.01 deg on a rad channel: quantum π/18000 rad (to rounding, 1 ulp)."""
    s = ChannelSensor(quantum="0.01 deg", bias=ureg.Quantity(1.0, "mrad"), range="90 deg").bind(
        Channel("theta", "rad")
    )
    np.testing.assert_allclose(s.quantum, np.pi / 18000, rtol=2e-16)
    np.testing.assert_allclose(s.bias, 1e-3, rtol=2e-16)
    np.testing.assert_allclose(s.range, np.pi / 2, rtol=2e-16)
    gyro = ChannelSensor(noise="1 deg/s").bind(Channel("theta_dot", "rad/s"))
    np.testing.assert_allclose(gyro.noise, np.pi / 180, rtol=2e-16)
    # a plain number is already SI of the channel
    assert ChannelSensor(quantum=1e-4).bind(Channel("theta", "rad")).quantum == 1e-4


@pytest.mark.parametrize(
    "sensor, message",
    [
        (ChannelSensor(quantum="1 m"), r"^sensors\[theta\]\.quantum: incompatible units"),
        (ChannelSensor(noise="1 N"), r"^sensors\[theta\]\.noise: incompatible units"),
        (ChannelSensor(noise=-1.0), r"^sensors\[theta\]\.noise: must be finite and >= 0"),
        (ChannelSensor(quantum=np.nan), r"^sensors\[theta\]\.quantum: must be finite"),
        (ChannelSensor(range=0.0), r"^sensors\[theta\]\.range: must be > 0 \(inf for none\)"),
        (ChannelSensor(bias=np.inf), r"^sensors\[theta\]\.bias: must be finite"),
    ],
)
def test_binding_refuses_wrong_dimensions_and_values_naming_the_field(sensor, message):
    with pytest.raises(ValueError, match=message):
        sensor.bind(Channel("theta", "rad"))


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(window=0), r"^window: must be a positive integer"),
        (dict(order=0), r"^order: must be a positive integer"),
        (dict(window=2, order=2), r"window >= order \+ 1"),
    ],
)
def test_derivative_filter_settings_are_checked_when_built(kwargs, message):
    with pytest.raises(ValueError, match=message):
        ChannelSensor(derivative_of="theta", **kwargs)


def test_derivative_of_an_unknown_or_derived_channel_is_refused(hub):
    with pytest.raises(
        ValueError,
        match=r"^encoder: HubAppendage has no output channel "
        r"'encoder'",
    ):
        resolve_channels(
            hub,
            SimConfig(
                duration=1.0, channel_sensors={"theta_dot": ChannelSensor(derivative_of="encoder")}
            ),
        )
    with pytest.raises(
        ValueError,
        match=r"^root_torque: derivative_of 'theta_dot' is itself a "
        r"derivative",
    ):
        resolve_channels(
            hub,
            SimConfig(
                duration=1.0,
                channel_sensors={
                    "theta_dot": ChannelSensor(derivative_of="theta"),
                    "root_torque": ChannelSensor(derivative_of="theta_dot"),
                },
            ),
        )


# -- ChannelActuator --------------------------------------------------------------------------
def test_actuator_is_scale_times_saturated_rate_limited_command_plus_bias():
    """u = scale·sat(rate_limit(c)) + bias; the rate limit allows rate_limit·dt per control
    period from the last limited command and the scale acts after the saturation (a 2x scale
    on a 0.5 saturation applies 1.0). Exact: every number is a dyadic fraction."""
    dt = 0.25
    a = ChannelActuator(saturation=0.5, rate_limit=2.0, scale=2.0, bias=0.125).bind(
        Channel("force", "N")
    )
    u, c = a.apply(np.array([0.25, 10.0, -10.0]), None, dt)  # first sample: no rate limit
    np.testing.assert_array_equal(c, [0.25, 0.5, -0.5])
    np.testing.assert_array_equal(u, [0.625, 1.125, -0.875])
    # next period: the change is at most 2.0 N/s × 0.25 s = 0.5 N from the last limited command
    u, c = a.apply(np.array([-10.0, -10.0, 10.0]), c, dt)
    np.testing.assert_array_equal(c, [-0.25, 0.0, 0.0])
    np.testing.assert_array_equal(u, 2.0 * c + 0.125)


def test_rate_limit_ramps_a_step_over_the_control_periods():
    """A step of 1 N under 3 N/s at 30 Hz: 0.1 N per period, reached after 10 periods."""
    dt = 1 / 30
    a = ChannelActuator(rate_limit="3 N/s").bind(Channel("force", "N"))
    c, out = None, []
    u, c = a.apply(np.zeros(1), c, dt)
    for _ in range(12):
        u, c = a.apply(np.ones(1), c, dt)
        out.append(u[0])
    np.testing.assert_allclose(out[:10], 0.1 * np.arange(1, 11), rtol=0, atol=1e-15)
    assert out[10:] == [1.0, 1.0]


def test_actuator_saturation_per_case_and_units():
    a = ChannelActuator(saturation=np.array([1.0, 2.0]), bias="-100 mN").bind(Channel("force", "N"))
    u, _ = a.apply(np.array([5.0, -5.0]), None, 0.1)
    np.testing.assert_allclose(u, [0.9, -2.1], rtol=0, atol=1e-15)


@pytest.mark.parametrize(
    "actuator, message",
    [
        (ChannelActuator(rate_limit="3 N"), r"^actuators\[force\]\.rate_limit: incompatible units"),
        (ChannelActuator(saturation="1 m"), r"^actuators\[force\]\.saturation: incompatible units"),
        (ChannelActuator(saturation=0.0), r"^actuators\[force\]\.saturation: must be > 0"),
        (ChannelActuator(scale=0.0), r"^actuators\[force\]\.scale: must be > 0"),
        (ChannelActuator(rate_limit=-1.0), r"^actuators\[force\]\.rate_limit: must be >= 0"),
    ],
)
def test_bad_actuators_are_refused_naming_the_field(actuator, message):
    with pytest.raises(ValueError, match=message):
        actuator.bind(Channel("force", "N"))


# -- ChannelDisturbance -----------------------------------------------------------------------
def test_impulses_land_on_the_first_sample_at_or_after_their_time_and_add_up():
    """dt = 1/75 s: 0.01 s (0.75 periods) lands on sample 1, as does 1/75 s itself (not on 2
    from the round-off of t/dt); 0.02 s on 2; sample 1 sums its two impulses; one at or after
    the last sample is dropped."""
    dt = 1 / 75
    times = (0.0, 0.01, 3 * dt, dt, 0.02, 10.0)  # 3·(1/75)/(1/75) = 3.0000000000000004
    d = ChannelDisturbance(impulse_times=times, impulses=(1.0, 2.0, 4.0, 8.0, 16.0, 32.0))
    got = d.bind(Channel("torque", "N*m")).impulses_at_samples(75, dt)
    assert got == {0: 1.0, 1: 10.0, 2: 16.0, 3: 4.0}


def test_disturbance_binding_converts_units():
    d = ChannelDisturbance(
        random="10 mN*m",
        impulse_times=("20 ms", 0.5),
        impulses=("1 N*m*s", ureg.Quantity(2.0, "mN*m*s")),
    ).bind(Channel("torque", "N*m"))
    np.testing.assert_allclose(d.random, 0.01, rtol=2e-16)
    np.testing.assert_allclose(d.impulse_times, (0.02, 0.5), rtol=2e-16)
    np.testing.assert_allclose(d.impulses, (1.0, 0.002), rtol=2e-16)
    assert d.active and not ChannelDisturbance().bind(Channel("torque", "N*m")).active


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (
            dict(impulse_times=(0.0,), impulses=("1 N*m",)),
            r"^disturbances\[torque\]\.impulses: incompatible units",
        ),
        (
            dict(impulse_times=(0.0, 1.0), impulses=(1.0,)),
            r"^disturbances\[torque\]\.impulses: give one number for each of the 2 impulse times",
        ),
        (
            dict(impulse_times=(-1.0,), impulses=(1.0,)),
            r"^disturbances\[torque\]\.impulse_times: must be finite and >= 0",
        ),
        (dict(random="1 N"), r"^disturbances\[torque\]\.random: incompatible units"),
    ],
)
def test_bad_disturbances_are_refused_naming_the_field(kwargs, message):
    with pytest.raises(ValueError, match=message):
        ChannelDisturbance(**kwargs).bind(Channel("torque", "N*m"))


def test_a_force_needs_its_driving_output_and_only_with_a_force():
    with pytest.raises(ValueError, match=r"^force_output"):
        ChannelDisturbance(force=BearingFriction(1.0))
    with pytest.raises(ValueError, match=r"^force_output"):
        ChannelDisturbance(force_output="theta_dot")
    with pytest.raises(ValueError, match=r"^force: must be callable"):
        ChannelDisturbance(force=3.0, force_output="theta_dot")


def test_random_disturbance_has_its_standard_deviation(hub):
    """RandomTorque(0.05 N m) on the hub: the recorded disturbance over 1501 samples has
    σ = 0.05 N m within 4 standard errors of a sample σ (1/√(2n) = 1.8 %: 7.3 %) and is held
    (the disturbance history is the drawn value times σ, zero mean within 4σ/√n)."""
    from flexsat.control import PD
    from flexsat.sim import simulate

    cfg = SimConfig(duration=20.0, random_torque=RandomTorque("50 mN*m"))
    w = simulate(hub, PD(0.0, 0.0), cfg).dataset.disturbance_torque.values[0]
    n = w.size
    assert abs(w.std() / 0.05 - 1) < 4 / np.sqrt(2 * n)
    assert abs(w.mean()) < 4 * 0.05 / np.sqrt(n)


# -- planar presets on the hub plant ----------------------------------------------------------
def test_an_ideal_config_binds_nothing(hub):
    assert resolve_channels(hub, SimConfig(duration=1.0)) == ({}, {}, {})


def test_planar_presets_map_onto_the_hub_channels(hub):
    friction = BearingFriction("20 ozf*in", "0.001 ozf*in*s/rad")
    cfg = SimConfig(
        duration=1.0,
        sensors=Sensors(
            encoder_resolution="0.01 deg",
            rate="gyro",
            gyro_noise="0.1 deg/s",
            strain_noise="1 mN*m",
        ),
        actuator=TorqueActuator(saturation="400 ozf*in", torque_constant_ratio=0.9),
        friction=friction,
        random_torque=RandomTorque(0.02),
        impulses=Impulses((0.1, 0.3), (0.5, -0.25)),
    )
    sensors, actuators, disturbances = resolve_channels(hub, cfg)
    assert set(sensors) == {"theta", "theta_dot", "root_torque"}
    np.testing.assert_allclose(sensors["theta"].quantum, np.radians(0.01), rtol=2e-16)
    np.testing.assert_allclose(sensors["theta_dot"].noise, np.radians(0.1), rtol=2e-16)
    np.testing.assert_allclose(sensors["root_torque"].noise, 1e-3, rtol=2e-16)
    a = actuators["torque"]
    # 1 ozf·in = 0.028349523125 kg × 9.80665 m/s² × 0.0254 m (exact definitions)
    np.testing.assert_allclose(a.saturation, 400 * 0.028349523125 * 9.80665 * 0.0254, rtol=1e-15)
    assert a.scale == 0.9 and a.rate_limit == np.inf and a.bias == 0.0
    d = disturbances["torque"]
    assert d.random == 0.02 and d.impulse_times == (0.1, 0.3) and d.impulses == (0.5, -0.25)
    assert d.force is cfg.friction and d.force_output == "theta_dot"


def test_rate_from_the_least_squares_filter_is_a_derivative_sensor(hub):
    cfg = SimConfig(duration=1.0, sensors=Sensors(rate="ls_filter", rate_window=5, rate_order=2))
    sensors, _, _ = resolve_channels(hub, cfg)
    s = sensors["theta_dot"]
    assert (s.derivative_of, s.window, s.order) == ("theta", 5, 2)


def test_a_channel_piece_overrides_the_preset_on_its_channel(hub):
    cfg = SimConfig(
        duration=1.0,
        sensors=Sensors(encoder_resolution="0.01 deg"),
        channel_sensors={"theta": ChannelSensor(quantum="0.1 deg", bias="1 deg")},
    )
    s = resolve_channels(hub, cfg)[0]["theta"]
    np.testing.assert_allclose([s.quantum, s.bias], np.radians([0.1, 1.0]), rtol=2e-16)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (
            dict(channel_sensors={"pitch": ChannelSensor()}),
            r"^pitch: HubAppendage has no output channel 'pitch'",
        ),
        (
            dict(channel_actuators={"theta": ChannelActuator()}),
            r"^theta: HubAppendage has no input channel 'theta' \(its input channels: torque\)",
        ),
        (
            dict(channel_disturbances={"wheel": ChannelDisturbance(random=1.0)}),
            r"^wheel: HubAppendage has no input channel 'wheel'",
        ),
        (
            dict(
                channel_disturbances={
                    "torque": ChannelDisturbance(force=BearingFriction(1.0), force_output="speed")
                }
            ),
            r"^speed: HubAppendage has no output channel 'speed'",
        ),
        (
            dict(channel_sensors={"theta": ChannelSensor(noise=1e-3)}),
            r"^theta: its sensor noise needs a noise stream, but HubAppendage\.noise_channels "
            r"\(theta_dot, root_torque, torque\) has none for it",
        ),
    ],
)
def test_a_piece_on_a_channel_the_plant_lacks_is_refused_naming_it(hub, kwargs, message):
    with pytest.raises(ValueError, match=message):
        resolve_channels(hub, SimConfig(duration=1.0, **kwargs))


@pytest.mark.parametrize(
    "kwargs, where",
    [
        (dict(random_torque=RandomTorque(1.0)), r"config\.friction, random_torque, impulses"),
        (dict(actuator=TorqueActuator(saturation=1.0)), r"config\.actuator"),
        (dict(sensors=Sensors(encoder_resolution=1e-3)), r"config\.sensors"),
    ],
)
def test_a_planar_preset_on_another_plant_names_the_preset(kwargs, where):
    channel = {"random_torque": "torque", "actuator": "torque", "sensors": "theta"}[
        next(iter(kwargs))
    ]
    with pytest.raises(
        ValueError,
        match=rf"^{channel}: Cart has no .* channel '{channel}'.*"
        rf"set by the planar preset {where}$",
    ):
        resolve_channels(Cart(), SimConfig(duration=1.0, **kwargs))


# -- noise streams ----------------------------------------------------------------------------
def test_noise_columns_follow_the_plants_noise_channels(hub):
    """One column per scalar channel and ``size`` columns per vector channel, in the order of
    ``plant.noise_channels`` (not the order of the outputs)."""
    assert noise_columns(hub) == {
        "theta_dot": slice(0, 1),
        "root_torque": slice(1, 2),
        "torque": slice(2, 3),
    }
    assert hub.noise_channels == ("theta_dot", "root_torque", "torque")
    columns = noise_columns(Cart())
    assert columns == {"trio": slice(0, 3), "position": slice(3, 4), "force": slice(4, 5)}
    assert noise_column(columns, "position", "its sensor noise", Cart()) == 3
    assert noise_column(columns, "trio", "its sensor noise", Cart()) == slice(0, 3)


def test_default_noise_channels_are_every_output_then_every_input():
    # the protocol's property instead of Cart's explicit order
    p = type("Plain", (Cart,), {"noise_channels": Plant.noise_channels})()
    assert p.noise_channels == ("position", "trio", "force")
    assert noise_columns(p)["force"] == slice(4, 5)


def test_a_noise_channel_naming_no_channel_is_refused():
    p = Cart()
    p.noise_channels = ("position", "gyro")
    with pytest.raises(ValueError, match=r"^gyro: noise_channels names no channel of Cart"):
        noise_columns(p)


class _TorqueFree(Controller):
    """Zero torque on a three-axis plant."""

    reads = ("rate",)
    writes = ("torque",)
    target = 0.0

    def __call__(self, t, y, state):
        return np.zeros(np.shape(y["rate"])), state


def test_a_channel_named_without_a_width_takes_it_from_the_plant():
    """The rigid spacecraft's ``torque`` is 3 values wide: pieces given by its name are read per
    axis (issue 20; before, a piece was one value wide: a scalar impulse hit all three axes and
    three values were taken as three cases or refused as three impulses)."""
    J = np.diag([100.0, 200.0, 300.0])
    plant = RigidSpacecraft(J)
    config = SimConfig(
        duration=1.0,
        channel_actuators={"torque": ChannelActuator(saturation=[0.1, "200 mN*m", 0.3])},
        channel_sensors={"rate": ChannelSensor(bias=("1 deg/s", 0.0, 0.0))},
        channel_disturbances={
            "torque": ChannelDisturbance(impulse_times=(0.0,), impulses=([0.0, 0.0, 3.0],))
        },
    )
    sensors, actuators, disturbances = resolve_channels(plant, config)
    np.testing.assert_array_equal(actuators["torque"].saturation, [0.1, 0.2, 0.3])
    np.testing.assert_allclose(sensors["rate"].bias, [np.pi / 180, 0.0, 0.0], rtol=1e-15)
    per_case = ChannelActuator(saturation=[[0.1, 0.2, 0.3], [1.0, 2.0, 3.0]])
    assert per_case.bind(plant.inputs[0]).saturation.shape == (2, 3)
    # the impulse (0, 0, 3) N·m·s about the principal z axis from rest: a pure spin
    # ω = (0, 0, H / J_z) (angular momentum; rotation about a principal axis stays one)
    x0 = plant.state_from(euler123=[0.0, 0.0, 0.0], rate=[0.0, 0.0, 0.0])
    run = simulate(plant, _TorqueFree(), replace(config, channel_sensors={}), 1, initial_state=x0)
    rate = run.dataset["rate"].values[0, -1]
    np.testing.assert_allclose(rate, [0.0, 0.0, 3.0 / 300.0], rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize(
    "piece, message",
    [
        (
            ChannelDisturbance(impulse_times=(0.0,), impulses=(3.0,)),
            r"^disturbances\[torque\]\.impulses: give 3 values \(the channel is 3 values wide\) "
            r"for each of the 1 impulse times, got shape \(1,\)",
        ),
        (
            ChannelActuator(saturation=[0.1, 0.2]),
            r"^actuators\[torque\]\.saturation: the channel is 3 values wide: give a number, 3 "
            r"values \(one per element\) or \(n_cases, 3\), got shape \(2,\)",
        ),
        (
            ChannelDisturbance(random=[[0.1], [0.2]]),
            r"^disturbances\[torque\]\.random: the channel is 3 values wide",
        ),
    ],
)
def test_a_value_that_does_not_fit_the_channels_width_is_refused(piece, message):
    torque = RigidSpacecraft(np.eye(3)).inputs[0]
    with pytest.raises(ValueError, match=message):
        piece.bind(torque)
    with pytest.raises(ValueError, match=r"^sensors\[theta\]\.noise: the channel is one value"):
        ChannelSensor(noise=[[0.1, 0.2]]).bind(Channel("theta", "rad"))
