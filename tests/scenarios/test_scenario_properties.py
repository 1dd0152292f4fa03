"""Property: any malformed scenario document ends in a ScenarioError (or, if it is still valid,
runs to finite results or stops with SimulationDiverged), quickly; no other exception escapes.

Documents are the packaged default and the examples, mutated at a random place: wrong types,
extreme and non-finite numbers, bad units, missing and unknown keys, deep nesting, and, on the
text, binary bytes, duplicated lines (duplicate keys) and truncation. Deterministic
(``derandomize``) so that CI is stable.
"""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from flexsat.scenarios import (
    IdentificationScenario,
    ScenarioError,
    default_scenario,
    load_scenario,
    run_scenario,
)
from flexsat.sim import SimulationDiverged
from scenario_mutations import VALUES, Clock, delete_at, get_at, key_paths, set_at

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"

#: seconds one document may take from text to outcome (load, prepare and, when short, the run);
#: the slowest valid one (an NPS LQG design) takes ~0.4 s here, and building a TAMU model of
#: the default size the first time (tamu_40deg with its ``model`` section emptied) 1.2 s, 6 s
#: on a machine loaded 3.5 times over (the bound guards against hangs and minute-long runs)
TIME_BOUND = 10.0

#: a valid document is simulated only when it is this small (control samples × runs × substeps)
SIMULATED_WORK = 3_000


def _small(data: dict) -> dict:
    """A fast variant of a maneuver document: a 0.2-0.5 s run, 3 modes where the case allows."""
    data = copy.deepcopy(data)
    if data.get("kind", "maneuver") == "maneuver":
        data["simulation"]["duration"] = "0.5 s"
        if data["case"] == "tamu":
            data["model"]["n_modes"] = 3
    return data


BASES = {
    "default": _small(yaml.safe_load(default_scenario().yaml_text)),
    "nps_pd": _small(yaml.safe_load((EXAMPLES / "nps_pd_slews.yaml").read_text())),
    "nps_lqg": _small(yaml.safe_load((EXAMPLES / "nps_lqg_30deg.yaml").read_text())),
    "tamu_40deg": _small(yaml.safe_load((EXAMPLES / "tamu_40deg.yaml").read_text())),
    # the hardware section (filters, preset, delay) and a run of its own mutated too
    "tamu_hardware": _small(yaml.safe_load((EXAMPLES / "tamu_hardware.yaml").read_text())),
    "identification": yaml.safe_load((EXAMPLES / "tamu_grid_identification.yaml").read_text()),
}
#: the default is cheap to prepare and comes up most often; the NPS ones build a finite-element
#: model (~0.3 s each)
BASE_WEIGHTS = {
    "default": 6,
    "nps_pd": 1,
    "nps_lqg": 1,
    "tamu_40deg": 1,
    "tamu_hardware": 1,
    "identification": 2,
}


@st.composite
def documents(draw) -> str | bytes:
    """A mutated scenario document (YAML text, or bytes after a binary mutation)."""
    name = draw(st.sampled_from([n for n, w in BASE_WEIGHTS.items() for _ in range(w)]))
    data = copy.deepcopy(BASES[name])
    for _ in range(draw(st.integers(1, 3))):
        paths = key_paths(data)
        kind = draw(st.sampled_from(["set", "set", "set", "delete", "unknown"]))
        path = draw(st.sampled_from(paths)) if paths else ()
        if kind == "set" and path:
            set_at(data, path, draw(VALUES))
        elif kind == "delete" and path:
            delete_at(data, path)
        else:
            parent = draw(
                st.sampled_from([()] + [p for p in paths if isinstance(get_at(data, p), dict)])
            )
            get_at(data, parent)[draw(st.sampled_from(["colour", "seed_", "Runs", "1"]))] = 1
    text = yaml.safe_dump(data, sort_keys=False, allow_unicode=True)
    lines = text.splitlines(keepends=True)
    mutation = draw(st.sampled_from(["none", "none", "bytes", "duplicate", "truncate"]))
    if mutation == "duplicate":
        index = draw(st.integers(0, len(lines) - 1))
        return "".join(lines[: index + 1] + [lines[index]] + lines[index + 1 :])
    if mutation == "truncate":
        return text[: draw(st.integers(0, len(text)))]
    if mutation == "bytes":
        raw = text.encode()
        at = draw(st.integers(0, len(raw)))
        return raw[:at] + draw(st.binary(min_size=1, max_size=8)) + raw[at:]
    return text


