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

from collections.abc import Callable
from dataclasses import dataclass
from typing import TypeAlias, TypeVar, cast

import numpy as np
import numpy.typing as npt
from scipy.linalg import expm

from flexsat.input_checks import FieldError
from flexsat.units import FloatArray

#: the schemes a plant may ask for with its ``integrator`` attribute
INTEGRATORS = ("etd2rk", "exp_rk4")

#: the nonlinear generalized force N(x, w), (n_cases, n_f) from states and held inputs
Force: TypeAlias = Callable[[FloatArray, FloatArray], FloatArray]
#: the propagators :func:`_per_case` builds for one case: a tuple of arrays (None: absent)
_Mats = TypeVar("_Mats", bound=tuple[FloatArray | None, ...])
#: the force columns B_f a propagator is built with (None for a linear run)
_Columns = TypeVar("_Columns", FloatArray, FloatArray | None)


def phi_products(
    A: FloatArray, h: float, B: FloatArray, n2: int = 0, order: int = 2
) -> tuple[FloatArray, ...]:
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
        raise FieldError("order", f"must be 2 or 3, got {order!r}")
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


def _per_case(
    fn: Callable[[FloatArray, FloatArray, _Columns], _Mats],
    A: FloatArray,
    Bu: FloatArray,
    Bf: _Columns,
) -> tuple[_Mats, bool]:
    """``fn(A, Bu, Bf)`` for shared matrices, or stacked over the case axis when any of them
    carries one (a dispersed plant); each result then has a leading case axis."""
    if A.ndim == 2 and Bu.ndim == 2 and (Bf is None or Bf.ndim == 2):
        return fn(A, Bu, Bf), False
    n = max(a.shape[0] for a in (A, Bu, Bf) if a is not None and a.ndim == 3)

    def case(a: FloatArray, i: int) -> FloatArray:
        return a if a.ndim == 2 else a[i]

    parts = [fn(case(A, i), case(Bu, i), Bf if Bf is None else case(Bf, i)) for i in range(n)]
    stacked = tuple(None if p[0] is None else np.stack(p) for p in zip(*parts))
    # each entry stacked over the cases: the same pattern of arrays and None as one case's
    return cast(_Mats, stacked), True


def _inputs(Bu: npt.ArrayLike) -> FloatArray:
    Bu = np.asarray(Bu, float)
    return Bu[..., None] if Bu.ndim == 1 else Bu


def apply(x: FloatArray, Mt: FloatArray, batched: bool) -> FloatArray:
    """x @ Mt for shared Mt (k, n), or per case (x[i] @ Mt[i]) when ``batched``."""
    return np.matmul(x[:, None, :], Mt)[:, 0] if batched else x @ Mt


