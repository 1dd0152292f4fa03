"""Scenario problems (flexsat.scenarios.errors): one ScenarioError lists every problem, each a
``field.path: rule`` line whose path is built from pydantic's error location (runs named by
their label) and the field a runtime message already names."""

from __future__ import annotations

import pytest
from pydantic import ValidationError

from flexsat.scenarios import Scenario, ScenarioError
from flexsat.scenarios.errors import _allowed_keys, _loc_path, _locate, pydantic_problem


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
            "sensors, disturbances, runs",
        ),
        (
            ("sensors", "rate_windw"),
            "encoder_resolution, rate, rate_window, rate_order, gyro_noise, strain_noise",
        ),
        # through a list and an optional section
        (("runs", 0, "reference", "beta"), "shape, u_max, duration, alpha, rise_time"),
        (("disturbances", "friction", "stiction"), "coulomb, viscous, smoothing"),
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
