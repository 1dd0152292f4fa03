r"""The "frontal assault": model parameters from measured FRFs and free-vibration frequencies.

Source: J. L. Junkins, T. C. Pollock and Z. H. Rahman, "CSI Sensing and Control: Analytical and
Experimental Results", 3rd NASA/DoD CSI Conference, San Diego, 1989, slides "Structural
identification: a frontal assault", Eqs. (8)–(12) (in Junkins, Pollock & Rahman 1990, the
Texas A&M final report; the FRF data layout — 3 motors × 6 strain gauges, 0.4–10 Hz in 0.2 Hz
steps — is that of Att. 6, G. H. James and J. L. Junkins, "Novel Sensing and Structural
Identification Methods: Preliminary Analytical and Experimental Results", AAS paper 89-425,
1989).

Model. A finite-element structure with stiffness linear in the parameters p (substructure
scalings, Att. 6 Eq. 5) and Rayleigh damping that follows the stiffness,

.. math::

    K(p) = K_0 + \sum_k p_k K_k, \qquad C(p) = \alpha M + \beta K(p),

    G(\omega, p) = H\,Z(\omega, p)^{-1} B, \qquad
    Z = (1 + i\omega\beta) K(p) + i\omega\alpha M - \omega^2 M,

with B the inputs (motor torques) and H the outputs (strain gauges). The free-vibration
frequencies Ω_i(p) are the undamped ones, K φ_i = Ω_i² M φ_i.

Objective (Eqs. 8–11). With ΔG(ω) = Ḡ(ω) − G(ω, p) and ΔΩ = Ω̄ − Ω(p),

.. math::

    J(p) = \tfrac12 \int_{\omega_{min}}^{\omega_{max}} \Delta G^H W_G \Delta G\,d\omega
         + \tfrac12 \Delta\Omega^T W_\Omega \Delta\Omega,

discretised (Eq. 11) on the measured frequencies by the trapezoid rule, q_k = trapezoid weight
/ mean spacing (1 inside, ½ at the ends), the real and imaginary parts of every FRF element
stacked, W_G = 1/σ_G² per element and W_Ω = 1/σ_Ω² by default.

Gauss–Newton (Eq. 12). [ΔG; ΔΩ] ≈ A Δp with A = [∂G/∂p; ∂Ω/∂p], Δp = A^† [ΔG; ΔΩ] — the
weighted pseudo-inverse (AᵀWA)⁻¹AᵀW — and p ← p + Δp. The sensitivities are analytic:

.. math::

    \frac{\partial G}{\partial p_k} = -H Z^{-1} \frac{\partial Z}{\partial p_k} Z^{-1} B
    = -(1 + i\omega\beta)\,(H Z^{-1}) K_k (Z^{-1} B), \qquad
    \frac{\partial \Omega_i}{\partial p_k} = \frac{\varphi_i^T K_k \varphi_i}{2\Omega_i}
    \quad (\varphi_i^T M \varphi_i = 1)

(the second is the classical eigenvalue derivative, distinct frequencies only). Both are checked
against central differences in the tests.

Covariance. With measurement noise of standard deviation σ_G on each real and imaginary part
and σ_Ω on each frequency, the first-order covariance of the estimate is the sandwich
(AᵀWA)⁻¹ AᵀW Σ W A (AᵀWA)⁻¹ (Σ = diag of the noise variances), which is (AᵀΣ⁻¹A)⁻¹ when
W = Σ⁻¹; the trapezoid's half weights at the ends make W ≠ Σ⁻¹ there, hence the sandwich.

"Potential trouble in toyland" (the slides): the iteration converges only if the model is
good and p_start is close to p. :func:`frontal_assault` runs the paper's plain Gauss–Newton
(``step_control="none"``) or halves a step until J decreases (``"halving"``);
docs/identification.md reports the measured basin of both on the TAMU grid.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt
import scipy.linalg as sla

from flexsat.input_checks import FieldError, require_count, require_finite, require_nonneg
from flexsat.units import FloatArray

__all__ = [
    "FRFData",
    "FrontalAssaultModel",
    "FrontalAssaultResult",
    "basin",
    "frontal_assault",
    "trapezoid_weights",
]

ComplexArray = npt.NDArray[np.complex128]
STEP_CONTROLS = ("none", "halving")


def _square(value: npt.ArrayLike, name: str, n: int | None = None) -> FloatArray:
    arr = require_finite(value, name)
    if arr.ndim != 2 or arr.shape[0] != arr.shape[1] or (n is not None and arr.shape[0] != n):
        want = f"({n}, {n})" if n is not None else "square"
        raise FieldError(name, f"must be a {want} matrix, got shape {arr.shape}")
    return arr


@dataclass(frozen=True)
class FrontalAssaultModel:
    """M, K(p) = K0 + Σ p_k K_k, Rayleigh C = α M + β K(p), inputs B (n, m), outputs H (s, n).

    ``names`` label the parameters (default ``p1``, ``p2``, ...). Matrices may be dense arrays
    or anything :func:`numpy.asarray` turns into one (convert sparse matrices with
    ``.toarray()``)."""

    M: FloatArray
    K0: FloatArray
    K_parts: tuple[FloatArray, ...]
    B: FloatArray
    H: FloatArray
    alpha: float = 0.0
    beta: float = 0.0
    names: tuple[str, ...] = field(default=())

    def __post_init__(self) -> None:
        m = _square(self.M, "M")
        n = m.shape[0]
        object.__setattr__(self, "M", m)
        object.__setattr__(self, "K0", _square(self.K0, "K0", n))
        parts = tuple(_square(k, f"K_parts[{i}]", n) for i, k in enumerate(self.K_parts))
        if not parts:
            raise FieldError("K_parts", "at least one stiffness part K_k is needed")
        object.__setattr__(self, "K_parts", parts)
        b = require_finite(self.B, "B")
        b = b[:, None] if b.ndim == 1 else b
        if b.ndim != 2 or b.shape[0] != n:
            raise FieldError("B", f"must be ({n}, m), got shape {b.shape}")
        h = require_finite(self.H, "H")
        h = h[None, :] if h.ndim == 1 else h
        if h.ndim != 2 or h.shape[1] != n:
            raise FieldError("H", f"must be (s, {n}), got shape {h.shape}")
        object.__setattr__(self, "B", b)
        object.__setattr__(self, "H", h)
        for name in ("alpha", "beta"):
            object.__setattr__(self, name, float(require_nonneg(getattr(self, name), name)))
        names = tuple(self.names) or tuple(f"p{i + 1}" for i in range(len(parts)))
        if len(names) != len(parts):
            raise FieldError("names", f"one name per stiffness part ({len(parts)}), got {names}")
        object.__setattr__(self, "names", names)

    @property
    def n_parameters(self) -> int:
        return len(self.K_parts)

    def _p(self, p: npt.ArrayLike) -> FloatArray:
        arr = require_finite(p, "p").reshape(-1)
        if arr.size != self.n_parameters:
            raise FieldError("p", f"must hold {self.n_parameters} parameters, got {arr.size}")
        return arr

    def stiffness(self, p: npt.ArrayLike) -> FloatArray:
        """K(p) = K0 + Σ p_k K_k."""
        pv = self._p(p)
        return self.K0 + sum((pk * kk for pk, kk in zip(pv, self.K_parts)), np.zeros_like(self.K0))

    def frf(self, p: npt.ArrayLike, omega: npt.ArrayLike) -> ComplexArray:
        """G(ω, p) = H Z⁻¹ B at each ω (rad/s): shape (len(ω), s, m)."""
        return self.frf_and_sensitivity(p, omega, sensitivity=False)[0]

    def frf_and_sensitivity(
        self, p: npt.ArrayLike, omega: npt.ArrayLike, sensitivity: bool = True
    ) -> tuple[ComplexArray, ComplexArray]:
        """G (len(ω), s, m) and ∂G/∂p (len(ω), s, m, P) (module docstring; empty if not
        ``sensitivity``)."""
        w = require_finite(omega, "omega", "rad/s").reshape(-1)
        k = self.stiffness(p)
        s_out, m_in = self.H.shape[0], self.B.shape[1]
        g = np.empty((w.size, s_out, m_in), complex)
        dg = np.empty((w.size, s_out, m_in, self.n_parameters) if sensitivity else (0,), complex)
        for j, wj in enumerate(w):
            factor = 1.0 + 1j * wj * self.beta
            z = factor * k + (1j * wj * self.alpha - wj**2) * self.M
            lu = sla.lu_factor(z)
            zb = sla.lu_solve(lu, self.B.astype(complex))
            g[j] = self.H @ zb
            if sensitivity:
                hz = sla.lu_solve(lu, self.H.T.astype(complex), trans=1).T  # H Z⁻¹
                for i, kk in enumerate(self.K_parts):
                    dg[j, :, :, i] = -factor * (hz @ (kk @ zb))
        return g, dg

    def modes(self, p: npt.ArrayLike, count: int) -> tuple[FloatArray, FloatArray]:
        """The ``count`` lowest undamped frequencies Ω (rad/s) and their mass-normalised
        shapes (n, count)."""
        c = require_count(count, "count")
        n = self.M.shape[0]
        if c > n:
            raise FieldError("count", f"the model has {n} modes, got {c}")
        k = self.stiffness(p)
        _, phi = sla.eigh(k, self.M, subset_by_index=(0, c - 1))
        # the Rayleigh quotient of each vector: its error is second order in the vector's, where
        # the Cholesky-reduced eigenvalue carries an absolute error ~ ε λ_max
        mass = np.einsum("ni,nm,mi->i", phi, self.M, phi)
        lam = np.einsum("ni,nm,mi->i", phi, k, phi) / mass
        if np.any(lam <= 0):
            raise FieldError("p", "K(p) is not positive definite at these parameters")
        return np.sqrt(lam), phi / np.sqrt(mass)

    def frequencies_and_sensitivity(
        self, p: npt.ArrayLike, count: int
    ) -> tuple[FloatArray, FloatArray]:
        """Ω (count,) rad/s and ∂Ω/∂p (count, P) = φᵀ K_k φ / (2Ω)."""
        om, phi = self.modes(p, count)
        d = np.stack([np.einsum("ni,nm,mi->i", phi, kk, phi) for kk in self.K_parts], axis=1)
        return om, d / (2 * om[:, None])


@dataclass(frozen=True)
class FRFData:
    """Measured FRFs and free-vibration frequencies (rad/s).

    Parameters
    ----------
    omega : array_like (K,)
        Measurement frequencies, rad/s (or a Quantity / unit string: Hz converted), increasing.
    frf : array_like (K, s, m) complex
        Ḡ(ω_k): outputs × inputs of the model's H and B.
    frf_sigma : float or array_like (K, s, m)
        Standard deviation of each real and of each imaginary part.
    frequencies : array_like (r,), optional
        Ω̄, the lowest r undamped frequencies, rad/s.
    frequency_sigma : float or array_like (r,)
        Their standard deviations, rad/s.
    """

    omega: FloatArray
    frf: ComplexArray
    frf_sigma: FloatArray
    frequencies: FloatArray = field(default_factory=lambda: np.zeros(0))
    frequency_sigma: FloatArray = field(default_factory=lambda: np.ones(0))

    def __post_init__(self) -> None:
        w = require_finite(self.omega, "omega", "rad/s").reshape(-1)
        if w.size < 2 or np.any(np.diff(w) <= 0) or w[0] < 0:
            raise FieldError("omega", "must be two or more increasing frequencies >= 0 (rad/s)")
        g = np.asarray(self.frf)
        if g.ndim != 3 or g.shape[0] != w.size or not np.all(np.isfinite(g)):
            raise FieldError(
                "frf", f"must be finite (K, s, m) with K = {w.size} frequencies, got {g.shape}"
            )
        sig = np.broadcast_to(require_finite(self.frf_sigma, "frf_sigma"), g.shape).astype(float)
        if np.any(sig <= 0):
            raise FieldError("frf_sigma", "standard deviations must be > 0")
        om = require_finite(self.frequencies, "frequencies", "rad/s").reshape(-1)
        so = np.broadcast_to(
            require_finite(self.frequency_sigma, "frequency_sigma", "rad/s"), om.shape
        ).astype(float)
        if om.size and (np.any(om <= 0) or np.any(so <= 0)):
            raise FieldError("frequencies", "frequencies and their sigmas must be > 0 (rad/s)")
        object.__setattr__(self, "omega", w)
        object.__setattr__(self, "frf", g.astype(complex))
        object.__setattr__(self, "frf_sigma", sig)
        object.__setattr__(self, "frequencies", om)
        object.__setattr__(self, "frequency_sigma", so)


def trapezoid_weights(omega: npt.ArrayLike) -> FloatArray:
    """Trapezoid-rule weights of Eq. (10)'s integral on ``omega``, divided by the mean spacing
    (1 inside a uniform grid, ½ at its ends)."""
    w = np.asarray(omega, float).reshape(-1)
    d = np.diff(w)
    q = np.zeros(w.size)
    q[:-1] += d / 2
    q[1:] += d / 2
    out: FloatArray = q / d.mean()
    return out


@dataclass(frozen=True)
class FrontalAssaultResult:
    """Outcome of :func:`frontal_assault`.

    ``p`` the estimate; ``covariance`` the sandwich covariance (module docstring);
    ``cost`` J at each iterate (the first at p_start); ``steps`` the Δp taken; ``converged``
    whether the last step fell below the tolerance; ``reason`` why the iteration stopped.
    """

    p: FloatArray
    covariance: FloatArray
    cost: tuple[float, ...]
    steps: tuple[FloatArray, ...]
    converged: bool
    reason: str
    names: tuple[str, ...]

    @property
    def sigma(self) -> FloatArray:
        return np.sqrt(np.diag(self.covariance))

    @property
    def iterations(self) -> int:
        return len(self.steps)


def _residual_and_jacobian(
    model: FrontalAssaultModel, data: FRFData, p: FloatArray, jacobian: bool = True
) -> tuple[FloatArray, FloatArray]:
    g, dg = model.frf_and_sensitivity(p, data.omega, sensitivity=jacobian)
    dgv = (data.frf - g).reshape(-1)
    r = [dgv.real, dgv.imag]
    rows = []
    if jacobian:
        a = dg.reshape(-1, model.n_parameters)
        rows = [a.real, a.imag]
    if data.frequencies.size:
        om, dom = model.frequencies_and_sensitivity(p, data.frequencies.size)
        r.append(data.frequencies - om)
        if jacobian:
            rows.append(dom)
    return np.concatenate(r), (np.vstack(rows) if jacobian else np.zeros((0, 0)))


def _weights(data: FRFData, frf_weight: float = 1.0) -> tuple[FloatArray, FloatArray]:
    """W (diagonal) of Eq. (10) and the noise variances Σ, in the residual's order."""
    q = trapezoid_weights(data.omega)[:, None, None]
    var = data.frf_sigma**2
    wg = frf_weight * np.broadcast_to(q / var, var.shape).reshape(-1)
    w = np.concatenate([wg, wg, 1 / data.frequency_sigma**2])
    sig = np.concatenate([var.reshape(-1), var.reshape(-1), data.frequency_sigma**2])
    return w, sig


