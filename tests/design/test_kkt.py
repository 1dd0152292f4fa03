"""The KKT report of flexsat.design.kkt at hand-made points with known multipliers."""

from __future__ import annotations

import numpy as np
import pytest

from flexsat.design.kkt import kkt_conditions
from flexsat.design.optimization_problem import (
    Constraint,
    DesignProblem,
    DesignVariable,
    Objective,
)
from flexsat.input_checks import FieldError

EPS = np.finfo(float).eps
#: the least-squares multipliers of a 2 × 2 system of condition ~3, times a few units: round-off
ROUND_OFF = 100 * EPS


def _problem(scales: tuple[float, float, float, float] = (1.0, 1.0, 1.0, 1.0)) -> DesignProblem:
    """min x² + y² s.t. x + y = 1, x <= 0.3: optimum (0.3, 0.7) with ν = −1.4, λ = 0.8
    (stationarity (0.6, 1.4) + ν (1, 1) + λ (1, 0) = 0). ``scales``: variables, objective,
    the equality and the inequality."""
    sx, sf, sh, sg = scales
    return DesignProblem(
        (DesignVariable("x", 1.0, -5, 5, scale=sx), DesignVariable("y", -1.0, -5, 5, scale=sx)),
        Objective("r2", lambda v: (float(v @ v), 2 * v), scale=sf),
        (
            Constraint("sum", lambda v: (v[0] + v[1] - 1.0, np.ones(2)), "equality", scale=sh),
            Constraint("cap", lambda v: (v[0] - 0.3, np.array([1.0, 0.0])), scale=sg),
        ),
    )


@pytest.mark.parametrize("scales", [(1.0, 1.0, 1.0, 1.0), (0.5, 3.0, 2.0, 10.0)])
def test_known_optimum_has_zero_residual_and_the_si_multipliers_whatever_the_scales(scales):
    """Residual 0 and the SI multipliers ν = −1.4, λ = 0.8 at the optimum, independent of the
    scaling (the multipliers are reported unscaled, λ = λ̃ scale_f / scale_g)."""
    rep = kkt_conditions(_problem(scales), [0.3, 0.7])
    assert rep.residual <= ROUND_OFF
    assert rep.active == ("sum", "cap") and rep.rank == 2
    assert rep.multipliers["sum"] == pytest.approx(-1.4, abs=ROUND_OFF)
    assert rep.multipliers["cap"] == pytest.approx(0.8, abs=ROUND_OFF)


def test_an_active_bound_carries_the_multiplier_a_constraint_would():
    """The cap written as the bound x <= 0.3 instead: active as "x <= upper", λ = 0.8."""
    prob = DesignProblem(
        (DesignVariable("x", 0.0, -5, 0.3, scale=1.0), DesignVariable("y", 0.0, -5, 5, scale=1.0)),
        Objective("r2", lambda v: (float(v @ v), 2 * v)),
        (Constraint("sum", lambda v: (v[0] + v[1] - 1.0, np.ones(2)), "equality"),),
    )
    rep = kkt_conditions(prob, [0.3, 0.7])
    assert rep.residual <= ROUND_OFF
    assert rep.active == ("sum", "x <= upper")
    assert rep.multipliers["x <= upper"] == pytest.approx(0.8, abs=ROUND_OFF)


@pytest.mark.parametrize("delta", [1e-3, 1e-5])
def test_a_point_pushed_past_the_cap_has_a_residual_of_the_push(delta):
    """(0.3 + δ, 0.7 − δ) stays on x + y = 1 and violates the cap by δ: primal = δ (unit
    scales); both gradients stay active, so stationarity holds (round-off) and λ = 0.8 − 4δ
    makes complementarity (0.8 − 4δ) δ < δ: the residual is δ."""
    rep = kkt_conditions(_problem(), [0.3 + delta, 0.7 - delta])
    assert rep.primal == pytest.approx(delta, rel=1e-9)  # δ from 0.3 + δ − 0.3: ε/δ relative
    assert rep.stationarity <= ROUND_OFF
    assert rep.complementarity == pytest.approx((0.8 - 4 * delta) * delta, rel=1e-9)
    assert rep.residual == rep.primal
    # the same push, in scaled units: the cap's scale 10 divides the violation
    scaled = kkt_conditions(_problem((1.0, 1.0, 1.0, 10.0)), [0.3 + delta, 0.7 - delta])
    assert scaled.primal == pytest.approx(delta / 10, rel=1e-9)


def test_an_inactive_inequality_gets_a_zero_multiplier_and_is_not_active():
    """Inside the cap by more than active_tol, the cap is inactive (λ = 0); within it, active."""
    prob = _problem()
    inside = kkt_conditions(prob, [0.2, 0.8])
    assert "cap" not in inside.active and inside.multipliers["cap"] == 0.0
    near = kkt_conditions(prob, [0.3 - 1e-8, 0.7 + 1e-8], active_tol=1e-6)
    assert near.active == ("sum", "cap")


@pytest.mark.parametrize("tol", [0.0, -1.0, float("nan"), float("inf")])
def test_bad_active_tol_and_problem_are_refused_by_name(tol):
    with pytest.raises(FieldError, match="active_tol"):
        kkt_conditions(_problem(), [0.3, 0.7], active_tol=tol)
    with pytest.raises(FieldError, match="problem"):
        kkt_conditions("not a problem", [0.3, 0.7])  # type: ignore[arg-type]
