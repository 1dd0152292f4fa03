"""CMG scenarios (kind: cmg, kind: cmg_station; issue 14): a small steering scenario reproduces
V3 and the preferred set's saturation, the null motion beside the torque law and the
reorientation; a singular start is refused under the pseudo-inverse and steered through by the
SR inverse; the station scenario reproduces the V9 contrast; every mistake is reported as
``field.path: rule`` before anything runs."""

import numpy as np
import pytest

from flexsat.dynamics import cmg
from flexsat.scenarios import ScenarioError, load_scenario, run_scenario

SMALL = """
kind: cmg
name: small cmg
cluster: {skew: "54.74 deg", n_units: 4, steering: pi, gimbal_rate_limit: "3 rad/s"}
runs:
  - {label: zero, demand: [1, 0, 0], initial: zero, duration: "2 s"}
  - {label: preferred, demand: [1, 0, 0], initial: preferred, duration: "4 s"}
  - label: with null
    demand: [1, 0, 0]
    initial: zero
    null_motion: {target: preferred, gain: "1 1/s"}
    duration: "4 s"
  - {label: reorient, reorient_to: alternate, initial: zero, duration: "10 s"}
"""

STATION = """
kind: cmg_station
name: small station
simulation: {orbits: 0.25, disturbance: aero_substitute}
runs: [{label: zero, initial: zero}, {label: alternate, initial: alternate}]
"""


def test_steering_runs_reproduce_v3_the_preferred_saturation_and_null_motion():
    result = run_scenario(load_scenario(SMALL))
    rows = {r["run"]: r for r in result.metrics_records()}
    h_s = 2 * np.cos(cmg.SKEW)
    # V3: internal singularity at 1.1546 h (t = |h| under the unit demand), V2 envelope 3.1546
    assert rows["zero"]["singular"] and rows["zero"]["internal"]
    assert rows["zero"]["end_time_s"] == pytest.approx(h_s, abs=1e-5)
    for label in ("preferred", "with null"):
        assert rows[label]["singular"] and not rows[label]["internal"]
        assert rows[label]["final_momentum_along_demand_h"] == pytest.approx(
            rows[label]["envelope_h"], abs=1e-3
        )
    # the null motion runs alone: no momentum, gain back to 0.5928 at [45, −45, 45, −45]°
    assert not rows["reorient"]["singular"]
    assert rows["reorient"]["final_momentum_h"] < 1e-10
    assert rows["reorient"]["final_gain"] == pytest.approx(0.5928, abs=1e-3)
    # the pseudo-inverse's rates grow without bound towards a singular stop: flagged
    assert rows["zero"]["rate_limit_exceeded"]
    ds = result.dataset()
    assert ds["gimbal_angles"].shape == (4, 401, 4)
    assert result.table[0][0] == "V1"


