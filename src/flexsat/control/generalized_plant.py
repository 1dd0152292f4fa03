r"""The standard generalized plant of H2 and H∞ synthesis, and the closed loop with a
compensator.

The standard problem (Doyle, Glover, Khargonekar & Francis, "State-space solutions to standard
H2 and H∞ control problems", IEEE Transactions on Automatic Control 34(8), 1989, 831–847,
Eq. 1): exogenous inputs w (disturbances, noises), controlled inputs u, regulated outputs z
(errors, weighted commands) and measurements y,

.. math::

    \dot x = A x + B_1 w + B_2 u, \qquad
    z = C_1 x + D_{11} w + D_{12} u, \qquad
    y = C_2 x + D_{21} w + D_{22} u,

partitioned as python-control's ``hinfsyn(P, nmeas, ncon)`` does it: the last ``ncon`` inputs
are u, the last ``nmeas`` outputs are y. With a compensator
:math:`\dot\xi = A_k\xi + B_k y`, :math:`u = C_k\xi + D_k y` (here D22 = 0 is required, so no
algebraic loop) the closed loop from w to z, state [x, ξ], is the lower linear fractional
transformation

.. math::

    T_{zw} = \left[\begin{array}{cc|c}
      A + B_2 D_k C_2 & B_2 C_k & B_1 + B_2 D_k D_{21} \\
      B_k C_2 & A_k & B_k D_{21} \\ \hline
      C_1 + D_{12} D_k C_2 & D_{12} C_k & D_{11} + D_{12} D_k D_{21}
    \end{array}\right]

(Zhou, Doyle & Glover, *Robust and Optimal Control*, Prentice Hall, 1996, on linear fractional
transformations).

:func:`lqg_plant` builds the generalized plant whose H2-optimal compensator is the LQG
compensator of weights Q, R and noise intensities Qn, Rn (Doyle et al. 1989; Zhou, Doyle &
Glover 1996, on H2 control): :math:`z = [Q^{1/2}x;\ R^{1/2}u]`, :math:`w = [w_p; v]`,
:math:`B_1 = [G Q_n^{1/2},\ 0]`, :math:`D_{21} = [0,\ R_n^{1/2}]`; then
:math:`\|T_{zw}\|_2^2` is the LQG cost :math:`\lim E[x^TQx + u^TRu]`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from flexsat.analysis.norms import system_matrices
from flexsat.control.lqr import check_matrix, check_psd, check_square
from flexsat.input_checks import FieldError

if TYPE_CHECKING:
    import numpy.typing as npt

    import control as ct
    from flexsat.units import FloatArray

__all__ = ["GeneralizedPlant", "closed_loop", "lqg_plant", "matrix_sqrt"]


def matrix_sqrt(M: FloatArray, field: str) -> FloatArray:
    """Symmetric square root of a symmetric positive semi-definite matrix."""
    M = check_psd(np.atleast_2d(np.asarray(M, float)), field)
    lam, V = np.linalg.eigh(M)
    return np.asarray((V * np.sqrt(np.clip(lam, 0.0, None))) @ V.T, float)


@dataclass(frozen=True)
class GeneralizedPlant:
    """The standard plant (module docstring), continuous time.

    Attributes
    ----------
    A, B1, B2, C1, C2, D11, D12, D21, D22 : ndarray
        Blocks of dimensions n, n_w, n_u, n_z, n_y.
    inputs, outputs : tuple of str
        Labels of [w, u] and [z, y] (python-control names).
    """

    A: FloatArray
    B1: FloatArray
    B2: FloatArray
    C1: FloatArray
    C2: FloatArray
    D11: FloatArray
    D12: FloatArray
    D21: FloatArray
    D22: FloatArray
    inputs: tuple[str, ...]
    outputs: tuple[str, ...]

    @classmethod
    def from_statespace(cls, P: ct.StateSpace, nmeas: int, ncon: int) -> GeneralizedPlant:
        """Partition a continuous StateSpace as python-control's ``hinfsyn`` does: the last
        ``ncon`` inputs are u, the last ``nmeas`` outputs are y.

        Raises
        ------
        FieldError
            A discrete P, or counts that leave no w or z.
        """
        A, B, C, D, dt = system_matrices(P, "P")
        if dt:
            raise FieldError(
                "P", "must be continuous (dt = 0): the synthesis is in continuous time"
            )
        for name, value, total in (("nmeas", nmeas, C.shape[0]), ("ncon", ncon, B.shape[1])):
            if isinstance(value, bool) or not isinstance(value, int | np.integer):
                raise FieldError(name, f"must be an integer, got {value!r}")
            if not 0 < value < total:
                raise FieldError(
                    name,
                    f"must be in 1 … {total - 1} (P has {total} of those signals), got {value}",
                )
        nw, nz = B.shape[1] - ncon, C.shape[0] - nmeas
        return cls(
            A,
            B[:, :nw],
            B[:, nw:],
            C[:nz],
            C[nz:],
            D[:nz, :nw],
            D[:nz, nw:],
            D[nz:, :nw],
            D[nz:, nw:],
            tuple(str(s) for s in P.input_labels),
            tuple(str(s) for s in P.output_labels),
        )

    @property
    def sizes(self) -> tuple[int, int, int, int, int]:
        """(n, n_w, n_u, n_z, n_y)."""
        return (
            self.A.shape[0],
            self.B1.shape[1],
            self.B2.shape[1],
            self.C1.shape[0],
            self.C2.shape[0],
        )

    @property
    def control_names(self) -> tuple[str, ...]:
        """Labels of u."""
        return self.inputs[self.B1.shape[1] :]

    @property
    def measurement_names(self) -> tuple[str, ...]:
        """Labels of y."""
        return self.outputs[self.C1.shape[0] :]

    def statespace(self) -> ct.StateSpace:
        """P as one python-control StateSpace, inputs [w, u], outputs [z, y]."""
        import control as ct

        return ct.ss(
            self.A,
            np.hstack([self.B1, self.B2]),
            np.vstack([self.C1, self.C2]),
            np.block([[self.D11, self.D12], [self.D21, self.D22]]),
            inputs=list(self.inputs),
            outputs=list(self.outputs),
            name="P",
        )

    def require_regular(self, need_d11_zero: bool) -> None:
        """The standing assumptions of the Riccati solutions (Doyle et al. 1989; Zhou,
        Doyle & Glover 1996): D22 = 0, D12 of full column rank, D21 of full
        row rank (and D11 = 0 when asked), each failure a FieldError naming the block."""
        if np.any(self.D22 != 0):
            raise FieldError(
                "P.D22", "must be zero (a strictly proper measurement of u): loop-shift it first"
            )
        if need_d11_zero and np.any(self.D11 != 0):
            raise FieldError(
                "P.D11", "must be zero for this synthesis (w must not reach z directly)"
            )
        n_u, n_y = self.B2.shape[1], self.C2.shape[0]
        if np.linalg.matrix_rank(self.D12) < n_u:
            raise FieldError(
                "P.D12",
                "must have full column rank (every control input weighted in z), rank "
                f"{np.linalg.matrix_rank(self.D12)} < {n_u}",
            )
        if np.linalg.matrix_rank(self.D21) < n_y:
            raise FieldError(
                "P.D21",
                "must have full row rank (every measurement noisy), rank "
                f"{np.linalg.matrix_rank(self.D21)} < {n_y}",
            )


def closed_loop(P: GeneralizedPlant, K: ct.StateSpace) -> ct.StateSpace:
    """T_zw of P with the compensator K (y → u, positive feedback convention u = K y;
    module docstring)."""
    import control as ct

    Ak, Bk, Ck, Dk, dt = system_matrices(K, "K")
    if dt:
        raise FieldError("K", "must be continuous to close the loop with a continuous P")
    n_u, n_y = P.B2.shape[1], P.C2.shape[0]
    if Dk.shape != (n_u, n_y):
        raise FieldError("K", f"must map {n_y} measurements to {n_u} controls, got {Dk.shape}")
    if np.any(P.D22 != 0):
        raise FieldError("P.D22", "must be zero to close the loop without an algebraic loop")
    A = np.block([[P.A + P.B2 @ Dk @ P.C2, P.B2 @ Ck], [Bk @ P.C2, Ak]])
    B = np.vstack([P.B1 + P.B2 @ Dk @ P.D21, Bk @ P.D21])
    C = np.hstack([P.C1 + P.D12 @ Dk @ P.C2, P.D12 @ Ck])
    D = P.D11 + P.D12 @ Dk @ P.D21
    nw, nz = P.B1.shape[1], P.C1.shape[0]
    return ct.ss(A, B, C, D, inputs=list(P.inputs[:nw]), outputs=list(P.outputs[:nz]), name="T_zw")


def lqg_plant(
    A: npt.ArrayLike,
    B: npt.ArrayLike,
    C: npt.ArrayLike,
    Q: npt.ArrayLike,
    R: npt.ArrayLike,
    Qn: npt.ArrayLike,
    Rn: npt.ArrayLike,
    G: npt.ArrayLike | None = None,
    controls: tuple[str, ...] | None = None,
    measurements: tuple[str, ...] | None = None,
) -> GeneralizedPlant:
    """The generalized plant whose H2-optimal compensator is LQG (module docstring).

    Parameters
    ----------
    A, B, C : array_like
        Plant (n, n), (n, m), (p, n).
    Q, R : array_like
        State (n, n, PSD) and control (m, m, PD) weights.
    Qn, Rn : array_like
        Process-noise (g, g, PSD, on G w; G defaults to B) and measurement-noise (p, p, PD)
        intensities.
    controls, measurements : tuple of str, optional
        Names of u and y (default ``u[i]``, ``y[i]``).
    """
    a = check_square(A, "A")
    n = a.shape[0]
    b = check_matrix(B, "B", n, None, f"(n, m) with n = {n}")
    c = check_matrix(C, "C", None, n, f"(p, n) with n = {n}")
    m, p = b.shape[1], c.shape[0]
    g = b if G is None else check_matrix(G, "G", n, None, f"(n, g) with n = {n}")
    Qh = matrix_sqrt(check_matrix(Q, "Q", n, n, f"({n}, {n})"), "Q")
    Rh = matrix_sqrt(check_matrix(R, "R", m, m, f"({m}, {m})"), "R")
    Wh = matrix_sqrt(
        check_matrix(Qn, "Qn", g.shape[1], g.shape[1], f"({g.shape[1]}, {g.shape[1]})"), "Qn"
    )
    Vh = matrix_sqrt(check_matrix(Rn, "Rn", p, p, f"({p}, {p})"), "Rn")
    ng = g.shape[1]
    u_names = controls or tuple(f"u[{i}]" for i in range(m))
    y_names = measurements or tuple(f"y[{i}]" for i in range(p))
    return GeneralizedPlant(
        a,
        np.hstack([g @ Wh, np.zeros((n, p))]),
        b,
        np.vstack([Qh, np.zeros((m, n))]),
        c,
        np.zeros((n + m, ng + p)),
        np.vstack([np.zeros((n, m)), Rh]),
        np.hstack([np.zeros((p, ng)), Vh]),
        np.zeros((p, m)),
        tuple(f"w[{i}]" for i in range(ng)) + tuple(f"v[{i}]" for i in range(p)) + u_names,
        tuple(f"z_x[{i}]" for i in range(n)) + tuple(f"z_u[{i}]" for i in range(m)) + y_names,
    )
