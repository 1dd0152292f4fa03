"""Homotopic minimum-norm differential correction: Junkins & Kim 1990 (Att. 5 of Junkins, Pollock
& Rahman 1990), Appendix Eqs. A1-A11 (L2255-L2325), and Agrawal & Bang 1996 Eqs. 16-28, on
textbook problems with known optima."""

import numpy as np
import pytest

from flexsat.analysis.homotopy import homotopy_minimize


def quadratic(p):
    return (p[0] - 2.0) ** 2 + (p[1] - 1.0) ** 2


def quadratic_gradient(p):
    return np.array([2 * (p[0] - 2.0), 2 * (p[1] - 1.0)])


def rosenbrock(p):
    return (1 - p[0]) ** 2 + 100 * (p[1] - p[0] ** 2) ** 2


def rosenbrock_gradient(p):
    return np.array([-2 * (1 - p[0]) - 400 * p[0] * (p[1] - p[0] ** 2), 200 * (p[1] - p[0] ** 2)])


# -- textbook optima -----------------------------------------------------------------------------
@pytest.mark.parametrize("analytic", [True, False])
def test_quadratic_with_a_linear_inequality(analytic):
    """min (x−2)² + (y−1)² s.t. x + y <= 2 → (1.5, 0.5), J = 0.5, the inequality active."""
    kw = (
        dict(gradient=quadratic_gradient, inequality_jacobian=lambda p: np.array([[-1.0, -1.0]]))
        if analytic
        else {}
    )
    res = homotopy_minimize(
        quadratic, [0.0, 0.0], inequality=lambda p: [-(p[0] + p[1])], inequality_bound=-2.0, **kw
    )
    assert res.success and res.feasible
    assert res.p == pytest.approx([1.5, 0.5], abs=1e-4)
    assert res.objective == pytest.approx(0.5, abs=1e-8)
    assert res.inequality[0] >= -2.0 - 1e-9
    assert "ineq[0]" in res.active
    assert res.projected_gradient < 1e-3


def test_inactive_inequality_gives_the_unconstrained_minimum():
    res = homotopy_minimize(
        lambda p: (p[0] - 0.5) ** 2 + (p[1] - 0.5) ** 2,
        [-1.0, 2.0],
        inequality=lambda p: [-(p[0] + p[1])],
        inequality_bound=-2.0,
    )
    assert res.p == pytest.approx([0.5, 0.5], abs=1e-4)
    assert res.objective == pytest.approx(0.0, abs=1e-8)
    assert "ineq[0]" not in res.active


def test_rosenbrock_in_the_unit_disc():
    """min Rosenbrock s.t. x² + y² <= 1 → (0.786415, 0.617698), J = 0.0456748 (the classic
    constrained example; SLSQP at tol 1e-14 gives 0.045674808719501)."""
    res = homotopy_minimize(
        rosenbrock,
        [-1.0, 0.5],
        gradient=rosenbrock_gradient,
        inequality=lambda p: [1.0 - p @ p],
        inequality_bound=0.0,
        inequality_jacobian=lambda p: -2 * p[None, :],
    )
    assert res.success
    assert res.p == pytest.approx([0.78641515, 0.61769831], abs=2e-4)
    assert res.objective == pytest.approx(0.0456748087, rel=1e-5)
    assert res.p @ res.p <= 1.0 + 1e-9


def test_equality_from_an_infeasible_start():
    """min x² + y² s.t. x y = 1 from (3, 0.5) (f = 1.5): feasibility homotopy, then (1, 1)."""
    res = homotopy_minimize(
        lambda p: p @ p,
        [3.0, 0.5],
        gradient=lambda p: 2 * p,
        equality=lambda p: [p[0] * p[1]],
        equality_target=[1.0],
        equality_jacobian=lambda p: np.array([[p[1], p[0]]]),
    )
    assert res.p == pytest.approx([1.0, 1.0], abs=1e-4)
    assert res.objective == pytest.approx(2.0, abs=1e-8)
    assert res.equality[0] == pytest.approx(1.0, abs=1e-10)
    feas = res.feasibility_steps
    # A5-A7: γ = 0.1 … 1 with the targets γ f_o + (1 − γ) f(p_start)
    assert [s.gamma for s in feas] == pytest.approx(np.linspace(0.1, 1.0, 10))
    assert feas[-1].max_violation < 1e-9
    assert np.array_equal(res.p_feasible, feas[-1].p)


def test_equality_and_bound_together():
    """min x² + y² + z² s.t. x + y + z = 3, x >= 1.5 → (1.5, 0.75, 0.75), J = 3.375."""
    res = homotopy_minimize(
        lambda p: p @ p,
        [0.0, 0.0, 0.0],
        gradient=lambda p: 2 * p,
        equality=lambda p: [p.sum()],
        equality_target=3.0,
        inequality=lambda p: [p[0]],
        inequality_bound=[1.5],
    )
    assert res.p == pytest.approx([1.5, 0.75, 0.75], abs=1e-4)
    assert res.objective == pytest.approx(3.375, abs=1e-8)
    assert set(res.active) >= {"eq[0]", "ineq[0]"}


