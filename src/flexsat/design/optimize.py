r"""Solve a :class:`~flexsat.design.optimization_problem.DesignProblem` with a chosen optimiser.

Methods (all driven in the scaled variables z = x / scale, f / scale_f, g / scale_g):

* ``"slsqp"`` -- sequential least-squares QP, :func:`scipy.optimize.minimize` (D. Kraft, "A
  software package for sequential quadratic programming", DFVLR-FB 88-28, 1988);
* ``"trust-constr"`` -- trust-region SQP / interior point, :func:`scipy.optimize.minimize`
  (Byrd, Hribar & Nocedal, SIAM J. Optim. 9(4), 877-900, 1999), BFGS Hessians;
* ``"ipopt"`` -- interior point through cyipopt (Wächter & Biegler, Math. Program. 106,
  25-57, 2006), when cyipopt imports (:func:`ipopt_available` says why not);
* ``"homotopy"`` -- flexsat's homotopic minimum-norm correction,
  :func:`flexsat.analysis.homotopy.homotopy_minimize` (its convention g >= T is fed −g >= 0).

Whatever the method, the reported optimum carries its own KKT check
(:func:`flexsat.design.kkt.kkt_conditions`): residual, active set and least-squares
multipliers recomputed at x, not the optimiser's.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt
from scipy import optimize as sopt

from flexsat.analysis.homotopy import homotopy_minimize
from flexsat.design.kkt import KKTReport, kkt_conditions
from flexsat.design.optimization_problem import DesignProblem, Evaluation
from flexsat.input_checks import FieldError
from flexsat.units import FloatArray

__all__ = [
    "METHODS",
    "HistoryEntry",
    "OptimizationResult",
    "ipopt_available",
    "optimize_design",
]

METHODS = ("slsqp", "trust-constr", "ipopt", "homotopy")


@dataclass(frozen=True)
class HistoryEntry:
    """One iterate: the design, its objective and the largest scaled constraint violation."""

    iteration: int
    x: FloatArray
    objective: float
    max_violation: float


@dataclass(frozen=True)
class OptimizationResult:
    """A reported optimum, whole: design, responses, KKT check and the path taken.

    Attributes
    ----------
    method : str
    names : tuple of str
        Variable names, in the order of ``x``.
    x : (n,) ndarray
        Design, SI.
    objective : float
    constraints : dict str -> float
        g_i (<= 0) or h_j (= 0) at x, SI.
    multipliers : dict str -> float
        Least-squares multipliers (minimisation convention, SI), see :class:`KKTReport`.
    active : tuple of str
    kkt : KKTReport
    success : bool
        The optimiser's own verdict (the KKT report is the independent one).
    message : str
    iterations : int
    evaluations : int
        Design points evaluated (objective, constraints and gradients each once per point).
    history : tuple of HistoryEntry
    """

    method: str
    names: tuple[str, ...]
    x: FloatArray
    objective: float
    constraints: dict[str, float]
    multipliers: dict[str, float]
    active: tuple[str, ...]
    kkt: KKTReport
    success: bool
    message: str
    iterations: int
    evaluations: int
    history: tuple[HistoryEntry, ...]

    @property
    def design(self) -> dict[str, float]:
        """Variable name -> value, SI."""
        return dict(zip(self.names, (float(v) for v in self.x)))

    def to_dict(self) -> dict[str, Any]:
        """Plain data (str, float, int, bool, lists, dicts; JSON-serialisable) for a report
        or a stored result."""
        kkt = self.kkt
        return {
            "method": self.method,
            "design": self.design,
            "objective": float(self.objective),
            "constraints": dict(self.constraints),
            "multipliers": dict(self.multipliers),
            "active": list(self.active),
            "kkt": {
                "residual": kkt.residual,
                "stationarity": kkt.stationarity,
                "primal": kkt.primal,
                "dual": kkt.dual,
                "complementarity": kkt.complementarity,
                "rank": kkt.rank,
            },
            "success": self.success,
            "message": self.message,
            "iterations": self.iterations,
            "evaluations": self.evaluations,
            "history": [
                {
                    "iteration": h.iteration,
                    "x": [float(v) for v in h.x],
                    "objective": float(h.objective),
                    "max_violation": float(h.max_violation),
                }
                for h in self.history
            ],
        }


def ipopt_available() -> tuple[bool, str]:
    """(True, "") when cyipopt imports, else (False, the reason)."""
    try:
        importlib.import_module("cyipopt")
    except ImportError as exc:
        return False, f"cyipopt does not import ({exc}); install it to use method='ipopt'"
    return True, ""


class _Scaled:
    """The problem in scaled variables, counting objective calls and recording iterates."""

    def __init__(self, problem: DesignProblem):
        self.p = problem
        self.s = problem.scale
        self.fs = problem.objective.scale
        self.gs = problem.constraint_scale
        self.eq = problem.equality
        self.first = problem.evaluations
        self.history: list[HistoryEntry] = []

    def ev(self, z: FloatArray) -> Evaluation:
        return self.p.evaluate(z * self.s)

    def f(self, z: FloatArray) -> float:
        return self.ev(z).objective / self.fs

    def df(self, z: FloatArray) -> FloatArray:
        return self.ev(z).objective_gradient * self.s / self.fs

    def g(self, z: FloatArray, mask: npt.NDArray[np.bool_]) -> FloatArray:
        return (self.ev(z).constraints / self.gs)[mask]

    def dg(self, z: FloatArray, mask: npt.NDArray[np.bool_]) -> FloatArray:
        ev = self.ev(z)
        return (ev.constraint_jacobian * self.s[None, :] / self.gs[:, None])[mask]

    def record(self, z: FloatArray) -> None:
        ev = self.ev(z)
        g = ev.constraints / self.gs
        viol = np.where(self.eq, np.abs(g), np.maximum(g, 0.0))
        x = z * self.s
        viol = np.concatenate(
            [
                viol,
                np.maximum(self.p.lower - x, 0) / self.s,
                np.maximum(x - self.p.upper, 0) / self.s,
            ]
        )
        self.history.append(
            HistoryEntry(len(self.history), x.copy(), ev.objective, float(viol.max(initial=0.0)))
        )


def optimize_design(
    problem: DesignProblem,
    method: str = "slsqp",
    *,
    x0: npt.ArrayLike | None = None,
    tol: float = 1e-12,
    max_iterations: int = 500,
    active_tol: float = 1e-6,
    options: dict[str, Any] | None = None,
) -> OptimizationResult:
    """Minimise ``problem`` by ``method`` and check the KKT conditions at the result.

    Parameters
    ----------
    problem : DesignProblem
    method : {"slsqp", "trust-constr", "ipopt", "homotopy"}
    x0 : (n,) array_like, optional
        Start, SI (default: the variables' values); within the bounds.
    tol : float
        Convergence tolerance handed to the optimiser (SLSQP ``ftol``; trust-constr ``gtol``,
        ``xtol`` and ``barrier_tol``; IPOPT ``tol``; homotopy ``tol``), scaled units.
    max_iterations : int
    active_tol : float
        Activity threshold of the KKT check (:func:`~flexsat.design.kkt.kkt_conditions`).
    options : dict, optional
        Further options passed to the optimiser as they are (homotopy: keyword arguments of
        :func:`~flexsat.analysis.homotopy.homotopy_minimize`, e.g. ``objective_goal``).

    Returns
    -------
    OptimizationResult
    """
    if not isinstance(problem, DesignProblem):
        raise FieldError("problem", f"must be a DesignProblem, got {type(problem).__name__}")
    if method not in METHODS:
        raise FieldError("method", f"must be one of {METHODS}, got {method!r}")
    if not (isinstance(tol, (int, float)) and np.isfinite(tol) and tol > 0):
        raise FieldError("tol", f"must be finite and > 0, got {tol!r}")
    if (
        isinstance(max_iterations, bool)
        or not isinstance(max_iterations, int)
        or max_iterations < 1
    ):
        raise FieldError("max_iterations", f"must be an integer >= 1, got {max_iterations!r}")
    if options is not None and not isinstance(options, dict):
        raise FieldError("options", f"must be a dict, got {options!r}")
    x_start = problem.start(x0)
    sp = _Scaled(problem)
    z0 = x_start / sp.s
    sp.record(z0)
    run = _RUNNERS[method]
    z, success, message, iterations = run(sp, z0, tol, max_iterations, dict(options or {}))
    # SLSQP may end a round-off outside a bound; the bounds are hard (a wall thinner than its
    # minimum is not a design), so the reported design is projected onto them
    x = np.clip(z * sp.s, problem.lower, problem.upper)
    ev = problem.evaluate(x)
    if not np.array_equal(sp.history[-1].x, x):
        sp.record(x / sp.s)
    report = kkt_conditions(problem, ev, active_tol=active_tol)
    return OptimizationResult(
        method=method,
        names=problem.names,
        x=x,
        objective=ev.objective,
        constraints={c.name: float(v) for c, v in zip(problem.constraints, ev.constraints)},
        multipliers=report.multipliers,
        active=report.active,
        kkt=report,
        success=bool(success),
        message=str(message),
        iterations=int(iterations),
        evaluations=problem.evaluations - sp.first,
        history=tuple(sp.history),
    )


Runner = Callable[
    [_Scaled, FloatArray, float, int, dict[str, Any]], tuple[FloatArray, bool, str, int]
]


def _bounds(sp: _Scaled) -> sopt.Bounds:
    return sopt.Bounds(sp.p.lower / sp.s, sp.p.upper / sp.s)


def _run_slsqp(
    sp: _Scaled, z0: FloatArray, tol: float, max_iter: int, options: dict[str, Any]
) -> tuple[FloatArray, bool, str, int]:
    cons = []
    ineq, eq = ~sp.eq, sp.eq
    if ineq.any():  # scipy's SLSQP wants c(z) >= 0: feed −g
        cons.append(
            {"type": "ineq", "fun": lambda z: -sp.g(z, ineq), "jac": lambda z: -sp.dg(z, ineq)}
        )
    if eq.any():
        cons.append({"type": "eq", "fun": lambda z: sp.g(z, eq), "jac": lambda z: sp.dg(z, eq)})
    res = sopt.minimize(
        sp.f,
        z0,
        jac=sp.df,
        method="SLSQP",
        bounds=_bounds(sp),
        constraints=cons,
        callback=sp.record,
        options={"ftol": tol, "maxiter": max_iter, **options},
    )
    return res.x, res.success, res.message, res.nit


def _run_trust_constr(
    sp: _Scaled, z0: FloatArray, tol: float, max_iter: int, options: dict[str, Any]
) -> tuple[FloatArray, bool, str, int]:
    cons = []
    ineq, eq = ~sp.eq, sp.eq
    if ineq.any():
        cons.append(
            sopt.NonlinearConstraint(
                lambda z: sp.g(z, ineq), -np.inf, 0.0, jac=lambda z: sp.dg(z, ineq)
            )
        )
    if eq.any():
        cons.append(
            sopt.NonlinearConstraint(lambda z: sp.g(z, eq), 0.0, 0.0, jac=lambda z: sp.dg(z, eq))
        )
    res = sopt.minimize(
        sp.f,
        z0,
        jac=sp.df,
        hess=sopt.BFGS(),
        method="trust-constr",
        bounds=_bounds(sp),
        constraints=cons,
        callback=lambda z, state: sp.record(z),
        options={
            "gtol": tol,
            "xtol": tol,
            "barrier_tol": tol,
            # scipy's default barrier start (0.1) leaves the iterate ~1e-6 (scaled) inside an
            # active bound; the start is feasible for the bounds, so begin near the tolerance
            "initial_barrier_parameter": tol,
            "initial_barrier_tolerance": tol,
            "maxiter": max_iter,
            **options,
        },
    )
    return res.x, res.status in (1, 2), res.message, res.nit


def _run_ipopt(
    sp: _Scaled, z0: FloatArray, tol: float, max_iter: int, options: dict[str, Any]
) -> tuple[FloatArray, bool, str, int]:
    ok, why = ipopt_available()
    if not ok:
        raise FieldError("method", why)
    cyipopt = importlib.import_module("cyipopt")
    ineq, eq = ~sp.eq, sp.eq
    cons = []
    if ineq.any():
        cons.append(
            {"type": "ineq", "fun": lambda z: -sp.g(z, ineq), "jac": lambda z: -sp.dg(z, ineq)}
        )
    if eq.any():
        cons.append({"type": "eq", "fun": lambda z: sp.g(z, eq), "jac": lambda z: sp.dg(z, eq)})
    bounds = list(zip(sp.p.lower / sp.s, sp.p.upper / sp.s))
    res = cyipopt.minimize_ipopt(
        sp.f,
        z0,
        jac=sp.df,
        bounds=bounds,
        constraints=cons,
        options={"tol": tol, "max_iter": max_iter, "print_level": 0, **options},
    )
    sp.record(res.x)
    return res.x, res.success, str(res.message), int(getattr(res, "nit", 0))


def _run_homotopy(
    sp: _Scaled, z0: FloatArray, tol: float, max_iter: int, options: dict[str, Any]
) -> tuple[FloatArray, bool, str, int]:
    # homotopy_minimize's inequalities are g >= T: constraints −g̃ >= 0 and the finite bounds
    ineq, eq = ~sp.eq, sp.eq
    zlo, zhi = sp.p.lower / sp.s, sp.p.upper / sp.s
    lo, hi = np.flatnonzero(np.isfinite(zlo)), np.flatnonzero(np.isfinite(zhi))
    n = z0.size
    eye = np.eye(n)

    def inequality(z: FloatArray) -> FloatArray:
        return np.concatenate([-sp.g(z, ineq), z[lo] - zlo[lo], zhi[hi] - z[hi]])

    def inequality_jacobian(z: FloatArray) -> FloatArray:
        return np.vstack([-sp.dg(z, ineq), eye[lo], -eye[hi]])

    kwargs: dict[str, Any] = {"tol": tol, "max_steps": max_iter}
    if inequality(z0).size:
        kwargs.update(
            inequality=inequality, inequality_bound=0.0, inequality_jacobian=inequality_jacobian
        )
    if eq.any():
        kwargs.update(
            equality=lambda z: sp.g(z, eq),
            equality_target=np.zeros(int(eq.sum())),
            equality_jacobian=lambda z: sp.dg(z, eq),
        )
    kwargs.update(options)
    res = homotopy_minimize(sp.f, z0, gradient=sp.df, **kwargs)
    for step in res.path:
        sp.record(step.p)
    return res.p, res.success, res.message, len(res.path)


_RUNNERS: dict[str, Runner] = {
    "slsqp": _run_slsqp,
    "trust-constr": _run_trust_constr,
    "ipopt": _run_ipopt,
    "homotopy": _run_homotopy,
}
