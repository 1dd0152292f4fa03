"""Claims of the generic engine: any Plant under any Controller, the law's channels checked
before the run, per-channel sensors and actuators, a plant's own integrator, and the linear
TAMU run reproduced by an independent discrete recursion."""

import numpy as np
import pytest
from cart_plants import TwoCarts
from scipy.linalg import expm

from flexsat.control.base import Controller
from flexsat.dynamics.plant import Channel, Plant
from flexsat.sim import ChannelActuator, ChannelDisturbance, ChannelSensor, SimConfig, simulate
from flexsat.units import to_si


class GapLaw(Controller):
    reads = ("gap",)
    writes = ("push",)
    target = 0.0

    def __init__(self, gain=1.0, shape=None):
        self.gain, self.shape = gain, shape

    def __call__(self, t, y, state):
        u = np.stack([self.gain * y["gap"], -self.gain * y["gap"]], axis=-1)
        return (u if self.shape is None else np.zeros(self.shape)), state


def test_a_two_input_plant_runs_and_records_its_channels():
    x0 = np.array([0.0, 0.1, 0.0, 0.0])
    r = simulate(TwoCarts(), GapLaw(0.0), SimConfig(duration=2.0), initial_state=x0)
    ds = r.dataset
    assert ds.position.shape == (1, 151, 2) and ds.push.shape == (1, 151, 2)
    # free oscillation of the gap at ω = sqrt(2k): exact linear propagation
    t = ds.time.values
    assert np.allclose(ds.gap.values[0], 0.1 * np.cos(np.sqrt(8.0) * t), rtol=0, atol=1e-12)
    assert np.ptp(ds.energy.values[0]) < 1e-14
    # not a hub maneuver: the summary of every channel (sim.metrics.channel_metrics)
    np.testing.assert_allclose(r.metrics["peak_gap"], 0.1, rtol=1e-12)
    assert "settling_time_s" not in r.metrics


def test_the_law_channels_are_checked_against_the_plant_before_the_run():
    class ReadsTheta(GapLaw):
        reads = ("gap", "theta")

    class WritesTorque(GapLaw):
        writes = ("torque",)

    cfg = SimConfig(duration=1.0)
    with pytest.raises(
        ValueError,
        match=r"^theta: ReadsTheta reads a measurement the plant "
        r"does not have",
    ):
        simulate(TwoCarts(), ReadsTheta(), cfg)
    with pytest.raises(
        ValueError,
        match=r"^torque: WritesTorque writes an unknown input "
        r"channel",
    ):
        simulate(TwoCarts(), WritesTorque(), cfg)
    with pytest.raises(
        ValueError,
        match=r"^push: GapLaw returned a command of shape \(1, 3\), "
        r"expected \(1, 2\)",
    ):
        simulate(TwoCarts(), GapLaw(shape=(1, 3)), cfg)


def test_channel_pieces_on_missing_channels_are_refused_naming_them():
    law = GapLaw()
    with pytest.raises(ValueError, match=r"^speed: TwoCarts has no output channel 'speed'"):
        simulate(
            TwoCarts(), law, SimConfig(duration=1.0, channel_sensors={"speed": ChannelSensor()})
        )
    with pytest.raises(
        ValueError,
        match=r"^torque: TwoCarts has no input channel 'torque'.*"
        r"config.friction, random_torque, impulses",
    ):
        from flexsat.sim import RandomTorque

        simulate(TwoCarts(), law, SimConfig(duration=1.0, random_torque=RandomTorque(1.0)))
    with pytest.raises(
        ValueError,
        match=r"^position: its sensor noise needs a noise stream, "
        r"but TwoCarts.noise_channels \(gap\) has none",
    ):
        simulate(
            TwoCarts(),
            law,
            SimConfig(
                duration=1.0,
                channel_sensors={
                    "gap": ChannelSensor(noise=0.1),
                    "position": ChannelSensor(noise=0.1),
                },
            ),
        )


def test_sensor_and_actuator_per_channel():
    """The gap is measured with bias, a quantum and a range (in mm, converted); the push is
    saturated, scaled and rate limited."""
    law = GapLaw(100.0)
    x0 = np.array([0.0, 0.1, 0.0, 0.0])
    cfg = SimConfig(
        duration=1.0,
        channel_sensors={"gap": ChannelSensor(bias="1 mm", quantum="2 mm", range="50 mm")},
        channel_actuators={"push": ChannelActuator(saturation=3.0, rate_limit="75 N/s", scale=0.5)},
    )
    ds = simulate(TwoCarts(), law, cfg, initial_state=x0).dataset
    measured = np.clip(0.002 * np.round((ds.gap.values[0] + 0.001) / 0.002), -0.05, 0.05)
    cmd = ds.push_command.values[0]
    assert np.allclose(cmd[:, 0], 100.0 * measured, rtol=0, atol=1e-12)
    applied = ds.push.values[0]
    assert np.abs(applied).max() <= 0.5 * 3.0 + 1e-15
    assert np.abs(np.diff(applied[:, 0])).max() <= 0.5 * 75.0 / 75.0 + 1e-12


