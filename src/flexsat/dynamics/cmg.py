"""Single-gimbal control moment gyros in a pyramid (Vadali, Oh & Walker, "Preferred Gimbal Angles
for Single Gimbal CMGs"; in Junkins, Pollock & Rahman 1990, Att. 13).

Plain array kernels with a leading case axis: the gimbal angles ``sigma`` have shape
``(..., n)``; momenta ``(..., 3)``, Jacobians ``(..., 3, n)``. Momenta are in units of one
rotor's momentum h (h = 1). Only the axial rotor momentum is modelled.

Geometry. Unit i of n sits at azimuth φ_i = 2π(i − 1)/n around the body z axis; its gimbal axis
is tilted by the skew angle δ from z towards the azimuth, and its rotor momentum turns in the
plane normal to the gimbal axis::

    g_i = [sinδ cosφ_i, sinδ sinφ_i, cosδ],   a_i = [−sinφ_i, cosφ_i, 0],   b_i = g_i × a_i
    h_i(σ_i) = cosσ_i a_i + sinσ_i b_i

For n = 4 this is exactly the paper's Eq. (1), and the Jacobian column ∂h_i/∂σ_i =
−sinσ_i a_i + cosσ_i b_i = g_i × h_i is Eq. (2).

Sign convention. The paper's Eq. (4)–(5) at ω = 0: the spacecraft feels the torque −ḣ, and the
steering law solves C σ̇ = ḣ_cmd. The kernels here take ``torque``, the torque on the
spacecraft, so ḣ_cmd = −torque; the paper's "torque demand" T of Eq. (5) is ḣ_cmd itself
(its "unit +x torque" is ``torque = [-1, 0, 0]`` here).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import TYPE_CHECKING

import numpy as np

from flexsat.input_checks import FieldError, require_finite

if TYPE_CHECKING:
    import numpy.typing as npt

    from flexsat.units import FloatArray, QuantityArrayLike, QuantityLike

#: the paper's pyramid skew angle, 54.74° (Att. 13 "Determination of Preferred
#: Initial Gimbal Angles"), in rad
SKEW = float(np.deg2rad(54.74))


def _require_skew(skew: QuantityLike) -> float:
    given = require_finite(skew, "skew", "rad")
    if given.ndim != 0:
        raise FieldError("skew", f"must be a scalar angle, got shape {given.shape}")
    value = float(given)
    if not 0.0 < value < np.pi / 2:
        raise FieldError("skew", f"must lie in (0, 90°) (a pyramid), got {np.rad2deg(value):.6g}°")
    return value


def _require_units(n_units: object) -> int:
    if isinstance(n_units, bool) or not isinstance(n_units, (int, np.integer)) or n_units < 3:
        raise FieldError("n_units", f"must be an integer >= 3 (3 units span 3-D), got {n_units!r}")
    return int(n_units)


@lru_cache(maxsize=64)
def _axes(n_units: int, skew: float) -> tuple[FloatArray, FloatArray, FloatArray]:
    phi = 2.0 * np.pi * np.arange(n_units) / n_units
    g = np.stack(
        [np.sin(skew) * np.cos(phi), np.sin(skew) * np.sin(phi), np.full(n_units, np.cos(skew))],
        axis=-1,
    )
    a = np.stack([-np.sin(phi), np.cos(phi), np.zeros(n_units)], axis=-1)
    b = np.cross(g, a)
    for arr in (g, a, b):
        arr.flags.writeable = False  # cached: shared by every caller
    return g, a, b


def pyramid_axes(
    n_units: int = 4, skew: QuantityLike = SKEW
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Gimbal axes g, rotor reference directions a (σ = 0) and b = g × a, each ``(n, 3)``.

    Parameters
    ----------
    n_units : int
        Number of units (>= 3), equally spaced in azimuth around the body z axis.
    skew : float or str
        Skew angle δ of the gimbal axes from z, in (0, 90°); rad or a string such as
        ``"54.74 deg"``.

    Returns
    -------
    g, a, b : ndarray
        See the module; for n = 4 they reproduce the paper's Eq. (1)–(2).
    """
    return _axes(_require_units(n_units), _require_skew(skew))