def _outcome(document) -> str:
    """'error', 'diverged', 'valid' or 'ran' (finite results); anything else escapes."""
    try:
        scenario = load_scenario(document)
        if isinstance(scenario, IdentificationScenario):
            return "valid"  # its stage 2 runs the campaign (minutes): load only
        from flexsat.scenarios import prepare_scenario

        plan = prepare_scenario(scenario)
        work = plan.config.n_steps * len(plan.controllers) * plan.config.substeps
        if work > SIMULATED_WORK:
            return "valid"
        result = run_scenario(scenario)
    except ScenarioError:
        return "error"
    except SimulationDiverged:
        return "diverged"
    histories = result.dataset()
    for name in ("theta", "theta_dot", "torque", "tip_deflection", "energy"):
        assert np.isfinite(histories[name].values).all(), name
    return "ran"


@settings(
    max_examples=120,
    deadline=None,
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
@given(documents())
def test_malformed_documents_end_in_a_scenario_error_quickly(document):
    clock = Clock()
    _outcome(document)  # raises anything other than the allowed outcomes
    clock.check(TIME_BOUND)


@pytest.mark.parametrize("name", sorted(BASES))
def test_the_unmutated_bases_are_valid(name):
    # the property is not vacuous: the documents it mutates are valid and the maneuvers run
    expected = "valid" if name == "identification" else "ran"
    assert _outcome(yaml.safe_dump(BASES[name], sort_keys=False)) == expected


#: every example of every kind, as parsed YAML: the load-only property below mutates these
EXAMPLE_DOCUMENTS = {p.stem: yaml.safe_load(p.read_text()) for p in sorted(EXAMPLES.glob("*.yaml"))}


@st.composite
def example_documents(draw) -> str:
    """An example of any kind with one to three values replaced, keys deleted or added."""
    data = copy.deepcopy(EXAMPLE_DOCUMENTS[draw(st.sampled_from(sorted(EXAMPLE_DOCUMENTS)))])
    for _ in range(draw(st.integers(1, 3))):
        paths = key_paths(data)
        path = draw(st.sampled_from(paths)) if paths else ()
        action = draw(st.sampled_from(["set", "set", "delete", "unknown"]))
        if action == "set" and path:
            set_at(data, path, draw(VALUES))
        elif action == "delete" and path:
            delete_at(data, path)
        else:
            parent = draw(
                st.sampled_from([()] + [p for p in paths if isinstance(get_at(data, p), dict)])
            )
            get_at(data, parent)[draw(st.sampled_from(["colour", "Runs", "1"]))] = 1
    return yaml.safe_dump(data, sort_keys=False, allow_unicode=True)


@settings(
    max_examples=400,
    deadline=None,
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
@given(example_documents())
def test_malformed_documents_of_every_kind_load_or_are_refused_by_name(document):
    """Stage 1 (YAML, schema, units, section rules) of every kind: a mutated example loads or
    ends in a ScenarioError, quickly; no other exception escapes."""
    clock = Clock()
    try:
        load_scenario(document)
    except ScenarioError as exc:
        assert all(":" in problem for problem in exc.problems)  # each names its field
    clock.check(TIME_BOUND)


def test_every_example_loads():
    for data in EXAMPLE_DOCUMENTS.values():
        load_scenario(yaml.safe_dump(data, sort_keys=False))
