r"""Realization from Markov parameters: ERA and ERA/DC, modal accuracy indicators and their
uncertainty.  The Markov parameters themselves (impulse tests, FRFs, OKID) come from
:mod:`flexsat.identify.markov` (its three functions stay importable from here).

ERA
---
Eigensystem Realization Algorithm (Juang & Pappa, *J. Guid. Control Dyn.* 8(5), 620–627,
1985). With α block rows and β block columns the Hankel matrices
:math:`H(k)_{ij} = Y_{k+i+j+1}` (i < α, j < β) factor as :math:`H(k) = P_\alpha A^k Q_\beta`.
With :math:`H(0) = U_n \Sigma_n V_n^T` truncated to the order n,

.. math::

    A = \Sigma_n^{-1/2} U_n^T H(1) V_n \Sigma_n^{-1/2}, \quad
    B = \Sigma_n^{1/2} V_n^T E_r, \quad C = E_q^T U_n \Sigma_n^{1/2}, \quad D = Y_0 .

Hankel sizing rules (defaults): α q ≥ 10 n and α q ≥ 200 rows, α ≤ L/2; β r ≥ α q and
β r ≥ 2000 (more columns average the noise), as far as α + β ≤ L, the number of Markov
parameters after Y_0, allows. The order must not exceed the numerical rank of H(0) (a clear
ValueError otherwise). Without ``order`` the order is put at the largest drop of the singular
values (rounded up to even).

Continuous modes from the eigenvalues z of A: :math:`s = \ln z / \Delta t`,
f = |s| / 2π, ζ = −Re s / |s|; shapes :math:`C \psi` at the output channels (one per complex
pair, Im s > 0).

Accuracy indicators (per mode, 0..1 except MSV):

* EMAC (extended modal amplitude coherence; Pappa, Elliott & Schenk 1993): the last block
  row used (lag k = min(α, β) − 1) of the observability matrix in modal coordinates against
  the prediction :math:`c_i \lambda_i^{k}`, times the same test on the controllability
  matrix at the same lag (Pappa uses its last block column; with β ≫ α that block lies where the
  response has decayed into the noise, so EMAC would read 0 for every mode); per component
  magnitude ratio × phase weight :math:`\max(0, 1 - |\Delta\phi|/(\pi/4))`, weighted by the
  squared predicted magnitude.
* MPC (modal phase collinearity): :math:`((\lambda_1-\lambda_2)/(\lambda_1+\lambda_2))^2` of
  the 2x2 matrix of real/imaginary parts of the shape (1: real mode, 0: circular).
* MAC against known shapes (when ``reference_shapes`` given): best match per mode.
* MSV (modal singular value, Juang & Pappa 1985):
  :math:`\sqrt{|c_i| |b_i| \sum_{k=0}^{\beta-1} |\lambda_i|^{k}}`, the mode's contribution to
  the Hankel matrix.

Uncertainty
-----------
First-order perturbation from the singular values. The discarded singular values of H(0) are
taken as the noise floor: a Hankel matrix of size m × p with i.i.d. noise of standard
deviation :math:`\sigma_e` has largest singular value :math:`\approx \sigma_e(\sqrt m + \sqrt p)`,
so :math:`\sigma_e = \sigma_{n+1} / (\sqrt m + \sqrt p)`. The same noise in H(1) perturbs
:math:`A` by :math:`\Sigma_n^{-1/2} U_n^T \delta H V_n \Sigma_n^{-1/2}` and, to first order,
the eigenvalue by :math:`l_i^H \delta A\, r_i` (left/right eigenvectors, :math:`l_i^H r_i = 1`),
of standard deviation :math:`\sigma_\lambda = \sigma_e \|\Sigma_n^{-1/2} l_i\| \|\Sigma_n^{-1/2}
r_i\|`. Then :math:`\sigma_s = \sigma_\lambda / (|\lambda| \Delta t)` and, splitting the
circular complex error evenly, ``frequency_std_hz`` :math:`= \sigma_s / (2\sqrt2\,\pi)` Hz and
``damping_std`` :math:`= \sqrt{1-\zeta^2}\, \sigma_s / (\sqrt2\, \omega)`. It is an order-of-
magnitude indicator (Hankel noise is not i.i.d.: entries repeat along anti-diagonals, and
the noise shared by H(0) and H(1) partly cancels), not a confidence interval. On the TAMU grid
(6 modes, 20 displacement channels, 1 % noise) it exceeds the observed RMS errors by a factor of
about 5 to 20, and 20 to 40 with all 60 modes and anti-aliasing filters (conservative).

:func:`bootstrap_uncertainty` gives a calibrated estimate instead: a parametric bootstrap
(Efron & Tibshirani, *An Introduction to the Bootstrap*, 1993, ch. 6) that adds noise of the
residual's level per channel to the realization's own Markov parameters, realizes each copy with
the same order and Hankel sizes, and takes the scatter of the paired modes.
"""

