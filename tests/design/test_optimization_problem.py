"""A design problem as data (flexsat.design.optimization_problem): evaluation, differences."""

from __future__ import annotations

import numpy as np
import pytest

from flexsat.design.optimization_problem import (
    Constraint,
    DesignProblem,
    DesignVariable,
    Objective,
)
from flexsat.input_checks import FieldError

EPS = np.finfo(float).eps


def test_each_response_is_called_once_per_point_and_the_last_point_is_cached():
    calls = {"f": 0, "g": 0}

    def f(x):
        calls["f"] += 1
        return float(x @ x), 2 * x

    def g(x):
        calls["g"] += 1
        return float(x[0] - 1), np.array([1.0, 0.0])

    prob = DesignProblem(
        (DesignVariable("a", 1.0), DesignVariable("b", 2.0)), Objective("f", f), Constraint("g", g)
    )
    first = prob.evaluate([1.0, 2.0])
    assert prob.evaluate(np.array([1.0, 2.0])) is first  # cached: no new call
    assert calls == {"f": 1, "g": 1} and prob.evaluations == 1
    prob.evaluate([0.5, 2.0])
    prob.evaluate([1.0, 2.0])  # only the last point is kept
    assert calls == {"f": 3, "g": 3} and prob.evaluations == 3
    assert first.constraints.tolist() == [0.0] and first.objective == 5.0


def test_central_differences_have_the_o_h2_truncation_of_the_formula():
    """For f = x³ the central difference is exactly 3x² + h² (f''' = 6, error h² f'''/6), with
    h = step · max(|x|, scale); round-off ε|f|/h ~ 1e-10 here, far below h² = 1e-6."""
    x0, step, scale = 2.0, 5e-4, 0.1
    prob = DesignProblem(
        (DesignVariable("x", x0, scale=scale),),
        Objective("cube", lambda x: float(x[0] ** 3), gradient="central", step=step),
    )
    h = step * max(abs(x0), scale)
    grad = prob.evaluate([x0]).objective_gradient[0]
    assert grad == pytest.approx(3 * x0**2 + h**2, abs=100 * EPS * x0**3 / h)
    assert abs(grad - 3 * x0**2) > 0.5 * h**2  # the truncation is there, and of that size


def test_the_response_cannot_change_the_design_vector():
    """Each response gets a copy of x: one that writes into it does not move the point."""

    def scribble(x):
        value = float(x.sum())
        x[:] = 99.0
        return value, np.ones(2)

    prob = DesignProblem(
        (DesignVariable("a", 1.0), DesignVariable("b", 1.0)),
        Objective("f", scribble),
        Constraint("g", lambda x: (float(x[0]), np.array([1.0, 0.0]))),
    )
    ev = prob.evaluate([1.0, 1.0])
    assert ev.x.tolist() == [1.0, 1.0] and ev.constraints.tolist() == [1.0]


def test_scales_default_to_the_magnitude_and_start_checks_the_bounds():
    prob = DesignProblem(
        (DesignVariable("a", -4.0, -5, 5), DesignVariable("b", 0.0, -1, 1)),
        Objective("f", lambda x: (0.0, np.zeros(2))),
    )
    assert prob.scale.tolist() == [4.0, 1.0]  # |value|, or 1 for a zero value
    with pytest.raises(FieldError, match="x0: b = 2.0 is outside its bounds"):
        prob.start([0.0, 2.0])
    with pytest.raises(FieldError, match="x0: must have 2 entries"):
        prob.start([0.0])


@pytest.mark.parametrize(
    "function, message",
    [
        (lambda x: 1.0, r"objective.function: with gradient='analytic' must return \(value"),
        (lambda x: (np.nan, np.zeros(1)), "objective.function: returned a non-finite value"),
        (lambda x: (1.0, [np.inf]), "objective.function: gradient must be 1 finite numbers"),
    ],
)
def test_a_bad_response_is_refused_naming_it(function, message):
    prob = DesignProblem((DesignVariable("a", 1.0),), Objective("f", function))
    with pytest.raises(FieldError, match=message):
        prob.evaluate([1.0])


def test_bad_problem_data_is_refused_by_field():
    with pytest.raises(FieldError, match=r"variables\['a'\].value: 3.0 is outside"):
        DesignVariable("a", 3.0, 0.0, 1.0)
    with pytest.raises(FieldError, match="variables: names must be distinct"):
        DesignProblem(
            (DesignVariable("a", 1.0), DesignVariable("a", 2.0)),
            Objective("f", lambda x: (0.0, np.zeros(2))),
        )
    with pytest.raises(FieldError, match=r"constraints\['h'\].kind: must be one of"):
        Constraint("h", lambda x: (0.0, np.zeros(1)), kind="<=")
