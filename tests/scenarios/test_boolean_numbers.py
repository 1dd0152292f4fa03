"""A YAML ``true``/``false`` where a scenario takes a number is refused, naming the field, for
every kind (issue 21): pydantic's lax mode read it as 1 or 0, so ``orbits: true`` ran one orbit
and ``gains: {K1: true}`` a gain of 1. The refusal is one validator of every schema section
(:class:`flexsat.scenarios.fields.SchemaSection`)."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from flexsat.scenarios import ScenarioError, load_scenario

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def _problems(example: str, path: list[str | int], value: object) -> list:
    doc = yaml.safe_load((EXAMPLES / example).read_text())
    node = doc
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = value
    with pytest.raises(ScenarioError) as info:
        load_scenario(yaml.safe_dump(doc, sort_keys=False))
    return info.value.problems


@pytest.mark.parametrize(
    "example, path, value, field, rule",
    [
        # cmg: a gimbal skew angle, a demand component, a harmonic frequency, a gain, a duration
        ("cmg_preferred_angles.yaml", ["cluster", "skew"], True, "cluster.skew", "number"),
        (
            "cmg_preferred_angles.yaml",
            ["runs", 4, "demand", "frequency"],
            True,
            ".frequency",
            "number",
        ),
        (
            "cmg_preferred_angles.yaml",
            ["runs", 2, "null_motion", "gain"],
            True,
            ".null_motion.gain",
            "number",
        ),
        ("cmg_preferred_angles.yaml", ["runs", 0, "duration"], False, ".duration", "number"),
        # maneuver: a gain with a unit, a plain gain, a shaping parameter, a count, a torque
        ("tamu_40deg.yaml", ["runs", 0, "gains", "g1"], True, "runs['Law I'].gains.g1", "number"),
        ("tamu_40deg.yaml", ["runs", 0, "gains", "g3"], True, "runs['Law I'].gains.g3", "number"),
        ("tamu_40deg.yaml", ["runs", 1, "reference", "alpha"], True, ".reference.alpha", "number"),
        ("tamu_40deg.yaml", ["model", "n_modes"], True, "model.n_modes", "an integer"),
        ("tamu_40deg.yaml", ["simulation", "duration"], True, "simulation.duration", "number"),
        (
            "tamu_40deg.yaml",
            ["disturbances", "random_torque"],
            True,
            "disturbances.random_torque",
            "number",
        ),
        # tether: a gain in a mapping of gains, an orbit count, an angle
        ("tether_retrieval.yaml", ["runs", 0, "gains", "K1"], True, ".gains", "['K1']"),
        ("tether_retrieval.yaml", ["simulation", "orbits"], True, "simulation.orbits", "number"),
        ("tether_retrieval.yaml", ["initial", "pitch"], True, "initial.pitch", "number"),
        # ppf: a weight in a list, a start gain, a weight, a ratio goal
        ("agrawal_bang_ppf.yaml", ["runs", 0, "weights"], [True, 100], ".weights", "[0]"),
        ("agrawal_bang_ppf.yaml", ["ppf", "initial_gains"], True, "ppf.initial_gains", "number"),
        ("agrawal_bang_ppf.yaml", ["ppf", "Q_u"], True, "ppf.Q_u", "number"),
        ("agrawal_bang_ppf.yaml", ["runs", 6, "goal", "value"], True, ".goal.value", "number"),
        # simulation: an LQR weight inside a list (read as 1.0 when a law's values were typed
        # list[Any]), a rate gain inside an MRP PD gain vector
        (
            "draper_rpl_lqr.yaml",
            ["runs", 1, "gains", "input_weights"],
            [0.01, True, 1],
            ".gains.input_weights",
            "[1]",
        ),
        (
            "own_spacecraft_slew.yaml",
            ["runs", 0, "gains", "P"],
            ["4.4 N*m*s/rad", True, "12 N*m*s/rad"],
            "runs['MRP PD'].gains.P",
            "[1]",
        ),
    ],
    ids=lambda v: repr(v)[:40],
)
def test_a_boolean_is_refused_where_a_number_is_expected(example, path, value, field, rule):
    problems = [p for p in _problems(example, path, value) if "not a boolean" in p.rule]
    assert len(problems) == 1, problems
    assert problems[0].path.endswith(field) or problems[0].path.startswith(field), problems[0]
    assert rule in problems[0].rule


def test_a_boolean_gimbal_angle_is_refused():
    """The gimbal angles are read by the cmg kind's own parser (names or angles): refused."""
    problems = _problems(
        "cmg_preferred_angles.yaml", ["runs", 4, "initial"], [True, "-60 deg", "60 deg", "120 deg"]
    )
    assert [p.path for p in problems] == ["runs['Kurokawa (V6)'].initial"]


def test_booleans_stay_valid_where_the_field_is_a_flag():
    """``stiffening: false`` (a flag of the maneuver kind's model) is still a boolean."""
    doc = yaml.safe_load((EXAMPLES / "tamu_40deg.yaml").read_text())
    assert doc["model"]["stiffening"] is False
    load_scenario(yaml.safe_dump(doc, sort_keys=False))
