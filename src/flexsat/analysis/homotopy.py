"""Homotopic nonlinear programming by minimum-norm differential correction.

Source: J. L. Junkins and Y. Kim, "First and Second Order Sensitivity of the Singular Value
Decomposition", Journal of the Astronautical Sciences 38(1), 1990, Appendix, Eqs. A1-A11
(Att. 5 Appendix), and the same optimizer as used by B. N. Agrawal and H. Bang, "Adaptive Structures
for Large Precision Antennas", Acta Astronautica, 1996, Eqs. 16-28.

Problem (A1-A2)::

    minimise J(p)  subject to  f_i(p) = f_oi (i = 1 … m),   g_j(p) >= T_j (j = 1 … q)

Method, as implemented by :func:`homotopy_minimize`:

1. **Active set (A3-A4).** Inequalities that are violated (or within ``active_tol`` of their
   bound) are held as equalities g_j(p) = T_j. A held inequality is released when its
   multiplier shows that the correction would move it into the interior (the first-order
   optimality sign test of gradient projection); at most N rows are kept, in priority order
   (equalities, then inequalities in their given order), as the paper prescribes.
2. **Feasibility homotopy (A5-A7).** The targets move from their values at the start to the
   goal, f_p(γ) = γ f_o + (1 − γ) f(p_start), γ = 0 → 1 (an inequality already satisfied at the
   start keeps its bound T_j).
3. **Minimum-norm correction (A8; Agrawal & Bang 1996 Eqs. 18-20, 25, 28).** For the residual
   r of the
   active rows with Jacobian A, Δp = −W⁻¹ Aᵀ (A W⁻¹ Aᵀ)⁺ r, the W-norm-minimal step, computed
   with a pseudo-inverse (rank-deficient rows give the least-squares step). Each step is
   damped by a backtracking line search on the sum of squared scaled residuals.
4. **Adaptive γ.** Each γ is iterated to convergence (at most ``max_corrections``
   corrections). On success γ advances; on failure the increment is halved and the last
   converged point restored. The feasibility phase fails when the increment falls below
   ``min_gamma_step``; the result then reports the active rows and their Jacobian (A8).
5. **Objective homotopy (A9-A11; Agrawal & Bang 1996 Eqs. 16-17).** From the feasible point, J is
   appended as an extra row with target J_o(γ) = γ J_goal + (1 − γ) J(p_feasible), γ reset to 0.
   The largest γ that still converges gives the constrained minimum (A11); reaching γ = 1
   means the goal itself was attained. The converged J exceeds the minimum by about
   ``min_gamma_step · (J_feasible − J_goal)``, so p is accurate to roughly the square root of
   that (relative).

Gradients are supplied by the user or taken by central finite differences.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal, overload

import numpy as np
import numpy.typing as npt

from flexsat.input_checks import FieldError, require_numeric
from flexsat.units import FloatArray

_EPS = np.finfo(float).eps


@dataclass(frozen=True)
class HomotopyStep:
    """One converged point of the homotopy path.

    Attributes
    ----------
    phase : {"feasibility", "objective"}
    gamma : float
        Homotopy parameter of the phase (0 … 1).
    p : (N,) ndarray
    objective : float
        J(p).
    corrections : int
        Minimum-norm corrections needed to converge at this γ.
    active : tuple of str
        Rows held at the last correction: ``"eq[i]"``, ``"ineq[j]"``, ``"objective"``.
    max_violation : float
        max over f_i − f_oi (absolute) and T_j − g_j (positive part) at p, against the *final*
        targets (zero once feasible).
    """

    phase: str
    gamma: float
    p: FloatArray
    objective: float
    corrections: int
    active: tuple[str, ...]
    max_violation: float


@dataclass(frozen=True)
class HomotopyResult:
    """Outcome of :func:`homotopy_minimize`.

    Attributes
    ----------
    p : (N,) ndarray
        Final (last converged) point.
    objective : float
        J(p).
    equality, inequality : ndarray
        f(p) and g(p) at the final point (empty when there are none).
    feasible : bool
        The feasibility homotopy reached γ = 1.
    success : bool
        Feasible, and (if optimising) the objective phase ran.
    goal_reached : bool
        The objective homotopy reached γ = 1, i.e. J(p) = J_goal.
    gamma : float
        Last converged γ of the objective phase (0 if it did not start).
    message : str
    path : tuple of HomotopyStep
        Every converged γ, both phases, in order.
    p_feasible : (N,) ndarray or None
        The feasible start of the objective phase.
    active : tuple of str
        Active rows at the end (on failure: the rows that could not be satisfied).
    jacobian : ndarray
        Jacobian of the active rows at the end (reported to the user on failure, A8).
    projected_gradient : float
        |∇J| projected on the null space of the active constraint rows (W metric), relative
        to |∇J|: a first-order optimality measure (0 at a constrained stationary point).
    n_evaluations : int
        Calls of the objective function.
    """

    p: FloatArray
    objective: float
    equality: FloatArray
    inequality: FloatArray
    feasible: bool
    success: bool
    goal_reached: bool
    gamma: float
    message: str
    path: tuple[HomotopyStep, ...]
    p_feasible: FloatArray | None
    active: tuple[str, ...]
    jacobian: FloatArray
    projected_gradient: float
    n_evaluations: int = 0

    @property
    def feasibility_steps(self) -> tuple[HomotopyStep, ...]:
        return tuple(s for s in self.path if s.phase == "feasibility")

    @property
    def objective_steps(self) -> tuple[HomotopyStep, ...]:
        return tuple(s for s in self.path if s.phase == "objective")


# -- input checks ------------------------------------------------------------------------------
def _vector(value: npt.ArrayLike, field: str) -> FloatArray:
    return require_numeric(value, field, "vector")


@overload
def _positive(
    value: Any, field: str, *, integer: Literal[True], upper: float | None = None
) -> int: ...
@overload
def _positive(
    value: Any, field: str, *, integer: Literal[False] = False, upper: float | None = None
) -> float: ...
def _positive(
    value: Any, field: str, *, integer: bool = False, upper: float | None = None
) -> float:
    if isinstance(value, bool):
        raise FieldError(field, f"must be a positive number, got {value!r}")
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise FieldError(field, f"must be a positive number, got {value!r}") from None
    if not (np.isfinite(number) and number > 0) or (upper is not None and number > upper):
        rule = f"in (0, {upper}]" if upper is not None else "> 0 and finite"
        raise FieldError(field, f"must be {rule}, got {value!r}")
    if integer:
        if number != int(number):
            raise FieldError(field, f"must be an integer, got {value!r}")
        return int(number)
    return number


def weight_factor(weight: npt.ArrayLike | None, n: int) -> npt.NDArray[np.floating[Any]]:
    """L with W = L Lᵀ for the weight W of a minimum-norm step (positive definite; a vector is
    a diagonal; None the identity), checked and named ``weight`` in errors."""
    if weight is None:
        return np.eye(n)
    w = _vector(weight, "weight")
    if w.ndim == 1:
        if w.shape != (n,) or np.any(w <= 0):
            raise FieldError("weight", f"a vector weight must have {n} entries > 0, got {weight!r}")
        return np.diag(np.sqrt(w))
    if w.shape != (n, n):
        raise FieldError(
            "weight", f"must be a vector of {n} or an ({n}, {n}) matrix, got shape {w.shape}"
        )
    if not np.allclose(w, w.T, rtol=1e-12, atol=0):
        raise FieldError("weight", "the matrix W must be symmetric")
    try:
        return np.linalg.cholesky(w)
    except np.linalg.LinAlgError:
        raise FieldError("weight", "the matrix W must be positive definite") from None


#: ``J(p) -> float``
ScalarFunction = Callable[[FloatArray], float]
#: ``f(p) -> array``: a gradient, constraint values or a Jacobian
VectorFunction = Callable[[FloatArray], npt.ArrayLike]


class _Failure(Exception):
    pass


@dataclass
class _Problem:
    objective: ScalarFunction
    gradient: VectorFunction | None
    equality: VectorFunction | None
    equality_jacobian: VectorFunction | None
    inequality: VectorFunction | None
    inequality_jacobian: VectorFunction | None
    n: int
    m: int
    q: int
    fd_step: float
    evaluations: int = 0
    cache: dict[bytes, tuple[float, FloatArray, FloatArray]] = field(default_factory=dict)

    # values ------------------------------------------------------------------------------------
    def values(self, p: FloatArray) -> tuple[float, FloatArray, FloatArray]:
        key = p.tobytes()
        if key in self.cache:
            return self.cache[key]
        self.evaluations += 1
        J = float(np.asarray(self.objective(p.copy()), dtype=float))
        ce = self._call(self.equality, p, self.m, "equality")
        ci = self._call(self.inequality, p, self.q, "inequality")
        if not (np.isfinite(J) and np.all(np.isfinite(ce)) and np.all(np.isfinite(ci))):
            raise _Failure("non-finite function value")
        if len(self.cache) > 64:
            self.cache.clear()
        self.cache[key] = (J, ce, ci)
        return J, ce, ci

    @staticmethod
    def _call(fun: VectorFunction | None, p: FloatArray, size: int, name: str) -> FloatArray:
        if fun is None:
            return np.zeros(0)
        out = np.atleast_1d(np.asarray(fun(p.copy()), dtype=float))
        if out.shape != (size,):
            raise FieldError(name, f"must return {size} values, got shape {out.shape}")
        return out

    # derivatives -------------------------------------------------------------------------------
    def _fd(self, p: FloatArray, which: int) -> FloatArray:
        rows = []
        for k in range(self.n):
            h = self.fd_step * max(1.0, abs(p[k]))
            e = np.zeros(self.n)
            e[k] = h
            plus, minus = self.values(p + e), self.values(p - e)
            rows.append((np.atleast_1d(plus[which]) - np.atleast_1d(minus[which])) / (2 * h))
        return np.array(rows).T  # (rows, n)

    def grad(self, p: FloatArray) -> FloatArray:
        if self.gradient is None:
            return self._fd(p, 0)[0]
        g = np.asarray(self.gradient(p.copy()), dtype=float).reshape(-1)
        if g.shape != (self.n,):
            raise FieldError("gradient", f"must return {self.n} values, got shape {g.shape}")
        if not np.all(np.isfinite(g)):
            raise _Failure("non-finite gradient")
        return g

    def jac(
        self, p: FloatArray, which: int, fun: VectorFunction | None, size: int, name: str
    ) -> FloatArray:
        if size == 0:
            return np.zeros((0, self.n))
        if fun is None:
            return self._fd(p, which)
        jac = np.asarray(fun(p.copy()), dtype=float).reshape(size, -1)
        if jac.shape != (size, self.n):
            raise FieldError(
                name, f"must return a ({size}, {self.n}) Jacobian, got shape {jac.shape}"
            )
        if not np.all(np.isfinite(jac)):
            raise _Failure(f"non-finite {name}")
        return jac

    def jac_eq(self, p: FloatArray) -> FloatArray:
        return self.jac(p, 1, self.equality_jacobian, self.m, "equality_jacobian")

    def jac_in(self, p: FloatArray) -> FloatArray:
        return self.jac(p, 2, self.inequality_jacobian, self.q, "inequality_jacobian")


def homotopy_minimize(
    objective: ScalarFunction,
    p0: npt.ArrayLike,
    *,
    gradient: VectorFunction | None = None,
    equality: VectorFunction | None = None,
    equality_target: npt.ArrayLike | None = None,
    equality_jacobian: VectorFunction | None = None,
    inequality: VectorFunction | None = None,
    inequality_bound: npt.ArrayLike | None = None,
    inequality_jacobian: VectorFunction | None = None,
    objective_goal: float = 0.0,
    weight: npt.ArrayLike | None = None,
    minimize: bool = True,
    gamma_step: float = 0.1,
    min_gamma_step: float = 1e-9,
    max_corrections: int = 8,
    tol: float = 1e-10,
    active_tol: float = 1e-7,
    max_step: float | None = None,
    fd_step: float = 1e-6,
    max_steps: int = 1000,
    max_evaluations: int = 100_000,
) -> HomotopyResult:
    """Minimise J(p) with equality and inequality constraints by homotopic minimum-norm
    differential correction (Att. 5 Appendix Eqs. A1-A11; Agrawal & Bang 1996 Eqs. 16-28).

    Parameters
    ----------
    objective : callable ``J(p) -> float``
    p0 : (N,) array_like
        Starting point p_start (need not be feasible).
    gradient : callable ``∇J(p) -> (N,)``, optional
        Default: central finite differences with step ``fd_step · max(1, |p_k|)``.
    equality : callable ``f(p) -> (m,)``, optional
        Equality constraint functions, with
    equality_target : (m,) array_like
        f_o, so that f(p) = f_o.
    equality_jacobian : callable ``(p) -> (m, N)``, optional
    inequality : callable ``g(p) -> (q,)``, optional
        Inequality constraint functions, with
    inequality_bound : (q,) array_like or float
        T, so that g(p) >= T.
    inequality_jacobian : callable ``(p) -> (q, N)``, optional
    objective_goal : float
        J_goal of Eq. A11 (default 0, "often 0" in the paper). Must be below J(p_feasible) for
        the objective phase to do anything.
    weight : (N,) or (N, N) array_like, optional
        W of Eq. A8 (positive definite; a vector is a diagonal). Default identity.
    minimize : bool
        False stops after the feasibility phase.
    gamma_step : float
        Initial (and largest) γ increment, in (0, 1].
    min_gamma_step : float
        Smallest γ increment before a phase stops.
    max_corrections : int
        Corrections allowed per γ before it counts as not converged.
    tol : float
        Convergence: every scaled residual |r_i| / max(1, |target_i|) <= tol.
    active_tol : float
        Inequalities within this scaled distance of their bound are candidates for the active
        set.
    max_step : float, optional
        Largest W-norm of one correction; a longer step counts as a failure (default
        unlimited).
    fd_step : float
        Relative finite-difference step for missing derivatives.
    max_steps : int
        Largest number of converged γ steps per phase (the objective phase can creep along a
        flat valley in tiny steps; it then stops here with the best point so far).
    max_evaluations : int
        Budget of objective/constraint evaluations.

    Returns
    -------
    HomotopyResult

    Raises
    ------
    ValueError
        Bad arguments, or functions returning wrongly shaped or non-finite values at ``p0``.

    Notes
    -----
    The method finds local minima only (the paper's caveat). Inequalities are one-sided:
    g(p) >= T; write an upper bound h(p) <= U as −h(p) >= −U.
    """
    p = _vector(p0, "p0").reshape(-1)
    if p.size == 0:
        raise FieldError("p0", "needs at least one parameter")
    n = p.size
    if not callable(objective):
        raise FieldError("objective", "must be callable")
    for name, fun in (
        ("gradient", gradient),
        ("equality", equality),
        ("equality_jacobian", equality_jacobian),
        ("inequality", inequality),
        ("inequality_jacobian", inequality_jacobian),
    ):
        if fun is not None and not callable(fun):
            raise FieldError(name, "must be callable or None")
    if (equality is None) != (equality_target is None):
        raise FieldError("equality_target", "give it exactly when equality is given")
    if (inequality is None) != (inequality_bound is None):
        raise FieldError("inequality_bound", "give it exactly when inequality is given")
    # equality_target is given exactly when equality is (checked above)
    f_o = (
        np.zeros(0)
        if equality_target is None
        else _vector(equality_target, "equality_target").reshape(-1)
    )
    m = f_o.size
    if equality is not None and m == 0:
        raise FieldError("equality_target", "must not be empty")
    if inequality is not None:
        assert inequality_bound is not None  # given with inequality (checked above)
        bound = _vector(inequality_bound, "inequality_bound")
        q = np.atleast_1d(np.asarray(inequality(p.copy()), dtype=float)).size
        T = np.broadcast_to(bound, (q,)).astype(float) if bound.ndim == 0 else bound.reshape(-1)
        if T.size != q:
            raise FieldError(
                "inequality_bound", f"must have {q} entries (one per inequality), got {T.size}"
            )
    else:
        T = np.zeros(0)
    q = T.size
    objective_goal = float(_vector(objective_goal, "objective_goal"))
    gamma_step = _positive(gamma_step, "gamma_step", upper=1.0)
    settings = _Settings(
        gamma_step,
        _positive(min_gamma_step, "min_gamma_step", upper=gamma_step),
        _positive(max_corrections, "max_corrections", integer=True),
        _positive(tol, "tol"),
        _positive(active_tol, "active_tol"),
        None if max_step is None else _positive(max_step, "max_step"),
        _positive(max_steps, "max_steps", integer=True),
        _positive(max_evaluations, "max_evaluations", integer=True),
    )
    fd_step = _positive(fd_step, "fd_step")
    L = weight_factor(weight, n)
    Linv_T = np.linalg.inv(L).T  # Δp = L⁻ᵀ y, |Δp|_W = |y|

    prob = _Problem(
        objective,
        gradient,
        equality,
        equality_jacobian,
        inequality,
        inequality_jacobian,
        n,
        m,
        q,
        fd_step,
    )
    try:
        J0, fe0, gi0 = prob.values(p)
    except _Failure:
        raise FieldError("objective", "non-finite value at p0") from None
    # validate user derivatives at the start (shape errors surface here, not mid-run)
    for name, check in (
        ("gradient", prob.grad),
        ("equality_jacobian", prob.jac_eq),
        ("inequality_jacobian", prob.jac_in),
    ):
        try:
            check(p)
        except _Failure:
            if name != "gradient":  # a gradient may be undefined at the start only
                raise FieldError(name, "non-finite value at p0") from None

    run = _Continuation(prob, f_o, T, fe0, gi0, Linv_T, settings)
    # phase 1: feasibility (A3-A8)
    if run.violation(fe0, gi0, scaled=True) <= settings.tol:
        run.path.append(
            HomotopyStep("feasibility", 1.0, p.copy(), J0, 0, (), run.violation(fe0, gi0))
        )
        feasible = True
    else:
        p, gamma1, feasible = run.run_phase(p, "feasibility", None)
    J, fe, gi = prob.values(p)
    if not feasible:
        return HomotopyResult(
            p,
            J,
            fe,
            gi,
            False,
            False,
            False,
            0.0,
            f"infeasible: the feasibility homotopy stopped at γ = {gamma1:.6g} "
            f"({run.last_fail}); active rows {list(run.last_active)} with the Jacobian in "
            "`jacobian`",
            tuple(run.path),
            None,
            run.last_active,
            run.last_A,
            np.nan,
            prob.evaluations,
        )
    p_feas, J_feas = p.copy(), J
    gamma2, goal = 0.0, False
    if not minimize:
        message = "feasible point found (minimize=False)"
    elif objective_goal >= J_feas:
        message = (
            f"objective_goal {objective_goal:.6g} is not below J(p_feasible) = "
            f"{J_feas:.6g}: nothing to minimise"
        )
    elif m >= n:
        message = "the equality constraints leave no freedom: the feasible point is returned"
    else:
        run.objective_goal = objective_goal
        p, gamma2, goal = run.run_phase(p, "objective", J_feas)
        J, fe, gi = prob.values(p)
        if goal:
            message = "objective goal reached"
        elif run.last_fail.startswith("max_steps"):
            message = (
                f"stopped after max_steps = {settings.max_steps} objective steps at γ = "
                f"{gamma2:.9g} (J = {J:.10g}); not yet the constrained minimum"
            )
        else:
            message = (
                f"constrained minimum: the objective homotopy stopped at γ = {gamma2:.9g} "
                f"(J = {J:.10g}; next step: {run.last_fail})"
            )
    try:
        pg = _projected_gradient(prob, p, run.last_active, Linv_T)
    except _Failure:
        pg = np.nan
    return HomotopyResult(
        p,
        J,
        fe,
        gi,
        True,
        True,
        goal,
        gamma2,
        message,
        tuple(run.path),
        p_feas,
        run.last_active,
        run.last_A,
        pg,
        prob.evaluations,
    )


@dataclass(frozen=True)
class _Settings:
    """The continuation's checked settings (:func:`homotopy_minimize`'s parameters)."""

    gamma_step: float
    min_gamma_step: float
    max_corrections: int
    tol: float
    active_tol: float
    max_step: float | None
    max_steps: int
    max_evaluations: int


class _Continuation:
    """The two homotopy phases of :func:`homotopy_minimize` on one problem: the γ loop
    (:meth:`run_phase`), the corrector at one γ (:meth:`converge`) and one damped minimum-norm
    correction (:meth:`step`); it keeps the path and the last active set and failure."""

    def __init__(
        self,
        prob: _Problem,
        f_o: FloatArray,
        T: FloatArray,
        fe0: FloatArray,
        gi0: FloatArray,
        Linv_T: npt.NDArray[Any],
        settings: _Settings,
    ) -> None:
        self.prob, self.f_o, self.T, self.fe0 = prob, f_o, T, fe0
        self.Linv_T, self.s = Linv_T, settings
        self.n, self.m, self.q = prob.n, f_o.size, T.size
        self.se = np.maximum(1.0, np.abs(f_o))
        self.sb = np.maximum(1.0, np.abs(T))
        self.T_start = np.minimum(gi0, T)
        self.names = [f"eq[{i}]" for i in range(self.m)] + [f"ineq[{j}]" for j in range(self.q)]
        self.objective_goal = 0.0
        self.path: list[HomotopyStep] = []
        self.last_active: tuple[str, ...] = ()
        self.last_A: FloatArray = np.zeros((0, self.n))
        self.last_fail = ""

    def violation(self, fe: FloatArray, gi: FloatArray, scaled: bool = False) -> float:
        parts = [np.abs(fe - self.f_o), np.maximum(0.0, self.T - gi)]
        if scaled:
            parts = [parts[0] / self.se, parts[1] / self.sb]
        return float(max((x.max() for x in parts if x.size), default=0.0))

    def targets(
        self, gamma: float, phase: str, J_feas: float | None
    ) -> tuple[Any, Any, float | None]:
        if phase == "feasibility":
            return (
                gamma * self.f_o + (1 - gamma) * self.fe0,
                gamma * self.T + (1 - gamma) * self.T_start,
                None,
            )
        assert J_feas is not None  # the objective phase starts from a feasible J
        return self.f_o, self.T, gamma * self.objective_goal + (1 - gamma) * J_feas

    def residuals(
        self, p: FloatArray, te: Any, tb: Any, Jo: float | None
    ) -> tuple[FloatArray, FloatArray, float | None]:
        J, fe, gi = self.prob.values(p)
        re, ri = (fe - te) / self.se, (gi - tb) / self.sb
        rJ = None if Jo is None else (J - Jo) / max(1.0, abs(Jo))
        return re, ri, rJ

    def merit(self, p: FloatArray, te: Any, tb: Any, Jo: float | None) -> float:
        try:
            re, ri, rJ = self.residuals(p, te, tb, Jo)
        except (_Failure, ValueError, ArithmeticError, np.linalg.LinAlgError):
            return np.inf
        return float(
            re @ re + np.minimum(ri, 0) @ np.minimum(ri, 0) + (0.0 if rJ is None else rJ * rJ)
        )

    def step(
        self, p: FloatArray, te: Any, tb: Any, Jo: float | None
    ) -> tuple[FloatArray, tuple[str, ...], FloatArray]:
        """One damped minimum-norm correction; returns (p_new, active names, jacobian).

        The step is the W-norm-minimal Δp with the equality rows (and the objective row)
        satisfied to first order and the inequality rows held as equalities on a working set,
        chosen by a small active-set loop: start from the violated/near-bound rows (A3), add a
        row whose linearisation the step would violate, release a satisfied row whose
        multiplier is negative (the step would move it inside), at most ``room`` rows (A4).
        """
        prob, n, m, q, tol = self.prob, self.n, self.m, self.q, self.s.tol
        Linv_T = self.Linv_T
        re, ri, rJ = self.residuals(p, te, tb, Jo)
        rows_eq = prob.jac_eq(p) / self.se[:, None]
        rows_all = prob.jac_in(p) / self.sb[:, None]
        room = n - (0 if Jo is None else 1)
        if m > room:
            raise _Failure("more equality constraints than free parameters")
        objrow = None
        if Jo is not None:
            objrow = prob.grad(p)[None, :] / max(1.0, abs(Jo))
        work = [int(j) for j in np.flatnonzero(ri <= self.s.active_tol)][: room - m]
        seen = set()
        for _ in range(4 * q + 4):
            A = np.vstack([rows_eq, rows_all[work]] + ([objrow] if objrow is not None else []))
            r = np.concatenate([re, ri[work]] + ([[rJ]] if rJ is not None else []))
            At = A @ Linv_T
            nu = -np.linalg.pinv(At @ At.T, rcond=1e-13, hermitian=True) @ r
            y = At.T @ nu
            dp = Linv_T @ y
            key = tuple(work)
            if key in seen:
                break
            seen.add(key)
            # add the inequality whose linearisation the step violates most
            lin = ri + rows_all @ dp
            outside = [j for j in range(q) if j not in work and lin[j] < -tol]
            if outside and len(work) < room - m:
                worst = min(outside, key=lambda j: lin[j])
                work = sorted(work + [worst])
                continue
            # release a satisfied inequality whose multiplier is negative (ν < 0: move inside)
            nu_in = nu[m : m + len(work)]
            cut = -1e-12 * max(1.0, float(np.abs(nu).max()))
            drop = [k for k, j in enumerate(work) if ri[j] >= 0 and nu_in[k] < cut]
            if drop:
                k = min(drop, key=lambda k: nu_in[k])
                work = work[:k] + work[k + 1 :]
                continue
            break
        if self.s.max_step is not None and np.linalg.norm(y) > self.s.max_step:
            raise _Failure("correction longer than max_step")
        m0 = self.merit(p, te, tb, Jo)
        alpha = 1.0
        while alpha >= 1.0 / 64:
            trial = p + alpha * dp
            if self.merit(trial, te, tb, Jo) < (1 - 1e-4 * alpha) * m0:
                active = tuple(
                    [self.names[i] for i in range(m)]
                    + [self.names[m + j] for j in work]
                    + (["objective"] if Jo is not None else [])
                )
                return trial, active, A
            alpha /= 2
        raise _Failure("line search failed")

    def converge(
        self, p: FloatArray, gamma: float, phase: str, J_feas: float | None
    ) -> tuple[FloatArray, int, tuple[str, ...], FloatArray]:
        te, tb, Jo = self.targets(gamma, phase, J_feas)
        active: tuple[str, ...] = ()
        A = np.zeros((0, self.n))
        for it in range(self.s.max_corrections + 1):
            if self.prob.evaluations > self.s.max_evaluations:
                raise _Failure("evaluation budget exhausted")
            re, ri, rJ = self.residuals(p, te, tb, Jo)
            worst = max(
                [
                    np.abs(re).max(initial=0.0),
                    np.maximum(0.0, -ri).max(initial=0.0),
                    0.0 if rJ is None else abs(rJ),
                ]
            )
            if worst <= self.s.tol:
                return p, it, active, A
            if it == self.s.max_corrections:
                break
            p, active, A = self.step(p, te, tb, Jo)
        raise _Failure(f"not converged in {self.s.max_corrections} corrections")

    def run_phase(
        self, p: FloatArray, phase: str, J_feas: float | None
    ) -> tuple[FloatArray, float, bool]:
        s = self.s
        gamma, dg, steps = 0.0, s.gamma_step, 0
        while gamma < 1.0:
            if steps >= s.max_steps:
                self.last_fail = f"max_steps = {s.max_steps} converged steps reached"
                return p, gamma, False
            g_try = gamma + dg
            if g_try > 1.0 - 1e-12:
                g_try = 1.0
            try:
                p_new, its, active, A = self.converge(p, g_try, phase, J_feas)
            except (_Failure, ValueError, np.linalg.LinAlgError, ArithmeticError) as exc:
                # a ValueError here comes from the user's functions away from p0 (e.g. a
                # degenerate eigen-structure): that γ step failed, try a smaller one
                self.last_fail = str(exc)
                if self.prob.evaluations > s.max_evaluations:
                    return p, gamma, False
                dg /= 2
                if dg < s.min_gamma_step:
                    return p, gamma, False
                continue
            p, gamma, steps = p_new, g_try, steps + 1
            self.last_active, self.last_A = active, A
            J, fe, gi = self.prob.values(p)
            self.path.append(
                HomotopyStep(phase, gamma, p.copy(), J, its, active, self.violation(fe, gi))
            )
            if its <= 3:
                dg = min(s.gamma_step, 2 * dg)
        return p, gamma, True


def _projected_gradient(
    prob: _Problem, p: FloatArray, active: Sequence[str], Linv_T: npt.NDArray[Any]
) -> float:
    g = prob.grad(p)
    rows = []
    if prob.m:
        rows.append(prob.jac_eq(p))
    idx = [int(a[5:-1]) for a in active if a.startswith("ineq[")]
    if idx:
        rows.append(prob.jac_in(p)[idx])
    gt = Linv_T.T @ g  # gradient in the W-whitened coordinates
    if rows:
        At = np.vstack(rows) @ Linv_T
        gt = gt - At.T @ np.linalg.lstsq(At.T, gt, rcond=None)[0]
    norm = np.linalg.norm(Linv_T.T @ g)
    return float(np.linalg.norm(gt) / norm) if norm > 0 else 0.0


__all__ = ["HomotopyResult", "HomotopyStep", "homotopy_minimize", "weight_factor"]