@dataclass(frozen=True)
class ExponentialStepper:
    """Precomputed ETD2RK propagators for one control period ``dt`` split into ``substeps``.

    Matrices are stored transposed so that a batch step is ``x @ Et``; with a leading case axis
    when the plant is dispersed (``batched``). Built without force columns (a linear run) it
    holds no φ2 product and takes no force.
    """

    Et: FloatArray  # e^{hA}ᵀ
    P1u: FloatArray  # (h φ1 B_u)ᵀ, shape (m, n_x)
    P1f: FloatArray | None  # (h φ1 B_f)ᵀ, shape (n_f, n_x)
    P2f: FloatArray | None  # (h φ2 B_f)ᵀ
    substeps: int
    batched: bool = False

    @classmethod
    def build(
        cls,
        A: npt.ArrayLike,
        Bu: npt.ArrayLike,
        Bf: npt.ArrayLike | None,
        dt: float,
        substeps: int = 1,
    ) -> ExponentialStepper:
        """Propagators of x' = A x + B_u w + B_f N(x); ``Bf=None`` for a linear run.

        Only the products of φ1, φ2 with the input columns are formed (:func:`phi_products`):
        an exponential of order n + m for a linear run, n + m + 2 n_f with n_f force columns.
        """
        if substeps < 1:
            raise FieldError("substeps", f"must be >= 1, got {substeps}")
        h = dt / substeps

        def one(
            A: FloatArray, Bu: FloatArray, Bf: FloatArray | None
        ) -> tuple[FloatArray, FloatArray, FloatArray | None, FloatArray | None]:
            m = Bu.shape[1]
            nf = 0 if Bf is None else Bf.shape[1]
            B = Bu if Bf is None else np.hstack([Bu, Bf])
            E, P1, P2 = phi_products(A, h, B, nf)
            P1f, P2f = (P1[:, m:].T.copy(), P2.T.copy()) if Bf is not None else (None, None)
            return E.T.copy(), P1[:, :m].T.copy(), P1f, P2f

        force_columns = None if Bf is None else np.asarray(Bf, float)
        mats, batched = _per_case(one, np.asarray(A, float), _inputs(Bu), force_columns)
        return cls(*mats, substeps, batched)

    def drive(self, w: FloatArray) -> FloatArray:
        """The held input's contribution h φ1 B_u w, (n_cases, n_x); w (n_cases, m) or
        (n_cases,) for one input."""
        if w.ndim == 1:
            w = w[:, None]
        return w @ self.P1u if not self.batched else apply(w, self.P1u, True)

    def step(self, x: FloatArray, w: FloatArray, force: Force | None = None) -> FloatArray:
        """Advance one control period with held input w and force N(x, w) (n_cases, n_f).

        Each substep is the exact zero-order-hold step of the linear part, plus the ETD2RK
        correction when a force is given.
        """
        if force is not None and self.P1f is None:
            raise FieldError("force", "this stepper was built without force columns (Bf=None)")
        drive = self.drive(w)  # held input: the same for every substep
        b = self.batched
        Et, P1f, P2f = self.Et, self.P1f, self.P2f
        if force is None or P1f is None or P2f is None:  # the linear step (P1f, P2f: both)
            for _ in range(self.substeps):
                x = (x @ Et if not b else apply(x, Et, b)) + drive
            return x
        if not b:  # shared propagators: plain products (the common, fastest path)
            for _ in range(self.substeps):
                f0 = force(x, w)
                a = x @ Et + drive + f0 @ P1f
                x = a + (force(a, w) - f0) @ P2f
            return x
        for _ in range(self.substeps):
            base = apply(x, Et, b) + drive
            f0 = force(x, w)
            a = base + apply(f0, P1f, b)
            x = a + apply(force(a, w) - f0, P2f, b)
        return x


@dataclass(frozen=True)
class ExpRK4Stepper:
    """Krogstad's fourth-order exponential Runge-Kutta scheme (module docstring), propagators
    for one control period split into ``substeps``; transposed as in
    :class:`ExponentialStepper`."""

    E2t: FloatArray  # e^{hA/2}ᵀ
    Et: FloatArray  # e^{hA}ᵀ
    Q1u: FloatArray  # ((h/2) φ1(hA/2) B_u)ᵀ
    P1u: FloatArray  # (h φ1(hA) B_u)ᵀ
    Q1f: FloatArray  # ((h/2) φ1(hA/2) B_f)ᵀ
    Q2f: FloatArray  # (h φ2(hA/2) B_f)ᵀ
    P1f: FloatArray  # (h φ1 B_f)ᵀ
    P2f: FloatArray  # (h φ2 B_f)ᵀ
    P3f: FloatArray  # (h φ3 B_f)ᵀ
    substeps: int
    batched: bool = False

    @classmethod
    def build(
        cls,
        A: npt.ArrayLike,
        Bu: npt.ArrayLike,
        Bf: npt.ArrayLike | None,
        dt: float,
        substeps: int = 1,
    ) -> ExpRK4Stepper:
        """Propagators of x' = A x + B_u w + B_f N(x) with the φ-products at h/2 and h."""
        if substeps < 1:
            raise FieldError("substeps", f"must be >= 1, got {substeps}")
        if Bf is None:
            raise FieldError("force_matrix", "exp_rk4 needs the plant's nonlinear force matrix")
        h = dt / substeps

        def one(A: FloatArray, Bu: FloatArray, Bf: FloatArray) -> tuple[FloatArray, ...]:
            m, nf = Bu.shape[1], Bf.shape[1]
            B = np.hstack([Bu, Bf])
            E2, R1, R2 = phi_products(A, h / 2, B, nf)  # τ φ1(τA) B, τ φ2(τA) B₂, τ = h/2
            E, P1, P2, P3 = phi_products(A, h, B, nf, order=3)
            t = [E2, E, R1[:, :m], P1[:, :m], R1[:, m:], 2 * R2, P1[:, m:], P2, P3]
            return tuple(M.T.copy() for M in t)

        mats, batched = _per_case(one, np.asarray(A, float), _inputs(Bu), np.asarray(Bf, float))
        E2t, Et, Q1u, P1u, Q1f, Q2f, P1f, P2f, P3f = mats
        return cls(E2t, Et, Q1u, P1u, Q1f, Q2f, P1f, P2f, P3f, substeps, batched)

    def step(self, x: FloatArray, w: FloatArray, force: Force | None) -> FloatArray:
        """Advance one control period with held input w and force N(x, w) (required: the
        scheme exists for the force; a linear run takes :class:`ExponentialStepper`)."""
        if force is None:
            raise FieldError("force", "exp_rk4 needs the plant's nonlinear force N(x, w)")
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
            x = (
                full
                + apply(-3.0 * fx + 2.0 * fa + 2.0 * fb - fc, self.P2f, b)
                + apply(4.0 * (fx - fa - fb + fc), self.P3f, b)
            )
        return x


