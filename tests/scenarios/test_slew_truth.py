"""The slew kind's truth plant and sensors (flexsat.scenarios.slew): the simulated plant
dispersed from the case's plant while the nominal maneuver and the designs stay on the case's
plant (kept once per nominal setup), its departures checked against the plant's own
parameters, the sensors' noise drawn from the seed, and every mistake named."""

import numpy as np
import pytest
import yaml

from flexsat.scenarios import ScenarioError, load_scenario, run_scenario, slew
from flexsat.scenarios.batch_cases import case_metrics

#: a cheap slew (12 plant modes, 4 designed, 6 s at 50 Hz) with a truth section and sensors
SMALL = """
kind: slew
name: small dispersed slew
case: eps
plant: {n_modes: 12}
truth: {inertia_scale: [1.0, 1.0, 1.0], frequency_scale: 1.0}
sensors: {rate: {noise: "1e-5 rad/s"}, attitude: {noise: 1.0e-5}}
maneuver:
  target: {euler123: ["0.5 rad", "0.5 rad", "0.5 rad"]}
  duration: "6 s"
  break_frequency: "5 rad/s"
controller: {modes: 4, linearization_points: 7}
simulation: {duration: "7.5 s", control_rate: "50 Hz", seed: 1}
runs:
  - label: torquers
    weights: {attitude: 1000, rate: 1000, modes: 1, torque: 50}
    break_frequency: "5 rad/s"
"""


def _document(**changes) -> str:
    """SMALL with sections' keys replaced: ``truth={"damping": 0.01}``."""
    data = yaml.safe_load(SMALL)
    for section, values in changes.items():
        if isinstance(values, dict):
            data[section] = {**data[section], **values}
        else:
            data[section] = values
    return yaml.safe_dump(data)


def _plants(text: str):
    """(case plant, truth plant) of a document."""
    scenario = load_scenario(text)
    kept = slew.nominal_design(scenario)
    if "plant" not in kept:
        run_plan_to_first_run(scenario)
    return kept["plant"], slew.truth_plant(scenario, kept["plant"])


def run_plan_to_first_run(scenario) -> None:
    plan = slew.SlewKind().plan(scenario)
    next(plan)
    plan.close()


def test_the_truth_scales_the_principal_moments_and_the_frequencies():
    """J' = R diag(s λ) Rᵀ: the principal moments of the truth are s λ (to eigh's backward
    error, ~1e-12 relative here) about the same axes; Ω' = s_Ω Ω; the modal damping is 2ζΩ'
    with the given ζ; the mode shapes (outputs, coupling) are the case's."""
    scale = [0.96, 1.04, 1.02]
    plant, truth = _plants(
        _document(truth={"inertia_scale": scale, "frequency_scale": 0.92, "damping": 0.002})
    )
    moments, axes = np.linalg.eigh(plant.inertia)
    rotated = axes.T @ truth.inertia @ axes
    assert np.allclose(np.diag(rotated), np.array(scale) * moments, rtol=1e-12)
    assert np.allclose(rotated - np.diag(np.diag(rotated)), 0.0, atol=1e-12 * moments.max())
    omega = np.sqrt(plant.stiffness)
    assert np.allclose(np.sqrt(truth.stiffness), 0.92 * omega, rtol=1e-14)
    assert np.allclose(truth.damping, 2 * 0.002 * 0.92 * omega, rtol=1e-14)
    assert np.array_equal(truth.coupling, plant.coupling)
    assert [c.name for c in truth.outputs] == [c.name for c in plant.outputs]


def test_per_mode_factors_and_no_departure():
    """One value per elastic mode; a truth section with every factor 1 and no damping is the
    case's plant itself."""
    factors = [float(f) for f in np.linspace(0.9, 1.1, 12)]
    plant, truth = _plants(_document(truth={"frequency_scale": factors, "damping": [0.01] * 12}))
    assert np.allclose(np.sqrt(truth.stiffness), np.array(factors) * np.sqrt(plant.stiffness))
    plant, same = _plants(SMALL)
    assert same is plant


def test_the_design_stays_on_the_case_plant_and_is_kept(monkeypatch):
    """Two documents differing in the truth, the sensors and the seed share one design
    fingerprint: the second runs without solving the maneuver or designing again, and its law
    is the first's (the gains of the case's plant), while its results differ. A change of a
    run's weights is another fingerprint."""
    import flexsat.control
    import flexsat.maneuvers

    calls = {"maneuver": 0, "design": 0}

    def counted(name, function):
        def wrapper(*args, **kwargs):
            calls[name] += 1
            return function(*args, **kwargs)

        return wrapper

    monkeypatch.setattr(
        flexsat.maneuvers, "three_axis_slew", counted("maneuver", flexsat.maneuvers.three_axis_slew)
    )
    monkeypatch.setattr(
        flexsat.control,
        "perturbation_design",
        counted("design", flexsat.control.perturbation_design),
    )
    nominal = load_scenario(_document(simulation={"seed": 77}))  # a setup not kept before
    dispersed = load_scenario(
        _document(
            truth={"inertia_scale": [1.03, 0.97, 1.0], "frequency_scale": 1.05},
            sensors={"rate": {"noise": "3e-5 rad/s"}},
            simulation={"seed": 78},
        )
    )
    fingerprint = slew.design_fingerprint(nominal)
    assert slew.design_fingerprint(dispersed) == fingerprint
    slew.nominal_design(nominal).clear()
    first = run_scenario(nominal)
    assert calls == {"maneuver": 1, "design": 1}
    second = run_scenario(dispersed)
    assert calls == {"maneuver": 1, "design": 1}
    assert second.nominal is first.nominal
    a, b = case_metrics(first), case_metrics(second)
    assert a["runs['torquers'].angle_error_mrad"] != b["runs['torquers'].angle_error_mrad"]
    heavier = load_scenario(SMALL.replace("torque: 50", "torque: 60"))
    assert slew.design_fingerprint(heavier) != fingerprint


