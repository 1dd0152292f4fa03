r"""Discrete placement on top of a continuous design problem.

Choose ``size`` locations among candidates by greedy forward selection or by Fedorov-style
exchange (one-for-one swaps until no swap improves; V. V. Fedorov, *Theory of Optimal
Experiments*, Academic Press 1972, §3.2), or by exhaustive enumeration on small cases
(:mod:`flexsat.analysis.placement`), then optimise the continuous variables of the chosen
set. The score maximised by the search is either a cheap criterion of the set
(:func:`gramian_log_det_score`: log det of the modal controllability Gramian, the D-optimal
criterion of actuator placement) or the continuous optimum itself (:func:`nested_score`:
minus the optimal objective of the set's continuous problem, so the search and the continuous
problem answer the same question).
"""

from __future__ import annotations

from collections.abc import Callable, Hashable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from flexsat.analysis.gramians import modal_controllability_gramian
from flexsat.analysis.placement_search import SearchResult, exchange, exhaustive, greedy
from flexsat.design.optimization_problem import DesignProblem
from flexsat.design.optimize import OptimizationResult, optimize_design
from flexsat.input_checks import FieldError, require_finite

__all__ = [
    "SEARCHES",
    "PlacementDesign",
    "gramian_log_det_score",
    "nested_score",
    "place_then_optimize",
]

SEARCHES = ("greedy", "exchange", "exhaustive")
Selection = tuple[Hashable, ...]
ProblemFor = Callable[[Selection], DesignProblem]


@dataclass(frozen=True)
class PlacementDesign:
    """The chosen set (with the search that chose it) and its continuous optimum."""

    search: SearchResult
    result: OptimizationResult


def gramian_log_det_score(
    omega: npt.ArrayLike, zeta: npt.ArrayLike, actuators: Mapping[Hashable, npt.ArrayLike]
) -> Callable[[Selection], float]:
    """Selection -> log det X_c of the modal controllability Gramian (Att. 4 Eqs. 24-25,
    :func:`~flexsat.analysis.gramians.modal_controllability_gramian`) with the selected
    actuators' modal input vectors as the columns of B; −inf for an uncontrollable set."""
    if not isinstance(actuators, Mapping) or not actuators:
        raise FieldError("actuators", "must be a non-empty mapping label -> modal input vector")
    cols = {k: require_finite(v, f"actuators[{k!r}]") for k, v in actuators.items()}
    w, z = require_finite(omega, "omega"), require_finite(zeta, "zeta")

    def score(selection: Selection) -> float:
        X = modal_controllability_gramian(w, z, np.column_stack([cols[k] for k in selection]))
        sign, logdet = np.linalg.slogdet(X)
        return float(logdet) if sign > 0 else -np.inf

    return score


def nested_score(
    problem_for: ProblemFor,
    method: str = "slsqp",
    kkt_tol: float = 1e-6,
    **optimize_kwargs: Any,
) -> Callable[[Selection], float]:
    """Selection -> −(optimal objective of ``problem_for(selection)``), refusing (FieldError)
    a continuous optimum whose KKT residual exceeds ``kkt_tol``: a set is never ranked by a
    point that is not an optimum."""
    if not callable(problem_for):
        raise FieldError("problem_for", f"must be callable, got {problem_for!r}")

    def score(selection: Selection) -> float:
        res = optimize_design(problem_for(selection), method, **optimize_kwargs)
        if not res.kkt.residual <= kkt_tol:
            raise FieldError(
                "problem_for",
                f"the continuous optimum of {selection!r} has KKT residual "
                f"{res.kkt.residual:.3g} > {kkt_tol:g} ({res.message})",
            )
        return -res.objective

    return score


def place_then_optimize(
    candidates: Sequence[Hashable],
    size: int,
    score: Callable[[Selection], float],
    problem_for: ProblemFor,
    *,
    search: str = "exchange",
    method: str = "slsqp",
    **optimize_kwargs: Any,
) -> PlacementDesign:
    """Choose ``size`` of ``candidates`` maximising ``score`` by ``search``, then minimise the
    continuous ``problem_for(selection)`` by ``method`` (:func:`~flexsat.design.optimize.
    optimize_design`, with ``optimize_kwargs``)."""
    searches: dict[str, Callable[..., SearchResult]] = {
        "greedy": greedy,
        "exchange": exchange,
        "exhaustive": exhaustive,
    }
    if search not in searches:
        raise FieldError("search", f"must be one of {SEARCHES}, got {search!r}")
    if not callable(problem_for):
        raise FieldError("problem_for", f"must be callable, got {problem_for!r}")
    found = searches[search](candidates, size, score)
    best = optimize_design(problem_for(found.selection), method, **optimize_kwargs)
    return PlacementDesign(found, best)
