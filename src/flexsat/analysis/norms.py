r"""H2 and H∞ norms of linear systems without slycot.

python-control computes both norms through slycot when it is installed; this module is the
scipy path used everywhere in flexsat, so the answer does not depend on an optional Fortran
package.

H2 (continuous, D = 0; Zhou, Doyle & Glover, *Robust and Optimal Control*, 1996, Lemma 4.4):

.. math::

    \|G\|_2^2 = \operatorname{tr}(C P C^T), \qquad A P + P A^T + B B^T = 0;

discrete (the same book, §4.3 for the discrete analogue): :math:`\|G\|_2^2 =
\operatorname{tr}(C P C^T + D D^T)` with :math:`A P A^T - P + B B^T = 0`. A continuous system
with D ≠ 0 has an infinite H2 norm (returned as ``math.inf``).

H∞: the two-step algorithm of Boyd, Balakrishnan & Kabamba (Math. Control Signals Systems 2,
1989, 207–219) and Bruinsma & Steinbuch ("A fast algorithm to compute the H∞-norm of a transfer
function matrix", Systems & Control Letters 14, 1990, 287–293). γ is a singular value of
G(jω) iff jω is an eigenvalue of the Hamiltonian

.. math::

    H(\gamma) = \begin{bmatrix} A + B R^{-1} D^T C & B R^{-1} B^T \\
    -C^T (I + D R^{-1} D^T) C & -(A + B R^{-1} D^T C)^T \end{bmatrix},
    \qquad R = \gamma^2 I - D^T D,

so with a lower bound γ_lb, the imaginary eigenvalues of H((1 + 2 tol) γ_lb) bracket the
frequency intervals where σ̄(G) exceeds it; σ̄ at their midpoints raises γ_lb, and when H has
no imaginary eigenvalue the norm lies in [γ_lb, (1 + 2 tol) γ_lb]. σ̄ is evaluated from
one eigen-decomposition of A (:class:`~flexsat.analysis.frequency_domain.ResponseEvaluator`),
at the starting points and, by Brent's method, between the neighbours of the best of them, so
that the first test usually certifies the bound. A discrete system is mapped to
a continuous one by the bilinear transform :math:`z = (1 + s)/(1 - s)`, which maps the unit
circle onto the imaginary axis and leaves the H∞ norm unchanged (Zhou, Doyle & Glover §21.1).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import scipy.linalg as sla
import scipy.optimize

from flexsat.input_checks import FieldError

if TYPE_CHECKING:
    import control as ct
    from flexsat.units import FloatArray

__all__ = ["HinfNorm", "h2_norm", "hinf_norm", "system_matrices"]


def system_matrices(
    system: ct.StateSpace, field: str = "system"
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, float]:
    """(A, B, C, D, dt) of a python-control StateSpace as float arrays (dt = 0: continuous).

    Raises
    ------
    FieldError
        Naming ``field`` when ``system`` is not a StateSpace or has an unspecified period.
    """
    import control as ct

    if isinstance(system, ct.TransferFunction):
        system = ct.ss(system)
    if not isinstance(system, ct.StateSpace):
        raise FieldError(field, f"must be a python-control StateSpace, got {type(system).__name__}")
    if system.dt is True:
        raise FieldError(field, "is discrete with an unspecified sampling time (dt=True)")
    dt = 0.0 if system.dt in (0, None) else float(system.dt)
    return (
        np.asarray(system.A, float).reshape(system.nstates, system.nstates),
        np.asarray(system.B, float).reshape(system.nstates, system.ninputs),
        np.asarray(system.C, float).reshape(system.noutputs, system.nstates),
        np.asarray(system.D, float).reshape(system.noutputs, system.ninputs),
        dt,
    )


def _require_stable(A: FloatArray, dt: float, field: str) -> None:
    if A.size == 0:
        return
    _require_stable_poles(np.linalg.eigvals(A), dt, field)


def _require_stable_poles(eig: np.ndarray, dt: float, field: str) -> None:
    if eig.size == 0:
        return
    radius = np.abs(eig) if dt else eig.real
    bound = 1.0 if dt else 0.0
    worst = int(np.argmax(radius))
    if radius[worst] >= bound:
        kind = "|z| >= 1" if dt else "Re s >= 0"
        raise FieldError(
            field,
            f"is not asymptotically stable (pole {complex(eig[worst]):.6g}, {kind}): its H2/H∞ "
            "norm is infinite or undefined",
        )


def h2_norm(system: ct.StateSpace, field: str = "system") -> float:
    r"""H2 norm by the Lyapunov equation (module docstring).

    Parameters
    ----------
    system : control.StateSpace
        Asymptotically stable, continuous or discrete.
    field : str
        Name used in error messages.

    Returns
    -------
    float
        ‖G‖₂; ``math.inf`` for a continuous system with a nonzero feedthrough D.
    """
    A, B, C, D, dt = system_matrices(system, field)
    _require_stable(A, dt, field)
    if dt == 0.0:
        if np.any(D != 0):
            return math.inf
        if A.size == 0:
            return 0.0
        P = sla.solve_continuous_lyapunov(A, -B @ B.T)
        value = np.trace(C @ P @ C.T)
    else:
        P = sla.solve_discrete_lyapunov(A, B @ B.T) if A.size else np.zeros((0, 0))
        value = np.trace(C @ P @ C.T + D @ D.T)
    # the trace of a Gram form is >= 0; round-off can leave it at -eps for a null system
    return float(math.sqrt(max(value, 0.0)))


@dataclass(frozen=True)
class HinfNorm:
    """The H∞ norm and where it is reached.

    Attributes
    ----------
    value : float
        ‖G‖∞ (the midpoint of the final bracket).
    peak_rad_s : float
        Frequency of the peak of σ̄(G), rad/s (0 for a static gain; for a discrete system the
        physical frequency, at most π/dt).
    lower, upper : float
        Bracket of the norm, upper/lower <= 1 + 2 tol.
    """

    value: float
    peak_rad_s: float
    lower: float
    upper: float

    def __float__(self) -> float:
        return self.value


def _bilinear(
    A: FloatArray, B: FloatArray, C: FloatArray, D: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Continuous (A, B, C, D) with G_c(s) = G_d((1 + s)/(1 − s)); needs −1 not a pole."""
    n = A.shape[0]
    M = np.linalg.inv(np.eye(n) + A)
    Ac = M @ (A - np.eye(n))
    Bc = math.sqrt(2.0) * M @ B
    Cc = math.sqrt(2.0) * C @ M
    Dc = D - C @ M @ B
    return Ac, Bc, Cc, Dc


