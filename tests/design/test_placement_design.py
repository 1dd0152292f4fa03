"""Claims about discrete placement on top of a continuous problem (``design.placement_design``).

A cantilever beam's three lowest modes (FE, :mod:`flexsat.structures.fem`), five candidate force
actuators along it. The continuous problem of a set: actuator authorities b_i (N per unit
command) minimising J_LQ(B diag b) + c Σ b_i² (LQ regulation from a unit modal initial state
against an actuator-size cost), gradient by the LQ adjoint (∂J/∂B, Riccati sensitivity).
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from flexsat.analysis.riccati_sensitivity import lq_cost_gradient
from flexsat.design.optimization_problem import DesignProblem, DesignVariable, Objective
from flexsat.design.optimize import optimize_design
from flexsat.design.placement_design import (
    gramian_log_det_score,
    nested_score,
    place_then_optimize,
)
from flexsat.input_checks import FieldError
from flexsat.structures.fem import Structure
from flexsat.structures.sections import Material, Section

SIZE_COST = 0.05
ZETA = 0.01


@pytest.fixture(scope="module")
def beam():
    s = Structure("beam")
    for i in range(11):
        s.add_node(i, (0.2 * i, 0.0, 0.0))
    for i in range(10):
        s.add_frame(i, i + 1, Material(70e9, 2700.0), Section.tube(0.03, 0.002))
    s.clamp(0)
    for i in range(1, 11):  # in-plane bending only: three distinct modes, all seen by uy
        s.clamp(i, ("ux", "uz", "rx", "ry"))
    asm = s.assemble()
    fe = asm.modes(3)
    candidates = {f"{n}Y": fe.shapes[asm.index(n, "uy")] for n in (2, 4, 6, 8, 10)}
    return fe.omegas, candidates


def _problem_for(omegas, candidates):
    n = omegas.size
    A = np.block(
        [[np.zeros((n, n)), np.eye(n)], [-np.diag(omegas**2), -np.diag(2 * ZETA * omegas)]]
    )
    X0 = np.eye(2 * n)

    def problem_for(selection):
        cols = np.column_stack([np.concatenate([np.zeros(n), candidates[k]]) for k in selection])

        def objective(b):
            g = lq_cost_gradient(A, cols * b, np.eye(2 * n), np.eye(len(b)), X0)
            dJ = np.einsum("ij,ij->j", g.dB, cols)  # ∂B/∂b_i = column i of cols
            return g.cost + SIZE_COST * b @ b, dJ + 2 * SIZE_COST * b

        b0 = np.ones(len(selection))
        return DesignProblem(
            tuple(DesignVariable(f"b[{k}]", 1.0, 0.01, 100.0, scale=1.0) for k in selection),
            Objective("LQ cost + size", objective, scale=objective(b0)[0]),
        )

    return problem_for


def test_exchange_finds_the_exhaustive_gramian_optimum(beam):
    omegas, candidates = beam
    score = gramian_log_det_score(omegas, np.full(omegas.size, ZETA), candidates)
    design = place_then_optimize(
        list(candidates), 2, score, _problem_for(omegas, candidates), search="exchange"
    )
    best = max(itertools.combinations(candidates, 2), key=score)
    assert design.search.selection == best
    assert design.search.score == score(best)
    assert design.result.kkt.residual <= 1e-6


def test_the_nested_search_equals_exhaustive_search_of_the_whole_problem(beam):
    # score of a set = minus its continuous optimum: exchange and exhaustive must pick the
    # same pair, and its optimum is the best over all C(5, 2) = 10 pairs
    omegas, candidates = beam
    problem_for = _problem_for(omegas, candidates)
    score = nested_score(problem_for)
    exchange = place_then_optimize(list(candidates), 2, score, problem_for, search="exchange")
    greedy = place_then_optimize(list(candidates), 2, score, problem_for, search="greedy")
    exhaustive = place_then_optimize(list(candidates), 2, score, problem_for, search="exhaustive")
    assert exchange.search.selection == exhaustive.search.selection
    optima = {
        pair: optimize_design(problem_for(pair)).objective
        for pair in itertools.combinations(candidates, 2)
    }
    assert exhaustive.result.objective == pytest.approx(min(optima.values()), rel=1e-9)
    assert greedy.result.objective >= exhaustive.result.objective - 1e-12
    # the pairs' optima differ by >= 1 % here, so "equal" is not decided by round-off
    ranked = sorted(optima.values())
    assert ranked[1] - ranked[0] > 0.01 * ranked[0]
    # the best pair: tip actuator at its authority limit, the other one interior, where
    # ∂J_LQ/∂b = −2 c b balances the gain of authority against its size
    assert exhaustive.search.selection == ("4Y", "10Y")
    assert exhaustive.result.active == ("b[10Y] <= upper",)
    assert exhaustive.result.kkt.residual <= 1e-6


def test_bad_placement_input_is_refused_by_name(beam):
    omegas, candidates = beam
    score = gramian_log_det_score(omegas, np.full(omegas.size, ZETA), candidates)
    problem_for = _problem_for(omegas, candidates)
    with pytest.raises(FieldError) as exc:
        place_then_optimize(list(candidates), 2, score, problem_for, search="annealing")
    assert exc.value.field == "search"
    with pytest.raises(FieldError) as exc:
        place_then_optimize(list(candidates), 2, score, "not callable")
    assert exc.value.field == "problem_for"
    with pytest.raises(FieldError) as exc:
        gramian_log_det_score(omegas, np.full(omegas.size, ZETA), {})
    assert exc.value.field == "actuators"
