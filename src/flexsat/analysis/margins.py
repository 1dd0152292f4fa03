r"""Gain, phase, delay and disk margins of a loop, continuous or sampled-data.

Classical margins of a SISO loop L (negative feedback, :mod:`~flexsat.analysis.frequency_domain`):
at every gain crossover :math:`|L(j\omega_c)| = 1` the phase margin is
:math:`\varphi = \arg(-L(j\omega_c)) \in (-\pi, \pi]` and the delay that brings that point onto
−1 is :math:`(\varphi \bmod 2\pi)/\omega_c`; at every phase crossover
(:math:`\operatorname{Im} L = 0`, :math:`\operatorname{Re} L < 0`) the gain factor that reaches
−1 is :math:`-1/\operatorname{Re} L` (Franklin, Powell & Emami-Naeini, *Feedback Control of
Dynamic Systems*, 7th ed., §6.4). The margins reported are the smallest ones: the phase margin of
least |φ|, the delay margin the least delay, the upper gain margin the least factor > 1 and the
lower gain margin the largest factor < 1. For a sampled loop, crossings are sought on
0 <= ω <= π/dt (the unit circle), and the delay margin is given in seconds and in whole samples.

A continuous loop may carry a pure delay τ (:math:`L(s)e^{-s\tau}`, infinite-dimensional). It is
closed-loop stable iff the delay-free loop is and τ is below the delay-free loop's delay margin:
as the delay grows from 0, the Nyquist curve moves continuously and can only reach −1 at a gain
crossover, after the delay :math:`(\varphi \bmod 2\pi)/\omega_c` (the definition of the delay
margin).

Disk margins (Seiler, Packard & Gahinet, "An introduction to disk margins", IEEE Control
Systems Magazine 40(5), 2020, 78–95, Eqs. (11)–(15)): the loop stays stable for every
multiplicative factor f in the disk :math:`D(\alpha, \sigma) = \{(1 + \tfrac{1-\sigma}{2}\delta)
/(1 - \tfrac{1+\sigma}{2}\delta) : |\delta| < \alpha\}` iff

.. math::

    \alpha < \alpha_{max} = 1 / \|S + \tfrac{\sigma - 1}{2} I\|_\infty \quad\text{(SISO)},
    \qquad \alpha_{max} = 1 / \sup_\omega \mu_\Delta\big(S + \tfrac{\sigma - 1}{2} I\big)
    \quad\text{(multiloop, } \Delta \text{ diagonal)}.

The SISO norm is computed exactly (:func:`~flexsat.analysis.norms.hinf_norm`); μ is bounded from
above by :math:`\inf_D \bar\sigma(D M D^{-1})` over positive diagonal D (exact for two loops,
Doyle 1982), so the multiloop margin returned is a guaranteed lower bound, evaluated on a
frequency grid refined around its worst point (with that point's optimal D held, since
σ̄(D M D⁻¹) bounds μ at every frequency, then D optimised again at the refined one).
The disk :math:`D(\alpha, \sigma)` meets the real axis at
:math:`g_{min} = (1 - \alpha\tfrac{1-\sigma}{2})/(1 + \alpha\tfrac{1+\sigma}{2})` and
:math:`g_{max} = (1 + \alpha\tfrac{1-\sigma}{2})/(1 - \alpha\tfrac{1+\sigma}{2})` (∞ when the
denominator is <= 0), and the unit circle at the phase
:math:`\arccos\big((1 + g_{min} g_{max})/(g_{min} + g_{max})\big)`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import scipy.optimize

from flexsat.analysis.frequency_domain import (
    ResponseEvaluator,
    close_other_channels,
    pole_grid,
)
from flexsat.analysis.norms import hinf_norm, system_matrices
from flexsat.input_checks import FieldError

if TYPE_CHECKING:
    import control as ct
    from flexsat.analysis.frequency_domain import Loop
    from flexsat.units import FloatArray

__all__ = [
    "DiskMargin",
    "LoopMargins",
    "UnstableLoopError",
    "disk_margin",
    "disk_margins",
    "loop_margins",
]


class UnstableLoopError(FieldError):
    """The closed loop is unstable: its margins are not defined (the error names the pole)."""


@dataclass(frozen=True)
class LoopMargins:
    """Classical margins of a SISO loop (module docstring).

    Attributes
    ----------
    gain_margin : float
        Least gain factor > 1 that destabilises (∞ if none).
    gain_margin_lower : float
        Largest gain factor < 1 that destabilises (0 if none; crossings where |L| > 1e6 are
        not counted).
    phase_margin_deg : float
        Phase margin of least magnitude, degrees (∞ when |L| never crosses 1).
    delay_margin_s : float
        Least extra delay that destabilises, s (∞ when |L| never crosses 1).
    delay_margin_samples : int or None
        For a sampled loop, the whole samples of delay it tolerates, floor(τ_m/dt).
    gain_crossover_rad_s, phase_crossover_rad_s : float
        Frequencies of the phase margin and of the upper gain margin, rad/s (NaN-free: ∞ when
        there is none).
    dt : float
        0 for a continuous loop, the period of a sampled one, s.
    """

    gain_margin: float
    gain_margin_lower: float
    phase_margin_deg: float
    delay_margin_s: float
    delay_margin_samples: int | None
    gain_crossover_rad_s: float
    phase_crossover_rad_s: float
    dt: float

    @property
    def gain_margin_db(self) -> float:
        return 20.0 * math.log10(self.gain_margin) if math.isfinite(self.gain_margin) else math.inf


def _siso(loop: Loop | ct.StateSpace, field: str) -> tuple[ct.StateSpace, FloatArray, float]:
    """(L, closed-loop poles, dt) of a Loop or of a bare SISO loop transfer."""
    transfer = getattr(loop, "transfer", loop)
    A, B, C, D, dt = system_matrices(transfer, field)
    if hasattr(loop, "closed_loop_A"):
        poles = np.linalg.eigvals(loop.closed_loop_A)
    else:
        if D.shape[0] != D.shape[1]:
            raise FieldError(field, f"a loop transfer must be square, got {D.shape}")
        E = np.linalg.inv(np.eye(D.shape[0]) + D)
        poles = np.linalg.eigvals(A - B @ E @ C) if A.size else np.zeros(0)
    return transfer, poles, dt


def require_stable_loop(poles: FloatArray, dt: float, field: str = "loop") -> None:
    """Refuse an unstable closed loop, naming its worst pole."""
    if poles.size == 0:
        return
    measure = np.abs(poles) if dt else poles.real
    worst = int(np.argmax(measure))
    if measure[worst] >= (1.0 if dt else 0.0):
        where = f"|z| = {abs(poles[worst]):.6g} >= 1" if dt else "in the closed right half-plane"
        raise UnstableLoopError(
            field,
            f"the closed loop is unstable (pole {complex(poles[worst]):.6g}, {where}): "
            "stability margins are not defined for it",
        )


def _crossings(w: FloatArray, f: FloatArray) -> list[tuple[float, float]]:
    """Brackets [w_i, w_{i+1}] where the real sequence f changes sign or is zero."""
    out = []
    for i in range(len(w) - 1):
        if f[i] == 0.0:
            out.append((w[i], w[i]))
        elif f[i] * f[i + 1] < 0:
            out.append((w[i], w[i + 1]))
    if f[-1] == 0.0:
        out.append((w[-1], w[-1]))
    return out


def loop_margins(
    loop: Loop | ct.StateSpace, delay_s: float = 0.0, n_per_decade: int = 400
) -> LoopMargins:
    """Gain, phase and delay margins of a SISO loop, continuous or sampled (module docstring).

    Parameters
    ----------
    loop : Loop or control.StateSpace
        A :class:`~flexsat.analysis.frequency_domain.Loop` broken at one channel, or a SISO loop
        transfer L (the closed loop 1/(1 + L) is formed from it).
    delay_s : float
        A pure delay τ, s, in a continuous loop, L(s) e^{−sτ} (a sampled loop carries its delay
        as states, :func:`~flexsat.analysis.frequency_domain.build_loop`).
    n_per_decade : int
        Density of the search grid; every crossing found is then solved to round-off.

    Raises
    ------
    UnstableLoopError
        When the closed loop is unstable (also when τ exceeds the delay margin).
    FieldError
        For a MIMO loop (break it at one channel, or use :func:`disk_margins`).
    """
    L, poles, dt = _siso(loop, "loop")
    if L.ninputs != 1 or L.noutputs != 1:
        raise FieldError(
            "loop",
            f"classical margins need a SISO loop, got {L.noutputs} x {L.ninputs}: break it at "
            "one channel (build_loop(..., break_at=name)) or use disk_margins",
        )
    tau = float(delay_s)
    if not (math.isfinite(tau) and tau >= 0):
        raise FieldError("delay_s", f"must be a delay >= 0, s; got {delay_s!r}")
    if tau and dt:
        raise FieldError("delay_s", "a sampled loop carries its delay in samples (build_loop)")
    require_stable_loop(poles, dt)
    A, B, C, D, _ = system_matrices(L)
    evaluate = ResponseEvaluator(A, B, C, D, dt)
    w = pole_grid(evaluate.poles, dt, n_per_decade)

    def response(x: float) -> complex:
        return complex(evaluate(np.array([x]))[0, 0, 0] * np.exp(-1j * x * tau))

    G = evaluate(w)[:, 0, 0] * np.exp(-1j * w * tau)
    finite = np.isfinite(G)
    w, G = w[finite], G[finite]

    def solve(fn, a: float, b: float) -> float:  # noqa: ANN001 - a local scalar function
        return a if a == b else scipy.optimize.brentq(fn, a, b, xtol=1e-14 * max(b, 1e-300))

    # gain crossovers and the phase there
    gain_x = [
        solve(lambda x: abs(response(x)) - 1.0, a, b) for a, b in _crossings(w, np.abs(G) - 1.0)
    ]
    phases = [float(np.angle(-response(x))) for x in gain_x]
    delays = [((p % (2 * math.pi)) / x if x > 0 else math.inf) for p, x in zip(phases, gain_x)]
    # phase crossovers: Im L = 0 with Re L < 0
    phase_x = [solve(lambda x: response(x).imag, a, b) for a, b in _crossings(w, G.imag)]
    if dt and abs(G[-1].imag) <= 1e-9 * abs(G[-1]):
        # at the Nyquist frequency z = −1 and a real system's L is real: a phase crossover
        # there has no sign change of Im L to bracket it
        phase_x.append(float(w[-1]))
    # a crossing where |L| > 1e6 (a rigid mode's double integrator near ω = 0, whose phase
    # sits at −180° to round-off) would be a "margin" below −120 dB: noise, not a margin
    factors = [(-1.0 / response(x).real, x) for x in phase_x if -1e6 < response(x).real < 0]
    upper = [f for f in factors if f[0] > 1.0]
    lower = [f for f in factors if f[0] < 1.0]
    gm, w_gm = min(upper) if upper else (math.inf, math.inf)
    gm_lo = max(lower)[0] if lower else 0.0
    if phases:
        k = int(np.argmin(np.abs(phases)))
        pm, w_pm = math.degrees(phases[k]), gain_x[k]
    else:
        pm, w_pm = math.inf, math.inf
    dm = min(delays) if delays else math.inf
    if tau:
        # the delayed loop is stable iff the delay-free one is and tau is below its delay margin
        free = loop_margins(loop, 0.0, n_per_decade)
        if tau >= free.delay_margin_s:
            raise UnstableLoopError(
                "delay_s",
                f"the delay {tau:g} s exceeds the loop's delay margin "
                f"{free.delay_margin_s:g} s: the closed loop is unstable",
            )
    samples = int(math.floor(dm / dt + 1e-9)) if dt and math.isfinite(dm) else None
    return LoopMargins(gm, gm_lo, pm, dm, samples, w_pm, w_gm, dt)


# -- disk margins --------------------------------------------------------------------------
@dataclass(frozen=True)
class DiskMargin:
    """A disk margin α and the gain and phase variations it guarantees (module docstring).

    Attributes
    ----------
    alpha : float
        α_max (for a multiloop margin, a guaranteed lower bound).
    skew : float
        σ of the disk.
    gain_range : (float, float)
        [g_min, g_max] of simultaneous gain variations tolerated (g_max may be ∞).
    phase_deg : float
        ± phase variation tolerated, degrees.
    frequency_rad_s : float
        Where the margin is smallest, rad/s.
    """

    alpha: float
    skew: float
    gain_range: tuple[float, float]
    phase_deg: float
    frequency_rad_s: float

    @property
    def gain_margin_db(self) -> float:
        """The disk gain margin as MATLAB's ``diskmargin`` states it: 20 log10 g_max."""
        return (
            20.0 * math.log10(self.gain_range[1]) if math.isfinite(self.gain_range[1]) else math.inf
        )