# ------------------------------------------------------------------------------------------
# modal 2×2-block propagation
#: ‖hA‖ (balanced: h max(ω, 2ζω)) up to which a block's φ-functions are summed as Taylor
#: series; beyond it the closed form has no cancellation worse than a few eps
_SERIES_RADIUS = 1.0


def _block_series(a: FloatArray, b: FloatArray, h: float) -> tuple[FloatArray, ...]:
    """(e^{hA}, h φ1(hA), h φ2(hA)) of A = [[0, 1], [−a_i, −b_i]] by Taylor series, (K, 2, 2)
    each.

    e^{M} = Σ M^j / j!, φ1 = Σ M^j / (j+1)!, φ2 = Σ M^j / (j+2)!, M = hA; for h max(√a, b) <= 1
    the terms fall as 1/j!, so 25 terms reach round-off. Exact (finite) for the rigid block.
    The 2×2 products are written out (two terms per entry): each block's numbers do not depend
    on the others.
    """
    M = np.zeros((a.size, 2, 2))
    M[:, 0, 1], M[:, 1, 0], M[:, 1, 1] = h, -h * a, -h * b
    E = np.broadcast_to(np.eye(2), M.shape).copy()
    F1, F2, P = E.copy(), 0.5 * E, E.copy()
    for j in range(1, 25):
        P = (P[:, :, :, None] * M[:, None, :, :]).sum(axis=2) / j  # M^j / j!
        E = E + P
        F1 = F1 + P / (j + 1)
        F2 = F2 + P / ((j + 1) * (j + 2))
    return E, h * F1, h * F2


def _phi_complex(z: npt.NDArray[np.complex128]) -> tuple[npt.NDArray[np.complex128], ...]:
    """(e^z, φ1(z), φ2(z)) for complex z with Re z <= 0, elementwise; series below |z| = 1/2
    (the closed forms cancel there)."""
    ez = np.exp(z)
    small = np.abs(z) < 0.5
    f1, f2 = np.empty_like(z), np.empty_like(z)
    zs, zl = z[small], z[~small]
    term, s1, s2 = np.ones_like(zs), np.zeros_like(zs), np.zeros_like(zs)
    for j in range(20):  # |z|^j / j! < 1e-24 for j = 20
        s1 = s1 + term / (j + 1)
        s2 = s2 + term / ((j + 1) * (j + 2))
        term = term * zs / (j + 1)
    f1[small], f2[small] = s1, s2
    big1 = (ez[~small] - 1.0) / zl
    f1[~small], f2[~small] = big1, (big1 - 1.0) / zl
    return ez, f1, f2