def _sigma(sigma: QuantityArrayLike, n_units: int) -> tuple[FloatArray, int]:
    n = _require_units(n_units)
    sig = require_finite(sigma, "sigma", "rad")
    if sig.ndim == 0 or sig.shape[-1] != n:
        raise FieldError(
            "sigma", f"last axis must hold the {n} gimbal angles, got shape {sig.shape}"
        )
    return sig, n


def momentum(sigma: QuantityArrayLike, skew: QuantityLike = SKEW, n_units: int = 4) -> FloatArray:
    """Cluster momentum h(σ) = Σ_i cosσ_i a_i + sinσ_i b_i (the paper's Eq. 1), in
    units of one rotor's momentum; shape ``(..., 3)``."""
    sig, n = _sigma(sigma, n_units)
    _, a, b = _axes(n, _require_skew(skew))
    return np.cos(sig) @ a + np.sin(sig) @ b


def _unit_momenta(sig: FloatArray, a: FloatArray, b: FloatArray) -> FloatArray:
    return np.cos(sig)[..., :, None] * a + np.sin(sig)[..., :, None] * b


def jacobian(sigma: QuantityArrayLike, skew: QuantityLike = SKEW, n_units: int = 4) -> FloatArray:
    """C(σ) = ∂h/∂σ, column i = −sinσ_i a_i + cosσ_i b_i = g_i × h_i (Eq. 2); ``(..., 3, n)``."""
    sig, n = _sigma(sigma, n_units)
    _, a, b = _axes(n, _require_skew(skew))
    cols = -np.sin(sig)[..., :, None] * a + np.cos(sig)[..., :, None] * b
    return np.swapaxes(cols, -1, -2)


def gain(sigma: QuantityArrayLike, skew: QuantityLike = SKEW, n_units: int = 4) -> FloatArray:
    """The cluster's gain det(C Cᵀ) (§8.2, after Eq. 7); zero exactly at singular σ."""
    c = jacobian(sigma, skew, n_units)
    return np.linalg.det(c @ np.swapaxes(c, -1, -2))


def envelope(
    direction: npt.ArrayLike, skew: QuantityLike = SKEW, n_units: int = 4
) -> tuple[FloatArray, FloatArray]:
    """The momentum envelope along a direction u: max over σ of uᵀh(σ).

    Each unit's momentum turns in the plane normal to its gimbal axis, so uᵀh_i is largest when
    h_i points along the projection of u onto that plane, P_i u = u − (g_iᵀu) g_i; then
    uᵀh_i = |P_i u| = √(1 − (g_iᵀu)²). The units are independent, so

        max_σ uᵀh = Σ_i √(1 − (g_iᵀu)²),   reached at h_i = P_i u / |P_i u|.

    This σ is the external (saturation) singularity along u: every Jacobian column g_i × h_i is
    then normal to u. Along +x with δ = 54.74° it is 2 cosδ + 2 = 3.1545 (§8.3, V2). It is
    the support function of the reachable set; where h(σ) at that point is not parallel to u
    (e.g. u = [1, 1, 1]: h·u = 3.1681, |h| on the ray through u only 3.1652, §8.3), a
    pseudo-inverse run along u saturates short of it.

    Parameters
    ----------
    direction : array_like, ``(..., 3)``
        Nonzero direction u (normalised here).

    Returns
    -------
    value : ndarray ``(...,)``
        max uᵀh.
    sigma : ndarray ``(..., n)``
        Gimbal angles reaching it (rad, in (−π, π]); undefined (0) for a unit whose gimbal axis
        is along u, where every σ_i gives uᵀh_i = 0.
    """
    u = require_finite(direction, "direction")
    if u.ndim == 0 or u.shape[-1] != 3:
        raise FieldError("direction", f"last axis must have 3 components, got shape {u.shape}")
    norm = np.linalg.norm(u, axis=-1, keepdims=True)
    if np.any(norm == 0):
        raise FieldError("direction", "must be nonzero")
    u = u / norm
    _, a, b = _axes(_require_units(n_units), _require_skew(skew))
    ua, ub = u @ a.T, u @ b.T  # components of P_i u in the unit's (a_i, b_i) plane
    return np.hypot(ua, ub).sum(axis=-1), np.arctan2(ub, ua)


