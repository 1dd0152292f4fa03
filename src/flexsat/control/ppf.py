r"""Positive position feedback (PPF) on collocated actuator/sensor pairs (issue #12).

B. N. Agrawal and H. Bang, *Adaptive Structures for Large Precision Antennas*, Acta Astronautica
1996 (IAF-94.1.4.202), §2; where the printed equations are wrong the docstrings below say so.

The structure in modal coordinates (Eq. 2), with n_a collocated pairs,

.. math::

    \ddot\eta + D\dot\eta + \Omega\eta = B_a u, \qquad y = C_s \eta,

B_a (m × n_a) the actuator influence (the paper's a_1 F̄ = a_1 Φᵀ F) and C_s (n_a × m) the
sensor rows (a_2 Fᵀ Φ). A bank of second-order filters, one per (actuator i, tuned mode j),
n_f = n_a n_t filters (Eqs. 3–4), each fed by its pair's sensor through the replicate matrix E
(n_f × n_a, ``E[i n_t + j, i] = 1``, reconstructed, not printed):

.. math::

    \ddot\xi + D_f\dot\xi + \Omega_f\xi = \Omega_f E y, \qquad u = E^T G \xi,

G = diag(g), g ordered actuator-major, ``g[i n_t + j] = g_ij`` (Eqs. 38–39). The closed loop
(Eqs. 5, 8) over x = [η, η̇, ξ, ξ̇] is

.. math::

    \bar A = \begin{bmatrix} 0 & I & 0 & 0 \\ -\Omega & -D & B_a E^T G & 0 \\
             0 & 0 & 0 & I \\ \Omega_f E C_s & 0 & -\Omega_f & -D_f \end{bmatrix}

(the (4,1) block is a_2 Ω_f C, a misprint repaired of the printed "a_2 C_f C"). In the paper's
notation a_1 Cᵀ G ξ = B_a Eᵀ G ξ and a_2 C η = E C_s η with C = E Fᵀ Φ.

Stability (Eq. 6): S = Ω − a_1 a_2 Cᵀ G C = Ω − B_a Eᵀ G E C_s. For collocated pairs
(B_a[:, i] = r_i C_s[i]ᵀ, r_i = a_1/a_2 of pair i > 0) S is symmetric, and scaling the filter
equations by G R Ω_f⁻¹ makes the loop a symmetric second-order system with "mass"
diag(I, G R Ω_f⁻¹), damping diag(D, G R Ω_f⁻¹ D_f) and stiffness whose Schur complement is S
(derived, not printed). So S > 0 decides stability only when G > 0 and both dampings are positive
definite; otherwise (a negative gain) S can be positive definite for an unstable loop and the
closed-loop eigenvalues decide.

Cost (Eqs. 7, 10–12): J = ½ tr(P̄ X₀), P̄ the solution of
Āᵀ P̄ + P̄ Ā + Q_s + Kᵀ Q_u K = 0 (P_s + P_u of Eq. 12 in one equation), K = [0, 0, Eᵀ G, 0] the
state form of u, X₀ = x₀ x₀ᵀ or E[x₀ x₀ᵀ] over an initial-condition distribution (F10).
Gradient, repaired (a sign error repaired), with V from Eq. 14
(Ā V + V Āᵀ + X₀ = 0):

.. math::

    \frac{\partial J}{\partial g_k}
        = \mathrm{tr}\Big[V \bar P \frac{\partial\bar A}{\partial g_k}\Big]
        + \mathrm{tr}\Big[V K^T Q_u \frac{\partial K}{\partial g_k}\Big]
    = \big[V(\bar P B + K^T Q_u)\big]_{\xi_k,\, i(k)},

since ∂Ā/∂g_k = B ∂K/∂g_k and ∂K/∂g_k has its single 1 at (actuator i(k), filter state ξ_k)
(B = [0; B_a; 0; 0]). The printed form, tr[V P ∂Ā] + tr[V (P_u B − Gᵀ Q_u) ∂G] with u = −G x,
has the sign of its second term flipped (relative error O(1) once Q_u is not negligible).

Eigenvalue sensitivities of S (Eqs. 26–27, S symmetric so ψ_i = φ_i):
∂λ_i/∂g_k = φ_iᵀ (∂S/∂g_k) φ_i, ∂S/∂g_k = −a_1 a_2 Cᵀ (∂G/∂g_k) C = −B_a[:, i] C_s[i].
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Protocol

import numpy as np
import scipy.linalg

from flexsat.control.lqr import check_matrix, check_psd, check_square
from flexsat.control.state_space_compensator import StateSpaceCompensator
from flexsat.input_checks import (
    FieldError,
    require_count,
    require_finite,
    require_nonneg,
    require_positive,
)

if TYPE_CHECKING:
    import numpy.typing as npt

    import control as ct
    from flexsat.analysis.sensitivity import InexactArray
    from flexsat.control.linear_form import ChannelItems
    from flexsat.units import FloatArray, QuantityArrayLike

__all__ = [
    "CollocatedPair",
    "PPFBank",
    "PPFController",
    "PPFModel",
    "PPFProblem",
    "PPFStability",
    "initial_second_moment",
    "ppf_closed_loop",
    "ppf_compensator",
    "ppf_cost_gradient",
    "ppf_feedback",
    "ppf_state_matrices",
    "ppf_stiffness",
    "ppf_stiffness_gradient",
    "replicate_matrix",
]

#: collocation: |B_a[:, i] − r_i C_s[i]| ≤ COLLOCATION_TOL |B_a[:, i]| (a few hundred ulps of
#: the vectors: the case's actuator and sensor vectors are one modal difference times two gains)
COLLOCATION_TOL = 1e-10


# ------------------------------------------------------------------------------------------------
# kernels (plain arrays; gains may carry leading case axes)
class CollocatedPair(Protocol):
    """An actuator/sensor pair in modal coordinates (a case's piezo pair): the modal force of
    a unit command (m,) and the sensor's modal output row (m,)."""

    @property
    def actuator(self) -> npt.ArrayLike: ...

    @property
    def sensor(self) -> npt.ArrayLike: ...


def replicate_matrix(n_actuators: int, n_tuned: int) -> FloatArray:
    """E (n_a n_t × n_a): sensor i copied to its n_t mode-tuned filters, ``E[i n_t + j, i] = 1``
    (Agrawal & Bang 1996 Eq. 4; the paper does not print E: reconstructed)."""
    return np.asarray(np.kron(np.eye(n_actuators), np.ones((n_tuned, 1))), np.float64)


def ppf_state_matrices(
    omega: FloatArray,
    zeta: FloatArray,
    B_a: FloatArray,
    C_s: FloatArray,
    omega_f: FloatArray,
    zeta_f: FloatArray,
    E: FloatArray,
) -> tuple[FloatArray, FloatArray]:
    r"""Open part A₀ and input matrix B of the closed loop Ā = A₀ + B K(g) (Eq. 8).

    Parameters
    ----------
    omega, zeta : (m,) arrays
        Structural frequencies (rad/s) and damping ratios.
    B_a : (m, n_a) array
        Modal actuator influence (a_1 F̄ of Eq. 2).
    C_s : (n_a, m) array
        Modal sensor rows (a_2 Fᵀ Φ).
    omega_f, zeta_f : (n_f,) arrays
        Filter frequencies (rad/s) and damping ratios, in filter order.
    E : (n_f, n_a) array
        Replicate matrix.

    Returns
    -------
    A0 : (n_x, n_x) array
        Ā at g = 0, n_x = 2m + 2n_f, with the (4,1) block Ω_f E C_s (a misprint repaired).
    B : (n_x, n_a) array
        [0; B_a; 0; 0].
    """
    m, nf = omega.size, omega_f.size
    n = 2 * m + 2 * nf
    A0 = np.zeros((n, n))
    im, ivm = np.arange(m), m + np.arange(m)
    i_xi, i_xid = 2 * m + np.arange(nf), 2 * m + nf + np.arange(nf)
    A0[im, ivm] = 1.0
    A0[ivm, im] = -(omega**2)
    A0[ivm, ivm] = -2 * zeta * omega
    A0[i_xi, i_xid] = 1.0
    A0[2 * m + nf :, :m] = (omega_f**2)[:, None] * (E @ C_s)
    A0[i_xid, i_xi] = -(omega_f**2)
    A0[i_xid, i_xid] = -2 * zeta_f * omega_f
    B = np.zeros((n, B_a.shape[1]))
    B[m : 2 * m] = B_a
    return A0, B


def ppf_feedback(g: npt.ArrayLike, E: FloatArray, n_modes: int) -> FloatArray:
    """K (..., n_a, n_x) with u = K x = Eᵀ G ξ (Eq. 5; the paper's −G of Eq. 9: ambiguous)."""
    gains = np.asarray(g, float)
    nf, na = E.shape
    K = np.zeros(gains.shape[:-1] + (na, 2 * n_modes + 2 * nf))
    K[..., 2 * n_modes : 2 * n_modes + nf] = np.swapaxes(E * gains[..., :, None], -1, -2)
    return K


def ppf_closed_loop(A0: FloatArray, B: FloatArray, K: FloatArray) -> FloatArray:
    """Ā = A₀ + B K (Eq. 8), (..., n_x, n_x) for K (..., n_a, n_x)."""
    return A0 + B @ K


def ppf_stiffness(
    omega: FloatArray, B_a: FloatArray, C_s: FloatArray, E: FloatArray, g: npt.ArrayLike
) -> FloatArray:
    r"""S = Ω − a_1 a_2 Cᵀ G C = Ω − B_a (Eᵀ G E) C_s (Eq. 6), symmetrised, (..., m, m).

    Eᵀ G E is diagonal, each actuator's gains summed over its filters (each filter passes a
    constant sensor signal with unit gain: Ω_f⁻¹ Ω_f), so S sees the quasi-static feedback.
    """
    s = np.asarray(g, float) @ E  # (..., n_a): diagonal of Eᵀ G E
    S = np.diag(omega**2) - np.einsum("ki,...i,il->...kl", B_a, s, C_s)
    return 0.5 * (S + np.swapaxes(S, -1, -2))


def ppf_stiffness_gradient(B_a: FloatArray, C_s: FloatArray, E: FloatArray) -> FloatArray:
    """∂S/∂g_k = −a_1 a_2 Cᵀ (∂G/∂g_k) C = −sym(B_a[:, i(k)] C_s[i(k)]) (Eq. 26), (n_f, m, m)."""
    outer = -np.einsum("ki,il->ikl", B_a, C_s)
    outer = 0.5 * (outer + np.swapaxes(outer, -1, -2))
    return outer[np.argmax(E, axis=1)]


def _lyap(A: FloatArray, Q: FloatArray) -> FloatArray:
    """X with A X + X Aᵀ + Q = 0 (Bartels–Stewart), symmetrised."""
    X = scipy.linalg.solve_continuous_lyapunov(A, -Q)
    return 0.5 * (X + X.T)


def ppf_cost_gradient(
    A0: FloatArray,
    B: FloatArray,
    E: FloatArray,
    n_modes: int,
    g: npt.ArrayLike,
    Q_s: FloatArray,
    Q_u: FloatArray,
    X0: FloatArray,
    gradient: bool = True,
) -> tuple[FloatArray, FloatArray | None]:
    r"""J = ½ tr(P̄ X₀) (Eqs. 10–12) and the repaired ∂J/∂g (Eqs. 13–14, printed sign repaired).

    Parameters
    ----------
    A0, B : arrays from :func:`ppf_state_matrices`
    E : (n_f, n_a) array
    n_modes : int
    g : (..., n_f) array
        Gains; leading axes are cases (one pair of Lyapunov solves each).
    Q_s : (n_x, n_x) array
        State weight (Eq. 12).
    Q_u : (n_a, n_a) array
        Control weight on u = Eᵀ G ξ.
    X0 : (n_x, n_x) array
        x₀ x₀ᵀ or E[x₀ x₀ᵀ].
    gradient : bool
        Also solve Eq. 14 and return ∂J/∂g.

    Returns
    -------
    J : (...) array
    dJ : (..., n_f) array or None
        [V (P̄ B + Kᵀ Q_u)] at (ξ_k, i(k)) (module docstring).

    The cost is finite only for a stable Ā; an unstable one gives a P̄ that is not the integral
    of Eq. 7, so callers check stability first (:class:`PPFProblem` does).
    """
    gains = np.asarray(g, float)
    lead = gains.shape[:-1]
    flat = gains.reshape(-1, gains.shape[-1])
    K_all = ppf_feedback(flat, E, n_modes)
    nf = E.shape[0]
    xi = 2 * n_modes + np.arange(nf)
    act = np.argmax(E, axis=1)
    J = np.empty(flat.shape[0])
    dJ = np.empty(flat.shape) if gradient else None
    for c, K in enumerate(K_all):
        Abar = A0 + B @ K
        P = _lyap(Abar.T, Q_s + K.T @ Q_u @ K)
        J[c] = 0.5 * np.sum(P * X0)
        if dJ is not None:
            V = _lyap(Abar, X0)
            W = V[xi] @ (P @ B + K.T @ Q_u)
            dJ[c] = W[np.arange(nf), act]
    return J.reshape(lead), (None if dJ is None else dJ.reshape(gains.shape))


def initial_second_moment(x0: npt.ArrayLike, weights: npt.ArrayLike | None = None) -> FloatArray:
    """X₀ = E[x₀ x₀ᵀ] over initial conditions (Agrawal & Bang 1996 §4, spec F10).

    Parameters
    ----------
    x0 : (n,) or (n_samples, n) array
        One initial state (X₀ = x₀ x₀ᵀ, Eq. 10) or samples of the distribution.
    weights : (n_samples,) array, optional
        Non-negative probabilities (normalised here); equal by default.
    """
    x = require_finite(x0, "x0")
    if x.ndim == 1:
        x = x[None]
    if x.ndim != 2 or x.size == 0:
        raise FieldError("x0", f"must have shape (n,) or (n_samples, n), got {x.shape}")
    if weights is None:
        w = np.full(x.shape[0], 1.0 / x.shape[0])
    else:
        w = require_nonneg(weights, "weights")
        if w.shape != (x.shape[0],) or w.sum() <= 0:
            raise FieldError(
                "weights",
                f"must be {x.shape[0]} non-negative numbers, not all zero, got shape {w.shape}",
            )
        w = w / w.sum()
    return np.einsum("s,si,sj->ij", w, x, x)


# ------------------------------------------------------------------------------------------------
# objects
@dataclass(frozen=True, eq=False)
class PPFModel:
    """Modal structure with n_a collocated pairs (Eq. 2; module docstring).

    Parameters
    ----------
    omega : (m,) array_like
        Natural frequencies, rad/s, > 0.
    zeta : scalar or (m,) array_like
        Modal damping ratios, ≥ 0.
    actuators : (m, n_a) array_like
        B_a: modal force of a unit command of each pair (its a_1 included).
    sensors : (n_a, m) array_like
        C_s: output row of each pair (its a_2 included).

    Raises
    ------
    ValueError
        Naming the field: non-finite values, mismatched shapes, a zero sensor row (a_2 = 0) or
        actuator column, a pair whose actuator is not a positive multiple of its sensor
        (non-collocated; S of Eq. 6 needs collocation).
    """

    omega: FloatArray
    zeta: FloatArray
    actuators: FloatArray
    sensors: FloatArray
    #: a_1/a_2 of each pair (B_a[:, i] = ratio[i] C_s[i]), set from the vectors
    ratio: FloatArray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        w = require_positive(self.omega, "omega", "rad/s")
        if w.ndim != 1 or w.size == 0:
            raise FieldError(
                "omega", f"must be a 1-D array of the m modal frequencies, got shape {w.shape}"
            )
        m = w.size
        z = require_nonneg(self.zeta, "zeta")
        if z.ndim > 1 or z.size not in (1, m):
            raise FieldError(
                "zeta", f"must be a scalar or one ratio per mode ({m}), got shape {z.shape}"
            )
        B_a = check_matrix(self.actuators, "actuators", m, None, f"(m, n_a) = ({m}, n_a)")
        na = B_a.shape[1]
        C_s = check_matrix(
            self.sensors, "sensors", na, m, f"(n_a, m) = ({na}, {m}), one row per actuator"
        )
        ratio = np.empty(na)
        for i in range(na):
            s, b = C_s[i], B_a[:, i]
            if not np.any(s):
                raise FieldError(f"sensors[{i}]", f"pair {i + 1} has a zero sensor row (a_2 = 0)")
            if not np.any(b):
                raise FieldError(
                    f"actuators[:, {i}]", f"pair {i + 1} has a zero actuator column (a_1 = 0)"
                )
            r = (b @ s) / (s @ s)
            if r <= 0 or np.linalg.norm(b - r * s) > COLLOCATION_TOL * np.linalg.norm(b):
                raise FieldError(
                    f"actuators[:, {i}]",
                    f"pair {i + 1} is not collocated: its actuator "
                    f"influence must be a positive multiple of its sensor row "
                    f"(a_1/a_2 > 0), residual {np.linalg.norm(b - r * s):.3g} of "
                    f"{np.linalg.norm(b):.3g}",
                )
            ratio[i] = r
        for name, arr in (
            ("omega", w),
            ("zeta", np.broadcast_to(z, (m,)).copy()),
            ("actuators", B_a),
            ("sensors", C_s),
            ("ratio", ratio),
        ):
            arr = np.array(arr, float)
            arr.flags.writeable = False
            object.__setattr__(self, name, arr)

    @classmethod
    def from_pairs(
        cls, omega: QuantityArrayLike, zeta: npt.ArrayLike, pairs: Iterable[CollocatedPair]
    ) -> PPFModel:
        """From objects with modal ``actuator`` and ``sensor`` vectors (the case's piezo pairs)."""
        given = tuple(pairs)
        if not given:
            raise FieldError("pairs", "give at least one actuator/sensor pair")
        return cls(
            require_positive(omega, "omega", "rad/s"),
            require_nonneg(zeta, "zeta"),
            np.column_stack([p.actuator for p in given]),
            np.vstack([p.sensor for p in given]),
        )

    @property
    def n_modes(self) -> int:
        return self.omega.size

    @property
    def n_actuators(self) -> int:
        return self.actuators.shape[1]


@dataclass(frozen=True, eq=False)
class PPFBank:
    """The filters of Eq. 3: frequencies ``omega_f`` (n_a, n_t), rad/s, and damping ratios
    ``zeta_f`` (scalar or (n_a, n_t)), filter (i, j) at index i n_t + j.

    Raises
    ------
    ValueError
        ``omega_f`` not 2-D, non-finite or ≤ 0; ``zeta_f`` negative or of another shape.
    """

    omega_f: FloatArray
    zeta_f: FloatArray

    def __post_init__(self) -> None:
        w = require_positive(self.omega_f, "omega_f", "rad/s")
        if w.ndim != 2 or w.size == 0:
            raise FieldError("omega_f", f"must have shape (n_actuators, n_tuned), got {w.shape}")
        z = require_nonneg(self.zeta_f, "zeta_f")
        try:
            z = np.broadcast_to(z, w.shape)
        except ValueError:
            raise FieldError(
                "zeta_f", f"must be a scalar or have the shape of omega_f {w.shape}, got {z.shape}"
            ) from None
        for name, arr in (("omega_f", w), ("zeta_f", z)):
            arr = np.array(arr, float)
            arr.flags.writeable = False
            object.__setattr__(self, name, arr)

    @classmethod
    def tuned(
        cls, model: PPFModel, zeta_f: float | npt.ArrayLike, n_tuned: int | None = None
    ) -> PPFBank:
        """ω_f,ij = ω_j for the first ``n_tuned`` modes (default all), every actuator (Agrawal &
        Bang 1996 §2: efficiency is largest when the filter and structure frequencies match)."""
        n = model.n_modes if n_tuned is None else require_count(n_tuned, "n_tuned")
        if n > model.n_modes:
            raise FieldError("n_tuned", f"must be 1 to {model.n_modes}, got {n_tuned!r}")
        return cls(
            np.tile(model.omega[:n], (model.n_actuators, 1)), require_nonneg(zeta_f, "zeta_f")
        )

    @property
    def n_actuators(self) -> int:
        return self.omega_f.shape[0]

    @property
    def n_tuned(self) -> int:
        return self.omega_f.shape[1]

    @property
    def n_filters(self) -> int:
        return self.omega_f.size

    @property
    def E(self) -> FloatArray:
        """Replicate matrix (n_f × n_a)."""
        return replicate_matrix(self.n_actuators, self.n_tuned)

    def check_gains(self, g: npt.ArrayLike, field: str = "gains") -> FloatArray:
        """g as a float vector of n_f finite values (actuator-major), else a ValueError."""
        gains = require_finite(g, field)
        if gains.shape != (self.n_filters,):
            raise FieldError(
                field,
                f"must have {self.n_filters} = n_actuators × n_tuned = "
                f"{self.n_actuators} × {self.n_tuned} values (g[i*n_tuned + j] = "
                f"g_ij), got shape {gains.shape}",
            )
        return gains


@dataclass(frozen=True)
class PPFStability:
    """Stability of a PPF loop (Eq. 6, derived, not printed).

    Attributes
    ----------
    stiffness_eigenvalues : (m,) array
        Eigenvalues of S, ascending.
    stiffness_positive : bool
        (a) S > 0.
    gains_positive : bool
        (b) G > 0.
    max_real_pole : float
        (c) Largest real part of the closed-loop eigenvalues, 1/s.
    decided_by : {"stiffness", "eigenvalues"}
        (d) "stiffness" when G > 0 and the structural and filter dampings are positive
        definite (S > 0 is then necessary and sufficient); else the direct eigenvalue check.
    stable : bool
        The deciding test's verdict.
    """

    stiffness_eigenvalues: FloatArray
    stiffness_positive: bool
    gains_positive: bool
    max_real_pole: float
    decided_by: str
    stable: bool


class PPFProblem:
    """The gain-optimisation problem of Agrawal & Bang 1996 §3 (Eqs. 6–14, 26) for a fixed
    model, bank,
    weights and initial-condition moment: cost, gradient, stiffness eigenvalues and their
    sensitivities, closed-loop poles and the stability report, all as functions of the gain
    vector g (n_g = n_a n_t values, ``g[i*n_tuned + j] = g_ij``).

    Parameters
    ----------
    model : PPFModel
    bank : PPFBank
        Must have the model's number of actuators.
    Q_s : (n_x, n_x) or (2m, 2m) array_like
        State weight (symmetric PSD); a (2m, 2m) weight acts on [η, η̇] only.
    Q_u : scalar or (n_a, n_a) array_like
        Control weight on u = Eᵀ G ξ (symmetric PSD; a scalar times I).
    X0 : (n_x, n_x) or (2m, 2m) array_like
        x₀ x₀ᵀ or E[x₀ x₀ᵀ] (:func:`initial_second_moment`), symmetric PSD; a (2m, 2m) moment
        starts the filters at rest.
    """

    def __init__(
        self,
        model: PPFModel,
        bank: PPFBank,
        Q_s: npt.ArrayLike,
        Q_u: npt.ArrayLike,
        X0: npt.ArrayLike,
    ) -> None:
        if not isinstance(model, PPFModel):
            raise FieldError("model", f"must be a PPFModel, got {type(model).__name__}")
        if not isinstance(bank, PPFBank):
            raise FieldError("bank", f"must be a PPFBank, got {type(bank).__name__}")
        if bank.n_actuators != model.n_actuators:
            raise FieldError(
                "bank",
                f"has filters for {bank.n_actuators} actuators, the model has "
                f"{model.n_actuators} pairs",
            )
        self.model, self.bank = model, bank
        m, nf = model.n_modes, bank.n_filters
        self.n_states = 2 * m + 2 * nf
        self.Q_s = self._state_matrix(Q_s, "Q_s")
        Qu = require_finite(Q_u, "Q_u")
        Qu = Qu * np.eye(model.n_actuators) if Qu.ndim == 0 else check_square(Qu, "Q_u")
        if Qu.shape[0] != model.n_actuators:
            raise FieldError(
                "Q_u",
                f"must be {model.n_actuators} × {model.n_actuators} (one row "
                f"per actuator), got shape {Qu.shape}",
            )
        self.Q_u = check_psd(Qu, "Q_u")
        self.X0 = self._state_matrix(X0, "X0")
        self.E = bank.E
        self.A0, self.B = ppf_state_matrices(
            model.omega,
            model.zeta,
            model.actuators,
            model.sensors,
            bank.omega_f.ravel(),
            bank.zeta_f.ravel(),
            self.E,
        )
        self.dS = ppf_stiffness_gradient(model.actuators, model.sensors, self.E)

    @classmethod
    def from_output_weight(
        cls,
        model: PPFModel,
        bank: PPFBank,
        outputs: npt.ArrayLike,
        output_weight: npt.ArrayLike,
        Q_u: npt.ArrayLike,
        X0: npt.ArrayLike,
    ) -> PPFProblem:
        """Q_s with Tᵀ Q̄ T on the η block for outputs ζ = T η (Eq. 35: T the tip rows giving
        ζ_t = [y_1ᵗ, α, y_2ᵗ, β], Q̄ the tip weight)."""
        m = model.n_modes
        T = check_matrix(outputs, "outputs", None, m, f"(q, m) = (q, {m})")
        Qb = check_psd(check_square(output_weight, "output_weight"), "output_weight")
        if Qb.shape[0] != T.shape[0]:
            raise FieldError(
                "output_weight",
                f"must be {T.shape[0]} × {T.shape[0]} (one row per output), got shape {Qb.shape}",
            )
        Q_s = np.zeros((2 * m, 2 * m))
        Q_s[:m, :m] = T.T @ Qb @ T
        return cls(model, bank, Q_s, Q_u, X0)

    def _state_matrix(self, value: npt.ArrayLike, field: str) -> FloatArray:
        M = check_psd(check_square(value, field), field)
        m2, n = 2 * self.model.n_modes, self.n_states
        if M.shape[0] == m2:
            M = scipy.linalg.block_diag(M, np.zeros((n - m2, n - m2)))
        elif M.shape[0] != n:
            raise FieldError(
                field,
                f"must be {m2} × {m2} (structure states [η, η̇]) or {n} × {n}"
                f" (with the filter states [ξ, ξ̇]), got shape {M.shape}",
            )
        return M

    @property
    def n_gains(self) -> int:
        return self.bank.n_filters

    def gains(self, g: npt.ArrayLike) -> FloatArray:
        """``g`` checked: n_g finite values (actuator-major)."""
        return self.bank.check_gains(g)

    def closed_loop_matrix(self, g: npt.ArrayLike) -> FloatArray:
        """Ā of Eq. 8 (n_x × n_x)."""
        K = ppf_feedback(self.gains(g), self.E, self.model.n_modes)
        return ppf_closed_loop(self.A0, self.B, K)

    def closed_loop_poles(self, g: npt.ArrayLike) -> InexactArray:
        """Eigenvalues of Ā, sorted by real part (descending); real when every one is."""
        lam = np.linalg.eigvals(self.closed_loop_matrix(g))
        return lam[np.argsort(-lam.real, kind="stable")]

    def stiffness(self, g: npt.ArrayLike) -> FloatArray:
        """S of Eq. 6 (m × m, symmetric)."""
        m = self.model
        return ppf_stiffness(m.omega, m.actuators, m.sensors, self.E, self.gains(g))

    def stiffness_eigenvalues(self, g: npt.ArrayLike) -> FloatArray:
        """Eigenvalues λ_i of S (Eq. 21), ascending."""
        return np.asarray(np.linalg.eigvalsh(self.stiffness(g)), np.float64)

    def stiffness_eigenvalue_gradients(self, g: npt.ArrayLike) -> FloatArray:
        """∂λ_i/∂g_k = φ_iᵀ (∂S/∂g_k) φ_i (Eqs. 26–27), (m, n_g), rows in the order of
        :meth:`stiffness_eigenvalues` (valid for distinct eigenvalues)."""
        _, phi = np.linalg.eigh(self.stiffness(g))
        return np.einsum("li,klm,mi->ik", phi, self.dS, phi)

    def stability(self, g: npt.ArrayLike) -> PPFStability:
        """The report of Eq. 6 with the G > 0 and direct eigenvalue checks (class docstring of
        :class:`PPFStability`)."""
        gains = self.gains(g)
        lam = self.stiffness_eigenvalues(gains)
        s_pos, g_pos = bool(lam[0] > 0), bool(np.all(gains > 0))
        damped = bool(np.all(self.model.zeta > 0) and np.all(self.bank.zeta_f > 0))
        max_re = float(np.max(self.closed_loop_poles(gains).real))
        if g_pos and damped:
            return PPFStability(lam, s_pos, g_pos, max_re, "stiffness", s_pos)
        return PPFStability(lam, s_pos, g_pos, max_re, "eigenvalues", max_re < 0)

    def _checked_stable(self, g: npt.ArrayLike) -> FloatArray:
        gains = self.gains(g)
        max_re = float(np.max(self.closed_loop_poles(gains).real))
        if not max_re < 0:
            raise FieldError(
                "gains",
                "the closed loop is unstable (largest real part of its poles "
                f"{max_re:.4g} 1/s): the cost of Eq. 7 is infinite",
            )
        return gains

    def cost(self, g: npt.ArrayLike) -> float:
        """J = ½ tr(P̄ X₀) (Eqs. 10–12); ValueError for an unstable loop (J infinite)."""
        J, _ = ppf_cost_gradient(
            self.A0,
            self.B,
            self.E,
            self.model.n_modes,
            self._checked_stable(g),
            self.Q_s,
            self.Q_u,
            self.X0,
            gradient=False,
        )
        return float(J)

    def cost_and_gradient(self, g: npt.ArrayLike) -> tuple[float, FloatArray]:
        """(J, ∂J/∂g) sharing the Lyapunov solve of P̄."""
        gains = self._checked_stable(g)
        J, dJ = ppf_cost_gradient(
            self.A0, self.B, self.E, self.model.n_modes, gains, self.Q_s, self.Q_u, self.X0
        )
        assert dJ is not None  # asked for (gradient=True)
        return float(J), dJ

    def gradient(self, g: npt.ArrayLike) -> FloatArray:
        """∂J/∂g, repaired Eq. 13 with V of Eq. 14 (module docstring), (n_g,)."""
        return self.cost_and_gradient(g)[1]


def ppf_compensator(bank: PPFBank, gains: npt.ArrayLike) -> ct.StateSpace:
    """The bank as a continuous python-control ``StateSpace`` from the n_a sensor signals to the
    n_a commands: state [ξ, ξ̇], ξ̈ = −Ω_f ξ − D_f ξ̇ + Ω_f E y, u = Eᵀ G ξ (Eqs. 3–5)."""
    import control as ct

    g = bank.check_gains(gains)
    E, nf = bank.E, bank.n_filters
    wf, zf = bank.omega_f.ravel(), bank.zeta_f.ravel()
    A = np.block([[np.zeros((nf, nf)), np.eye(nf)], [-np.diag(wf**2), -np.diag(2 * zf * wf)]])
    B = np.vstack([np.zeros((nf, bank.n_actuators)), wf[:, None] ** 2 * E])
    C = np.hstack([E.T * g, np.zeros((bank.n_actuators, nf))])
    return ct.ss(A, B, C, np.zeros((bank.n_actuators, bank.n_actuators)))


class PPFController(StateSpaceCompensator):
    """The PPF bank as a sampled law (:class:`StateSpaceCompensator` of
    :func:`ppf_compensator`): zero-order-hold discretisation at the control period, exact for
    a sensor signal held between samples; its ``linear_form`` feeds the compiled loop.

    Parameters
    ----------
    bank : PPFBank
    gains : (n_g,) array_like
        g_ij, actuator-major.
    dt : float, str or pint.Quantity
        Control period, s.
    measurements, commands : sequence of str or Channel, optional
        Pair i's sensor and actuator channels; default ``y1`` … and ``u1`` … (the case's plant).
    """

    def __init__(
        self,
        bank: PPFBank,
        gains: npt.ArrayLike,
        dt: QuantityArrayLike,
        measurements: ChannelItems | None = None,
        commands: ChannelItems | None = None,
    ) -> None:
        if not isinstance(bank, PPFBank):
            raise FieldError("bank", f"must be a PPFBank, got {type(bank).__name__}")
        n = bank.n_actuators
        self.bank = bank
        self.gains = bank.check_gains(gains)
        super().__init__(
            ppf_compensator(bank, self.gains),
            measurements or [f"y{i + 1}" for i in range(n)],
            commands or [f"u{i + 1}" for i in range(n)],
            dt=dt,
        )
