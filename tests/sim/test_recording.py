"""Claims of what a run records (flexsat.sim.recording), through flexsat.sim.simulate: a
dataset case × time with each channel's SI unit in ``units``, vector channels with a component
axis, commands, applied inputs, disturbances and input forces per input channel, the recorded
outputs equal to C x of the recorded states, and metrics records ready for JSON (NaN → None)."""

import json

import numpy as np
import pytest
import xarray as xr
from cart_plants import TwoCarts

from flexsat.control.base import Controller
from flexsat.dynamics.plant import Channel
from flexsat.sim import (
    BearingFriction,
    ChannelDisturbance,
    ChannelSensor,
    SimConfig,
    SimResult,
    simulate,
)


class Carts(TwoCarts):
    """The two carts with a ``brake`` force on the first as well; outputs also the first cart's
    ``speed``, the ``gap`` also kept as measured."""

    inputs = (Channel("push", "N", size=2), Channel("brake", "N"))
    outputs = (Channel("position", "m", size=2), Channel("gap", "m"), Channel("speed", "m/s"))
    recorded_measurements = ("gap",)
    noise_channels = ("gap", "push")

    def linear_part(self):
        A, B = super().linear_part()
        return A, np.hstack([B, [[0.0], [0.0], [1.0], [0.0]]])


class SpreadLaw(Controller):
    """Pushes the carts apart in proportion to the measured gap; brakes nothing."""

    reads = ("gap",)
    writes = ("push", "brake")
    target = 0.0

    def __call__(self, t, y, state):
        g = y["gap"]
        return {"push": np.stack([-0.5 * g, 0.5 * g], axis=-1), "brake": np.zeros_like(g)}, state


X0 = np.array([[0.0, 0.1, 0.0, 0.0], [0.0, 0.2, 0.0, 0.0], [0.0, -0.1, 0.3, 0.0]])


@pytest.fixture(scope="module")
def run():
    cfg = SimConfig(
        duration="2 s",
        control_rate="50 Hz",
        channel_disturbances={
            "push": ChannelDisturbance(random="10 mN"),
            "brake": ChannelDisturbance(
                force=BearingFriction(viscous=0.5), force_output="speed", force_name="drag"
            ),
        },
        channel_sensors={"gap": ChannelSensor(noise="1 mm")},
    )
    return simulate(Carts(), SpreadLaw(), cfg, n_cases=3, initial_state=X0, record_states=True)


def test_dimensions_are_case_by_time_with_a_component_axis_for_vector_channels(run):
    ds = run.dataset
    assert ds.sizes["case"] == 3 and ds.sizes["time"] == 101  # 2 s at 50 Hz: 100 periods
    np.testing.assert_array_equal(ds.case.values, [0, 1, 2])
    np.testing.assert_allclose(ds.time.values, np.arange(101) / 50, rtol=0, atol=1e-15)
    for name in ("gap", "gap_measured", "brake", "brake_command", "drag_brake", "energy"):
        assert ds[name].dims == ("case", "time"), name
    for name in ("position", "push", "push_command", "disturbance_push"):
        assert ds[name].dims[:2] == ("case", "time") and ds[name].shape == (3, 101, 2), name
    assert ds.position.dims[2] == "position_component" and ds.push.dims[2] == "push_component"
    # one axis per channel: its histories combine element-wise
    assert ds.push_command.dims == ds.push.dims
    assert ds.state.dims == ("case", "time", "state_index") and ds.sizes["state_index"] == 4


def test_every_history_carries_its_channels_unit(run):
    ds = run.dataset
    expected = {
        "position": "m",
        "gap": "m",
        "gap_measured": "m",
        "push": "N",
        "push_command": "N",
        "disturbance_push": "N",
        "brake": "N",
        "brake_command": "N",
        "drag_brake": "N",
        "energy": "J",
    }
    for name, unit in expected.items():
        assert ds[name].attrs["units"] == unit, name
    assert ds.time.attrs["units"] == "s"
    assert ds.attrs["control_rate_Hz"] == 50.0 and ds.attrs["substeps"] >= 1


def test_a_unit_with_a_power_keeps_it():
    """``*`` between factors is written as a space (``N*m`` → ``N m``, below) and a power as
    ``^``: the attribute parses back to the channel's unit."""
    from flexsat.units import ureg

    class PowerCarts(Carts):
        inputs = (Channel("push", "N", size=2), Channel("brake", "kg*m/s**2"))

    ds = simulate(PowerCarts(), SpreadLaw(), SimConfig(duration=0.1), initial_state=X0[0]).dataset
    assert ds.brake.attrs["units"] == "kg m/s^2"
    assert ureg.Unit(ds.brake.attrs["units"]) == ureg.Unit("kg*m/s**2")


def test_only_channels_with_a_disturbance_or_force_get_its_history(run):
    ds = run.dataset
    assert "disturbance_brake" not in ds and "drag_push" not in ds and "friction_push" not in ds
    assert "speed" not in ds  # not in the plant's ``recorded``


def test_recorded_states_are_stored_and_the_outputs_are_their_c_x(run):
    """state (case, time, state_index) starts at the given initial states; the recorded
    outputs equal C x of them (unit rows: exact; the gap p2 − p1 to one rounding)."""
    ds = run.dataset
    X = ds.state.values
    np.testing.assert_array_equal(X[:, 0], X0)
    np.testing.assert_array_equal(ds.position.values, X[..., :2])
    np.testing.assert_allclose(ds.gap.values, X[..., 1] - X[..., 0], rtol=0, atol=1e-16)
    energy = 0.5 * (X[..., 2:] ** 2).sum(-1) + 2.0 * (X[..., 1] - X[..., 0]) ** 2
    np.testing.assert_allclose(ds.energy.values, energy, rtol=1e-15, atol=0)


