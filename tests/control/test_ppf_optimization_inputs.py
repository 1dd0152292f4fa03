"""The PPF optimiser and its goal rule refuse non-finite, negative and absurd goals, and a start
cost out of float64 scale, by name (issue 21), instead of writing NaN paths as a result."""

from __future__ import annotations

import math

import numpy as np
import pytest

from flexsat.cases.agrawal_bang import agrawal_bang
from flexsat.cases.agrawal_bang_ppf import GoalRule, ppf_problem
from flexsat.control.ppf_optimization import optimize_ppf_gains
from flexsat.input_checks import FieldError

G0 = np.full(9, 100.0)  # the paper's initial gains (Agrawal & Bang 1996, L264)


@pytest.fixture(scope="module")
def problem():
    return ppf_problem(agrawal_bang(), (100.0, 100.0), "first").problem


@pytest.mark.parametrize(
    "goal, field",
    [
        ({"goal_ratio": math.nan}, "goal_ratio"),
        ({"goal_ratio": math.inf}, "goal_ratio"),
        ({"goal_ratio": 1e300}, "goal_ratio"),  # J_goal beyond J_init/rtol
        ({"goal_ratio": -0.5}, "goal_ratio"),
        ({"J_goal": -1e300}, "J_goal"),
        ({"J_goal": 1e300}, "J_goal"),
        ({}, "J_goal"),
    ],
)
def test_the_optimiser_refuses_a_goal_by_name(problem, goal, field):
    with pytest.raises(FieldError, match=f"^{field}: "):
        optimize_ppf_gains(problem, G0, **goal)


def test_a_start_cost_out_of_float64_scale_is_refused_naming_the_problem():
    # weights of 1e300 scale J_init to ~1e-306: no digits left for rtol = 1e-10
    tiny = ppf_problem(agrawal_bang(), (1e300, 1e300), "three").problem
    with pytest.raises(FieldError, match="^problem: the cost at the start"):
        optimize_ppf_gains(tiny, G0, goal_ratio=0.2)


def test_a_goal_within_the_bounds_gives_finite_paths(problem):
    result = optimize_ppf_gains(problem, G0, goal_ratio=1.0 + 1e-3, gamma_step=1.0, max_steps=3)
    assert np.isfinite(result.cost_path).all() and np.isfinite(result.gains).all()


@pytest.mark.parametrize("value", [0.0, -1.0, math.nan, math.inf])
def test_a_ratio_goal_rule_must_be_positive_and_finite(value):
    with pytest.raises(FieldError, match="^goal.value: "):
        GoalRule("ratio", value)
