"""Property: a mutated identification scenario is refused with a ScenarioError naming a field
path, or passes both stages of checks (the schema, then the checks against the case: nodes,
substructures, camera rig) quickly; no other exception escapes (issue 21).

The documents are examples/tamu_grid_identification.yaml with one to three values replaced by
wrong types, extreme and non-finite numbers, bad units, or keys deleted and added;
derandomized. The campaign itself is not run here: even a small one takes ~20 s (its report
is written in tests/report/test_json_data.py).
"""

from __future__ import annotations

import copy
import math
from pathlib import Path

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from flexsat.scenarios import ScenarioError, load_scenario
from flexsat.scenarios.identification import IdentificationKind
from scenario_mutations import Clock, mutate, set_at

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "tamu_grid_identification.yaml"
BASE = yaml.safe_load(EXAMPLE.read_text())

#: seconds one document may take from text to the end of its checks
TIME_BOUND = 5.0

NUMBERS = st.sampled_from(
    [0, -1, 1e308, -1e308, 1e-308, 2**70, 1e29, 1.5, 1e12, 61, math.nan, math.inf, -math.inf]
)
BAD_UNITS = st.sampled_from(
    ["1 kg", "15 deg", "nan s", "inf Hz", "1e400 s", "1e12 s", "-3 N*s", "5 furlong", "", "1 1 s"]
)
WRONG_TYPES = st.one_of(
    st.none(),
    st.booleans(),
    st.lists(st.integers(-1, 30), max_size=3),
    st.dictionaries(st.sampled_from(["x", "node", "a"]), st.integers(-2, 2), max_size=2),
    st.text(max_size=12),
)
VALUES = st.one_of(NUMBERS, BAD_UNITS, WRONG_TYPES)


@st.composite
def documents(draw) -> str:
    data = mutate(draw, copy.deepcopy(BASE), VALUES, ["gain", "Runs"])
    return yaml.safe_dump(data, sort_keys=False, allow_unicode=True)


def _outcome(document: str) -> str:
    """'error' or 'valid' (both stages of checks passed); anything else escapes."""
    try:
        scenario = load_scenario(document)
        if scenario.kind != "identification":
            return "valid"  # a deleted kind: another kind's checks (test_scenario_properties)
        next(IdentificationKind().plan(scenario))  # stage 2, up to the campaign
    except ScenarioError as exc:
        assert exc.problems and all(p.path for p in exc.problems), exc  # each names its field
        return "error"
    return "valid"


@settings(
    max_examples=150,
    deadline=None,
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
@given(documents())
def test_mutated_identification_documents_are_refused_by_name_or_pass_quickly(document):
    clock = Clock()
    _outcome(document)
    clock.check(TIME_BOUND)


def test_the_base_passes_both_stages():
    assert _outcome(yaml.safe_dump(BASE, sort_keys=False)) == "valid"


@pytest.mark.parametrize(
    "path, value",
    [
        (("sensors", "targets"), [1, 999]),
        (("sensors", "strain_gauges"), [[16, 999, "x"]]),
        (("wheels", "nodes"), [3, 7, 999]),
        (("hammer", "node"), -1),
        (("a_priori", "stiffness_scale"), {"no such part": 1.1}),
        (("case_overrides",), {"motor_mass": "-1 kg"}),
        (("video", "cameras", 0, "position"), ["nan m", "0 m", "0 m"]),
        (("identification", "band"), "1e12 Hz"),
        (("truth", "modes"), 10**9),
    ],
)
def test_values_the_case_refuses_are_named(path, value):
    data = copy.deepcopy(BASE)
    set_at(data, path, value)
    assert _outcome(yaml.safe_dump(data, sort_keys=False)) == "error"
