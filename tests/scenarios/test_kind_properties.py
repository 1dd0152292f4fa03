"""Property, per kind (slew, ppf, simulation): any mutation of one of the kind's examples ends in
a ScenarioError whose every problem names a field path, a run to finite results, or a stated
divergence (SimulationDiverged), quickly; no other exception escapes.

The examples are first made small (:func:`small`: a short run at a low control rate, few modes,
two runs) so that a valid mutation runs through every step, the goals and the dataset included;
a mutation that asks for a long simulation is caught before it runs (:func:`guarded`) and only
counts as loaded and planned. Mutations: wrong types, extreme and non-finite numbers, bad units,
missing and unknown keys (tests/scenario_mutations.py). Deterministic
(``derandomize``) so that CI is stable.
"""

from __future__ import annotations

import contextlib
import copy
import functools
from pathlib import Path
from unittest import mock

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from flexsat.scenarios import ScenarioError, load_scenario, run_scenario
from flexsat.sim import SimulationDiverged
from flexsat.units import to_si
from scenario_mutations import VALUES, Clock, delete_at, get_at, key_paths, set_at

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"

#: seconds one document may take from text to outcome; the slowest small example (an EPS slew:
#: the nominal TPBVP by continuation, three gain schedules, three 2.5 s runs) takes ~3 s here
TIME_BOUND = 10.0

#: a simulation runs only when it is this small (control samples × substeps × cases); a larger
#: one (a mutated duration or rate) is stopped before it starts
SIMULATED_WORK = 20_000

#: control samples of a small simulation-kind example
SMALL_SAMPLES = 20


def small(data: dict) -> dict:
    """A fast variant of an example of kind slew, ppf or simulation (module docstring)."""
    data = copy.deepcopy(data)
    kind = data["kind"]
    if kind == "slew":
        # 7 design modes: the 7 point forces of the EPS need as many states to act on
        data["plant"] = {"n_modes": 8}
        data["controller"] = {"modes": 7, "linearization_points": 3}
        data["maneuver"]["duration"] = "3 s"
        # the example's own control rate: a law tuned at 100 Hz (eps_slew_6s_flown's) need not
        # be stable sampled at 50 Hz
        data["simulation"] = {
            "duration": "3.75 s",
            "control_rate": data["simulation"]["control_rate"],
        }
        data["runs"] = data["runs"][:2]
        for run in data["runs"]:
            if "weights" not in run:  # a planned torque flown alone
                continue
            run["weights"] = {
                k: v[0] if isinstance(v, list) else v for k, v in run["weights"].items()
            }
    elif kind == "ppf":
        data["simulation"] = {"duration": "0.5 s", "control_rate": "50 Hz"}
        data["runs"] = [data["runs"][0], data["runs"][-1]]
    elif kind == "simulation":
        sim = data["simulation"]
        rate = to_si(sim["control_rate"], "Hz")
        sim["duration"] = f"{min(to_si(sim['duration'], 's'), SMALL_SAMPLES / rate):.6g} s"
        data["runs"] = data["runs"][:2]
    return data


def _examples(kind: str) -> dict[str, dict]:
    found = {}
    for path in sorted(EXAMPLES.glob("*.yaml")):
        data = yaml.safe_load(path.read_text())
        if data.get("kind") == kind:
            found[path.stem] = small(data)
    return found


BASES = {kind: _examples(kind) for kind in ("slew", "ppf", "simulation")}


def _with_hardware() -> dict:
    """The Draper/RPL example with a hardware section (an amplifier, a filter, a delay), a
    run's own section and a cable spring: the sections of flexsat.scenarios.hardware_section
    mutated too."""
    data = yaml.safe_load((EXAMPLES / "draper_rpl_lqr.yaml").read_text())
    data["hardware"] = {
        "amplifiers": {"u1_hub": {"current_limit": "1 A", "torque_constant": "2 N*m/A"}},
        "filters": {"state": {"type": "bessel", "order": 2, "corner": "20 Hz"}},
        "delay": "20 ms",
    }
    data["runs"][1]["hardware"] = {"preset": "ideal"}
    data["disturbances"] = {
        "u1_hub": {
            "cable": {
                "constant": "0.01 N*m",
                "profile": [
                    {"angle": "0 deg", "torque": 0},
                    {"angle": "10 deg", "torque": "1 mN*m"},
                ],
            }
        }
    }
    return small(data)


