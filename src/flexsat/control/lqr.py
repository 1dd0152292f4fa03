r"""Linear-quadratic regulators with checked inputs and a reported Riccati residual.

Continuous time (Hailey, Sortun & Agrawal c. 1992 Eqs. 38–40; EPS slew study c. 1989
Eq. 28 with the cross weight N):

.. math::

    J = \int_0^\infty x^T Q x + 2 x^T N u + u^T R u \; dt, \qquad u = -K x,

    0 = A^T S + S A - (S B + N) R^{-1} (S B + N)^T + Q, \qquad K = R^{-1} (B^T S + N^T).

Discrete time, :math:`x_{k+1} = A x_k + B u_k`, :math:`J = \sum x^T Q x + 2 x^T N u + u^T R u`:

.. math::

    0 = A^T S A - S - (A^T S B + N)(R + B^T S B)^{-1}(B^T S A + N^T) + Q, \qquad
    K = (R + B^T S B)^{-1} (B^T S A + N^T).

The equations are solved by ``scipy.linalg.solve_continuous_are`` /
``solve_discrete_are`` (generalized Schur method on the extended pencil, with balancing) — the
same solver python-control uses when slycot is absent, so the gains agree with
``control.lqr`` / ``control.dlqr`` to roundoff.

Relative residual
-----------------
Every solve reports, and logs at DEBUG level (logger ``flexsat.control.lqr``), the relative
residual of its Riccati equation: the Frobenius norm of the right-hand side evaluated at the
computed S divided by the sum of the norms of its terms,

.. math::

    \rho_c = \frac{\| A^T S + S A - (SB+N)R^{-1}(SB+N)^T + Q \|_F}
                  {2\|A^T S\|_F + \|(SB+N)R^{-1}(SB+N)^T\|_F + \|Q\|_F},

    \rho_d = \frac{\| A^T S A - S - (A^T S B+N)(R+B^T S B)^{-1}(B^T S A+N^T) + Q \|_F}
                  {\|A^T S A\|_F + \|S\|_F + \|(A^T S B+N)(R+B^T S B)^{-1}(B^T S A+N^T)\|_F
                   + \|Q\|_F}.

This is the backward-error measure of the Riccati literature: roundoff in forming the terms
alone gives ~1e-16 · n, independent of how large S is. The residual relative to ‖Q‖ alone
(``residual_q``, also reported) carries the roundoff of the large terms ‖AᵀS‖ ~ ‖A‖‖S‖ and so
grows with them: for the lightly damped modal models of ``benchmarks/bench_lqr.py`` (rigid mode
plus modes 0.1–100 rad/s, ζ = 0.005) it is 1e-9 (50 states) to 4e-8 (400 states) while ρ_c is
3e-13 to 4e-12.

A ρ above the accepted residual is an error (``ValueError`` naming the residual). A
backward-stable Schur solve computes an orthonormal basis [U11; U21] of the stable invariant
subspace to O(n ε) and returns S = U21 U11⁻¹, so the error of S, and with it ρ, is bounded by
n ε (κ(U11) + 3) (Laub 1979; Petkov, Christov & Konstantinov, *Numerical Methods for Linear
Control Systems*, 1991): κ(U11) follows from S itself, the basis being [I; S](I + S²)^-1/2, as
√(1 + s_max²)/√(1 + s_min²) over the singular values of S (:func:`riccati_error_bound`). The
accepted residual is ten times that bound (the bound is a first-order estimate), at least
``RESIDUAL_TOL`` = √ε ≈ 1.5e-8 and at most ``RESIDUAL_MAX`` = 1e-6: a solution that satisfies
its own equation to fewer than six digits is refused however ill-conditioned the problem (e.g.
``lqr(1e150·A, ...)`` with a stable A: S ~ 1/‖A‖ underflows to 0 and ρ = 1; badly scaled data,
‖A‖ = 1e10 against unit B, Q, R, give ρ ~ 0.4). Measured: 4e-12 at 400 states (45 n ε).

Checks
------
Before solving: A square, B with n rows, Q (n, n) symmetric positive semi-definite, R (m, m)
symmetric positive definite, N (n, m) with :math:`Q - N R^{-1} N^T \succeq 0` (the joint
weight positive semi-definite), (A, B) stabilizable and
:math:`(Q - N R^{-1} N^T,\; A - B R^{-1} N^T)` detectable, both by the PBH rank test on the
marginal or unstable eigenvalues. After solving: S finite and the closed loop stable. Every
failure is a ``ValueError`` naming the field and the rule.

The PBH test is scale-aware, so that a lightly damped modal model with modes from 0.1 to
1,000 rad/s (‖A‖ ~ ω²_max = 1e6, eigenvalues 0.01 apart at the low end) is not refused: a single
threshold √ε‖A‖ on σ_min[A − λI, B] = 0.015 exceeds the distance between its low eigenvalues,
so every low mode looked uncontrollable. Instead, A is balanced (diagonal similarity) and each
eigenvalue is tested on its own scale:

- marginal means :math:`\mathrm{Re}\,\lambda \ge -\sqrt{\epsilon}|\lambda|` (damping ratio
  below √ε) or :math:`|\lambda| \le r = \sqrt{\epsilon}\max(1, \|A\|_1)` (numerically zero,
  where a defective rigid mode's computed pair ±(ε‖A‖)^½ lies); discrete
  :math:`|\lambda| \ge 1 - \sqrt{\epsilon}`;
- λ and the eigenvalues within r of it are one cluster; with W an orthonormal basis of its left
  invariant subspace (reordered complex Schur form) and M = WᴴAW, λ is uncontrollable when
  :math:`\sigma_k[(M - \lambda I)/s_\lambda,\; W^H B/\|B\|_2] \le \sqrt{\epsilon}`,
  :math:`s_\lambda = \max(\|M\|_2, \epsilon^{1/4}\|A\|_1)`: the relative distance of λ's
  own block from uncontrollability, a perturbation of relative size √ε of that block.
  The left invariant subspace of one cluster is accurate to ~ε‖A‖/gap (balanced ‖A‖), far below
  √ε for the models here, so an uncontrollable mode still measures ~ε.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
import scipy.linalg

from flexsat.analysis.controllability import pbh_clusters
from flexsat.input_checks import FieldError, require_numeric

if TYPE_CHECKING:
    import numpy.typing as npt

    from flexsat.units import FloatArray

log = logging.getLogger(__name__)

__all__ = [
    "RiccatiSolution",
    "care_residual",
    "dare_residual",
    "dlqr",
    "lqr",
    "riccati_error_bound",
    "uncontrollable_modes",
]

#: relative tolerance of the symmetry and semi-definiteness checks of the weights
WEIGHT_TOL = 1e-10
_SQRT_EPS = np.sqrt(np.finfo(float).eps)
#: relative Riccati residual above which a solve is refused (module docstring)
RESIDUAL_TOL = _SQRT_EPS
#: largest relative residual ever accepted, whatever the conditioning (module docstring)
RESIDUAL_MAX = 1e-6


class RiccatiSolution(tuple[np.ndarray, np.ndarray, np.ndarray]):
    """Result of a Riccati design: unpacks as ``(gain, solution, poles)`` like python-control's
    ``lqr`` → (K, S, E) and ``lqe`` → (L, P, E).

    Attributes
    ----------
    gain : ndarray
        K (m, n) for a regulator, L (n, p) for a filter.
    solution : ndarray (n, n)
        Stabilizing solution S (regulator) or error covariance P (filter).
    poles : ndarray (n,)
        Closed-loop eigenvalues, eig(A − BK) or eig(A − LC).
    residual : float
        Relative Riccati residual (module docstring, ρ_c or ρ_d).
    residual_q : float
        Residual norm relative to ‖Q‖_F (the weight or the process-noise intensity) alone.
    absolute_residual : float
        Frobenius norm of the residual matrix.
    kind : str
        What was designed ("lqr", "dlqr", "kalman", ...; empty when not said).
    """

    gain: FloatArray
    solution: FloatArray
    poles: npt.NDArray[np.complex128]
    residual: float
    residual_q: float
    absolute_residual: float
    kind: str

    def __new__(
        cls,
        gain: FloatArray,
        solution: FloatArray,
        poles: npt.NDArray[np.complex128],
        residual: float,
        residual_q: float,
        absolute_residual: float,
        kind: str = "",
    ) -> RiccatiSolution:
        obj = super().__new__(cls, (gain, solution, poles))
        obj.gain, obj.solution, obj.poles = gain, solution, poles
        obj.residual = float(residual)
        obj.residual_q = float(residual_q)
        obj.absolute_residual = float(absolute_residual)
        obj.kind = kind
        return obj

    def __getnewargs__(
        self,
    ) -> tuple[FloatArray, FloatArray, npt.NDArray[np.complex128], float, float, float, str]:
        return (
            self.gain,
            self.solution,
            self.poles,
            self.residual,
            self.residual_q,
            self.absolute_residual,
            self.kind,
        )

    def __repr__(self) -> str:
        return (
            f"RiccatiSolution({self.kind or 'riccati'}: gain {self.gain.shape}, "
            f"residual {self.residual:.2e}, max Re pole {np.max(np.real(self.poles)):.4g})"
        )


# ------------------------------------------------------------------------------------------------
# input checks (shared with flexsat.control.estimation)
def _finite(value: npt.ArrayLike, field: str) -> FloatArray:
    return require_numeric(value, field, "matrix")


def check_square(value: npt.ArrayLike, field: str) -> FloatArray:
    """A finite non-empty square matrix (a scalar is 1 × 1)."""
    arr = _finite(value, field)
    if arr.ndim == 0:
        arr = arr.reshape(1, 1)
    if arr.ndim != 2 or arr.shape[0] != arr.shape[1] or arr.shape[0] == 0:
        raise FieldError(field, f"must be a non-empty square matrix, got shape {arr.shape}")
    return arr


def check_matrix(
    value: npt.ArrayLike, field: str, rows: int | None, cols: int | None, rule: str
) -> FloatArray:
    """A finite 2-D matrix of the given rows/cols (None: any); 1-D means one column when rows
    is fixed, one row when cols is fixed."""
    arr = _finite(value, field)
    if arr.ndim == 0:
        arr = arr.reshape(1, 1)
    elif arr.ndim == 1:
        arr = arr[:, None] if rows is not None and arr.size == rows else arr[None, :]
    if (
        arr.ndim != 2
        or (rows is not None and arr.shape[0] != rows)
        or (cols is not None and arr.shape[1] != cols)
        or arr.size == 0
    ):
        raise FieldError(field, f"must have shape {rule}, got {np.shape(value)}")
    return arr


def check_symmetric(arr: FloatArray, field: str) -> FloatArray:
    scale = max(np.abs(arr).max(initial=0.0), np.finfo(float).tiny)
    asym = np.abs(arr - arr.T).max(initial=0.0)
    if asym > WEIGHT_TOL * scale:
        raise FieldError(field, f"must be symmetric (max |{field} − {field}ᵀ| = {asym:.3g})")
    return 0.5 * (arr + arr.T)


def check_psd(arr: FloatArray, field: str, strict: bool = False) -> FloatArray:
    """Symmetric positive semi-definite (definite when ``strict``)."""
    arr = check_symmetric(arr, field)
    lam = np.linalg.eigvalsh(arr)
    scale = max(np.abs(lam).max(initial=0.0), np.finfo(float).tiny)
    if strict and lam.min() <= arr.shape[0] * np.finfo(float).eps * scale:
        raise FieldError(
            field, f"must be symmetric positive definite (smallest eigenvalue {lam.min():.3g})"
        )
    if lam.min() < -WEIGHT_TOL * scale:
        raise FieldError(
            field, f"must be positive semi-definite (smallest eigenvalue {lam.min():.3g})"
        )
    return arr


def _pbh_fails(A: FloatArray, B: FloatArray, discrete: bool) -> list[complex]:
    """Unstable or marginal eigenvalues λ of A at which [A − λI, B] loses rank (PBH), each
    cluster tested on its own scale (:func:`flexsat.analysis.controllability.pbh_clusters`), one
    of each conjugate pair."""

    def marginal(lam: npt.NDArray[np.complex128], radius: float) -> npt.NDArray[np.bool_]:
        if discrete:
            unstable = np.abs(lam) >= 1.0 - _SQRT_EPS
        else:
            unstable = (lam.real >= -_SQRT_EPS * np.abs(lam)) | (np.abs(lam) <= radius)
        return unstable & (lam.imag >= -radius)

    return pbh_clusters(A, B, marginal)


def uncontrollable_modes(
    A: npt.ArrayLike, B: npt.ArrayLike, discrete: bool = False
) -> list[complex]:
    """Unstable or marginal eigenvalues of A that are not controllable from B (PBH test).

    Empty when (A, B) is stabilizable. For detectability of (C, A) call it with (Aᵀ, Cᵀ).
    """
    a = check_square(A, "A")
    b = check_matrix(B, "B", a.shape[0], None, f"(n, m) with n = {a.shape[0]}")
    return _pbh_fails(a, b, discrete)


def _fmt(modes: Sequence[complex]) -> str:
    return ", ".join(f"{m.real:.4g}{m.imag:+.4g}j" for m in modes[:6]) + (
        " ..." if len(modes) > 6 else ""
    )


# ------------------------------------------------------------------------------------------------
def care_residual(
    A: FloatArray,
    B: FloatArray,
    Q: FloatArray,
    R: FloatArray,
    S: FloatArray,
    N: FloatArray | None = None,
) -> tuple[float, float, float]:
    """(relative ρ_c, relative to ‖Q‖_F, absolute) residual of the continuous Riccati equation
    at S (module docstring)."""
    SBN = S @ B + (0.0 if N is None else N)
    quad = SBN @ np.linalg.solve(R, SBN.T)
    AtS = A.T @ S
    res = AtS + AtS.T - quad + Q
    absolute = np.linalg.norm(res)
    denom = 2 * np.linalg.norm(AtS) + np.linalg.norm(quad) + np.linalg.norm(Q)
    return (
        float(absolute / denom if denom > 0 else absolute),
        float(absolute / np.linalg.norm(Q) if np.linalg.norm(Q) > 0 else np.inf),
        float(absolute),
    )


def dare_residual(
    A: FloatArray,
    B: FloatArray,
    Q: FloatArray,
    R: FloatArray,
    S: FloatArray,
    N: FloatArray | None = None,
) -> tuple[float, float, float]:
    """(relative ρ_d, relative to ‖Q‖_F, absolute) residual of the discrete Riccati equation."""
    AtSB = A.T @ S @ B + (0.0 if N is None else N)
    quad = AtSB @ np.linalg.solve(R + B.T @ S @ B, AtSB.T)
    AtSA = A.T @ S @ A
    res = AtSA - S - quad + Q
    absolute = np.linalg.norm(res)
    denom = np.linalg.norm(AtSA) + np.linalg.norm(S) + np.linalg.norm(quad) + np.linalg.norm(Q)
    return (
        float(absolute / denom if denom > 0 else absolute),
        float(absolute / np.linalg.norm(Q) if np.linalg.norm(Q) > 0 else np.inf),
        float(absolute),
    )


_LQR_LABELS = {
    "A": "A",
    "B": "B",
    "Q": "Q",
    "R": "R",
    "N": "N",
    "stabilizable": "(A, B) is not stabilizable: eigenvalue(s) {} of A are not controllable from B",
    "detectable": "(Q − N R⁻¹ Nᵀ, A − B R⁻¹ Nᵀ) is not detectable: eigenvalue(s) {} are not "
    "seen by the state weight (weight those states in Q)",
    "joint_field": "N",
    "joint": "the joint weight [[Q, N], [Nᵀ, R]] must be positive semi-definite, but "
    "Q − N R⁻¹ Nᵀ has smallest eigenvalue {:.3g}",
}


def solve_riccati(
    A: npt.ArrayLike,
    B: npt.ArrayLike,
    Q: npt.ArrayLike,
    R: npt.ArrayLike,
    N: npt.ArrayLike | None,
    discrete: bool,
    labels: dict[str, str],
    kind: str,
    checked: bool = False,
) -> RiccatiSolution:
    """Validate, solve, verify and log one Riccati design (labels name the fields); with
    ``checked`` the matrices are trusted to be checked already (only made float arrays)."""
    if checked:
        return _solve_checked(
            np.asarray(A, float),
            np.asarray(B, float),
            np.asarray(Q, float),
            np.asarray(R, float),
            None if N is None else np.asarray(N, float),
            discrete,
            labels,
            kind,
        )
    a = check_square(A, labels["A"])
    n = a.shape[0]
    b = check_matrix(B, labels["B"], n, None, f"(n, m) with n = {n} (the states of A)")
    m = b.shape[1]
    q = check_psd(check_matrix(Q, labels["Q"], n, n, f"(n, n) = ({n}, {n})"), labels["Q"])
    r = check_psd(
        check_matrix(R, labels["R"], m, m, f"(m, m) = ({m}, {m})"), labels["R"], strict=True
    )
    cross = None if N is None else check_matrix(N, labels["N"], n, m, f"(n, m) = ({n}, {m})")
    return _solve_checked(a, b, q, r, cross, discrete, labels, kind)


def _solve_checked(
    A: FloatArray,
    B: FloatArray,
    Q: FloatArray,
    R: FloatArray,
    N: FloatArray | None,
    discrete: bool,
    labels: dict[str, str],
    kind: str,
) -> RiccatiSolution:
    """Solve, verify and log a Riccati design on checked matrices (:func:`solve_riccati`)."""
    n, m = B.shape
    if N is not None and np.any(N):
        RiN = np.linalg.solve(R, N.T)
        Qt = 0.5 * ((Q - N @ RiN) + (Q - N @ RiN).T)
        lam = np.linalg.eigvalsh(Qt)
        scale = max(
            np.abs(np.linalg.eigvalsh(Q)).max(),
            np.abs(np.linalg.eigvalsh(N @ RiN)).max(),
            np.finfo(float).tiny,
        )
        if lam.min() < -WEIGHT_TOL * scale:
            raise FieldError(labels["joint_field"], labels["joint"].format(lam.min()))
        At = A - B @ RiN
    else:
        N, Qt, At = None, Q, A
    bad = _pbh_fails(A, B, discrete)
    if bad:
        raise ValueError(labels["stabilizable"].format(_fmt(bad)))
    lam_q = np.linalg.eigvalsh(Qt)
    definite = lam_q.min() > _SQRT_EPS * max(lam_q.max(), np.finfo(float).tiny)
    bad = [] if definite else _pbh_fails(At.T, Qt, discrete)
    if bad:
        raise ValueError(labels["detectable"].format(_fmt(bad)))

    solver = scipy.linalg.solve_discrete_are if discrete else scipy.linalg.solve_continuous_are
    try:
        # overflow in the solver's balancing of extreme data is caught below (S finite, residual)
        with np.errstate(over="ignore", invalid="ignore"):
            S = solver(A, B, Q, R, s=N, balanced=True)
    except (np.linalg.LinAlgError, ValueError) as exc:
        raise FieldError(
            labels["A"],
            f"no stabilizing Riccati solution ({exc}); the pair is "
            "numerically close to unstabilizable or undetectable",
        ) from None
    if not np.all(np.isfinite(S)):
        raise FieldError(labels["A"], "the Riccati solution is not finite")
    S = 0.5 * (S + S.T)
    NT = 0.0 if N is None else N.T
    if discrete:
        K = np.linalg.solve(R + B.T @ S @ B, B.T @ S @ A + NT)
        rel, rel_q, absolute = dare_residual(A, B, Q, R, S, N)
    else:
        K = np.linalg.solve(R, B.T @ S + NT)
        rel, rel_q, absolute = care_residual(A, B, Q, R, S, N)
    E = scipy.linalg.eigvals(A - B @ K)
    margin = np.max(np.abs(E)) - 1.0 if discrete else np.max(E.real)
    if margin >= 0:
        raise FieldError(
            labels["A"],
            "the Riccati solution does not stabilize the closed loop "
            f"(max {'|λ|' if discrete else 'Re λ'} = "
            f"{np.max(np.abs(E)) if discrete else np.max(E.real):.3g})",
        )
    log.debug(
        "%s: n=%d m=%d relative Riccati residual %.3e (rel. to ||Q|| %.3e)", kind, n, m, rel, rel_q
    )
    accepted = min(max(RESIDUAL_TOL, 10 * riccati_error_bound(S)), RESIDUAL_MAX)
    if not rel <= accepted:
        norms = ", ".join(
            f"‖{labels[k]}‖ = {np.linalg.norm(v):.3g}"
            for k, v in (("A", A), ("B", B), ("Q", Q), ("R", R))
        )
        raise FieldError(
            labels["A"],
            f"the Riccati solution is inaccurate: its relative residual {rel:.3g} "
            f"exceeds the accepted {accepted:.2g} (ten times the Schur method's error bound, "
            f"within [√ε, {RESIDUAL_MAX:g}]): the data are too badly scaled for the solver "
            f"({norms}); rescale the states, inputs or time unit",
        )
    return RiccatiSolution(K, S, E, rel, rel_q, absolute, kind)


def riccati_error_bound(S: npt.ArrayLike) -> float:
    """Relative error bound of a Riccati solution S computed by the Schur method, and of its
    relative residual: n ε (κ(U11) + 3), κ(U11) = √(1 + s_max²)/√(1 + s_min²) over the singular
    values of S (module docstring).

    Parameters
    ----------
    S : array_like (n, n)
        The computed solution.
    """
    s = np.linalg.svd(np.asarray(S, dtype=float), compute_uv=False)
    return len(s) * np.finfo(float).eps * (np.hypot(1.0, s[0]) / np.hypot(1.0, s[-1]) + 3.0)


def lqr(
    A: npt.ArrayLike,
    B: npt.ArrayLike,
    Q: npt.ArrayLike,
    R: npt.ArrayLike,
    N: npt.ArrayLike | None = None,
) -> RiccatiSolution:
    r"""Continuous-time LQR (Hailey, Sortun & Agrawal c. 1992 Eqs. 38–40; with N,
    EPS slew study c. 1989 Eq. 28).

    Parameters
    ----------
    A : array_like (n, n)
    B : array_like (n, m)
    Q : array_like (n, n)
        State weight, symmetric positive semi-definite.
    R : array_like (m, m) or scalar
        Input weight, symmetric positive definite.
    N : array_like (n, m), optional
        Cross weight (cost term 2 xᵀ N u); :math:`Q - N R^{-1} N^T \succeq 0`.

    Returns
    -------
    RiccatiSolution
        Unpacks as ``K, S, E`` like ``control.lqr``: gain K (m, n) with u = −Kx, Riccati
        solution S, closed-loop eigenvalues E = eig(A − BK); also ``.residual`` (relative
        Riccati residual ρ_c, module docstring) and ``.residual_q``.

    Raises
    ------
    ValueError
        Bad shapes, non-finite entries, Q not symmetric PSD, R not symmetric PD, joint weight
        indefinite, (A, B) not stabilizable, the weighted pair not detectable, no
        stabilizing solution, or a relative residual above the accepted one (module docstring).
    """
    return solve_riccati(A, B, Q, R, N, False, _LQR_LABELS, "lqr")


def dlqr(
    A: npt.ArrayLike,
    B: npt.ArrayLike,
    Q: npt.ArrayLike,
    R: npt.ArrayLike,
    N: npt.ArrayLike | None = None,
) -> RiccatiSolution:
    r"""Discrete-time LQR for :math:`x_{k+1} = A x_k + B u_k`, :math:`u_k = -K x_k`.

    Arguments, checks and result as :func:`lqr` (residual ρ_d; poles eig(A − BK) inside the
    unit circle). Gains equal ``control.dlqr``'s.
    """
    return solve_riccati(A, B, Q, R, N, True, _LQR_LABELS, "dlqr")
