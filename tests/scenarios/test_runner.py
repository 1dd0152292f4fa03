"""Claims: every malformed scenario file and every run beyond flexsat.limits ends in one clear
ScenarioError naming the field, before anything runs; a diverging run exits 1 and writes
nothing."""

from __future__ import annotations

import copy
import time
from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

from flexsat.cli import app
from flexsat.scenarios import (
    ScenarioError,
    default_scenario,
    load_scenario,
    maneuver_cases,
    prepare_scenario,
    run_scenario,
)
from flexsat.sim import SimulationDiverged

runner = CliRunner()


def small_data() -> dict:
    """The default scenario as a dict, with a 3-mode model and a 2 s run (fast)."""
    data = yaml.safe_load(default_scenario().yaml_text)
    data["model"]["n_modes"] = 3
    data["simulation"]["duration"] = "2 s"
    return data


def problem(source) -> str:
    """The one problem line of the ScenarioError that loading and preparing ``source`` raises
    (a dict is dumped to YAML first)."""
    text = yaml.safe_dump(source) if isinstance(source, dict) else source
    with pytest.raises(ScenarioError) as info:
        prepare_scenario(load_scenario(text))
    assert len(info.value.problems) == 1, info.value.problems
    return info.value.problems[0]


def changed(section: str, **values) -> dict:
    data = small_data()
    data[section].update(values)
    return data


# -- item 3: numbers with bounds -------------------------------------------------------------------
@pytest.mark.parametrize("data, expected", [
    (changed("simulation", duration="1e12 s"),
     "simulation.duration: control samples (duration × control_rate) = 7.5e+13, above the limit "
     "2,000,000 (flexsat.limits); shorten the run or lower the control rate"),
    (changed("simulation", seed=1e29),
     "simulation.seed: must be an integer in [0, 4294967295], got 1e+29"),
    (changed("simulation", seed=1.5), "simulation.seed: must be an integer in [0, 4294967295], "
                                      "got 1.5"),
    (changed("model", n_modes=100_000), "model.n_modes: modes per appendage = 1e+05, above the "
                                        "limit 100 (flexsat.limits)"),
    (changed("sensors", rate_window=True), "sensors.rate_window: must be an integer in "
                                           "[1, 1000], got True"),
    (changed("maneuver", angle="1e12 rad"), "maneuver.angle: a slew of at most ten turns "
                                            "(62.83 rad) either way, got 1e+12 rad"),
    (changed("actuator", torque_constant_ratio=1e300), "actuator.torque_constant_ratio: actual "
                                                       "/ nominal torque constant, at most 10, "
                                                       "got 1e+300"),
])
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
    assert problem(data) == ("case_overrides.n_modes: modes per appendage = 1e+05, above the "
                             "limit 100 (flexsat.limits)")


def test_memory_of_all_runs_together_is_checked(monkeypatch):
    from flexsat import limits

    # 2 s at 75 Hz = 151 samples, 2 runs of one case, 29 values of 8 B each: 70,064 B
    monkeypatch.setattr(limits, "MAX_MEMORY", 70_000)
    assert problem(small_data()).startswith(
        "simulation.duration: a run of 151 samples × 2 cases × 29 values needs about 68.4 kB of "
        "memory")


def test_numerical_failure_of_the_case_model_is_a_scenario_error():
    data = small_data()
    data["case_overrides"]["tip_radius"] = 1e300
    assert problem(data).startswith("case_overrides: the tamu model cannot be built from these "
                                    "values (OverflowError")


def test_too_many_runs_are_refused():
    data = small_data()
    data["runs"] = [dict(data["runs"][0], label=f"run {i}") for i in range(101)]
    assert problem(data).startswith("runs: List should have at most 100 items")


# -- item 4: divergence -----------------------------------------------------------------------------
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


# -- item 5: scenario files -------------------------------------------------------------------------
def test_non_utf8_bytes_are_refused(tmp_path):
    path = tmp_path / "latin1.yaml"
    path.write_bytes(default_scenario().yaml_text.encode() + "# café\n".encode("latin-1"))
    assert problem(path) == (f"scenario: {str(path)!r} is not UTF-8 text (byte 0xe9 at offset "
                             f"{len(default_scenario().yaml_text.encode()) + 5}); save it as UTF-8")