def test_every_run_is_a_simulation_the_runner_hands_to_simulate():
    # the kind plans each run as a (plant, law, configuration) triple on the gimbal cluster:
    # a torque-steering run the pseudo-inverse law with the engine's stop at the first singular
    # set, a reorientation the null-motion law
    from flexsat.control.cmg_steering import NullMotionSteering, PseudoInverseSteering
    from flexsat.dynamics.gimbal_cluster import GimbalCluster
    from flexsat.scenarios.cmg import N_OUT, CmgKind
    from flexsat.scenarios.kind import Simulation
    from flexsat.sim import simulate

    scenario = load_scenario(SMALL)
    plan = CmgKind().plan(scenario)
    run = next(plan)
    while run.label != "reorient":
        task = run.task
        assert isinstance(task, Simulation) and isinstance(task.law, PseudoInverseSteering)
        assert task.config.law_mode == "continuous" and task.config.stop.terminal
        sim = simulate(task.plant, task.law, task.config, **task.options)
        if run.label == "zero":
            # V3: under the unit demand from σ = 0 the stop is at |h| = t = 2 cos δ (1.1546 h)
            assert sim.dataset.attrs["stopped"] == 1
            assert sim.dataset.attrs["stop_time"] == pytest.approx(2 * np.cos(cmg.SKEW), abs=1e-5)
            assert sim.dataset["time"].values[-1] == sim.dataset.attrs["stop_time"]
        run = plan.send(sim)
    task = run.task
    assert isinstance(task, Simulation) and run.path == "runs['reorient']"
    assert isinstance(task.plant, GimbalCluster) and isinstance(task.law, NullMotionSteering)
    assert task.config.law_mode == "continuous" and task.config.n_steps == N_OUT - 1
    # σ = s[1, −1, 1, −1] has h ≡ 0 and the law moves s' = 45° − s: s = 45°(1 − e^{−t}) (V8)
    sim = simulate(task.plant, task.law, task.config, **task.options)
    t = sim.dataset["time"].values
    s = np.deg2rad(45.0) * (1.0 - np.exp(-t))
    np.testing.assert_allclose(
        sim.dataset["state"].values[0], s[:, None] * [1.0, -1.0, 1.0, -1.0], atol=1e-8
    )
    # the simulation comes back as the run's gimbal history; the V1–V8 table closes the plan
    assert plan.send(sim).label == "V1–V8 table"
    with pytest.raises(StopIteration) as done:
        plan.send(())
    result = done.value.value
    assert [r.label for r in result.runs] == ["zero", "preferred", "with null", "reorient"]
    np.testing.assert_array_equal(result.runs[-1].gimbals.sigma, sim.dataset["state"].values[0])
    assert result.runs[-1].outcome == "no singularity"


def test_a_singular_start_is_refused_by_the_pseudo_inverse_and_passed_by_the_sr_inverse():
    start = 'initial: ["-90 deg", "180 deg", "90 deg", "0 deg"]'  # V2: the +x envelope
    text = SMALL.replace('initial: zero, duration: "2 s"', start + ', duration: "2 s"')
    with pytest.raises(ScenarioError, match=r"runs\['zero'\].*starts singular.*alpha > 0"):
        run_scenario(load_scenario(text))
    sr = text.replace("steering: pi", "steering: sr, alpha: 1.0e-3")
    result = run_scenario(load_scenario(sr))
    row = result.metrics_records()[0]
    assert row["singular"] and row["end_time_s"] == pytest.approx(2.0)  # ran the whole time
    # the SR inverse gives no rate along the singular direction: the demand beyond the
    # envelope is not delivered, the momentum stays on it (3.1546 h) with finite rates
    assert row["final_momentum_along_demand_h"] == pytest.approx(row["envelope_h"], abs=1e-6)
    assert np.isfinite(row["peak_gimbal_rate_rad_s"])


def test_the_station_scenario_contrasts_zero_gimbals_with_the_alternate_set():
    result = run_scenario(load_scenario(STATION))
    rows = {r["run"]: r for r in result.metrics_records()}
    # V9 (tests/cases/test_space_station_cmg.py): singular at 494 s from σ(0) = 0, none from
    # [45, −45, 45, −45]° (a quarter orbit here)
    assert rows["zero"]["singular"] and rows["zero"]["singular_time_s"] == pytest.approx(
        494.3, abs=1.0
    )
    assert rows["zero"]["internal"]
    assert not rows["alternate"]["singular"]
    ds = result.dataset()
    assert np.isnan(ds["gain"].sel(run="zero").values[-1])  # stopped at the singularity
    assert np.all(np.isfinite(ds["gain"].sel(run="alternate").values))


