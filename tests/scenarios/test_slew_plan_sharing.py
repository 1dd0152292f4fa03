"""Runs of a slew scenario whose planned shaping differs only by ``feedback`` share one plan
(flexsat.scenarios.slew_planned, ``plan_for_run``): the plan is computed once, and what is
flown is what the run computes alone. Small setup (the claim is about the bookkeeping, not the
physics): the EPS on 6 elastic modes, a 2-mode design model, 6 sines per axis, 20 Hz control."""

import numpy as np

import flexsat.design.planned_slew as planned_slew_module
from flexsat.scenarios import load_scenario, run_scenario
from flexsat.scenarios.slew import nominal_design

HEAD = """
kind: slew
name: {name}
case: eps
plant: {{n_modes: 6}}
maneuver:
  target: {{euler123: ["0.5 rad", "0.5 rad", "0.5 rad"]}}
  duration: "6 s"
  break_frequency: "5 rad/s"
controller: {{modes: 2, linearization_points: 5}}
simulation: {{duration: "7.5 s", control_rate: "20 Hz"}}
runs:
"""
FED = """  - label: planned + feedback
    weights: {attitude: 1000, rate: 1000, modes: 1, torque: 50}
    break_frequency: "5 rad/s"
    shaping: {kind: planned, basis: 6}
"""
ALONE = """  - label: planned
    shaping: {kind: planned, basis: 6, feedback: false}
"""
OTHER = """  - label: three iterations
    shaping: {kind: planned, basis: 6, iterations: 3, feedback: false}
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
    several = load_scenario(HEAD.format(name="plans shared") + FED + ALONE + OTHER)
    result = run_scenario(several)
    # one plan for the two runs differing by feedback, one for the run with other iterations
    assert len(calls) == 2
    plans = nominal_design(several)["plans"]
    assert plans["planned"] is plans["planned + feedback"]
    assert plans["three iterations"] is not plans["planned"]

    # the run that was handed the first run's plan flies, bit for bit, what it computes alone
    # (a document of its own: its own kept design, nothing shared with the one above)
    single = load_scenario(HEAD.format(name="plan alone") + ALONE)
    alone = run_scenario(single)
    assert len(calls) == 3
    own = nominal_design(single)["plans"]["planned"]
    t = np.linspace(0.0, own.duration, 61)
    assert np.array_equal(own.torque(t), plans["planned"].torque(t))
    assert own.energy == plans["planned"].energy
    rows = {r["run"]: r for r in result.metrics_records()}
    assert _same({r["run"]: r for r in alone.metrics_records()}["planned"], rows["planned"])


def test_a_plan_is_not_reused_at_another_control_rate():
    """The kept designs and plans are sampled at the control rate: a document at another rate
    (or of another length) gets its own, while another seed (a Monte Carlo of the truth)
    reuses them. Before, a document at 20 Hz reused the plan computed at 50 Hz."""
    from flexsat.scenarios.slew import design_fingerprint

    base = HEAD.format(name="rate") + ALONE
    at_20 = design_fingerprint(load_scenario(base))
    at_50 = design_fingerprint(load_scenario(base.replace('"20 Hz"', '"50 Hz"')))
    longer = design_fingerprint(load_scenario(base.replace('"7.5 s"', '"8 s"')))
    seeded = design_fingerprint(
        load_scenario(base.replace('control_rate: "20 Hz"', 'control_rate: "20 Hz", seed: 7'))
    )
    assert len({at_20, at_50, longer}) == 3
    assert seeded == at_20
