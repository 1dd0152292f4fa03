r"""Controllability and observability Gramians of lightly damped modal systems.

Sources: Y. Kim and J. L. Junkins, "A Measure of Controllability for Actuator Placement", AIAA
Guidance, Navigation and Control Conference, 1990 (Att. 4 of Junkins, Pollock & Rahman 1990),
Eqs. (7), (14)–(16), (24)–(25) (the printed signs of Eq. (25) are wrong: every "−"
is a "+"). Gawronski's approximate modal Gramians: W. Gawronski, *Advanced Structural
Dynamics and Active Control of Structures* (Springer 2004), Ch. 4–5 (Property 5.1).

State convention
----------------
Every modal function here uses the state :math:`z = (\eta, \dot\eta)` of Att. 4 Eq. (14), i.e.
the order of :meth:`flexsat.structures.modal_model.ModalModel.to_statespace`:

.. math::

    A = \begin{bmatrix} 0 & I \\ -\Omega^2 & -2 Z \Omega \end{bmatrix}, \quad
    B = \begin{bmatrix} 0 \\ \bar D \end{bmatrix}, \quad
    C = [C_q \;\; C_v],

with :math:`\Omega = \mathrm{diag}(\omega_i)` (rad/s), :math:`Z = \mathrm{diag}(\zeta_i)`,
:math:`\bar D = \Phi^T D` the modal input matrix (one row per mode) and :math:`C_q, C_v` the
output rows on :math:`\eta` and :math:`\dot\eta`.

Gramians computed here
----------------------
* :func:`modal_controllability_gramian`: the closed form of Att. 4 Eq. (25) (signs corrected),
  for inputs that enter the rate equations only (forces, torques).
* :func:`modal_gramian`: the exact Gramian of a modal system for *any* input or output matrix,
  by an explicit solution of the 4 × 4 linear system of each mode pair (i, j); O(n²) work.
  Used for observability Gramians (outputs on both η and η̇) and inputs with a displacement part.
* :func:`gawronski_gramians`: Gawronski's diagonal approximation for well-separated, lightly
  damped modes, :math:`W_{c,i} \approx \|\bar d_i\|^2 / (4\zeta_i\omega_i)\, I_2` in the
  coordinates :math:`(\omega_i\eta_i, \dot\eta_i)`.
* :func:`lyapunov_gramian`: any stable (A, B) or (A, C) by
  :func:`scipy.linalg.solve_continuous_lyapunov` (Bartels–Stewart), the reference of the tests.
* :func:`finite_horizon_gramian`: :math:`\int_0^T e^{At} B B^T e^{A^T t} dt` by the Van Loan block
  exponential, for systems with rigid-body modes (whose infinite-horizon Gramian does not exist,
  and which python-control's ``gram`` refuses).

Tolerances (tests/analysis/test_gramians.py): closed forms against ``solve_continuous_lyapunov``
to a relative Frobenius error below 1e-10 (observed ~1e-14 … 1e-12); the finite-horizon Gramian
against adaptive quadrature to 1e-9 relative, and against the Lyapunov solution
:math:`X - e^{AT} X e^{A^T T}` to 1e-10.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import scipy.linalg as sla

from flexsat.input_checks import FieldError, require_finite, require_nonneg, require_positive
from flexsat.units import FloatArray

__all__ = [
    "GawronskiGramians",
    "finite_horizon_gramian",
    "gawronski_gramians",
    "gramian_residual",
    "lyapunov_gramian",
    "modal_controllability_gramian",
    "modal_gramian",
    "modal_observability_gramian",
    "modal_state_matrices",
]

KINDS = ("controllability", "observability")
#: ζω at or below which a mode counts as undamped (rigid or conservative): no infinite-horizon
#: Gramian exists. Relative to ω_max: modes of a structure with ζω ~ 1e-12 ω_max are treated as
#: rigid because their Gramian would be 1e12 × larger than the rest and meaningless.
_UNDAMPED_TOL = 1e-12


# ------------------------------------------------------------------------------------------------
# input checks
def modal_parameters(omega: npt.ArrayLike, zeta: npt.ArrayLike) -> tuple[FloatArray, FloatArray]:
    w = require_nonneg(omega, "omega")
    if w.ndim != 1 or w.size == 0:
        raise FieldError("omega", f"must be a non-empty 1-D array of rad/s, got shape {w.shape}")
    z = require_nonneg(zeta, "zeta")
    if z.ndim == 0:
        z = np.full(w.size, float(z))
    if z.shape != w.shape:
        raise FieldError("zeta", f"must be a scalar or have shape {w.shape}, got {z.shape}")
    return w, z


def _matrix(
    value: npt.ArrayLike, field: str, rows: int | None = None, cols: int | None = None
) -> FloatArray:
    arr = require_finite(value, field)
    if arr.ndim == 1:
        arr = arr[:, None] if rows is not None and arr.size == rows else arr[None, :]
    if arr.ndim != 2:
        raise FieldError(field, f"must be a 2-D array, got shape {arr.shape}")
    if rows is not None and arr.shape[0] != rows:
        raise FieldError(field, f"must have {rows} rows, got shape {arr.shape}")
    if cols is not None and arr.shape[1] != cols:
        raise FieldError(field, f"must have {cols} columns, got shape {arr.shape}")
    return arr


def modal_inputs(B: npt.ArrayLike, n: int, field: str = "B") -> FloatArray:
    """Modal input matrix (n, m); a 1-D array of length n is one input."""
    arr = require_finite(B, field)
    if arr.ndim == 1:
        arr = arr[:, None]
    if arr.ndim != 2 or arr.shape[0] != n:
        raise FieldError(field, f"must have shape (n_modes, m) = ({n}, m), got {np.shape(B)}")
    return arr


def modal_outputs(
    Cq: npt.ArrayLike | None, Cv: npt.ArrayLike | None, n: int
) -> tuple[FloatArray, FloatArray]:
    """Output rows (p, n) on η and η̇; a missing one reads zero, both missing is an error."""
    if Cq is None and Cv is None:
        raise ValueError("Cq, Cv: give at least one output matrix (rows on η or on η̇)")
    mats: list[FloatArray | None] = []
    for value, field in ((Cq, "Cq"), (Cv, "Cv")):
        if value is None:
            mats.append(None)
            continue
        arr = require_finite(value, field)
        arr = arr[None, :] if arr.ndim == 1 else arr
        if arr.ndim != 2 or arr.shape[1] != n:
            raise FieldError(
                field, f"must have shape (p, n_modes) = (p, {n}), got {np.shape(value)}"
            )
        mats.append(arr)
    p = next(a.shape[0] for a in mats if a is not None)
    rows = [np.zeros((p, n)) if a is None else a for a in mats]
    if rows[0].shape[0] != rows[1].shape[0]:
        raise ValueError(
            f"Cq, Cv: must have the same number of rows, got {rows[0].shape[0]} and "
            f"{rows[1].shape[0]}"
        )
    return rows[0], rows[1]


def require_damped(w: FloatArray, z: FloatArray, caller: str) -> None:
    decay = z * w
    scale = max(float(w.max()), 1.0)
    bad = np.flatnonzero(decay <= _UNDAMPED_TOL * scale)
    if bad.size:
        raise ValueError(
            f"{caller}: modes {bad.tolist()} have ζω = 0 (rigid-body or undamped modes): the "
            "infinite-horizon Gramian does not exist. Drop them (ModalModel.elastic()) or use "
            "finite_horizon_gramian over a stated horizon T"
        )


def _kind(kind: str) -> str:
    if kind not in KINDS:
        raise FieldError("kind", f"must be one of {KINDS}, got {kind!r}")
    return kind


# ------------------------------------------------------------------------------------------------
def modal_state_matrices(
    omega: npt.ArrayLike,
    zeta: npt.ArrayLike,
    B: npt.ArrayLike | None = None,
    Cq: npt.ArrayLike | None = None,
    Cv: npt.ArrayLike | None = None,
) -> tuple[FloatArray, FloatArray | None, FloatArray | None]:
    r"""First-order modal matrices in the state :math:`z = (\eta, \dot\eta)` (Att. 4 Eq. 16).

    Parameters
    ----------
    omega, zeta : array_like (n,)
        Natural frequencies (rad/s) and damping ratios (scalar ζ: the same for every mode).
    B : array_like (n, m), optional
        Modal input matrix :math:`\bar D = \Phi^T D`.
    Cq, Cv : array_like (p, n), optional
        Output rows on η and η̇.

    Returns
    -------
    A : ndarray (2n, 2n)
    Bz : ndarray (2n, m) = [0; B] (None when ``B`` is None)
    Cz : ndarray (p, 2n) = [Cq, Cv] (None when both are None)
    """
    w, z = modal_parameters(omega, zeta)
    n = w.size
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-np.diag(w**2), -np.diag(2 * z * w)]])
    Bz = None
    if B is not None:
        Bm = modal_inputs(B, n)
        Bz = np.vstack([np.zeros_like(Bm), Bm])
    Cz = None
    if Cq is not None or Cv is not None:
        Cq, Cv = modal_outputs(Cq, Cv, n)
        Cz = np.hstack([Cq, Cv])
    return A, Bz, Cz


def modal_controllability_gramian(
    omega: npt.ArrayLike, zeta: npt.ArrayLike, B: npt.ArrayLike
) -> FloatArray:
    r"""Closed-form controllability Gramian of a modal system, Att. 4 Eqs. (24)–(25).

    Solves :math:`A X + X A^T + B B^T = 0` (Att. 4 Eq. 7, signs corrected) for
    :math:`B = [0; \bar D]`. With :math:`W = \bar D \bar D^T`:

    .. math::

        \Delta_{ij} &= (\omega_i^2 - \omega_j^2)^2
            + 4\omega_i\omega_j(\zeta_i\omega_i + \zeta_j\omega_j)
              (\zeta_i\omega_j + \zeta_j\omega_i) \\
        [X_{\eta\eta}]_{ij} &= 2(\zeta_i\omega_i + \zeta_j\omega_j)\, W_{ij} / \Delta_{ij} \\
        [X_{\eta\dot\eta}]_{ij} &= (\omega_i^2 - \omega_j^2)\, W_{ij} / \Delta_{ij} \\
        [X_{\dot\eta\dot\eta}]_{ij} &= 2\omega_i\omega_j(\zeta_i\omega_j + \zeta_j\omega_i)\,
            W_{ij} / \Delta_{ij}

    (the OCR prints every "+" as "−", which gives 0/0 on the diagonal). On the diagonal
    :math:`[X_{\eta\eta}]_{ii} = W_{ii}/(4\zeta_i\omega_i^3)` and
    :math:`[X_{\dot\eta\dot\eta}]_{ii} = W_{ii}/(4\zeta_i\omega_i)`.

    Parameters
    ----------
    omega, zeta : array_like (n,)
        rad/s and damping ratios; every mode needs ζω > 0.
    B : array_like (n, m) or (n,)
        Modal input matrix :math:`\bar D` (row i: modal force of each input on mode i).

    Returns
    -------
    ndarray (2n, 2n)
        X in the state order (η, η̇).

    Raises
    ------
    ValueError
        Bad shapes, non-finite values, or a mode with ζω = 0 (rigid or undamped; see
        :func:`finite_horizon_gramian`).
    """
    w, z = modal_parameters(omega, zeta)
    Bm = modal_inputs(B, w.size)
    require_damped(w, z, "modal_controllability_gramian")
    W = Bm @ Bm.T
    wi, wj = w[:, None], w[None, :]
    zi, zj = z[:, None], z[None, :]
    s = zi * wi + zj * wj
    delta = (wi**2 - wj**2) ** 2 + 4 * wi * wj * s * (zi * wj + zj * wi)
    Xqq = 2 * s * W / delta
    Xqv = (wi**2 - wj**2) * W / delta
    Xvv = 2 * wi * wj * (zi * wj + zj * wi) * W / delta
    return np.block([[Xqq, Xqv], [Xqv.T, Xvv]])


def _pair_systems(w: FloatArray, z: FloatArray, kind: str) -> FloatArray:
    r"""The 4 × 4 matrix of the (i, j) block equation, for every pair: shape (n, n, 4, 4).

    Unknown block :math:`X^{ij} = [[a, b], [c, d]]` (a = ηη, b = ηη̇, c = η̇η, d = η̇η̇); per mode
    :math:`A_i = [[0, 1], [-k_i, -s_i]]`, :math:`k = \omega^2`, :math:`s = 2\zeta\omega`.

    controllability: :math:`A_i X^{ij} + X^{ij} A_j^T = -Q^{ij}`;
    observability: :math:`A_i^T X^{ij} + X^{ij} A_j = -Q^{ij}`.
    """
    n = w.size
    k, s = w**2, 2 * z * w
    ki, kj = np.broadcast_to(k[:, None], (n, n)), np.broadcast_to(k[None, :], (n, n))
    si, sj = np.broadcast_to(s[:, None], (n, n)), np.broadcast_to(s[None, :], (n, n))
    one, zero = np.ones((n, n)), np.zeros((n, n))
    if kind == "controllability":
        rows = [
            [zero, one, one, zero],  # (1,1): b + c
            [-kj, -sj, zero, one],  # (1,2): d − k_j a − s_j b
            [-ki, zero, -si, one],  # (2,1): d − k_i a − s_i c
            [zero, -ki, -kj, -(si + sj)],  # (2,2): −k_i b − k_j c − (s_i + s_j) d
        ]
    else:
        rows = [
            [zero, -kj, -ki, zero],  # (1,1): −k_i c − k_j b
            [one, -sj, zero, -ki],  # (1,2): a − s_j b − k_i d
            [one, zero, -si, -kj],  # (2,1): a − s_i c − k_j d
            [zero, one, one, -(si + sj)],  # (2,2): b + c − (s_i + s_j) d
        ]
    return np.moveaxis(np.array(rows), (0, 1), (2, 3))


def modal_gramian(
    omega: npt.ArrayLike, zeta: npt.ArrayLike, Q: npt.ArrayLike, kind: str = "controllability"
) -> FloatArray:
    r"""Exact Gramian of a modal system for any weight :math:`Q = B B^T` or :math:`C^T C`.

    Solves :math:`A X + X A^T + Q = 0` (controllability) or :math:`A^T X + X A + Q = 0`
    (observability) for the modal A of Att. 4 Eq. (16) one mode pair at a time: the (i, j)
    2 × 2 block obeys 4 linear equations that involve no other mode. Their determinant is
    exactly the :math:`\Delta_{ij}` of Att. 4 Eq. (25) (checked numerically in the tests),
    positive whenever ζω > 0, so the n² small systems are solved in one batched call. For
    :math:`Q = [0, 0; 0, W]` this is Att. 4 Eq. (25) (:func:`modal_controllability_gramian`).

    Parameters
    ----------
    omega, zeta : array_like (n,)
    Q : array_like (2n, 2n)
        Symmetric weight in the state order (η, η̇): :math:`B_z B_z^T` or :math:`C_z^T C_z`.
    kind : {"controllability", "observability"}

    Returns
    -------
    ndarray (2n, 2n)
    """
    w, z = modal_parameters(omega, zeta)
    kind = _kind(kind)
    n = w.size
    Q = require_finite(Q, "Q")
    if Q.shape != (2 * n, 2 * n):
        raise FieldError("Q", f"must have shape (2n, 2n) = ({2 * n}, {2 * n}), got {Q.shape}")
    require_damped(w, z, "modal_gramian")
    # rhs per pair: −(Q_ηη, Q_ηη̇, Q_η̇η, Q_η̇η̇)[i, j]
    rhs = -np.stack([Q[:n, :n], Q[:n, n:], Q[n:, :n], Q[n:, n:]], axis=-1)
    sol = np.linalg.solve(_pair_systems(w, z, kind), rhs[..., None])[..., 0]
    X = np.block([[sol[..., 0], sol[..., 1]], [sol[..., 2], sol[..., 3]]])
    return 0.5 * (X + X.T)


def modal_observability_gramian(
    omega: npt.ArrayLike,
    zeta: npt.ArrayLike,
    Cq: npt.ArrayLike | None = None,
    Cv: npt.ArrayLike | None = None,
) -> FloatArray:
    r"""Exact observability Gramian :math:`A^T Y + Y A + C^T C = 0` of a modal system,
    :math:`C = [C_q, C_v]` (displacement and velocity outputs), by :func:`modal_gramian`.

    For one mode with a displacement output only (:math:`C_v = 0`) the diagonal block is
    :math:`Y_{\eta\eta} = \|c_i\|^2 (1 + 4\zeta_i^2) / (4\zeta_i\omega_i)`,
    :math:`Y_{\eta\dot\eta} = \|c_i\|^2 / (2\omega_i^2)`,
    :math:`Y_{\dot\eta\dot\eta} = \|c_i\|^2 / (4\zeta_i\omega_i^3)` (c_i the i-th column of
    C_q), which the tests check.
    """
    w, z = modal_parameters(omega, zeta)
    Cq, Cv = modal_outputs(Cq, Cv, w.size)
    C = np.hstack([Cq, Cv])
    return modal_gramian(w, z, C.T @ C, kind="observability")


# ------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class GawronskiGramians:
    r"""Gawronski's approximately diagonal Gramians of a lightly damped modal system.

    In the coordinates :math:`x_i = (\omega_i \eta_i, \dot\eta_i)` the Gramians are close to
    :math:`\mathrm{diag}(w_{c,i} I_2)` and :math:`\mathrm{diag}(w_{o,i} I_2)`:

    .. math::

        w_{c,i} = \frac{\|\bar d_i\|^2}{4\zeta_i\omega_i}, \quad
        w_{o,i} = \frac{\|c_{q,i}\|^2/\omega_i^2 + \|c_{v,i}\|^2}{4\zeta_i\omega_i}, \quad
        \gamma_i = \sqrt{w_{c,i} w_{o,i}},\quad
        \|G_i\|_2 = \frac{\|\bar d_i\|\, \|c_i\|}{2\sqrt{\zeta_i\omega_i}},

    with :math:`\bar d_i` the i-th row of :math:`\bar D` and :math:`c_{q,i}, c_{v,i}` the
    i-th columns of :math:`C_q, C_v`. The neglected cross-mode blocks are of relative size
    :math:`\zeta\omega_i\omega_j / |\omega_i^2 - \omega_j^2|`, hence "well-separated modes".

    Attributes
    ----------
    wc, wo : ndarray (n,)
        Diagonal controllability and observability Gramian entries (per mode).
    hankel : ndarray (n,)
        Approximate Hankel singular values γ_i (each is a double singular value).
    h2 : ndarray (n,)
        Approximate H2 norm of each mode.
    controllability, observability : ndarray (2n, 2n)
        The same approximations expressed in the state (η, η̇) of the rest of this module:
        :math:`[X_{\eta\eta}]_{ii} = w_{c,i}/\omega_i^2`, :math:`[X_{\dot\eta\dot\eta}]_{ii} =
        w_{c,i}`, everything else 0 (and the dual for observability).
    """

    wc: FloatArray
    wo: FloatArray
    hankel: FloatArray
    h2: FloatArray
    controllability: FloatArray
    observability: FloatArray


def gawronski_gramians(
    omega: npt.ArrayLike,
    zeta: npt.ArrayLike,
    B: npt.ArrayLike,
    Cq: npt.ArrayLike | None = None,
    Cv: npt.ArrayLike | None = None,
) -> GawronskiGramians:
    r"""Gawronski's diagonal Gramian approximation (see :class:`GawronskiGramians`).

    Parameters
    ----------
    omega, zeta : array_like (n,)
        Every mode needs ω > 0 and ζ > 0.
    B : array_like (n, m)
        Modal input matrix.
    Cq, Cv : array_like (p, n), optional
        Output rows on η and η̇ (at least one).
    """
    w, z = modal_parameters(omega, zeta)
    n = w.size
    Bm = modal_inputs(B, n)
    Cq, Cv = modal_outputs(Cq, Cv, n)
    require_damped(w, z, "gawronski_gramians")
    b2 = np.sum(Bm**2, axis=1)
    c2 = np.sum(Cq**2, axis=0) / w**2 + np.sum(Cv**2, axis=0)
    wc, wo = b2 / (4 * z * w), c2 / (4 * z * w)
    Xc = np.diag(np.concatenate([wc / w**2, wc]))
    # observability in (η, η̇): y = (C_q/ω)(ωη) + C_v η̇ ⇒ Y_ηη = ω² w_o, Y_η̇η̇ = w_o
    Xo = np.diag(np.concatenate([wo * w**2, wo]))
    return GawronskiGramians(
        wc=wc,
        wo=wo,
        hankel=np.sqrt(wc * wo),
        h2=np.sqrt(b2 * c2) / (2 * np.sqrt(z * w)),
        controllability=Xc,
        observability=Xo,
    )


# ------------------------------------------------------------------------------------------------
def _system(A: npt.ArrayLike, M: npt.ArrayLike, kind: str) -> tuple[FloatArray, FloatArray]:
    """(A, Q) with Q = B Bᵀ (controllability, B (n, m)) or Cᵀ C (observability, C (p, n))."""
    A = require_finite(A, "A")
    if A.ndim != 2 or A.shape[0] != A.shape[1] or A.shape[0] == 0:
        raise FieldError("A", f"must be a non-empty square matrix, got shape {A.shape}")
    n = A.shape[0]
    if kind == "controllability":
        B = _matrix(M, "B", rows=n)
        return A, B @ B.T
    C = _matrix(M, "C", cols=n)
    return A, C.T @ C


def lyapunov_gramian(
    A: npt.ArrayLike, M: npt.ArrayLike, kind: str = "controllability"
) -> FloatArray:
    r"""Infinite-horizon Gramian of a stable system by Bartels–Stewart.

    Controllability: :math:`A X + X A^T + B B^T = 0` (``M`` = B, n × m); observability:
    :math:`A^T Y + Y A + C^T C = 0` (``M`` = C, p × n). Refuses A with an eigenvalue of real
    part >= 0 (rigid-body modes included), where the Gramian does not exist: use
    :func:`finite_horizon_gramian`.
    """
    kind = _kind(kind)
    A, Q = _system(A, M, kind)
    lam = np.linalg.eigvals(A)
    scale = max(float(np.abs(lam).max()), 1.0)
    if np.any(lam.real >= -_UNDAMPED_TOL * scale):
        raise FieldError(
            "A",
            "not asymptotically stable (max Re λ = "
            f"{lam.real.max():.3g}); rigid-body or undamped modes have no infinite-horizon "
            "Gramian: use finite_horizon_gramian",
        )
    X = sla.solve_continuous_lyapunov(A if kind == "controllability" else A.T, -Q)
    return 0.5 * (X + X.T)


def finite_horizon_gramian(
    A: npt.ArrayLike, M: npt.ArrayLike, horizon: float, kind: str = "controllability"
) -> FloatArray:
    r"""Finite-horizon Gramian by the Van Loan block exponential; rigid modes allowed.

    .. math::

        W_c(T) = \int_0^T e^{At} B B^T e^{A^T t}\, dt, \qquad
        W_o(T) = \int_0^T e^{A^T t} C^T C\, e^{A t}\, dt.

    Van Loan (1978): with :math:`H = \begin{bmatrix} -A & Q \\ 0 & A^T \end{bmatrix}`,
    :math:`e^{H h} = \begin{bmatrix} \cdot & F_{12} \\ 0 & F_{22} \end{bmatrix}` gives
    :math:`W(h) = F_{22}^T F_{12}` and :math:`e^{A h} = F_{22}^T`. To keep :math:`e^{-Ah}` from
    growing, the exponential is taken over :math:`h = T / 2^k` with :math:`\|A\|_1 h \le 1/2`
    and the interval is doubled k times, :math:`W(2h) = W(h) + e^{Ah} W(h) e^{A^T h}`
    (observability: A replaced by Aᵀ).

    Parameters
    ----------
    A : array_like (n, n)
        Any real square matrix (stable, marginally stable with rigid-body modes, or unstable).
    M : array_like
        B (n, m) for "controllability", C (p, n) for "observability".
    horizon : float
        T > 0, in the time unit of A (s).
    kind : {"controllability", "observability"}

    Returns
    -------
    ndarray (n, n), symmetric positive semi-definite.
    """
    kind = _kind(kind)
    A, Q = _system(A, M, kind)
    T = float(require_positive(horizon, "horizon"))
    F = A if kind == "controllability" else A.T
    n = F.shape[0]
    norm = float(np.abs(F).sum(axis=0).max())
    k = 0 if norm * T <= 0.5 else int(np.ceil(np.log2(2 * norm * T)))
    h = T / 2**k
    H = np.block([[-F, Q], [np.zeros((n, n)), F.T]]) * h
    E = sla.expm(H)
    Phi = E[n:, n:].T  # e^{F h}
    W = Phi @ E[:n, n:]  # F22ᵀ F12
    for _ in range(k):
        W = W + Phi @ W @ Phi.T
        Phi = Phi @ Phi
    return 0.5 * (W + W.T)


def gramian_residual(
    A: npt.ArrayLike, M: npt.ArrayLike, X: npt.ArrayLike, kind: str = "controllability"
) -> float:
    r"""Relative Lyapunov residual :math:`\|A X + X A^T + BB^T\|_F / \|BB^T\|_F`
    (observability: :math:`\|A^T X + X A + C^T C\|_F / \|C^T C\|_F`)."""
    kind = _kind(kind)
    A, Q = _system(A, M, kind)
    X = require_finite(X, "X")
    R = A @ X + X @ A.T + Q if kind == "controllability" else A.T @ X + X @ A + Q
    return float(np.linalg.norm(R) / max(np.linalg.norm(Q), np.finfo(float).tiny))