def frontal_assault(
    model: FrontalAssaultModel,
    data: FRFData,
    p_start: npt.ArrayLike,
    iterations: int = 30,
    tol: float = 1e-12,
    step_control: str = "none",
    max_halvings: int = 30,
    frf_weight: float = 1.0,
) -> FrontalAssaultResult:
    """Gauss–Newton on Eq. (10)–(12) (module docstring) from ``p_start``.

    Parameters
    ----------
    model : FrontalAssaultModel
    data : FRFData
        Measured FRFs on the model's outputs × inputs, and free-vibration frequencies.
    p_start : array_like (P,)
    iterations : int
        Gauss–Newton steps at most.
    tol : float
        Converged when max |Δp| ≤ tol · max(1, max |p|).
    step_control : str
        ``"none"``: the paper's full steps; ``"halving"``: a step is halved until J does not
        increase (at most ``max_halvings`` times, then the iteration stops).
    frf_weight : float
        Factor on W_G against W_Ω (> 0; 1: both the inverse noise variances). A small factor
        first (frequencies dominate), then 1, widens the basin (docs/identification.md).

    Raises
    ------
    FieldError
        Shapes that do not match the model, an unknown ``step_control``, or a Jacobian of
        lower rank than the parameters (the data do not determine p).
    """
    if step_control not in STEP_CONTROLS:
        raise FieldError("step_control", f"must be one of {STEP_CONTROLS}, got {step_control!r}")
    s_out, m_in = model.H.shape[0], model.B.shape[1]
    if data.frf.shape[1:] != (s_out, m_in):
        raise FieldError(
            "data.frf",
            f"must be (K, {s_out}, {m_in}) for the model's H and B, got {data.frf.shape}",
        )
    p = model._p(p_start).copy()
    fw = float(require_finite(frf_weight, "frf_weight").reshape(-1)[0])
    if not fw > 0:
        raise FieldError("frf_weight", f"must be > 0, got {frf_weight!r}")
    w, var = _weights(data, fw)
    sw = np.sqrt(w)

    def cost(r: FloatArray) -> float:
        return 0.5 * float(np.sum(w * r * r))

    costs: list[float] = []
    steps: list[FloatArray] = []
    reason = "iteration limit"
    converged = False
    try:
        r, a = _residual_and_jacobian(model, data, p)
    except FieldError as exc:
        raise FieldError("p_start", f"the model cannot be evaluated at p_start: {exc}") from None
    costs.append(cost(r))
    for _ in range(require_count(iterations, "iterations")):
        aw = a * sw[:, None]
        sv = np.linalg.svd(aw, compute_uv=False)
        if sv[-1] <= sv[0] * 1e-12 * len(sv):
            raise FieldError(
                "data",
                f"the Jacobian has rank < {model.n_parameters} (singular values "
                f"{sv[0]:.3g} ... {sv[-1]:.3g}): "
                "the FRFs and frequencies do not determine every parameter",
            )
        dp = np.linalg.lstsq(aw, sw * r, rcond=None)[0]
        trial = p + dp
        try:
            r_t, a_t = _residual_and_jacobian(model, data, trial)
            c_t = cost(r_t)
        except FieldError:
            c_t, r_t, a_t = np.inf, r, a
        halvings = 0
        while step_control == "halving" and c_t > costs[-1] and halvings < max_halvings:
            dp = dp / 2
            trial = p + dp
            halvings += 1
            try:
                r_t, a_t = _residual_and_jacobian(model, data, trial)
                c_t = cost(r_t)
            except FieldError:
                c_t = np.inf
        if not np.isfinite(c_t):
            reason = "the step left the region where K(p) is positive definite"
            break
        if step_control == "halving" and c_t > costs[-1]:
            reason = "no step that lowers J"
            break
        p, r, a = trial, r_t, a_t
        steps.append(np.asarray(dp, dtype=float))
        costs.append(c_t)
        if np.max(np.abs(dp)) <= tol * max(1.0, float(np.max(np.abs(p)))):
            converged, reason = True, "converged"
            break
    info = np.linalg.inv(a.T @ (a * w[:, None]))  # (Aᵀ W A)⁻¹
    cov = info @ ((a * (w * w * var)[:, None]).T @ a) @ info  # sandwich with Aᵀ W Σ W A
    return FrontalAssaultResult(
        p=p,
        covariance=cov,
        cost=tuple(costs),
        steps=tuple(steps),
        converged=converged,
        reason=reason,
        names=model.names,
    )


