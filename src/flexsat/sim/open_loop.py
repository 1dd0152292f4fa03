r"""Exact open-loop response of a linear plant to a piecewise-polynomial torque.

The plant x' = A x + B u(t) (one input column) is driven by a torque that is a polynomial on
each piece [b_j, b_{j+1}] of a partition, written in the normalised local time
σ = (t − b_j)/h_j, h_j = b_{j+1} − b_j:  u = Σ_k a_jk σ^k. After the last break u = 0 (free
response). No time step is involved: the state is propagated in the plant's modal coordinates
with the variation-of-constants (Duhamel) integral evaluated in closed form,

.. math::

    \xi(t_j + s) = e^{\lambda s}\xi_j + b \sum_k a_{jk}\,\sigma^k\,k!\,s\,\varphi_{k+1}(\lambda s),
    \qquad \varphi_m(z) = \int_0^1 e^{(1-v)z}\frac{v^{m-1}}{(m-1)!}dv,

for every elastic eigenvalue λ of A (distinct, the lightly damped modes of a flexible vehicle),
since :math:`\int_0^s e^{\lambda(s-\tau)}\tau^k d\tau = k!\,s^{k+1}\varphi_{k+1}(\lambda s)`.
Zero eigenvalues (a free rigid body: θ and θ' of a hub) form a nilpotent block A_r (A_r² = 0,
a Jordan chain) whose response is the polynomial
:math:`(I + A_r s)\rho_j + \sum_k a_{jk}\sigma^k [b_r s/(k+1) + A_r b_r s^2/((k+1)(k+2))]`.
Written in σ, the coefficients carry no inverse powers of h_j, so rise times → 0 (α → 0 of the
smoothed bang-bang) stay exact; a zero-length piece leaves the state unchanged.

Used for the Junkins, Pollock & Rahman 1990 trade surfaces
(:mod:`flexsat.design.trade_surfaces`): the open-loop
flexible response to the smoothed bang-bang torque (Att. 3 Eq. 12 of
Junkins, Pollock & Rahman 1990), whose pieces :func:`torque_pieces` gives exactly.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, TypeAlias

import numpy as np
import numpy.typing as npt

from flexsat.input_checks import FieldError, require_finite
from flexsat.maneuvers.torque_shapes import BangBang, SmoothBangBang
from flexsat.sim.instruments import unit_row
from flexsat.units import FloatArray

if TYPE_CHECKING:
    from flexsat.dynamics.plant import Plant

#: modal coordinates and the eigen-quantities behind them: complex in general, real for a
#: plant with rigid modes only
InexactArray: TypeAlias = npt.NDArray[np.inexact[Any]]

#: |z| below which φ_m(z) is summed as its Taylor series (the recurrence
#: φ_{m+1} = (φ_m − 1/m!)/z cancels for small |z|); 30 terms leave 2^30/30! ≈ 4e-24
_SERIES_RADIUS, _SERIES_TERMS = 2.0, 30

#: Eq. 12 pieces of the smoothed bang-bang in σ on each piece: rise h(σ) = 3σ² − 2σ³ over Δt,
#: plateau 1, reversal 1 − 2 h(σ) over 2Δt, plateau −1, return −1 + h(σ) over Δt
_SMOOTH_PIECES = np.array(
    [
        [0.0, 0.0, 3.0, -2.0],
        [1.0, 0.0, 0.0, 0.0],
        [1.0, 0.0, -6.0, 4.0],
        [-1.0, 0.0, 0.0, 0.0],
        [-1.0, 0.0, 3.0, -2.0],
    ]
)


def torque_pieces(shape: SmoothBangBang | BangBang) -> tuple[FloatArray, FloatArray]:
    """Breaks and σ-polynomial coefficients of a smoothed bang-bang (or bang-bang) torque.

    Att. 3 Eq. 12 (Junkins, Pollock & Rahman 1990): with Δt = αT, t1 = T/2 − Δt, t2 = T/2 + Δt,
    t3 = T − Δt, u = sign(angle) u_max f with f = h(t/Δt), 1, 1 − 2h((t − t1)/(2Δt)), −1,
    −1 + h((t − t3)/Δt), h(x) = x²(3 − 2x). α = 0 (bang-bang) leaves three zero-length pieces.

    Parameters
    ----------
    shape : SmoothBangBang or BangBang
        The reference torque; its parameters may be arrays (a batch of cases).

    Returns
    -------
    breaks : (C, 6) array
        0, Δt, t1, t2, t3, T per case, s (C = the shape's number of elements, at least 1).
    coeffs : (C, 5, 4) array
        Torque coefficients a_jk of σ^k on each piece, N m.
    """
    if isinstance(shape, SmoothBangBang):
        alpha = shape.alpha
    elif isinstance(shape, BangBang):
        alpha = np.zeros_like(shape.duration)
    else:
        raise FieldError(
            "shape",
            "the exact response needs a piecewise-polynomial torque "
            f"(SmoothBangBang or BangBang), got {type(shape).__name__}",
        )
    T, a, peak = np.broadcast_arrays(shape.duration, alpha, np.sign(shape.angle) * shape.u_max)
    T, dt, peak = T.reshape(-1), (a * T).reshape(-1), peak.reshape(-1)
    breaks = np.stack([0 * T, dt, T / 2 - dt, T / 2 + dt, T - dt, T], axis=1)
    return breaks, peak[:, None, None] * _SMOOTH_PIECES


def _phi(z: InexactArray, m_max: int) -> list[InexactArray]:
    """φ_1 … φ_{m_max} of complex z (module docstring), series inside |z| < 2."""
    small = np.abs(z) < _SERIES_RADIUS
    zl = np.where(small, 1.0, z)
    zs = z[small]
    out: list[InexactArray] = []
    phi = np.exp(zl)
    for m in range(1, m_max + 1):
        phi = (phi - 1.0 / math.factorial(m - 1)) / zl
        value = phi.copy()
        if zs.size:  # Horner sum of z^j/(j+m)!, j < _SERIES_TERMS
            acc = np.zeros_like(zs)
            for j in range(_SERIES_TERMS - 1, -1, -1):
                acc = acc * zs + 1.0 / math.factorial(j + m)
            value[small] = acc
        out.append(value)
    return out


_NOT_MODAL = (
    "A: the zero eigenvalues of the plant must form a rigid-body (nilpotent, "
    "A_r² = 0) block and the others be distinct; the exact response does not apply"
)


def _nullity(s: FloatArray) -> int:
    """Number of zero singular values among ``s`` (descending): below 1e-10 of the largest,
    far under the smallest elastic one (6e-7 of it for the 10-mode TAMU A²) and far above the
    rounding of structural zeros (2e-20 of it there)."""
    return int(np.sum(s <= 1e-10 * s[0])) if s[0] > 0 else s.size


class _Modes:
    """A = V diag-ish(A_r, Λ) V⁻¹: nilpotent rigid block A_r and distinct elastic λ."""

    def __init__(self, A: FloatArray, B: FloatArray):
        n = A.shape[0]
        # rigid directions: the null space of A² (θ, θ' of a free hub span it exactly)
        _, s, vh = np.linalg.svd(A @ A)
        r = _nullity(s)
        lam, vec = np.linalg.eig(A)
        keep = np.argsort(np.abs(lam))[r:]
        self.lam = lam[keep]
        V = np.concatenate([vh[n - r :].T.astype(complex), vec[:, keep]], axis=1)
        self.V = V
        self.r = r
        # a longer Jordan chain of 0 (or a defective elastic eigenvalue) leaves V singular
        if np.linalg.cond(V) > 1e10:
            raise ValueError(_NOT_MODAL)
        self.Vinv = np.linalg.inv(V)
        Ar = (self.Vinv @ A @ V)[:r, :r].real
        if r and np.abs(Ar @ Ar).max() > 1e-9 * max(np.abs(Ar).max(), 1.0):
            raise ValueError(_NOT_MODAL)
        self.Ar = Ar
        self.b = self.Vinv @ B

    def advance(
        self, xi: InexactArray, s: FloatArray, sigma: FloatArray, a: FloatArray
    ) -> InexactArray:
        """Modal state ``s`` seconds into a piece from ``xi`` (..., n) under coefficients
        ``a`` (..., d+1), at σ = s/h (..., )."""
        r, b = self.r, self.b
        s_, sg = s[..., None], sigma[..., None]
        z = self.lam * s_
        phis = _phi(z, a.shape[-1])
        el = np.exp(z) * xi[..., r:]
        rig = xi[..., :r] + s_ * (xi[..., :r] @ self.Ar.T)
        Arb = self.Ar @ b[:r]
        for k in range(a.shape[-1]):
            w = a[..., k, None] * sg**k
            el = el + w * b[r:] * (math.factorial(k) * s_ * phis[k])
            rig = rig + w * (b[:r] * s_ / (k + 1) + Arb * s_**2 / ((k + 1) * (k + 2)))
        return np.concatenate([rig, el], axis=-1)


def piecewise_polynomial_response(
    A: npt.ArrayLike,
    B: npt.ArrayLike,
    breaks: npt.ArrayLike,
    coeffs: npt.ArrayLike,
    times: npt.ArrayLike,
    x0: npt.ArrayLike | None = None,
) -> FloatArray:
    """States of x' = A x + B u(t) at ``times`` under a piecewise-polynomial torque, exactly.

    Parameters
    ----------
    A : (n_x, n_x) array
        State matrix, shared by every case; its zero eigenvalues must form a rigid-body
        (nilpotent) block and its other eigenvalues be distinct (module docstring).
    B : (n_x,) or (n_x, 1) array
        Input column.
    breaks : (C, P+1) array
        Non-decreasing piece boundaries per case, s; the response starts at ``breaks[:, 0]``.
    coeffs : (C, P, d+1) array
        Torque coefficients of σ^k on each piece (σ = normalised time in the piece), N m.
    times : (n_t,) or (n_t, C) array
        Evaluation times, s, each >= the case's start; after the last break u = 0.
    x0 : (n_x,) or (C, n_x) array, optional
        State at the start (default rest at 0).

    Returns
    -------
    (n_t, C, n_x) array
        The states (real), exact up to rounding.
    """
    A = require_finite(A, "A")
    B = require_finite(B, "B").reshape(-1)
    breaks = require_finite(breaks, "breaks")
    coeffs = require_finite(coeffs, "coeffs")
    n = A.shape[0]
    if A.shape != (n, n) or B.shape != (n,):
        raise ValueError(
            f"A, B: need A (n_x, n_x) and one input column B (n_x,), got {A.shape} and {B.shape}"
        )
    if (
        breaks.ndim != 2
        or coeffs.ndim != 3
        or coeffs.shape[:2] != (breaks.shape[0], breaks.shape[1] - 1)
    ):
        raise FieldError(
            "coeffs",
            f"need breaks (C, P+1) and coeffs (C, P, d+1), got {breaks.shape} and {coeffs.shape}",
        )
    h = np.diff(breaks, axis=1)
    if np.any(h < 0):
        raise FieldError("breaks", "must be non-decreasing along each case")
    C, P = h.shape
    times = require_finite(times, "times")
    times = times.reshape(times.shape[0], -1) if times.ndim else times.reshape(1, 1)
    if times.shape[1] not in (1, C) or times.ndim > 2:
        raise FieldError(
            "times", f"need shape (n_t,) or (n_t, {C}) (one column per case), got {times.shape}"
        )
    times = np.broadcast_to(times, (times.shape[0], C))
    if np.any(times < breaks[:, 0]):
        raise FieldError("times", "must not precede the start of the response (breaks[:, 0])")
    modes = _Modes(A, B)
    start_state = np.zeros(n) if x0 is None else require_finite(x0, "x0")
    xi: InexactArray = np.broadcast_to(start_state @ modes.Vinv.T, (C, n))
    # modal state at every break, one piece at a time over all cases
    states = [xi]
    for piece in range(P):
        xi = modes.advance(xi, h[:, piece], np.ones(C), coeffs[:, piece])
        states.append(xi)
    at_breaks = np.stack(states, axis=1)  # (C, P+1, n)
    # piece of each time: the last break <= t (P: after the end, the free response)
    j = np.stack(
        [np.searchsorted(breaks[c], times[:, c], side="right") - 1 for c in range(C)], axis=1
    )
    j = np.clip(j, 0, P)
    cases = np.arange(C)[None, :]
    start = breaks[cases, j]
    s = times - start
    inside = j < P
    jp = np.minimum(j, P - 1)
    hj = h[cases, jp]
    sigma = np.where(inside & (hj > 0), s / np.where(hj > 0, hj, 1.0), 0.0)
    a = np.where(inside[..., None], coeffs[cases, jp], 0.0)
    xi_t = modes.advance(at_breaks[cases, j], s, sigma, a)
    return (xi_t @ modes.V.T).real


def open_loop_response(
    plant: Plant, shape: SmoothBangBang | BangBang, times: npt.ArrayLike
) -> FloatArray:
    """Exact open-loop response of a linear plant, at rest at ``shape.theta0``, to the torque
    ``shape`` (a smoothed bang-bang batch), at ``times`` (n_t,) or (n_t, C), s.

    Returns the states, (n_t, C, n_x) (C: the shape's number of elements).
    """
    if plant.nonlinear or plant.n_inputs != 1:
        raise FieldError(
            "plant",
            "the exact open-loop response needs a linear plant with one "
            "input channel (turn the rotational stiffening off)",
        )
    A, B = plant.linear_part()
    breaks, coeffs = torque_pieces(shape)
    x0 = np.zeros((breaks.shape[0], plant.nx))
    row = unit_row(plant, "theta")
    if row is not None:
        x0[:, row] = np.broadcast_to(shape.theta0, np.shape(shape.duration)).reshape(-1)
    return piecewise_polynomial_response(A, B, breaks, coeffs, times, x0)


__all__ = ["open_loop_response", "piecewise_polynomial_response", "torque_pieces"]
