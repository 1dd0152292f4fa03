"""Claims of the run settings (flexsat.sim.config): fields in SI from numbers, quantities or unit
strings, refused naming the field; the control grid; the substeps raised to keep the explicit
friction stable (h λ <= FRICTION_STEP_LIMIT); runs beyond flexsat.limits refused before they
start, naming the field."""

import math

import numpy as np
import pytest

from flexsat import limits
from flexsat.control import PD
from flexsat.dynamics.plant import Channel, Plant
from flexsat.sim import (
    BearingFriction,
    ChannelActuator,
    ChannelDisturbance,
    ChannelSensor,
    SimConfig,
)
from flexsat.sim.channels import resolve_channels
from flexsat.sim.config import (
    FRICTION_STEP_LIMIT,
    check_resources,
    force_rates,
    recorded_values,
    run_substeps,
    stable_substeps,
)
from flexsat.units import ureg


class Cart(Plant):
    """A unit mass pushed by a force: x = [p, v], outputs p and v (linear)."""

    inputs = (Channel("force", "N"),)
    outputs = (Channel("position", "m"), Channel("speed", "m/s"))
    recorded = ("position",)
    nx = 2

    def linear_part(self):
        return np.array([[0.0, 1.0], [0.0, 0.0]]), np.array([[0.0], [0.5]])  # mass 2 kg

    def output_matrices(self, name):
        C = {"position": np.array([[1.0, 0.0]]), "speed": np.array([[0.0, 1.0]])}[name]
        return C, np.zeros((1, 1)), None


# -- fields -----------------------------------------------------------------------------------
def test_unit_strings_and_quantities_are_stored_in_si():
    cfg = SimConfig(duration="15 s", control_rate="75 Hz", settling_band="0.5 deg")
    assert cfg.duration == 15.0 and cfg.control_rate == 75.0
    np.testing.assert_allclose(cfg.settling_band, np.radians(0.5), rtol=2e-16)
    cfg = SimConfig(duration=ureg.Quantity(2.0, "min"), control_rate="1 kHz")
    assert cfg.duration == 120.0 and cfg.control_rate == 1000.0


def test_control_grid():
    """dt = 1/rate; n_steps = round(duration·rate) control periods (so n_steps + 1 samples):
    15 s at 75 Hz is 1125 periods, and a duration a rounding error short of a whole number of
    periods still counts it."""
    cfg = SimConfig(duration="15 s", control_rate="75 Hz")
    assert cfg.dt == 1 / 75 and cfg.n_steps == 1125
    assert SimConfig(duration=0.1 * 3, control_rate=10.0).n_steps == 3  # 0.30000000000000004
    assert SimConfig(duration=1.0 - 1e-12, control_rate=1000.0).n_steps == 1000


def test_defaults():
    cfg = SimConfig(duration=1.0)
    assert (cfg.control_rate, cfg.substeps, cfg.seed) == (75.0, 4, 0)
    np.testing.assert_allclose(cfg.settling_band, np.radians(0.5), rtol=2e-16)
    assert cfg.channel_sensors == {} and not cfg.friction.active


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(duration="15 m"), r"^duration: .*"),
        (dict(duration=0.0), r"^duration: .*"),
        (dict(duration=-1.0), r"^duration: .*"),
        (dict(duration=np.nan), r"^duration: .*"),
        (dict(duration=1.0, control_rate="75 s"), r"^control_rate: .*"),
        (dict(duration=1.0, control_rate=0.0), r"^control_rate: .*"),
        (dict(duration=1.0, settling_band="1 m"), r"^settling_band: .*"),
        (dict(duration=1.0, substeps=0), r"^substeps: must be a positive integer"),
        (dict(duration=1.0, substeps=2.5), r"^substeps: must be a positive integer"),
        (dict(duration=1.0, seed=0.5), r"^seed: must be an integer in \[0, 4294967295\]"),
        (dict(duration=1.0, seed=True), r"^seed: must be an integer"),
        (dict(duration=1.0, seed=2**32), r"^seed: must be an integer"),
        (
            dict(duration=1.0, channel_sensors={"theta": ChannelActuator()}),
            r"^channel_sensors: must map channel names to ChannelSensor",
        ),
        (
            dict(duration=1.0, channel_actuators={"torque": ChannelSensor()}),
            r"^channel_actuators: must map channel names to ChannelActuator",
        ),
        (
            dict(duration=1.0, channel_disturbances={1: ChannelDisturbance()}),
            r"^channel_disturbances: must map channel names to ChannelDisturbance",
        ),
        (
            dict(duration=1.0, channel_sensors=[("theta", ChannelSensor())]),
            r"^channel_sensors: must map",
        ),
    ],
)
def test_bad_fields_are_refused_naming_them(kwargs, message):
    with pytest.raises(ValueError, match=message):
        SimConfig(**kwargs)


