"""EPS slew-goal rows of ``flexsat validate`` (flexsat.checks.eps): the planned slews with
torquers alone meet the EPS slew study c. 1989 goals (3 % Euler-angle error and a 10:1 rim
deflection reduction at 1.25 T) at 10 s and at 6 s, and the rows would fail the values the
paper's torquers-only feedback cases A and D leave (docs/eps.md)."""

import pytest

from flexsat.checks import run_checks, select_checks


@pytest.fixture(scope="module")
def goal_checks():
    rows = [c for c in select_checks("eps") if "planned" in c.quantity]
    assert len(rows) == 4
    return rows


def test_the_planned_slews_meet_both_goals_at_10_and_6_s(goal_checks):
    results = run_checks(checks=goal_checks)
    assert [r.status for r in results] == ["pass"] * 4
    # far inside the goals: the 10 design modes are brought to rest at T, what remains is
    # the 35 modes above them (measured: 3e-6 % and ratios 16,400:1 and 2,500:1)
    for r in results:
        assert r.computed < 0.01 * (r.check.published + r.check.atol)


def test_the_goal_rows_refuse_what_the_feedback_cases_leave(goal_checks):
    # case D's 9.6 % (95.7 mrad of 1 rad) and A's 5.5:1, D's 4.7:1 (docs/eps.md)
    angle = [c for c in goal_checks if "Euler" in c.quantity]
    ratio = [c for c in goal_checks if "deflection" in c.quantity]
    assert all(not c.passes(9.57) and c.passes(2.9) and not c.passes(3.1) for c in angle)
    assert all(not c.passes(1 / 5.5) and not c.passes(1 / 4.7) and c.passes(1 / 11) for c in ratio)