from __future__ import annotations

import dataclasses
import warnings
from dataclasses import dataclass, field
from typing import Any, TypeAlias

import numpy as np
import numpy.typing as npt

from flexsat import limits
from flexsat.identify.markov import check_markov

# importable from here as before the Markov-parameter functions moved to flexsat.identify.markov
from flexsat.identify.markov import markov_from_frf as markov_from_frf
from flexsat.identify.markov import markov_parameters as markov_parameters
from flexsat.identify.markov import okid as okid
from flexsat.input_checks import (
    FieldError,
    require_count,
    require_numeric,
    require_positive_scalar,
    require_scalar,
)
from flexsat.units import FloatArray, FrequencyArray, holds_quantity, to_si_array

__all__ = [
    "Realization",
    "bootstrap_uncertainty",
    "era",
    "era_dc",
    "mac",
]

ComplexArray: TypeAlias = npt.NDArray[np.complex128]
IntArray: TypeAlias = npt.NDArray[np.intp]
#: real or complex: :func:`numpy.linalg.eig` returns real arrays when every eigenvalue is real
InexactArray: TypeAlias = npt.NDArray[np.inexact[Any]]
#: a realization's factors: A, B, C, the singular values, the order, and the observability and
#: controllability factors
Factors: TypeAlias = tuple[
    FloatArray, FloatArray, FloatArray, FloatArray, int, FloatArray, FloatArray
]


# ------------------------------------------------------------------------------------------------
def mac(phi: npt.ArrayLike, psi: npt.ArrayLike) -> FloatArray:
    """Modal assurance criterion matrix |φ_i^H ψ_j|² / (|φ_i|² |ψ_j|²); shapes as columns."""
    given = []
    for name, value in (("phi", phi), ("reference_shapes", psi)):
        if isinstance(value, (str, bytes)) or holds_quantity(value):
            raise FieldError(name, f"must be a numeric (complex) array, got {value!r}")
        shapes = np.atleast_2d(np.asarray(value))
        if shapes.dtype.kind not in "biufc":
            raise FieldError(name, f"must be a numeric (complex) array, got {value!r}")
        given.append(shapes)
    phi, psi = given
    for name, shapes in (("phi", phi), ("reference_shapes", psi)):
        if shapes.ndim != 2 or shapes.size == 0 or not np.all(np.isfinite(shapes)):
            raise FieldError(
                name, f"must be a non-empty finite (outputs, modes) array, got shape {shapes.shape}"
            )
    if phi.shape[0] != psi.shape[0]:
        raise FieldError(
            "reference_shapes",
            f"must have {phi.shape[0]} rows (one per output), got {psi.shape[0]}",
        )
    num = np.abs(phi.conj().T @ psi) ** 2
    den = np.outer(np.sum(np.abs(phi) ** 2, 0), np.sum(np.abs(psi) ** 2, 0))
    return num / np.where(den > 0, den, 1.0)


def _mpc(shape: ComplexArray) -> float:
    X = np.column_stack([shape.real, shape.imag])
    ev = np.linalg.eigvalsh(X.T @ X)
    tot = ev.sum()
    return float(((ev[1] - ev[0]) / tot) ** 2) if tot > 0 else 0.0