BASES["simulation"]["draper_rpl_hardware"] = _with_hardware()


class TooLarge(Exception):
    """A valid mutated document whose simulation is too long to run in a property test."""


@contextlib.contextmanager
def guarded():
    """:func:`flexsat.scenarios.runner`'s simulate, refusing runs above :data:`SIMULATED_WORK`."""
    from flexsat.scenarios import runner

    simulate = runner.simulate

    def bounded(plant, law, config, **options):
        work = config.n_steps * config.substeps * options.get("n_cases", 1)
        if work > SIMULATED_WORK:
            raise TooLarge(work)
        return simulate(plant, law, config, **options)

    with mock.patch.object(runner, "simulate", bounded):
        yield


def _assert_finite(result) -> None:
    """The result's histories are finite: every variable over time, the optimised gains, and
    the optimiser's paths up to their end (later steps are NaN padding to the longest run).
    A per-run metric may be NaN: not defined for that run (the open loop's pointing error)."""
    ds = result.dataset()
    for name, variable in ds.data_vars.items():
        if variable.dtype.kind != "f":
            continue
        if "time" in variable.dims or name.startswith("gains_"):
            assert np.isfinite(variable.values).all(), name
        elif "step" in variable.dims:
            steps = variable.transpose("run", "step", ...).values
            finite = np.isfinite(steps.reshape(*steps.shape[:2], -1)).all(axis=-1)
            assert finite[:, 0].all() and (np.diff(finite.astype(int), axis=1) <= 0).all(), name


def outcome(document: str) -> str:
    """'error', 'diverged', 'large' (valid, too long to simulate here) or 'ran'; anything else
    escapes."""
    try:
        scenario = load_scenario(document)
        with guarded():
            result = run_scenario(scenario)
    except ScenarioError as exc:
        for problem in exc.problems:
            # a problem of the text (YAML syntax, nesting) is placed by its line instead
            assert problem.path or " line " in problem.rule, f"names no field: {problem}"
        return "error"
    except SimulationDiverged:
        return "diverged"
    except TooLarge:
        return "large"
    _assert_finite(result)
    return "ran"


def mutated(kind: str):
    """A strategy: an example of ``kind`` with one to three values replaced, keys deleted or
    added."""

    @st.composite
    def documents(draw) -> str:
        bases = BASES[kind]
        data = copy.deepcopy(bases[draw(st.sampled_from(sorted(bases)))])
        for _ in range(draw(st.integers(1, 3))):
            paths = [p for p in key_paths(data) if p != ("kind",)]
            path = draw(st.sampled_from(paths))
            action = draw(st.sampled_from(["set", "set", "set", "delete", "unknown"]))
            if action == "set":
                set_at(data, path, draw(VALUES))
            elif action == "delete":
                delete_at(data, path)
            else:
                parent = draw(
                    st.sampled_from([()] + [p for p in paths if isinstance(get_at(data, p), dict)])
                )
                get_at(data, parent)[draw(st.sampled_from(["colour", "Runs", "1"]))] = 1
        return yaml.safe_dump(data, sort_keys=False, allow_unicode=True)

    return documents()


def _settings(n: int):
    return settings(
        max_examples=n,
        deadline=None,
        derandomize=True,
        database=None,
        suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
    )


@functools.cache
def _warm(kind: str) -> None:
    """Run the kind's small examples once: the first run of a kind imports its modules and
    builds its case (seconds), which the time bound is not about."""
    for data in BASES[kind].values():
        outcome(yaml.safe_dump(data, sort_keys=False))


def _check(kind: str, document: str) -> None:
    _warm(kind)
    clock = Clock()
    outcome(document)  # raises anything other than the allowed outcomes
    clock.check(TIME_BOUND)


@_settings(25)
@given(mutated("slew"))
def test_mutated_slew_examples_are_refused_by_name_or_run_finite(document):
    _check("slew", document)


