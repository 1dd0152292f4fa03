r"""Exact natural modes of a uniform Euler–Bernoulli cantilever with a tip body, and of a free hub.

Cantilever with tip mass and rotary inertia
-------------------------------------------
A uniform beam of length :math:`L`, bending stiffness :math:`EI` and mass per length
:math:`\rho` is clamped at :math:`\xi = 0` and carries at :math:`\xi = L` a point mass
:math:`m \ge 0` with rotary inertia :math:`J \ge 0`.  For harmonic motion
:math:`y(\xi) e^{i\omega t}`

.. math::

    EI\, y'''' = \rho \omega^2 y, \qquad \beta^4 = \rho \omega^2 / EI,

    y(0) = y'(0) = 0, \qquad EI\, y''(L) = J \omega^2 y'(L), \qquad EI\, y'''(L) = -m \omega^2 y(L).

Bounded basis
-------------
The textbook cosh/sinh form of the frequency equation loses all accuracy for
:math:`\beta L \gtrsim 15` (it subtracts numbers of size :math:`e^{\beta L}`).  Here every
solution of the ODE is written in the basis

.. math::

    y = a_1 e^{-\beta \xi} + a_2 e^{-\beta (L - \xi)} + a_3 \cos \beta \xi + a_4 \sin \beta \xi,

whose functions and scaled derivatives :math:`y^{(j)} / \beta^j` are bounded by 1 on
:math:`[0, L]`.  With :math:`z = \beta L`, :math:`E = e^{-z}`, :math:`c = \cos z`,
:math:`s = \sin z`, :math:`\mu = m / (\rho L)`, :math:`\iota = J / (\rho L^3)`,
:math:`\hat m = \mu z` and :math:`\hat J = \iota z^3`, the four boundary conditions (each divided
by :math:`EI \beta^j` and by a smooth positive factor so that all entries are bounded) are

.. math::

    \begin{bmatrix}
      1 & E & 1 & 0 \\
      -1 & E & 0 & 1 \\
      E & (1 - \hat J) / (1 + \hat J)
        & (-c + \hat J s) / (1 + \hat J) & (-s - \hat J c) / (1 + \hat J) \\
      E (\hat m - 1) / (1 + \hat m) & 1 & (s + \hat m c) / (1 + \hat m)
        & (\hat m s - c) / (1 + \hat m)
    \end{bmatrix} a = 0 .

Its determinant :math:`\Delta(z)` is the (bounded, smooth) frequency function; the natural
frequencies are its roots and the mode coefficients :math:`a` its null vectors (SVD).

Root finding and root counting
------------------------------
:math:`\Delta` is sampled on a grid of step :math:`\pi/32` in :math:`z`, sign changes are
refined with :func:`scipy.optimize.brentq` to full double precision, and the number of roots
found is checked against the Wittrick–Williams count

.. math::

    N(\omega) = J_0(\omega) + s\{K(\omega)\},

where :math:`J_0` is the number of clamped–clamped beam frequencies below :math:`\omega`
(closed form) and :math:`s\{K\}` the number of negative eigenvalues of the exact dynamic stiffness
matrix of the structure at its free nodal degrees of freedom.  Any grid interval whose sign
changes disagree with the count is subdivided, so closely spaced roots are not missed.

Free hub with n appendages
--------------------------
:func:`hub_free_frequencies` treats a rigid hub (inertia :math:`I_h`, free rotation
:math:`\theta`) carrying :math:`n` identical beams clamped radially at radius :math:`l_0`, all
deforming alike (anti-symmetric motion).  The inertial displacement
:math:`w(\xi) = y(\xi) + (l_0 + \xi)\theta` satisfies the same beam equation, with

.. math::

    w(0) = l_0 \theta, \quad w'(0) = \theta, \quad EI\, w''(L) = J\omega^2 w'(L), \quad
    EI\, w'''(L) = -m \omega^2 w(L),

    -\omega^2 I_h \theta + n\, EI\, \bigl(l_0 w'''(0) - w''(0)\bigr) = 0,

the last being the hub equation :math:`I_h \theta'' = u + n (M_0 - l_0 S_0)` with
:math:`M_0 = EI y''(0)`, :math:`S_0 = EI y'''(0)` and :math:`u = 0`.  The unknowns are the four
basis coefficients and :math:`\varphi = \theta L`; see :func:`_hub_matrix` for the bounded
5x5 system.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import lru_cache
from numbers import Integral

import numpy as np
import numpy.typing as npt
from scipy.optimize import brentq

from flexsat.input_checks import (
    FieldError,
    require_count,
    require_finite,
    require_nonneg,
    require_positive,
)
from flexsat.units import FloatArray

__all__ = [
    "CLAMPED_FREE_BETA_L",
    "FREE_FREE_BETA_L",
    "CantileverModes",
    "CantileverModesBatch",
    "TipMassCantilever",
    "cantilever_modes_batch",
    "clamped_free_beta_L",
    "hub_free_frequencies",
]

#: Roots β_i L of the clamped–free frequency equation 1 + cos z cosh z = 0 (tabulated values).
CLAMPED_FREE_BETA_L = (1.875104069, 4.694091133, 7.854757438, 10.99554073, 14.13716839)
#: Roots β_i L of the free–free (= clamped–clamped) equation 1 − cos z cosh z = 0, z > 0.
FREE_FREE_BETA_L = (4.730040745, 7.853204624, 10.99560784, 14.13716549)

_SCAN_STEP = math.pi / 32  # grid step in z = βL for the sign-change scan
_SUBDIVIDE = 8  # sub-intervals per refinement of an inconsistent grid interval
_MAX_DEPTH = 8  # refinement levels (interval shrinks by 8**8 ≈ 1.7e7)
#: relative bracket width at which the vectorised root refinement stops (that of brentq here)
BATCH_ROOT_RTOL = 4 * np.finfo(float).eps
_BATCH_MAX_ITER = 200  # Illinois steps; each at least halves a stalled side: never reached

IntArray = npt.NDArray[np.int_]


# ------------------------------------------------------------------------------------------------
# input checks
def _real(value: float, field: str) -> float:
    return float(require_finite(value, field))


def _positive(value: float, field: str) -> float:
    return float(require_positive(value, field))


def _nonneg(value: float, field: str) -> float:
    return float(require_nonneg(value, field))


# ------------------------------------------------------------------------------------------------
# bounded boundary-condition matrices (vectorised over z = βL)
def _tip_rows(
    z: FloatArray, mu: float | FloatArray, iota: float | FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Tip moment and shear rows, each divided by a positive factor (1 + Ĵ), (1 + m̂); μ, ι
    scalars or one per entry of z."""
    E, c, s = np.exp(-z), np.cos(z), np.sin(z)
    jh, mh = iota * z**3, mu * z
    moment = np.stack([E * (1 + jh), 1 - jh, -c + jh * s, -s - jh * c], -1) / (1 + jh)[..., None]
    shear = np.stack([E * (mh - 1), 1 + mh, s + mh * c, mh * s - c], -1) / (1 + mh)[..., None]
    return moment, shear


