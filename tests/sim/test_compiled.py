"""Claims of the compiled path of simulate (flexsat.sim.compiled): it is taken by itself for
linear plants under linear laws, and it changes nothing: every recorded history and metric
equals the Python loop's (``compiled=False``) to round-off.

Tolerance: the two loops do the same arithmetic with the sums of the matrix products in a
different order, a few ulps per product; a stable closed loop carries these without growth, so
after n_t samples a history differs by at most ~ n_t · eps of its own peak (checked with a
factor 4 of margin). The bearing friction amplifies a rate difference δ into c1 δ / ε (its
slope below the smoothing speed ε): its history is compared on that scale. Noise streams,
quantisation and saturation take the same decisions on both paths (the same seeds, and values
that differ by round-off do not straddle a rounding boundary in these runs).
"""

from functools import partial
from pathlib import Path

import numpy as np
import pytest

from flexsat.control import PD
from flexsat.dynamics.dispersion import stack_plants
from flexsat.dynamics.hub_appendage import HubAppendage
from flexsat.scenarios import default_scenario, load_scenario, run_scenario, runner
from flexsat.sim import (
    BearingFriction,
    ChannelSensor,
    Impulses,
    RandomTorque,
    Sensors,
    SimConfig,
    SimulationDiverged,
    TorqueActuator,
    simulate,
)
from flexsat.units import to_si

EPS = np.finfo(float).eps
EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
#: metrics computed from a history (a difference of its values): (history, unit factor)
METRIC_SOURCES = {
    "residual_energy_J": ("energy", 1.0),
    "residual_energy_at_T_J": ("energy", 1.0),
    "overshoot_deg": ("theta", np.degrees(1.0)),
    "peak_rate_error_deg_s": ("theta_dot", np.degrees(1.0)),
}
FRICTION = BearingFriction(to_si("20 ozf*in", "N*m"), to_si("0.001 ozf*in*s/rad", "N*m*s/rad"))


def assert_same(compiled, python, friction=None):
    """Every float history and metric of two datasets equal to 4 n_t eps of its peak."""
    a, b = compiled.dataset, python.dataset
    assert a.attrs["engine"] == "compiled" and b.attrs["engine"] == "python"
    assert set(a.data_vars) == set(b.data_vars)
    n_t = a.sizes["time"]
    tol = 4 * n_t * EPS
    for var in a.data_vars:
        x, y = a[var].values, b[var].values
        assert x.shape == y.shape, var
        scale = np.nanmax(np.abs(y), initial=0.0)
        if var.startswith("friction") and friction is not None:
            rate = np.abs(b["theta_dot"].values).max()
            scale = friction.coulomb / friction.smoothing * rate
        elif var in METRIC_SOURCES:  # a metric: on the scale of the history it comes from
            source, factor = METRIC_SOURCES[var]
            scale = max(scale, factor * np.abs(b[source].values).max())
        elif y.ndim == 1:  # a channel metric (final_<channel>, ...): on its channel's scale
            for name in b.data_vars:
                if b[name].ndim > 1 and var.endswith(name):
                    scale = max(scale, np.abs(b[name].values).max())
        same_nan = np.isnan(x) == np.isnan(y)
        assert same_nan.all(), var
        diff = np.nan_to_num(np.abs(x - y))
        assert diff.max(initial=0.0) <= tol * scale, (var, diff.max() / max(scale, 1e-300))


def _both(plant, law, cfg, **kwargs):
    return simulate(plant, law, cfg, **kwargs), simulate(plant, law, cfg, compiled=False, **kwargs)


def test_default_scenario_runs_are_unchanged(monkeypatch):
    """The TAMU default scenario (Law I and Law II, friction, encoder, LS rate filter, random
    torque, saturation) runs on the compiled loop and equals the Python loop."""
    fast = run_scenario(default_scenario())
    monkeypatch.setattr(runner, "simulate", partial(simulate, compiled=False))
    slow = run_scenario(default_scenario())
    for a, b in zip(fast.results, slow.results):
        assert_same(a, b, FRICTION)