def disk_variations(alpha: float, skew: float) -> tuple[tuple[float, float], float]:
    """([g_min, g_max], phase in degrees) of the disk D(α, σ) (module docstring)."""
    a = alpha * (1.0 - skew) / 2.0
    b = alpha * (1.0 + skew) / 2.0
    g_min = (1.0 - a) / (1.0 + b)
    g_max = (1.0 + a) / (1.0 - b) if b < 1.0 else math.inf
    if math.isinf(g_max):
        cos_phi = g_min
    else:
        cos_phi = (1.0 + g_min * g_max) / (g_min + g_max)
    phase = math.degrees(math.acos(max(-1.0, min(1.0, cos_phi))))
    return (g_min, g_max), phase


def _check_skew(skew: float) -> float:
    s = float(skew)
    if not math.isfinite(s):
        raise FieldError("skew", f"must be a finite number, got {skew!r}")
    return s


def disk_margin(loop: Loop | ct.StateSpace, skew: float = 0.0) -> DiskMargin:
    r"""SISO disk margin, exactly: :math:`\alpha = 1/\|S + \tfrac{\sigma-1}{2}\|_\infty`.

    Parameters
    ----------
    loop : Loop or control.StateSpace
        SISO loop (broken at one channel) or its transfer.
    skew : float
        σ: 0 balanced, 1 the S-based margin, −1 the T-based one.
    """
    sigma = _check_skew(skew)
    L, poles, dt = _siso(loop, "loop")
    if L.ninputs != 1 or L.noutputs != 1:
        raise FieldError("loop", "disk_margin is SISO: use disk_margins for a MIMO loop")
    require_stable_loop(poles, dt)
    A, B, C, D, _ = system_matrices(L)
    return _stable_disk_margin(A, B, C, D, dt, sigma)