def test_objective_homotopy_follows_its_targets_seed004_eq17():
    """Every converged objective step satisfies J = γ J_goal + (1 − γ) J(p_feasible), and a
    reachable goal ends the homotopy at γ = 1."""
    res = homotopy_minimize(
        quadratic,
        [0.0, 0.0],
        gradient=quadratic_gradient,
        inequality=lambda p: [-(p[0] + p[1])],
        inequality_bound=-2.0,
        objective_goal=1.0,
    )
    J_feas = quadratic(res.p_feasible)
    for step in res.objective_steps:
        assert step.objective == pytest.approx(
            step.gamma * 1.0 + (1 - step.gamma) * J_feas, rel=1e-9
        )
    assert res.goal_reached and res.gamma == 1.0
    assert res.objective == pytest.approx(1.0, rel=1e-9)
    gammas = [s.gamma for s in res.objective_steps]
    assert np.all(np.diff(gammas) > 0)


def test_minimum_norm_correction_with_weight_eq_a8():
    """x + y = 1 from (0, 0) with W = diag(1, 4): Δp = W⁻¹aᵀ(aW⁻¹aᵀ)⁻¹ = (0.8, 0.2)."""
    res = homotopy_minimize(
        lambda p: 0.0,
        [0.0, 0.0],
        equality=lambda p: [p.sum()],
        equality_target=[1.0],
        weight=[1.0, 4.0],
        minimize=False,
    )
    assert res.p == pytest.approx([0.8, 0.2], abs=1e-9)
    assert res.message.startswith("feasible point found")
    full = homotopy_minimize(
        lambda p: 0.0,
        [0.0, 0.0],
        equality=lambda p: [p.sum()],
        equality_target=[1.0],
        weight=np.diag([1.0, 4.0]),
        minimize=False,
    )
    assert full.p == pytest.approx(res.p, abs=1e-9)


def test_infeasible_constraints_are_reported():
    """x >= 1 and x <= −1 cannot both hold: the feasibility homotopy stops and reports (A8)."""
    res = homotopy_minimize(
        lambda p: p @ p, [0.0, 0.0], inequality=lambda p: [p[0], -p[0]], inequality_bound=[1.0, 1.0]
    )
    assert not res.feasible and not res.success
    assert res.message.startswith("infeasible")
    assert res.jacobian.shape[1] == 2


def test_goal_above_the_feasible_cost_does_nothing():
    res = homotopy_minimize(quadratic, [2.0, 1.0], objective_goal=5.0)
    assert res.success and res.message.startswith("objective_goal")
    assert np.array_equal(res.p, [2.0, 1.0])


def test_too_many_equalities_leave_no_freedom():
    res = homotopy_minimize(
        lambda p: p[0] ** 2, [0.0], equality=lambda p: [p[0]], equality_target=[0.3]
    )
    assert res.p == pytest.approx([0.3]) and "no freedom" in res.message


def test_undefined_gradient_ends_the_objective_phase_there():
    """A non-finite gradient (e.g. a non-differentiable objective) fails that γ step only."""
    grad = lambda p: quadratic_gradient(p) if p[0] < 1.0 else np.full(2, np.nan)  # noqa: E731
    res = homotopy_minimize(quadratic, [0.0, 0.0], gradient=grad)
    assert res.success and not res.goal_reached
    assert res.p[0] < 1.01 and res.objective < quadratic(np.zeros(2))


# -- bad inputs ----------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "kwargs,message",
    [
        (dict(objective=3.0), r"^objective: must be callable"),
        (dict(p0=[]), r"^p0: needs at least one parameter"),
        (dict(p0=[np.nan, 0.0]), r"^p0: must be finite"),
        (dict(p0="x"), r"^p0: must be a numeric vector"),
        (dict(equality=lambda p: [p[0]]), r"^equality_target: give it exactly when"),
        (dict(inequality_bound=1.0), r"^inequality_bound: give it exactly when"),
        (
            dict(inequality=lambda p: [p[0], p[1]], inequality_bound=[1.0, 2.0, 3.0]),
            r"^inequality_bound: must have 2 entries",
        ),
        (
            dict(equality=lambda p: [p[0], p[1]], equality_target=[1.0]),
            r"^equality: must return 1 values",
        ),
        (dict(gradient=lambda p: [1.0]), r"^gradient: must return 2 values"),
        (
            dict(
                equality=lambda p: [p[0]],
                equality_target=[1.0],
                equality_jacobian=lambda p: np.ones((2, 2)),
            ),
            r"^equality_jacobian: must return a",
        ),
        (dict(gamma_step=0.0), r"^gamma_step: must be in \(0, 1.0\]"),
        (dict(gamma_step=1.5), r"^gamma_step: must be in \(0, 1.0\]"),
        (dict(min_gamma_step=0.5, gamma_step=0.1), r"^min_gamma_step: must be in"),
        (dict(max_corrections=2.5), r"^max_corrections: must be an integer"),
        (dict(weight=[1.0, -1.0]), r"^weight: a vector weight must have 2 entries > 0"),
        (dict(weight=[[1.0, 2.0], [2.0, 1.0]]), r"^weight: the matrix W must be positive definite"),
        (dict(weight=[[1.0, 0.5], [0.0, 1.0]]), r"^weight: the matrix W must be symmetric"),
        (dict(gradient="g"), r"^gradient: must be callable or None"),
        (dict(objective=lambda p: np.nan), r"^objective: non-finite value at p0"),
        (
            dict(
                inequality=lambda p: [p[0]],
                inequality_bound=1.0,
                inequality_jacobian=lambda p: [[np.nan, 0.0]],
            ),
            r"^inequality_jacobian: non-finite value at p0",
        ),
    ],
)
def test_bad_inputs_name_the_field(kwargs, message):
    args = dict(objective=quadratic, p0=[0.0, 0.0])
    args.update(kwargs)
    with pytest.raises(ValueError, match=message):
        homotopy_minimize(args.pop("objective"), args.pop("p0"), **args)
