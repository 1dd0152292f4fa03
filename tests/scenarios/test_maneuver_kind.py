"""The maneuver kind (:mod:`flexsat.scenarios.maneuver_kind`): stage 2 of the validation,
:func:`prepare_scenario` building the case, the controllers and the configuration -- case
parameters, gains, numbers and runs beyond :mod:`flexsat.limits` end in one ScenarioError naming
the field, before anything runs -- and :class:`ManeuverKind` planning one simulation per run
whose outcomes come back to the result in the scenario's order."""

from __future__ import annotations

import time

import numpy as np
import pytest
import yaml

from flexsat.scenarios import ScenarioError, load_scenario, prepare_scenario
from flexsat.scenarios.kind import Simulation
from flexsat.scenarios.maneuver_kind import ManeuverKind, ManeuverResult
from maneuver_scenarios import error_of, problem, small_data


def problems_of(mutate) -> str:
    """The ScenarioError message of the small scenario changed by ``mutate(data)``."""
    data = small_data()
    mutate(data)
    return str(error_of(data))


def changed(section: str, **values) -> dict:
    data = small_data()
    data[section].update(values)
    return data


# -- planning -------------------------------------------------------------------------------------
def test_plan_yields_one_simulation_per_run_and_returns_their_outcomes_in_order():
    scenario = load_scenario(yaml.safe_dump(small_data()))
    prepared = prepare_scenario(scenario)
    plan = ManeuverKind().plan(scenario)
    assert ManeuverKind().steps(scenario) == 2
    run = next(plan)
    seen = []
    try:
        while True:
            # each run is the prepared model under its own controller, named by its label
            assert isinstance(run.task, Simulation)
            assert run.task.config == prepared.config
            assert run.task.plant.n_modes == prepared.model.n_modes
            seen.append((run.label, run.path, type(run.task.law).__name__))
            run = plan.send(f"outcome of {run.label}")
    except StopIteration as done:
        result = done.value
    assert [(label, path) for label, path, _ in seen] == [
        ("Law I", "runs['Law I']"),
        ("Law II", "runs['Law II']"),
    ]
    assert [law for *_, law in seen] == [
        type(prepared.controllers[label]).__name__ for label in ("Law I", "Law II")
    ]
    assert isinstance(result, ManeuverResult)
    assert result.results == ("outcome of Law I", "outcome of Law II")


def test_plan_refuses_before_yielding_anything():
    data = small_data()
    data["runs"][0]["gains"]["g1"] = -1
    plan = ManeuverKind().plan(load_scenario(yaml.safe_dump(data)))
    with pytest.raises(ScenarioError, match=r"runs\['Law I'\]\.gains\.g1: must be >= 0"):
        next(plan)


# -- building the case and the controllers ---------------------------------------------------------
def test_prepare_builds_model_config_and_controllers():
    plan = prepare_scenario(load_scenario(yaml.safe_dump(small_data())))
    assert plan.model.n_modes == 3
    assert list(plan.controllers) == ["Law I", "Law II"]
    assert plan.controllers["Law II"].reference.alpha == pytest.approx(0.2)


def test_pd_poles_are_cyclic_and_use_the_reference_inertia():
    data = small_data()
    data["runs"].append(
        {
            "label": "PD",
            "law": "pd",
            "poles": {"natural_frequency": "0.06 Hz", "damping_ratio": 0.9},
            "reference": {"shape": "sinusoidal", "duration": "10 s"},
        }
    )
    plan = prepare_scenario(load_scenario(yaml.safe_dump(data)))
    pd = plan.controllers["PD"]
    wn = 2 * np.pi * 0.06
    assert float(pd.kp) == pytest.approx(plan.case.reference_inertia * wn**2)
    assert float(pd.kd) == pytest.approx(2 * 0.9 * wn * plan.case.reference_inertia)
    assert float(pd.reference.duration) == pytest.approx(10.0)


@pytest.mark.parametrize(
    "key, value, expected",
    [
        ("hub_inertia", "-5 ozf*in*s**2", "case_overrides.hub_inertia: must be > 0"),
        ("tip_mass", -1.0, "case_overrides.tip_mass: must be >= 0"),
        ("density", 0, "case_overrides.density: must be > 0"),
        ("modulus", "-1 psi", "case_overrides.modulus: must be > 0"),
    ],
)
def test_non_positive_inertia_mass_stiffness(key, value, expected):
    assert expected in problems_of(lambda d: d["case_overrides"].update({key: value}))


def test_unknown_case_parameter_comes_from_the_builder():
    message = problems_of(lambda d: d["case_overrides"].update(hub_mass=1))
    assert "case_overrides: tamu: unknown parameter(s) ['hub_mass']" in message


