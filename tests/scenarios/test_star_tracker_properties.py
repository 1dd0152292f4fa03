"""Property: a mutated star-tracker scenario ends in a ScenarioError naming a field path, or a
run whose metrics are finite or null with a stated reason (strict JSON), quickly; no other
exception escapes (issue 21).

The documents are a small fast variant of examples/star_tracker.yaml (3 attitudes a run) with
one to three values replaced by wrong types, extreme and non-finite numbers, bad units, or keys
deleted and added; derandomized, so that CI is stable.
"""

from __future__ import annotations

import copy
import json
import math
from pathlib import Path

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from flexsat.report.json_data import NULL_REASONS, dumps
from flexsat.scenarios import ScenarioError, load_scenario, run_scenario
from scenario_mutations import Clock, mutate

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "star_tracker.yaml"

#: seconds one document may take from text to outcome
TIME_BOUND = 5.0
#: a valid document runs when it identifies at most this many attitudes (~5 ms each) with at
#: most MAX_FALSE false stars a field
MAX_ATTITUDES = 10
MAX_FALSE = 20


def _small() -> dict:
    data = yaml.safe_load(EXAMPLE.read_text())
    for run in data["runs"]:
        run["attitudes"] = 3
    return data


BASE = _small()

NUMBERS = st.sampled_from(
    [0, -1, 1e308, -1e308, 1e-308, 2**70, 1e29, 1.5, 1e12, 0.999, math.nan, math.inf, -math.inf]
)
BAD_UNITS = st.sampled_from(
    ["1 kg", "1e-6 deg", "nan deg", "inf arcsec", "1e400 deg", "-3 deg", "400 deg", "5 um", ""]
)
WRONG_TYPES = st.one_of(
    st.none(),
    st.booleans(),
    st.lists(st.integers(-1, 3), max_size=4),
    st.dictionaries(st.sampled_from(["source", "seed", "a"]), st.integers(-2, 2), max_size=2),
    st.text(max_size=12),
)
VALUES = st.one_of(NUMBERS, BAD_UNITS, WRONG_TYPES)


@st.composite
def documents(draw) -> str:
    data = mutate(draw, copy.deepcopy(BASE), VALUES, ["fov", "Runs"])
    return yaml.safe_dump(data, sort_keys=False, allow_unicode=True)


def _outcome(document: str) -> str:
    """'error', 'valid' (too long to run here) or 'ran'; anything else escapes."""
    try:
        scenario = load_scenario(document)
        if (
            sum(r.attitudes for r in scenario.runs) > MAX_ATTITUDES
            or max(r.false_stars for r in scenario.runs) > MAX_FALSE
            or scenario.catalog.source != "synthetic"
        ):
            return "valid"
        result = run_scenario(scenario)
    except ScenarioError as exc:
        assert exc.problems and all(p.path for p in exc.problems), exc  # each names its field
        return "error"
    records = json.loads(dumps(result.metrics_records()))  # strict JSON
    for record in records:
        nulls = {k for k, v in record.items() if v is None}
        assert nulls <= set(record.get(NULL_REASONS, {})), record  # every null says why
    return "ran"


@settings(
    max_examples=60,
    deadline=None,
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
@given(documents())
def test_mutated_star_tracker_documents_end_cleanly_and_quickly(document):
    clock = Clock()
    _outcome(document)
    clock.check(TIME_BOUND)


def test_the_small_base_runs():
    assert _outcome(yaml.safe_dump(BASE, sort_keys=False)) == "ran"


@pytest.mark.parametrize(
    "path, value",
    [
        (("catalog", "magnitude_limit"), 1e308),
        (("catalog", "magnitude_limit"), 30),
        (("catalog", "magnitude_limit"), -5),
        (("catalog", "seed"), 2**70),
        (("cameras", 0, "field_of_view"), "1e-6 deg"),
        (("cameras", 0, "field_of_view"), "179 deg"),
        (("cameras", 0, "field_of_view"), "180 deg"),
        (("cameras", 0, "field_of_view"), "400 deg"),
        (("cameras", 0, "n_pixels"), 2**70),
        (("cameras", 0, "n_pixels"), 2),
        (("cameras", 0, "pixel_pitch"), "1e-300 m"),
        (("cameras", 0, "centroid_noise"), 1e308),
        (("cameras", 0, "magnitude_limit"), -30),
        (("cameras", 1, "mounting"), ["nan deg", "0 deg", "0 deg"]),
        (("cameras", 1, "mounting"), ["1e300 deg", "0 deg", "0 deg"]),
        (("cameras", 1, "mounting"), ["0 deg"]),
        (("identification", "tolerance"), "1e-300 arcsec"),
        (("identification", "tolerance"), "180 deg"),
        (("identification", "min_triplets"), 10**9),
        (("identification", "min_fields"), 3),
        (("runs", 0, "false_stars"), 1000),
        (("runs", 0, "missing_fraction"), 0.999),
        (("runs", 0, "seed"), 2**70),
    ],
)
def test_extreme_values_end_cleanly(path, value):
    data = copy.deepcopy(BASE)
    node = data
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = value
    clock = Clock()
    assert _outcome(yaml.safe_dump(data, sort_keys=False)) in ("error", "ran", "valid")
    clock.check(TIME_BOUND)