@pytest.mark.parametrize("rate", ["ls_filter", "gyro"])
def test_pd_with_every_sensor_actuator_and_disturbance(tamu_case, rate):
    """PD slew with encoder quantisation, the LS rate filter or a noisy gyro, strain-gauge
    noise, friction, random torque, two impulses and a saturation that is reached."""
    plant = tamu_case.model()
    sensors = Sensors(encoder_resolution="0.01 deg", rate=rate, gyro_noise=1e-4, strain_noise=0.01)
    cfg = SimConfig(
        duration=6.0,
        sensors=sensors,
        friction=FRICTION,
        random_torque=RandomTorque(0.02),
        actuator=TorqueActuator(saturation=0.5),
        impulses=Impulses((1.0, 2.5), (0.05, -0.03)),
        channel_sensors={"root_torque": ChannelSensor(noise=0.01, bias=0.002)},
    )
    law = PD(20.0, 30.0, target=np.radians(40.0))
    fast, slow = _both(plant, law, cfg)
    assert_same(fast, slow, FRICTION)
    assert np.abs(slow.dataset.torque.values).max() == pytest.approx(0.5)  # saturated


def test_lqg_scenario_is_unchanged(monkeypatch):
    """The NPS LQG slews (an estimator state in the law, gyro noise) on both loops."""
    text = (EXAMPLES / "nps_lqg_30deg.yaml").read_text()
    fast = run_scenario(load_scenario(text))
    monkeypatch.setattr(runner, "simulate", partial(simulate, compiled=False))
    slow = run_scenario(load_scenario(text))
    for a, b in zip(fast.results, slow.results):
        assert_same(a, b)


def test_dispersed_batch_is_unchanged(tamu_case):
    """Hub inertia and damping dispersed over 3 cases (per-case A, B in the kernel) with
    friction and random torque."""
    p = tamu_case.model().params
    plants = [
        HubAppendage(
            p.__class__(**{**p.__dict__, "hub_inertia": h * p.hub_inertia, "damping": z}), n_modes=4
        )
        for h, z in ((1.0, 0.005), (1.3, 0.01), (0.8, 0.02))
    ]
    cfg = SimConfig(duration=3.0, friction=FRICTION, random_torque=RandomTorque(0.01))
    fast, slow = _both(stack_plants(plants), PD(5.0, 20.0, target=[0.3, 0.4, 0.5]), cfg)
    assert_same(fast, slow, FRICTION)


def test_structural_plant_under_lqr_is_unchanged(monkeypatch):
    """The Draper/RPL modal plant (a StructuralPlant, three torquers, one saturated) under
    its LQR (ScheduledStateFeedback reading the whole state)."""
    text = (EXAMPLES / "draper_rpl_lqr.yaml").read_text()
    fast = run_scenario(load_scenario(text))
    monkeypatch.setattr(runner, "simulate", partial(simulate, compiled=False))
    slow = run_scenario(load_scenario(text))
    for a, b in zip(fast.results, slow.results):
        assert a.dataset.attrs["propagation"] == "modal"  # decoupled modes: a permutation
        assert_same(a, b)


def test_modal_propagation_of_a_batch_equals_the_python_loop(tamu_case):
    """20 TAMU PD slews with friction and random torque: 90,000 integrator steps, so the
    compiled loop propagates the modal 2×2 blocks (flexsat.sim.compiled.modal_form); the
    result equals the Python loop's dense exponential to 1e-10 of each history's peak (the
    issue's bound for linear runs; the modal change of coordinates is exact to cond(T) eps)."""
    plant = tamu_case.model()
    cfg = SimConfig(duration=15.0, friction=FRICTION, random_torque=RandomTorque(0.01))
    law = PD(np.linspace(5.0, 10.0, 20), 20.0, target=np.radians(40.0))
    fast, slow = _both(plant, law, cfg)
    assert fast.dataset.attrs["propagation"] == "modal"
    for var in ("theta", "theta_dot", "torque", "tip_deflection", "root_torque", "energy"):
        a, b = fast.dataset[var].values, slow.dataset[var].values
        assert np.abs(a - b).max() <= 1e-10 * np.abs(b).max(), var