@_settings(60)
@given(mutated("ppf"))
def test_mutated_ppf_examples_are_refused_by_name_or_run_finite(document):
    _check("ppf", document)


@_settings(100)
@given(mutated("simulation"))
def test_mutated_simulation_examples_are_refused_by_name_or_run_finite(document):
    _check("simulation", document)


@pytest.mark.parametrize(
    "kind, name", [(kind, name) for kind, bases in BASES.items() for name in sorted(bases)]
)
def test_the_small_examples_run(kind, name):
    # the properties are not vacuous: every document they mutate runs to finite results
    assert outcome(yaml.safe_dump(BASES[kind][name], sort_keys=False)) == "ran"


def _changed(kind: str, name: str, path: tuple, value) -> str:
    data = copy.deepcopy(BASES[kind][name])
    set_at(data, path, value)
    return yaml.safe_dump(data, sort_keys=False)


#: the findings of the issue 21 probe, each (kind, example, key path, value, field path named)
PROBE = [
    (
        "slew",
        "eps_slew_6s",
        ("maneuver", "break_frequency"),
        "1e12 rad/s",
        "maneuver.break_frequency",
    ),
    (
        "slew",
        "eps_slew_6s",
        ("runs", 0, "break_frequency"),
        "1e12 rad/s",
        "runs['D: torquers'].break_frequency",
    ),
    ("slew", "eps_slew_6s", ("maneuver", "shaping_damping"), 1e300, "maneuver.shaping_damping"),
    ("slew", "eps_slew_6s", ("maneuver", "rate_weight"), 1e300, "maneuver.rate_weight"),
    (
        "slew",
        "eps_slew_6s",
        ("runs", 0, "shaping_damping"),
        1e300,
        "runs['D: torquers'].shaping_damping",
    ),
    (
        "slew",
        "eps_slew_6s",
        ("runs", 0, "shaping_damping"),
        1e10,
        "runs['D: torquers'].shaping_damping",
    ),
    (
        "slew",
        "eps_slew_6s",
        ("runs", 0, "weights", "attitude"),
        1e300,
        "runs['D: torquers'].weights.attitude",
    ),
    (
        "slew",
        "eps_slew_6s",
        ("controller", "linearization_points"),
        1e12,
        "controller.linearization_points",
    ),
    ("slew", "eps_slew_6s", ("controller", "modes"), 101, "controller.modes"),
    ("slew", "eps_slew_6s", ("plant", "n_modes"), 101, "plant.n_modes"),
    ("slew", "eps_slew_6s", ("plant", "rim_nodes"), [], "plant.rim_nodes"),
    ("ppf", "agrawal_bang_ppf", ("runs", 1, "weights"), [1e300, 1e300], "runs['3b 0.2'].weights"),
    ("ppf", "agrawal_bang_ppf", ("ppf", "Q_u"), 1e300, "runs['1a paper'].weights"),
    ("ppf", "agrawal_bang_ppf", ("runs", 1, "goal", "value"), 0, "runs['3b 0.2'].goal.value"),
    ("ppf", "agrawal_bang_ppf", ("runs", 1, "goal", "value"), 1e300, "runs['3b 0.2'].goal.value"),
    (
        "ppf",
        "agrawal_bang_ppf",
        ("runs", 1, "goal"),
        {"rule": "offset", "value": -1e300},
        "runs['3b 0.2'].goal.value",
    ),
    (
        "simulation",
        "agrawal_bang_lqr",
        ("runs", 0, "gains", "state_weights"),
        1e300,
        "runs['LQR'].gains.state_weights",
    ),
    (
        "simulation",
        "agrawal_bang_lqr",
        ("runs", 0, "gains", "input_weights"),
        1e-300,
        "runs['LQR'].gains.input_weights",
    ),
]


@pytest.mark.parametrize("kind, name, path, value, field", PROBE)
def test_the_probe_findings_are_refused_before_the_runs_naming_the_field(
    kind, name, path, value, field
):
    document = _changed(kind, name, path, value)
    with guarded(), pytest.raises(ScenarioError) as caught:
        run_scenario(load_scenario(document))
    assert [p.path for p in caught.value.problems] == [field]