def _block_closed_form(a: FloatArray, b: FloatArray, h: float) -> tuple[FloatArray, ...]:
    """(e^{hA}, h φ1(hA), h φ2(hA)) of A = [[0, 1], [−a_i, −b_i]], a_i > 0, in closed form,
    (K, 2, 2) each.

    With σ = b/2 and (μh)² = (σ² − a) h² (underdamped < 0, critically damped 0, overdamped
    > 0) the eigenvalues are λ1,2 = −σ ± μ. Away from critical damping every function g of the
    2×2 matrix is Sylvester's interpolation

        g(A) = [g(λ1) (A − λ2 I) − g(λ2) (A − λ1 I)] / (λ1 − λ2),

    with g = e^{hλ}, h φ1(hλ), h φ2(hλ) (Cox & Matthews 2002, Eq. 22's φ definitions; the
    overdamped slow root taken as −a/(σ + μ), free of cancellation). Near critical damping
    (|μh|² < 1e-3) the denominator cancels; there Cayley–Hamilton gives
    e^{At} = e^{−σt} [C I + S (A + σ I)], C = cosh(μt), S = sinh(μt)/μ summed as series in
    (μt)², and the input integrals follow from A h φ1(hA) = e^{hA} − I, A h φ2(hA) = φ1(hA) − I
    (no cancellation: this branch has σh >= 1/2).
    """
    K = a.size
    A = np.zeros((K, 2, 2))
    A[:, 0, 1], A[:, 1, 0], A[:, 1, 1] = 1.0, -a, -b
    I2 = np.broadcast_to(np.eye(2), A.shape)
    sigma = 0.5 * b
    x = (sigma * sigma - a) * h * h  # (μh)²
    out = np.empty((3, K, 2, 2))
    crit = np.abs(x) < 1e-3
    if crit.any():
        xc, sc, ac, bc = x[crit], sigma[crit], a[crit], b[crit]
        C = 1 + xc / 2 + xc**2 / 24 + xc**3 / 720 + xc**4 / 40320
        S = h * (1 + xc / 6 + xc**2 / 120 + xc**3 / 5040 + xc**4 / 362880)
        E = np.exp(-sc * h)[:, None, None] * (
            C[:, None, None] * I2[crit]
            + S[:, None, None] * (A[crit] + sc[:, None, None] * I2[crit])
        )
        Ainv = np.zeros((xc.size, 2, 2))
        Ainv[:, 0, 0], Ainv[:, 0, 1], Ainv[:, 1, 0] = -bc / ac, -1.0 / ac, 1.0
        P1 = np.einsum("kij,kjl->kil", Ainv, E - I2[crit])
        out[0, crit], out[1, crit] = E, P1
        out[2, crit] = np.einsum("kij,kjl->kil", Ainv, P1 / h - I2[crit])
    rest = ~crit
    if rest.any():
        xr, sr, ar = x[rest], sigma[rest], a[rest]
        under = xr < 0
        mu = (
            np.where(
                under, 1j * np.sqrt(np.where(under, -xr, 0.0)), np.sqrt(np.where(under, 0.0, xr))
            )
            / h
        )
        l1 = np.where(under, -sr + mu, -ar / np.where(under, 1.0, sr + mu.real))
        l2 = -sr - mu
        g1 = _phi_complex((h * l1).astype(np.complex128))
        g2 = _phi_complex((h * l2).astype(np.complex128))
        Ar, Ir = A[rest], I2[rest]
        for k, hk in enumerate((1.0, h, h)):
            G = (
                g1[k][:, None, None] * (Ar - l2[:, None, None] * Ir)
                - g2[k][:, None, None] * (Ar - l1[:, None, None] * Ir)
            ) / (l1 - l2)[:, None, None]
            out[k, rest] = hk * G.real
    return out[0], out[1], out[2]


