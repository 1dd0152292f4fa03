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


def phi_products(A: np.ndarray, h: float, B: np.ndarray, n2: int = 0
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(e^{hA}, h φ1(hA) B, h φ2(hA) B₂) by one block exponential; B₂ = B's last ``n2`` columns.

    Van Loan's construction restricted to the input columns: with k = B's columns and
    J = [0; I_{n2}] (k × n2),

        expm(h [[A, B, 0], [0, 0, J], [0, 0, 0]]) = [[e^{hA}, h φ1 B, h² φ2 B J], ...],

    an exponential of order n + k + n2 instead of the 3n of the full φ1, φ2 (B = I, n2 = n
    is that full construction). Valid for singular A (the rigid-body mode).
    """
    n, k = B.shape
    C = np.zeros((n + k + n2, n + k + n2))
    C[:n, :n] = A
    C[:n, n : n + k] = B
    C[n + k - n2 : n + k, n + k :] = np.eye(n2)
    E = expm(h * C)
    return E[:n, :n], E[:n, n : n + k], E[:n, n + k :] / h


@dataclass(frozen=True)
class ExponentialStepper:
    """Precomputed propagators for one control period ``dt`` split into ``substeps``.

    Matrices are stored transposed so that a batch step is ``x @ Et``. Built without force
    columns (a linear run) it holds no φ2 product and takes no force.
    """

    Et: np.ndarray  # e^{hA}ᵀ
    P1u: np.ndarray  # (h φ1 B_u)ᵀ, shape (n_x,)
    P1f: np.ndarray | None  # (h φ1 B_f)ᵀ, shape (n_f, n_x)
    P2f: np.ndarray | None  # (h φ2 B_f)ᵀ
    substeps: int

    @classmethod
    def build(cls, A, Bu, Bf, dt: float, substeps: int = 1) -> "ExponentialStepper":
        """Propagators of x' = A x + B_u w + B_f N(x); ``Bf=None`` for a linear run.

        Only the products of φ1, φ2 with the input columns are formed (:func:`phi_products`):
        an exponential of order n + 1 for a linear run, n + 1 + 2 n_f with n_f force columns.
        """
        if substeps < 1:
            raise ValueError(f"substeps: must be >= 1, got {substeps}")
        A = np.asarray(A, float)
        Bu = np.asarray(Bu, float).reshape(-1, 1)
        nf = 0 if Bf is None else np.shape(Bf)[1]
        B = Bu if Bf is None else np.hstack([Bu, np.asarray(Bf, float)])
        E, P1, P2 = phi_products(A, dt / substeps, B, nf)
        P1f, P2f = (P1[:, 1:].T.copy(), P2.T.copy()) if Bf is not None else (None, None)
        return cls(E.T.copy(), P1[:, 0].copy(), P1f, P2f, substeps)

    def step(self, x: np.ndarray, w: np.ndarray, force=None) -> np.ndarray:
        """Advance one control period with held input w (n_cases,) and force N(x, w).

        Each substep is the exact zero-order-hold step of the linear part, plus the ETD2RK
        correction when a force is given.
        """
        if force is not None and self.P1f is None:
            raise ValueError("force: this stepper was built without force columns (Bf=None)")
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
