"""Homotopic minimum-norm optimisation of PPF gains with eigenvalue-constraint restoration.

Source: Agrawal & Bang, *Adaptive structures for large precision antennas*,
Acta Astronautica, 1996, Eqs. 15-28.

Problem (Eq. 15, with the constraint of Eqs. 21-22 and a direct stability check)::

    minimise J(g)   subject to   λ_i(S(g)) >= λ_i^c,   S = Ω − a1 a2 Cᵀ G C,
                                 max Re eig(Ā(g)) < −stability_margin

The problem is any object with the five methods of the PPF gain problem (duck-typed)::

    cost(g) -> float                          J = ½ tr(P̄ X0)                  (Eqs. 10-12)
    gradient(g) -> (n_g,)                     ∂J/∂g                          (Eqs. 13-14, repaired)
    stiffness_eigenvalues(g) -> (n,)          eigenvalues of S, ascending    (Eq. 21)
    stiffness_eigenvalue_gradients(g) -> (n, n_g)   ∂λ_i/∂g_k                 (Eq. 26)
    closed_loop_poles(g) -> complex array     eigenvalues of Ā               (Eq. 8)

Method of :func:`optimize_ppf_gains` (the paper's, §§3.1–3.2):

1. **Homotopy (Eqs. 16-17).** From a feasible start g0 with J_init = J(g0), the target cost
   moves as J0(γ) = γ J_goal + (1 − γ) J_init; at each γ the residual
   H = J(g) − J0(γ) is driven to zero.
2. **Minimum-norm correction (Eqs. 18-20).** H + Ã Δg = 0 with Ã = ∇Jᵀ (one row), and the
   W-norm-minimal solution Δg = −W⁻¹Ãᵀ(ÃW⁻¹Ãᵀ)⁻¹H. Its length is |H| / |∇J|_W⁻¹: where J is
   insensitive to the gains they move far.
3. **Nested restoration and the active set (Eqs. 21-28).** After each correction the
   eigenvalues of S are checked; if some λ_j < λ_j^c the violated rows H_c = λ_j − λ_j^c are
   corrected by Δg = −W⁻¹L̃ᵀ(L̃W⁻¹L̃ᵀ)⁻¹H_c with the analytic sensitivities L̃ (Eq. 26),
   repeated until every eigenvalue is back above its floor (the restoration loop sits inside
   the γ loop, §3.2). A restored constraint "becomes an active set on the prescribed boundary"
   (§3.2): the next corrections at the same γ hold it there, its row joining Ã in Eq. 18
   ("locally, only the active constraint set is considered", §3.1); "on the next stage with
   new homotopy parameter γ, the design parameters are set free to change" (§3.2), so every
   new γ starts with an empty active set. Without the held rows the corrections of J and the
   restorations alternate (two projections) and converge only linearly along the boundary:
   on the tests' model the run then crept in γ steps of 1e-6 and used up ``max_steps``.
4. **Stability.** The closed-loop poles are then checked directly: S > 0 implies stability only
   for G > 0 (derived from Eq. 6; on the tests' model g = −1e3 on every filter is unstable
   with S > 0). A correction that leaves the loop unstable is rejected outright and the cost is
   never evaluated there (the Lyapunov "cost" of an unstable loop is finite and may even be
   negative).
5. **Adaptive γ.** A γ whose corrections fail (not converged in ``max_corrections``, restoration
   not converged, unstable loop, non-finite values) is abandoned, the last converged gains are
   restored and the γ increment halved; a quickly converged γ doubles it again (up to
   ``gamma_step``). "We adopt the solution corresponding to the largest γ for which
   convergence is achieved as the constrained minimum" (§3.1): when the increment falls below
   ``min_gamma_step`` the run stops there (status ``"stalled"``).

Why not :func:`flexsat.analysis.homotopy.homotopy_minimize` (the general form of the same
method, Junkins, Pollock & Rahman 1990 Att. 5, which cites this paper): (a) it
picks its working set before each
step by predicting which inequalities the linearised step would violate and releasing rows by
their multipliers, whereas the paper enters a constraint only through the nested restoration
(Eq. 28, eigenvalue rows alone, after a correction of J alone) and frees it at the next γ —
reproducing the paper means its iteration; (b) it has no veto for a step that destabilises the
loop (its line search accepts any trial that lowers its merit, and the cost of an unstable loop
is a meaningless finite number); (c) it refuses a goal at or above the starting cost, while
the paper's published runs apparently had J_goal > J_init, which this module must
reproduce. The W handling (W = L Lᵀ, a vector is a diagonal) is reused from it.

:func:`scipy_ppf_gains` solves the same constrained problem with ``scipy.optimize.minimize``
(SLSQP, analytic gradient and eigenvalue Jacobian) as an independent check.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

import numpy as np
from scipy.optimize import minimize

from flexsat.analysis.homotopy import weight_factor
from flexsat.input_checks import (
    FieldError,
    require_count,
    require_finite,
    require_nonneg,
    require_numeric,
    require_scalar,
)

if TYPE_CHECKING:
    import numpy.typing as npt

    from flexsat.units import FloatArray

SOURCE = "Agrawal & Bang 1996, Eqs. 15-28"


class PPFGainProblem(Protocol):
    """The PPF gain-problem interface (:class:`~flexsat.control.ppf.PPFProblem` is one), each
    method of the gain vector g (n_g,): the cost J, its gradient (n_g,), the ascending
    eigenvalues of S (n,), their gradients (n, n_g) and the closed-loop poles."""

    def cost(self, g: FloatArray) -> npt.ArrayLike: ...

    def gradient(self, g: FloatArray) -> npt.ArrayLike: ...

    def stiffness_eigenvalues(self, g: FloatArray) -> npt.ArrayLike: ...

    def stiffness_eigenvalue_gradients(self, g: FloatArray) -> npt.ArrayLike: ...

    def closed_loop_poles(self, g: FloatArray) -> npt.ArrayLike: ...


#: the methods of :class:`PPFGainProblem` (checked at run time: the interface is duck-typed)
PROBLEM_METHODS = (
    "cost",
    "gradient",
    "stiffness_eigenvalues",
    "stiffness_eigenvalue_gradients",
    "closed_loop_poles",
)

#: default λ_i^c as a fraction of the open-loop stiffness eigenvalues λ_i(S(0)) = ω_i² (the
#: paper gives no margin): 1 % keeps every mode's stiffness away from zero.
DEFAULT_FLOOR_FRACTION = 0.01

#: restoration aims this far (relative) above the floor: λ_min(S) is concave in g (S is affine
#: in g), so Newton steps aimed at the floor itself approach it from below and never reach it.
RESTORATION_MARGIN = 1e-6

#: scaled constraint violation (λ_i − λ_i^c)/ω_i² accepted at the end of the SLSQP run
CONSTRAINT_TOL = 1e-8

GOAL_REACHED, STOPPED, STALLED = "goal reached", "stopped at gamma_stop", "stalled"


class _Failure(Exception):
    """A correction at the current γ failed: the step is rejected and the γ increment halved."""


@dataclass(frozen=True)
class PPFHomotopyStep:
    """One converged γ of the homotopy (``gamma = 0`` is the start).

    Attributes
    ----------
    gamma : float
    cost : float
        J(g) at the converged gains.
    target : float
        J0(γ) = γ J_goal + (1 − γ) J_init (Eq. 16).
    gains : (n_g,) ndarray
    min_stiffness_eigenvalue : float
        Smallest eigenvalue of S (Eq. 6), 1/s².
    max_pole_real : float
        Largest real part of the closed-loop poles (Eq. 8), 1/s.
    corrections : int
        Minimum-norm corrections (Eq. 19) used at this γ.
    restorations : int
        Restoration steps (Eq. 28) used at this γ.
    active : tuple of int
        Eigenvalues of S (0-based, ascending) held on their floor at this γ.
    """

    gamma: float
    cost: float
    target: float
    gains: FloatArray
    min_stiffness_eigenvalue: float
    max_pole_real: float
    corrections: int
    restorations: int
    active: tuple[int, ...]


@dataclass(frozen=True)
class PPFHomotopyResult:
    """Outcome of :func:`optimize_ppf_gains`.

    Attributes
    ----------
    gains : (n_g,) ndarray
        Gains at the last converged γ.
    cost : float
        J(gains).
    gamma : float
        Last converged γ.
    status : {"goal reached", "stopped at gamma_stop", "stalled"}
        γ = 1 reached (J = J_goal); γ = ``gamma_stop`` < 1 reached; or the γ increment fell
        below ``min_gamma_step`` (or ``max_steps`` was used up) at ``gamma``, which then marks
        the constrained minimum in the paper's sense (§3.1).
    message : str
        The status with the reason of the last failed step.
    cost_initial, cost_goal : float
        J_init = J(g0) and J_goal.
    eigenvalue_floor : (n,) ndarray
        λ_i^c used, 1/s².
    history : tuple of PPFHomotopyStep
        Every converged γ in order, starting with γ = 0 (g0).
    n_evaluations : int
        Calls of ``problem.cost``.
    """

    gains: FloatArray
    cost: float
    gamma: float
    status: str
    message: str
    cost_initial: float
    cost_goal: float
    eigenvalue_floor: FloatArray
    history: tuple[PPFHomotopyStep, ...]
    n_evaluations: int

    @property
    def goal_reached(self) -> bool:
        return self.status == GOAL_REACHED

    @property
    def gamma_path(self) -> FloatArray:
        return np.array([s.gamma for s in self.history])

    @property
    def cost_path(self) -> FloatArray:
        return np.array([s.cost for s in self.history])

    @property
    def target_path(self) -> FloatArray:
        return np.array([s.target for s in self.history])

    @property
    def gain_path(self) -> FloatArray:
        """(n_steps, n_g): the gains at every converged γ."""
        return np.array([s.gains for s in self.history])


@dataclass(frozen=True)
class EigenvalueRestoration:
    """Outcome of :func:`restore_eigenvalue_constraints` (Eqs. 21-28).

    Attributes
    ----------
    gains : (n_g,) ndarray
        Restored gains (the input gains when nothing was violated or the restoration failed).
    step : (n_g,) ndarray
        gains − input gains.
    eigenvalues : (n,) ndarray
        λ_i(S) at ``gains``, ascending.
    restored : bool
        Every λ_i >= λ_i^c at ``gains``.
    iterations : int
        Restoration steps (Eq. 28) taken.
    message : str
    """

    gains: FloatArray
    step: FloatArray
    eigenvalues: FloatArray
    restored: bool
    iterations: int
    message: str


@dataclass(frozen=True)
class ScipyPPFResult:
    """Outcome of :func:`scipy_ppf_gains`.

    Attributes
    ----------
    gains : (n_g,) ndarray
    cost : float
    success : bool
        scipy's success flag and the constraints hold at ``gains``.
    message : str
    iterations : int
    min_stiffness_eigenvalue, max_pole_real : float
    n_evaluations : int
        Calls of ``problem.cost``.
    """

    gains: FloatArray
    cost: float
    success: bool
    message: str
    iterations: int
    min_stiffness_eigenvalue: float
    max_pole_real: float
    n_evaluations: int


# -- the problem, checked ----------------------------------------------------------------------
class _Checked:
    """The problem's methods with their shapes checked (a wrong shape is the problem's bug: a
    ValueError naming the method) and non-finite values turned into a failed step."""

    def __init__(self, problem: PPFGainProblem) -> None:
        missing = [name for name in PROBLEM_METHODS if not callable(getattr(problem, name, None))]
        if missing:
            raise FieldError(
                "problem",
                f"missing method(s) {', '.join(missing)}; a PPF gain "
                f"problem needs {', '.join(PROBLEM_METHODS)}",
            )
        self.problem = problem
        self.n_gains = 0
        self.n_modes = 0
        self.evaluations = 0

    def _finite(self, value: FloatArray, name: str) -> FloatArray:
        if not np.all(np.isfinite(value)):
            raise _Failure(f"problem.{name} is not finite")
        return value

    def cost(self, g: FloatArray) -> float:
        self.evaluations += 1
        return float(self._finite(np.asarray(self.problem.cost(g.copy()), float), "cost"))

    def gradient(self, g: FloatArray) -> FloatArray:
        out = np.asarray(self.problem.gradient(g.copy()), float)
        if out.shape != (self.n_gains,):
            raise FieldError("problem.gradient", f"must return ({self.n_gains},), got {out.shape}")
        return self._finite(out, "gradient")

    def eigenvalues(self, g: FloatArray) -> FloatArray:
        out = np.asarray(self.problem.stiffness_eigenvalues(g.copy()), float)
        if out.shape != (self.n_modes,):
            raise FieldError(
                "problem.stiffness_eigenvalues", f"must return ({self.n_modes},), got {out.shape}"
            )
        return self._finite(out, "stiffness_eigenvalues")

    def eigenvalue_jacobian(self, g: FloatArray) -> FloatArray:
        out = np.asarray(self.problem.stiffness_eigenvalue_gradients(g.copy()), float)
        if out.shape != (self.n_modes, self.n_gains):
            raise FieldError(
                "problem.stiffness_eigenvalue_gradients",
                f"must return ({self.n_modes}, {self.n_gains}), got {out.shape}",
            )
        return self._finite(out, "stiffness_eigenvalue_gradients")

    def max_pole_real(self, g: FloatArray) -> float:
        poles = np.asarray(self.problem.closed_loop_poles(g.copy()))
        if poles.ndim != 1 or poles.size == 0:
            raise FieldError(
                "problem.closed_loop_poles",
                f"must return a 1-D array of poles, got shape {poles.shape}",
            )
        return float(self._finite(np.max(poles.real), "closed_loop_poles"))


def _setup(
    problem: PPFGainProblem,
    g: npt.ArrayLike,
    field: str,
    eigenvalue_floor: float | npt.ArrayLike | None,
) -> tuple[_Checked, FloatArray, FloatArray]:
    """The checked problem, the gains ``g`` (named ``field``) and λ^c."""
    ev = _Checked(problem)
    g = require_numeric(g, field, "gain vector")
    if g.ndim != 1 or g.size == 0:
        raise FieldError(field, f"must be a non-empty vector of gains, got shape {g.shape}")
    ev.n_gains = g.size
    try:
        lam = np.asarray(problem.stiffness_eigenvalues(g.copy()), float)
        jac = np.asarray(problem.stiffness_eigenvalue_gradients(g.copy()), float)
    except (ValueError, IndexError, TypeError) as exc:
        raise FieldError(
            field, f"the problem cannot be evaluated at {g.size} gains ({exc})"
        ) from None
    if lam.ndim != 1 or jac.shape != (lam.size, g.size):
        raise FieldError(
            field,
            f"has {g.size} gains but the problem's eigenvalue sensitivities "
            f"have shape {jac.shape} (one column per gain expected)",
        )
    ev.n_modes = lam.size
    if eigenvalue_floor is None:
        try:
            floor = DEFAULT_FLOOR_FRACTION * ev.eigenvalues(np.zeros(g.size))
        except _Failure as exc:
            raise FieldError("eigenvalue_floor", f"the default needs λ(S(0)), but {exc}") from None
    else:
        floor = require_nonneg(eigenvalue_floor, "eigenvalue_floor", "1/s**2")
        if floor.ndim > 1 or floor.size not in (1, lam.size):
            raise FieldError(
                "eigenvalue_floor",
                f"must be a number or {lam.size} values (one per "
                f"eigenvalue of S, ascending), got shape {floor.shape}",
            )
        floor = np.broadcast_to(floor.reshape(-1), lam.shape).astype(float)
    return ev, g, floor


def _start(
    problem: PPFGainProblem,
    g0: npt.ArrayLike,
    eigenvalue_floor: float | npt.ArrayLike | None,
    stability_margin: float,
) -> tuple[_Checked, FloatArray, FloatArray, float, float]:
    """Check the problem and the start; return (checked problem, g0, λ^c, margin, J_init).

    The start must be feasible (λ_i(S) >= λ_i^c) and stable: J_init = J(g_feasible) anchors the
    homotopy (Eq. 16, "the initial choice … must be found to satisfy the inequality
    constraints", §3.1), and a cost evaluated on an unstable loop means nothing. An infeasible
    start is an error naming the violated eigenvalue; :func:`restore_eigenvalue_constraints`
    makes one feasible (Eq. 28 applied to the start).
    """
    ev, g, floor = _setup(problem, g0, "g0", eigenvalue_floor)
    margin = float(require_nonneg(stability_margin, "stability_margin", "1/s"))
    try:
        lam = ev.eigenvalues(g)
        max_re = ev.max_pole_real(g)
    except _Failure as exc:
        raise FieldError("g0", f"{exc} at the start") from None
    low = np.flatnonzero(lam < floor)
    if low.size:
        i = int(low[0])
        raise FieldError(
            "g0",
            f"violates the eigenvalue floor: λ_{i + 1}(S) = {lam[i]:.6g} < "
            f"λ_{i + 1}^c = {floor[i]:.6g} (Eq. 22); make the start feasible first, "
            f"e.g. with restore_eigenvalue_constraints",
        )
    if max_re >= -margin:
        raise FieldError(
            "g0",
            "the closed loop is unstable at the start: max Re(pole) = "
            f"{max_re:.6g} >= −stability_margin = {-margin:.6g} (S alone does not "
            f"guarantee stability for negative gains)",
        )
    try:
        J = ev.cost(g)
        ev.gradient(g)
    except _Failure as exc:
        raise FieldError("g0", f"{exc} at the start") from None
    return ev, g, floor, margin, J


def _inverse_weight(weight: npt.ArrayLike | None, n: int) -> FloatArray:
    """W⁻¹ of Eqs. 19 and 28 (W positive definite; a vector is a diagonal)."""
    Linv = np.linalg.inv(weight_factor(weight, n))
    return Linv.T @ Linv


def _minimum_norm_step(rows: FloatArray, residual: FloatArray, Winv: FloatArray) -> FloatArray:
    """Δg = −W⁻¹Aᵀ(AW⁻¹Aᵀ)⁻¹H (Eqs. 19, 28); a pseudo-inverse for rank-deficient rows (then the
    least-squares step)."""
    WA = Winv @ rows.T
    return -WA @ (np.linalg.pinv(rows @ WA, rcond=1e-13, hermitian=True) @ residual)


def _restore(
    ev: _Checked,
    g: FloatArray,
    target: FloatArray,
    floor: FloatArray,
    Winv: FloatArray,
    max_iterations: int,
) -> tuple[FloatArray, int, npt.NDArray[np.bool_]]:
    """Eqs. 23-28: restore λ_j >= λ_j^c on the violated set.

    Returns (gains, steps, rows): ``rows`` marks every eigenvalue that was corrected (the
    constraints that became active "on the prescribed boundary", §3.2).
    """
    rows = np.zeros(floor.shape, bool)
    for it in range(max_iterations + 1):
        lam = ev.eigenvalues(g)
        if np.all(lam >= floor):
            return g, it, rows
        if it == max_iterations:
            j = int(np.argmin(lam - floor))
            raise _Failure(
                f"restoration not converged in {max_iterations} steps (λ_{j + 1}(S) = "
                f"{lam[j]:.6g} < {floor[j]:.6g})"
            )
        # the violated set of Eq. 23, with the rows already restored to just below their target
        # held too, so a restored eigenvalue is not pushed back by the next row's step
        work = lam < target
        rows |= work
        g = g + _minimum_norm_step(ev.eigenvalue_jacobian(g)[work], lam[work] - target[work], Winv)
    raise AssertionError("unreachable")  # the loop returns or raises at it == max_iterations


def _restoration_target(floor: FloatArray) -> FloatArray:
    """Where Eq. 24 aims: ``RESTORATION_MARGIN`` (relative) above λ^c."""
    return floor + RESTORATION_MARGIN * np.maximum(floor, np.finfo(float).tiny)


def restore_eigenvalue_constraints(
    problem: PPFGainProblem,
    g: npt.ArrayLike,
    eigenvalue_floor: float | npt.ArrayLike | None = None,
    *,
    weight: npt.ArrayLike | None = None,
    max_iterations: int = 20,
) -> EigenvalueRestoration:
    """Restore λ_i(S(g)) >= λ_i^c by minimum-norm corrections (Agrawal & Bang 1996 Eqs. 21-28).

    Each step takes the violated set {j : λ_j < λ_j^c} (Eq. 23), H_c = λ_j − λ_j^c (Eq. 24)
    with the analytic sensitivities ∂λ_j/∂g_k = φ_jᵀ (∂S/∂g_k) φ_j (Eq. 26) and
    Δg = −W⁻¹L̃ᵀ(L̃W⁻¹L̃ᵀ)⁻¹H_c (Eq. 28). The rows aim ``RESTORATION_MARGIN`` (relative) above
    the floor, so the result satisfies it rather than approaching it from below.

    Parameters
    ----------
    problem : PPF gain problem (see the module)
    g : (n_g,) array_like
        Gains, possibly violating the floor.
    eigenvalue_floor : float or (n,) array_like, optional
        λ_i^c >= 0 in 1/s² (for the i-th smallest eigenvalue). Default
        ``DEFAULT_FLOOR_FRACTION`` · λ_i(S(0)).
    weight : (n_g,) or (n_g, n_g) array_like, optional
        W (positive definite; a vector is a diagonal). Default identity.
    max_iterations : int

    Returns
    -------
    EigenvalueRestoration
    """
    ev, given, floor = _setup(problem, g, "g", eigenvalue_floor)
    max_iterations = require_count(max_iterations, "max_iterations")
    Winv = _inverse_weight(weight, given.size)
    try:
        g_new, its, _ = _restore(
            ev, given.copy(), _restoration_target(floor), floor, Winv, max_iterations
        )
    except _Failure as exc:
        return EigenvalueRestoration(
            given, np.zeros_like(given), ev.eigenvalues(given), False, max_iterations, str(exc)
        )
    message = "feasible as given" if its == 0 else f"restored in {its} step(s)"
    return EigenvalueRestoration(g_new, g_new - given, ev.eigenvalues(g_new), True, its, message)


# -- the homotopy ------------------------------------------------------------------------------
def check_goal_ratio(value: float, field: str = "goal_ratio") -> float:
    """A goal given as the ratio J_goal/J_init: one finite number > 0.

    J is a positive quadratic cost at a stable start (J_init > 0), so a ratio <= 0 names no
    cost the homotopy could reach; the constrained minimum is asked for by ``J_goal = 0``,
    an absolute goal.
    """
    ratio = require_scalar(value, field)
    if not ratio > 0:
        raise FieldError(
            field,
            f"a ratio J_goal/J_init must be > 0 (the cost of a stable loop is > 0; give "
            f"J_goal = 0 for the constrained minimum), got {value!r}",
        )
    return ratio


def _check_costs(J_init: float, goal: float, goal_field: str, rtol: float) -> None:
    """Refuse a start cost or a goal the homotopy cannot follow in float64.

    J is a positive quadratic cost, so J_goal < 0 is meaningless (J_goal = 0, unreachable,
    asks for the constrained minimum, §3.1). The targets
    J0(γ) = γ J_goal + (1 − γ) J_init are met to ``rtol`` · |J0|: with J_goal > J_init/rtol
    the J_init part is below that tolerance from the first step on, and a J_init that is not
    at least tiny/rtol (weights of 1e300 scale it to ~1e-306) leaves no digits to converge on.
    """
    tiny, huge = np.finfo(float).tiny, np.finfo(float).max
    if not tiny / rtol <= J_init <= huge * rtol:
        raise FieldError(
            "problem",
            f"the cost at the start J_init = {J_init:.3g} is outside [{tiny / rtol:.3g}, "
            f"{huge * rtol:.3g}], where rtol = {rtol:g} of it is a float64 number: its "
            "weights are out of scale",
        )
    if not 0.0 <= goal <= J_init / rtol:
        raise FieldError(
            goal_field,
            f"the goal cost J_goal = {goal:.3g} must be in [0, J_init/rtol = "
            f"{J_init / rtol:.3g}] (J >= 0; beyond J_init/rtol the start is below the "
            "convergence tolerance)",
        )


def optimize_ppf_gains(
    problem: PPFGainProblem,
    g0: npt.ArrayLike,
    J_goal: float | None = None,
    goal_ratio: float | None = None,
    gamma_stop: float = 1.0,
    eigenvalue_floor: float | npt.ArrayLike | None = None,
    weight: npt.ArrayLike | None = None,
    *,
    stability_margin: float = 0.0,
    gamma_step: float = 0.1,
    min_gamma_step: float = 1e-6,
    max_corrections: int = 10,
    max_restorations: int = 20,
    max_steps: int = 500,
    rtol: float = 1e-10,
) -> PPFHomotopyResult:
    """Optimise PPF gains by the homotopic minimum-norm method of Agrawal & Bang 1996 (Eqs. 15-28).

    At γ = γ_k the cost is driven to J0(γ) = γ J_goal + (1 − γ) J_init (Eqs. 16-17) by
    corrections Δg = −W⁻¹∇J (J − J0) / (∇Jᵀ W⁻¹ ∇J) (Eqs. 18-20), each followed by the nested
    restoration of the violated eigenvalues of S (Eqs. 21-28) and a direct check of the
    closed-loop poles; see the module for the whole method and its failure rules.

    Parameters
    ----------
    problem : PPF gain problem
        Any object with ``cost``, ``gradient``, ``stiffness_eigenvalues``,
        ``stiffness_eigenvalue_gradients`` and ``closed_loop_poles`` (see the module).
    g0 : (n_g,) array_like
        Feasible, stable start (all 100 in the paper, Table 1). An infeasible start is an error:
        restore it first with :func:`restore_eigenvalue_constraints`.
    J_goal : float, optional
        The goal cost. Above J_init the homotopy *raises* J (along +∇J), as the paper's
        published runs apparently did.
    goal_ratio : float, optional
        Alternatively J_goal = goal_ratio · J_init, goal_ratio > 0 (the paper sets the goal
        "based upon the objective function with the initial gains", §4). Give exactly one of
        the two.
    gamma_stop : float
        Last γ, in (0, 1] (0.9 in the paper, §4).
    eigenvalue_floor : float or (n,) array_like, optional
        λ_i^c >= 0 of Eq. 22, 1/s², for the i-th smallest eigenvalue of S. Default
        ``DEFAULT_FLOOR_FRACTION`` · λ_i(S(0)) = 1 % of ω_i² (the paper gives none).
    weight : (n_g,) or (n_g, n_g) array_like, optional
        W of Eqs. 19 and 28 (positive definite; a vector is a diagonal). Default identity.
    stability_margin : float
        Every closed-loop pole must have Re < −stability_margin (1/s, >= 0).
    gamma_step : float
        First and largest γ increment, in (0, 1] (0.1: the paper's γ = 0.1 … 1.0).
    min_gamma_step : float
        The run stalls when the increment falls below this.
    max_corrections : int
        Corrections (Eq. 19) allowed per γ.
    max_restorations : int
        Restoration steps (Eq. 28) allowed after one correction.
    max_steps : int
        Converged γ steps allowed (a creeping run then stalls).
    rtol : float
        A γ has converged when |J − J0(γ)| <= rtol · |J0(γ)| (rtol · |J_init| if J0(γ) = 0).

    Returns
    -------
    PPFHomotopyResult

    Raises
    ------
    ValueError
        A problem object missing methods; g0 not a finite vector of the problem's gains, or
        infeasible (names the violated eigenvalue), or unstable; J_goal / goal_ratio missing,
        both given or not finite; gamma_stop outside (0, 1]; other options out of range.
    """
    ev, g, floor, margin, J_init = _start(problem, g0, eigenvalue_floor, stability_margin)
    if J_goal is not None and goal_ratio is None:
        goal, goal_field = float(require_finite(J_goal, "J_goal")), "J_goal"
    elif goal_ratio is not None and J_goal is None:
        goal, goal_field = check_goal_ratio(goal_ratio) * J_init, "goal_ratio"
    else:
        raise FieldError(
            "J_goal", "give exactly one of J_goal and goal_ratio (J_goal = goal_ratio · J_init)"
        )
    rtol = float(require_finite(rtol, "rtol"))
    if not 0.0 < rtol < 1.0:
        raise FieldError("rtol", f"must be in (0, 1), got {rtol!r}")
    _check_costs(J_init, goal, goal_field, rtol)
    gamma_stop = float(require_finite(gamma_stop, "gamma_stop"))
    if not 0.0 < gamma_stop <= 1.0:
        raise FieldError("gamma_stop", f"must be in (0, 1], got {gamma_stop!r}")
    gamma_step = float(require_finite(gamma_step, "gamma_step"))
    if not 0.0 < gamma_step <= 1.0:
        raise FieldError("gamma_step", f"must be in (0, 1], got {gamma_step!r}")
    min_gamma_step = float(require_finite(min_gamma_step, "min_gamma_step"))
    if not 0.0 < min_gamma_step <= gamma_step:
        raise FieldError(
            "min_gamma_step", f"must be in (0, gamma_step = {gamma_step}], got {min_gamma_step!r}"
        )
    max_corrections = require_count(max_corrections, "max_corrections")
    max_restorations = require_count(max_restorations, "max_restorations")
    max_steps = require_count(max_steps, "max_steps")
    Winv = _inverse_weight(weight, g.size)

    lam_target = _restoration_target(floor)

    def converge(
        g: FloatArray, target: float
    ) -> tuple[FloatArray, float, int, int, npt.NDArray[np.bool_]]:
        """Corrections (Eq. 19) with the nested restoration (Eq. 28), the active set and the
        stability veto, at one γ; returns (gains, J, corrections, restorations, active)."""
        tol = rtol * (abs(target) if target != 0 else abs(J_init))
        restorations = 0
        active = np.zeros(floor.shape, bool)  # free at every new γ (§3.2)
        for k in range(max_corrections + 1):
            J = ev.cost(g)
            H = J - target
            if abs(H) <= tol:
                return g, J, k, restorations, active
            if k == max_corrections:
                raise _Failure(f"|J − J0(γ)| = {abs(H):.3g} after {max_corrections} corrections")
            grad = ev.gradient(g)
            if not np.any(grad):
                raise _Failure("∇J = 0: J cannot be corrected to first order")
            rows, residual = grad[None, :], np.array([H])
            if active.any():
                # Eq. 18 with the active eigenvalue rows held on their boundary (Eq. 24)
                lam = ev.eigenvalues(g)
                rows = np.vstack([rows, ev.eigenvalue_jacobian(g)[active]])
                residual = np.concatenate([residual, lam[active] - lam_target[active]])
            g = g + _minimum_norm_step(rows, residual, Winv)
            g, steps, restored = _restore(ev, g, lam_target, floor, Winv, max_restorations)
            restorations += steps
            active |= restored
            max_re = ev.max_pole_real(g)
            if max_re >= -margin:
                raise _Failure(
                    f"the correction makes the loop unstable (max Re(pole) = {max_re:.3g})"
                )
        raise AssertionError("unreachable")  # returns or raises at k == max_corrections

    def record(
        gamma: float,
        g: FloatArray,
        J: float,
        target: float,
        corrections: int,
        restorations: int,
        active: npt.NDArray[np.bool_],
    ) -> PPFHomotopyStep:
        return PPFHomotopyStep(
            gamma,
            J,
            target,
            g.copy(),
            float(ev.eigenvalues(g)[0]),
            ev.max_pole_real(g),
            corrections,
            restorations,
            tuple(int(i) for i in np.flatnonzero(active)),
        )

    history = [record(0.0, g, J_init, J_init, 0, 0, np.zeros(floor.shape, bool))]
    gamma, dgamma, J, last_fail = 0.0, gamma_step, J_init, ""
    status = None
    while status is None:
        if gamma >= gamma_stop:
            status = GOAL_REACHED if gamma_stop == 1.0 else STOPPED
            break
        if len(history) > max_steps:
            status, last_fail = STALLED, f"max_steps = {max_steps} converged steps used"
            break
        g_try = gamma + dgamma
        if g_try > gamma_stop - 1e-12:
            g_try = gamma_stop
        target = g_try * goal + (1.0 - g_try) * J_init
        try:
            g_new, J_new, corrections, restorations, active = converge(g, target)
        except (_Failure, np.linalg.LinAlgError) as exc:
            last_fail = str(exc)
            dgamma /= 2
            if dgamma < min_gamma_step:
                status = STALLED
            continue
        g, J, gamma = g_new, J_new, g_try
        history.append(record(gamma, g, J, target, corrections, restorations, active))
        if corrections <= 3:
            dgamma = min(gamma_step, 2 * dgamma)
    if status == STALLED:
        message = (
            f"stalled at γ = {gamma:.9g} (J = {J:.10g}): the constrained minimum in the "
            f"paper's sense (§3.1); next step: {last_fail}"
        )
    else:
        message = f"{status}: γ = {gamma:.9g}, J = {J:.10g}"
    return PPFHomotopyResult(
        g, J, gamma, status, message, J_init, goal, floor, tuple(history), ev.evaluations
    )


# -- the scipy cross-check ---------------------------------------------------------------------
def scipy_ppf_gains(
    problem: PPFGainProblem,
    g0: npt.ArrayLike,
    eigenvalue_floor: float | npt.ArrayLike | None = None,
    stability_margin: float = 0.0,
    *,
    tol: float = 1e-12,
    max_iterations: int = 1000,
) -> ScipyPPFResult:
    """The same problem (Eq. 15 with Eqs. 21-22 and the stability margin) by SLSQP
    (``scipy.optimize.minimize``): an independent check of :func:`optimize_ppf_gains`.

    minimise J(g) s.t. λ_i(S(g)) >= λ_i^c (analytic Jacobian, Eq. 26) and
    −max Re eig(Ā(g)) >= stability_margin (finite-difference Jacobian: the interface has no pole
    sensitivities, and the constraint is a max, smooth only where one pole dominates). SLSQP,
    not trust-constr: on the tests' model trust-constr stopped on its step tolerance 17 % above
    the minimum SLSQP and the homotopy agree on.

    The variables are scaled by the start, x = g / |g0| (1 where g0 = 0), J by J_init and each
    constraint by its size at g = 0 (ω_i², |max Re|), so SLSQP works on numbers of order one
    whatever the units of the gains.

    Parameters
    ----------
    problem, g0, eigenvalue_floor, stability_margin
        As for :func:`optimize_ppf_gains` (same start rules).
    tol : float
        SLSQP's ``ftol`` on the scaled cost J / J_init.
    max_iterations : int

    Returns
    -------
    ScipyPPFResult
        ``success`` also requires the constraints to hold at the result to
        ``CONSTRAINT_TOL`` (scaled): SLSQP meets its linearised constraints exactly, so what
        is left is second order in its last step.
    """
    ev, start, floor, margin, J_init = _start(problem, g0, eigenvalue_floor, stability_margin)
    tol = float(require_finite(tol, "tol"))
    if not tol > 0:
        raise FieldError("tol", f"must be > 0, got {tol!r}")
    max_iterations = require_count(max_iterations, "max_iterations")
    scale = np.abs(start)
    scale[scale == 0] = 1.0
    J_scale = abs(J_init) if J_init != 0 else 1.0
    lam_scale = np.maximum(floor, np.abs(ev.eigenvalues(np.zeros(start.size))))
    lam_scale[lam_scale == 0] = 1.0
    re_scale = max(abs(ev.max_pole_real(np.zeros(start.size))), margin, np.finfo(float).tiny)

    def fun(x: FloatArray) -> float:
        return ev.cost(scale * x) / J_scale

    def jac(x: FloatArray) -> FloatArray:
        return ev.gradient(scale * x) * scale / J_scale

    def eig_con(x: FloatArray) -> FloatArray:
        return (ev.eigenvalues(scale * x) - floor) / lam_scale

    def eig_jac(x: FloatArray) -> FloatArray:
        return ev.eigenvalue_jacobian(scale * x) * scale[None, :] / lam_scale[:, None]

    def stab_con(x: FloatArray) -> FloatArray:
        return np.array([(-ev.max_pole_real(scale * x) - margin) / re_scale])

    cons = [{"type": "ineq", "fun": eig_con, "jac": eig_jac}, {"type": "ineq", "fun": stab_con}]
    try:
        res = minimize(
            fun,
            start / scale,
            jac=jac,
            method="SLSQP",
            constraints=cons,
            options={"ftol": tol, "maxiter": max_iterations},
        )
    except _Failure as exc:
        raise FieldError("problem", f"{exc} during the SLSQP run") from None
    x = res.x
    feasible = bool(np.all(eig_con(x) >= -CONSTRAINT_TOL) and stab_con(x)[0] > 0)
    return ScipyPPFResult(
        scale * x,
        ev.cost(scale * x),
        bool(res.success) and feasible,
        str(res.message),
        int(res.nit),
        float(ev.eigenvalues(scale * x)[0]),
        ev.max_pole_real(scale * x),
        ev.evaluations,
    )


__all__ = [
    "CONSTRAINT_TOL",
    "DEFAULT_FLOOR_FRACTION",
    "PROBLEM_METHODS",
    "RESTORATION_MARGIN",
    "SOURCE",
    "EigenvalueRestoration",
    "PPFGainProblem",
    "PPFHomotopyResult",
    "PPFHomotopyStep",
    "ScipyPPFResult",
    "check_goal_ratio",
    "optimize_ppf_gains",
    "restore_eigenvalue_constraints",
    "scipy_ppf_gains",
]