def test_impulse_on_an_input_channel_is_b_times_j():
    """J = (0, 2) N·s on the 2-wide ``push`` (one value per cart, the channel's width from the
    plant): Δv = B J = (0, 2) m/s; the spring keeps the momentum 2 N·s of the two unit masses,
    so the gap is 2 sin(ωt)/ω (ω = sqrt(2k)) and their centre moves at 1 m/s, exactly (linear
    propagation). Before, the channel was taken as one value wide and (0, 2) was refused as two
    impulses for one time; a flat (0, 2) is now refused naming the width."""
    push = ChannelDisturbance(impulse_times=(0.0,), impulses=([0.0, 2.0],))
    cfg = SimConfig(duration=0.5, channel_disturbances={"push": push})
    ds = simulate(TwoCarts(), GapLaw(0.0), cfg).dataset
    t, w = ds.time.values, np.sqrt(8.0)
    np.testing.assert_allclose(ds.gap.values[0], 2.0 * np.sin(w * t) / w, rtol=0, atol=1e-12)
    np.testing.assert_allclose(ds.position.values[0].mean(axis=-1), t, rtol=0, atol=1e-12)
    flat = ChannelDisturbance(impulse_times=(0.0,), impulses=(0.0, 2.0))
    cfg = SimConfig(duration=0.5, channel_disturbances={"push": flat})
    with pytest.raises(ValueError, match=r"^disturbances\[push\].impulses: give 2 values \(the"):
        simulate(TwoCarts(), GapLaw(0.0), cfg)


class Spinner(Plant):
    """A unit vector turned at the commanded rate: x' = ω J x, stepped by the plant's own RK4
    and normalised (a stand-in for a quaternion integrator)."""

    inputs = (Channel("rate", "rad/s"),)
    outputs = (Channel("angle", "rad"),)
    recorded = ("angle",)
    nonlinear = True

    @property
    def nx(self):
        return 2

    def linear_part(self):
        return np.zeros((2, 2)), np.zeros((2, 1))

    def output(self, name, x, u, f_in=None):
        return np.arctan2(x[..., 1], x[..., 0])

    def initial_state(self, n):
        return np.tile([1.0, 0.0], (n, 1))

    def step(self, x, u, h):
        def f(x):
            return u[:, :1] * np.stack([-x[:, 1], x[:, 0]], axis=1)

        k1 = f(x)
        k2 = f(x + h / 2 * k1)
        k3 = f(x + h / 2 * k2)
        k4 = f(x + h * k3)
        return x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)

    def normalize(self, x):
        return x / np.linalg.norm(x, axis=-1, keepdims=True)


class ConstantRate(Controller):
    reads = ("angle",)
    writes = ("rate",)
    target = 0.0

    def __call__(self, t, y, state):
        return np.full(np.shape(y["angle"]), 0.5), state


def test_a_plant_with_its_own_integrator_is_stepped_and_normalised():
    """θ = 0.5 t exactly (RK4 on a rotation loses only ~h⁵ per step, and the normalisation
    removes the norm drift); ‖x‖ = 1 to round-off."""
    r = simulate(Spinner(), ConstantRate(), SimConfig(duration=2.0, substeps=3), record_states=True)
    t = r.dataset.time.values
    assert np.allclose(r.dataset.angle.values[0], 0.5 * t, rtol=0, atol=1e-12)
    assert np.abs(np.linalg.norm(r.dataset.state.values[0], axis=-1) - 1).max() < 1e-15
    assert r.dataset.attrs["substeps"] == 3