def _cantilever_matrix(z: npt.ArrayLike, mu: float, iota: float) -> FloatArray:
    """Bounded 4x4 boundary-condition matrix of the tip-mass cantilever, shape (..., 4, 4)."""
    z = np.asarray(z, dtype=float)
    E, one, zero = np.exp(-z), np.ones_like(z), np.zeros_like(z)
    moment, shear = _tip_rows(z, mu, iota)
    return np.stack(
        [np.stack([one, E, one, zero], -1), np.stack([-one, E, zero, one], -1), moment, shear], -2
    )


def _hub_matrix(z: npt.ArrayLike, mu: float, iota: float, r: float, eta: float) -> FloatArray:
    r"""Bounded 5x5 matrix of the free hub problem, unknowns (a_1..a_4, φ = θL).

    With r = l0/L and η = I_h / (n ρ L³), the rows are

    * w(0) − l0 θ = 0:                 [1, E, 1, 0, −r] / (1 + r)
    * (w'(0) − θ)/β = 0 (times z):     [−z, zE, 0, z, −1] / (1 + z)
    * tip moment and shear rows of the cantilever, with 0 in the φ column
    * hub equation / (n EI β²):        [−(1 + rz), E(rz − 1), 1, −rz, −η z²] / (1 + rz + η z²)
    """
    z = np.asarray(z, dtype=float)
    E, one, zero = np.exp(-z), np.ones_like(z), np.zeros_like(z)
    rz = r * z
    moment, shear = _tip_rows(z, mu, iota)
    rows = [
        np.stack([one, E, one, zero, -r * one], -1) / (1 + r),
        np.stack([-z, z * E, zero, z, -one], -1) / (1 + z)[..., None],
        np.concatenate([moment, zero[..., None]], -1),
        np.concatenate([shear, zero[..., None]], -1),
        np.stack([-(1 + rz), E * (rz - 1), one, -rz, -eta * z**2], -1)
        / (1 + rz + eta * z**2)[..., None],
    ]
    return np.stack(rows, -2)


# ------------------------------------------------------------------------------------------------
# Wittrick–Williams root count
def _clamped_clamped_count(z: npt.ArrayLike) -> IntArray:
    """Number of roots of cos z cosh z = 1 in (0, z) (clamped–clamped beam frequencies below).

    J0 = i − (1 − (−1)^i sgn(1 − cos z cosh z)) / 2 with i = ⌊z/π⌋; the sign is evaluated as
    sgn(sech z − cos z) (no overflow).  The first root is 4.73, so J0 = 0 for z < 1.
    """
    z = np.asarray(z, dtype=float)
    i = np.floor(z / np.pi)
    e = np.exp(-z)
    sg = np.sign(2 * e / (1 + e * e) - np.cos(z))
    j0 = i - (1 - (-1.0) ** i * sg) / 2
    return np.where(z < 1.0, 0, np.rint(j0)).astype(int)


