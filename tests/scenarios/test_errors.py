"""Scenario problems (flexsat.scenarios.errors): one ScenarioError lists every problem, each a
``field.path: rule`` line whose path is built from pydantic's error location (runs named by
their label) and the field a runtime message already names."""

from __future__ import annotations

import pickle

import pytest
import yaml
from pydantic import ValidationError

from flexsat.input_checks import FieldError
from flexsat.scenarios import (
    Problem,
    Scenario,
    ScenarioError,
    default_scenario,
    load_scenario,
    prepare_scenario,
)
from flexsat.scenarios.errors import _allowed_keys, _loc_path, _locate, locate, pydantic_problem


def test_the_error_counts_and_lists_its_problems():
    one = ScenarioError(["name: required"])
    assert str(one) == "invalid scenario (1 problem):\n  name: required"
    problems = ["a: x", "b.c: y"]
    two = ScenarioError(problems)
    assert str(two) == "invalid scenario (2 problems):\n  a: x\n  b.c: y"
    problems.append("d: z")  # the error keeps its own list
    assert two.problems == ["a: x", "b.c: y"]
    assert isinstance(two, ValueError)


@pytest.mark.parametrize(
    "path, message, expected",
    [
        # a runtime message names its own field: appended to the section's path
        ("runs['Law I'].gains", "g1: must be >= 0", "runs['Law I'].gains.g1: must be >= 0"),
        ("runs[0]", "gains.g1: required", "runs[0].gains.g1: required"),
        # the path already ends with that field: not repeated
        ("simulation.duration", "duration: must be > 0", "simulation.duration: must be > 0"),
        ("case", "case: unknown case 'x'", "case: unknown case 'x'"),
        # ... but only a whole path element counts ("n_modes" does not end with the field "modes")
        ("model.n_modes", "modes: bad", "model.n_modes.modes: bad"),
        # a message without a field name is about the path itself
        ("simulation", "must be finite", "simulation: must be finite"),
        (
            "runs[0]",
            "Input should be a valid dictionary",
            "runs[0]: Input should be a valid dictionary",
        ),
        # the empty path is the scenario
        ("", "must be a YAML mapping", "scenario: must be a YAML mapping"),
        ("", "name: required", "name: required"),
    ],
)
def test_locate_joins_the_path_and_the_message(path, message, expected):
    assert _locate(path, message) == expected


RUNS = {"runs": [{"label": "Law I"}, {"label": 7}, {}], "simulation": {"duration": 1}}


@pytest.mark.parametrize(
    "loc, expected",
    [
        (("simulation", "duration"), "simulation.duration"),
        (("runs", 0, "gains", "g1"), "runs['Law I'].gains.g1"),
        (("runs", 1, "law"), "runs[1].law"),  # a label that is not a string names nothing
        (("runs", 2, "law"), "runs[2].law"),  # no label
        (("runs", 9, "law"), "runs[9].law"),  # beyond the list (pydantic's location is kept)
        (("disturbances", "impulses", 0, "time"), "disturbances.impulses[0].time"),  # not in data
        ((), ""),
    ],
)
def test_loc_path_names_runs_by_their_label(loc, expected):
    assert _loc_path(loc, RUNS) == expected


def test_loc_path_of_a_document_that_is_not_a_mapping():
    assert _loc_path(("runs", 0, "label"), ["a list"]) == "runs[0].label"


@pytest.mark.parametrize(
    "loc, expected",
    [
        (
            ("colour",),
            "kind, name, case, case_overrides, model, maneuver, simulation, actuator, "
            "sensors, disturbances, hardware, runs",
        ),
        (
            ("sensors", "rate_windw"),
            "encoder_resolution, rate, rate_window, rate_order, gyro_noise, strain_noise",
        ),
        # through a list and an optional section
        (("runs", 0, "reference", "beta"), "shape, u_max, duration, alpha, rise_time"),
        (("disturbances", "friction", "stiction"), "coulomb, viscous, smoothing"),
        # the hardware section, through a mapping of channel sections
        (("hardware", "filters", "root_torque", "q"), "type, order, corner"),
        (
            ("runs", 1, "hardware", "wheels", "torque", "amplifier", "q"),
            "mode, gain, current_limit, bandwidth, torque_constant, dac_range, voltage_limit",
        ),
    ],
)
def test_allowed_keys_are_those_of_the_model_at_the_location(loc, expected):
    assert _allowed_keys(loc, Scenario) == expected