def test_1000_levels_of_nesting_are_refused_before_the_parser_recurses():
    text = default_scenario().yaml_text + "extra: " + "[" * 1000 + "]" * 1000 + "\n"
    assert default_scenario().yaml_text.count("\n") == 18  # so the nesting is on line 19
    assert problem(text) == ("scenario: nested deeper than 32 levels at line 19 "
                             "(flexsat.limits.MAX_NESTING)")


def test_duplicate_keys_are_refused_naming_the_key_and_lines():
    text = default_scenario().yaml_text.replace("seed: 0}", "seed: 0, seed: 7}")
    assert problem(text) == "simulation.seed: duplicate key (lines 8 and 8); give it once"
    assert problem(default_scenario().yaml_text + "\nname: again\n") == (
        "name: duplicate key (lines 3 and 20); give it once")


def test_anchors_and_merge_keys_still_work():
    text = default_scenario().yaml_text.replace(
        "gains: {g1: \"600 ozf*in/rad\"", "gains: &law1 {g1: \"600 ozf*in/rad\"")
    assert load_scenario(text).runs[0].gains.g1 > 0
    merged = ("base: &b {duration: 2 s, control_rate: 75 Hz}\n"
              "simulation: {<<: *b, duration: 1 s}\n")
    assert yaml.safe_load(merged)["simulation"]["duration"] == "1 s"
    with pytest.raises(ScenarioError) as info:  # other problems, but no duplicate: an
        load_scenario(merged)                   # override of a merged key is YAML's own rule
    assert not [p for p in info.value.problems if "duplicate" in p]


def test_aliases_expanding_beyond_the_limit_are_refused():
    text = "a: &a [" + ", ".join(["1"] * 10) + "]\n"
    for level in "bcde":
        previous = chr(ord(level) - 1)
        text += f"{level}: &{level} [" + ", ".join([f"*{previous}"] * 10) + "]\n"
    assert problem(text) == ("d: more than 10,000 values once aliases are expanded "
                             "(flexsat.limits.MAX_DOCUMENT_NODES)")


def test_oversized_document_is_refused():
    assert problem("#" * 300_000) == ("scenario: the document is larger than 256,000 bytes "
                                      "(flexsat.limits.MAX_DOCUMENT_BYTES); a scenario is a few kB")


def test_case_without_a_maneuver_model_is_refused_at_load():
    data = small_data()
    data["case"] = "eps"
    del data["case_overrides"], data["model"]
    assert problem(data) == ("case: 'eps' has no maneuver model (a hub plant to slew); cases "
                             "with one: tamu, nps")
    assert set(maneuver_cases()) == {"tamu", "nps"}


# -- identification scenarios ---------------------------------------------------------------------
IDENTIFICATION = yaml.safe_load(
    (Path(__file__).resolve().parents[2] / "examples" / "tamu_grid_identification.yaml")
    .read_text())


@pytest.mark.parametrize("section, values, expected", [
    ("wheels", {"duration": "1e9 s"}, "wheels.duration: samples (duration × sample_rate) = 5e+10, "
                                      "above the limit 2,000,000 (flexsat.limits); shorten the "
                                      "test or lower the sample rate"),
    ("hammer", {"sample_rate": "-200 Hz"}, "hammer.sample_rate: must be > 0, got -200"),
    ("video", {"field_rate": "1e12 Hz"}, "video.duration: samples (duration × field_rate) = "
                                         "4.5e+12, above the limit 2,000,000"),
    ("identification", {"bootstrap_samples": 1e9}, "identification.bootstrap_samples: must be an "
                                                   "integer in [0, 1000], got 1000000000.0"),
])
def test_identification_tests_beyond_the_limits_are_refused_at_load(section, values, expected):
    data = copy.deepcopy(IDENTIFICATION)
    data[section].update(values)
    with pytest.raises(ScenarioError) as info:
        load_scenario(yaml.safe_dump(data))
    assert len(info.value.problems) == 1 and info.value.problems[0].startswith(expected)


def test_identification_seed_is_bounded():
    data = dict(IDENTIFICATION, seed=1e29)
    with pytest.raises(ScenarioError, match=r"seed: must be an integer in \[0, 4294967295\], got "
                                            r"1e\+29"):
        load_scenario(yaml.safe_dump(data))