def basin(
    model: FrontalAssaultModel,
    data: FRFData,
    p_true: npt.ArrayLike,
    directions: Sequence[npt.ArrayLike],
    scales: Sequence[float],
    step_control: str = "none",
    tolerance: float = 1e-6,
    frequencies_first: bool = False,
) -> FloatArray:
    """Convergence map: for each direction d (relative, per parameter) and scale s, whether the
    iteration from p_true ⊙ (1 + s d) returns to p_true within ``tolerance`` (relative).
    Returns a (len(directions), len(scales)) array of 1.0 (converged to p_true), 0.0 (stopped
    or diverged) and 0.5 (converged elsewhere: a wrong local minimum). With
    ``frequencies_first`` each start is first fitted with ``frf_weight=1e-6`` (the frequencies
    dominate), then with the full weights."""
    pt = model._p(p_true)
    out = np.zeros((len(directions), len(scales)))
    for i, d in enumerate(directions):
        dv = require_finite(d, "directions").reshape(-1)
        for j, s in enumerate(scales):
            start = pt * (1 + float(s) * dv)
            if np.any(start <= 0):
                continue
            try:
                if frequencies_first:
                    start = frontal_assault(
                        model, data, start, 40, step_control=step_control, frf_weight=1e-6
                    ).p
                res = frontal_assault(model, data, start, iterations=40, step_control=step_control)
            except FieldError:
                continue
            if res.converged and np.all(np.abs(res.p / pt - 1) < tolerance):
                out[i, j] = 1.0
            elif res.converged:
                out[i, j] = 0.5
    return out
