"""Runs of a slew scenario whose planned shaping differs only by ``feedback`` share one plan
(flexsat.scenarios.slew, ``_plan``): the plan is computed once, and what is flown is what the
run computes alone. Small setup: the EPS on 12 elastic modes, a 4-mode design model."""

import numpy as np

import flexsat.design.planned_slew as planned_slew_module
from flexsat.scenarios import load_scenario, run_scenario
from flexsat.scenarios.slew import nominal_design

HEAD = """
kind: slew
name: {name}
case: eps
plant: {{n_modes: 12}}
maneuver:
  target: {{euler123: ["0.5 rad", "0.5 rad", "0.5 rad"]}}
  duration: "6 s"
  break_frequency: "5 rad/s"
controller: {{modes: 4, linearization_points: 7}}
simulation: {{duration: "7.5 s", control_rate: "50 Hz"}}
runs:
"""
FED = """  - label: planned + feedback
    weights: {attitude: 1000, rate: 1000, modes: 1, torque: 50}
    break_frequency: "5 rad/s"
    shaping: {kind: planned, basis: 12}
"""
ALONE = """  - label: planned
    shaping: {kind: planned, basis: 12, feedback: false}
"""
OTHER = """  - label: fewer sines
    shaping: {kind: planned, basis: 8, feedback: false}
"""


def _counted(monkeypatch) -> list[int]:
    calls: list[int] = []
    real = planned_slew_module.planned_slew

    def counting(*args, **kwargs):
        calls.append(1)
        return real(*args, **kwargs)

    monkeypatch.setattr(planned_slew_module, "planned_slew", counting)
    return calls


def _same(a: dict, b: dict) -> bool:
    """Equal rows, a NaN equal to a NaN."""
    nan = [k for k, v in a.items() if isinstance(v, float) and np.isnan(v)]
    return a.keys() == b.keys() and all(
        (k in nan and isinstance(b[k], float) and np.isnan(b[k])) or a[k] == b[k] for k in a
    )


def test_runs_differing_only_by_feedback_share_one_plan_equal_to_the_runs_own(monkeypatch):
    calls = _counted(monkeypatch)
    both = load_scenario(HEAD.format(name="plans shared") + FED + ALONE + OTHER)
    result = run_scenario(both)
    # one plan for the two basis-12 runs, one for the basis-8 run
    assert len(calls) == 2
    plans = nominal_design(both)["plans"]
    assert plans["planned"] is plans["planned + feedback"]
    assert plans["fewer sines"] is not plans["planned"]

    # the shared plan and the flown runs are, bit for bit, those of each run alone (a
    # document of its own: its own kept design, so nothing is shared with the one above)
    rows = {r["run"]: r for r in result.metrics_records()}
    for name, run in (("planned + feedback", FED), ("planned", ALONE)):
        single = load_scenario(HEAD.format(name=f"only {name}") + run)
        alone = run_scenario(single)
        own = nominal_design(single)["plans"][name]
        t = np.linspace(0.0, own.duration, 61)
        assert np.array_equal(own.torque(t), plans[name].torque(t)), name
        assert own.energy == plans[name].energy, name
        assert _same({r["run"]: r for r in alone.metrics_records()}[name], rows[name]), name
    assert len(calls) == 4


def test_a_run_whose_plan_inputs_differ_gets_its_own_plan(monkeypatch):
    calls = _counted(monkeypatch)
    fed = FED.replace("basis: 12}", "basis: 12, iterations: 3}")
    scenario = load_scenario(HEAD.format(name="plans differ") + fed + ALONE)
    run_scenario(scenario)
    plans = nominal_design(scenario)["plans"]
    assert len(calls) == 2
    assert plans["planned"] is not plans["planned + feedback"]
