"""Exponential integrators for x' = A x + B_u w + B_f N(x), w held constant over a step.

The linear part is propagated exactly with matrix exponentials (zero-order hold on w). The
nonlinear generalized force N(x) (bearing friction, rotational stiffening) is handled by the
second-order exponential Runge-Kutta scheme ETD2RK of Cox & Matthews (J. Comput. Phys. 176,
2002, Eq. 22):

    a       = e^{hA} x_n + h φ1(hA) F(x_n)
    x_{n+1} = a + h φ2(hA) (F(a) − F(x_n)),       φ1(z) = (e^z − 1)/z,  φ2(z) = (e^z − 1 − z)/z²

F(x) = B_u w + B_f N(x). It is exact when N is constant and second-order accurate otherwise; the
stiff elastic modes never limit the step because they sit in the exact linear part.
All kernels act on a leading case axis: x has shape (n_cases, n_x).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg import expm


def phi_matrices(A: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(e^{hA}, h φ1(hA), h φ2(hA)) by one block exponential (Van Loan's construction).

    expm(h [[A, I, 0], [0, 0, I], [0, 0, 0]]) = [[e^{hA}, h φ1, h² φ2], [0, I, h I], [0, 0, I]],
    valid for singular A (the rigid-body mode).
    """
    n = A.shape[0]
    C = np.zeros((3 * n, 3 * n))
    C[:n, :n] = A
    C[:n, n : 2 * n] = np.eye(n)
    C[n : 2 * n, 2 * n :] = np.eye(n)
    E = expm(h * C)
    return E[:n, :n], E[:n, n : 2 * n], E[:n, 2 * n :] / h


@dataclass(frozen=True)
class ExponentialStepper:
    """Precomputed propagators for one control period ``dt`` split into ``substeps``.

    Matrices are stored transposed so that a batch step is ``x @ Et``.
    """

    Et: np.ndarray  # e^{hA}ᵀ
    P1u: np.ndarray  # (h φ1 B_u)ᵀ, shape (n_x,)
    P1f: np.ndarray  # (h φ1 B_f)ᵀ, shape (n_f, n_x)
    P2f: np.ndarray  # (h φ2 B_f)ᵀ
    substeps: int

    @classmethod
    def build(cls, A, Bu, Bf, dt: float, substeps: int = 1) -> "ExponentialStepper":
        if substeps < 1:
            raise ValueError(f"substeps: must be >= 1, got {substeps}")
        E, P1, P2 = phi_matrices(np.asarray(A, float), dt / substeps)
        return cls(E.T.copy(), P1 @ Bu, (P1 @ Bf).T.copy(), (P2 @ Bf).T.copy(), substeps)

    def step(self, x: np.ndarray, w: np.ndarray, force=None) -> np.ndarray:
        """Advance one control period with held input w (n_cases,) and force N(x, w).

        Each substep is the exact zero-order-hold step of the linear part, plus the ETD2RK
        correction when a force is given.
        """
        drive = np.multiply.outer(w, self.P1u)  # held input: the same for every substep
        for _ in range(self.substeps):
            base = x @ self.Et + drive
            if force is None:
                x = base
                continue
            f0 = force(x, w)
            a = base + f0 @ self.P1f
            x = a + (force(a, w) - f0) @ self.P2f
        return x