def test_allowed_keys_inside_a_mapping_of_channel_sections():
    """A key under ``disturbances.<channel>`` (a mapping of channel names to sections) is
    checked against the channel section's fields; found by the load-only property test."""
    from flexsat.scenarios.simulation import SimulationScenario

    allowed = _allowed_keys(("disturbances", "force", "colour"), SimulationScenario)
    assert "impulses" in allowed.split(", ")


def test_problem_uses_the_validators_own_message_not_pydantics_wrapper():
    data = {
        "name": "x",
        "case": "tamu",
        "maneuver": {"angle": "40 kg"},
        "simulation": {"duration": 1, "rate": 2},
        "runs": [],
    }
    with pytest.raises(ValidationError) as info:
        Scenario.model_validate(data)
    lines = sorted(pydantic_problem(error, data, Scenario) for error in info.value.errors())
    assert lines[0] == "maneuver.angle: incompatible units (kilogram given, rad expected)"
    assert lines[1].startswith("runs: List should have at least 1 item")
    assert lines[2] == (
        "simulation.rate: unknown key (allowed: duration, control_rate, "
        "integration_step, settling_band, seed)"
    )
    assert len(lines) == 3


# -- problems as records, fields as data -------------------------------------------------------
def test_a_problem_is_a_record_that_reads_as_its_line():
    problem = Problem("runs['Law I'].gains.g1", "must be >= 0, got -1")
    assert (problem.path, problem.rule) == ("runs['Law I'].gains.g1", "must be >= 0, got -1")
    assert problem == "runs['Law I'].gains.g1: must be >= 0, got -1"
    assert Problem("", "must be a YAML mapping") == "scenario: must be a YAML mapping"
    assert pickle.loads(pickle.dumps(problem)).path == problem.path  # dask workers
    error = pickle.loads(pickle.dumps(ScenarioError([problem])))
    assert error.problems[0].path == problem.path and str(error).endswith(str(problem))


def test_locate_takes_the_field_of_a_field_error_as_data():
    """The field travels as an attribute: a field the text form could not name (an indexed
    one) is placed all the same, and a rule that itself looks like ``word: ...`` is kept."""
    assert locate("runs['a'].gains", FieldError("g1", "must be >= 0")) == (
        "runs['a'].gains.g1: must be >= 0"
    )
    indexed = locate("cameras", FieldError("lens[2]", "must be > 0"))
    assert (indexed.path, indexed.rule) == ("cameras.lens[2]", "must be > 0")
    tricky = locate("runs[0]", FieldError("k", "note: a rule with a colon"))
    assert (tricky.path, tricky.rule) == ("runs[0].k", "note: a rule with a colon")
    assert locate("simulation.duration", FieldError("duration", "x")).path == "simulation.duration"


def test_input_checks_and_limits_raise_field_errors():
    from flexsat import limits
    from flexsat.input_checks import require_positive

    with pytest.raises(FieldError) as info:
        require_positive(-1.0, "hub_inertia", "kg*m**2")
    assert info.value.field == "hub_inertia" and str(info.value).startswith("hub_inertia: ")
    with pytest.raises(FieldError) as info:
        limits.check_count(10, 5, "duration", "samples")
    assert info.value.field == "duration"
    assert info.value.rule == "samples = 10, above the limit 5 (flexsat.limits)"


def test_a_resource_limit_is_placed_by_the_field_it_names():
    """check_resources names the SimConfig input (``duration``); the maneuver document says
    where that input comes from (``simulation.duration``), no message is parsed."""
    data = yaml.safe_load(default_scenario().yaml_text)
    # 1e6 control samples (within MAX_SAMPLES) x 100 substeps: 1e8 integrator steps
    data["simulation"]["duration"] = "1e4 s"
    data["simulation"]["control_rate"] = "100 Hz"
    data["simulation"]["integration_step"] = "1e-4 s"
    with pytest.raises(ScenarioError) as info:
        prepare_scenario(load_scenario(yaml.safe_dump(data)))
    (problem,) = info.value.problems
    assert problem.path == "simulation.duration"
    assert problem.rule.startswith("integrator steps (")