def test_linear_tamu_run_equals_an_independent_discrete_recursion(tamu_case):
    """Law I on the linear TAMU plant (ideal sensors, no disturbances) is the discrete
    recursion x_{k+1} = Φ x_k + Γ u_k, u_k = −g1 (θ_k − θ_f) − g2 θ'_k − g3 r_k with the root
    torque r_k from the plant's acceleration form (``outputs``) at the held input u_{k−1}; Φ, Γ
    from one exponential of [[A, B], [0, 0]]. Agreement to 1e-10 relative (the issue's bound
    for linear runs; both are exact, they differ by round-off in different products)."""
    from flexsat.control import LyapunovRegulator

    model = tamu_case.model()
    g1, g2, g3 = (to_si("3000 ozf*in/rad", "N*m/rad"), to_si("800 ozf*in*s/rad", "N*m*s/rad"), 0.5)
    law = LyapunovRegulator(g1, g2, g3, target=0.5)
    cfg = SimConfig(duration=8.0)
    ds = simulate(model, law, cfg, record_states=True).dataset
    A, B, _ = model.state_space
    n, dt = model.nx, cfg.dt
    E = expm(dt * np.block([[A, B[:, None]], [np.zeros((1, n + 1))]]))
    Phi, Gam = E[:n, :n], E[:n, n]
    x, u_prev, xs, us = np.zeros(n), 0.0, [], []
    for _ in range(cfg.n_steps + 1):
        y = model.outputs(x, u_prev)
        u = -(g1 * (y["theta"] - 0.5) + g2 * y["theta_dot"] + g3 * y["root_torque"])
        xs.append(x)
        us.append(u)
        x, u_prev = Phi @ x + Gam * u, u
    xs, us = np.array(xs), np.array(us)
    assert np.abs(ds.state.values[0] - xs).max() <= 1e-10 * np.abs(xs).max()
    assert np.abs(ds.torque.values[0] - us).max() <= 1e-10 * np.abs(us).max()


class Bernoulli(Plant):
    """x' = −x + x² through the exponential integrators: A = −1, B_f = 1, f = x²."""

    inputs = (Channel("drive", ""),)
    outputs = (Channel("value", ""),)
    recorded = ("value",)
    nonlinear = True
    force_matrix = np.array([[1.0]])

    def __init__(self, integrator):
        self.integrator = integrator

    @property
    def nx(self):
        return 1

    def linear_part(self):
        return np.array([[-1.0]]), np.zeros((1, 1))

    def nonlinear_force(self, x, u):
        return x**2

    def output_matrices(self, name):
        return np.ones((1, 1)), np.zeros((1, 1)), np.zeros((1, 1))


class Idle(Controller):
    reads = ("value",)
    writes = ("drive",)
    target = 0.0

    def __call__(self, t, y, state):
        return np.zeros(np.shape(y["value"])), state


@pytest.mark.parametrize("integrator, tol", [("etd2rk", 1e-6), ("exp_rk4", 1e-11)])
def test_the_plant_chooses_its_integrator(integrator, tol):
    """The exact solution x0 e^{−t} / (1 − x0 (1 − e^{−t})) at 75 Hz with 4 substeps: ETD2RK's
    error ~h² (measured 4.4e-7), Krogstad's ~h⁴ (measured 1.1e-13)."""
    x0 = 0.5
    r = simulate(Bernoulli(integrator), Idle(), SimConfig(duration=2.0), initial_state=[x0])
    t = r.dataset.time.values
    exact = x0 * np.exp(-t) / (1 - x0 * (1 - np.exp(-t)))
    assert np.abs(r.dataset.value.values[0] - exact).max() < tol


def test_a_rigid_spacecraft_slews_under_its_own_integrator():
    """The three-axis rigid body (its RKMK4 ``step``, 4 substeps per period) under the
    quaternion PD law, 30° about a skew axis: the engine keeps ‖β‖ = 1 to round-off and the
    slew settles: the overdamped loop's slow pole is (Kp/2)/Kd = 0.1 1/s, so 0.52 rad decays
    by about e^{-6} in 60 s, below 2e-3 rad (measured 7e-4)."""
    from flexsat.control.attitude_laws import QuaternionPD
    from flexsat.dynamics.rigid_spacecraft import RigidSpacecraft

    plant = RigidSpacecraft(np.diag([100.0, 120.0, 80.0]))
    axis, angle = np.array([1.0, 2.0, 2.0]) / 3, np.radians(30.0)
    x0 = np.concatenate([[np.cos(angle / 2)], np.sin(angle / 2) * axis, np.zeros(3)])
    r = simulate(
        plant,
        QuaternionPD(Kp=20.0, Kd=100.0),
        SimConfig(duration=60.0, control_rate=10.0),
        initial_state=x0,
    )
    beta = r.dataset.attitude.values[0]
    assert np.abs(np.linalg.norm(beta, axis=-1) - 1).max() < 1e-14
    assert 2 * np.arccos(min(abs(beta[-1, 0]), 1.0)) < 2e-3


def test_non_finite_per_case_channel_parameters_are_refused_naming_the_channel():
    law = GapLaw()
    cfg = SimConfig(
        duration=0.1, channel_actuators={"push": ChannelActuator(saturation=[1.0, float("nan")])}
    )
    with pytest.raises(
        ValueError,
        match=r"^actuators\[push\].saturation: must be >= 0 \(inf for "
        r"none\)",
    ):
        simulate(TwoCarts(), law, cfg, n_cases=2)
    cfg = SimConfig(duration=0.1, channel_sensors={"gap": ChannelSensor(bias=float("inf"))})
    with pytest.raises(ValueError, match=r"^sensors\[gap\].bias: must be finite"):
        simulate(TwoCarts(), law, cfg)
