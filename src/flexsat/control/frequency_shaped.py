r"""Frequency-shaped LQR with a cross weight (EPS slew study c. 1989, Eqs. 22–30).

The control penalty is shaped in frequency by augmenting the plant with the control and its
derivatives. With ``order=2`` (the paper) the plant input :math:`u_1` and its rate
:math:`u_2 = \dot u_1` become states and the new control is the acceleration
:math:`u_3 = \ddot u_1` (Eq. 23):

.. math::

    \delta X = \begin{bmatrix} \delta x \\ \delta u_1 \\ \delta u_2 \end{bmatrix}, \quad
    \hat A = \begin{bmatrix} A & B & 0 \\ 0 & 0 & I \\ 0 & 0 & 0 \end{bmatrix}, \quad
    \hat B = \begin{bmatrix} 0 \\ 0 \\ I \end{bmatrix}.

The running cost is :math:`\delta x^T Q \delta x + |W(d/dt)\, \delta u_1|_R^2` with the
two-pole shaping filter :math:`W(s) = 1 + 2\zeta_B s/\omega_B + s^2/\omega_B^2` (break
frequency :math:`\omega_B`), i.e. frequency weight
:math:`(1 - \omega^2/\omega_B^2)^2 + 4\zeta_B^2\omega^2/\omega_B^2` — "two-pole roll-off at the
break frequency". Dropping the total-derivative terms
(:math:`2u_1u_2 = d(u_1^2)/dt`, :math:`2u_2u_3 = d(u_2^2)/dt`, which change the cost by a
constant fixed by the initial state and so leave the optimal gain unchanged) gives the weight of
Eq. 22 (generalised to :math:`\zeta_B`, the damped reading of the weight):

.. math::

    \hat Q = \mathrm{diag}\!\left(Q,\; R,\; \tfrac{4\zeta_B^2}{\omega_B^2} R\right), \quad
    \hat N = \begin{bmatrix} 0 \\ R/\omega_B^2 \\ 0 \end{bmatrix}, \quad
    \hat R = R / \omega_B^4 .

:math:`\zeta_B = 0` is the paper's literal weight (the penalty vanishes at ω_B and the optimal
torque can ring there; the paper is ambiguous here); :math:`\zeta_B = 1` is a double real pole. With
``order=1`` only :math:`u_1` is a state, the control is :math:`u_2 = \dot u_1` and
:math:`W(s) = 1 + s/\omega_B` (one-pole roll-off): :math:`\hat Q = \mathrm{diag}(Q, R)`,
:math:`\hat N = [0; R/\omega_B]`, :math:`\hat R = R/\omega_B^2`.

The steady-state gain solves the cross-term Riccati equation Eq. 28 (:func:`~flexsat.control
.lqr.lqr` with N); the control (Eq. 26/30) is

.. math::

    \delta u_3 = -\hat R^{-1} (\hat B^T P + \hat N^T)\, \delta X
                 + \hat R^{-1}\hat B^T \left[\hat A^T - (P\hat B + \hat N)\hat R^{-1}\hat B^T
                 \right]^{-1} P \hat d,

the second term the feedforward of a slowly varying plant disturbance
:math:`\hat d = [d; 0; 0]` (Eq. 29: :math:`\xi = -\hat A_{cl}^{-T} P \hat d`, feedforward
:math:`-\hat R^{-1}\hat B^T \xi`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from flexsat.control.lqg import DEFAULT_MEASUREMENTS, EstimatorController, zoh
from flexsat.control.lqr import RiccatiSolution, check_matrix, check_psd, check_square, lqr
from flexsat.input_checks import (
    FieldError,
    require_count,
    require_finite,
    require_nonneg,
    require_positive,
)

if TYPE_CHECKING:
    import numpy.typing as npt

    from flexsat.control.linear_form import LinearLaw
    from flexsat.maneuvers.torque_shapes import TorqueShape
    from flexsat.units import FloatArray

__all__ = [
    "FrequencyShapedController",
    "FrequencyShapedDesign",
    "frequency_shaped_lqr",
    "shaping_weights",
]


def shaping_weights(
    Q: npt.ArrayLike,
    R: npt.ArrayLike,
    break_frequency: float,
    order: int = 2,
    damping: float = 0.0,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    r"""Augmented weights (Q̂, N̂, R̂) of Eq. 22 (module docstring) for state weight Q (n, n)
    and control weight R (m, m) (the paper's D)."""
    wb = float(require_positive(break_frequency, "break_frequency", "rad/s"))
    zb = float(require_nonneg(damping, "damping", ""))
    Qm = np.atleast_2d(np.asarray(Q, float))
    Rm = np.atleast_2d(np.asarray(R, float))
    n, m = Qm.shape[0], Rm.shape[0]
    wb = np.float64(wb)  # an absurd ω_B or ζ_B overflows to inf (refused below), not an exception
    with np.errstate(over="ignore", under="ignore"):
        scales = (wb ** -(2 * order), 4 * np.float64(zb) ** 2 / wb**2)
    if not 0.0 < scales[0] < np.inf:
        raise FieldError(
            "break_frequency",
            f"ω_B^-{2 * order} = {scales[0]:.3g} (the weight R/ω_B^{2 * order} of the shaped "
            f"input) is not a representable float, got ω_B = {wb:.3g} rad/s",
        )
    if not np.isfinite(scales[1]):
        raise FieldError("damping", f"the shaping weight 4ζ²/ω_B² overflows, got ζ = {zb:.3g}")
    if order == 2:
        Qa = np.zeros((n + 2 * m, n + 2 * m))
        Qa[:n, :n] = Qm
        Qa[n : n + m, n : n + m] = Rm
        Qa[n + m :, n + m :] = scales[1] * Rm
        Na = np.zeros((n + 2 * m, m))
        Na[n : n + m] = Rm / wb**2
        return Qa, Na, Rm / wb**4
    Qa = np.zeros((n + m, n + m))
    Qa[:n, :n] = Qm
    Qa[n:, n:] = Rm
    Na = np.zeros((n + m, m))
    Na[n:] = Rm / wb
    return Qa, Na, Rm / wb**2


def augment(A: FloatArray, B: FloatArray, order: int = 2) -> tuple[FloatArray, FloatArray]:
    """Augmented (Â, B̂) of Eq. 23 (integrator chain of ``order`` on every input)."""
    n, m = B.shape
    k = order * m
    Aa = np.zeros((n + k, n + k))
    Aa[:n, :n] = A
    Aa[:n, n : n + m] = B
    if order == 2:
        Aa[n : n + m, n + m :] = np.eye(m)
    Ba = np.zeros((n + k, m))
    Ba[n + k - m :] = np.eye(m)
    return Aa, Ba


@dataclass(frozen=True)
class FrequencyShapedDesign:
    """A frequency-shaped LQR design (:func:`frequency_shaped_lqr`).

    Attributes
    ----------
    A, B : plant, (n, n) and (n, m)
    A_aug, B_aug, Q_aug, N_aug, R_aug : augmented problem (Eqs. 22–23)
    solution : RiccatiSolution of Eq. 28 (gain over [x, u1(, u2)], P, poles, residual)
    break_frequency, order, damping : shaping parameters
    """

    A: FloatArray
    B: FloatArray
    A_aug: FloatArray
    B_aug: FloatArray
    Q_aug: FloatArray
    N_aug: FloatArray
    R_aug: FloatArray
    solution: RiccatiSolution
    break_frequency: float
    order: int
    damping: float

    @property
    def gain(self) -> FloatArray:
        """K̂ (m, n + order·m): δu_order+1 = −K̂ δX (Eq. 26)."""
        return self.solution.gain

    @property
    def plant_gain(self) -> FloatArray:
        return self.gain[:, : self.A.shape[0]]

    @property
    def chain_gain(self) -> FloatArray:
        """Gains on the control states [δu1(, δu2)]."""
        return self.gain[:, self.A.shape[0] :]

    @property
    def poles(self) -> npt.NDArray[np.complex128]:
        return self.solution.poles

    @property
    def disturbance_gain(self) -> FloatArray:
        r"""K_d (m, n), the coefficient of a constant plant disturbance d in Eq. 30:
        :math:`K_d = \hat R^{-1}\hat B^T \hat A_{cl}^{-T} P E` with E = [I; 0] placing d in
        the augmented state (:math:`\hat d = E d`) and :math:`\hat A_{cl} = \hat A -
        \hat B\hat K`, so that the feedforward :math:`K_d d = -\hat R^{-1}\hat B^T\xi` with
        ξ of Eq. 29. The "time-varying" feedforward of the EPS slew study c.
        1989 interpolates this gain and
        multiplies the current d(t)."""
        n = self.A.shape[0]
        Acl = self.A_aug - self.B_aug @ self.gain
        xi = np.linalg.solve(Acl.T, self.solution.solution[:, :n])
        return np.asarray(np.linalg.solve(self.R_aug, self.B_aug.T @ xi), np.float64)

    def disturbance_feedforward(self, d: npt.ArrayLike) -> FloatArray:
        r"""Constant control term of Eq. 30 for a constant plant disturbance d (n,):
        :math:`\hat R^{-1}\hat B^T \hat A_{cl}^{-T} P \hat d` = :math:`-\hat R^{-1}\hat B^T\xi`
        with ξ of Eq. 29 (:attr:`disturbance_gain` times d)."""
        n = self.A.shape[0]
        dv = require_finite(d, "d")
        if dv.shape != (n,):
            raise FieldError("d", f"must have shape (n,) = ({n},), got {dv.shape}")
        return self.disturbance_gain @ dv

    def controller(
        self, C: npt.ArrayLike, L: npt.ArrayLike, dt: float, **kwargs: Any
    ) -> FrequencyShapedController:
        """The law with estimator gain L (n, p) on the plant outputs C (p, n); keyword
        arguments as :class:`FrequencyShapedController`."""
        return FrequencyShapedController(self, C, L, dt, **kwargs)


def frequency_shaped_lqr(
    A: npt.ArrayLike,
    B: npt.ArrayLike,
    Q: npt.ArrayLike,
    R: npt.ArrayLike,
    break_frequency: float,
    order: int = 2,
    damping: float = 0.0,
) -> FrequencyShapedDesign:
    r"""Frequency-shaped LQR (EPS slew study c. 1989 Eqs. 22–28), module docstring.

    Parameters
    ----------
    A, B : array_like (n, n), (n, m)
        Continuous plant (e.g. the linearisation about the nominal maneuver).
    Q : array_like (n, n)
        Plant-state weight (PSD).
    R : array_like (m, m)
        Control weight at low frequency (the paper's D; PD).
    break_frequency : float, str or pint.Quantity
        ω_B, rad/s (a Quantity or a string such as ``"2 Hz"`` is converted): above it the
        control is penalised as ω⁴/ω_B⁴ (order 2) or ω²/ω_B² (order 1).
    order : {1, 2}
        1: augment the control (rate is the new control); 2: control and rate (acceleration
        is the new control, the paper's form).
    damping : float
        ζ_B of the shaping filter (order 2); 0 is the paper's literal weight.

    Returns
    -------
    FrequencyShapedDesign
        The augmented problem and its :class:`~flexsat.control.lqr.RiccatiSolution` (gain,
        P, closed-loop poles, relative residual).
    """
    a = check_square(A, "A")
    n = a.shape[0]
    b = check_matrix(B, "B", n, None, f"(n, m) with n = {n}")
    m = b.shape[1]
    q = check_psd(check_matrix(Q, "Q", n, n, f"(n, n) = ({n}, {n})"), "Q")
    r = check_psd(check_matrix(R, "R", m, m, f"(m, m) = ({m}, {m})"), "R", strict=True)
    k = require_count(order, "order")
    if k not in (1, 2):
        raise FieldError("order", f"must be 1 (control rate) or 2 (rate and acceleration), got {k}")
    wb = float(require_positive(break_frequency, "break_frequency", "rad/s"))
    zb = float(require_nonneg(damping, "damping", ""))
    Qa, Na, Ra = shaping_weights(q, r, wb, k, zb)
    Aa, Ba = augment(a, b, k)
    sol = lqr(Aa, Ba, Qa, Ra, Na)
    return FrequencyShapedDesign(a, b, Aa, Ba, Qa, Na, Ra, sol, wb, k, zb)


class FrequencyShapedController(EstimatorController):
    r"""Frequency-shaped LQR law with a Kalman estimator of the plant state.

    The shaping states δu1 (and δu2) live inside the law and are known exactly; the plant
    state is estimated as in :class:`~flexsat.control.lqg.LQGController` (exact ZOH
    propagation of the continuous estimator, absolute coordinates, x̂₀ = C⁺y₀). Each sample:

    .. math::

        u_k = u_{ref,k} + \delta u_{1,k}, \qquad
        v_k = -K_x(\hat x_k - x_{ref,k}) - K_z z_k, \qquad z = [\delta u_1(, \delta u_2)],

    the torque :math:`u_k` is held for the period and the chain :math:`\dot z` = [δu2, v]
    (or [v]) is propagated exactly with :math:`v_k` held. The chain makes the commanded torque
    continuous (and its rate, for order 2) between samples up to the hold.

    Parameters
    ----------
    design : FrequencyShapedDesign
        Single-input (m = 1) design.
    C, L : array_like
        Plant outputs (p, n) and continuous Kalman gain (n, p).
    dt, target, reference, measurements, reference_states, feedforward, initial_estimate
        As :class:`~flexsat.control.lqg.LQGController`.
    disturbance : array_like (n,), optional
        Constant plant disturbance d for the Eq. 30 feedforward term (default none).
    """

    def __init__(
        self,
        design: FrequencyShapedDesign,
        C: npt.ArrayLike,
        L: npt.ArrayLike,
        dt: float,
        target: float | npt.ArrayLike = 0.0,
        reference: TorqueShape | None = None,
        measurements: str | Sequence[str] = DEFAULT_MEASUREMENTS,
        reference_states: Sequence[int] | None = None,
        feedforward: bool = True,
        initial_estimate: str | npt.ArrayLike = "measurement",
        disturbance: npt.ArrayLike | None = None,
    ) -> None:
        self._setup(
            design.A,
            design.B,
            C,
            L,
            dt,
            target,
            reference,
            measurements,
            reference_states,
            feedforward,
            "continuous",
            initial_estimate,
        )
        self.design = design
        k = design.order
        chain = np.zeros((k, k))
        if k == 2:
            chain[0, 1] = 1.0
        self.chain_zoh = zoh(chain, np.eye(k, 1, -(k - 1)), self.dt)
        self.offset = (
            0.0 if disturbance is None else float(design.disturbance_feedforward(disturbance)[0])
        )

    def initial_state(self, n_cases: int) -> dict[str, FloatArray]:
        state = super().initial_state(n_cases)
        state["chain"] = np.zeros((n_cases, self.design.order))
        return state

    def __call__(
        self, t: float, y: Mapping[str, FloatArray], state: dict[str, FloatArray]
    ) -> tuple[FloatArray, dict[str, FloatArray]]:
        Y, x_hat, x_ref, u_ref = self._begin(t, y, state)
        z = np.asarray(state["chain"], float)
        u = u_ref + z[:, 0]
        v = (
            self.offset
            - (x_hat - x_ref) @ self.design.plant_gain[0]
            - z @ self.design.chain_gain[0]
        )
        out = self._propagate(t, x_hat, u, Y)
        Pz, Gz = self.chain_zoh
        out["chain"] = z @ Pz.T + np.multiply.outer(v, Gz[:, 0])
        return u, out

    def linear_form(self, dt: float, times: npt.ArrayLike, n_cases: int) -> LinearLaw:
        r"""State [x̂, z]: with e1 picking δu1 from the chain,

        .. math::

            \begin{bmatrix} \hat x \\ z \end{bmatrix}_{k+1} =
            \begin{bmatrix} \Phi & \Gamma_u e_1^T \\ -G_z K_x & P_z - G_z K_z \end{bmatrix}
            \begin{bmatrix} \hat x \\ z \end{bmatrix}_k
            + \begin{bmatrix} \Gamma_y \\ 0 \end{bmatrix} y_k
            + \begin{bmatrix} \Gamma_u u_{ref,k} \\ G_z (d_{ff} + K_x x_{ref,k}) \end{bmatrix},
            \qquad u_k = u_{ref,k} + e_1^T z_k,

        shifted into the linear form (:mod:`~flexsat.control.linear_form`); z starts at 0."""
        on_ref, u_ref, Cpinv, s0 = self._linear_pieces(dt, times, n_cases)
        Phi, Gu, Gy = self.estimator
        Pz, Gz = self.chain_zoh
        Kx, Kz = self.design.plant_gain, self.design.chain_gain
        n, k = Phi.shape[0], Pz.shape[0]
        e1 = np.eye(1, k)
        A = np.block([[Phi, Gu @ e1], [-Gz @ Kx, Pz - Gz @ Kz]])
        B = np.vstack([Gy, np.zeros((k, Gy.shape[1]))])
        C = np.hstack([np.zeros((1, n)), e1])
        # forcing F v_k with v = [u_ref, d_ff + K_x x_ref] and F = diag(Γ_u, G_z)
        F = np.block([[Gu, np.zeros((n, 1))], [np.zeros((k, 1)), Gz]])
        a, b = np.broadcast_arrays(u_ref, self.offset + on_ref(Kx))
        v = np.concatenate([a, b], axis=-1)
        K0 = None if Cpinv is None else np.vstack([Cpinv, np.zeros((k, Cpinv.shape[1]))])
        start = None if s0 is None else np.concatenate([s0, np.zeros((s0.shape[0], k))], axis=-1)
        return self._linear_law(A, B, C, u_ref, F, v, K0, start)

    def closed_loop_matrix(self) -> FloatArray:
        """Sampled-data closed-loop transition matrix of the design plant with this law,
        state [x, x̂, z]; stable iff every eigenvalue is inside the unit circle."""
        Phi_p, Gam_p = self.plant_zoh
        Phi, Gu, Gy = self.estimator
        Pz, Gz = self.chain_zoh
        Kx, Kz = self.design.plant_gain, self.design.chain_gain
        n, k = Phi_p.shape[0], Pz.shape[0]
        e1 = np.eye(1, k)  # u = z[0]
        return np.block(
            [
                [Phi_p, np.zeros((n, n)), Gam_p @ e1],
                [Gy @ self.C, Phi, Gu @ e1],
                [np.zeros((k, n)), -Gz @ Kx, Pz - Gz @ Kz],
            ]
        )