def _element_dynamic_stiffness(z: npt.ArrayLike) -> FloatArray:
    r"""Exact dynamic stiffness of a free beam element, scaled, shape (..., 4, 4).

    End degrees of freedom q = (w(0), w'(0)/β, w(L), w'(L)/β); the conjugate end forces, divided
    by EI β³, are (w'''(0)/β³, −w''(0)/β², −w'''(L)/β³, w''(L)/β²).  Both are bounded matrices
    A, B in the basis coefficients and K = B A⁻¹ (symmetric; A is singular only at the
    clamped–clamped frequencies, the poles of K).
    """
    z = np.asarray(z, dtype=float)
    E, c, s, one, zero = np.exp(-z), np.cos(z), np.sin(z), np.ones_like(z), np.zeros_like(z)
    A = np.stack(
        [
            np.stack([one, E, one, zero], -1),
            np.stack([-one, E, zero, one], -1),
            np.stack([E, one, c, s], -1),
            np.stack([-E, one, -s, c], -1),
        ],
        -2,
    )
    B = np.stack(
        [
            np.stack([-one, E, zero, -one], -1),
            np.stack([-one, -E, one, zero], -1),
            np.stack([E, -one, -s, c], -1),
            np.stack([E, one, -c, -s], -1),
        ],
        -2,
    )
    K = np.swapaxes(np.linalg.solve(np.swapaxes(A, -1, -2), np.swapaxes(B, -1, -2)), -1, -2)
    return 0.5 * (K + np.swapaxes(K, -1, -2))


def _negative_count(K: FloatArray) -> IntArray:
    return (np.linalg.eigvalsh(K) < 0).sum(-1)


def _cantilever_count(
    z: npt.ArrayLike, mu: float | FloatArray, iota: float | FloatArray
) -> IntArray:
    """Number of tip-mass cantilever frequencies with βL < z (Wittrick–Williams); μ, ι
    scalars or one per entry of z."""
    z = np.asarray(z, dtype=float)
    K = _element_dynamic_stiffness(z)[..., 2:, 2:].copy()
    K[..., 0, 0] -= mu * z
    K[..., 1, 1] -= iota * z**3
    return _clamped_clamped_count(z) + _negative_count(K)


def _hub_count(z: npt.ArrayLike, mu: float, iota: float, r: float, eta: float) -> IntArray:
    """Number of free-hub frequencies with βL < z, rigid-body mode included (Wittrick–Williams).

    Degrees of freedom (θ/β, w(L), w'(L)/β); the root is slaved to the hub by
    w(0) = l0 θ = (r z)(θ/β), w'(0)/β = θ/β.  Everything is divided by n EI β³.
    """
    z = np.asarray(z, dtype=float)
    K = _element_dynamic_stiffness(z)
    K[..., 2, 2] -= mu * z
    K[..., 3, 3] -= iota * z**3
    T = np.zeros(z.shape + (4, 3))
    T[..., 0, 0] = r * z
    T[..., 1, 0] = 1.0
    T[..., 2, 1] = 1.0
    T[..., 3, 2] = 1.0
    K3 = np.swapaxes(T, -1, -2) @ K @ T
    K3[..., 0, 0] -= eta * z**3
    return _clamped_clamped_count(z) + _negative_count(0.5 * (K3 + np.swapaxes(K3, -1, -2)))


# ------------------------------------------------------------------------------------------------
# root finder
def _find_roots(
    matrix: Callable[[npt.ArrayLike], FloatArray],
    count: Callable[[npt.ArrayLike], IntArray],
    k: int,
    z_start: float,
) -> FloatArray:
    """First k roots z > z_start of det(matrix(z)), with count(z) = number of roots in (z_start, z).

    Sign changes on a grid of step π/32 are refined with brentq (relative tolerance 4 eps);
    grid intervals where the number of sign changes disagrees with the count are subdivided.
    """

    def det(z: npt.ArrayLike) -> FloatArray:
        return np.linalg.det(matrix(np.atleast_1d(np.asarray(z, dtype=float))))

    def solve(
        a: float, b: float, da: float, db: float, na: int, nb: int, depth: int
    ) -> list[float]:
        n = nb - na
        if n == 0 and da * db > 0:
            return []
        if n == 1 and da * db <= 0:
            if da == 0.0:
                return [a]
            if db == 0.0:
                return [b]
            eps4 = 4 * np.finfo(float).eps
            return [brentq(lambda t: det(t)[0], a, b, xtol=1e-300, rtol=eps4, maxiter=500)]
        if depth >= _MAX_DEPTH:
            raise RuntimeError(
                f"beam frequency equation: cannot isolate {n} root(s) in βL ∈ [{a:.15g}, {b:.15g}]"
                " (multiple or numerically coincident roots)"
            )
        sub = np.linspace(a, b, _SUBDIVIDE + 1)
        ds, cs = det(sub), count(sub)
        ds[0], ds[-1], cs[0], cs[-1] = da, db, na, nb
        out = []
        for i in range(_SUBDIVIDE):
            out += solve(sub[i], sub[i + 1], ds[i], ds[i + 1], cs[i], cs[i + 1], depth + 1)
        return out

    c0 = int(count(np.array([z_start]))[0])
    if c0 != 0:
        raise RuntimeError(f"beam frequency equation: {c0} root(s) below scan start βL={z_start}")
    roots: list[float] = []
    lo = z_start
    while len(roots) < k:  # extend the scan in chunks until the count reaches k
        npts = int(math.ceil((k - len(roots) + 1) * math.pi / _SCAN_STEP))
        grid = lo + _SCAN_STEP * np.arange(npts + 1)
        d, c = det(grid), count(grid)
        for i in range(npts):
            roots += solve(grid[i], grid[i + 1], d[i], d[i + 1], c[i], c[i + 1], 0)
        if len(roots) != c[-1]:
            raise RuntimeError("beam frequency equation: root count mismatch")
        lo = grid[-1]
    return np.sort(np.asarray(roots))[:k]