def test_model_options_are_checked_by_the_builder():
    assert "model.n_modes: must be a positive integer, got 0" in problems_of(
        lambda d: d["model"].update(n_modes=0)
    )


@pytest.mark.parametrize(
    "run, gain, value, expected",
    [
        (0, "g1", -1.0, "runs['Law I'].gains.g1: must be >= 0"),
        (1, "g2", "-800 ozf*in*s/rad", "runs['Law II'].gains.g2: must be >= 0"),
        (1, "g3", -4, "runs['Law II'].gains.g3: must be > -4 (= -n_appendages)"),
    ],
)
def test_inadmissible_gains(run, gain, value, expected):
    assert expected in problems_of(lambda d: d["runs"][run]["gains"].update({gain: value}))


def test_all_problems_are_collected():
    def mutate(d):
        d["maneuver"]["angle"] = "40 kg"
        d["simulation"]["integration_step"] = "1 s"
        d["runs"][0]["gains"]["g1"] = -1

    message = problems_of(mutate)
    assert "invalid scenario (2 problems)" in message  # schema stage stops before the gains
    data = small_data()
    data["runs"][0]["gains"]["g1"] = -1
    data["runs"][1]["gains"]["g3"] = -5
    with pytest.raises(ScenarioError) as info:
        prepare_scenario(load_scenario(yaml.safe_dump(data)))
    assert len(info.value.problems) == 2


# -- stage 2 and resources: numbers with bounds ---------------------------------------------------
@pytest.mark.parametrize(
    "data, expected",
    [
        (
            changed("simulation", duration="1e12 s"),
            "simulation.duration: control samples (duration × control_rate) = 7.5e+13, "
            "above the limit "
            "2,000,000 (flexsat.limits); shorten the run or lower the control rate",
        ),
        (
            changed("simulation", seed=1e29),
            "simulation.seed: must be an integer in [0, 4294967295], got 1e+29",
        ),
        (
            changed("simulation", seed=1.5),
            "simulation.seed: must be an integer in [0, 4294967295], got 1.5",
        ),
        (
            changed("model", n_modes=100_000),
            "model.n_modes: modes per appendage = 1e+05, above the limit 100 (flexsat.limits)",
        ),
        (
            changed("sensors", rate_window=True),
            "sensors.rate_window: must be an integer, not a boolean, got True",
        ),
        (
            changed("maneuver", angle="1e12 rad"),
            "maneuver.angle: a slew of at most ten turns (62.83 rad) either way, got 1e+12 rad",
        ),
        (
            changed("actuator", torque_constant_ratio=1e300),
            "actuator.torque_constant_ratio: actual "
            "/ nominal torque constant, at most 10, "
            "got 1e+300",
        ),
    ],
)
def test_numbers_beyond_their_bounds_are_refused_at_load(data, expected):
    assert problem(data) == expected


def test_stiff_friction_is_refused_before_it_hangs():
    data = small_data()
    data["disturbances"]["friction"]["coulomb"] = 1e30
    start = time.perf_counter()
    message = problem(data)
    assert time.perf_counter() - start < 5.0  # was an unbounded substep loop
    assert message.startswith("disturbances.friction: a stable integration of the friction")
    assert "needs substeps per control period = 2.272e+31, above the limit 1,000" in message


def test_modes_through_case_overrides_are_refused_before_the_model_is_built():
    data = small_data()
    del data["model"]["n_modes"]
    data["case_overrides"]["n_modes"] = 100_000
    assert problem(data) == (
        "case_overrides.n_modes: modes per appendage = 1e+05, above the limit 100 (flexsat.limits)"
    )


def test_memory_of_all_runs_together_is_checked(monkeypatch):
    from flexsat import limits

    # 2 s at 75 Hz = 151 samples, 2 runs of one case, 13 histories and the loop's 32-sample
    # buffer of 8 states + 3 noise streams, 8 B each: 8 × 2 × (151 × 13 + 32 × 11) = 37,040 B
    monkeypatch.setattr(limits, "MAX_MEMORY", 37_000)
    assert problem(small_data()).startswith(
        "simulation.duration: a run of 151 samples × 2 cases × 13 values (and a 32-sample buffer "
        "of 11) needs about 36.2 kB of memory"
    )


def test_numerical_failure_of_the_case_model_is_a_scenario_error():
    data = small_data()
    data["case_overrides"]["tip_radius"] = 1e300
    assert problem(data).startswith(
        "case_overrides: the tamu model cannot be built from these values (OverflowError"
    )


def test_too_many_runs_are_refused():
    data = small_data()
    data["runs"] = [dict(data["runs"][0], label=f"run {i}") for i in range(101)]
    assert problem(data).startswith("runs: List should have at most 100 items")