def test_a_kept_design_gives_the_results_of_a_fresh_one(monkeypatch):
    """The same document run with its design kept from a run of another truth, and run with
    nothing kept (DESIGNS_KEPT = 0): the same metrics, bit for bit."""
    text = _document(truth={"frequency_scale": 0.95, "damping": 0.003})
    run_scenario(load_scenario(_document(truth={"frequency_scale": 1.05})))  # keeps the design
    kept = case_metrics(run_scenario(load_scenario(text)))
    monkeypatch.setattr(slew, "DESIGNS_KEPT", 0)
    fresh = case_metrics(run_scenario(load_scenario(text)))
    assert kept.keys() == fresh.keys()
    for name, value in kept.items():
        assert np.array_equal(value, fresh[name], equal_nan=True), name


def test_the_sensor_noise_is_drawn_from_the_seed():
    """The noisy sensors change the run, and their draw follows simulation.seed: the same seed
    repeats it, another seed does not; without noise the seed does not matter."""
    key = "runs['torquers'].angle_error_x_mrad"

    def metric(**changes):
        return case_metrics(run_scenario(load_scenario(_document(**changes))))[key]

    quiet = {"rate": {"noise": "0 rad/s"}, "attitude": {"noise": 0.0}}
    noisy = {"rate": {"noise": "1e-3 rad/s"}, "attitude": {"noise": 1e-3}}
    assert metric(sensors=quiet, simulation={"seed": 1}) == metric(
        sensors=quiet, simulation={"seed": 2}
    )
    one = metric(sensors=noisy, simulation={"seed": 1})
    assert one == metric(sensors=noisy, simulation={"seed": 1})
    assert one != metric(sensors=noisy, simulation={"seed": 2})
    assert one != metric(sensors=quiet, simulation={"seed": 1})


def test_the_goal_verdicts_are_metrics():
    """angle_goal_met, deflection_goal_met and goals_met (both) are numbers of metrics.json,
    each the rule on its metric: error within 3 % of 0.5 rad, ratio at least 10."""
    metrics = case_metrics(run_scenario(load_scenario(SMALL)))
    for run in ("open loop", "torquers"):
        p = f"runs[{run!r}]."
        angle = metrics[p + "angle_error_mrad"] <= 0.03 * 500.0
        deflection = metrics[p + "deflection_ratio_after"] >= 10.0
        assert metrics[p + "angle_goal_met"] == float(angle)
        assert metrics[p + "deflection_goal_met"] == float(deflection)
        assert metrics[p + "goals_met"] == float(angle and deflection)


@pytest.mark.parametrize(
    "changes, message",
    [
        (
            {"truth": {"frequency_scale": 0.0}},
            r"truth\.frequency_scale: must be a finite number > 0, got 0\.0",
        ),
        (
            {"truth": {"frequency_scale": [1.0, -0.5]}},
            r"truth\.frequency_scale: item 1 must be a finite number > 0, got -0\.5",
        ),
        ({"truth": {"inertia_scale": [1.0, 1.0]}}, r"truth\.inertia_scale: give one factor or 3"),
        (
            {"truth": {"damping": -0.01}},
            r"truth\.damping: must be a finite damping ratio >= 0, got -0\.01",
        ),
        ({"truth": {"stiffness": 2.0}}, r"truth\.stiffness: unknown key"),
    ],
)
def test_schema_mistakes_are_named(changes, message):
    with pytest.raises(ScenarioError, match=message):
        load_scenario(_document(**changes))


@pytest.mark.parametrize(
    "changes, message",
    [
        (
            # the EPS's principal moments (1.45, 9.07, 9.13) × 1e4 kg m²: the greatest × 1.2
            # exceeds the sum of the two others
            {"truth": {"inertia_scale": [1.0, 1.0, 1.2]}},
            r"truth\.inertia_scale: .*triangle inequality",
        ),
        (
            {"truth": {"frequency_scale": [1.0] * 5}},
            r"truth\.frequency_scale: give one value or 12 \(the plant's elastic modes\), got 5",
        ),
        (
            {"truth": {"damping": [0.01] * 13}},
            r"truth\.damping: give one value or 12 \(the plant's elastic modes\), got 13",
        ),
        (
            {"sensors": {"gyro": {"noise": "1e-5 rad/s"}}},
            r"sensors\.gyro: the plant has no output channel 'gyro' \(its channels: attitude",
        ),
        (
            {"sensors": {"rate": {"noise": "1e-5 m"}}},
            r"sensors\.rate\.noise: .*rad/s",
        ),
    ],
)
def test_plant_mistakes_are_named_before_any_run(changes, message):
    scenario = load_scenario(_document(**changes))
    with pytest.raises(ScenarioError, match=message):
        run_plan_to_first_run(scenario)