def _coherence(pred: InexactArray, ident: InexactArray) -> float:
    """EMAC of one mode's components (Pappa et al. 1993)."""
    a, b = np.abs(pred), np.abs(ident)
    ratio = np.where((a > 0) & (b > 0), np.minimum(a, b) / np.maximum(np.maximum(a, b), 1e-300), 0)
    dphi = np.abs(np.angle(ident * np.conj(pred)))
    weight = np.clip(1 - dphi / (np.pi / 4), 0, 1)
    wts = a**2
    return float(np.sum(ratio * weight * wts) / np.sum(wts)) if np.sum(wts) > 0 else 0.0


@dataclass(frozen=True, eq=False)
class Realization:
    """Identified discrete realization and its modes (see the module docstring).

    Attributes
    ----------
    A, B, C, D : ndarray
        Discrete realization (sample interval ``dt``).
    dt : float
    singular_values : ndarray
        Of H(0) (or of the correlation matrix for ERA/DC).
    frequencies_hz : FrequencyArray (modes,)
        Cyclic frequencies, Hz, ascending; tagged with their unit, so a model update that
        takes rad/s refuses them (use :attr:`omega_rad_s`).
    damping : ndarray (modes,)
    shapes : ndarray (q, modes) complex
        At the output channels, normalised to unit norm with the largest component real.
    emac, mpc, msv : ndarray (modes,)
    mac : ndarray (modes,) or None
        Best MAC with ``reference_shapes``.
    frequency_std_hz : FrequencyArray (modes,) or None
        Standard deviations of :attr:`frequencies_hz`, Hz: first-order uncertainty from the
        singular-value noise floor (module docstring), or the bootstrap's.
    damping_std : ndarray (modes,) or None
    rows, cols, order : int
    """

    A: FloatArray
    B: FloatArray
    C: FloatArray
    D: FloatArray
    dt: float
    singular_values: FloatArray
    frequencies_hz: FrequencyArray
    damping: FloatArray
    shapes: ComplexArray
    emac: FloatArray
    mpc: FloatArray
    msv: FloatArray
    mac: FloatArray | None
    frequency_std_hz: FrequencyArray | None
    damping_std: FloatArray | None
    rows: int
    cols: int
    order: int
    extra: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        # tagged Hz; values tagged rad/s are refused rather than relabelled
        for name in ("frequencies_hz", "frequency_std_hz"):
            value = getattr(self, name)
            if value is not None:
                hz = FrequencyArray(to_si_array(value, "Hz", name), "Hz")
                object.__setattr__(self, name, hz)

    @property
    def omega_rad_s(self) -> FrequencyArray:
        """Angular frequencies ω = 2π f, rad/s: what a model update takes."""
        return self.frequencies_hz.to("rad/s")

    def __repr__(self) -> str:
        f = ", ".join(f"{x:.4g}" for x in self.frequencies_hz)
        return f"Realization(order={self.order}, rows={self.rows}, cols={self.cols}, f=[{f}] Hz)"


def _hankel(Y: FloatArray, start: int, rows: int, cols: int) -> FloatArray:
    q, r = Y.shape[1:]
    H = np.empty((rows * q, cols * r))
    for i in range(rows):
        blk = Y[start + i : start + i + cols]  # (cols, q, r)
        H[i * q : (i + 1) * q] = blk.transpose(1, 0, 2).reshape(q, cols * r)
    return H


