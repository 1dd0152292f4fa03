r"""Karush–Kuhn–Tucker conditions at a design point, with multipliers by least squares.

For minimise f(x) subject to g_i(x) <= 0, h_j(x) = 0 and the bounds (written as
lower_k − x_k <= 0, x_k − upper_k <= 0), a regular local minimum x* has multipliers with

.. math::

    \nabla f + \sum_i \lambda_i \nabla g_i + \sum_j \nu_j \nabla h_j = 0
        \quad\text{(stationarity of the Lagrangian)},\\
    g_i \le 0,\ h_j = 0 \quad\text{(primal feasibility)},\qquad
    \lambda_i \ge 0 \quad\text{(dual feasibility)},\qquad
    \lambda_i g_i = 0 \quad\text{(complementary slackness)}

(H. W. Kuhn and A. W. Tucker, "Nonlinear programming", Proc. 2nd Berkeley Symposium, 1951;
J. Nocedal and S. J. Wright, *Numerical Optimization*, 2nd ed., Springer 2006, Thm. 12.1).
This is the minimisation form; a statement for maximisation (∇J = Σ λ ∇g with the opposite
sign of λ) turns into it with f = −J.

The multipliers are not taken from the optimiser: they are recomputed at x by linear least
squares on the gradients of the *active* constraints (inequalities with g̃_i >= −active_tol,
bounds within active_tol, every equality), λ = argmin ‖∇f̃ + J_Aᵀ λ‖, and every inactive
inequality gets λ = 0. All four residuals are measured in the problem's scaled units
(z = x / scale, f̃ = f / scale_f, g̃ = g / scale_g):

* stationarity: ‖∇_z f̃ + J_Aᵀ λ̃‖∞ / max(1, ‖∇_z f̃‖∞),
* primal: the largest scaled violation (positive part of g̃ and of the bounds, |h̃|),
* dual: the largest −λ̃_i over active inequalities and bounds (0 when none is negative),
* complementarity: max |λ̃_i g̃_i| over active inequalities and bounds,

and the KKT residual is their maximum. The multipliers are reported unscaled, for the
problem as written in SI: λ_i = λ̃_i · scale_f / scale_gi (bounds: scale_f / scale_xk).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from flexsat.design.optimization_problem import DesignProblem, Evaluation
from flexsat.input_checks import FieldError
from flexsat.units import FloatArray

__all__ = ["KKTReport", "kkt_conditions"]


@dataclass(frozen=True)
class KKTReport:
    """KKT residuals, active set and least-squares multipliers at one design point.

    Attributes
    ----------
    residual : float
        max of the four residuals below (scaled units, see the module notes).
    stationarity, primal, dual, complementarity : float
    active : tuple of str
        Active constraints by name; a bound is ``"<variable> >= lower"`` or
        ``"<variable> <= upper"``.
    multipliers : dict str -> float
        λ (SI, minimisation convention) of every constraint and of every active bound;
        0 for an inactive inequality.
    rank : int
        Rank of the active gradients (less than their number: the multipliers are not
        unique, least squares gives the minimum-norm ones).
    """

    residual: float
    stationarity: float
    primal: float
    dual: float
    complementarity: float
    active: tuple[str, ...]
    multipliers: dict[str, float]
    rank: int


def kkt_conditions(
    problem: DesignProblem,
    x: npt.ArrayLike | Evaluation,
    active_tol: float = 1e-6,
) -> KKTReport:
    """Check the KKT conditions of ``problem`` at ``x`` (see the module notes).

    Parameters
    ----------
    problem : DesignProblem
    x : (n,) design vector (SI), or an :class:`Evaluation` of the problem at it
    active_tol : float
        A scaled inequality g̃_i >= −active_tol, or a variable within active_tol · scale_k of a
        bound, counts as active.

    Returns
    -------
    KKTReport
    """
    if not isinstance(problem, DesignProblem):
        raise FieldError("problem", f"must be a DesignProblem, got {type(problem).__name__}")
    if not (np.isfinite(active_tol) and active_tol > 0):
        raise FieldError("active_tol", f"must be finite and > 0, got {active_tol!r}")
    ev = x if isinstance(x, Evaluation) else problem.evaluate(x)
    s, fs = problem.scale, problem.objective.scale
    gs, eq = problem.constraint_scale, problem.equality
    grad_f = s * ev.objective_gradient / fs
    g = ev.constraints / gs
    jac = ev.constraint_jacobian * s[None, :] / gs[:, None]
    z, zlo, zhi = ev.x / s, problem.lower / s, problem.upper / s

    # every constraint row in the minimisation form: value (<= 0 or = 0), gradient, name, SI factor
    rows: list[tuple[float, FloatArray, str, float, bool]] = []
    for i, c in enumerate(problem.constraints):
        rows.append((g[i], jac[i], c.name, fs / gs[i], bool(eq[i])))
    for k, name in enumerate(problem.names):
        e = np.zeros(s.size)
        e[k] = 1.0
        if np.isfinite(zlo[k]):
            rows.append((zlo[k] - z[k], -e, f"{name} >= lower", fs / s[k], False))
        if np.isfinite(zhi[k]):
            rows.append((z[k] - zhi[k], e, f"{name} <= upper", fs / s[k], False))

    primal = max([0.0] + [abs(v) if is_eq else max(v, 0.0) for v, _, _, _, is_eq in rows])
    active = [r for r in rows if r[4] or r[0] >= -active_tol]
    if active:
        A = np.array([r[1] for r in active])
        lam, *_, sv = np.linalg.lstsq(A.T, -grad_f, rcond=None)
        rank = int(np.sum(sv > sv.max() * max(A.shape) * np.finfo(float).eps)) if sv.size else 0
        resid = grad_f + A.T @ lam
    else:
        lam, rank, resid = np.zeros(0), 0, grad_f
    stationarity = float(np.max(np.abs(resid)) / max(1.0, np.max(np.abs(grad_f))))
    ineq = np.array([not r[4] for r in active], dtype=bool)
    values = np.array([r[0] for r in active])
    dual = float(max(0.0, -lam[ineq].min())) if ineq.any() else 0.0
    comp = float(np.max(np.abs(lam[ineq] * values[ineq]))) if ineq.any() else 0.0

    multipliers = {c.name: 0.0 for c in problem.constraints}
    for r, value in zip(active, lam):
        multipliers[r[2]] = float(value * r[3])
    return KKTReport(
        residual=max(stationarity, primal, dual, comp),
        stationarity=stationarity,
        primal=float(primal),
        dual=dual,
        complementarity=comp,
        active=tuple(r[2] for r in active),
        multipliers=multipliers,
        rank=rank,
    )