def test_nonlinear_plant_takes_the_python_loop(tamu_case):
    """Rotational stiffening makes the plant nonlinear: the Python loop runs, and asking for
    the compiled one says why it cannot."""
    plant = HubAppendage(tamu_case.model().params, n_modes=3, stiffening=True)
    cfg = SimConfig(duration=0.5)
    law = PD(5.0, 20.0, target=0.3)
    assert simulate(plant, law, cfg).dataset.attrs["engine"] == "python"
    with pytest.raises(ValueError, match="^compiled: .*the plant is nonlinear"):
        simulate(plant, law, cfg, compiled=True)


def test_divergence_is_reported_the_same_way(tamu_case):
    """A destabilising gain in case 1 of 3: the same exception, cases, time and message."""
    law = PD(np.array([5.0, 1e9, 5.0]), np.array([20.0, 1e7, 20.0]), target=tamu_case.angle)
    errors = []
    for compiled in (None, False):
        with pytest.raises(SimulationDiverged) as info:
            simulate(tamu_case.model(), law, SimConfig(duration=2.0), compiled=compiled)
        errors.append(info.value)
    assert errors[0].cases == errors[1].cases == (1,)
    assert errors[0].time == errors[1].time
    assert str(errors[0]) == str(errors[1])


def test_divergence_of_a_modal_batch_is_reported_the_same_way(tamu_case):
    """20 cases (modal propagation), case 7 destabilised: the Python loop's exception (its
    bound is on the physical state: the compiled path re-runs a diverged modal batch dense)."""
    kp, kd = np.full(20, 5.0), np.full(20, 20.0)
    kp[7], kd[7] = 1e9, 1e7
    law = PD(kp, kd, target=tamu_case.angle)
    cfg = SimConfig(duration=15.0, friction=FRICTION)
    errors = []
    for compiled in (None, False):
        with pytest.raises(SimulationDiverged) as info:
            simulate(tamu_case.model(), law, cfg, compiled=compiled)
        errors.append(info.value)
    assert errors[0].cases == (7,)
    assert str(errors[0]) == str(errors[1])


def test_recorded_states_are_the_python_loops(tamu_case):
    """record_states=True on a modal batch: the states, back in the plant's coordinates."""
    cfg = SimConfig(duration=15.0, friction=FRICTION)
    law = PD(np.linspace(5.0, 10.0, 6), 20.0, target=0.5)
    fast, slow = _both(tamu_case.model(), law, cfg, record_states=True)
    assert fast.dataset.attrs["propagation"] == "modal"
    a, b = fast.dataset.state.values, slow.dataset.state.values
    assert np.abs(a - b).max() <= 1e-10 * np.abs(b).max()


def test_kernels_compile_without_a_writable_cache(monkeypatch):
    """Where numba finds no writable cache directory it refuses ``cache=True`` at decoration;
    the kernels' decorator then compiles without the cache, with one warning."""
    import numba.core.caching as caching

    from flexsat.sim import kernel_arrays

    for cls in caching.CacheImpl._locator_classes:
        monkeypatch.setattr(cls, "from_function", classmethod(lambda cls, f, s: None))
    monkeypatch.setattr(kernel_arrays, "_UNCACHED", [])

    def double(x):
        return 2.0 * x

    with pytest.warns(RuntimeWarning, match="compiling without the on-disk cache"):
        compiled = kernel_arrays.cached_jit(error_model="numpy")(double)
    assert compiled(1.5) == 3.0