def test_the_largest_seed_and_sample_count_are_accepted():
    SimConfig(duration=1.0, seed=limits.MAX_SEED)
    cfg = SimConfig(duration=limits.MAX_SAMPLES / 1000.0, control_rate=1000.0)
    assert cfg.n_steps == limits.MAX_SAMPLES
    with pytest.raises(ValueError, match=r"^duration: control samples"):
        SimConfig(duration=limits.MAX_SAMPLES / 1000.0 + 0.01, control_rate=1000.0)


# -- stable substeps --------------------------------------------------------------------------
def _lambda(tamu_model, friction):
    """The bearing's damping rate below the smoothing speed, computed independently of
    force_rates: λ = (c1/ε + c2) (M⁻¹)_θθ, the stiffness of the regularised friction over the
    hub's effective inertia (the θ' row of M⁻¹ is where the torque column of B lands)."""
    return friction.max_slope * np.linalg.inv(tamu_model.mass_matrix)[0, 0]


@pytest.mark.parametrize(
    "coulomb, smoothing, rate, requested",
    [
        ("20 ozf*in", 1e-3, 75.0, 4),  # TAMU bearing, default smoothing: 4 substeps are enough
        ("20 ozf*in", 1e-5, 75.0, 4),  # 100x stiffer: raised
        ("20 ozf*in", 1e-5, 500.0, 4),  # a faster control rate needs fewer
        (0.5, 1e-4, 75.0, 1),
    ],
)
def test_substeps_keep_h_lambda_within_the_limit(tamu_model, coulomb, smoothing, rate, requested):
    """substeps = max(requested, ceil(dt λ / FRICTION_STEP_LIMIT)): the smallest count with
    h λ <= 1.5 (ETD2RK is stable for h λ <= 2), never below the request."""
    friction = BearingFriction(coulomb, "0.001 ozf*in*s/rad", smoothing)
    dt = 1 / rate
    lam = _lambda(tamu_model, friction)
    n = stable_substeps(tamu_model, friction, dt, requested)
    assert n == max(requested, math.ceil(dt * lam / FRICTION_STEP_LIMIT))
    assert dt / n * lam <= FRICTION_STEP_LIMIT
    if n > requested:  # raised: one fewer would exceed the limit
        assert dt / (n - 1) * lam > FRICTION_STEP_LIMIT
    assert FRICTION_STEP_LIMIT == 1.5


def test_force_rate_is_the_bearing_stiffness_over_the_hub_inertia(tamu_model):
    """force_rates' λ = max|∂f/∂θ'| |C_θ' B_τ| equals (c1/ε + c2)(M⁻¹)_θθ to rounding (an
    11 × 11 inverse: ~cond(M)·eps, 1e-12)."""
    friction = BearingFriction(0.2, 0.01, 1e-3)
    d = {"torque": ChannelDisturbance(force=friction, force_output="theta_dot")}
    ((name, lam),) = force_rates(tamu_model, d)
    assert name == "torque"
    np.testing.assert_allclose(lam, _lambda(tamu_model, friction), rtol=1e-12)


def test_inactive_friction_keeps_the_requested_substeps(tamu_model):
    assert stable_substeps(tamu_model, BearingFriction(), 1 / 75, 3) == 3


def test_friction_needing_more_substeps_than_the_limit_is_refused(tamu_model):
    with pytest.raises(
        ValueError,
        match=r"^friction: a stable integration of the friction "
        r"\(damping rate .* 1/s below the smoothing speed\).*"
        r"above the limit 1,000 .*raise smoothing",
    ):
        stable_substeps(tamu_model, BearingFriction(1.0, 0.0, 1e-9), 1 / 75, 4)