# ------------------------------------------------------------------------------------------------
# public API
@dataclass(frozen=True, eq=False)
class CantileverModes:
    r"""Mass-normalized modes of a :class:`TipMassCantilever`.

    Mode i is

    .. math::

        \phi_i(\xi) = a_{i1} e^{-\beta_i \xi} + a_{i2} e^{-\beta_i (L - \xi)}
                      + a_{i3} \cos \beta_i \xi + a_{i4} \sin \beta_i \xi,

    normalized so that :math:`\int_0^L \rho \phi_i^2 d\xi + m \phi_i(L)^2 + J \phi_i'(L)^2 = 1`
    and signed so that :math:`\phi_i(L) > 0` (or :math:`\phi_i'(L) > 0` if :math:`\phi_i(L) = 0`).

    Attributes
    ----------
    length : float
        Beam length L, m.
    betas : ndarray, shape (k,)
        Wavenumbers β_i, 1/m.
    omegas : ndarray, shape (k,)
        Natural frequencies ω_i = β_i² √(EI/ρ), rad/s.
    coefficients : ndarray, shape (k, 4)
        Basis coefficients (a_i1, a_i2, a_i3, a_i4), units of 1/√(kg) (φ has units kg^-1/2).
    """

    length: float
    betas: FloatArray
    omegas: FloatArray
    coefficients: FloatArray

    def evaluate(self, xi: npt.ArrayLike, derivative: int = 0) -> FloatArray:
        r"""Mode shapes or their derivatives at stations ξ.

        .. math::

            \frac{d^j \phi_i}{d\xi^j} = \beta_i^j \left[ (-1)^j a_{i1} e^{-\beta_i \xi}
                + a_{i2} e^{-\beta_i (L - \xi)} + a_{i3} \cos^{(j)}(\beta_i \xi)
                + a_{i4} \sin^{(j)}(\beta_i \xi) \right]

        Parameters
        ----------
        xi : array_like, shape (n,) or scalar
            Stations along the beam, 0 <= ξ <= L, m.
        derivative : int
            Order j of the derivative, 0..4.

        Returns
        -------
        ndarray, shape (n, k)
        """
        is_int = isinstance(derivative, (Integral, np.integer)) and not isinstance(derivative, bool)
        if not is_int or not 0 <= derivative <= 4:
            raise FieldError("derivative", f"must be an integer in 0..4, got {derivative!r}")
        xi = np.atleast_1d(np.asarray(xi, dtype=float))
        if xi.ndim != 1:
            raise FieldError("xi", f"must be a scalar or 1-D array, got shape {xi.shape}")
        L = self.length
        tol = 1e-12 * L
        if not np.all(np.isfinite(xi)) or np.any(xi < -tol) or np.any(xi > L + tol):
            raise FieldError("xi", f"stations must be finite and lie in [0, {L}]")
        b, a = self.betas, self.coefficients
        x = np.outer(xi, b)
        j = int(derivative)
        cos_j = (np.cos, lambda t: -np.sin(t), lambda t: -np.cos(t), np.sin)[j % 4](x)
        sin_j = (np.sin, np.cos, lambda t: -np.sin(t), lambda t: -np.cos(t))[j % 4](x)
        y = (
            (-1.0) ** j * a[:, 0] * np.exp(-x)
            + a[:, 1] * np.exp(-np.outer(L - xi, b))
            + a[:, 2] * cos_j
            + a[:, 3] * sin_j
        )
        return y * b**j