def _stable_disk_margin(
    A: FloatArray, B: FloatArray, C: FloatArray, D: FloatArray, dt: float, sigma: float
) -> DiskMargin:
    """disk_margin of the SISO loop (A, B, C, D), its closed loop known to be stable."""
    import control as ct

    e = 1.0 / (1.0 + D[0, 0])
    M = ct.ss(A - e * B @ C, e * B, -e * C, np.array([[e + (sigma - 1.0) / 2.0]]), dt)
    norm = hinf_norm(M, field="loop")
    alpha = 1.0 / norm.value if norm.value > 0 else math.inf
    gains, phase = disk_variations(alpha, sigma)
    return DiskMargin(alpha, sigma, gains, phase, norm.peak_rad_s)


def _osborne(M: np.ndarray, sweeps: int = 20) -> FloatArray:
    """Diagonal scalings d balancing the off-diagonal row and column sums of |M| (Osborne's
    iteration, Osborne 1960), a near-optimal start for the μ upper bound; M is (..., n, n),
    every matrix of the batch balanced at once."""
    n = M.shape[-1]
    A = np.abs(M) * (1.0 - np.eye(n))
    d = np.ones(M.shape[:-1])
    for _ in range(sweeps):
        for i in range(n):
            # row_i = d_i Σ_j A_ij / d_j, col_i = Σ_j A_ji d_j / d_i; d_i ← d_i sqrt(col/row)
            row = np.einsum("...j,...j->...", A[..., i, :], 1.0 / d)
            col = np.einsum("...j,...j->...", A[..., :, i], d)
            ok = (row > 0) & (col > 0)
            d[..., i] = np.where(
                ok, np.sqrt(np.where(ok, col, 1.0) / np.where(ok, row, 1.0)), d[..., i]
            )
    return d / d[..., :1]


