"""Exponential integrators for x' = A x + B_u w + B_f N(x), w held constant over a step.

The linear part is propagated exactly with matrix exponentials (zero-order hold on w). The
nonlinear generalized force N(x) (bearing friction, rotational stiffening, gyroscopic terms)
enters through a constant matrix B_f and is handled by one of two exponential Runge-Kutta
schemes:

* ``"etd2rk"``, the second-order scheme of Cox & Matthews (J. Comput. Phys. 176, 2002, Eq. 22):

      a       = e^{hA} x_n + h φ1(hA) F(x_n)
      x_{n+1} = a + h φ2(hA) (F(a) − F(x_n)),      φ1(z) = (e^z − 1)/z,  φ2(z) = (e^z − 1 − z)/z²

* ``"exp_rk4"``, Krogstad's fourth-order scheme (J. Comput. Phys. 203, 2005, Eq. 20; the
  tableau in Hochbruck & Ostermann, Acta Numerica 19, 2010, Eq. 2.39), for plants whose force is
  large (the gyroscopic terms of a tumbling flexible spacecraft):

      a       = e^{hA/2} x + (h/2) φ1(hA/2) F(x)
      b       = a + h φ2(hA/2) (F(a) − F(x))
      c       = e^{hA} x + h φ1(hA) F(x) + 2 h φ2(hA) (F(b) − F(x))
      x_{n+1} = e^{hA} x + h φ1 F(x) + h φ2 (−3 F(x) + 2 F(a) + 2 F(b) − F(c))
                + 4 h φ3 (F(x) − F(a) − F(b) + F(c)),        φ3(z) = (e^z − 1 − z − z²/2)/z³

F(x) = B_u w + B_f N(x). Both are exact when N is constant (so exact for a linear plant with a
held input); the stiff elastic modes never limit the step because they sit in the exact linear
part. Only φ-products with the columns of B_u and B_f are formed (:func:`phi_products`).

All steppers act on a leading case axis: x has shape (n_cases, n_x). A dispersed plant gives A
and B with a leading case axis as well; its propagators are then per case (n_cases, n_x, n_x)
and each step is a batched product.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg import expm

#: the schemes a plant may ask for with its ``integrator`` attribute
INTEGRATORS = ("etd2rk", "exp_rk4")


def phi_products(A: np.ndarray, h: float, B: np.ndarray, n2: int = 0, order: int = 2):
    """(e^{hA}, h φ1(hA) B, h φ2(hA) B₂[, h φ3(hA) B₂]) by one block exponential; B₂ = B's
    last ``n2`` columns; φ3 is returned when ``order`` = 3.

    Van Loan's construction restricted to the input columns: with k = B's columns and
    J = [0; I_{n2}] (k × n2),

        expm(h [[A, B, 0, 0], [0, 0, J, 0], [0, 0, 0, I], [0, 0, 0, 0]])
            = [[e^{hA}, h φ1 B, h² φ2 B J, h³ φ3 B J], ...],

    an exponential of order n + k + (order − 1) n2 instead of the (order + 1) n of the full
    φ-functions. Valid for singular A (the rigid-body mode).
    """
    if order not in (2, 3):
        raise ValueError(f"order: must be 2 or 3, got {order!r}")
    n, k = B.shape
    size = n + k + (order - 1) * n2
    C = np.zeros((size, size))
    C[:n, :n] = A
    C[:n, n : n + k] = B
    C[n + k - n2 : n + k, n + k : n + k + n2] = np.eye(n2)
    if order == 3:
        C[n + k : n + k + n2, n + k + n2 :] = np.eye(n2)
    E = expm(h * C)
    out = (E[:n, :n], E[:n, n : n + k], E[:n, n + k : n + k + n2] / h)
    return out + (E[:n, n + k + n2 :] / h**2,) if order == 3 else out


def _per_case(fn, A, Bu, Bf):
    """``fn(A, Bu, Bf)`` for shared matrices, or stacked over the case axis when any of them
    carries one (a dispersed plant); each result then has a leading case axis."""
    if A.ndim == 2 and Bu.ndim == 2 and (Bf is None or Bf.ndim == 2):
        return fn(A, Bu, Bf), False
    n = max(a.shape[0] for a in (A, Bu, Bf) if a is not None and a.ndim == 3)
    pick = [None if a is None else (a if a.ndim == 2 else a[i]) for i in range(n)
            for a in (A, Bu, Bf)]
    parts = [fn(*pick[3 * i : 3 * i + 3]) for i in range(n)]
    return tuple(None if p[0] is None else np.stack(p) for p in zip(*parts)), True


def _inputs(Bu) -> np.ndarray:
    Bu = np.asarray(Bu, float)
    return Bu[..., None] if Bu.ndim == 1 else Bu


def apply(x: np.ndarray, Mt: np.ndarray, batched: bool) -> np.ndarray:
    """x @ Mt for shared Mt (k, n), or per case (x[i] @ Mt[i]) when ``batched``."""
    return np.matmul(x[:, None, :], Mt)[:, 0] if batched else x @ Mt


@dataclass(frozen=True)
class ExponentialStepper:
    """Precomputed ETD2RK propagators for one control period ``dt`` split into ``substeps``.

    Matrices are stored transposed so that a batch step is ``x @ Et``; with a leading case axis
    when the plant is dispersed (``batched``). Built without force columns (a linear run) it
    holds no φ2 product and takes no force.
    """

    Et: np.ndarray  # e^{hA}ᵀ
    P1u: np.ndarray  # (h φ1 B_u)ᵀ, shape (m, n_x)
    P1f: np.ndarray | None  # (h φ1 B_f)ᵀ, shape (n_f, n_x)
    P2f: np.ndarray | None  # (h φ2 B_f)ᵀ
    substeps: int
    batched: bool = False

    @classmethod
    def build(cls, A, Bu, Bf, dt: float, substeps: int = 1) -> "ExponentialStepper":
        """Propagators of x' = A x + B_u w + B_f N(x); ``Bf=None`` for a linear run.

        Only the products of φ1, φ2 with the input columns are formed (:func:`phi_products`):
        an exponential of order n + m for a linear run, n + m + 2 n_f with n_f force columns.
        """
        if substeps < 1:
            raise ValueError(f"substeps: must be >= 1, got {substeps}")
        h = dt / substeps

        def one(A, Bu, Bf):
            m = Bu.shape[1]
            nf = 0 if Bf is None else Bf.shape[1]
            B = Bu if Bf is None else np.hstack([Bu, Bf])
            E, P1, P2 = phi_products(A, h, B, nf)
            P1f, P2f = (P1[:, m:].T.copy(), P2.T.copy()) if Bf is not None else (None, None)
            return E.T.copy(), P1[:, :m].T.copy(), P1f, P2f

        Bf = None if Bf is None else np.asarray(Bf, float)
        mats, batched = _per_case(one, np.asarray(A, float), _inputs(Bu), Bf)
        return cls(*mats, substeps, batched)

    def drive(self, w: np.ndarray) -> np.ndarray:
        """The held input's contribution h φ1 B_u w, (n_cases, n_x); w (n_cases, m) or
        (n_cases,) for one input."""
        if w.ndim == 1:
            w = w[:, None]
        return w @ self.P1u if not self.batched else apply(w, self.P1u, True)

    def step(self, x: np.ndarray, w: np.ndarray, force=None) -> np.ndarray:
        """Advance one control period with held input w and force N(x, w) (n_cases, n_f).

        Each substep is the exact zero-order-hold step of the linear part, plus the ETD2RK
        correction when a force is given.
        """
        if force is not None and self.P1f is None:
            raise ValueError("force: this stepper was built without force columns (Bf=None)")
        drive = self.drive(w)  # held input: the same for every substep
        b = self.batched
        if not b:  # shared propagators: plain products (the common, fastest path)
            Et, P1f, P2f = self.Et, self.P1f, self.P2f
            for _ in range(self.substeps):
                if force is None:
                    x = x @ Et + drive
                    continue
                f0 = force(x, w)
                a = x @ Et + drive + f0 @ P1f
                x = a + (force(a, w) - f0) @ P2f
            return x
        for _ in range(self.substeps):
            base = apply(x, self.Et, b) + drive
            if force is None:
                x = base
                continue
            f0 = force(x, w)
            a = base + apply(f0, self.P1f, b)
            x = a + apply(force(a, w) - f0, self.P2f, b)
        return x


@dataclass(frozen=True)
class ExpRK4Stepper:
    """Krogstad's fourth-order exponential Runge-Kutta scheme (module docstring), propagators
    for one control period split into ``substeps``; transposed as in
    :class:`ExponentialStepper`."""

    E2t: np.ndarray  # e^{hA/2}ᵀ
    Et: np.ndarray  # e^{hA}ᵀ
    Q1u: np.ndarray  # ((h/2) φ1(hA/2) B_u)ᵀ
    P1u: np.ndarray  # (h φ1(hA) B_u)ᵀ
    Q1f: np.ndarray  # ((h/2) φ1(hA/2) B_f)ᵀ
    Q2f: np.ndarray  # (h φ2(hA/2) B_f)ᵀ
    P1f: np.ndarray  # (h φ1 B_f)ᵀ
    P2f: np.ndarray  # (h φ2 B_f)ᵀ
    P3f: np.ndarray  # (h φ3 B_f)ᵀ
    substeps: int
    batched: bool = False

    @classmethod
    def build(cls, A, Bu, Bf, dt: float, substeps: int = 1) -> "ExpRK4Stepper":
        """Propagators of x' = A x + B_u w + B_f N(x) with the φ-products at h/2 and h."""
        if substeps < 1:
            raise ValueError(f"substeps: must be >= 1, got {substeps}")
        if Bf is None:
            raise ValueError("force_matrix: exp_rk4 needs the plant's nonlinear force matrix")
        h = dt / substeps

        def one(A, Bu, Bf):
            m, nf = Bu.shape[1], Bf.shape[1]
            B = np.hstack([Bu, Bf])
            E2, R1, R2 = phi_products(A, h / 2, B, nf)  # τ φ1(τA) B, τ φ2(τA) B₂, τ = h/2
            E, P1, P2, P3 = phi_products(A, h, B, nf, order=3)
            t = [E2, E, R1[:, :m], P1[:, :m], R1[:, m:], 2 * R2, P1[:, m:], P2, P3]
            return tuple(M.T.copy() for M in t)

        mats, batched = _per_case(one, np.asarray(A, float), _inputs(Bu),
                                  np.asarray(Bf, float))
        return cls(*mats, substeps, batched)

    def step(self, x: np.ndarray, w: np.ndarray, force) -> np.ndarray:
        """Advance one control period with held input w and force N(x, w)."""
        w = np.asarray(w, float)
        w2 = w[:, None] if w.ndim == 1 else w
        b = self.batched
        half_drive, drive = apply(w2, self.Q1u, b), apply(w2, self.P1u, b)
        for _ in range(self.substeps):
            fx = force(x, w)
            half = apply(x, self.E2t, b) + half_drive
            a = half + apply(fx, self.Q1f, b)
            fa = force(a, w)
            bb = a + apply(fa - fx, self.Q2f, b)
            fb = force(bb, w)
            full = apply(x, self.Et, b) + drive + apply(fx, self.P1f, b)
            c = full + apply(2.0 * (fb - fx), self.P2f, b)
            fc = force(c, w)
            x = (full + apply(-3.0 * fx + 2.0 * fa + 2.0 * fb - fc, self.P2f, b)
                 + apply(4.0 * (fx - fa - fb + fc), self.P3f, b))
        return x
