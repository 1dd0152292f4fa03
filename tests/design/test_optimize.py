"""Claims about the design-optimisation layer (``design.optimize``, ``design.kkt``,
``design.optimization_problem``) on problems whose optimum is known in closed form.

Tolerances: the closed-form tube optimum is reproduced to 1e-8 relative (issue 23's bound; the
KKT system there is solved by SLSQP to its ftol = 1e-10 in scaled units, and the optimum sits
at a vertex, where x is fixed by the two active constraints to their round-off, ~1e-15);
optimisers agree within 1 % (issue 23) and every reported optimum has KKT residual <= 1e-6.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from flexsat.design.kkt import kkt_conditions
from flexsat.design.optimization_problem import (
    Constraint,
    DesignProblem,
    DesignVariable,
    Objective,
)
from flexsat.design.optimize import ipopt_available, optimize_design
from flexsat.design.reference_problems import (
    CANTILEVER_BETA1_L,
    CantileverTube,
    cantilever_tube_optimum,
)
from flexsat.input_checks import FieldError

KKT = 1e-6


def test_beta1_l_is_the_first_clamped_free_root():
    # Rao (2007) Table 11.3 gives β₁L = 1.875104; the root satisfies cos·cosh = −1
    b = CANTILEVER_BETA1_L
    assert abs(b - 1.875104) < 1e-6
    assert abs(np.cos(b) * np.cosh(b) + 1.0) < 1e-14


def test_slsqp_reproduces_the_closed_form_tube_optimum_and_its_multipliers_to_1e_8():
    tube = CantileverTube()
    exact = cantilever_tube_optimum(tube)
    res = optimize_design(tube.problem(), "slsqp")
    assert res.kkt.residual <= KKT
    assert set(res.active) == {"frequency floor", "t >= lower"}
    assert abs(res.x[0] - exact["t"]) <= 1e-8 * exact["t"]
    assert abs(res.x[1] - exact["D"]) <= 1e-8 * exact["D"]
    assert abs(res.objective - exact["mass"]) <= 1e-8 * exact["mass"]
    for name in ("frequency floor", "t >= lower"):
        assert abs(res.multipliers[name] - exact[name]) <= 1e-8 * abs(exact[name]), name
    # the frequency floor is met exactly and the history starts at the start, ends at x
    assert abs(res.constraints["frequency floor"]) <= 1e-8 * tube.omega_min
    assert np.array_equal(res.history[0].x, tube.problem().x0)
    assert np.array_equal(res.history[-1].x, res.x)
    assert res.design == {"t": res.x[0], "D": res.x[1]}
    # the history ends at the optimum, and the whole result is plain data
    data = json.loads(json.dumps(res.to_dict()))
    assert data["active"] == list(res.active) and data["kkt"]["residual"] == res.kkt.residual
    assert data["history"][-1]["objective"] == res.objective
    assert len(data["history"]) == len(res.history) >= res.iterations


@pytest.mark.parametrize(
    "method, x0",
    [
        ("trust-constr", [5e-3, 0.1]),
        ("homotopy", None),
    ],
)
def test_independent_optimisers_agree_with_the_closed_form_tube_optimum(method, x0):
    tube = CantileverTube()
    exact = cantilever_tube_optimum(tube)
    res = optimize_design(tube.problem(), method, x0=x0)
    assert res.kkt.residual <= KKT, res.kkt
    assert abs(res.objective - exact["mass"]) <= 0.01 * exact["mass"]
    assert np.allclose(res.x, [exact["t"], exact["D"]], rtol=0.01, atol=0)
    lam = res.multipliers["frequency floor"]
    assert abs(lam - exact["frequency floor"]) <= 0.01 * exact["frequency floor"]


def test_a_central_difference_gradient_asked_for_by_name_reaches_the_same_optimum():
    tube = CantileverTube()
    exact = cantilever_tube_optimum(tube)
    base = tube.problem()
    fd = DesignProblem(
        base.variables,
        Objective("mass", lambda x: tube.responses(x)["mass"][0], gradient="central"),
        (
            Constraint(
                "frequency floor",
                lambda x: tube.omega_min - tube.responses(x)["omega"][0],
                gradient="central",
                scale=tube.omega_min,
            ),
        ),
    )
    ev, ev_fd = base.evaluate(base.x0), fd.evaluate(base.x0)
    # O(h²) truncation with h = 1e-6 max(|x|, scale) and round-off ε|f|/h: both ≲ 1e-9
    assert np.allclose(ev_fd.objective_gradient, ev.objective_gradient, rtol=1e-7)
    assert np.allclose(ev_fd.constraint_jacobian, ev.constraint_jacobian, rtol=1e-7)
    res = optimize_design(fd, "slsqp")
    assert abs(res.objective - exact["mass"]) <= 1e-6 * exact["mass"]
    assert res.kkt.residual <= KKT


def _circle_problem() -> DesignProblem:
    """min x² + y² subject to x + y = 1 and x <= 0.3: x = 0.3, y = 0.7 (active inequality).

    Stationarity: (0.6, 1.4) + ν (1, 1) + λ (1, 0) = 0, so ν = −1.4, λ = 0.8."""
    return DesignProblem(
        (DesignVariable("x", 1.0, -5, 5, scale=1.0), DesignVariable("y", -1.0, -5, 5, scale=1.0)),
        Objective("r2", lambda v: (float(v @ v), 2 * v)),
        (
            Constraint("sum", lambda v: (v[0] + v[1] - 1.0, np.ones(2)), kind="equality"),
            Constraint("cap", lambda v: (v[0] - 0.3, np.array([1.0, 0.0]))),
        ),
    )


@pytest.mark.parametrize("method", ["slsqp", "trust-constr", "homotopy"])
def test_equality_and_inequality_multipliers_of_a_quadratic_program(method):
    res = optimize_design(_circle_problem(), method)
    assert res.kkt.residual <= KKT
    assert np.allclose(res.x, [0.3, 0.7], atol=1e-6)
    assert set(res.active) == {"sum", "cap"}
    assert res.multipliers["sum"] == pytest.approx(-1.4, abs=1e-6)
    assert res.multipliers["cap"] == pytest.approx(0.8, abs=1e-6)


def test_kkt_check_fails_away_from_the_optimum_and_flags_a_wrong_signed_multiplier():
    prob = _circle_problem()
    # feasible, not optimal: stationarity fails
    rep = kkt_conditions(prob, [0.2, 0.8])
    assert rep.stationarity > 0.1 and rep.primal == 0.0 and rep.active == ("sum",)
    # infeasible: primal violation of the equality
    assert kkt_conditions(prob, [0.3, 0.3]).primal == pytest.approx(0.4)
    # the cap pushing the wrong way: min x² + y² with x + y = 1, x >= 0.6 written as
    # 0.6 − x <= 0 is optimal at (0.6, 0.4); the same point with the cap as x − 0.6 <= 0 is not
    # a minimum (x = 0.5 is better): (1.2, 0.8) + ν (1, 1) + λ (±1, 0) = 0 gives λ = ±0.4
    wrong = DesignProblem(
        prob.variables,
        prob.objective,
        (prob.constraints[0], Constraint("cap", lambda v: (v[0] - 0.6, np.array([1.0, 0.0])))),
    )
    right = DesignProblem(
        prob.variables,
        prob.objective,
        (prob.constraints[0], Constraint("cap", lambda v: (0.6 - v[0], np.array([-1.0, 0.0])))),
    )
    assert kkt_conditions(right, [0.6, 0.4]).residual <= 1e-12
    bad = kkt_conditions(wrong, [0.6, 0.4])
    assert kkt_conditions(right, [0.6, 0.4]).multipliers["cap"] == pytest.approx(0.4)
    assert bad.dual == pytest.approx(0.4) and bad.multipliers["cap"] == pytest.approx(-0.4)


def test_ipopt_agrees_with_slsqp_when_cyipopt_imports():
    ok, why = ipopt_available()
    if not ok:
        pytest.skip(why)
    tube = CantileverTube()
    exact = cantilever_tube_optimum(tube)
    res = optimize_design(tube.problem(), "ipopt")
    assert res.kkt.residual <= KKT
    assert abs(res.objective - exact["mass"]) <= 0.01 * exact["mass"]


def _var(**kw):
    return DesignVariable(**{"name": "a", "value": 1.0, "lower": 0.0, "upper": 2.0, **kw})


@pytest.mark.parametrize(
    "build, field",
    [
        (lambda: _var(value=3.0), "variables['a'].value"),
        (lambda: _var(lower=2.0, upper=1.0), "variables['a'].lower"),
        (lambda: _var(value=np.nan), "variables['a'].value"),
        (lambda: _var(scale=-1.0), "variables['a'].scale"),
        (lambda: _var(name=""), "name"),
        (lambda: Objective("f", 3.0), "objective.function"),
        (lambda: Objective("f", abs, gradient="forward"), "objective.gradient"),
        (lambda: Objective("f", abs, scale=0.0), "objective.scale"),
        (lambda: Constraint("c", abs, kind=">="), "constraints['c'].kind"),
        (
            lambda: DesignProblem((_var(), _var()), Objective("f", abs)),
            "variables",
        ),
        (lambda: DesignProblem((), Objective("f", abs)), "variables"),
        (lambda: DesignProblem((_var(),), abs), "objective"),
    ],
)
def test_bad_problem_data_is_refused_by_name(build, field):
    with pytest.raises(FieldError) as exc:
        build()
    assert exc.value.field == field


@pytest.mark.parametrize(
    "function, field",
    [
        (lambda x: float(x[0]), "objective.function"),  # analytic but no gradient
        (lambda x: (float(x[0]), np.ones(3)), "objective.function"),  # wrong gradient size
        (lambda x: (np.nan, np.ones(1)), "objective.function"),
        (lambda x: ("a", np.ones(1)), "objective.function"),
    ],
)
def test_bad_responses_are_refused_by_name(function, field):
    prob = DesignProblem((_var(),), Objective("f", function))
    with pytest.raises(FieldError) as exc:
        optimize_design(prob)
    assert exc.value.field == field


@pytest.mark.parametrize(
    "kwargs, field",
    [
        (dict(method="newton"), "method"),
        (dict(x0=[1.0, 2.0]), "x0"),
        (dict(x0=[5.0]), "x0"),
        (dict(tol=0.0), "tol"),
        (dict(max_iterations=0), "max_iterations"),
        (dict(options=[1]), "options"),
    ],
)
def test_bad_optimiser_settings_are_refused_by_name(kwargs, field):
    prob = DesignProblem((_var(),), Objective("f", lambda x: (float(x[0] ** 2), 2 * x)))
    with pytest.raises(FieldError) as exc:
        optimize_design(prob, **kwargs)
    assert exc.value.field == field
