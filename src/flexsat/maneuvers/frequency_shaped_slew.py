"""Single-axis frequency-shaped optimal rest-to-rest slew, solved exactly by the Hamiltonian
matrix exponential (EPS slew study c. 1989, after Chun, Turner & Juang 1987).

Problem (the single-axis closed form; a principal axis, so G(ω) = 0).
State ``x = [θ, ω, u1, u2]`` with the normalized torque ``u1 = u / I`` [rad/s²], its rate ``u2``
and the control ``u3 = u̇2``::

    θ̇ = ω,   ω̇ = u1,   u̇1 = u2,   u̇2 = u3                                   (12)-(14)

    J = ½ ∫_0^T [ q ω² + (u1 + u3/ω_B²)² + (4 ζ_B²/ω_B²) u2² ] dt              (15)

The running cost is the time-domain form of the frequency weight |W(jω)|² on the torque with the
two-pole shaping filter ``W(s) = 1 + 2 ζ_B s/ω_B + s²/ω_B²`` (the damped reading):
``|W(u1)|² = (u1 + ü1/ω_B²)² + 4ζ_B² u̇1²/ω_B² + d/dt(...)``, the total derivatives vanishing
because u1 = u2 = 0 at both ends.  ``ζ_B = 0`` is the paper's literal weight (s = +1:
penalty (1 - ω²/ω_B²)², zero at ω_B, so the torque rings at ω_B); ``ζ_B = 1`` is the damped
reading (penalty (1 + ω²/ω_B²)², the s = -1 form up to boundary terms).

Costates ``[p, λ, μ1, μ2]`` and the optimal control (Eqs. 17-20, single axis)::

    H  = ½ L + p ω + λ u1 + μ1 u2 + μ2 u3
    ṗ = 0,  λ̇ = -q ω - p,  μ̇1 = ω_B² μ2 - λ,  μ̇2 = -(4ζ_B²/ω_B²) u2 - μ1    (16)-(19)
    u3 = -ω_B² (u1 + ω_B² μ2)                                                  (20)

so ``z = [x, costates]`` obeys the linear Hamiltonian system ``ż = K z`` and
``z(T) = e^{KT} z(0)`` (Eq. 21).  Boundary conditions: θ(0) = 0, θ(T) = Θ and
ω = u1 = u2 = 0 at both ends.

Solution.  Single shooting partitions ``Φ = e^{KT}`` and solves ``Φ_xp p(0) = x_T - Φ_xx x_0``
for the initial costates (the "standard partitioned matrix solution").  With ζ_B > 0
the Hamiltonian has eigenvalues with real part ±ζ_B ω_B (±ω_B for ζ_B = 1), so Φ_xp grows like
e^{ζ_B ω_B T} and is ill conditioned once ω_B T ≳ 15.  When ``cond(Φ_xp)`` exceeds
``cond_limit``, or one interval would be too long for an accurate exponential, the problem is
solved instead by multiple shooting: the knots ``z_k`` of N equal segments are the unknowns of
one sparse block system ``e^{Kh} z_k - z_{k+1} = 0`` plus the eight boundary conditions, each
segment short enough that ``e^{Kh}`` grows by at most e³ and turns by at most 30 rad (ω_B h ≤ 30:
the ringing of ζ_B = 0, which the expm scaling and squaring resolves poorly over many periods).
The result records which method was used and the single-shot condition number.

Everything is solved in scaled variables (time in units of T, θ in units of Θ, and the diagonal
balancing of K·T from :func:`scipy.linalg.matrix_balance`, exact powers of two) because the
raw K holds ω_B⁴ next to 1.

Also propagated in those scaled variables (``FrequencyShapedSlew.z``), from the knot below t.

The observation that with ζ_B = 0, q = 0, T = 10 s, u1 changes sign 5
times at ω_B = 2.5 rad/s and 13 times at 5 rad/s is reproduced by this formulation (tested);
with ζ_B = 1 it changes sign once.

Limits.  ω_B → ∞ with q = 0 gives the minimum-energy torque 6IΘ/T²(1 - 2t/T) only for
ζ_B > 0: the forced zero torque at the ends costs a boundary layer of width ~1/ω_B and a peak
deficit O(1/(ω_B T)) (0.4 % at ω_B T = 2000).  With the literal ζ_B = 0 the ringing at ω_B is free
(zero penalty), so it absorbs the jump of the minimum-energy torque at the ends and keeps its
amplitude: the peak tends to 2 × 6IΘ/T² (1.995 × at ω_B T = 2000), while the cost still tends
to the minimum energy.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt
import scipy.linalg
import scipy.sparse
import scipy.sparse.linalg

from flexsat.input_checks import FieldError, require_finite, require_nonneg, require_positive
from flexsat.units import FloatArray, QuantityArrayLike, QuantityLike

__all__ = [
    "MAX_SHOOTING_SEGMENTS",
    "FrequencyShapedSlew",
    "balanced_hamiltonian",
    "shooting_segments",
    "frequency_shaped_slew",
    "hamiltonian",
    "hamiltonian_matrix",
    "shaping_control",
]

_GROWTH_PER_SEGMENT = 3.0  # ln of the largest growth e^{Re(λ) h} allowed in one shooting segment
_PHASE_PER_SEGMENT = 30.0  # largest |λ| h in one segment (ω_B h for the ringing at ω_B)
_LOG_OVERFLOW = 700.0  # e^{700} ~ 1e304: beyond it e^{KT} is not representable in float64

#: shooting segments of one single-axis slew: the sparse system holds ~72 entries per segment
#: (~9 kB of Python lists while it is assembled), so 10⁵ segments are ~1 GB; the three-axis
#: continuation (:mod:`flexsat.maneuvers.three_axis_slew`) checks its own dense Jacobian
MAX_SHOOTING_SEGMENTS = 100_000


def hamiltonian_matrix(omega_b: float, zeta_b: float = 0.0, q: float = 0.0) -> FloatArray:
    """The 8×8 matrix K of ``ż = K z``, ``z = [θ, ω, u1, u2, p, λ, μ1, μ2]`` (SI).

    Eqs. (12)-(14) with u3 from (20), and the costate Eqs. (16)-(19) of the paper
    in the general ζ_B form (see the module docstring).
    """
    wb2 = np.float64(omega_b) * omega_b
    k = np.zeros((8, 8))
    k[0, 1] = 1.0  # θ̇ = ω
    k[1, 2] = 1.0  # ω̇ = u1
    k[2, 3] = 1.0  # u̇1 = u2
    # an absurd ω_B or ζ_B overflows to inf here (numpy floats), which the caller refuses by name
    with np.errstate(over="ignore"):
        k[3, 2], k[3, 7] = -wb2, -wb2 * wb2  # u̇2 = u3 = -ω_B²(u1 + ω_B² μ2)
        k[7, 3], k[7, 6] = -4.0 * np.float64(zeta_b) ** 2 / wb2, -1.0  # μ̇2 = -(4ζ_B²/ω_B²) u2 - μ1
    k[5, 1], k[5, 4] = -q, -1.0  # λ̇ = -q ω - p
    k[6, 7], k[6, 5] = wb2, -1.0  # μ̇1 = ω_B² μ2 - λ
    return k


def shaping_control(state: npt.ArrayLike, costate: npt.ArrayLike, omega_b: float) -> FloatArray:
    """Optimal control u3 = -ω_B² (u1 + ω_B² μ2), Eq. (20), on arrays ``(..., 4)``."""
    state, costate = np.asarray(state), np.asarray(costate)
    wb2 = omega_b * omega_b
    return -wb2 * (state[..., 2] + wb2 * costate[..., 3])


def hamiltonian(
    state: npt.ArrayLike,
    costate: npt.ArrayLike,
    u3: npt.ArrayLike,
    omega_b: float,
    zeta_b: float = 0.0,
    q: float = 0.0,
) -> FloatArray:
    """H = ½ L + p ω + λ u1 + μ1 u2 + μ2 u3 for any u3, on arrays ``(..., 4)``.

    Kept a function of an arbitrary u3 so that its gradients give the costate equations
    (-∂H/∂x) and the stationarity condition (∂H/∂u3 = 0 at Eq. 20).
    """
    x, c, u3 = np.asarray(state), np.asarray(costate), np.asarray(u3)
    wb2 = omega_b * omega_b
    running = (
        q * x[..., 1] ** 2 + (x[..., 2] + u3 / wb2) ** 2 + 4.0 * zeta_b**2 / wb2 * x[..., 3] ** 2
    )
    return (
        0.5 * running
        + c[..., 0] * x[..., 1]
        + c[..., 1] * x[..., 2]
        + c[..., 2] * x[..., 3]
        + c[..., 3] * u3
    )


@dataclass(frozen=True)
class FrequencyShapedSlew:
    """Solved slew: the state-costate knots and the evaluation of the trajectory (SI).

    ``knots`` (N+1,) are the segment boundaries [s]; ``z_knots`` (N+1, 8) the state-costate
    vector there; ``method`` is ``"single shooting"`` or ``"multiple shooting"``;
    ``condition`` is cond(Φ_xp) of the single-shot partition of e^{KT} (the reason for the
    choice); ``n_segments`` = N.  ``K`` is the SI Hamiltonian matrix; the solution is propagated
    with the balanced dimensionless ``K_scaled = T S⁻¹ K S`` on ``z = scale · ζ``
    (``S = diag(scale)``), which keeps ω_B⁴ away from the matrix exponential.
    """

    angle: float
    inertia: float
    duration: float
    omega_b: float
    zeta_b: float
    q: float
    K: FloatArray
    scale: FloatArray
    K_scaled: FloatArray
    knots: FloatArray
    z_knots: FloatArray
    method: str
    condition: float

    @property
    def n_segments(self) -> int:
        return len(self.knots) - 1

    def z(self, t: QuantityArrayLike) -> FloatArray:
        """State-costate vector at times ``t`` (any shape, within [0, T]): shape ``t.shape + (8,)``.

        Propagated exactly, ``z(t) = e^{K (t - t_k)} z_k`` from the knot below t, so the growth
        over one evaluation is that of one segment.
        """
        t = require_finite(t, "t", "s")
        span = 1e-12 * self.duration  # rounding of t = T computed by the caller
        if np.any(t < -span) or np.any(t > self.duration + span):
            raise FieldError(
                "t",
                f"must lie in [0, {self.duration:g}] s (the maneuver), got "
                f"[{t.min():g}, {t.max():g}]",
            )
        flat = np.clip(t.ravel(), 0.0, self.duration)
        k = np.clip(np.searchsorted(self.knots, flat, side="right") - 1, 0, self.n_segments - 1)
        tau = (flat - self.knots[k]) / self.duration
        phi = scipy.linalg.expm(self.K_scaled[None] * tau[:, None, None])
        zeta = np.einsum("nij,nj->ni", phi, self.z_knots[k] / self.scale)
        return (zeta * self.scale).reshape(t.shape + (8,))

    def torque(self, t: QuantityArrayLike) -> FloatArray:
        """Physical torque I u1(t) [N m]."""
        return self.inertia * self.z(t)[..., 2]

    def theta(self, t: QuantityArrayLike) -> FloatArray:
        """Angle θ(t) [rad]."""
        return self.z(t)[..., 0]

    def omega(self, t: QuantityArrayLike) -> FloatArray:
        """Rate ω(t) [rad/s]."""
        return self.z(t)[..., 1]

    def hamiltonian(self, t: QuantityArrayLike) -> FloatArray:
        """H(t) along the solution (constant for this autonomous problem)."""
        z = self.z(t)
        u3 = shaping_control(z[..., :4], z[..., 4:], self.omega_b)
        return hamiltonian(z[..., :4], z[..., 4:], u3, self.omega_b, self.zeta_b, self.q)

    def boundary_error(self) -> float:
        """Largest boundary-condition residual at 0 and T from the evaluated trajectory, each
        relative to its natural size: θ to Θ, ω to Θ/T, u1 to Θ/T², and u2 to
        (Θ/T²)·max(1/T, ω_B), because the shaped torque rises or rings on the time scale 1/ω_B
        (its rate is ~ω_B T times Θ/T³ when ω_B T is large)."""
        ends = self.z(np.array([0.0, self.duration]))[:, :4]
        target = np.array([[0.0, 0.0, 0.0, 0.0], [self.angle, 0.0, 0.0, 0.0]])
        scale = abs(self.angle) / self.duration ** np.arange(4)
        scale[3] *= max(1.0, self.omega_b * self.duration)
        return float(np.max(np.abs(ends - target) / scale))


def frequency_shaped_slew(
    angle: QuantityLike,
    inertia: QuantityLike,
    duration: QuantityLike,
    omega_b: QuantityLike,
    zeta_b: QuantityLike = 0.0,
    q: QuantityLike = 0.0,
    cond_limit: float = 1e8,
) -> FrequencyShapedSlew:
    """Optimal frequency-shaped rest-to-rest slew about one principal axis (module docstring).

    Parameters
    ----------
    angle : slew angle Θ [rad] (finite, nonzero; "deg" strings accepted).
    inertia : principal moment of inertia I [kg m²] (> 0).
    duration : maneuver time T [s] (> 0).
    omega_b : shaping break frequency ω_B [rad/s] (> 0).
    zeta_b : shaping damping ζ_B (>= 0; 0 = the paper's literal weight, 1 = damped).
    q : weight on ω² [1/s²] (>= 0).
    cond_limit : largest cond(Φ_xp) accepted for single shooting (else multiple shooting).

    Returns
    -------
    FrequencyShapedSlew
    """
    angle = float(require_finite(angle, "angle", "rad"))
    if angle == 0.0:
        raise FieldError("angle", "must be nonzero (a zero slew has the trivial solution u = 0)")
    inertia = float(require_positive(inertia, "inertia", "kg*m**2"))
    duration = float(require_positive(duration, "duration", "s"))
    omega_b = float(require_positive(omega_b, "omega_b", "rad/s"))
    zeta_b = float(require_nonneg(zeta_b, "zeta_b", ""))
    q = float(require_nonneg(q, "q", "1/s**2"))
    cond_limit = float(require_positive(cond_limit, "cond_limit"))

    # Dimensionless problem: τ = t/T, θ in units of Θ (the problem is linear in Θ).  In these
    # units K becomes K(ω_B T, ζ_B, q T²) with the costates rescaled accordingly; the diagonal
    # balancing D (powers of two) then evens out the powers of ω_B T.
    kb, d, growth, n = shooting_segments(omega_b, duration, zeta_b, q)
    x0 = np.zeros(4)
    xt = np.array([1.0, 0.0, 0.0, 0.0])
    if growth < _LOG_OVERFLOW:
        phi = scipy.linalg.expm(kb)
        # In balanced variables x_b(1) = Φ_xx x_b(0) + Φ_xp c_b(0).
        condition = float(np.linalg.cond(phi[:4, 4:]))
    else:
        condition = np.inf  # e^{KT} overflows: the single-shot partition cannot even be formed
    if condition <= cond_limit and n == 1:
        c0 = np.linalg.solve(phi[:4, 4:], xt / d[:4] - phi[:4, :4] @ (x0 / d[:4]))
        start = np.concatenate([x0 / d[:4], c0])
        zb = np.vstack([start, phi @ start])
        tau = np.array([0.0, 1.0])
        method = "single shooting"
    else:
        n = max(n, 2)
        tau = np.linspace(0.0, 1.0, n + 1)
        zb = _multiple_shooting(kb, n, x0 / d[:4], xt / d[:4])
        method = "multiple shooting"

    # Back to SI: ẑ = D ζ; x = diag(Θ, Θ/T, Θ/T², Θ/T³) x̂ and, since J = (Θ²/T³) Ĵ, the
    # costates ∂J/∂x are [p, λ, μ1, μ2] = diag(Θ/T³, Θ/T², Θ/T, Θ) ĉ (so K = S K̂ S⁻¹ / T).
    powers = np.array([0, 1, 2, 3, 3, 2, 1, 0])
    scale = d * angle / duration**powers
    z_knots = zb * scale[None, :]
    return FrequencyShapedSlew(
        angle=angle,
        inertia=inertia,
        duration=duration,
        omega_b=omega_b,
        zeta_b=zeta_b,
        q=q,
        K=hamiltonian_matrix(omega_b, zeta_b, q),
        scale=scale,
        K_scaled=kb,
        knots=tau * duration,
        z_knots=z_knots,
        method=method,
        condition=condition,
    )


def balanced_hamiltonian(
    wbt: float, zeta_b: float, q_hat: float
) -> tuple[FloatArray, FloatArray, float, float]:
    """(K_b, D, spectral abscissa, segment count) of the dimensionless problem (ω_B T, ζ_B,
    q T²), before anything is solved: K_b = D⁻¹ K̂ D is K̂ balanced by the powers of two D; the
    count is inf when K̂ is not finite (ω_B T or ζ_B overflowing its entries).

    Segment count: each segment's e^{K_b h} grows by at most e^3 (spectral abscissa) and turns
    by at most _PHASE_PER_SEGMENT rad (spectral radius); beyond that the scaling and squaring of
    expm and the single-shot partition lose digits (measured: BC error 1.6e-12 at ω_B T = 25,
    2e-8 at ω_B T = 500 single shot).
    """
    k_hat = hamiltonian_matrix(wbt, zeta_b, q_hat)
    if not np.all(np.isfinite(k_hat)):
        return k_hat, np.ones(8), np.inf, np.inf
    _, (d, _) = scipy.linalg.matrix_balance(k_hat, permute=False, separate=True)
    kb = k_hat * (1.0 / d)[:, None] * d[None, :]  # K_b = D⁻¹ K̂ D, ζ = D⁻¹ ẑ
    eig = np.linalg.eigvals(kb)
    growth, radius = float(np.max(eig.real)), float(np.max(np.abs(eig)))
    if not (np.isfinite(growth) and np.isfinite(radius)):
        return kb, d, np.inf, np.inf
    n = max(1.0, np.ceil(growth / _GROWTH_PER_SEGMENT), np.ceil(radius / _PHASE_PER_SEGMENT))
    return kb, d, growth, n


def shooting_segments(
    omega_b: float, duration: float, zeta_b: float, q: float
) -> tuple[FloatArray, FloatArray, float, int]:
    """:func:`balanced_hamiltonian` of a slew (SI inputs), its segment count checked against
    :data:`MAX_SHOOTING_SEGMENTS` before anything is allocated.

    Raises
    ------
    flexsat.input_checks.FieldError
        Blaming the input that makes the count too large: ``q`` if the problem without it fits,
        else ``zeta_b`` if the undamped one fits, else ``omega_b`` (ω_B T counts).
    """
    wbt = omega_b * duration
    kb, d, growth, n = balanced_hamiltonian(wbt, zeta_b, q * duration**2)
    if n <= MAX_SHOOTING_SEGMENTS:
        return kb, d, growth, int(n)
    if q > 0 and balanced_hamiltonian(wbt, zeta_b, 0.0)[3] <= MAX_SHOOTING_SEGMENTS:
        field, what = "q", f"the rate weight q T² = {q * duration**2:.3g}"
    elif zeta_b > 0 and balanced_hamiltonian(wbt, 0.0, 0.0)[3] <= MAX_SHOOTING_SEGMENTS:
        field, what = "zeta_b", f"the shaping damping ζ_B = {zeta_b:.3g} (4ζ_B²/(ω_B T)²)"
    else:
        field, what = "omega_b", f"ω_B T = {wbt:.3g} (break frequency × duration)"
    raise FieldError(
        field,
        f"{what} needs {n:.3g} shooting segments, above the limit {MAX_SHOOTING_SEGMENTS:,} "
        "(flexsat.maneuvers.frequency_shaped_slew.MAX_SHOOTING_SEGMENTS: one segment per e³ "
        "of growth or 30 rad of ringing of the Hamiltonian system)",
    )


def _multiple_shooting(kb: FloatArray, n: int, x0: FloatArray, xt: FloatArray) -> FloatArray:
    """Knots ζ_0..ζ_N of ``ζ' = K_b ζ`` on N equal segments of [0, 1] with the rest-to-rest
    boundary conditions: one sparse (8N + 8)-square block system."""
    phi = scipy.linalg.expm(kb / n)
    m = 8 * (n + 1)
    rows: list[int | np.integer[Any]] = []
    cols: list[int | np.integer[Any]] = []
    vals: list[float] = []
    # Rows 0..3: x(0) = x0.
    rows += list(range(4))
    cols += list(range(4))
    vals += [1.0] * 4
    ii, jj = np.nonzero(phi)
    for k in range(n):  # rows 4 + 8k ..: Φ ζ_k - ζ_{k+1} = 0
        r0 = 4 + 8 * k
        rows += list(r0 + ii) + list(r0 + np.arange(8))
        cols += list(8 * k + jj) + list(8 * (k + 1) + np.arange(8))
        vals += list(phi[ii, jj]) + [-1.0] * 8
    r0 = 4 + 8 * n  # last 4 rows: x(1) = x_T
    rows += list(r0 + np.arange(4))
    cols += list(8 * n + np.arange(4))
    vals += [1.0] * 4
    a = scipy.sparse.csc_matrix((vals, (rows, cols)), shape=(m, m))
    rhs = np.zeros(m)
    rhs[:4] = x0
    rhs[-4:] = xt
    return scipy.sparse.linalg.spsolve(a, rhs).reshape(n + 1, 8)