def _scaled_norm(M: np.ndarray, d: FloatArray) -> float:
    return float(np.linalg.norm((d[:, None] * M) / d[None, :], 2))


def _scaled_norms(M: np.ndarray, d: FloatArray) -> FloatArray:
    """σ̄(D M D⁻¹) of a batch (n_w, n, n) with scalings d (n_w, n) or (n,)."""
    return np.linalg.svd((d[..., :, None] * M) / d[..., None, :], compute_uv=False)[..., 0]


def _optimised_scaling(M: np.ndarray, d0: FloatArray) -> tuple[float, FloatArray]:
    """(σ̄(D M D⁻¹), d) minimised over log d from d0 (Nelder–Mead, d_0 fixed to 1)."""
    res = scipy.optimize.minimize(
        lambda logd: _scaled_norm(M, np.exp(np.concatenate([[0.0], logd]))),
        np.log(d0[1:] / d0[0]),
        method="Nelder-Mead",
        options={"xatol": 1e-10, "fatol": 1e-14, "maxiter": 4000},
    )
    return float(res.fun), np.exp(np.concatenate([[0.0], res.x]))


def mu_upper_bound(M: np.ndarray, optimise: bool = True) -> float:
    """An upper bound of μ of M for diagonal complex Δ: σ̄(D M D⁻¹) with D positive diagonal,
    from Osborne's balancing and, with ``optimise``, minimised over log D (Nelder–Mead, the
    first entry fixed by scale invariance). Any D gives a valid bound; the infimum is μ itself
    for up to three blocks (Doyle, "Analysis of feedback systems with structured
    uncertainties", IEE Proc. D 129(6), 1982, 242–250)."""
    n = M.shape[0]
    if n == 1:
        return float(abs(M[0, 0]))
    d0 = _osborne(M)
    best = min(_scaled_norm(M, d0), _scaled_norm(M, np.ones(n)))
    if not optimise:
        return best
    return min(best, _optimised_scaling(M, d0)[0])