def block_propagators(
    omega: npt.ArrayLike, zeta: float | npt.ArrayLike, h: float
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """(e^{hA_i}, h φ1(hA_i), h φ2(hA_i)) per block A_i = [[0, 1], [−ω_i², −2ζ_i ω_i]], each
    ``omega.shape`` + (2, 2); ω = 0 is a rigid (double-integrator) block. Every block at once
    (the blocks of many cases too); each block's numbers do not depend on the others."""
    omega = np.asarray(omega, float)
    zeta = np.broadcast_to(np.asarray(zeta, float), omega.shape)
    w, z = omega.ravel(), zeta.ravel()
    a, b = w * w, 2.0 * z * w
    small = h * np.maximum(w, np.abs(b)) <= _SERIES_RADIUS
    out = np.empty((3, w.size, 2, 2))
    for mask, form in ((small, _block_series), (~small, _block_closed_form)):
        if mask.any():
            out[:, mask] = np.stack(form(a[mask], b[mask], h))
    shape = omega.shape + (2, 2)
    return out[0].reshape(shape), out[1].reshape(shape), out[2].reshape(shape)


def _refined_modes(K: np.ndarray, M: np.ndarray, steps: int = 2) -> tuple[np.ndarray, np.ndarray]:
    """Undamped modes K φ = λ M φ (Φᵀ M Φ = I), each refined by Newton steps; K, M (N, n, n)
    (a stack of problems), λ (N, n) ascending, Φ (N, n, n).

    The eigenproblem is reduced with the Cholesky factor M = L Lᵀ (Kt = L⁻¹ K L⁻ᵀ, Φ = L⁻ᵀ Y),
    one LAPACK call per problem of the stack. ``eigh`` leaves errors ~ eps ‖K‖ / gap in a low
    mode: with the stiff modes of a fine model (‖K‖ ~ ω_max² ~ 1e11 at 100 modes per
    appendage) that is 1e-8. The residual K φ − λ M φ of a low mode is computed far more
    accurately (its entries on stiff rows multiply small components), so Newton's correction
    of the bordered system

        [[K − λ M, −M φ], [−(M φ)ᵀ, 0]] [δφ; δλ] = [−(K − λ M) φ; (φᵀ M φ − 1) / 2]

    restores the mode to round-off of its own scale (iterative refinement of an eigenpair).
    """
    Linv = np.linalg.inv(np.linalg.cholesky(M))
    LinvT = np.swapaxes(Linv, -1, -2)
    Kt = Linv @ K @ LinvT
    lam, Y = np.linalg.eigh(0.5 * (Kt + np.swapaxes(Kt, -1, -2)))
    Phi = LinvT @ Y
    N, n = lam.shape
    J = np.zeros((N, n, n + 1, n + 1))  # one bordered system per mode, solved as one batch
    rhs = np.zeros((N, n, n + 1))
    for _ in range(steps):
        MPhi = M @ Phi
        J[:, :, :n, :n] = K[:, None] - lam[:, :, None, None] * M[:, None]
        J[:, :, :n, n] = J[:, :, n, :n] = -np.swapaxes(MPhi, -1, -2)
        rhs[:, :, :n] = -np.swapaxes(K @ Phi - MPhi * lam[:, None, :], -1, -2)
        rhs[:, :, n] = 0.5 * (np.einsum("cij,cij->cj", Phi, MPhi) - 1.0)
        d = np.linalg.solve(J, rhs[..., None])[..., 0]
        Phi = Phi + np.swapaxes(d[:, :, :n], -1, -2)
        lam = lam + d[:, :, n]
    return lam, Phi


def modal_coordinates(
    M: npt.ArrayLike, K: npt.ArrayLike, C: npt.ArrayLike, rigid_tol: float = 1e-12
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Similarity x = T z that makes the first-order form of M q'' + C q' + K q = f
    block-diagonal with companion 2×2 blocks.

    x = [q; q'], A = [[0, I], [−M⁻¹K, −M⁻¹C]]. Returns (T, T_inv, omega, zeta) with
    T⁻¹ A T = diag([[0, 1], [−ω_i², −2ζ_i ω_i]]), rigid blocks (ω = 0) first, then ascending
    ω; use T_inv (formed from the factors, see below) rather than inverting T. M, K, C may be
    stacks (N, n, n) of problems with the same number of rigid modes (the cases of a dispersed
    plant): every result then has a leading case axis, each case computed alone (batched
    LAPACK calls, elementwise operations), so its numbers do not depend on the stack.

    Two stages, because the eigenvectors of A itself are only accurate to eps ‖A‖ / gap
    (‖A‖ ~ ω_max²: at 100 modes per appendage the low modes lose 8 digits):

    1. the undamped modes of (K, M) (``eigh`` refined by Newton steps, see
       :func:`_refined_modes`; Φᵀ M Φ = I, Φᵀ K Φ = Λ) in the balanced
       coordinates x̃ = [√Λ η; η'] (q = Φ η; √Λ → 1 for a rigid mode), where
       Ã = [[0, √Λ], [−√Λ, −ΦᵀCΦ]] has ‖Ã‖ ~ ω_max;
    2. with non-proportional damping (the hub + appendage plant: its damping is diagonal in
       cantilever, not in free-free coordinates) the elastic part of Ã is still coupled by
       ΦᵀCΦ; each complex pair λ, λ̄ of its eigenvalues (eigenvector v = [u; λ w]) gives
       a = |λ|², b = −2 Re λ and columns v2 = Re(−i v / Im λ), v1 = (Ã + b) v2 (then
       Ã v1 = −a v2 by Cayley–Hamilton on the pair's invariant plane), v phased so that its
       position half is as real as can be: for proportional damping v1 = [u; 0],
       v2 = [0; u], z1 the modal coordinate and z2 its rate.

    A rigid mode (Kφ = 0) must carry no damping (Cφ = 0); overdamped (real) elastic
    eigenvalues are rejected (pair them by hand with :func:`block_propagators`).
    """
    M, K, C = (np.asarray(a, float) for a in (M, K, C))
    single = M.ndim == 2
    if single:
        M, K, C = M[None], K[None], C[None]
    N, n = M.shape[0], M.shape[-1]
    lam, Phi = _refined_modes(K, M)
    rigid = lam <= rigid_tol * np.maximum(lam.max(axis=1, keepdims=True), 0.0)
    r = int(rigid[0].sum())
    if not (rigid[:, :r].all() and not rigid[:, r:].any()):
        raise FieldError("K", "the cases of a stack must have the same number of rigid modes")
    lam = np.where(rigid, 0.0, lam)
    s = np.where(rigid, 1.0, np.sqrt(lam))
    Ct = np.swapaxes(Phi, -1, -2) @ C @ Phi
    scale = np.abs(Ct).max(axis=(1, 2))
    if (np.abs(Ct[:, :r]).max(axis=(1, 2), initial=0.0) > rigid_tol * scale).any():
        raise FieldError(
            "C",
            "damps a rigid-body mode (C φ ≠ 0 for K φ = 0); modal_coordinates "
            "needs undamped rigid modes",
        )
    ne = n - r
    At = np.zeros((N, 2 * ne, 2 * ne))
    i = np.arange(ne)
    At[:, i, ne + i] = s[:, r:]
    At[:, ne + i, i] = -s[:, r:]
    At[:, ne:, ne:] = -Ct[:, r:, r:]
    mu, V = np.linalg.eig(At)
    real = np.abs(mu.imag) <= rigid_tol * np.abs(mu)
    if real.any():
        raise FieldError(
            "C",
            f"overdamped (real) modes {mu[real].real}; modal_coordinates "
            "handles oscillatory modes only",
        )
    # the upper eigenvalue of each pair, ascending |λ|
    order = np.argsort(np.where(mu.imag > 0, np.abs(mu), np.inf), axis=1, kind="stable")[:, :ne]
    lm = np.take_along_axis(mu, order, axis=1)  # (N, ne)
    v = np.take_along_axis(V, order[:, None, :], axis=2)  # (N, 2 ne, ne)
    pos = v[:, :ne]
    phase = np.exp(-0.5j * np.angle(np.sum(pos**2, axis=1))) / np.linalg.norm(pos, axis=1)
    v = v * phase[:, None, :]
    a, b = np.abs(lm) ** 2, -2.0 * lm.real
    v2 = (-1j * v / lm.imag[:, None, :]).real
    v1 = At @ v2 + b[:, None, :] * v2
    Tt = np.zeros((N, 2 * n, 2 * n))  # columns in x̃ = [√Λ η; η']
    j = np.arange(r)
    Tt[:, j, 2 * j] = Tt[:, n + j, 2 * j + 1] = 1.0
    el, cols = r + i, 2 * r + 2 * i
    Tt[:, el[:, None], cols[None, :]] = v1[:, :ne]
    Tt[:, (n + el)[:, None], cols[None, :]] = v1[:, ne:]
    Tt[:, el[:, None], cols[None, :] + 1] = v2[:, :ne]
    Tt[:, (n + el)[:, None], cols[None, :] + 1] = v2[:, ne:]
    w = np.sqrt(a)
    omega = np.concatenate([np.zeros((N, r)), w], axis=1)
    zeta = np.concatenate([np.zeros((N, r)), b / (2 * w)], axis=1)
    S = np.zeros((N, 2 * n, 2 * n))  # x = S x̃
    S[:, :n, :n] = Phi / s[:, None, :]
    S[:, n:, n:] = Phi
    # T⁻¹ = T̃⁻¹ S⁻¹ with S⁻¹ = diag(√Λ Φᵀ M, Φᵀ M) (Φᵀ M Φ = I): inverting T itself would
    # cost cond(T) ~ ω_max / ω_min digits, inverting T̃ only those of the damped mode shapes
    Sinv = np.zeros_like(S)
    PhiTM = np.swapaxes(Phi, -1, -2) @ M
    Sinv[:, :n, :n] = PhiTM * s[:, :, None]
    Sinv[:, n:, n:] = PhiTM
    out = (S @ Tt, np.linalg.solve(Tt, Sinv), omega, zeta)
    return (out[0][0], out[1][0], out[2][0], out[3][0]) if single else out


@dataclass(frozen=True)
class ModalPropagator:
    """Exact zero-order-hold step of a modal plant, O(n) per step.

    The plant z' = A_z z + B w + B_f N with A_z = diag([[0, 1], [−ω_i², −2ζ_i ω_i]]) (a rigid
    block has ω = 0): each 2×2 block is propagated by its closed-form exponential and input
    integrals (:func:`block_propagators`), so one step costs 4 n + n m multiply-adds instead of
    the n² of :class:`ExponentialStepper`. Arrays are laid out for
    :func:`flexsat.sim.kernels.closed_loop` with ``block_diagonal=True``.

    Attributes
    ----------
    E : (n, 2)      row i of e^{hA_z} restricted to its block's two columns
    P1u : (n, m)    h φ1(hA_z) B
    P1f, P2f : (n, n_f) or None     h φ1(hA_z) B_f, h φ2(hA_z) B_f
    substeps : int
    """

    E: FloatArray
    P1u: FloatArray
    P1f: FloatArray | None
    P2f: FloatArray | None
    substeps: int

    @classmethod
    def build(
        cls,
        omega: npt.ArrayLike,
        zeta: float | npt.ArrayLike,
        B: npt.ArrayLike,
        dt: float,
        substeps: int = 1,
        Bf: npt.ArrayLike | None = None,
    ) -> ModalPropagator:
        """Propagators of the modal plant with block frequencies ``omega`` (rad/s), damping
        ratios ``zeta``, input columns ``B`` (n, m) and force columns ``Bf`` (n, n_f); with a
        leading case axis on all of them (omega (N, n/2), B (N, n, m)), each case's (the
        propagators of a dispersed plant, :attr:`E` (N, n, 2), :attr:`P1u` (N, n, m), ...).
        The 2×2 block products are written out, so a case's numbers do not depend on the
        others."""
        if substeps < 1:
            raise FieldError("substeps", f"must be >= 1, got {substeps}")
        omega = np.asarray(omega, float)
        E2, F1, F2 = block_propagators(omega, zeta, dt / substeps)
        lead, nb = omega.shape[:-1], omega.shape[-1]
        n = 2 * nb
        inputs = np.asarray(B, float).reshape(lead + (n, -1))

        def apply(F: FloatArray, X: FloatArray) -> FloatArray:
            # block-diagonal F (..., nb, 2, 2) times X (..., n, k)
            Xb = X.reshape(lead + (nb, 1, 2, X.shape[-1]))
            return (F[..., :, :, None] * Xb).sum(axis=-2).reshape(lead + (n, -1))

        P1f = P2f = None
        if Bf is not None:
            forces = np.asarray(Bf, float).reshape(lead + (n, -1))
            P1f, P2f = apply(F1, forces), apply(F2, forces)
        return cls(E2.reshape(lead + (n, 2)), apply(F1, inputs), P1f, P2f, substeps)

    def step(self, z: FloatArray, w: FloatArray, force: Force | None = None) -> FloatArray:
        """Advance z (n_cases, n) one control period with held input w (n_cases, m); ``force``
        (z, w) -> (n_cases, n_f) adds the ETD2RK correction as in :class:`ExponentialStepper`."""
        if force is not None and self.P1f is None:
            raise FieldError("force", "this propagator was built without force columns (Bf=None)")
        Eb = self.E.reshape(-1, 2, 2)
        drive = w @ self.P1u.T
        P1f, P2f = self.P1f, self.P2f
        for _ in range(self.substeps):
            zb = z.reshape(z.shape[0], -1, 2)
            base = np.einsum("bij,cbj->cbi", Eb, zb).reshape(z.shape) + drive
            if force is None or P1f is None or P2f is None:  # linear (built without Bf)
                z = base
                continue
            f0 = force(z, w)
            a = base + f0 @ P1f.T
            z = a + (force(a, w) - f0) @ P2f.T
        return z
