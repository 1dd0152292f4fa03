"""Property: a mutated ``design`` scenario ends in a ScenarioError whose every problem names a
field path, or runs to a finite optimum, quickly; no other exception escapes (issue 23).

The documents are the design examples made small (one optimiser, at most 40 iterations, no
Pareto front): examples/own_structure_design.yaml (a ``model:`` with an inline FE model) and
examples/tamu_codesign_pareto.yaml (a reference problem with ``parameters:``), with one to three
values replaced by wrong types, extreme and non-finite numbers, bad units, or keys deleted and
added (tests/scenario_mutations.py). Derandomized, so that CI is stable.
"""

from __future__ import annotations

import copy
import math
import time
from pathlib import Path

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from flexsat.scenarios import ScenarioError, load_scenario, run_scenario
from scenario_mutations import VALUES, mutate

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"

#: seconds one document may take from text to outcome: the small own-structure example runs
#: in ~0.5 s of CPU (40 SLSQP iterations at most, ~15 ms per FE evaluation with its
#: derivatives), the hub-boom one in ~1 s; the bound guards against hangs on a loaded machine
TIME_BOUND = 20.0


def _small(name: str) -> dict:
    data = yaml.safe_load((EXAMPLES / name).read_text())
    data.pop("pareto", None)
    data["optimizer"] = {"method": "slsqp", "max_iterations": 40}
    return data


BASES = {
    "own_structure": _small("own_structure_design.yaml"),
    "hub_boom": _small("tamu_codesign_pareto.yaml"),
}


@st.composite
def documents(draw) -> str:
    data = copy.deepcopy(BASES[draw(st.sampled_from(sorted(BASES)))])
    data = mutate(draw, data, VALUES, ["colour", "Runs", "1"])
    return yaml.safe_dump(data, sort_keys=False, allow_unicode=True)


def outcome(document: str) -> str:
    """'error' (every problem placed) or 'ran' (a finite optimum); anything else escapes."""
    try:
        result = run_scenario(load_scenario(document))
    except ScenarioError as exc:
        for problem in exc.problems:
            assert problem.path or " line " in problem.rule, f"names no field: {problem}"
        return "error"
    for optimum in result.optima:
        assert math.isfinite(optimum.objective)
        assert all(math.isfinite(v) for v in optimum.x)
    return "ran"


@settings(
    max_examples=60,
    deadline=None,
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
@given(documents())
def test_mutated_design_examples_are_refused_by_name_or_run_finite(document):
    start = time.perf_counter()
    outcome(document)
    assert time.perf_counter() - start < TIME_BOUND


@pytest.mark.parametrize("name", sorted(BASES))
def test_the_small_examples_run(name):
    # the property is not vacuous: every document it mutates runs to a finite optimum
    assert outcome(yaml.safe_dump(BASES[name], sort_keys=False)) == "ran"