def _gram(z: npt.ArrayLike) -> FloatArray:
    r"""∫_0^z g_p g_q dx for g = (e^{-x}, e^{-(z-x)}, cos x, sin x), shape (..., 4, 4)."""
    z = np.asarray(z, dtype=float)
    E, c, s = np.exp(-z), np.cos(z), np.sin(z)
    g11 = -np.expm1(-2 * z) / 2
    G = np.empty(z.shape + (4, 4))
    G[..., 0, 0] = G[..., 1, 1] = g11
    G[..., 0, 1] = G[..., 1, 0] = z * E
    G[..., 0, 2] = G[..., 2, 0] = (1 + E * (s - c)) / 2
    G[..., 0, 3] = G[..., 3, 0] = (1 - E * (s + c)) / 2
    G[..., 1, 2] = G[..., 2, 1] = (c + s - E) / 2
    G[..., 1, 3] = G[..., 3, 1] = (s - c + E) / 2
    G[..., 2, 2] = z / 2 + np.sin(2 * z) / 4
    G[..., 3, 3] = z / 2 - np.sin(2 * z) / 4
    G[..., 2, 3] = G[..., 3, 2] = s * s / 2
    return G


@dataclass(frozen=True)
class TipMassCantilever:
    r"""Uniform clamped–free Euler–Bernoulli beam with a tip mass and tip rotary inertia.

    .. math::

        EI\, y'''' = \rho \omega^2 y,\quad y(0) = y'(0) = 0,\quad
        EI\, y''(L) = J \omega^2 y'(L),\quad EI\, y'''(L) = -m \omega^2 y(L).

    Parameters
    ----------
    length : float
        Beam length L > 0, m.
    EI : float
        Bending stiffness > 0, N m².
    rho : float
        Mass per unit length > 0, kg/m.
    tip_mass : float
        Tip point mass m >= 0, kg.
    tip_inertia : float
        Rotary inertia J >= 0 of the tip body about its own centre, kg m².

    Raises
    ------
    ValueError
        Naming the offending field if a value is not finite, or out of range.
    """

    length: float
    EI: float
    rho: float
    tip_mass: float = 0.0
    tip_inertia: float = 0.0

    def __post_init__(self) -> None:
        for name in ("length", "EI", "rho"):
            object.__setattr__(self, name, _positive(getattr(self, name), name))
        for name in ("tip_mass", "tip_inertia"):
            object.__setattr__(self, name, _nonneg(getattr(self, name), name))

    @property
    def _mu(self) -> float:
        return self.tip_mass / (self.rho * self.length)

    @property
    def _iota(self) -> float:
        return self.tip_inertia / (self.rho * self.length**3)

    def _beta_L(self, k: int) -> FloatArray:
        return _tip_loaded_roots(self._mu, self._iota, require_count(k, "k"))

    def betas(self, k: int) -> FloatArray:
        """First k roots β_i of the frequency equation, 1/m, ascending, relative accuracy ~1e-15."""
        return self._beta_L(k) / self.length

    def frequencies(self, k: int) -> FloatArray:
        """First k natural frequencies ω_i = β_i² √(EI/ρ), rad/s."""
        return self.betas(k) ** 2 * math.sqrt(self.EI / self.rho)

    def modes(self, k: int) -> CantileverModes:
        r"""First k mass-normalized modes (see :class:`CantileverModes`).

        The coefficients are the right singular vectors of the smallest singular value of the
        bounded boundary-condition matrix at each root, scaled by

        .. math::

            \int_0^L \rho \phi^2 d\xi + m \phi(L)^2 + J \phi'(L)^2
              = \frac{\rho L}{z} a^T G(z) a + m \phi(L)^2 + J \phi'(L)^2,

        with G the closed-form Gram matrix of the basis (:func:`_gram`).
        """
        z = self._beta_L(k)
        L = self.length
        b = z / L
        _, _, vh = np.linalg.svd(_cantilever_matrix(z, self._mu, self._iota))
        a = vh[:, -1, :]
        E, c, s = np.exp(-z), np.cos(z), np.sin(z)
        tip = np.stack([E, np.ones_like(z), c, s], -1)
        dtip = b[:, None] * np.stack([-E, np.ones_like(z), -s, c], -1)
        y_l, dy_l = (a * tip).sum(-1), (a * dtip).sum(-1)
        beam = self.rho * L / z * np.einsum("ip,ipq,iq->i", a, _gram(z), a)
        norm = np.sqrt(beam + self.tip_mass * y_l**2 + self.tip_inertia * dy_l**2)
        sign = np.where(y_l != 0.0, np.sign(y_l), np.sign(dy_l))
        a = a * (sign / norm)[:, None]
        return CantileverModes(L, b, b**2 * math.sqrt(self.EI / self.rho), a)