@dataclass(frozen=True)
class Singularity:
    """Classification of gimbal sets (see :func:`classify_singularity`); arrays of the case shape.

    ``singular``: det(CCᵀ) below the threshold. ``direction``: the singular direction u (the
    eigenvector of CCᵀ of least eigenvalue, signed so uᵀh >= 0), ``(..., 3)``. ``signs``: ε_i =
    sign(uᵀh_i), ``(..., n)``. ``internal``: singular and not external, i.e. uᵀh below the
    envelope along u. ``margin``: envelope(u) − uᵀh (zero at an external singularity).
    """

    singular: npt.NDArray[np.bool_]
    internal: npt.NDArray[np.bool_]
    direction: FloatArray
    signs: npt.NDArray[np.int_]
    margin: FloatArray


def classify_singularity(
    sigma: QuantityArrayLike, skew: QuantityLike = SKEW, n_units: int = 4, threshold: float = 1e-6
) -> Singularity:
    """Singularity detection and classification (§8.2–§8.3, F23).

    At a singular σ every column g_i × h_i of C is normal to the singular direction u, so each
    h_i = ε_i P_i u/|P_i u| and uᵀh = Σ ε_i |P_i u|. The singularity is external (on the
    momentum envelope, :func:`envelope`) when all ε_i = +1 (u signed so uᵀh >= 0), internal
    otherwise: then uᵀh is below the envelope along u by 2 Σ_{ε_i<0} |P_i u|.

    Parameters
    ----------
    threshold : float
        Gain det(CCᵀ) below which σ counts as singular (dimensionless, h = 1).
    """
    thr = float(require_finite(threshold, "threshold"))
    if thr <= 0:
        raise FieldError("threshold", f"must be > 0, got {threshold!r}")
    sig, n = _sigma(sigma, n_units)
    d = _require_skew(skew)
    c = jacobian(sig, d, n)
    cct = c @ np.swapaxes(c, -1, -2)
    _, vecs = np.linalg.eigh(cct)
    u = vecs[..., :, 0]
    _, a, b = _axes(n, d)
    h = np.cos(sig) @ a + np.sin(sig) @ b
    flip = np.where(np.einsum("...i,...i->...", u, h) < 0, -1.0, 1.0)
    u = u * flip[..., None]
    uh_i = np.einsum("...j,...ij->...i", u, _unit_momenta(sig, a, b))
    signs = np.where(uh_i < 0, -1, 1)
    env, _ = envelope(u, d, n)
    margin = env - np.einsum("...i,...i->...", u, h)
    singular = np.linalg.det(cct) < thr
    # external iff every ε_i = +1; a unit whose h_i is ~normal to u carries no sign (its |P_i u|
    # ~ 0 contributes nothing to the envelope), so decide on the margin, which is 2Σ_{ε<0}|P_i u|
    internal = singular & (margin > np.sqrt(thr))
    return Singularity(singular, internal, u, signs, margin)


def steering_rates(
    sigma: QuantityArrayLike,
    torque: npt.ArrayLike,
    skew: QuantityLike = SKEW,
    n_units: int = 4,
    alpha: float = 0.0,
) -> FloatArray:
    """Gimbal rates σ̇ = Cᵀ(CCᵀ + αI)⁻¹ ḣ_cmd with ḣ_cmd = −torque (§8.2 Eq. 7; α > 0 is the
    singularity-robust inverse of Nakamura & Hanafusa, §8.5 Eq. 17).

    Parameters
    ----------
    sigma : array_like ``(..., n)``
        Gimbal angles (rad or strings with units).
    torque : array_like ``(..., 3)``
        Torque on the spacecraft, in units of h per second (h = 1); the cluster's momentum
        changes by −torque (Eq. 4).
    alpha : float
        Singularity-robust weight (>= 0); 0 is the pseudo-inverse, which raises ValueError at an
        exactly singular σ (CCᵀ not invertible).

    Returns
    -------
    ndarray ``(..., n)``
        Gimbal rates, rad/s.
    """
    al = float(require_finite(alpha, "alpha"))
    if al < 0:
        raise FieldError("alpha", f"must be >= 0, got {alpha!r}")
    tq = require_finite(torque, "torque")
    if tq.ndim == 0 or tq.shape[-1] != 3:
        raise FieldError("torque", f"last axis must have 3 components, got shape {tq.shape}")
    sig, n = _sigma(sigma, n_units)
    _, a, b = _axes(n, _require_skew(skew))
    return steer(sig, tq, a, b, al)