def test_commands_applied_inputs_disturbances_and_forces_are_recorded(run):
    """No actuator: applied = command; the plant's input is applied + disturbance (σ 10 mN,
    held per period: 2 × 101 × 3 draws, σ within 4 standard errors 1/√(2n) = 2.8 %: 11 %);
    the drag is −0.5 · v1 of the state at each sample, exactly."""
    ds = run.dataset
    np.testing.assert_array_equal(ds.push.values, ds.push_command.values)
    np.testing.assert_array_equal(ds.brake.values, 0.0)
    gm = ds.gap_measured.values
    np.testing.assert_array_equal(ds.push_command.values, np.stack([-0.5 * gm, 0.5 * gm], axis=-1))
    d = ds.disturbance_push.values
    assert abs(d.std() / 0.01 - 1) < 4 / np.sqrt(2 * d.size)
    np.testing.assert_array_equal(ds.drag_brake.values, -0.5 * ds.state.values[..., 2])
    # the measured gap is the true gap plus 1 mm noise (a sample σ within 11 % of 1 mm)
    err = gm - ds.gap.values
    assert abs(err.std() / 1e-3 - 1) < 4 / np.sqrt(2 * err.size)


def test_states_are_kept_only_when_asked():
    ds = simulate(Carts(), SpreadLaw(), SimConfig(duration=0.5), initial_state=X0[0]).dataset
    assert "state" not in ds and "state_index" not in ds.dims
    # no random disturbance and no force: no disturbance or force histories
    assert not any(k.startswith(("disturbance_", "friction_")) for k in ds.data_vars)


def test_a_long_run_is_recorded_across_chunks_like_a_short_one():
    """The outputs are computed per chunk of samples after the fact: a 10 s run (751 samples,
    many chunks) has the same first 2 s as a 2 s run (151 samples), bit for bit."""
    cfg_long, cfg_short = SimConfig(duration=10.0), SimConfig(duration=2.0)
    a = simulate(Carts(), SpreadLaw(), cfg_long, initial_state=X0[0]).dataset
    b = simulate(Carts(), SpreadLaw(), cfg_short, initial_state=X0[0]).dataset
    for name in ("position", "gap", "energy", "push"):
        np.testing.assert_array_equal(a[name].values[:, :151], b[name].values, err_msg=name)


# -- metrics records ---------------------------------------------------------------------------
def test_metrics_records_turn_non_finite_values_into_none():
    ds = xr.Dataset(coords={"case": np.arange(3)})
    r = SimResult(
        ds, {"settling_time_s": np.array([1.5, np.nan, np.inf]), "peak": np.array([1.0, 2.0, -3.0])}
    )
    rows = r.metrics_records(labels=["a", "b", "c"])
    assert rows == [
        {"run": "a", "settling_time_s": 1.5, "peak": 1.0},
        {"run": "b", "settling_time_s": None, "peak": 2.0},
        {"run": "c", "settling_time_s": None, "peak": -3.0},
    ]
    assert all(type(v) is float for v in (rows[0]["settling_time_s"], rows[2]["peak"]))
    assert r.metrics_records()[1] == {"settling_time_s": None, "peak": 2.0}
    json.dumps(rows, allow_nan=False)


def test_a_hub_maneuver_that_has_not_settled_reports_none(tamu_model):
    """A 1 s run of a slow PD toward 0.1 rad never enters the band: settling time NaN in the
    metrics, None in the records, which serialise as strict JSON."""
    from flexsat.control import PD

    r = simulate(tamu_model, PD(1.0, 1.0, target=0.1), SimConfig(duration=1.0))
    assert np.isnan(r.metrics["settling_time_s"][0])
    rows = r.metrics_records()
    assert len(rows) == 1 and rows[0]["settling_time_s"] is None
    assert set(rows[0]) == set(r.metrics)
    json.dumps(rows, allow_nan=False)
    assert r.dataset.torque.attrs["units"] == "N m"  # the channel's N*m
    for key, val in r.metrics.items():  # the metrics are also per-case variables of the dataset
        assert r.dataset[key].dims == ("case",)
        np.testing.assert_array_equal(r.dataset[key].values, val)


def test_a_law_without_a_target_on_a_maneuver_plant_records_channel_metrics(tamu_case):
    """A state-space compensator has no maneuver target: its run of the hub + appendage plant
    ends with the channel summary instead of the maneuver metrics (found by flexsat.testing:
    the recorder asked every law for ``reference_at``, which reads ``target``, and the run
    failed at its end with an AttributeError)."""
    import control as ct
    from flexsat.control.state_space_compensator import StateSpaceCompensator

    lead = ct.ss([[-4.0]], [[1.0, 0.5]], [[-3.0]], [[-5.0, -20.0]])
    config = SimConfig(duration=0.5)
    law = StateSpaceCompensator(lead, ["theta", "theta_dot"], "torque", dt=config.dt)
    plant = tamu_case.model()
    ds = simulate(plant, law, config, initial_state=plant.state_from(theta=0.1)).dataset
    assert "theta_ref" not in ds and "settling_time_s" not in ds
    assert ds["final_theta"].values[0] == ds["theta"].values[0, -1]
    assert ds["peak_torque"].values[0] == np.abs(ds["torque"].values[0]).max() > 0
