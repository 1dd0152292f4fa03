r"""Model reduction of flexible plants: balanced truncation, residualisation, modal truncation.

Every method reduces only the **asymptotically stable part** of the plant and keeps the rest
(rigid-body modes, any marginal or unstable pole) exactly: the state matrix is brought to an
ordered real Schur form with the eigenvalues of :math:`\operatorname{Re}\lambda \ge -\epsilon`
first, and the two blocks are decoupled by the Sylvester equation
:math:`A_{11}X - XA_{22} + A_{12} = 0` (the additive decomposition
:math:`G = G_u + G_s`; Zhou, Doyle & Glover, *Robust and Optimal Control*, 1996, §7.2 and
§8.4). :math:`G_u` is kept as is; :math:`G_s` is reduced, so the error is the error of the
stable part, :math:`G - G_r = G_s - G_{s,r}`.

**Balanced truncation, square-root method** (Laub, Heath, Paige & Ward, "Computation of
system balancing transformations and other applications of simultaneous diagonalization
algorithms", IEEE Trans. AC-32(2), 1987, 115–122; Tombs & Postlethwaite, "Truncated balanced
realization of a stable non-minimal state-space system", Int. J. Control 46(4), 1987,
1319–1330): with the Gramians :math:`A P + P A^T + BB^T = 0`, :math:`A^T Q + Q A + C^T C = 0`
(solved in the real modal form block pair by block pair, each pair a Kronecker system of at
most 4 × 4, so that every entry is accurate relative to its own size; scipy's Bartels–Stewart
solver :func:`scipy.linalg.solve_continuous_lyapunov` on the whole matrix when A is defective;
python-control's ``balred`` needs slycot, which flexsat does not require) factored after
scaling to a unit diagonal as
:math:`P = L_c L_c^T`, :math:`Q = L_o L_o^T` and the SVD :math:`L_o^T L_c = U \Sigma V^T`, the
Hankel singular values are :math:`\sigma_i = \Sigma_{ii}` and the projections
:math:`T = L_c V_1 \Sigma_1^{-1/2}`, :math:`W = L_o U_1 \Sigma_1^{-1/2}` (:math:`W^T T = I`)
give :math:`A_r = W^T A T`, :math:`B_r = W^T B`, :math:`C_r = C T`.

**Singular-perturbation approximation** (residualisation of the balanced realisation; Liu &
Anderson, "Singular perturbation approximation of balanced systems", Int. J. Control 50(4),
1989, 1379–1405): with the balanced realisation partitioned after the kept states,
:math:`A_r = A_{11} - A_{12}A_{22}^{-1}A_{21}`, :math:`B_r = B_1 - A_{12}A_{22}^{-1}B_2`,
:math:`C_r = C_1 - C_2A_{22}^{-1}A_{21}`, :math:`D_r = D - C_2A_{22}^{-1}B_2`; it matches the DC
gain exactly where truncation matches at infinite frequency.

Both obey Glover's bound (Glover, "All optimal Hankel-norm approximations of linear
multivariable systems and their L∞-error bounds", Int. J. Control 39(6), 1984, 1115–1193,
Theorem 9.6; Liu & Anderson 1989 for the residualised model)

.. math::

    \|G_s - G_{s,r}\|_\infty \le 2 \sum_{i > r} \sigma_i

(each distinct σ counted once; flexsat sums every discarded σ, which is larger, hence also a
bound).

**Modal truncation** keeps whole modes of the stable part, in its real block-diagonal modal form
(one 2 × 2 block per complex pair, one 1 × 1 per real pole), ranked by

* ``"modal_cost"``: Skelton's component cost (Skelton & Yousuff, "Component cost analysis of
  large scale systems", Int. J. Control 37(2), 1983, 285–304),
  :math:`V_i = \operatorname{tr}\big[(P C^T C)_{ii}\big]` over the block of mode i, with P the
  controllability Gramian of the modal realisation; :math:`\sum_i V_i = \|G_s\|_2^2`;
* ``"h2"``: Gawronski's H2 modal index, the H2 norm of the mode alone (Gawronski, *Advanced
  Structural Dynamics and Active Control of Structures*, Springer, 2004, §5.2; for a lightly
  damped mode :math:`\|G_i\|_2 \approx \|b_i\|\,\|c_i\| / (2\sqrt{\zeta_i\omega_i})`, computed
  here exactly from the mode's 2 × 2 Lyapunov equation);
* ``"hankel"``: Gawronski's Hankel index, the largest Hankel singular value of the mode alone
  (:math:`\approx \|b_i\|\,\|c_i\|/(4\zeta_i\omega_i)`, the same book §5.3).

With ``static_correction`` the discarded modes' DC gain :math:`-C_d A_d^{-1} B_d` is added to D
(modal residualisation). Modal truncation has no a-priori bound; its error is measured.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import scipy.linalg as sla

from flexsat.analysis.norms import hinf_norm, system_matrices
from flexsat.input_checks import FieldError

if TYPE_CHECKING:
    import control as ct
    from flexsat.units import FloatArray

__all__ = [
    "ModalForm",
    "ReducedModel",
    "StableSplit",
    "balanced_reduction",
    "compare_reductions",
    "hankel_singular_values",
    "modal_form",
    "modal_indices",
    "modal_truncation",
    "reduction_error",
    "split_stable",
]

Matrices = tuple["FloatArray", "FloatArray", "FloatArray", "FloatArray"]
Matrices3 = tuple["FloatArray", "FloatArray", "FloatArray"]


@dataclass(frozen=True)
class StableSplit:
    r"""The additive decomposition :math:`G = G_u + G_s` (module docstring).

    Attributes
    ----------
    unstable : tuple of ndarray
        (A, B, C) of the kept part (Re λ >= −margin): rigid modes, marginal or unstable poles.
    stable : tuple of ndarray
        (A, B, C, D) of the asymptotically stable part (it carries the feedthrough D).
    """

    unstable: tuple[FloatArray, FloatArray, FloatArray]
    stable: Matrices


def split_stable(system: ct.StateSpace, margin: float = 1e-9) -> StableSplit:
    """Split a continuous system into its marginal/unstable and stable parts.

    Parameters
    ----------
    system : control.StateSpace
        Continuous.
    margin : float
        Poles with Re λ >= −margin·max(1, ρ(A)) count as marginal (kept exactly).

    Raises
    ------
    FieldError
        For a discrete system, or when the Sylvester equation that decouples the parts is
        ill-conditioned (a stable pole too close to a marginal one).
    """
    A, B, C, D, dt = system_matrices(system)
    if dt:
        raise FieldError("system", "must be continuous (dt = 0) to be reduced here")
    n = A.shape[0]
    if n == 0:
        z = np.zeros((0, 0))
        return StableSplit((z, np.zeros((0, B.shape[1])), np.zeros((C.shape[0], 0))), (A, B, C, D))
    scale = max(1.0, float(np.max(np.abs(np.linalg.eigvals(A)))))
    cut = -margin * scale
    T, U, k = sla.schur(A, output="real", sort=lambda re, im: re >= cut)
    k = int(k)
    A11, A12, A22 = T[:k, :k], T[:k, k:], T[k:, k:]
    X = sla.solve_sylvester(A11, -A22, -A12) if k and k < n else np.zeros((k, n - k))
    if not np.all(np.isfinite(X)) or np.linalg.norm(X) > 1e8 * (1 + np.linalg.norm(A12)):
        raise FieldError(
            "system", "a stable pole is too close to a marginal one to separate the two parts"
        )
    # similarity S = U [[I, X], [0, I]]: block-diagonal [[A11, 0], [0, A22]]
    S = U @ np.block([[np.eye(k), X], [np.zeros((n - k, k)), np.eye(n - k)]])
    Sinv = np.block([[np.eye(k), -X], [np.zeros((n - k, k)), np.eye(n - k)]]) @ U.T
    Bt, Ct = Sinv @ B, C @ S
    return StableSplit((A11, Bt[:k], Ct[:, :k]), (A22, Bt[k:], Ct[:, k:], D))


def _psd_factor(P: FloatArray) -> FloatArray:
    """L with L Lᵀ = P for a symmetric positive semi-definite P (eigen-decomposition, so that a
    numerically singular Gramian of a non-minimal system is factored too)."""
    w, V = np.linalg.eigh(0.5 * (P + P.T))
    return np.asarray(V * np.sqrt(np.clip(w, 0.0, None)), float)


def _block_gramian(A: FloatArray, F: FloatArray, blocks: tuple[slice, ...]) -> FloatArray:
    """The solution of A X + X Aᵀ + F Fᵀ = 0 for a block-diagonal A, block pair by block pair:
    (I ⊗ A_i + A_j ⊗ I) vec X_ij = −vec(F_i F_jᵀ), each at most 4 × 4 (module docstring)."""
    X = np.zeros((A.shape[0], A.shape[0]))
    for bi in blocks:
        Ai, ni = A[bi, bi], bi.stop - bi.start
        for bj in blocks:
            if bj.start < bi.start:
                continue
            Aj, nj = A[bj, bj], bj.stop - bj.start
            K = np.kron(np.eye(nj), Ai) + np.kron(Aj, np.eye(ni))
            rhs = -(F[bi] @ F[bj].T).reshape(-1, order="F")
            Xij = np.linalg.solve(K, rhs).reshape((ni, nj), order="F")
            X[bi, bj] = Xij
            X[bj, bi] = Xij.T
    return X


def _graded_factor(P: FloatArray) -> FloatArray:
    """L with L Lᵀ = P for a symmetric positive semi-definite P whose diagonal spans many decades:
    the factor of the unit-diagonal D⁻¹PD⁻¹ (D = diag(P)^½), scaled back, so that small
    entries keep their relative accuracy (Demmel & Veselić, "Jacobi's method is more accurate
    than QR", SIAM J. Matrix Anal. Appl. 13(4), 1992, 1204–1245: the scaled matrix's condition
    governs the error)."""
    d = np.sqrt(np.clip(np.diag(P), 0.0, None))
    d[d == 0.0] = 1.0
    return d[:, None] * _psd_factor(P / np.outer(d, d))


def _gramian_factors(
    A: FloatArray, B: FloatArray, C: FloatArray
) -> tuple[FloatArray, FloatArray, Matrices3]:
    """Factors of the two Gramians and the realisation they belong to (module docstring).

    In the real modal form (when A is diagonalisable with a well-conditioned eigenvector
    matrix) the Gramians are solved block pair by block pair, so that every entry is accurate
    relative to its own size; scipy's Bartels–Stewart solver on the whole matrix leaves an
    error of ε‖P‖ in every entry, which swamps the Gramian of a stiff, weakly controllable
    mode (TAMU's 430 Hz mode: P entries near 1e-11 against ‖P‖ = 4.5) and moved its Hankel
    values by 30 % from one BLAS kernel to another. A defective A falls back to Bartels–Stewart.
    """
    try:
        form = modal_form((A, B, C, np.zeros((C.shape[0], B.shape[1]))))
    except FieldError:
        P = sla.solve_continuous_lyapunov(A, -B @ B.T)
        Q = sla.solve_continuous_lyapunov(A.T, -C.T @ C)
        return _psd_factor(P), _psd_factor(Q), (A, B, C)
    Am, Bm, Cm, _ = form.matrices
    P = _block_gramian(Am, Bm, form.blocks)
    Q = _block_gramian(Am.T, Cm.T, form.blocks)
    return _graded_factor(P), _graded_factor(Q), (Am, Bm, Cm)


def hankel_singular_values(system: ct.StateSpace) -> FloatArray:
    """Hankel singular values of the stable part, descending (module docstring)."""
    A, B, C, _ = split_stable(system).stable
    if A.size == 0:
        return np.zeros(0)
    Lc, Lo, _ = _gramian_factors(A, B, C)
    return np.asarray(np.linalg.svd(Lo.T @ Lc, compute_uv=False), float)


@dataclass(frozen=True)
class ReducedModel:
    """A reduced plant with what it was reduced from.

    Attributes
    ----------
    system : control.StateSpace
        The reduced model, the same input and output labels as the original; its first
        ``n_kept_exactly`` states are the kept marginal part.
    method : str
        ``"balanced_truncation"``, ``"residualization"`` or ``"modal:<index>"``.
    n_kept_exactly : int
        States of the marginal/unstable part, kept unchanged.
    hankel_singular_values : ndarray
        Of the stable part (all of them, descending); empty for modal truncation.
    error_bound : float
        Glover's bound 2 Σ σ_discarded (``math.inf`` for modal truncation: none a priori).
    kept_modes : tuple of int
        For modal truncation, the indices of the kept modes in :func:`modal_form` order.
    stable_full, stable_reduced : tuple of ndarray
        (A, B, C, D) of the stable parts before and after, whose difference is the error.
    """

    system: ct.StateSpace
    method: str
    n_kept_exactly: int
    hankel_singular_values: FloatArray
    error_bound: float
    kept_modes: tuple[int, ...]
    stable_full: Matrices
    stable_reduced: Matrices


def _order(order: int, n: int) -> int:
    if isinstance(order, bool) or not isinstance(order, (int, np.integer)) or order < 0:
        raise FieldError("order", f"must be a whole number of states >= 0, got {order!r}")
    if order > n:
        raise FieldError("order", f"the stable part has {n} states, asked to keep {order}")
    return int(order)


def _assemble(
    system: ct.StateSpace,
    unstable: tuple[FloatArray, FloatArray, FloatArray],
    reduced: Matrices,
    prefix: str,
) -> ct.StateSpace:
    import control as ct

    Au, Bu, Cu = unstable
    Ar, Br, Cr, Dr = reduced
    ku, kr = Au.shape[0], Ar.shape[0]
    A = sla.block_diag(Au, Ar) if ku + kr else np.zeros((0, 0))
    B = np.vstack([Bu, Br])
    C = np.hstack([Cu, Cr])
    states = [f"rigid[{i}]" for i in range(ku)] + [f"{prefix}[{i}]" for i in range(kr)]
    return ct.ss(
        A,
        B,
        C,
        Dr,
        states=states,
        inputs=list(system.input_labels),
        outputs=list(system.output_labels),
        name=f"{system.name}_reduced",
    )


def balanced_reduction(
    system: ct.StateSpace, order: int, method: str = "truncate", margin: float = 1e-9
) -> ReducedModel:
    """Balanced truncation or residualisation of the stable part (module docstring).

    Parameters
    ----------
    system : control.StateSpace
        Continuous; rigid-body and marginal modes are kept exactly.
    order : int
        States of the stable part to keep (the marginal part comes on top).
    method : {"truncate", "residualize"}
    margin : float
        As in :func:`split_stable`.

    Returns
    -------
    ReducedModel
        With the Hankel singular values and the bound 2 Σ_{i > order} σ_i.
    """
    if method not in ("truncate", "residualize"):
        raise FieldError("method", f"must be 'truncate' or 'residualize', got {method!r}")
    split = split_stable(system, margin)
    A, B, C, D = split.stable
    r = _order(order, A.shape[0])
    if A.size:
        # the projections act on the realisation the Gramians were solved in
        Lc, Lo, (A, B, C) = _gramian_factors(A, B, C)
        U, s, Vt = np.linalg.svd(Lo.T @ Lc)
    else:
        U = Vt = np.zeros((0, 0))
        s = np.zeros(0)
    bound = 2.0 * float(np.sum(s[r:]))
    if method == "truncate" or r == A.shape[0]:
        if r and s[r - 1] <= 0:
            raise FieldError("order", f"the stable part is of minimal order < {r}: keep fewer")
        scale = 1.0 / np.sqrt(s[:r]) if r else np.zeros(0)
        T = Lc @ Vt[:r].T * scale
        W = Lo @ U[:, :r] * scale
        reduced = (W.T @ A @ T, W.T @ B, C @ T, D)
    else:
        # balance the minimal part (σ above round-off), then residualise past the order
        nm = int(np.sum(s > s[0] * 1e-12 * A.shape[0])) if s.size else 0
        if nm < r:
            raise FieldError("order", f"the stable part is of minimal order {nm} < {r}")
        scale = 1.0 / np.sqrt(s[:nm])
        T = Lc @ Vt[:nm].T * scale
        W = Lo @ U[:, :nm] * scale
        Ab, Bb, Cb = W.T @ A @ T, W.T @ B, C @ T
        A11, A12, A21, A22 = Ab[:r, :r], Ab[:r, r:], Ab[r:, :r], Ab[r:, r:]
        X = np.linalg.solve(A22, np.hstack([A21, Bb[r:]]))
        reduced = (
            A11 - A12 @ X[:, :r],
            Bb[:r] - A12 @ X[:, r:],
            Cb[:, :r] - Cb[:, r:] @ X[:, :r],
            D - Cb[:, r:] @ X[:, r:],
        )
    label = "balanced_truncation" if method == "truncate" else "residualization"
    return ReducedModel(
        _assemble(system, split.unstable, reduced, "bal"),
        label,
        split.unstable[0].shape[0],
        np.asarray(s, float),
        bound,
        (),
        split.stable,
        reduced,
    )


@dataclass(frozen=True)
class ModalForm:
    """The stable part in real block-diagonal modal form (module docstring).

    Attributes
    ----------
    blocks : tuple of slice
        The states of each mode (2 for a complex pair, 1 for a real pole), by rising frequency.
    frequencies_rad_s, damping_ratios : ndarray
        ω_i = |λ_i| and ζ_i = −Re λ_i/|λ_i| of each mode.
    matrices : tuple of ndarray
        (A, B, C, D) of the stable part in these coordinates.
    """

    blocks: tuple[slice, ...]
    frequencies_rad_s: FloatArray
    damping_ratios: FloatArray
    matrices: Matrices


def modal_form(stable: Matrices) -> ModalForm:
    """The real modal form of a stable (A, B, C, D) (e.g. :attr:`StableSplit.stable`).

    Raises
    ------
    FieldError
        When A is defective or nearly so (eigenvector matrix condition > 1e10).
    """
    A, B, C, D = stable
    lam, V = np.linalg.eig(A) if A.size else (np.zeros(0, complex), np.zeros((0, 0)))
    order = np.lexsort((lam.imag, np.abs(lam)))
    cols: list[FloatArray] = []
    blocks, freqs, damps = [], [], []
    used = np.zeros(lam.size, bool)
    tol = 1e-10 * max(1.0, float(np.max(np.abs(lam)))) if lam.size else 0.0
    for k in order:
        if used[k]:
            continue
        used[k] = True
        z, v = lam[k], V[:, k]
        if abs(z.imag) <= tol:
            blocks.append(slice(len(cols), len(cols) + 1))
            cols.append(v.real / np.linalg.norm(v.real))
        else:
            # its conjugate partner: the unused eigenvalue closest to conj(z)
            free = np.flatnonzero(~used)
            used[free[np.argmin(np.abs(lam[free] - np.conj(z)))]] = True
            blocks.append(slice(len(cols), len(cols) + 2))
            cols += [v.real, v.imag]
        freqs.append(abs(z))
        damps.append(-z.real / abs(z))
    T = np.column_stack(cols) if cols else np.zeros((0, 0))
    if T.size and np.linalg.cond(T) > 1e10:
        raise FieldError("system", "its stable part is (nearly) defective: no modal form")
    Am = np.linalg.solve(T, A @ T) if T.size else A
    for b in blocks:  # zero the round-off between blocks: the form is block diagonal
        mask = np.ones(Am.shape[0], bool)
        mask[b] = False
        Am[b][:, mask] = 0.0
        Am[np.ix_(mask, np.arange(b.start, b.stop))] = 0.0
    Bm = np.linalg.solve(T, B) if T.size else B
    Cm = C @ T if T.size else C
    mats = (np.asarray(Am, float), np.asarray(Bm, float), np.asarray(Cm, float), D)
    return ModalForm(tuple(blocks), np.array(freqs), np.array(damps), mats)


def _mode_gramians(Ai: FloatArray, Bi: FloatArray, Ci: FloatArray) -> tuple[FloatArray, FloatArray]:
    P = sla.solve_continuous_lyapunov(Ai, -Bi @ Bi.T)
    Q = sla.solve_continuous_lyapunov(Ai.T, -Ci.T @ Ci)
    return P, Q


def modal_indices(form: ModalForm, index: str = "modal_cost") -> FloatArray:
    """One index per mode of :func:`modal_form` (module docstring); larger means keep.

    Parameters
    ----------
    form : ModalForm
    index : {"modal_cost", "h2", "hankel"}
    """
    A, B, C, _ = form.matrices
    if index == "modal_cost":
        P = sla.solve_continuous_lyapunov(A, -B @ B.T)
        W = P @ C.T @ C
        return np.array([float(np.trace(W[b, b])) for b in form.blocks])
    if index not in ("h2", "hankel"):
        raise FieldError("index", f"must be 'modal_cost', 'h2' or 'hankel', got {index!r}")
    out = []
    for b in form.blocks:
        P, Q = _mode_gramians(A[b, b], B[b], C[:, b])
        if index == "h2":
            out.append(math.sqrt(max(float(np.trace(C[:, b] @ P @ C[:, b].T)), 0.0)))
        else:
            ev = np.linalg.eigvals(P @ Q)
            out.append(math.sqrt(max(float(np.max(ev.real)), 0.0)))
    return np.array(out)


def modal_truncation(
    system: ct.StateSpace,
    n_modes: int,
    index: str = "modal_cost",
    static_correction: bool = False,
    margin: float = 1e-9,
) -> ReducedModel:
    """Keep the marginal part and the ``n_modes`` stable modes of largest index.

    Parameters
    ----------
    system : control.StateSpace
        Continuous.
    n_modes : int
        Modes (pairs or real poles) of the stable part to keep.
    index : {"modal_cost", "h2", "hankel"}
        The ranking (module docstring).
    static_correction : bool
        Add the discarded modes' DC gain to D.
    margin : float
        As in :func:`split_stable`.
    """
    split = split_stable(system, margin)
    form = modal_form(split.stable)
    if (
        isinstance(n_modes, bool)
        or not isinstance(n_modes, (int, np.integer))
        or not 0 <= n_modes <= len(form.blocks)
    ):
        raise FieldError(
            "n_modes", f"must be a whole number in [0, {len(form.blocks)}], got {n_modes!r}"
        )
    score = modal_indices(form, index)
    kept = sorted(np.argsort(-score, kind="stable")[: int(n_modes)].tolist())
    A, B, C, D = form.matrices
    keep = [i for k in kept for i in range(form.blocks[k].start, form.blocks[k].stop)]
    drop = [i for i in range(A.shape[0]) if i not in keep]
    Dr = D.copy()
    if static_correction and drop:
        Dr = D - C[:, drop] @ np.linalg.solve(A[np.ix_(drop, drop)], B[drop])
    reduced = (A[np.ix_(keep, keep)], B[keep], C[:, keep], Dr)
    return ReducedModel(
        _assemble(system, split.unstable, reduced, "mode"),
        f"modal:{index}",
        split.unstable[0].shape[0],
        np.zeros(0),
        math.inf,
        tuple(kept),
        form.matrices,
        reduced,
    )


def reduction_error(model: ReducedModel, tol: float = 1e-8) -> float:
    """‖G − G_r‖∞ = ‖G_s − G_{s,r}‖∞ by :func:`~flexsat.analysis.norms.hinf_norm`."""
    import control as ct

    A1, B1, C1, D1 = model.stable_full
    A2, B2, C2, D2 = model.stable_reduced
    err = ct.ss(
        sla.block_diag(A1, A2),
        np.vstack([B1, B2]),
        np.hstack([C1, -C2]),
        D1 - D2,
    )
    return hinf_norm(err, tol=tol).value


def compare_reductions(
    system: ct.StateSpace, n_modes: int, indices: Sequence[str] = ("modal_cost", "h2", "hankel")
) -> dict[str, tuple[ReducedModel, float]]:
    """Every method at the same size: ``n_modes`` modes of the stable part for modal truncation
    and as many states (the kept modes' state count under the first index) for the balanced
    methods. Returns {method: (model, H∞ error)}."""
    out: dict[str, tuple[ReducedModel, float]] = {}
    order = -1
    for idx in indices:
        m = modal_truncation(system, n_modes, idx)
        out[m.method] = (m, reduction_error(m))
        if order < 0:
            order = m.stable_reduced[0].shape[0]
    for method in ("truncate", "residualize"):
        b = balanced_reduction(system, max(order, 0), method)
        out[b.method] = (b, reduction_error(b))
    return out