def steer(
    sig: FloatArray, torque: FloatArray, a: FloatArray, b: FloatArray, alpha: float
) -> FloatArray:
    """Unchecked kernel of :func:`steering_rates` (for plants that check once): ``sig``
    (..., n) rad, ``torque`` (..., 3), axes ``a``, ``b`` of :func:`pyramid_axes`, α >= 0."""
    c = np.swapaxes(-np.sin(sig)[..., :, None] * a + np.cos(sig)[..., :, None] * b, -1, -2)
    ct = np.swapaxes(c, -1, -2)
    m = c @ ct
    if alpha:
        m = m + alpha * np.eye(3)
    lam = np.linalg.eigvalsh(m)
    # CCᵀ singular to working precision: its solve would return round-off amplified by 1/eps
    if np.any(lam[..., 0] <= 10 * np.finfo(float).eps * lam[..., -1]):
        raise FieldError(
            "sigma",
            "singular gimbal set (CCᵀ singular to working precision): the "
            "pseudo-inverse has no solution; use alpha > 0 (singularity-robust "
            "inverse)",
        )
    shape = np.broadcast_shapes(m.shape[:-1], torque.shape)
    y = np.linalg.solve(
        np.broadcast_to(m, shape + (3,)), -np.broadcast_to(torque, shape)[..., None]
    )
    return (ct @ y)[..., 0]


@dataclass(frozen=True)
class GimbalRun:
    """A gimbal run (:func:`flexsat.cases.cmg_pyramid.integrate_gimbals`,
    :func:`~flexsat.cases.cmg_pyramid.reorient`): times ``t`` (n_t,), angles ``sigma`` (n_t, n),
    momenta ``h`` (n_t, 3), ``singular`` (the run stopped on det(CCᵀ) = threshold) and the
    gain there ``gain`` (n_t,)."""

    t: FloatArray
    sigma: FloatArray
    h: FloatArray
    gain: FloatArray
    singular: bool


#: the paper's offset from the +x saturation set [−90, 180, 90, 0]° to its starting set
#: [−89, 177, 90, −1]° for the back integration, in rad
PAPER_PERTURBATION = np.deg2rad([1.0, -3.0, 0.0, -1.0])


#: Preferred initial gimbal sets of the paper's pyramid (4 units, δ = 54.74°), in degrees, for
#: the six axis directions and eight oblique ones: computed data, the output of
#: :func:`flexsat.cases.cmg_pyramid.preferred_angles` with the paper's perturbation (back
#: integration, rtol 1e-10), rounded to 0.01°; ``tests/dynamics/test_cmg.py`` recomputes
#: every row. The paper stores such sets for use (Att. 13 "Conclusions":
#: "preferred-set data must be stored"); its Table 1 lists hand-chosen sets for six demands,
#: of which only the +x row came from the back integration (V4: [−59.6, 60.7, 118, −121]°).
#: Back integration from the *same* offset lands elsewhere along other directions (+y:
#: [110.91, −115.22, −52.08, 51.08]°, not Table 1's [−120, −60, 60, 120]°): any set on the
#: back-integrated path saturates without an internal singularity, so both are admissible.
#: Directions are as given (normalised when used).
PREFERRED_SETS = (
    ((1, 0, 0), (-59.66, 60.58, 117.98, -121.12)),
    ((-1, 0, 0), (120.34, -119.42, -62.02, 58.88)),
    ((0, 1, 0), (110.91, -115.22, -52.08, 51.08)),
    ((0, -1, 0), (-69.09, 64.78, 127.92, -128.92)),
    ((0, 0, 1), (-128.65, -67.14, 68.23, 129.30)),
    ((0, 0, -1), (51.35, 112.86, -111.77, -50.70)),
    ((1, 1, 0), (-56.97, 59.82, 115.86, -118.36)),
    ((1, -1, 0), (172.01, -5.01, 174.05, -8.10)),
    ((-1, 1, 0), (-7.99, 174.99, -5.95, 171.90)),
    ((-1, -1, 0), (123.03, -120.18, -64.14, 61.64)),
    ((1, 1, 1), (71.24, 137.21, -129.96, -72.07)),
    ((-1, -1, -1), (-108.76, -42.79, 50.04, 107.93)),
    ((4, 2, 0), (-49.77, 56.33, 120.44, -117.67)),
    ((2, 4, 0), (117.74, -126.51, -55.57, 51.63)),
)


