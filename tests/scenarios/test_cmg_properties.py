"""Property: a mutated CMG scenario (``kind: cmg`` or ``kind: cmg_station``) ends in a
ScenarioError naming its field, runs to finite results, or stops with SimulationDiverged,
quickly; no other exception escapes (as tests/scenarios/test_scenario_properties.py for the
maneuver kind).

Documents are the two examples (examples/cmg_preferred_angles.yaml, examples/space_station_cmg.yaml)
made short (durations of a few seconds, a quarter orbit) and mutated at a random place: wrong
types, extreme and non-finite numbers, bad units, missing and unknown keys. The V1–V8 table every
``kind: cmg`` plan ends with does not depend on the document: it is computed once for the module
(about 7 s) and reused. Deterministic (``derandomize``) so that CI is stable.
"""

from __future__ import annotations

import copy
import math
from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from flexsat.scenarios import ScenarioError, load_scenario, run_scenario
from flexsat.scenarios import cmg as cmg_kind
from flexsat.sim import SimulationDiverged
from scenario_mutations import Clock, mutate, set_at

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"

#: seconds one document may take from text to outcome (load, plan, the runs): an unmutated
#: base takes ~0.7 s on an idle core, ~2.5 s with 8 processes on 2 cores (measured); the bound
#: catches a hang or a run whose work the schema failed to bound, not a slow machine
TIME_BOUND = 10.0
#: a valid document is run only when its work is this small: steering-run seconds × the largest
#: demand rate (rotor momenta per second, or the harmonic's frequency), or station orbits × runs
STEERING_WORK = 20.0
STATION_WORK = 0.5


def _short_cmg(data: dict) -> dict:
    """One run of each form (constant demand, null motion beside it, harmonic demand,
    reorientation), 2 s each."""
    data = copy.deepcopy(data)
    keep = ("x, zero gimbals (V3)", "x, zero + null motion", "Kurokawa (V6)")
    data["runs"] = [r for r in data["runs"] if r["label"] in keep or "reorient_to" in r]
    for run in data["runs"]:
        run["duration"] = "2 s"
    return data


def _short_station(data: dict) -> dict:
    """A tenth of an orbit (571 s: V9's 494 s inside it), zero and preferred gimbals."""
    data = copy.deepcopy(data)
    data["simulation"]["orbits"] = 0.1
    data["runs"] = [r for r in data["runs"] if r["initial"] != "alternate"]
    return data


BASES = {
    "cmg": _short_cmg(yaml.safe_load((EXAMPLES / "cmg_preferred_angles.yaml").read_text())),
    "station": _short_station(yaml.safe_load((EXAMPLES / "space_station_cmg.yaml").read_text())),
}


@pytest.fixture(scope="module", autouse=True)
def _table_once():
    """The kind's V1–V8 table, computed once for the module (it reads no document)."""
    patch = pytest.MonkeyPatch()
    table = cmg_kind.validation_table()
    patch.setattr(cmg_kind, "validation_table", lambda: table)
    yield
    patch.undo()


NUMBERS = st.sampled_from(
    [0, -1, 1e308, -1e308, 1e-308, 2**70, 1e29, 1.5, 1e12, 100.0, math.nan, math.inf, -math.inf]
)
BAD_UNITS = st.sampled_from(
    ["1 kg", "15 deg", "nan s", "inf Hz", "1e400 s", "1e12 s", "-3 N*m", "5 furlong", "", "1 1 s"]
)
WRONG_TYPES = st.one_of(
    st.none(),
    st.booleans(),
    st.lists(st.booleans(), min_size=4, max_size=4),
    st.lists(st.integers(-400, 400), max_size=5),
    st.dictionaries(st.sampled_from(["constant", "target", "a"]), st.integers(), max_size=2),
    st.text(max_size=12),
)
VALUES = st.one_of(NUMBERS, BAD_UNITS, WRONG_TYPES)


