"""Running a scenario (flexsat.scenarios.runner): nothing runs when any run is invalid; a
diverging run is named and exits 1, writing nothing; a case without a maneuver model is refused
at load. Preparing a maneuver scenario (its kind's stage 2) is tested in
tests/scenarios/test_maneuver_kind.py."""

from __future__ import annotations

import pytest
import yaml
from typer.testing import CliRunner

import flexsat.scenarios.runner as scenario_module
from flexsat.cli import app
from flexsat.scenarios import (
    ScenarioError,
    load_scenario,
    maneuver_cases,
    run_scenario,
)
from flexsat.sim import SimulationDiverged
from maneuver_scenarios import problem, small_data

runner = CliRunner()


# -- the runner ---------------------------------------------------------------------------------
def test_nothing_runs_when_any_run_is_invalid(monkeypatch):
    calls = []
    monkeypatch.setattr(scenario_module, "simulate", lambda *a, **k: calls.append(a))
    data = small_data()
    data["runs"][1]["gains"]["g1"] = -1
    with pytest.raises(ScenarioError):
        run_scenario(load_scenario(yaml.safe_dump(data)))
    assert calls == []


# -- divergence -----------------------------------------------------------------------------------
def unstable_data() -> dict:
    """A PD run whose gains destabilise the sampled loop (kd dt / I ≫ 2), no torque limit."""
    data = small_data()
    data["actuator"] = {}
    data["runs"] = [{"label": "too stiff", "law": "pd", "gains": {"kp": 1e9, "kd": 1e7}}]
    return data


def test_diverging_run_is_named_and_raises():
    with pytest.raises(SimulationDiverged) as info:
        run_scenario(load_scenario(yaml.safe_dump(unstable_data())))
    message = str(info.value)
    assert message.startswith("runs['too stiff']: simulation diverged at t = ")
    assert "the feedback gains destabilise it at the 75 Hz control rate" in message


def test_cli_run_exits_1_and_writes_nothing_when_a_run_diverges(tmp_path):
    path = tmp_path / "unstable.yaml"
    path.write_text(yaml.safe_dump(unstable_data()))
    out = tmp_path / "out"
    result = runner.invoke(app, ["run", str(path), "-o", str(out)])
    assert result.exit_code == 1
    assert "runs['too stiff']: simulation diverged" in result.stderr
    assert "Traceback" not in result.output
    assert not out.exists()


# -- the case -------------------------------------------------------------------------------------
def test_case_without_a_maneuver_model_is_refused_at_load():
    data = small_data()
    data["case"] = "eps"
    del data["case_overrides"], data["model"]
    assert problem(data) == (
        "case: 'eps' has no maneuver model (a hub plant to slew); cases with one: tamu, nps"
    )
    assert set(maneuver_cases()) == {"tamu", "nps"}
