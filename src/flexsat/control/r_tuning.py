r"""Modal LQR with the control weight r tuned to damping targets (Kim & Junkins' design 2).

Source: Y. Kim and J. L. Junkins, "A Measure of Controllability for Actuator Placement", AIAA
Guidance, Navigation and Control Conference, 1990 (Att. 4 of Junkins, Pollock & Rahman 1990),
Eq. (33) and Table 3.

The reduced modal model (Att. 4 Eqs. 29–30) of ``n`` modes driven by ``m`` actuators,

.. math::

    \ddot\eta + \mathrm{diag}(2\zeta_i\omega_i)\,\dot\eta + \mathrm{diag}(\omega_i^2)\,\eta
    = \bar D u, \qquad z = (\eta, \dot\eta),

is regulated by the LQR of Eq. (33) with the modal energy as the state weight,

.. math::

    J = \int_0^\infty z^T Q z + u^T R u\,dt, \qquad
    Q = \mathrm{blockdiag}(\Omega, I),\ \Omega = \mathrm{diag}(\omega_1^2 \ldots \omega_n^2),
    \qquad R = r I

(:math:`z^T Q z` is twice the modal energy; the OCR prints "− uᵀRu"). The scalar ``r`` is
"tuned" until the targeted closed-loop modes meet :math:`\omega_i^c \zeta_i^c \ge T_i`
(the paper: modes 1–3 with T = 0.2, 0.2, 0.25 rad/s), with Att. 4's definitions after
Eq. (32): :math:`\omega_i^c = \mathrm{Im}\,\lambda_i`,
:math:`\zeta_i^c = -\mathrm{Re}\,\lambda_i / |\lambda_i|`, so
:math:`\omega_i^c\zeta_i^c = -\mathrm{Re}\,\lambda_i\,\mathrm{Im}\,\lambda_i / |\lambda_i|`
(a relative ζ²/2 below the decay rate −Re λ).

The paper does not say how r is tuned. :func:`tune_r` returns the *largest* r that meets every
target — the cheapest design, the one whose binding target holds with equality — found by a
logarithmic scan that brackets the first feasible r from above and a bisection on log r to
``rtol``. Closed-loop eigenvalues are assigned to the open-loop modes by a minimum-distance
matching (:func:`scipy.optimize.linear_sum_assignment`), so a mode keeps its number when the
feedback reorders the frequencies.

The Riccati equation is solved with the input scaled by 1/√r (B R⁻¹ Bᵀ = B̃ B̃ᵀ with
B̃ = B/√r and unit weight, K = K̃/√r), which keeps the solver's backward-error check
(:func:`flexsat.control.lqr.lqr`) meaningful down to very cheap control.

Reported with each design, as in Table 3: the gain norm (Frobenius, ``gain_norm``; the paper's
column "G_α" does not say which norm) and the condition number of the closed-loop eigenvector
matrix with unit-norm columns (``condition``). For the undamped open loop that number is known
in closed form: the eigenvectors of different modes are orthogonal and each mode's pair
(1, ±iω)/√(1 + ω²) has singular values √2/√(1 + ω²) and √2 ω/√(1 + ω²), so with every
ω_i > 1 rad/s the condition number is exactly ω_max in rad/s (it depends on the time unit).
Feedback that acts mostly on the low modes leaves it near ω_max.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from scipy.optimize import linear_sum_assignment

from flexsat.control.lqr import lqr
from flexsat.input_checks import FieldError, require_finite
from flexsat.units import FloatArray

__all__ = [
    "ATT4_TARGETS",
    "ModalLQR",
    "RTuning",
    "modal_lqr",
    "modal_state_space",
    "tune_r",
]

ComplexArray = npt.NDArray[np.complex128]

#: Att. 4 after Eq. (33): ω_i ζ_i ≥ T_i for modes 1–3, rad/s
ATT4_TARGETS = (0.2, 0.2, 0.25)


@dataclass(frozen=True)
class ModalLQR:
    """One modal LQR design (SI, seconds).

    Attributes
    ----------
    r : float
        Control weight, R = r I.
    gain : ndarray (m, 2n)
        u = −K z, z = (η, η̇).
    eigenvalues : ndarray (n,) complex
        Closed-loop eigenvalue assigned to each open-loop mode (upper half plane).
    omega, zeta : ndarray (n,)
        ω^c = Im λ and ζ^c = −Re λ / |λ| (Att. 4, after Eq. 32).
    gain_norm : float
        Frobenius norm of K.
    condition : float
        2-norm condition number of the closed-loop eigenvector matrix, unit-norm columns.
    residual : float
        Relative Riccati residual of the solve.
    """

    r: float
    gain: FloatArray
    eigenvalues: ComplexArray
    omega: FloatArray
    zeta: FloatArray
    gain_norm: float
    condition: float
    residual: float

    @property
    def zeta_omega(self) -> FloatArray:
        """ω^c ζ^c per mode, rad/s."""
        return self.omega * self.zeta


@dataclass(frozen=True)
class RTuning:
    """The outcome of :func:`tune_r`: the design at the largest feasible r, the targets and the
    search record (``history``: (r, worst margin min_i(ω_iζ_i − T_i)) for every r solved)."""

    design: ModalLQR
    modes: tuple[int, ...]
    targets: FloatArray
    history: tuple[tuple[float, float], ...]

    @property
    def r(self) -> float:
        return self.design.r

    @property
    def margins(self) -> FloatArray:
        """ω_iζ_i − T_i of the targeted modes (≥ 0; the binding one ≈ 0)."""
        return self.design.zeta_omega[list(self.modes)] - self.targets

    @property
    def binding(self) -> int:
        """The targeted mode (0-based) whose target holds with equality."""
        return self.modes[int(np.argmin(self.margins))]


def _modal_inputs(
    omega: npt.ArrayLike, zeta: npt.ArrayLike, d_bar: npt.ArrayLike
) -> tuple[FloatArray, FloatArray, FloatArray]:
    w = require_finite(omega, "omega", "rad/s").reshape(-1)
    if w.size == 0 or np.any(w <= 0):
        raise FieldError("omega", "must be one or more natural frequencies > 0 (rad/s)")
    z = np.broadcast_to(require_finite(zeta, "zeta"), w.shape).astype(float)
    if np.any(z < 0) or np.any(z >= 1):
        raise FieldError("zeta", "damping ratios must lie in [0, 1)")
    d = require_finite(d_bar, "d_bar")
    if d.ndim == 1:
        d = d[:, None]
    if d.ndim != 2 or d.shape[0] != w.size:
        raise FieldError(
            "d_bar", f"must be (n_modes, n_inputs) = ({w.size}, m), got shape {d.shape}"
        )
    return w, z, d


def modal_state_space(
    omega: npt.ArrayLike, zeta: npt.ArrayLike, d_bar: npt.ArrayLike
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """A, B of z = (η, η̇) (Att. 4 Eqs. 14–16) and Q = blockdiag(diag(ω²), I) (Eq. 33)."""
    w, z, d = _modal_inputs(omega, zeta, d_bar)
    n = w.size
    a = np.block([[np.zeros((n, n)), np.eye(n)], [-np.diag(w**2), -np.diag(2 * z * w)]])
    b = np.vstack([np.zeros_like(d), d])
    q = np.diag(np.concatenate([w**2, np.ones(n)]))
    return a, b, q


def _assign(open_loop: ComplexArray, closed: ComplexArray) -> ComplexArray:
    """Closed-loop eigenvalues (upper half plane) in the order of the open-loop modes."""
    upper = closed[closed.imag > 0]
    if upper.size != open_loop.size:
        raise FieldError(
            "d_bar",
            f"the closed loop has {upper.size} oscillatory modes for {open_loop.size} open-loop "
            "ones (an overdamped mode): ω^c ζ^c is undefined; lower the gain (raise r)",
        )
    rows, cols = linear_sum_assignment(np.abs(open_loop[:, None] - upper[None, :]))
    out: ComplexArray = upper[cols[np.argsort(rows)]]
    return out


def modal_lqr(
    omega: npt.ArrayLike, zeta: npt.ArrayLike, d_bar: npt.ArrayLike, r: float
) -> ModalLQR:
    """The LQR of Att. 4 Eq. (33) for the modal model (ω, ζ, D̄) and R = r I (module docstring).

    Parameters
    ----------
    omega, zeta : array_like (n,)
        Natural frequencies (rad/s, > 0; or a Quantity / unit string) and damping ratios (a
        scalar broadcasts).
    d_bar : array_like (n, m)
        Modal input matrix Φᵀ D.
    r : float
        Control weight, > 0.
    """
    if not (isinstance(r, (int, float, np.floating)) and np.isfinite(r) and r > 0):
        raise FieldError("r", f"must be a finite number > 0, got {r!r}")
    w, z, d = _modal_inputs(omega, zeta, d_bar)
    a, b, q = modal_state_space(w, z, d)
    m = d.shape[1]
    sol = lqr(a, b / np.sqrt(r), q, np.eye(m))
    k = np.asarray(sol[0]) / np.sqrt(r)
    vals, vecs = np.linalg.eig(a - b @ k)
    vecs = vecs / np.linalg.norm(vecs, axis=0)
    lam_open = -z * w + 1j * w * np.sqrt(1 - z**2)
    lam = _assign(lam_open, vals)
    return ModalLQR(
        r=float(r),
        gain=k,
        eigenvalues=lam,
        omega=lam.imag.copy(),
        zeta=-lam.real / np.abs(lam),
        gain_norm=float(np.linalg.norm(k)),
        condition=float(np.linalg.cond(vecs)),
        residual=float(sol.residual),
    )


def tune_r(
    omega: npt.ArrayLike,
    zeta: npt.ArrayLike,
    d_bar: npt.ArrayLike,
    targets: Sequence[float] | npt.ArrayLike = ATT4_TARGETS,
    modes: Sequence[int] | None = None,
    r_range: tuple[float, float] = (1e-8, 1e8),
    rtol: float = 1e-9,
) -> RTuning:
    """The largest r for which every targeted mode has ω_i^c ζ_i^c ≥ T_i (Att. 4, Eq. 33).

    Parameters
    ----------
    omega, zeta, d_bar
        The modal model, as :func:`modal_lqr`.
    targets : sequence of float
        T_i, rad/s or a Quantity (default Att. 4's 0.2, 0.2, 0.25).
    modes : sequence of int, optional
        0-based mode numbers the targets apply to (default the first ``len(targets)``).
    r_range : (float, float)
        Search interval for r, scanned from the top by factors of 10 (r is relative to the
        squared input units: the interval depends on them).
    rtol : float
        Relative width of the final bracket on r.

    Raises
    ------
    FieldError
        Bad inputs, or no r in ``r_range`` meets the targets (e.g. a targeted mode the
        actuators cannot move), naming the mode that falls short.
    """
    w, z, d = _modal_inputs(omega, zeta, d_bar)
    t = require_finite(targets, "targets", "rad/s").reshape(-1)
    if t.size == 0 or np.any(t <= 0):
        raise FieldError("targets", "must be one or more targets T_i > 0 (rad/s)")
    idx = tuple(range(t.size)) if modes is None else tuple(int(i) for i in modes)
    if len(idx) != t.size or len(set(idx)) != len(idx) or min(idx) < 0 or max(idx) >= w.size:
        raise FieldError(
            "modes", f"one distinct mode number in 0..{w.size - 1} per target, got {modes!r}"
        )
    lo_r, hi_r = (float(v) for v in r_range)
    if not (0 < lo_r < hi_r and np.isfinite(hi_r)):
        raise FieldError("r_range", f"must be (low, high) with 0 < low < high, got {r_range!r}")
    if not (0 < rtol < 1):
        raise FieldError("rtol", f"must lie in (0, 1), got {rtol!r}")
    history: list[tuple[float, float]] = []

    def margin(r: float) -> tuple[float, ModalLQR | None]:
        try:
            design = modal_lqr(w, z, d, r)
        except FieldError:
            history.append((r, -np.inf))  # an overdamped mode: treat as infeasible
            return -np.inf, None
        value = float(np.min(design.zeta_omega[list(idx)] - t))
        history.append((r, value))
        return value, design

    r = hi_r
    best: ModalLQR | None = None
    last: ModalLQR | None = None
    upper = hi_r
    while r >= lo_r:
        value, design = margin(r)
        if value >= 0:
            best = design
            break
        last = design or last
        upper = r
        r /= 10.0
    if best is None:
        if last is None:
            raise FieldError(
                "targets", f"no r in [{lo_r:.3g}, {hi_r:.3g}] gives an oscillatory closed loop"
            )
        short = idx[int(np.argmin(last.zeta_omega[list(idx)] - t))]
        raise FieldError(
            "targets",
            f"no r in [{lo_r:.3g}, {hi_r:.3g}] gives ω_i ζ_i ≥ T_i: mode {short + 1} reaches "
            f"only {last.zeta_omega[short]:.4g} rad/s (T = {t[idx.index(short)]:.4g}) at "
            f"r = {last.r:.3g}; can the actuators move it?",
        )
    lower = best.r
    if lower == hi_r:
        return RTuning(best, idx, t, tuple(history))  # the target is met by the cheapest design
    while upper / lower - 1 > rtol:
        mid = float(np.sqrt(lower * upper))
        value, design = margin(mid)
        if value >= 0 and design is not None:
            lower, best = mid, design
        else:
            upper = mid
    return RTuning(best, idx, t, tuple(history))