def disk_margins(
    loop: Loop, skew: float = 0.0, n_per_decade: int = 60
) -> tuple[tuple[DiskMargin, ...], DiskMargin]:
    r"""Loop-at-a-time and multiloop disk margins of a MIMO loop (module docstring).

    Parameters
    ----------
    loop : Loop
        Broken at the plant input or output (every channel).
    skew : float
        σ of the disks.
    n_per_decade : int
        Density of the grid for the multiloop margin (then refined around its worst point).

    Returns
    -------
    (per-channel DiskMargin, ...), DiskMargin
        Each channel broken with the others closed (exact), and the multiloop margin (all
        channels perturbed independently at once; a guaranteed lower bound through the
        D-scaled upper bound of μ).
    """

    sigma = _check_skew(skew)
    L, poles, dt = _siso(loop, "loop")
    require_stable_loop(poles, dt)
    A, B, C, D, _ = system_matrices(L)
    m = D.shape[0]
    # every channel's loop, the others closed, closes into the same (stable) closed loop
    per_channel = tuple(
        _stable_disk_margin(*close_other_channels((A, B, C, D), i), dt, sigma) for i in range(m)
    )
    S = loop.sensitivity() if hasattr(loop, "sensitivity") else None
    if S is None:
        raise FieldError("loop", "give a Loop (build_loop) for the multiloop margin")
    shift = (sigma - 1.0) / 2.0 * np.eye(m)
    evaluate = ResponseEvaluator(*system_matrices(S)[:4], dt)

    # ω = 0 too: S of a stable closed loop is finite there, and the worst point may be at DC
    grid = np.concatenate([[0.0], pole_grid(evaluate.poles, dt, n_per_decade)])
    Ms = evaluate(grid) + shift
    if m == 1:
        rough = np.abs(Ms[:, 0, 0])
    else:
        rough = np.minimum(_scaled_norms(Ms, _osborne(Ms)), _scaled_norms(Ms, np.ones(m)))
    # the optimised bound is below the cheap one at every frequency: optimise in decreasing
    # order of the cheap bound and stop when it falls below the best optimised value, which
    # then is the grid's maximum of the optimised bound
    best_value, k = -math.inf, 0
    for j in np.argsort(rough)[::-1]:
        if rough[j] <= best_value:
            break
        value = mu_upper_bound(Ms[j])
        if value > best_value:
            best_value, k = value, int(j)
    peak, w_peak = best_value, float(grid[k])
    # refine the frequency with the scaling D of the grid's worst point held (σ̄(D M D⁻¹)
    # bounds μ at every ω), then optimise D again there: a bound at one more point
    d_k = _optimised_scaling(Ms[k], _osborne(Ms[k]))[1] if m > 1 else np.ones(1)
    lo, hi = grid[max(k - 1, 0)], grid[min(k + 1, len(grid) - 1)]
    best = scipy.optimize.minimize_scalar(
        lambda x: -_scaled_norm(evaluate(np.array([x]))[0] + shift, d_k),
        bounds=(lo, hi),
        method="bounded",
        options={"xatol": 1e-12 * hi},
    )
    refined = mu_upper_bound(evaluate(np.array([best.x]))[0] + shift)
    if refined > peak:
        peak, w_peak = refined, float(best.x)
    alpha = 1.0 / peak if peak > 0 else math.inf
    gains, phase = disk_variations(alpha, sigma)
    return per_channel, DiskMargin(alpha, sigma, gains, phase, w_peak)
