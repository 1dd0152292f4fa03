"""Property: a mutated sweep or Monte Carlo document ends, at load time, in a ScenarioError
whose every problem names a field path, or in a valid study whose case count is within
flexsat.limits.MAX_CASES, quickly; no other exception escapes (issue 21: a distribution
written as a list or a mapping, a 2,000,000-case study, a 1e9-point axis).

The documents are examples/tamu_trade_surfaces.yaml and examples/tamu_montecarlo.yaml with one
to three values replaced by wrong types, extreme and non-finite numbers, bad units, or keys
deleted and added, next to a copy of the maneuver scenario they vary; derandomized, so that CI
is stable. (Running a study: tests/scenarios/test_batch_scenario.py, with a small maneuver.)
"""

from __future__ import annotations

import copy
import math
import shutil
from pathlib import Path

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from flexsat import limits
from flexsat.scenarios import ScenarioError, load_scenario
from flexsat.scenarios.batch import BatchScenario, case_count
from scenario_mutations import Clock, mutate

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
BASES = {
    name: yaml.safe_load((EXAMPLES / f"{name}.yaml").read_text())
    for name in ("tamu_trade_surfaces", "tamu_montecarlo")
}

#: seconds one document may take from text to outcome (parsing and validating the study, and
#: the maneuver scenario it names)
TIME_BOUND = 5.0

NUMBERS = st.sampled_from(
    [0, -1, 1e308, 2**70, 1e29, 1.5, 1e9, 2_000_000, 100_001, math.nan, math.inf, -math.inf]
)
BAD_UNITS = st.sampled_from(
    ["1 kg", "15 deg", "nan ozf*in", "inf kg", "1e400 s", "-3 N*m", "5 furlong", "", "1 1 s"]
)
WRONG_TYPES = st.one_of(
    st.none(),
    st.booleans(),
    st.lists(st.integers(-2, 2), max_size=3),
    st.lists(st.sampled_from(["normal", "1 kg"]), min_size=1, max_size=2),
    st.dictionaries(st.sampled_from(["normal", "mean", "n", "a"]), st.integers(-2, 2), max_size=2),
    st.text(max_size=12),
)
VALUES = st.one_of(NUMBERS, BAD_UNITS, WRONG_TYPES)


@st.composite
def documents(draw) -> str:
    """A study example with one to three values replaced, keys deleted or added."""
    data = copy.deepcopy(BASES[draw(st.sampled_from(sorted(BASES)))])
    mutate(draw, data, VALUES, ["colour", "Parameters"])
    return yaml.safe_dump(data, sort_keys=False, allow_unicode=True)


@pytest.fixture(scope="module")
def folder(tmp_path_factory) -> Path:
    """A folder with the maneuver scenario the studies vary."""
    out = tmp_path_factory.mktemp("studies")
    shutil.copy(EXAMPLES / "tamu_40deg.yaml", out / "tamu_40deg.yaml")
    return out


def _outcome(folder: Path, text: str) -> str:
    path = folder / "study.yaml"
    path.write_text(text, encoding="utf-8")
    try:
        spec = load_scenario(path)
    except ScenarioError as exc:
        assert exc.problems and all(p.path for p in exc.problems), str(exc)
        return "error"
    if isinstance(spec, BatchScenario):
        assert 1 <= case_count(spec) <= limits.MAX_CASES
    return "valid"


@settings(
    max_examples=120,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)
@given(documents())
def test_a_mutated_study_is_refused_by_field_or_valid_and_bounded(folder, text):
    clock = Clock()
    assert _outcome(folder, text) in ("error", "valid")
    clock.check(TIME_BOUND)


@pytest.mark.parametrize(
    "name, path, value, field",
    [
        ("tamu_montecarlo", ("cases",), 2_000_000, "cases"),
        (
            "tamu_montecarlo",
            ("parameters", "hub_inertia", "distribution"),
            ["normal"],
            "parameters",
        ),
        ("tamu_montecarlo", ("parameters", "tip_mass"), {"distribution": {"a": 1}}, "parameters"),
        ("tamu_trade_surfaces", ("parameters", "alpha", "n"), 1_000_000_000, "parameters"),
        ("tamu_trade_surfaces", ("parameters", "u_max", "n"), 20_000, "parameters"),
    ],
)
def test_the_issue_s_studies_are_refused_by_field_at_load(folder, name, path, value, field):
    data = copy.deepcopy(BASES[name])
    node = data
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = value
    with pytest.raises(ScenarioError) as err:
        load_scenario(_write(folder, data))
    assert [p.path.split(".")[0] for p in err.value.problems] == [field], str(err.value)


def _write(folder: Path, data: dict) -> Path:
    path = folder / "study.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    return path
