r"""Three-axis LQG attitude compensator on the attitude-error linearisation.

Design (the continuous-time LQG of Hailey, Sortun & Agrawal c. 1992 Eqs. 38–45, here with m
inputs and p measurements). On the linearisation
:math:`\dot z = Az + B\,\delta u`, :math:`y = Cz` of
:func:`~flexsat.dynamics.attitude_linearization.linearize_attitude` (z = [e, δω, δη, δη̇], e
the MRP or quaternion-vector error, B its three torque columns, C the measured error
:math:`y = [e, \delta\omega]`), a regulator :math:`\delta u = -K\hat z`,
:math:`K = R^{-1}B^TS` (:func:`~flexsat.control.lqr.lqr`, python-control's ``lqr``) and a
Kalman estimator :math:`\dot{\hat z} = A\hat z + B\,\delta u + L(y - C\hat z)`,
:math:`L = PC^TR_n^{-1}` for process noise G w (default G = B: torque noise) of intensity
:math:`Q_n` and measurement noise of intensity :math:`R_n`
(:func:`~flexsat.control.estimation.kalman`, python-control's ``lqe``). The compensator from y
to δu is the textbook

.. math::

    \dot{\hat z} = (A - BK - LC)\,\hat z + L\,y, \qquad \delta u = -K\hat z

(:meth:`AttitudeLQG.compensator`, a python-control ``StateSpace``), and the closed loop with the
linear plant has the eigenvalues eig(A − BK) ∪ eig(A − LC) (separation principle).

The law on the nonlinear plant. Each sample it reads the plant's ``attitude`` β (Euler
parameters) and ``rate`` ω, forms the error about the target frame R at the sample time t,

.. math::

    \beta_R(t) = \exp(\omega_r t)\otimes\beta_R(0), \qquad
    \delta q = \beta\otimes\beta_R(t)^* \;\;(\delta q_0 \ge 0), \qquad
    y = [e(\delta q),\; \omega - \omega_r],

with e = δq_v/(1 + δq0) (MRPs on the short rotation: past a 180° error the shadow set is taken,
|σ| <= 1, Schaub & Junkins, *Analytical Mechanics of Space Systems*, 4th ed., Eqs. 3.142 and
3.151) or e = δq_v, and ω_r the linearisation's reference rate (zero: regulation at rest to a
fixed target). It commands :math:`u = u_r - K\hat z` on all three axes (u_r = ω_r × Jω_r, the
torque that keeps the reference rate) and propagates the estimate exactly over the control
period for the torque and measurement held (zero-order hold, :func:`~flexsat.control.lqg.zoh`):

.. math::

    \hat z_{k+1} = \Phi\hat z_k + \Gamma_u\,\delta u_k + \Gamma_y\,y_k, \qquad
    [\Phi \;|\; \Gamma_u\;\Gamma_y] \text{ from } \exp\!\left(\begin{bmatrix} A - LC & [B\;L] \\
    0 & 0\end{bmatrix} dt\right),

as :class:`~flexsat.control.lqg.LQGController` does for one axis. The estimate starts at the
minimum-norm state reproducing the first measurement, :math:`\hat z_0 = C^+y_0` (the error and
rate measured, the modes at rest). The law is nonlinear in the measured β (the error
quaternion, its MRP map and shadow set), so it has no linear form and the engine calls it
sample by sample.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np

from flexsat.control.attitude_laws import error_quaternion
from flexsat.control.base import Controller
from flexsat.control.estimation import kalman
from flexsat.control.lqg import DT_TOL, zoh
from flexsat.control.lqr import check_matrix, lqr
from flexsat.dynamics.attitude import quaternion_exp, quaternion_multiply, require_quaternion
from flexsat.dynamics.attitude_linearization import AttitudeLinearization
from flexsat.input_checks import FieldError, require_numeric, require_positive

if TYPE_CHECKING:
    import numpy.typing as npt

    import control
    from flexsat.control.lqr import RiccatiSolution
    from flexsat.units import FloatArray

__all__ = ["AttitudeLQG"]


class AttitudeLQG(Controller):
    r"""LQG attitude compensator on three torque axes (module docstring).

    Parameters
    ----------
    linearization : AttitudeLinearization
        The design plant (:func:`~flexsat.dynamics.attitude_linearization.linearize_attitude`):
        its torque columns and measured rows [e, δω] are the law's B and C.
    K : array_like (3, n)
        Regulator gain, δu = −K ẑ (e.g. ``lqr(A, B, Q, R).gain``).
    L : array_like (n, 6)
        Continuous estimator gain.
    dt : float
        Control period, s (the simulator's 1 / control_rate).
    beta_target : array_like (4,) or (n_cases, 4)
        Unit Euler parameters of the target frame at t = 0 (default the inertial frame); with a
        reference rate it turns as exp(ω_r t) ⊗ β_target.
    """

    reads = ("attitude", "rate")
    writes = ("torque",)
    #: the designs behind the gains, set by :meth:`design`
    regulator: RiccatiSolution
    filter: RiccatiSolution

    def __init__(
        self,
        linearization: AttitudeLinearization,
        K: npt.ArrayLike,
        L: npt.ArrayLike,
        dt: float,
        beta_target: npt.ArrayLike = (1.0, 0.0, 0.0, 0.0),
    ) -> None:
        if not isinstance(linearization, AttitudeLinearization):
            raise FieldError(
                "linearization",
                "must be an AttitudeLinearization (flexsat.dynamics.linearize_attitude), got "
                f"{type(linearization).__name__}",
            )
        self.linearization = linearization
        self.A = linearization.A
        self.B = linearization.B[:, linearization.torque_columns]
        self.C = linearization.C[linearization.measured_rows]
        n, p = self.A.shape[0], self.C.shape[0]
        self.K = check_matrix(K, "K", 3, n, f"(3, n) = (3, {n})")
        self.L = check_matrix(L, "L", n, p, f"(n, p) = ({n}, {p})")
        self.dt = float(require_positive(dt, "dt", "s"))
        target = require_quaternion(beta_target, "beta_target")
        if target.ndim > 2:
            raise FieldError(
                "beta_target", f"must have shape (4,) or (n_cases, 4), got {target.shape}"
            )
        self.beta_target = target
        Phi, Gam = zoh(self.A - self.L @ self.C, np.hstack([self.B, self.L]), self.dt)
        #: (Φ, Γ_u, Γ_y) of ẑ_{k+1} = Φ ẑ_k + Γ_u δu_k + Γ_y y_k
        self.estimator = (Phi, Gam[:, :3], Gam[:, 3:])
        self._Cpinv = np.asarray(np.linalg.pinv(self.C), np.float64)

    @classmethod
    def design(
        cls,
        linearization: AttitudeLinearization,
        Q: npt.ArrayLike,
        R: npt.ArrayLike,
        Qn: npt.ArrayLike,
        Rn: npt.ArrayLike,
        dt: float,
        G: npt.ArrayLike | None = None,
        beta_target: npt.ArrayLike = (1.0, 0.0, 0.0, 0.0),
    ) -> AttitudeLQG:
        r"""Design K = lqr(A, B, Q, R) and L = lqe(A, G, C, Qn, Rn) on the linearisation and
        build the law.

        Parameters
        ----------
        linearization : AttitudeLinearization
        Q : array_like (n, n)
            State weight on z = [e, δω, δη, δη̇].
        R : array_like (3, 3) or scalar
            Torque weight.
        Qn : array_like (g, g)
            Process-noise intensity on G w (G defaults to the torque columns B: Qn (3, 3),
            N²·m²·s).
        Rn : array_like (6, 6)
            Measurement-noise intensity of [e, δω].
        dt : float
            Control period, s.
        G : array_like (n, g), optional
        beta_target : array_like (4,) or (n_cases, 4)

        Notes
        -----
        The designs are kept in ``.regulator`` and ``.filter`` (RiccatiSolution, with
        residuals).
        """
        if not isinstance(linearization, AttitudeLinearization):
            raise FieldError(
                "linearization",
                "must be an AttitudeLinearization (flexsat.dynamics.linearize_attitude), got "
                f"{type(linearization).__name__}",
            )
        A = linearization.A
        B = linearization.B[:, linearization.torque_columns]
        C = linearization.C[linearization.measured_rows]
        reg = lqr(A, B, Q, R)
        filt = kalman(A, B if G is None else require_numeric(G, "G"), C, Qn, Rn)
        law = cls(linearization, reg.gain, filt.gain, dt, beta_target)
        law.regulator, law.filter = reg, filt
        return law

    # -- the law -----------------------------------------------------------------------------
    def _batched(self) -> list[tuple[int, ...]]:
        return [self.beta_target.shape[:-1]]

    @property
    def n_states(self) -> int:
        return self.A.shape[0]

    def initial_state(self, n_cases: int) -> dict[str, FloatArray]:
        return {
            "z_hat": np.zeros((n_cases, self.n_states)),
            "started": np.zeros(n_cases, bool),
            "t": np.full(n_cases, np.nan),
        }

    def target_at(self, t: float) -> FloatArray:
        """β_R(t) = exp(ω_r t) ⊗ β_target, (4,) or (n_cases, 4)."""
        rate = self.linearization.rate
        if not np.any(rate):
            return self.beta_target
        return quaternion_multiply(quaternion_exp(rate * t), self.beta_target)

    def measured_error(self, t: float, beta: npt.ArrayLike, w: npt.ArrayLike) -> FloatArray:
        """y = [e, ω − ω_r] (..., 6) at time t for attitude β (..., 4) and rate ω (..., 3)."""
        dq = error_quaternion(beta, self.target_at(t))
        dq = np.where(dq[..., :1] < 0, -dq, dq)
        e = dq[..., 1:]
        if self.linearization.coordinates == "mrp":
            e = e / (1 + dq[..., :1])
        rate = np.asarray(w, float) - self.linearization.rate
        return np.concatenate(np.broadcast_arrays(e, rate), -1)

    def __call__(
        self, t: float, y: Mapping[str, FloatArray], state: dict[str, FloatArray]
    ) -> tuple[FloatArray, dict[str, FloatArray]]:
        """The torque u = u_r − K ẑ (N·m, body axes, (n_cases, 3)) and the next estimate."""
        z_hat = np.array(state["z_hat"], float)
        nc = z_hat.shape[0]
        beta = np.asarray(y["attitude"], float)
        # a measured (noisy) attitude need not be unit: normalised before the error is formed
        beta = beta / np.linalg.norm(beta, axis=-1, keepdims=True)
        Y = np.broadcast_to(self.measured_error(t, beta, y["rate"]), (nc, 6))
        started = np.asarray(state["started"], bool)
        gap = t - np.asarray(state["t"], float)[started]
        if gap.size and np.any(np.abs(gap - self.dt) > DT_TOL * self.dt):
            raise FieldError(
                "dt",
                f"the law was built for a sample period of {self.dt:g} s but was called "
                f"{float(np.max(gap)):g} s after its previous sample (build it with the "
                "simulator's 1/control_rate)",
            )
        if not np.all(started):
            z_hat[~started] = Y[~started] @ self._Cpinv.T
        du = -z_hat @ self.K.T
        Phi, Gu, Gy = self.estimator
        z_next = z_hat @ Phi.T + du @ Gu.T + Y @ Gy.T
        u = self.linearization.torque + du
        return u, {"z_hat": z_next, "started": np.ones(nc, bool), "t": np.full(nc, float(t))}

    # -- linear analysis -----------------------------------------------------------------------
    def compensator(self) -> control.StateSpace:
        r"""The continuous compensator from y = [e, δω] to δu:
        :math:`\dot{\hat z} = (A - BK - LC)\hat z + Ly`, :math:`\delta u = -K\hat z`, with
        python-control signal names (states ``<state>_hat``, inputs the measured outputs,
        outputs ``torque[i]``)."""
        import control

        lin = self.linearization
        A, B, C, K, L = self.A, self.B, self.C, self.K, self.L
        return control.ss(
            A - B @ K - L @ C,
            L,
            -K,
            np.zeros((3, C.shape[0])),
            states=[f"{s}_hat" for s in lin.states],
            inputs=list(lin.outputs[lin.measured_rows]),
            outputs=list(lin.inputs[lin.torque_columns]),
            name="attitude_lqg",
        )