@lru_cache(maxsize=256)
def _tip_loaded_roots(mu: float, iota: float, k: int) -> FloatArray:
    """First k roots βL of the tip-loaded cantilever's frequency equation for the tip mass and
    rotary-inertia ratios μ = m/(ρL), ι = J/(ρL³), read-only and cached: they depend on (μ, ι, k)
    alone, so the beams of a Monte Carlo that disperses EI, the hub or the gains share them
    (the root search is 55 % of a 10-mode hub + appendage build)."""
    z0 = 1e-3
    while _cantilever_count(np.array([z0]), mu, iota)[0] > 0 and z0 > 1e-12:
        z0 /= 10  # only for extreme tip mass, where β_1 L -> (3/μ)^(1/4)
    roots = _find_roots(
        lambda z: _cantilever_matrix(z, mu, iota),
        lambda z: _cantilever_count(z, mu, iota),
        k,
        z0,
    )
    roots.flags.writeable = False
    return roots


def _batch_roots(mu: FloatArray, iota: FloatArray, k: int) -> FloatArray:
    r"""First k roots z = βL of the tip-loaded cantilever for each case (μ_c, ι_c), (n, k).

    The vectorised counterpart of :func:`_tip_loaded_roots`, every case and mode at once:

    1. **Bracket.** Root i of case c lies in exactly one cell [g_j, g_{j+1}] of the grid
       g_j = z_s + j π/32 (z_s = 10⁻³, the scalar scan's start): the cell with
       N(g_j) ≤ i < N(g_{j+1}), N the Wittrick–Williams count (:func:`_cantilever_count`).
       A tip body only adds mass, so z_i ≤ z_i of the bare clamped–free beam
       (Rayleigh: added mass lowers every frequency, ω ∝ z²) and the cell is found by
       bisection on j between z_s (N = 0, checked) and that bound (N ≥ i + 1, checked).
       The cell is a function of (μ_c, ι_c, i) alone, whatever the batch.
    2. **Refine.** Regula falsi with the Anderson–Björck weighting of the retained end
       (Anderson & Björck 1973, BIT 13, 253–264; Illinois' ½ when the weight is not
       positive) on the bounded determinant Δ(z) of :func:`_cantilever_matrix`, which
       changes sign across a simple root. The bracket [a, b] keeps the sign change; the
       iteration stops when |b − a| or the last step is at most :data:`BATCH_ROOT_RTOL` · b
       (the relative tolerance of the scalar solver's brentq; the convergence is
       superlinear, so the last step bounds the error: the two solvers agree to an ulp or
       two, tested at 1e-12). A step onto a or outside the bracket (rounding) bisects.

    Each case's operations (elementwise numpy and one 4×4 LAPACK call per matrix) do not
    depend on the other cases: a case gives the same bits in any batch. A case whose cell
    holds two roots (numerically coincident roots) or whose tip mass puts a root below z_s is
    solved by the scalar :func:`_tip_loaded_roots` (grid subdivision) instead.
    """
    n = mu.size
    z_s = 1e-3
    I = np.broadcast_to(np.arange(k, dtype=float), (n, k))
    M, Io = np.broadcast_to(mu[:, None], (n, k)), np.broadcast_to(iota[:, None], (n, k))

    def grid(j: FloatArray) -> FloatArray:
        return z_s + _SCAN_STEP * j

    def cells(z: FloatArray) -> FloatArray:
        return np.floor((z - z_s) / _SCAN_STEP)

    # a first bracket of a few cells around the roots of the batch's median tip body (it
    # only saves count evaluations: the cell found does not depend on it)
    guess = cells(_tip_loaded_roots(float(np.median(mu)), float(np.median(iota)), k))
    lo = np.broadcast_to(np.maximum(guess - 2.0, 0.0), (n, k)).copy()
    hi = np.broadcast_to(guess + 3.0, (n, k)).copy()
    n_lo, n_hi = _cantilever_count(grid(lo), M, Io), _cantilever_count(grid(hi), M, Io)
    wide = (n_lo > I) | (n_hi < I + 1)
    if wide.any():  # the sure bracket: z_s (no root below) and past the bare beam's root i
        bare = cells(_tip_loaded_roots(0.0, 0.0, k)) + 1.0
        lo[wide], hi[wide] = 0.0, np.broadcast_to(bare, (n, k))[wide]
        n_lo[wide] = _cantilever_count(grid(lo[wide]), M[wide], Io[wide])
        n_hi[wide] = _cantilever_count(grid(hi[wide]), M[wide], Io[wide])
    scalar = ((n_lo > I) | (n_hi < I + 1)).any(axis=1)
    while True:  # bisection on the cell index, keeping N(g_lo) <= i < N(g_hi)
        idx = np.nonzero(hi - lo > 1.0)
        if not idx[0].size:
            break
        mid = np.floor(0.5 * (lo[idx] + hi[idx]))
        n_mid = _cantilever_count(grid(mid), M[idx], Io[idx])
        below = n_mid <= I[idx]
        lo[idx], n_lo[idx] = np.where(below, mid, lo[idx]), np.where(below, n_mid, n_lo[idx])
        hi[idx], n_hi[idx] = np.where(below, hi[idx], mid), np.where(below, n_hi[idx], n_mid)
    a, b = grid(lo), grid(hi)
    scalar |= ~((n_lo == I) & (n_hi == I + 1)).all(axis=1)

    def det(z: FloatArray, m: FloatArray, j: FloatArray) -> FloatArray:
        return np.linalg.det(_cantilever_matrix_cases(z, m, j))

    fa, fb = det(a, M, Io), det(b, M, Io)
    root = np.where(fa == 0.0, a, b)
    active = (fa != 0.0) & (fb != 0.0) & ~scalar[:, None]
    for _ in range(_BATCH_MAX_ITER):
        if not active.any():
            break
        A, B, FA, FB = a[active], b[active], fa[active], fb[active]
        c = B - FB * (B - A) / (FB - FA)
        # a secant step onto b is the converged root (the step test below ends it); one
        # onto a or outside the bracket (rounding) bisects instead
        inside = ((c > np.minimum(A, B)) & (c < np.maximum(A, B))) | (c == B)
        c = np.where(inside, c, 0.5 * (A + B))
        fc = det(c, M[active], Io[active])
        flip = np.sign(fc) != np.sign(FB)  # the root lies between b and c: a <- b
        scale = 1.0 - fc / FB  # Anderson–Björck's weight of the end kept, else Illinois' ½
        FA = np.where(flip, FB, FA * np.where(scale > 0.0, scale, 0.5))
        A = np.where(flip, B, A)
        a[active], fa[active], b[active], fb[active] = A, FA, c, fc
        root[active] = c
        tol = BATCH_ROOT_RTOL * np.abs(c)
        active[active] = (fc != 0.0) & (np.abs(c - A) > tol) & (np.abs(c - B) > tol)
    else:
        raise RuntimeError("beam frequency equation: the batched root refinement did not converge")
    for c in np.flatnonzero(scalar):
        root[c] = _tip_loaded_roots(float(mu[c]), float(iota[c]), k)
    return root


