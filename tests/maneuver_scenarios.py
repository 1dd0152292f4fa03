"""A small maneuver scenario and the errors of preparing one, shared by the tests of the
maneuver kind (tests/scenarios/test_maneuver_kind.py) and of the runner
(tests/scenarios/test_runner.py)."""

from __future__ import annotations

import pytest
import yaml

from flexsat.scenarios import ScenarioError, default_scenario, load_scenario, prepare_scenario


def small_data() -> dict:
    """The default scenario as a dict, with a 3-mode model and a 2 s run (fast)."""
    data = yaml.safe_load(default_scenario().yaml_text)
    data["model"]["n_modes"] = 3
    data["simulation"]["duration"] = "2 s"
    return data


def error_of(source) -> ScenarioError:
    """The ScenarioError that loading and preparing ``source`` raises (a dict is dumped to YAML
    first)."""
    text = yaml.safe_dump(source) if isinstance(source, dict) else source
    with pytest.raises(ScenarioError) as info:
        prepare_scenario(load_scenario(text))
    return info.value


def problem(source) -> str:
    """The one problem line of :func:`error_of` ``source``."""
    error = error_of(source)
    assert len(error.problems) == 1, error.problems
    return error.problems[0]