def preferred_set(direction: npt.ArrayLike) -> FloatArray:
    """The stored preferred set (:data:`PREFERRED_SETS`) whose direction is nearest to the
    demand direction u (largest cosine), rad ``(4,)``; for the paper's pyramid only (other
    clusters: :func:`flexsat.cases.cmg_pyramid.preferred_angles`)."""
    u = require_finite(direction, "direction")
    if u.shape != (3,) or not np.any(u):
        raise FieldError("direction", f"must be a nonzero 3-vector, got {direction!r}")
    dirs = np.array([d for d, _ in PREFERRED_SETS], float)
    cos = dirs @ u / (np.linalg.norm(dirs, axis=1) * np.linalg.norm(u))
    return np.deg2rad(np.array(PREFERRED_SETS[int(np.argmax(cos))][1]))


def steering_with_null_motion(
    sigma: QuantityArrayLike,
    torque: npt.ArrayLike,
    sigma_target: QuantityArrayLike,
    gain_k: QuantityLike = 1.0,
    skew: QuantityLike = SKEW,
    n_units: int = 4,
    alpha: float = 0.0,
    null_alpha: float = 0.0,
) -> FloatArray:
    """Torque steering with null motion beside it: σ̇ = Cᵀ(CCᵀ + αI)⁻¹(−torque) + τ k(σ_f − σ)
    (§8.2 Eq. 7 plus §8.5 Eq. 13–15; the paper's conclusion that "the reorientation law may
    need to run alongside the torque law", Att. 13 "Conclusions").

    τ = I − Cᵀ(CCᵀ + α_n I)⁻¹C (:func:`null_projector`): with ``null_alpha`` = 0 the added
    motion changes no momentum (Cτ = 0), so the torque delivered is the steering law's alone;
    α_n > 0 keeps it bounded through singular sets at a residual momentum rate
    α_n(CCᵀ + α_n I)⁻¹Ck(σ_f − σ). Shapes as :func:`steering_rates`; ``sigma_target`` ``(n,)``
    or ``(..., n)``, rad.
    """
    k = float(require_finite(gain_k, "gain_k", "1/s"))
    if k < 0:
        raise FieldError("gain_k", f"must be >= 0, got {gain_k!r}")
    sig, n = _sigma(sigma, n_units)
    target, _ = _sigma(sigma_target, n)
    rates = steering_rates(sig, torque, skew, n, alpha)
    tau = null_projector(sig, skew, n, null_alpha)
    return rates + np.einsum("...ij,...j->...i", tau, k * (target - sig))


def null_projector(
    sigma: QuantityArrayLike, skew: QuantityLike = SKEW, n_units: int = 4, alpha: float = 0.0
) -> FloatArray:
    """τ = I − Cᵀ(CCᵀ + αI)⁻¹C (§8.5 Eq. 14; α > 0: Eq. 17, the singularity-robust form).

    With α = 0, τ is the orthogonal projector onto the null space of C (τ² = τ, Cτ = 0): gimbal
    motion τd changes no momentum. With α > 0 it stays bounded at singular σ, at the price of
    a residual momentum rate Cτd = α(CCᵀ + αI)⁻¹Cd. Shape ``(..., n, n)``.
    """
    al = float(require_finite(alpha, "alpha"))
    if al < 0:
        raise FieldError("alpha", f"must be >= 0, got {alpha!r}")
    c = jacobian(sigma, skew, n_units)
    ct = np.swapaxes(c, -1, -2)
    m = c @ ct + al * np.eye(3)
    if al == 0 and np.any(
        np.linalg.eigvalsh(m)[..., 0] <= 10 * np.finfo(float).eps * np.linalg.eigvalsh(m)[..., -1]
    ):
        raise FieldError(
            "sigma",
            "singular gimbal set (CCᵀ singular to working precision): the "
            "projector needs alpha > 0 (singularity-robust inverse)",
        )
    return np.eye(c.shape[-1]) - ct @ np.linalg.solve(m, c)