def test_a_linear_run_takes_one_exact_step_and_a_forced_one_its_substeps(tamu_model):
    cfg = SimConfig(duration=1.0, substeps=3)
    assert run_substeps(tamu_model, cfg, resolve_channels(tamu_model, cfg)[2]) == 1
    stiff = BearingFriction("20 ozf*in", 0.0, 1e-5)
    cfg = SimConfig(duration=1.0, substeps=3, friction=stiff)
    expected = stable_substeps(tamu_model, stiff, cfg.dt, 3)
    assert expected > 3
    assert run_substeps(tamu_model, cfg, resolve_channels(tamu_model, cfg)[2]) == expected
    assert check_resources(tamu_model, cfg) == expected


def test_friction_on_a_generic_plant_channel_raises_the_substeps():
    """A viscous-like force f(v) = −c tanh(v/ε) on the cart's force channel, driven by its
    speed: λ = (c/ε) |C_v B| = (c/ε)/m."""
    force = BearingFriction(coulomb=2.0, smoothing=1e-3)
    d = {"force": ChannelDisturbance(force=force, force_output="speed")}
    lam = 2.0 / 1e-3 * 0.5
    assert force_rates(Cart(), d) == [("force", pytest.approx(lam, rel=1e-15))]
    assert stable_substeps(Cart(), d, 0.01, 1) == math.ceil(0.01 * lam / 1.5)


# -- resources --------------------------------------------------------------------------------
def test_too_many_cases_are_refused_naming_n_cases(tamu_model):
    cfg = SimConfig(duration=1.0)
    assert check_resources(tamu_model, cfg, limits.MAX_CASES) == 1
    with pytest.raises(
        ValueError,
        match=r"^n_cases: cases in one batch = 1e\+05, above the "
        r"limit 100,000 \(flexsat.limits\); split the batch",
    ):
        check_resources(tamu_model, cfg, limits.MAX_CASES + 1)


def test_too_many_integrator_steps_are_refused_naming_duration(tamu_model, monkeypatch):
    """76 samples × 4 substeps (a friction run) = 304 integrator steps."""
    cfg = SimConfig(duration=1.0, friction=BearingFriction(0.01))
    assert check_resources(tamu_model, cfg) == 4
    monkeypatch.setattr(limits, "MAX_INTEGRATOR_STEPS", 303)
    with pytest.raises(
        ValueError,
        match=r"^duration: integrator steps \(76 control samples × "
        r"4 substeps\) = 304, above the limit 303",
    ):
        check_resources(tamu_model, cfg)


def test_memory_counts_the_histories_and_the_states_when_recorded(monkeypatch):
    """The cart, 1 s at 75 Hz (76 samples), 10 cases: the histories are its recorded output
    (position), 4 per input (command, applied, disturbance, force) and the energy: 6 values;
    the loop's 32-sample buffer holds 2 states and 3 noise columns (position, speed, force).
    8 B × 10 × (76 × 6 + 32 × 5) = 49,280 B; record_states adds 76 × 2 states per case."""
    cfg = SimConfig(duration=1.0)
    assert recorded_values(Cart()) == 6
    need = 8 * 10 * (76 * 6 + 32 * 5)
    monkeypatch.setattr(limits, "MAX_MEMORY", need)
    assert check_resources(Cart(), cfg, 10) == 1
    with pytest.raises(
        ValueError,
        match=r"^duration: a run of 76 samples × 10 cases × 8 values "
        r"\(and a 32-sample buffer of 5\) needs about 60 kB",
    ):
        check_resources(Cart(), cfg, 10, record_states=True)
    monkeypatch.setattr(limits, "MAX_MEMORY", need - 1)
    with pytest.raises(ValueError, match=r"^duration: .*above the limit .*MAX_MEMORY"):
        check_resources(Cart(), cfg, 10)


def test_resources_are_checked_against_the_plant_channels(tamu_model):
    """check_resources binds the channel pieces first: a piece on a missing channel is refused
    before any estimate (the same message as the run)."""
    cfg = SimConfig(duration=1.0, channel_sensors={"pitch": ChannelSensor()})
    with pytest.raises(ValueError, match=r"^pitch: HubAppendage has no output channel"):
        check_resources(tamu_model, cfg)


def test_a_hub_maneuver_fits_the_default_limits(tamu_case, tamu_model):
    """The TAMU configuration (15 s at 75 Hz, friction on) with a PD law is accepted as is."""
    cfg = tamu_case.sim_config(duration=15.0)
    substeps = check_resources(tamu_model, cfg, PD(1.0, 1.0).n_cases)
    assert substeps >= cfg.substeps