@pytest.mark.parametrize(
    "change, message",
    [
        (('skew: "54.74 deg"', 'skew: "54.74 furlong"'), "cluster.skew"),
        (('skew: "54.74 deg"', 'skew: "95 deg"'), r"cluster.skew: must lie in \(0, 90°\)"),
        (
            ('gimbal_rate_limit: "3 rad/s"', 'gimbal_rate_limit: "0 rad/s"'),
            "cluster.gimbal_rate_limit: must be > 0",
        ),
        (
            ('gimbal_rate_limit: "3 rad/s"', 'gimbal_rate_limit: "-1 deg/s"'),
            "cluster.gimbal_rate_limit: must be > 0",
        ),
        (("steering: pi", "steering: newton"), "cluster.steering"),
        (("steering: pi", "steering: sr, alpha: 0"), "cluster.alpha"),
        (("n_units: 4", "n_units: 2"), "cluster.n_units: must be an integer in"),
        (
            ('initial: zero, duration: "2 s"', 'initial: random, duration: "2 s"'),
            r"runs\['zero'\].initial: must be one of",
        ),
        (
            ('initial: zero, duration: "2 s"', 'initial: [1, 2, 3], duration: "2 s"'),
            r"runs\['zero'\]: gimbal sets need 4 angles",
        ),
        (
            ('demand: [1, 0, 0], initial: zero, duration: "2 s"', 'initial: zero, duration: "2 s"'),
            r"runs\['zero'\].*demand: give a torque demand or reorient_to",
        ),
        (
            ("demand: [1, 0, 0], initial: preferred", "demand: [0, 0, 0], initial: preferred"),
            r"runs\['preferred'\].*'preferred' needs a demand",
        ),
        (
            (
                "demand: [1, 0, 0], initial: zero, duration",
                "demand: [1, 0], initial: zero, duration",
            ),
            r"runs\['zero'\].demand",
        ),
        (('duration: "2 s"', 'duration: "-2 s"'), r"runs\['zero'\].duration"),
        (("label: preferred", "label: zero"), "runs: duplicate label 'zero'"),
        (("steering: pi,", "steering: pi, colour: red,"), "cluster.colour: unknown key"),
    ],
)
def test_schema_mistakes_are_named(change, message):
    old, new = change
    assert old in SMALL
    with pytest.raises(ScenarioError, match=message):
        load_scenario(SMALL.replace(old, new))


@pytest.mark.parametrize(
    "change, message",
    [
        (("orbits: 0.25", "orbits: 0"), "simulation.orbits"),
        (("disturbance: aero_substitute", "disturbance: AERO1"), "simulation.disturbance"),
        (("initial: alternate", "initial: [1, 2]"), r"runs\['alternate'\].initial: the station"),
        (
            ("runs:", 'station: {rotor_momentum: "-3500 lbf*ft*s"}\nruns:'),
            "station.rotor_momentum: must be > 0",
        ),
        (("runs:", "station: {inertia: [1, 2]}\nruns:"), "inertia: three principal moments"),
        (("runs:", 'lqr: {attitude: "0 deg"}\nruns:'), "lqr.attitude: must be > 0"),
    ],
)
def test_station_schema_mistakes_are_named(change, message):
    old, new = change
    assert old in STATION
    with pytest.raises(ScenarioError, match=message):
        load_scenario(STATION.replace(old, new))


def test_an_uncontrollable_filter_choice_is_reported_against_lqr():
    text = STATION.replace("runs:", "lqr: {roll_yaw_filters: [1, 2]}\nruns:")
    with pytest.raises(ScenarioError, match="lqr.*roll_yaw_filters.*not stabilizable"):
        run_scenario(load_scenario(text))


@pytest.mark.parametrize(
    "change, message",
    [
        (
            ("demand: [1, 0, 0], initial: zero", "demand: [1e308, 0, 0], initial: zero"),
            r"runs\['zero'\].demand: components must be at most 100",
        ),
        (('duration: "2 s"', 'duration: "1e12 s"'), r"runs\['zero'\].duration: at most 3600 s"),
        (
            (
                "demand: [1, 0, 0], initial: zero",
                "demand: {constant: [0, 1, 0], frequency: 1e9}, initial: zero",
            ),
            "frequency: must lie in",
        ),
        (
            ('initial: zero, duration: "2 s"', 'initial: [.nan, 0, 0, 0], duration: "2 s"'),
            r"runs\['zero'\].initial: angles must be finite",
        ),
        (
            ('initial: zero, duration: "2 s"', 'initial: ["5 furlong", 0, 0, 0], duration: "2 s"'),
            r"runs\['zero'\].initial: incompatible units",
        ),
    ],
)
def test_extreme_values_are_refused_before_anything_runs(change, message):
    # bounds that keep a run's integrator work finite (|T| × duration) are part of the schema
    old, new = change
    with pytest.raises(ScenarioError, match=message):
        load_scenario(SMALL.replace(old, new))