def _cantilever_matrix_cases(z: FloatArray, mu: FloatArray, iota: FloatArray) -> FloatArray:
    """:func:`_cantilever_matrix` with μ and ι per entry of z (the same shape), (..., 4, 4)."""
    E, one, zero = np.exp(-z), np.ones_like(z), np.zeros_like(z)
    moment, shear = _tip_rows(z, mu, iota)
    return np.stack(
        [np.stack([one, E, one, zero], -1), np.stack([-one, E, zero, one], -1), moment, shear], -2
    )


@dataclass(frozen=True, eq=False)
class CantileverModesBatch:
    """Mass-normalized modes of n tip-loaded cantilevers, one per case (the fields of
    :class:`CantileverModes` with a leading case axis).

    Attributes
    ----------
    length : ndarray, shape (n,)
        Beam lengths L, m.
    betas, omegas : ndarray, shape (n, k)
        Wavenumbers β (1/m) and frequencies ω (rad/s).
    coefficients : ndarray, shape (n, k, 4)
        Basis coefficients of :class:`CantileverModes`.
    """

    length: FloatArray
    betas: FloatArray
    omegas: FloatArray
    coefficients: FloatArray

    def evaluate(self, s: FloatArray, derivative: int = 0) -> FloatArray:
        """Mode shapes (or their derivative of order 0 or 1) at the stations ξ = s L of each
        case, s in [0, 1] (p,): shape (n, k, p), the station axis last
        (:meth:`CantileverModes.evaluate`)."""
        if derivative not in (0, 1):
            raise FieldError("derivative", f"must be 0 or 1, got {derivative!r}")
        b, a = self.betas[..., None], self.coefficients[..., None, :]
        L = self.length[:, None, None]
        x = b * (L * np.asarray(s, float))
        far = b * (L * (1.0 - np.asarray(s, float)))
        sign = -1.0 if derivative else 1.0
        cos_j, sin_j = (np.cos(x), np.sin(x)) if derivative == 0 else (-np.sin(x), np.cos(x))
        y = (
            sign * a[..., 0] * np.exp(-x)
            + a[..., 1] * np.exp(-far)
            + a[..., 2] * cos_j
            + a[..., 3] * sin_j
        )
        return y * b if derivative else y