@st.composite
def documents(draw) -> str:
    """A short CMG example with one to three values replaced, keys deleted or added."""
    data = copy.deepcopy(BASES[draw(st.sampled_from(sorted(BASES)))])
    mutate(draw, data, VALUES, ["colour", "Runs", "1"], path_first=True)
    return yaml.safe_dump(data, sort_keys=False, allow_unicode=True)


def _work(scenario) -> float:
    if scenario.kind == "cmg_station":
        return scenario.simulation.orbits * len(scenario.runs)
    total = 0.0
    for run in scenario.runs:
        demand = run.demand
        if demand is None:
            rate = 1.0
        elif isinstance(demand, list):
            rate = max(1.0, float(np.abs(demand).max()))
        else:
            rate = max(
                1.0,
                float(np.abs(demand.constant).max() + np.abs(demand.amplitude).max()),
                demand.frequency,
            )
        total += run.duration * rate
    return total


def _outcome(document: str) -> str:
    """'error', 'diverged', 'valid' (too long to run here) or 'ran' (finite results)."""
    try:
        scenario = load_scenario(document)
        bound = STATION_WORK if scenario.kind == "cmg_station" else STEERING_WORK
        if _work(scenario) > bound:
            return "valid"
        result = run_scenario(scenario)
    except ScenarioError as exc:
        assert all(":" in problem for problem in exc.problems)  # each names its field
        return "error"
    except SimulationDiverged:
        return "diverged"
    ds = result.dataset()
    for name in ("gimbal_angles", "gain"):
        values = ds[name].values
        # NaN only past a run's singular stop (the padding), never inside a run
        assert np.isfinite(values[..., 0] if values.ndim == 3 else values).any()
    for record in result.metrics_records():
        for key, value in record.items():
            assert not isinstance(value, float) or math.isfinite(value), key
    return "ran"


@settings(
    max_examples=60,
    deadline=None,
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
@given(documents())
def test_mutated_cmg_documents_end_cleanly_and_quickly(document):
    clock = Clock()
    _outcome(document)  # raises anything other than the allowed outcomes
    clock.check(TIME_BOUND)


@pytest.mark.parametrize("name", sorted(BASES))
def test_the_unmutated_bases_run(name):
    # the property is not vacuous: the documents it mutates run
    assert _outcome(yaml.safe_dump(BASES[name], sort_keys=False)) == "ran"


@pytest.mark.parametrize(
    "name, path, value, message",
    [
        (
            "cmg",
            ("runs", 0, "initial"),
            [True, 0, 0, 0],
            r"runs.*initial: gimbal angles must be numbers",
        ),
        (
            "station",
            ("runs", 0, "initial"),
            [0, False, 0, 0],
            r"runs.*initial: gimbal angles must be numbers",
        ),
        (
            "cmg",
            ("runs", 0, "initial"),
            ["-90 deg", "180 deg", "90 deg", "0 deg"],
            r"runs\['x, zero gimbals \(V3\)'\].*sigma0: starts singular",
        ),
        (
            "station",
            ("runs", 0, "initial"),
            ["-90 deg", "180 deg", "90 deg", "0 deg"],
            r"runs\['sigma\(0\) = 0'\].*sigma0: starts singular",
        ),
    ],
)
def test_what_the_property_found_is_refused_by_field(name, path, value, message):
    data = copy.deepcopy(BASES[name])
    set_at(data, path, value)
    with pytest.raises(ScenarioError, match=message):
        run_scenario(load_scenario(yaml.safe_dump(data, sort_keys=False)))


@pytest.mark.parametrize(
    "path, value",
    [(("runs", 0, "demand"), [True, 0, 0]), (("runs", 2, "demand", "constant"), [0, 0.3, False])],
)
def test_a_boolean_demand_is_refused_by_field(path, value):
    data = copy.deepcopy(BASES["cmg"])
    set_at(data, path, value)
    with pytest.raises(ScenarioError, match=r"runs.*must be three finite numbers"):
        load_scenario(yaml.safe_dump(data, sort_keys=False))
