r"""Kalman filters and the NPS estimator refinement.

Continuous-time steady-state Kalman filter (Hailey, Sortun & Agrawal c. 1992 Eqs. 41–44) for

.. math::

    \dot x = A x + B u + G w, \qquad y = C x + v, \qquad
    E\begin{bmatrix} w \\ v \end{bmatrix}[w^T \; v^T] =
    \begin{bmatrix} Q_n & N_n \\ N_n^T & R_n \end{bmatrix} \delta(t - \tau),

with estimator :math:`\dot{\hat x} = A\hat x + B u + L (y - C \hat x)`,

.. math::

    0 = A P + P A^T - (P C^T + G N_n) R_n^{-1} (P C^T + G N_n)^T + G Q_n G^T, \qquad
    L = (P C^T + G N_n) R_n^{-1},

solved as the dual regulator problem :math:`(A^T, C^T, G Q_n G^T, R_n, G N_n)` of
:func:`flexsat.control.lqr.lqr` ("by duality: A → Aᵀ, B → Cᵀ, R_xx → Q_xx, R_uu → Q_yy",
Hailey, Sortun & Agrawal c. 1992 after Eq. 44), so it has the same checks, the
same reported and logged relative
residual, and gains equal to python-control's ``lqe`` / ``dlqe``.

Estimator refinement (Hailey, Sortun & Agrawal c. 1992 Eqs. 46–53)
------------------------------------------
With the regulator :math:`u = G_R \hat x` (:math:`G_R = -K`) the estimation error e enters the
plant as :math:`B G_R e` (Eq. 50), so the error that matters is the one the regulator feeds
back, :math:`J = \int e^T G_R^T B^T B G_R e\, dt` (Eq. 51). The paper uses that weight as the
process-noise intensity of the filter design (Eq. 52, a heuristic),

.. math::

    Q_{xx} = G_R^T B^T B G_R \qquad (:func:`regulator_weighted_process_noise`),

after zeroing the regulator gains of the modes the sensors cannot estimate (Eq. 53,
:func:`truncate_gains`; the paper keeps states 1, 2, 3, 8, 9, 10 of 14 — θ, q1, q2 and their
rates). The recomputed Kalman gain then estimates the dropped modes open loop (their gain rows
are near zero) and the retained ones closed loop (:func:`refine_estimator`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from flexsat.control.lqr import (
    WEIGHT_TOL,
    RiccatiSolution,
    check_matrix,
    check_psd,
    check_square,
    solve_riccati,
)
from flexsat.input_checks import FieldError

if TYPE_CHECKING:
    import numpy.typing as npt

    from flexsat.units import FloatArray

__all__ = [
    "RefinedEstimator",
    "dkalman",
    "kalman",
    "refine_estimator",
    "regulator_weighted_process_noise",
    "truncate_gains",
]

_KALMAN_LABELS = {
    "A": "A",
    "B": "C",
    "Q": "G Qn Gᵀ",
    "R": "Rn",
    "N": "G Nn",
    "stabilizable": "(A, C) is not detectable: eigenvalue(s) {} of A are not observable from "
    "the measurements C",
    "detectable": "(A, G Qn^½) is not stabilizable: the process noise does not excite "
    "eigenvalue(s) {} of A (on or outside the stability boundary), so no "
    "stabilizing filter exists",
    "joint_field": "Nn",
    "joint": "the joint noise intensity [[Qn, Nn], [Nnᵀ, Rn]] must be positive "
    "semi-definite, but Qn − Nn Rn⁻¹ Nnᵀ has smallest eigenvalue {:.3g}",
}


def _filter(
    state_matrix: npt.ArrayLike,
    noise_input: npt.ArrayLike | None,
    output_matrix: npt.ArrayLike,
    process_noise: npt.ArrayLike,
    measurement_noise: npt.ArrayLike,
    cross_noise: npt.ArrayLike | None,
    discrete: bool,
) -> RiccatiSolution:
    """:func:`kalman` (``discrete`` false) or :func:`dkalman`; the arguments in their order."""
    A = check_square(state_matrix, "A")
    n = A.shape[0]
    G = (
        np.eye(n)
        if noise_input is None
        else check_matrix(noise_input, "G", n, None, f"(n, g) with n = {n}")
    )
    g = G.shape[1]
    C = check_matrix(output_matrix, "C", None, n, f"(p, n) with n = {n}")
    p = C.shape[0]
    Qn = check_psd(check_matrix(process_noise, "Qn", g, g, f"(g, g) = ({g}, {g})"), "Qn")
    Rn = check_psd(
        check_matrix(measurement_noise, "Rn", p, p, f"(p, p) = ({p}, {p})"), "Rn", strict=True
    )
    NG = None
    if cross_noise is not None:
        Nn = check_matrix(cross_noise, "Nn", g, p, f"(g, p) = ({g}, {p})")
        joint = Qn - Nn @ np.linalg.solve(Rn, Nn.T)
        lam = np.linalg.eigvalsh(0.5 * (joint + joint.T))
        scale = max(np.abs(np.linalg.eigvalsh(Qn)).max(), np.finfo(float).tiny)
        if lam.min() < -WEIGHT_TOL * scale:
            raise FieldError(
                _KALMAN_LABELS["joint_field"], _KALMAN_LABELS["joint"].format(lam.min())
            )
        NG = G @ Nn
    W = G @ Qn @ G.T
    W = 0.5 * (W + W.T)
    kind = "dkalman" if discrete else "kalman"
    dual = solve_riccati(A.T, C.T, W, Rn, NG, discrete, _KALMAN_LABELS, kind, checked=True)
    return RiccatiSolution(
        dual.gain.T,
        dual.solution,
        dual.poles,
        dual.residual,
        dual.residual_q,
        dual.absolute_residual,
        kind,
    )


def kalman(
    A: npt.ArrayLike,
    G: npt.ArrayLike | None,
    C: npt.ArrayLike,
    Qn: npt.ArrayLike,
    Rn: npt.ArrayLike,
    Nn: npt.ArrayLike | None = None,
) -> RiccatiSolution:
    r"""Continuous-time steady-state Kalman filter (module docstring; Hailey, Sortun
    & Agrawal c. 1992 Eqs. 41–44).

    Parameters
    ----------
    A : array_like (n, n)
    G : array_like (n, g) or None
        Process-noise input matrix (None: the identity, w acts on every state).
    C : array_like (p, n)
    Qn : array_like (g, g)
        Process-noise intensity, symmetric positive semi-definite.
    Rn : array_like (p, p)
        Measurement-noise intensity, symmetric positive definite.
    Nn : array_like (g, p), optional
        Cross intensity E[w vᵀ].

    Returns
    -------
    RiccatiSolution
        Unpacks as ``L, P, E`` like ``control.lqe``: gain L (n, p), error covariance P,
        estimator poles E = eig(A − LC); ``.residual`` is the relative residual of the filter
        Riccati equation.

    Raises
    ------
    ValueError
        Bad shapes or values, Qn not PSD, Rn not PD, joint intensity indefinite, (A, C) not
        detectable, an unstable / marginal mode the noise does not excite, or a relative
        Riccati residual above the accepted one (:mod:`flexsat.control.lqr`).
    """
    return _filter(A, G, C, Qn, Rn, Nn, False)


def dkalman(
    A: npt.ArrayLike,
    G: npt.ArrayLike | None,
    C: npt.ArrayLike,
    Qn: npt.ArrayLike,
    Rn: npt.ArrayLike,
    Nn: npt.ArrayLike | None = None,
) -> RiccatiSolution:
    r"""Discrete-time steady-state Kalman filter, predictor form (as ``control.dlqe``).

    For :math:`x_{k+1} = A x_k + B u_k + G w_k`, :math:`y_k = C x_k + v_k` with covariances
    Qn, Rn, Nn = E[w vᵀ], the estimator
    :math:`\hat x_{k+1} = A \hat x_k + B u_k + L (y_k - C \hat x_k)` has

    .. math::

        L = (A P C^T + G N_n)(C P C^T + R_n)^{-1},

    P the stationary one-step prediction covariance. Returns ``L, P, E`` (E = eig(A − LC)).
    """
    return _filter(A, G, C, Qn, Rn, Nn, True)


# ------------------------------------------------------------------------------------------------
# NPS estimator refinement (Hailey, Sortun & Agrawal c. 1992 Eqs. 46–53)
def regulator_weighted_process_noise(gain: npt.ArrayLike, B: npt.ArrayLike) -> FloatArray:
    r"""Process-noise intensity :math:`Q_{xx} = G^T B^T B G` (Hailey,
    Sortun & Agrawal c. 1992 Eq. 52).

    Parameters
    ----------
    gain : array_like (m, n)
        Regulator gain, either sign (the paper's G = −K_R; the product is sign-free).
    B : array_like (n, m)
        Control input matrix.

    Returns
    -------
    ndarray (n, n)
        Symmetric positive semi-definite, rank <= m (rank 1 for one torque).
    """
    Gm = check_matrix(gain, "gain", None, None, "(m, n)")
    m, n = Gm.shape
    Bm = check_matrix(B, "B", n, m, f"(n, m) = ({n}, {m}), matching gain (m, n)")
    BG = Bm @ Gm
    Qxx = BG.T @ BG
    return 0.5 * (Qxx + Qxx.T)


def truncate_gains(gain: npt.ArrayLike, keep: npt.ArrayLike) -> FloatArray:
    """Regulator gain with every column outside ``keep`` set to zero (Hailey, Sortun &
    Agrawal c. 1992 Eq. 53).

    Parameters
    ----------
    gain : array_like (m, n)
    keep : sequence of int (0-based state indices) or boolean mask (n,)
        The paper's G_6 keeps states 1, 2, 3, 8, 9, 10 (1-based) of the 14-state NPS model,
        i.e. ``keep = (0, 1, 2, 7, 8, 9)``.
    """
    K = check_matrix(gain, "gain", None, None, "(m, n)").copy()
    n = K.shape[1]
    mask = _mask(keep, n)
    K[:, ~mask] = 0.0
    return K


def _mask(keep: npt.ArrayLike, n: int) -> npt.NDArray[np.bool_]:
    arr = np.asarray(keep)
    if arr.dtype == bool:
        if arr.shape != (n,):
            raise FieldError("keep", f"a boolean mask must have shape ({n},), got {arr.shape}")
        return arr.copy()
    if arr.ndim != 1 or arr.size == 0 or not np.issubdtype(arr.dtype, np.integer):
        raise FieldError(
            "keep", f"must be state indices (integers) or a boolean mask, got {keep!r}"
        )
    if np.any(arr < 0) or np.any(arr >= n):
        raise FieldError("keep", f"indices must be in 0 … {n - 1}, got {arr.tolist()}")
    mask = np.zeros(n, dtype=bool)
    mask[arr] = True
    return mask


@dataclass(frozen=True)
class RefinedEstimator:
    """Result of :func:`refine_estimator`.

    Attributes
    ----------
    gain : ndarray (m, n)     reduced regulator gain K (zero outside ``keep``), u = −K x̂
    process_noise : ndarray   Q_xx = Kᵀ Bᵀ B K used for the filter (Eq. 52)
    filter : RiccatiSolution  the recomputed Kalman design (L, P, E)
    keep : ndarray (n,) bool  states whose gains are kept
    """

    gain: FloatArray
    process_noise: FloatArray
    filter: RiccatiSolution
    keep: npt.NDArray[np.bool_]

    @property
    def L(self) -> FloatArray:
        return self.filter.gain


def refine_estimator(
    A: npt.ArrayLike,
    B: npt.ArrayLike,
    C: npt.ArrayLike,
    gain: npt.ArrayLike,
    keep: npt.ArrayLike,
    Rn: npt.ArrayLike,
    truncate: bool = True,
) -> RefinedEstimator:
    r"""The NPS estimator refinement (Hailey, Sortun & Agrawal c. 1992 Eqs. 52–53).

    1. zero the regulator gains outside ``keep`` (Eq. 53) unless ``truncate`` is false;
    2. set :math:`Q_{xx} = K^T B^T B K` with that gain (Eq. 52);
    3. recompute the continuous Kalman gain with :math:`G = I` and the same measurement-noise
       intensity Rn.

    The filter then has (near) zero gain rows for the states the regulator no longer uses —
    they are estimated open loop, as the paper says.
    """
    Am = check_square(A, "A")
    n = Am.shape[0]
    K = check_matrix(gain, "gain", None, n, f"(m, n) with n = {n}")
    mask = _mask(keep, n) if truncate else np.ones(n, bool)
    K = truncate_gains(K, mask)
    Qxx = regulator_weighted_process_noise(K, B)
    return RefinedEstimator(K, Qxx, kalman(Am, None, C, Qxx, Rn), mask)