def cantilever_modes_batch(
    length: npt.ArrayLike,
    EI: npt.ArrayLike,
    rho: npt.ArrayLike,
    tip_mass: npt.ArrayLike,
    tip_inertia: npt.ArrayLike,
    k: int,
) -> CantileverModesBatch:
    r"""First k mass-normalized modes of n tip-loaded cantilevers at once.

    Case c is :meth:`TipMassCantilever.modes` of ``TipMassCantilever(length[c], EI[c],
    rho[c], tip_mass[c], tip_inertia[c])`` (the arguments broadcast to one shape (n,)): the
    roots of the frequency equation from :func:`_batch_roots` (vectorised bracketing and
    Illinois refinement, equal to the scalar solver's to a few ulps), then the same null
    vectors and normalisation as the scalar modes, every case in one array operation. A case
    gives the same bits in any batch.

    Raises
    ------
    ValueError
        Naming the field, for a non-finite or out-of-range value (the rules of
        :class:`TipMassCantilever`).
    """
    k = require_count(k, "k")
    fields = {"length": length, "EI": EI, "rho": rho}
    values = {f: require_positive(v, f) for f, v in fields.items()}
    values["tip_mass"] = require_nonneg(tip_mass, "tip_mass")
    values["tip_inertia"] = require_nonneg(tip_inertia, "tip_inertia")
    L, EI_, rho_, m, J = (
        np.ascontiguousarray(v, dtype=float).ravel()
        for v in np.broadcast_arrays(*(np.atleast_1d(values[f]) for f in values))
    )
    mu, iota = m / (rho_ * L), J / (rho_ * L**3)
    z = _batch_roots(mu, iota, k)
    b = z / L[:, None]
    M, Io = np.broadcast_to(mu[:, None], z.shape), np.broadcast_to(iota[:, None], z.shape)
    _, _, vh = np.linalg.svd(_cantilever_matrix_cases(z, M, Io))
    a = vh[..., -1, :]
    E, c, s = np.exp(-z), np.cos(z), np.sin(z)
    tip = np.stack([E, np.ones_like(z), c, s], -1)
    dtip = b[..., None] * np.stack([-E, np.ones_like(z), -s, c], -1)
    y_l, dy_l = (a * tip).sum(-1), (a * dtip).sum(-1)
    G = _gram(z)
    beam = (rho_ * L)[:, None] / z * (a * (G * a[..., None, :]).sum(-1)).sum(-1)
    norm = np.sqrt(beam + m[:, None] * y_l**2 + J[:, None] * dy_l**2)
    sign = np.where(y_l != 0.0, np.sign(y_l), np.sign(dy_l))
    a = a * (sign / norm)[..., None]
    return CantileverModesBatch(L, b, b**2 * np.sqrt(EI_ / rho_)[:, None], a)


def clamped_free_beta_L(k: int) -> FloatArray:
    """First k roots z of 1 + cos z cosh z = 0, computed with the tip-mass solver (m = J = 0)."""
    return TipMassCantilever(1.0, 1.0, 1.0).betas(k)


def hub_free_frequencies(
    beam: TipMassCantilever, hub_radius: float, hub_inertia: float, n_appendages: int, k: int
) -> FloatArray:
    r"""First k elastic natural frequencies of a free hub carrying n identical appendages, rad/s.

    The hub (inertia :math:`I_h` about its axis) rotates freely; each beam is clamped radially at
    :math:`l_0` = ``hub_radius`` and all beams deform alike.  In the inertial displacement
    :math:`w = y + (l_0 + \xi)\theta` the eigenproblem is

    .. math::

        EI\, w'''' = \rho\omega^2 w,\quad w(0) = l_0\theta,\quad w'(0) = \theta,\quad
        EI\, w''(L) = J\omega^2 w'(L),\quad EI\, w'''(L) = -m\omega^2 w(L),

        -\omega^2 I_h \theta + n\, EI \bigl(l_0 w'''(0) - w''(0)\bigr) = 0,

    solved as the bounded 5x5 determinant of :func:`_hub_matrix` in (a, θL).  The rigid-body root
    ω = 0 is excluded: the scan starts at half the first clamped frequency (by interlacing the
    first elastic free-hub frequency is at least the first clamped one).

    Parameters
    ----------
    beam : TipMassCantilever
        One appendage (with its tip body).
    hub_radius : float
        l0 >= 0, m.
    hub_inertia : float
        I_h > 0, kg m².
    n_appendages : int
        n >= 1.
    k : int
        Number of elastic frequencies.

    Returns
    -------
    ndarray, shape (k,)
        ω_i in rad/s, ascending.
    """
    if not isinstance(beam, TipMassCantilever):
        raise FieldError("beam", f"must be a TipMassCantilever, got {type(beam).__name__}")
    l0 = _nonneg(hub_radius, "hub_radius")
    I_h = _positive(hub_inertia, "hub_inertia")
    n = require_count(n_appendages, "n_appendages")
    k = require_count(k, "k")
    L, rho = beam.length, beam.rho
    mu, iota, r, eta = beam._mu, beam._iota, l0 / L, I_h / (n * rho * L**3)
    z0 = 0.5 * beam._beta_L(1)[0]

    def count(z: npt.ArrayLike) -> IntArray:
        return _hub_count(z, mu, iota, r, eta) - 1  # the rigid-body mode lies below z0

    z = _find_roots(lambda z: _hub_matrix(z, mu, iota, r, eta), count, k, z0)
    return (z / L) ** 2 * math.sqrt(beam.EI / rho)