def hinf_norm(system: ct.StateSpace, tol: float = 1e-8, field: str = "system") -> HinfNorm:
    r"""H∞ norm by the Boyd–Balakrishnan / Bruinsma–Steinbuch iteration (module docstring).

    Parameters
    ----------
    system : control.StateSpace
        Asymptotically stable, continuous or discrete.
    tol : float
        Relative width of the final bracket (upper = (1 + 2 tol) lower); > 0.
    field : str
        Name used in error messages.

    Returns
    -------
    HinfNorm
    """
    if not (isinstance(tol, float | int) and 0 < tol < 0.1):
        raise FieldError("tol", f"must be a number in (0, 0.1), got {tol!r}")
    from flexsat.analysis.frequency_domain import ResponseEvaluator

    A, B, C, D, dt = system_matrices(system, field)
    n = A.shape[0]
    if n == 0:
        g = float(np.linalg.norm(D, 2)) if D.size else 0.0
        return HinfNorm(g, 0.0, g, g)
    # one eigen-decomposition of A serves the stability test and every σ̄(G) evaluated below;
    # a discrete G at the bilinear frequency w is G(e^{jθ}) with θ = 2 atan w (rad/sample)
    evaluate = ResponseEvaluator(A, B, C, D, 1.0 if dt else 0.0)
    _require_stable_poles(evaluate.poles, dt, field)

    def sigma(w: np.ndarray) -> np.ndarray:
        G = evaluate(2.0 * np.arctan(w) if dt else w)
        return np.linalg.svd(G, compute_uv=False)[:, 0] if G.size else np.zeros(len(w))

    A0, B0, C0, D0 = A, B, C, D

    def exact(w: float) -> float:
        # a value kept as the lower bound is σ̄ of a backward-stable dense solve: the modal
        # evaluator's error grows with κ of its eigenvectors (up to 1e6), which near an
        # optimal H∞ design (a controller with entries ~1e6) reaches 1e-6 of σ̄ and would put
        # the "lower" bound above the norm
        x = complex(np.exp(2j * math.atan(w))) if dt else 1j * w
        G = D0 + C0 @ np.linalg.solve(x * np.eye(n) - A0, B0)
        return float(np.linalg.svd(G, compute_uv=False)[0]) if G.size else 0.0

    def to_physical(w: float) -> float:
        # s = jw on the imaginary axis is z = (1 + jw)/(1 − jw) = exp(2j atan w)
        return 2.0 * math.atan(w) / dt if dt else w

    poles = evaluate.poles
    if dt:
        # poles strictly inside the unit circle, so −1 is not one and the map is defined
        A, B, C, D = _bilinear(A, B, C, D)
        poles = (poles - 1.0) / (poles + 1.0)
    # starting guesses (Bruinsma & Steinbuch 1990 §3): ω = 0, ω = ∞ (the feedthrough D) and the
    # magnitude of every pole; a start above σ̄(D) also keeps R = γ²I − DᵀD well conditioned
    candidates = np.array([0.0] + sorted({float(x) for x in np.abs(poles) if x > 0}))
    values = sigma(candidates)
    k = int(np.argmax(values))
    lower, peak = exact(float(candidates[k])), float(candidates[k])
    if 0 < k < len(candidates) - 1:
        # the peak between the neighbouring guesses, to round-off: then the first Hamiltonian
        # test usually certifies it (any point of σ̄ is a valid lower bound)
        lo, hi = float(candidates[k - 1]), float(candidates[k + 1])
        best = scipy.optimize.minimize_scalar(
            lambda x: -float(sigma(np.array([x]))[0]),
            bounds=(lo, hi),
            method="bounded",
            options={"xatol": 1e-12 * hi},
        )
        refined = exact(float(best.x)) if -best.fun > lower else lower
        if refined > lower:
            lower, peak = refined, float(best.x)
    d_norm = float(np.linalg.norm(D, 2))
    if d_norm > lower:
        lower, peak = d_norm, math.inf
    if lower == 0.0:
        return HinfNorm(0.0, 0.0, 0.0, 0.0)
    m, p = B.shape[1], C.shape[0]
    for _ in range(200):
        gamma = (1.0 + 2.0 * tol) * lower
        R = gamma**2 * np.eye(m) - D.T @ D
        Rinv = np.linalg.inv(R)
        Ah = A + B @ Rinv @ D.T @ C
        H = np.block(
            [
                [Ah, B @ Rinv @ B.T],
                [-C.T @ (np.eye(p) + D @ Rinv @ D.T) @ C, -Ah.T],
            ]
        )
        eig = np.linalg.eigvals(H)
        scale = max(1.0, float(np.max(np.abs(eig))))
        imaginary = np.sort(eig.imag[(np.abs(eig.real) < 1e-8 * scale) & (eig.imag >= 0)])
        if imaginary.size == 0:
            upper = gamma
            break
        if imaginary.size == 1:  # a tangency: evaluate there
            mids = imaginary
        else:
            mids = 0.5 * (imaginary[:-1] + imaginary[1:])
        sig = sigma(np.asarray(mids, float))
        best = int(np.argmax(sig))
        top = exact(float(mids[best]))
        if top <= lower:
            # the Hamiltonian's eigenvalues are at the round-off level of the bracket: the
            # peak is lower to the precision the eigenvalue test can resolve
            upper = gamma
            break
        lower, peak = top, float(mids[best])
    else:  # pragma: no cover - the iteration converges quadratically (Boyd et al. 1989)
        raise FieldError(field, "the H∞ iteration did not converge in 200 steps")
    peak_phys = (math.pi / dt if dt else math.inf) if math.isinf(peak) else to_physical(peak)
    return HinfNorm(0.5 * (lower + upper), peak_phys, lower, upper)
