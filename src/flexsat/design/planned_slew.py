r"""A slew planned over the whole maneuver: the torque history that brings the design modes to
rest at T at the least effort (or the least peak) within the limits, by the torquers and, where
given, point forces.

:mod:`flexsat.design.slew_shaping` corrects the rigid nominal torque τ_n by
:math:`J v(t)`, :math:`v = S(t)\,c` a sine series per axis vanishing at 0 and T, and gives the
linear terminal conditions :math:`X c = r` (the rigid state back on the nominal's at T, the
design modes at rest; :func:`~flexsat.design.slew_shaping.terminal_map`). Of the coefficients
meeting them it took the minimum-norm one. Here the whole history is optimised:

.. math::

    \min_c\ E(c) = \int_0^T \lVert J v(t)\rVert^2\,dt
    = \tfrac T2 \sum_{j=1}^{n_b} c_j^T J^T J\, c_j
    \quad\text{s.t.}\quad X c = r,\quad
    |\tau_{n,a}(t_k) + (J S(t_k) c)_a| \le L_a\ \ (a = x, y, z;\ k = 1..n_s),

(the sines are orthogonal on [0, T], :math:`\int_0^T \sin\frac{j\pi t}{T}\sin\frac{l\pi t}{T}
dt = \frac T2\delta_{jl}`), or, with ``objective="peak"``, the least peak torque
:math:`\min_c \max_{a,k} |\tau_a(t_k)| / L_a` (a linear programme). The equality constraints
are eliminated exactly: with the SVD :math:`X = U\Sigma V^T` (rank r_X, singular values below
:math:`10^{-10}\sigma_1` dropped — X is rank deficient by design, the repeated antenna pairs
leaving combinations the torque cannot reach), :math:`c = c_0 + V_n z`, :math:`c_0` the
minimum-norm solution and :math:`V_n` a basis of the null space, so the problem is a convex QP
in z with the limits as linear inequalities, solved by SLSQP with its exact gradient
:math:`\nabla E = V_n^T H (c_0 + V_n z)` and constraint Jacobians (scipy.optimize; Kraft, D.,
"A software package for sequential quadratic programming", DFVLR-FB 88-28, 1988), from the
unconstrained optimum :math:`z^* = -(V_n^T H V_n)^{-1}V_n^T H c_0`. At the optimum the
multipliers of the active limits are the non-negative least-squares solution of
:math:`\nabla E + G_A^T\lambda = 0` (Karush–Kuhn–Tucker, for minimisation with constraints
g ≤ 0: λ ≥ 0), and the KKT residual is reported. When the limits admit no solution the least
feasible peak torque is reported instead (the linear programme above, HiGHS through
scipy.optimize.linprog): the number that shows the limit, not the method, prevents the goal.

Point forces (``forces``): the plant's force actuators planned beside the torque, each a sine
series of its own, :math:`F_i(t) = \sum_j d_{ij}\sin(j\pi t/T)` (the model of their action
on the modes and on the hub is in :mod:`~flexsat.design.slew_shaping`). The coefficients are
then [c; d], the terminal conditions :math:`X_\tau c + X_F d = r`, and the energy counts
every input,

.. math::

    E(c, d) = \int_0^T \lVert J v\rVert^2 + w_F \lVert F\rVert^2\,dt
    = \tfrac T2 \Big(\sum_j c_j^T J^T J c_j + w_F \sum_{i,j} d_{ij}^2\Big),

with the force limits :math:`|F_i(t_k)| \le L_F` beside the torque limits and the least peak
taken over both, :math:`\max(|\tau_a|/L_a, |F_i|/L_F)`. Torque sines weigh about
:math:`\lVert J\rVert^2` (1e10 on the EPS) and force sines w_F, so the QP is solved in
coefficients scaled to a unit Hessian diagonal (an exact change of variables), and SLSQP's
point is polished by solving the KKT system on its active set (kept when it meets every limit
with λ ≥ 0: then it is the optimum of the convex QP). Since zero forces are feasible, the
optimum with forces never costs more energy than the torquers' alone.

The limits are imposed at n_s equally spaced samples; between samples the highest sine
(period 2T/n_b) can exceed a sampled peak by at most 1 − cos(π T/(n_b (n_s − 1)))
relative (1.9 % at the default n_s = 16 n_b + 1); the reported peaks are those of a grid 4
times finer.

The feedback on top (:class:`PlannedTrajectory`): the planned torque flown on the design model
(the one engine, :func:`flexsat.sim.simulate`) gives the planned attitude, rate and modal
state, the nominal of :func:`~flexsat.control.perturbation_feedback.perturbation_design`; the
law then feeds back the departures from the plan, its modal motion included (the plan's modes
move during the slew and come to rest at T).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from flexsat.design.slew_shaping import ShapedSlew, TerminalMap, terminal_map
from flexsat.input_checks import FieldError, require_count
from flexsat.units import FloatArray

if TYPE_CHECKING:
    from flexsat.dynamics.flexible_spacecraft import FlexibleSpacecraft
    from flexsat.maneuvers.three_axis_slew import ThreeAxisSlew
    from flexsat.sim import SimConfig

__all__ = ["OBJECTIVES", "PlannedSlew", "PlannedTrajectory", "plan_slew", "planned_slew"]

#: what the plan minimises
OBJECTIVES = ("energy", "peak")
#: singular values of X below this fraction of the largest are dropped (rank deficiency by
#: design; the target has no component there to rounding, see the module docstring)
RANK_RCOND = 1e-10
#: a sampled limit is active within this fraction of the limit
ACTIVE_TOL = 1e-6


@dataclass(frozen=True, eq=False)
class PlannedSlew:
    """A planned slew and how its optimum was reached (module docstring).

    Attributes
    ----------
    shaped : ShapedSlew
        The torque history τ_n + J v (the law's nominal).
    objective : str
        ``energy`` or ``peak``.
    feasible : bool
        The terminal conditions and the limits were met together.
    energy : float
        ∫‖J v‖² dt, N² m² s.
    peak_torques : (3,) array
        max |τ_a| over a grid 4 × finer than the samples, N m.
    torque_limit : (3,) array or None
        L, N m.
    least_peak : float
        The least max_a,k |τ_a(t_k)|/L_a meeting the terminal conditions (in N m without
        limits; NaN when not computed: energy objective with limits that do not bind); with
        planned forces the maximum runs over the limited inputs, |F_i(t_k)|/L_F included.
    active : int
        Sampled limits active at the optimum.
    multipliers : (n_active,) array
        λ of the active limits, energy per normalised torque ((N m)² s).
    kkt_residual : float
        ‖∇E + G_Aᵀλ‖ / ‖∇E‖ (‖∇E‖ itself, relative to ‖V_nᵀHc₀‖, when nothing is active).
    terminal_residual : float
        ‖X c − r‖ / ‖r‖.
    rank : int
        Rank of X kept (of 6 + 2n conditions).
    message : str
    iterates : tuple of float
        ‖r_k‖ of the successive linearisations (:func:`planned_slew`): the terminal state's
        departure before each step and, last, after the final one (unless the limits were
        infeasible).
    torque_energy : float
        ∫‖J v‖² dt alone, N² m² s (``energy`` less the forces' w_F ∫‖F‖² dt).
    peak_forces : (n_F,) array
        max |F_i| over the fine grid, N (empty without planned forces).
    force_limit : float or None
        L_F, N.
    """

    shaped: ShapedSlew
    objective: str
    feasible: bool
    energy: float
    peak_torques: FloatArray
    torque_limit: FloatArray | None
    least_peak: float
    active: int
    multipliers: FloatArray
    kkt_residual: float
    terminal_residual: float
    rank: int
    message: str
    iterates: tuple[float, ...] = ()
    torque_energy: float = float("nan")
    peak_forces: FloatArray = field(default_factory=lambda: np.zeros(0))
    force_limit: float | None = None

    @property
    def duration(self) -> float:
        return self.shaped.duration

    @property
    def force_channels(self) -> tuple[str, ...]:
        """The planned point forces' plant channels (empty for torquers alone)."""
        return self.shaped.force_channels

    def forces(self, t: npt.ArrayLike) -> FloatArray:
        """The planned point forces (..., n_F), N."""
        return self.shaped.forces(t)

    @property
    def target(self) -> FloatArray:
        return self.shaped.target

    def torque(self, t: npt.ArrayLike) -> FloatArray:
        """The planned torque, N m."""
        return self.shaped.torque(t)

    def summary(self) -> dict[str, float | int | bool | str]:
        """The plan's numbers by name (for reports)."""
        out: dict[str, float | int | bool | str] = {
            "objective": self.objective,
            "feasible": self.feasible,
            "energy_N2m2s": self.energy,
            "active_limits": self.active,
            "largest_multiplier": float(self.multipliers.max()) if self.multipliers.size else 0.0,
            "kkt_residual": self.kkt_residual,
            "terminal_residual": self.terminal_residual,
            "rank": self.rank,
            "least_peak": self.least_peak,
        }
        for a, p in zip("xyz", self.peak_torques, strict=True):
            out[f"planned_peak_torque_{a}_Nm"] = float(p)
        out["torque_energy_N2m2s"] = self.torque_energy
        for name, p in zip(self.force_channels, self.peak_forces, strict=True):
            out[f"planned_peak_{name}_N"] = float(p)
        return out


def _limits(torque_limit: npt.ArrayLike | None) -> FloatArray | None:
    if torque_limit is None:
        return None
    L = np.broadcast_to(np.asarray(torque_limit, float), (3,)).copy()
    if not np.all(np.isfinite(L) & (L > 0.0)):
        raise FieldError("torque_limit", f"must be finite and > 0 N m, got {L.tolist()}")
    return L


def _force_settings(
    n_f: int, force_limit: float | None, force_weight: float, objective: str, torque_limited: bool
) -> float | None:
    """The force limit (N) checked against the forces planned and the objective."""
    if not (np.isfinite(force_weight) and force_weight > 0.0):
        raise FieldError("force_weight", f"must be finite and > 0 m², got {force_weight!r}")
    if force_limit is not None:
        force_limit = float(force_limit)
        if not (np.isfinite(force_limit) and force_limit > 0.0):
            raise FieldError("force_limit", f"must be finite and > 0 N, got {force_limit!r}")
        if not n_f:
            raise FieldError("force_limit", "given without forces planned (terminal map)")
    if n_f and objective == "peak" and (force_limit is None or not torque_limited):
        raise FieldError(
            "force_limit" if force_limit is None else "torque_limit",
            "required with objective 'peak' and planned forces: the peak is taken relative "
            "to the limits, |τ_a|/L_a and |F_i|/L_F together",
        )
    return force_limit


def _least_peak(G: FloatArray, h: FloatArray, n_z: int) -> tuple[FloatArray | None, float, str]:
    """min s s.t. G z − s ≤ h (rows normalised): (z, s, message) by HiGHS."""
    from scipy.optimize import linprog

    cost = np.zeros(n_z + 1)
    cost[-1] = 1.0
    A = np.hstack([G, -np.ones((G.shape[0], 1))])
    res = linprog(cost, A_ub=A, b_ub=h, bounds=[(None, None)] * (n_z + 1), method="highs")
    if res.status != 0:
        return None, float("nan"), f"least peak: {res.message}"
    return res.x[:n_z], float(res.x[-1]), "least peak by HiGHS"


def _restricted_qp(
    P: FloatArray, q: FloatArray, G: FloatArray, h: FloatArray, f0: float, start: FloatArray
) -> tuple[FloatArray, str]:
    """min ½zᵀPz + qᵀz s.t. G z ≤ h by SLSQP (objective scaled by f0), from ``start``."""
    from scipy.optimize import minimize

    res = minimize(
        lambda v: (0.5 * v @ P @ v + q @ v) / f0,
        start,
        jac=lambda v: (P @ v + q) / f0,
        constraints=[{"type": "ineq", "fun": lambda v: h - G @ v, "jac": lambda v: -G}],
        method="SLSQP",
        options={"maxiter": 500, "ftol": 1e-12},
    )
    return np.asarray(res.x, float), str(res.message)


def _polish(
    P: FloatArray, q: FloatArray, G: FloatArray, h: FloatArray, z: FloatArray
) -> FloatArray:
    """SLSQP's optimum made exact on its active set: the equality-constrained QP
    min ½zᵀPz + qᵀz s.t. G_A z = h_A by its KKT system (least squares: rows of G_A may be
    dependent), kept when it meets every limit and its multipliers are non-negative (then it
    is the optimum of the convex QP); otherwise SLSQP's point."""
    active = np.flatnonzero(h - G @ z <= ACTIVE_TOL)
    if not active.size:
        return z
    GA = G[active]
    n, k = P.shape[0], active.size
    K = np.block([[P, GA.T], [GA, np.zeros((k, k))]])
    sol = np.linalg.lstsq(K, np.concatenate([-q, h[active]]), rcond=None)[0]
    z_new, mu = sol[:n], sol[n:]
    scale = max(float(np.abs(mu).max()), 1e-300)
    if np.max(G @ z_new - h) <= 1e-9 and np.min(mu) >= -1e-8 * scale:
        return np.asarray(z_new, float)
    return z


def _input_map(terminal: TerminalMap, t: FloatArray) -> FloatArray:
    """M(t_k) (n_s, 3 + n_F, (3 + n_F) n_b): the planned inputs' change [J v; F] per
    coefficient (torque rows N m, force rows N)."""
    n_b, n_f, J = terminal.n_basis, terminal.n_forces, terminal.inertia
    M = np.zeros((t.size, 3 + n_f, (3 + n_f) * n_b))
    M[:, :3, : 3 * n_b] = np.einsum("ab,kbc->kac", J, terminal.basis(t))
    if n_f:
        M[:, 3:, 3 * n_b :] = terminal.force_basis(t)
    return M


def plan_slew(
    terminal: TerminalMap,
    nominal: ThreeAxisSlew,
    objective: str = "energy",
    torque_limit: npt.ArrayLike | None = None,
    n_samples: int | None = None,
    start: npt.ArrayLike | None = None,
    force_limit: float | None = None,
    force_weight: float = 1.0,
) -> PlannedSlew:
    r"""The planned correction of ``nominal`` (module docstring): one QP (or LP) on the
    conditions ``terminal``, over the torque sines and the sines of the point forces the
    terminal map plans (``terminal.force_channels``).

    Parameters
    ----------
    terminal : TerminalMap
        The terminal conditions (:func:`~flexsat.design.slew_shaping.terminal_map`) of a
        change Δc of the coefficients.
    nominal : ThreeAxisSlew
        The rigid nominal maneuver the correction is added to.
    objective : {"energy", "peak"}
    torque_limit : float or (3,) array, optional
        |τ_a| ≤ L_a at the samples, N m (SI floats).
    n_samples : int, optional
        Samples of [0, T] where the limits hold (default 16 n_b + 1).
    start : ((3 + n_F), n_b) array, optional
        Coefficients already planned (``terminal`` linearised along their trajectory): the
        result is start + Δc with X Δc = r, the objective and limits on the whole history.
    force_limit : float, optional
        |F_i| ≤ L_F at the samples for every planned force, N. Required, with
        ``torque_limit``, by ``objective="peak"`` when forces are planned.
    force_weight : float
        w_F, m²: the energy is :math:`\int_0^T \lVert J v\rVert^2 + w_F\lVert F\rVert^2 dt`
        (a force of 1 N costs as much as :math:`\sqrt{w_F}` N m of torque).

    Raises
    ------
    ValueError
        Naming ``objective``, ``torque_limit``, ``force_limit``, ``force_weight``,
        ``n_samples`` or ``start``.
    """
    from scipy.linalg import null_space

    if objective not in OBJECTIVES:
        raise FieldError("objective", f"must be one of {', '.join(OBJECTIVES)}, got {objective!r}")
    L = _limits(torque_limit)
    n_b, T, J, n_f = terminal.n_basis, terminal.duration, terminal.inertia, terminal.n_forces
    L_F = _force_settings(n_f, force_limit, float(force_weight), objective, L is not None)
    n_s = 16 * n_b + 1 if n_samples is None else require_count(n_samples, "n_samples")
    if n_s < 2:
        raise FieldError("n_samples", f"must be at least 2, got {n_s}")
    n_c = (3 + n_f) * n_b
    H_tau = (0.5 * T) * np.kron(J.T @ J, np.eye(n_b))
    H = np.zeros((n_c, n_c))
    H[: 3 * n_b, : 3 * n_b] = H_tau
    H[3 * n_b :, 3 * n_b :] = (0.5 * T * float(force_weight)) * np.eye(n_f * n_b)
    # with forces, the coefficients scaled to unit diagonal of H (c = D ĉ, an exact change of
    # variables): torque sines weigh ~‖J‖², force sines w_F, and SLSQP would not resolve the
    # reduced problem at that condition
    D = 1.0 / np.sqrt(np.diag(H)) if n_f else np.ones(n_c)
    X, r = terminal.X * D, terminal.target
    U, sv, Vt = np.linalg.svd(X, full_matrices=True)
    rank = int(np.sum(sv > RANK_RCOND * sv[0]))
    c_prev = np.zeros(n_c) if start is None else np.asarray(start, float).reshape(-1)
    if c_prev.shape != (n_c,) or not np.all(np.isfinite(c_prev)):
        raise FieldError("start", f"must be {n_c} finite coefficients ({3 + n_f}, n_b)")
    c0 = c_prev / D + Vt[:rank].T @ ((U[:, :rank].T @ r) / sv[:rank])
    N = Vt[rank:].T if rank < Vt.shape[0] else null_space(X)
    Hs = H * D[:, None] * D[None, :]
    P, q = N.T @ Hs @ N, N.T @ Hs @ c0
    z = -np.linalg.solve(P, q)  # the unconstrained optimum

    t = np.linspace(0.0, T, n_s)
    scale_in = np.concatenate(
        [L if L is not None else np.ones(3), np.full(n_f, L_F if L_F is not None else 1.0)]
    )
    # the limited inputs' rows (all of them for the peak objective, _force_settings)
    limited = np.r_[np.full(3, L is not None), np.full(n_f, L_F is not None)]
    if objective == "peak":
        limited[:] = True
    M = _input_map(terminal, t)[:, limited] * D  # (n_s, n_lim, n_c), per scaled coefficient
    u_n = np.concatenate([nominal.torque(t), np.zeros((n_s, n_f))], axis=1)[:, limited]
    scale = np.tile(scale_in[limited], n_s)
    MN = M.reshape(-1, n_c) @ N  # rows (k, input)
    # normalised rows: ±(u_n + M (c0 + N z))/L ≤ 1  →  G z ≤ h
    G = np.vstack([MN / scale[:, None], -MN / scale[:, None]])
    base = (u_n.reshape(-1) + M.reshape(-1, n_c) @ c0) / scale
    h = np.concatenate([1.0 - base, 1.0 + base])
    any_limit = L is not None or L_F is not None

    least_peak, message = float("nan"), ""
    feasible = True
    if objective == "peak":
        z_lp, least_peak, message = _least_peak(G, np.concatenate([-base, base]), N.shape[1])
        if z_lp is None:
            raise FieldError("objective", message)  # an LP without solution: a bug, not input
        z = z_lp
        feasible = L is None or least_peak <= 1.0
    elif any_limit and np.max(G @ z - h) > 0.0:
        f0 = max(float(0.5 * z @ P @ z + q @ z + 0.5 * c0 @ Hs @ c0), 1e-300)

        def qp(z_start: FloatArray) -> tuple[FloatArray, str]:
            # constraint generation: SLSQP on the rows violated or near their limit so far,
            # adding the rows its optimum violates until it meets them all; the optimum of a
            # relaxation that meets every row is the optimum of the whole problem (a few
            # hundred of the thousands of sampled rows instead of all: 38 s -> a few s on the
            # EPS examples)
            work = np.flatnonzero(G @ z_start - h > -0.05)
            y, rounds, text = z_start, 0, ""
            while rounds < 50:
                rounds += 1
                y, text = _restricted_qp(P, q, G[work], h[work], f0, y)
                new = np.setdiff1d(np.flatnonzero(G @ y - h > 1e-9), work)
                if not new.size:
                    break
                work = np.union1d(work, new)
            return (
                _polish(P, q, G, h, y),
                f"SLSQP on {work.size} of {G.shape[0]} rows ({rounds} rounds): {text}",
            )

        z, message = qp(z)
        if np.max(G @ z - h) > 1e-6:
            z_lp, least_peak, lp_message = _least_peak(G, np.concatenate([-base, base]), N.shape[1])
            message += f"; {lp_message}: {least_peak:.4g} × the limit"
            if z_lp is not None and least_peak <= 1.0:
                # feasible after all: SLSQP again from the least-peak point, inside the limits
                z, again = qp(z_lp)
                message += f"; from the least-peak point, {again}"
            feasible = bool(np.max(G @ z - h) <= 1e-6)
    else:
        message = "unconstrained optimum (closed form)"

    c = D * (c0 + N @ z)
    grad = P @ z + q
    slack = h - G @ z
    active_rows = (
        np.flatnonzero(slack <= ACTIVE_TOL) if (any_limit and feasible) else np.zeros(0, dtype=int)
    )
    lam = np.zeros(0)
    if objective == "energy" and len(active_rows):
        from scipy.optimize import nnls

        lam, _ = nnls(G[active_rows].T, -grad)
        kkt = float(np.linalg.norm(grad + G[active_rows].T @ lam) / np.linalg.norm(grad))
    elif objective == "energy":
        kkt = float(np.linalg.norm(grad) / max(float(np.linalg.norm(q)), 1e-300))
    else:
        kkt = float("nan")  # an LP optimum: HiGHS's own optimality certificate
    c_tau, d = c[: 3 * n_b], c[3 * n_b :]
    shaped = ShapedSlew(
        nominal,
        c_tau.reshape(3, n_b),
        J,
        float(
            np.linalg.norm(terminal.X @ (c - c_prev) - r) / max(float(np.linalg.norm(r)), 1e-300)
        ),
        terminal.force_channels,
        d.reshape(n_f, n_b) if n_f else None,
    )
    fine = np.linspace(0.0, T, 4 * (n_s - 1) + 1)
    peaks = np.abs(shaped.torque(fine)).max(axis=0)
    return PlannedSlew(
        shaped=shaped,
        objective=objective,
        feasible=feasible,
        energy=float(c @ H @ c),
        peak_torques=peaks,
        torque_limit=L,
        least_peak=least_peak,
        active=len(active_rows),
        multipliers=lam,
        kkt_residual=kkt,
        terminal_residual=shaped.residual,
        rank=rank,
        message=message,
        torque_energy=float(c_tau @ H_tau @ c_tau),
        peak_forces=np.abs(shaped.forces(fine)).max(axis=0) if n_f else np.zeros(0),
        force_limit=L_F,
    )


class PlannedTrajectory:
    """The plan flown on the design model: the nominal of the perturbation feedback on top
    (module docstring). ``beta``, ``omega``, ``torque``, ``elastic`` at any t (held beyond
    [0, T]; between the control samples by cubic splines, the Euler parameters renormalised).

    The rate the plan leaves at T (the terminal residual of the successive linearisation,
    ~1e-8 rad/s on the EPS) is taken out, blended in as (t/T)⁸ (a change below the residual
    itself over the maneuver): a linearisation at a rate of that size splits the rigid
    attitude's triple zero eigenvalue by about that much, and the stabilisability test of the
    design at T then refuses it (the nominal maneuver ends at rest to 1e-16 rad/s).

    Parameters
    ----------
    plan : PlannedSlew or ShapedSlew
    design_plant : FlexibleSpacecraft
    config : SimConfig
        Its control period is the sample grid of the plan's torque.
    """

    def __init__(
        self, plan: PlannedSlew | ShapedSlew, design_plant: FlexibleSpacecraft, config: SimConfig
    ) -> None:
        from dataclasses import replace

        from scipy.interpolate import CubicSpline

        from flexsat.control import NominalTorque
        from flexsat.sim import simulate

        shaped = plan.shaped if isinstance(plan, PlannedSlew) else plan
        self.plan = shaped
        self.duration = float(shaped.duration)
        self.target = shaped.target
        #: the planned point forces, flown with the torque (empty for torquers alone)
        self.force_channels = shaped.force_channels
        h = float(config.dt)
        run_config = replace(config, duration=h * (int(np.ceil(self.duration / h)) + 1))
        run = simulate(
            design_plant, NominalTorque(shaped, h), run_config, n_cases=1, record_states=True
        )
        t = run.dataset["time"].values
        x = run.dataset["state"].isel(case=0).values
        inside = t <= self.duration + 1e-9 * h
        t, x = t[inside], x[inside]
        self._beta = CubicSpline(t, x[:, :4])
        self._omega = CubicSpline(t, x[:, 4:7])
        self._omega_end = np.asarray(self._omega(self.duration), float)
        self._elastic = CubicSpline(t, np.stack([design_plant.output("elastic", s) for s in x]))
        self.n_modes = design_plant.n_modes

    def _held(self, t: npt.ArrayLike) -> FloatArray:
        return np.clip(np.asarray(t, float), 0.0, self.duration)

    def beta(self, t: npt.ArrayLike) -> FloatArray:
        b = np.asarray(self._beta(self._held(t)), float)
        return b / np.linalg.norm(b, axis=-1, keepdims=True)

    def omega(self, t: npt.ArrayLike) -> FloatArray:
        """The planned rate less its terminal residual blended in as (t/T)⁸ (see the class
        docstring), rad/s."""
        s = self._held(t)
        ramp = (s / self.duration) ** 8
        return np.asarray(self._omega(s), float) - ramp[..., None] * self._omega_end

    def torque(self, t: npt.ArrayLike) -> FloatArray:
        return self.plan.torque(t)

    def forces(self, t: npt.ArrayLike) -> FloatArray:
        """The planned point forces (..., n_F), N."""
        return self.plan.forces(t)

    def elastic(self, t: npt.ArrayLike) -> FloatArray:
        """[η, η̇] of the design modes along the plan (..., 2n)."""
        return np.asarray(self._elastic(self._held(t)), float)


def planned_slew(
    truth: FlexibleSpacecraft,
    design_plant: FlexibleSpacecraft,
    nominal: ThreeAxisSlew,
    config: SimConfig,
    n_basis: int = 30,
    objective: str = "energy",
    torque_limit: npt.ArrayLike | None = None,
    n_samples: int | None = None,
    iterations: int = 4,
    tolerance: float = 1e-6,
    peak_margin: float = 0.02,
    forces: Sequence[str] = (),
    force_limit: float | None = None,
    force_weight: float = 1.0,
) -> PlannedSlew:
    r"""The planned slew by successive linearisation (module docstring): :func:`plan_slew` on
    the conditions along the rigid nominal, then along the planned trajectory itself until the
    terminal state of the planned torque flown on ``truth`` (its design modes, the attitude
    error from the target and the rate) is below ``tolerance`` relative to the first one's.

    The modal conditions are linear in the torque; the rigid rotation is not (the correction
    changes the path, so the attitude at T is met only to first order by one step: measured,
    40 mrad on the 10-mode EPS in 6 s). Each step's residual is quadratic in the previous one
    (Newton's method on the terminal conditions, the objective re-minimised at each step).

    Parameters
    ----------
    truth, design_plant, nominal, config, n_basis
        As :func:`~flexsat.design.slew_shaping.terminal_map`.
    objective, torque_limit, n_samples
        As :func:`plan_slew`.
    iterations : int
        Relinearisations after the first step (at most; the terminal state is measured once
        more after the last).
    tolerance : float
        Stop when ‖r_k‖ ≤ tolerance ‖r_0‖.
    peak_margin : float
        With ``objective="peak"``: the least peak of the first linearisation (the LP) is
        relaxed by this fraction and the energy minimised within it at every step (an LP
        vertex jumps between linearisations, and the iteration would not settle).
    forces : sequence of str
        Force channels of the plants (``force_<node><AXIS>``) planned beside the torque
        (:mod:`~flexsat.design.slew_shaping`, "Point forces as planned inputs"); empty for
        torquers alone.
    force_limit, force_weight
        As :func:`plan_slew`.
    """
    from dataclasses import replace

    iterations = int(iterations)
    if iterations < 0:
        raise FieldError("iterations", f"must be >= 0, got {iterations}")
    if not (np.isfinite(tolerance) and tolerance > 0.0):
        raise FieldError("tolerance", f"must be finite and > 0, got {tolerance!r}")
    if not (np.isfinite(peak_margin) and peak_margin >= 0.0):
        raise FieldError("peak_margin", f"must be finite and >= 0, got {peak_margin!r}")
    forces = tuple(forces)
    terminal = terminal_map(truth, design_plant, nominal, config, n_basis, forces=forces)
    plan = plan_slew(
        terminal, nominal, objective, torque_limit, n_samples, None, force_limit, force_weight
    )
    if objective == "peak" and plan.feasible:
        # the least peak, then the least energy within it (a vertex of the LP jumps between
        # linearisations; the energy within a fixed limit does not)
        limit = plan.least_peak * (1.0 + peak_margin)
        torque_limit = limit * (plan.torque_limit if plan.torque_limit is not None else 1.0)
        force_limit = None if plan.force_limit is None else limit * plan.force_limit
        least = plan.least_peak
        plan = replace(
            plan_slew(
                terminal,
                nominal,
                "energy",
                torque_limit,
                n_samples,
                None,
                force_limit,
                force_weight,
            ),
            least_peak=least,
        )
    r0 = float(np.linalg.norm(terminal.target))
    history = [r0]
    for step in range(iterations + 1):
        if not plan.feasible:
            break
        trajectory = PlannedTrajectory(plan, design_plant, config)
        terminal = terminal_map(
            truth, design_plant, trajectory, config, n_basis, rigid=True, forces=forces
        )
        history.append(float(np.linalg.norm(terminal.target)))
        if history[-1] <= tolerance * r0 or step == iterations:
            break
        least = plan.least_peak
        start = plan.shaped.coefficients
        if plan.shaped.force_coefficients is not None:
            start = np.vstack([start, plan.shaped.force_coefficients])
        plan = plan_slew(
            terminal, nominal, "energy", torque_limit, n_samples, start, force_limit, force_weight
        )
        plan = replace(plan, least_peak=least if np.isnan(plan.least_peak) else plan.least_peak)
    return replace(plan, objective=objective, iterates=tuple(history))