def _sizes(
    L: int, q: int, r: int, order: int | None, rows: int | None, cols: int | None
) -> tuple[int, int]:
    if rows is None:
        want = max(10 * (order or 0), 200)
        rows = max(2, min(-(-want // q), L // 2))
    rows = require_count(rows, "rows")
    if cols is None:
        cols = max(1, min(L - rows, max(-(-rows * q // r), 2000 // r)))
    cols = require_count(cols, "cols")
    if rows + cols > L:
        raise FieldError(
            "rows",
            f"rows + cols = {rows + cols} needs more than the {L} Markov "
            "parameters after Y_0 (H(1) uses Y_1 .. Y_rows+cols)",
        )
    return rows, cols


def _order(s: FloatArray, order: int | None, field: str = "order") -> int:
    tol = s[0] * max(s.size, 1) * np.finfo(float).eps * 10
    rank = int(np.sum(s > tol))
    if order is None:
        k = min(rank, s.size - 1)
        if k < 1:
            raise FieldError("markov", "the Hankel matrix has rank 0 (no response)")
        gaps = np.log(s[:k]) - np.log(np.maximum(s[1 : k + 1], tol))
        order = int(np.argmax(gaps)) + 1
        order += order % 2
        return min(order, rank)
    order = require_count(order, field)
    if order > rank:
        raise FieldError(
            field,
            f"{order} exceeds the numerical rank {rank} of the Hankel "
            f"matrix ({s.size} singular values); lower the order or give more data",
        )
    return order


def _modes(
    A: FloatArray,
    B: FloatArray,
    C: FloatArray,
    dt: float,
    cols: int,
    reference_shapes: npt.ArrayLike | None,
) -> tuple[
    FloatArray,
    FloatArray,
    ComplexArray,
    FloatArray,
    FloatArray,
    FloatArray | None,
    InexactArray,
    InexactArray,
    IntArray,
    InexactArray,
]:
    lam, W = np.linalg.eig(A)
    s = np.log(lam.astype(complex)) / dt
    keep = np.flatnonzero(s.imag > 1e-9 / dt)
    order_ = np.argsort(np.abs(s[keep]))
    keep = keep[order_]
    s, lam_k = s[keep], lam[keep]
    Winv = np.linalg.inv(W)
    shapes = C @ W[:, keep]
    bmod = Winv[keep] @ B
    freq = np.abs(s) / (2 * np.pi)
    zeta = -s.real / np.abs(s)
    msv = np.sqrt(
        np.linalg.norm(shapes, axis=0)
        * np.linalg.norm(bmod, axis=1)
        * np.array([np.sum(np.abs(z) ** np.arange(cols)) for z in lam_k])
    )
    mpc = np.array([_mpc(shapes[:, i]) for i in range(keep.size)])
    norm = shapes / np.linalg.norm(shapes, axis=0)
    big = np.argmax(np.abs(norm), axis=0)
    norm = norm * np.exp(-1j * np.angle(norm[big, np.arange(keep.size)]))
    mac_best = None
    if reference_shapes is not None:
        mac_best = mac(norm, _reference_shapes(reference_shapes, C.shape[0])).max(axis=1)
    return freq, zeta, norm, msv, mpc, mac_best, lam_k, bmod, keep, W


def _reference_shapes(value: npt.ArrayLike, q: int) -> FloatArray:
    """Known shapes (q, m) at the q outputs (a vector: one shape), each nonzero."""
    ref = require_numeric(value, "reference_shapes", "array")
    if ref.ndim == 1:
        ref = ref[:, None]
    if ref.ndim != 2 or ref.shape[0] != q or ref.shape[1] == 0:
        raise FieldError(
            "reference_shapes", f"must have shape ({q}, modes), one row per output, got {ref.shape}"
        )
    if np.any(np.all(ref == 0, axis=0)):
        raise FieldError("reference_shapes", "each shape must have a nonzero entry")
    return ref


def _realize(Y: FloatArray, order: int | None, rows: int, cols: int) -> Factors:
    q, r = Y.shape[1:]
    H0 = _hankel(Y, 1, rows, cols)
    H1 = _hankel(Y, 2, rows, cols)
    U, s, Vt = np.linalg.svd(H0, full_matrices=False)
    n = _order(s, order)
    Sh = np.sqrt(s[:n])
    A = (U[:, :n].T @ H1 @ Vt[:n].T) / np.outer(Sh, Sh)
    Ob = U[:, :n] * Sh
    Co = Sh[:, None] * Vt[:n]
    return A, Co[:, :r], Ob[:q], s, n, Ob, Co


def era(
    markov: npt.ArrayLike,
    dt: float = 1.0,
    order: int | None = None,
    rows: int | None = None,
    cols: int | None = None,
    reference_shapes: npt.ArrayLike | None = None,
) -> Realization:
    """Eigensystem Realization Algorithm (Juang & Pappa 1985).

    Parameters
    ----------
    markov : array_like (L+1, q, r)
        Markov parameters Y_0..Y_L (:func:`markov_parameters`, :func:`okid`); (L+1,) for SISO.
    dt : float
        Sample interval, s.
    order : int, optional
        Realization order n (twice the number of modes); default at the largest singular-value
        drop. Must not exceed the numerical rank of H(0).
    rows, cols : int, optional
        Hankel block rows α and columns β (see the sizing rules in the module docstring).
    reference_shapes : array_like (q, m), optional
        Known shapes at the output channels; gives ``mac``.

    Returns
    -------
    Realization

    Raises
    ------
    ValueError
        Naming the field: NaN in ``markov``, wrong shapes, ``order`` above the Hankel rank,
        Hankel sizes needing more data than given.
    """
    Y = check_markov(markov)
    dt = require_positive_scalar(dt, "dt", "s")
    L, q, r = Y.shape[0] - 1, Y.shape[1], Y.shape[2]
    order = None if order is None else require_count(order, "order")
    if reference_shapes is not None:
        reference_shapes = _reference_shapes(reference_shapes, q)
    rows, cols = _sizes(L, q, r, order, rows, cols)
    factors = _realize(Y, order, rows, cols)
    return _finish(Y, dt, factors, rows, cols, reference_shapes, (rows * q, cols * r))


def _perturbation_std(
    s: FloatArray,
    n: int,
    shape: tuple[int, int],
    W: InexactArray,
    keep: IntArray,
    lam: InexactArray,
    freq: FloatArray,
    zeta: FloatArray,
    dt: float,
) -> tuple[FloatArray, FloatArray]:
    """First-order standard deviations of f and ζ from the singular-value noise floor."""
    if n >= s.size:
        return np.zeros_like(freq), np.zeros_like(zeta)
    sigma_e = s[n] / (np.sqrt(shape[0]) + np.sqrt(shape[1]))  # per-entry noise of the Hankel
    Winv = np.linalg.inv(W)
    ih = 1.0 / np.sqrt(s[:n])
    left = np.linalg.norm(Winv[keep] * ih, axis=1)
    right = np.linalg.norm(W[:, keep] * ih[:, None], axis=0)
    std_s = sigma_e * left * right / (np.abs(lam) * dt)  # |δs| (complex, circular)
    w = 2 * np.pi * freq
    fstd = std_s / (np.sqrt(2) * 2 * np.pi)
    zstd = np.sqrt(np.clip(1 - zeta**2, 0, 1)) * std_s / (np.sqrt(2) * w)
    return fstd, zstd


def _finish(
    Y: FloatArray,
    dt: float,
    factors: Factors,
    rows: int,
    cols: int,
    reference_shapes: npt.ArrayLike | None,
    shape: tuple[int, int] | None,
    extra: dict[str, Any] | None = None,
) -> Realization:
    A, B, C, s, n, Ob, Co = factors
    q, r = Y.shape[1:]
    freq, zeta, shapes, msv, mpc, mac_best, lam, bmod, keep, W = _modes(
        A, B, C, dt, cols, reference_shapes
    )
    # EMAC at lag k = min(rows, cols) - 1: observability block k (modal) vs c λ^k,
    # controllability block k vs λ^k b (see the module docstring)
    k = min(rows, cols) - 1
    Winv = np.linalg.inv(W)
    obs_k = Ob[k * q : (k + 1) * q] @ W[:, keep]
    con_k = Winv[keep] @ Co[:, k * r : (k + 1) * r]
    raw = C @ W[:, keep]
    emac = np.array(
        [
            _coherence(raw[:, i] * lam[i] ** k, obs_k[:, i])
            * _coherence(bmod[i] * lam[i] ** k, con_k[i])
            for i in range(keep.size)
        ]
    )
    fstd = zstd = None
    if shape is not None:
        fstd, zstd = _perturbation_std(s, n, shape, W, keep, lam, freq, zeta, dt)
    return Realization(
        A,
        B,
        C,
        Y[0],
        dt,
        s,
        FrequencyArray(freq, "Hz"),
        zeta,
        shapes,
        emac,
        mpc,
        msv,
        mac_best,
        None if fstd is None else FrequencyArray(fstd, "Hz"),
        zstd,
        rows,
        cols,
        n,
        extra or {},
    )


def _markov_of(real: Realization, n: int) -> FloatArray:
    """Markov parameters D, CB, CAB, ... (n + 1 of them) of a discrete realization."""
    out, x = [real.D], real.B
    for _ in range(n):
        out.append(real.C @ x)
        x = real.A @ x
    return np.array(out)


def bootstrap_uncertainty(
    realization: Realization,
    markov: npt.ArrayLike,
    n_samples: int = 20,
    seed: int | None = None,
    match_tolerance: float = 0.05,
) -> Realization:
    """Standard deviations of the frequencies and damping ratios by parametric bootstrap.

    The residual ``markov - Y(realization)`` gives the noise level of each output/input pair
    (its standard deviation over the parameters after Y_0); ``n_samples`` noisy copies of the
    realization's own Markov parameters are realized by :func:`era` with the same order and
    Hankel sizes, each of their modes is paired with the nearest original mode in frequency
    (within ``match_tolerance``, relative), and the sample standard deviations replace
    ``frequency_std_hz`` and ``damping_std`` (NaN for a mode found in fewer than half the copies).

    Parameters
    ----------
    realization : Realization
        From :func:`era` on ``markov``.
    markov : array_like (L+1, q, r)
    n_samples : int
        Bootstrap copies (the relative error of a standard deviation from n samples is about
        ``1/sqrt(2 (n - 1))``: 16 % for 20).
    seed : int, optional
    match_tolerance : float

    Returns
    -------
    Realization
        A copy with the bootstrap ``frequency_std_hz`` and ``damping_std``;
        ``extra["uncertainty"] = "bootstrap"``, ``extra["bootstrap_samples"]`` and the
        bootstrap bias estimates ``extra["frequency_bias"]``, ``extra["damping_bias"]`` (mean
        of the copies minus the original: noise biases ERA damping upward, by up to 5 % of
        ζ at 2 % noise on the grid; subtract it for a bias-corrected estimate).
    """
    if not isinstance(realization, Realization):
        raise FieldError(
            "realization", f"must be a Realization (of era()), got {type(realization).__name__}"
        )
    Y = check_markov(markov)
    n = require_count(n_samples, "n_samples")
    if n < 2:
        raise FieldError("n_samples", f"at least 2 bootstrap copies are needed, got {n}")
    limits.check_count(
        n,
        limits.MAX_BOOTSTRAP_SAMPLES,
        "n_samples",
        "bootstrap copies (one ERA each)",
        "the standard deviations' own error is 1/sqrt(2 n): 0.7 % at the limit",
    )
    if seed is not None and not (limits.is_integral(seed) and 0 <= seed <= limits.MAX_SEED):
        raise FieldError(
            "seed", f"must be None or an integer in [0, {limits.MAX_SEED}], got {seed!r}"
        )
    tolerance = require_scalar(match_tolerance, "match_tolerance")
    if not 0 < tolerance <= 1:
        raise FieldError(
            "match_tolerance",
            f"must be a relative frequency difference in (0, 1], got {match_tolerance!r}",
        )
    if (
        realization.extra.get("method", "era") != "era"
        or realization.C.shape[0] != Y.shape[1]
        or realization.B.shape[1] != Y.shape[2]
    ):
        raise FieldError(
            "realization",
            "must come from era() on these Markov parameters "
            f"({Y.shape[1]} outputs, {Y.shape[2]} inputs)",
        )
    model = _markov_of(realization, Y.shape[0] - 1)
    sigma = (Y - model)[1:].std(axis=0)
    rng = np.random.default_rng(None if seed is None else int(seed))
    f0 = realization.frequencies_hz.view(np.ndarray)
    f_all = np.full((n, f0.size), np.nan)
    z_all = np.full((n, f0.size), np.nan)
    for b in range(n):
        copy = era(
            model + sigma[None] * rng.standard_normal(Y.shape),
            realization.dt,
            order=realization.order,
            rows=realization.rows,
            cols=realization.cols,
        )
        if copy.frequencies_hz.size == 0:
            continue
        for i, f in enumerate(f0):
            k = int(np.argmin(np.abs(copy.frequencies_hz - f)))
            if f > 0 and abs(copy.frequencies_hz[k] / f - 1) <= tolerance:
                f_all[b, i], z_all[b, i] = copy.frequencies_hz[k], copy.damping[k]
    found = np.sum(np.isfinite(f_all), axis=0)
    ok = found >= max(2, n // 2)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN columns of unmatched modes
        fstd = np.where(ok, np.nanstd(f_all, axis=0, ddof=1), np.nan)
        zstd = np.where(ok, np.nanstd(z_all, axis=0, ddof=1), np.nan)
        fbias = np.where(ok, np.nanmean(f_all, axis=0) - f0, np.nan)
        zbias = np.where(ok, np.nanmean(z_all, axis=0) - realization.damping, np.nan)
    return dataclasses.replace(
        realization,
        frequency_std_hz=FrequencyArray(fstd, "Hz"),
        damping_std=zstd,
        extra={
            **realization.extra,
            "uncertainty": "bootstrap",
            "bootstrap_samples": n,
            "frequency_bias": fbias,
            "damping_bias": zbias,
        },
    )


def era_dc(
    markov: npt.ArrayLike,
    dt: float = 1.0,
    order: int | None = None,
    rows: int | None = None,
    cols: int | None = None,
    blocks: int = 2,
    lag: int = 1,
    reference_shapes: npt.ArrayLike | None = None,
) -> Realization:
    """ERA with data correlations (ERA/DC; Juang, Cooper & Wright, *Control Theory Adv. Tech.*
    4(1), 1988), built on ERA (Juang & Pappa 1985).

    With :math:`R(k) = H(k) H(0)^T = P A^k (Q Q^T P^T)`, the block correlation Hankel matrix
    :math:`\\mathcal{R}(k)_{ij} = R(k + (i + j)\\tau)` (``blocks`` × ``blocks``, lag τ) factors
    as :math:`\\hat P A^k \\hat W`; its SVD gives A as in ERA, C from the first q rows of
    :math:`\\hat P = P_n \\Sigma_n^{1/2}` and B from :math:`P^{+} H(0)`. Correlating reduces
    the noise bias of the singular values. Arguments and result as :func:`era`; the
    perturbation uncertainty is not defined for the correlation matrix (``frequency_std_hz`` and
    ``damping_std`` are None).
    """
    Y = check_markov(markov)
    dt = require_positive_scalar(dt, "dt", "s")
    L, q, r = Y.shape[0] - 1, Y.shape[1], Y.shape[2]
    order = None if order is None else require_count(order, "order")
    if reference_shapes is not None:
        reference_shapes = _reference_shapes(reference_shapes, q)
    blocks = require_count(blocks, "blocks")
    lag = require_count(lag, "lag")
    reach = 1 + 2 * (blocks - 1) * lag
    if rows is None or cols is None:
        rows, cols = _sizes(L - reach, q, r, order, rows, cols)
    elif require_count(rows, "rows") + require_count(cols, "cols") + reach > L:
        raise FieldError(
            "rows",
            f"rows + cols + correlation reach {rows + cols + reach} exceeds "
            f"the {L} Markov parameters",
        )

    def build(rows: int, cols: int) -> Factors:
        H0 = _hankel(Y, 1, rows, cols)
        R = {k: _hankel(Y, 1 + k, rows, cols) @ H0.T for k in range(reach + 1)}

        def big(k: int) -> FloatArray:
            return np.block([[R[k + (i + j) * lag] for j in range(blocks)] for i in range(blocks)])

        U, s, Vt = np.linalg.svd(big(0), full_matrices=False)
        n = _order(s, order)
        Sh = np.sqrt(s[:n])
        A = (U[:, :n].T @ big(1) @ Vt[:n].T) / np.outer(Sh, Sh)
        Pn = (U[:, :n] * Sh)[: rows * q]
        Gam = np.linalg.pinv(Pn) @ H0
        return A, Gam[:, :r], Pn[:q], s, n, Pn, Gam

    return _finish(
        Y, dt, build(rows, cols), rows, cols, reference_shapes, None, extra={"method": "ERA/DC"}
    )
