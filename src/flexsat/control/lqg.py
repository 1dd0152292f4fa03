r"""LQG compensator behind the :class:`~flexsat.control.base.Controller` interface.

Hailey, Sortun & Agrawal c. 1992, Eqs. 38–45: a regulator :math:`u = -K \hat x`
(:func:`~flexsat.control.lqr.lqr`) fed
by a Kalman estimator (:func:`~flexsat.control.estimation.kalman`)

.. math::

    \dot{\hat x} = A \hat x + B u + L (y - C \hat x)

(the paper's SOBS of Eq. 45, with the full estimated state as output — the paper prints output
matrix C there, which would only reproduce ŷ; the paper is ambiguous here).

Discrete-time implementation
----------------------------
The law runs at the simulator's control period ``dt`` with the torque held between samples.
With continuous gains (``gains="continuous"``, the paper's design) the estimator ODE is
propagated *exactly* over one period for inputs held constant (zero-order hold on both u and
y):

.. math::

    \hat x_{k+1} = \Phi \hat x_k + \Gamma_u u_k + \Gamma_y y_k, \qquad
    \begin{bmatrix} \Phi & [\Gamma_u \; \Gamma_y] \\ 0 & I \end{bmatrix}
    = \exp\left(\begin{bmatrix} A - LC & [B \; L] \\ 0 & 0 \end{bmatrix} dt\right),

and :math:`u_k = -K(\hat x_k - x_{ref,k})`: the compensator is strictly proper, so y_k acts on
the torque from the next sample on. With discrete gains (``gains="discrete"``, designed by
:func:`~flexsat.control.lqr.dlqr` / :func:`~flexsat.control.estimation.dkalman` for the ZOH
plant :math:`(\Phi_p, \Gamma_p)`) it is the predictor estimator
:math:`\hat x_{k+1} = \Phi_p \hat x_k + \Gamma_p u_k + L (y_k - C \hat x_k)`.

How the slew command enters
---------------------------
The estimator runs on the absolute state (it is driven by the measured θ and θ' and by the
torque actually commanded). The regulator acts on the error state
:math:`\hat x - x_{ref}` with :math:`x_{ref} = \theta_{ref} e_\theta + \dot\theta_{ref}
e_{\dot\theta}` (flexible coordinates referenced to zero):

* no reference: a *step* of the reference to ``target`` at t = 0 (:math:`\theta_{ref}` =
  target, :math:`\dot\theta_{ref}` = 0). For a free hub (no stiffness on θ, so θ is a pure
  integrator and every rigid rotation is an equilibrium) this is identical to the other
  reading of the paper's 30° LQG slew, a *regulation offset*: start at −30° and regulate to 0;
* a shaped reference (``reference``, a torque shape of :mod:`flexsat.maneuvers`): track
  :math:`(\theta_{ref}, \dot\theta_{ref})` and feed its torque :math:`u_{ref}` forward.

The initial estimate is the minimum-norm state reproducing the first measurement,
:math:`\hat x_0 = C^+ y_0` (θ̂ and θ̂' measured, flexible states zero), unless an initial
estimate is given.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
import scipy.linalg

from flexsat.control.base import SlewLaw
from flexsat.control.estimation import dkalman, kalman
from flexsat.control.linear_form import (
    LinearLaw,
    absorb_affine,
    per_case,
    reference_tables,
    sample_times,
)
from flexsat.control.lqr import check_matrix, check_square, dlqr, lqr
from flexsat.input_checks import FieldError, require_finite, require_numeric, require_positive

if TYPE_CHECKING:
    import numpy.typing as npt

    from flexsat.control.lqr import RiccatiSolution
    from flexsat.maneuvers.torque_shapes import TorqueShape
    from flexsat.units import FloatArray

#: K x_ref on the sample grid, (n_t, C, 1), for a gain row K (1, n)
ReferenceGain = Callable[["FloatArray"], "FloatArray"]

__all__ = ["EstimatorController", "LQGController", "zoh"]

DEFAULT_MEASUREMENTS = ("theta", "theta_dot")
#: relative tolerance on the spacing of successive calls (the law is built for one period)
DT_TOL = 1e-6


def zoh(A: npt.ArrayLike, B: npt.ArrayLike, dt: float) -> tuple[FloatArray, FloatArray]:
    r"""Exact zero-order-hold discretisation: :math:`\Phi = e^{A dt}`,
    :math:`\Gamma = \int_0^{dt} e^{A s} ds\, B` (one matrix exponential of the block matrix)."""
    a = require_numeric(A, "A", "matrix")
    b = require_numeric(B, "B", "matrix")
    h = float(require_positive(dt, "dt", "s"))
    n, m = b.shape
    blk = np.zeros((n + m, n + m))
    blk[:n, :n] = a * h
    blk[:n, n:] = b * h
    E = scipy.linalg.expm(blk)
    return E[:n, :n], E[:n, n:]


def _plant_matrices(plant: Any) -> tuple[FloatArray, FloatArray, FloatArray]:
    """(A, B, C) of a StateSpace, a SecondOrderModel or a tuple (A, B, C[, D])."""
    if hasattr(plant, "first_order"):
        A, B, C, _ = plant.first_order()
    elif isinstance(plant, (tuple, list)):
        if len(plant) not in (3, 4):
            raise FieldError("plant", f"give (A, B, C) or (A, B, C, D), got {len(plant)} items")
        A, B, C = plant[:3]
    else:
        dt = getattr(plant, "dt", 0)
        if dt not in (0, None):
            raise FieldError("plant", f"must be a continuous-time model, got dt = {dt}")
        A, B, C = plant.A, plant.B, plant.C
    return np.asarray(A, float), np.asarray(B, float), np.asarray(C, float)


class EstimatorController(SlewLaw):
    """Shared machinery of the observer-based laws: measurement stacking, the estimator
    update, the reference state and the sample-period check (see the module docstring)."""

    writes = ("torque",)
    A: FloatArray
    B: FloatArray
    C: FloatArray
    L: FloatArray
    dt: float
    gains: str
    measurements: tuple[str, ...]
    reference_states: tuple[int, int]
    feedforward: bool
    plant_zoh: tuple[FloatArray, FloatArray]
    #: (Φ, Γ_u, Γ_y) of x̂_{k+1} = Φ x̂_k + Γ_u u_k + Γ_y y_k
    estimator: tuple[FloatArray, FloatArray, FloatArray]
    initial_estimate: FloatArray | None
    _Cpinv: FloatArray

    def _setup(
        self,
        A: npt.ArrayLike,
        B: npt.ArrayLike,
        C: npt.ArrayLike,
        L: npt.ArrayLike,
        dt: float,
        target: float | npt.ArrayLike,
        reference: TorqueShape | None,
        measurements: str | Sequence[str],
        reference_states: Sequence[int] | None,
        feedforward: bool,
        gains: str,
        initial_estimate: str | npt.ArrayLike,
    ) -> None:
        a = check_square(A, "A")
        n = a.shape[0]
        b = check_matrix(B, "B", n, None, f"(n, 1) with n = {n}")
        if b.shape[1] != 1:
            raise FieldError(
                "B",
                "the controller interface commands one torque, so B must have "
                f"one column, got {b.shape[1]}",
            )
        c = check_matrix(C, "C", None, n, f"(p, n) with n = {n}")
        p = c.shape[0]
        gain = check_matrix(L, "L", n, p, f"(n, p) = ({n}, {p})")
        self.dt = float(require_positive(dt, "dt", "s"))
        keys = (measurements,) if isinstance(measurements, str) else tuple(measurements)
        if len(keys) != p or not all(isinstance(k, str) for k in keys):
            raise FieldError(
                "measurements",
                f"give {p} measurement keys (one per row of C), got {keys!r}",
            )
        if reference_states is None:
            if n % 2:
                raise FieldError(
                    "reference_states",
                    "the state has odd size; give the indices "
                    "(angle, rate) of θ and θ' in the state",
                )
            reference_states = (0, n // 2)
        i, j = (int(v) for v in reference_states)
        if not (0 <= i < n and 0 <= j < n) or i == j:
            raise FieldError(
                "reference_states",
                f"must be two distinct state indices in 0 … {n - 1}, got {reference_states!r}",
            )
        if gains not in ("continuous", "discrete"):
            raise FieldError("gains", f"must be 'continuous' or 'discrete', got {gains!r}")
        self.A, self.B, self.C, self.L = a, b, c, gain
        self.gains = gains
        self.measurements = keys
        self.reads = keys
        self.reference_states = (i, j)
        self.reference = reference
        self.feedforward = bool(feedforward)
        if reference is not None:
            target = reference.theta0 + reference.angle
        self.target = require_finite(target, "target", "rad")
        self.plant_zoh = zoh(a, b, self.dt)
        if gains == "continuous":
            Phi, Gam = zoh(a - gain @ c, np.hstack([b, gain]), self.dt)
        else:
            Phi = self.plant_zoh[0] - gain @ c
            Gam = np.hstack([self.plant_zoh[1], gain])
        self.estimator = (Phi, Gam[:, :1], Gam[:, 1:])
        self._Cpinv = np.asarray(np.linalg.pinv(c), np.float64)
        if isinstance(initial_estimate, str):
            if initial_estimate != "measurement":
                raise FieldError(
                    "initial_estimate",
                    f"must be 'measurement' or a state array, got {initial_estimate!r}",
                )
            self.initial_estimate = None
        else:
            x0 = require_finite(initial_estimate, "initial_estimate")
            if x0.shape[-1:] != (n,) or x0.ndim > 2:
                raise FieldError(
                    "initial_estimate",
                    f"must have shape (n,) or (n_cases, n) with n = {n}, got {x0.shape}",
                )
            self.initial_estimate = x0

    @property
    def n_states(self) -> int:
        return self.A.shape[0]

    def initial_state(self, n_cases: int) -> dict[str, FloatArray]:
        n = self.n_states
        state = {
            "x_hat": np.zeros((n_cases, n)),
            "started": np.zeros(n_cases, bool),
            "t": np.full(n_cases, np.nan),
        }
        if self.initial_estimate is not None:
            state["x_hat"][:] = self.initial_estimate
            state["started"][:] = True
        return state

    def _measure(self, y: Mapping[str, FloatArray], n_cases: int) -> FloatArray:
        try:
            cols = [np.broadcast_to(np.asarray(y[k], float), (n_cases,)) for k in self.measurements]
        except KeyError as exc:
            raise FieldError(
                "measurements", f"key {exc.args[0]!r} not in the measurements {sorted(y)}"
            ) from None
        return np.stack(cols, axis=-1)

    def _begin(
        self, t: float, y: Mapping[str, FloatArray], state: dict[str, FloatArray]
    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray | float]:
        """Stacked measurements Y (n_cases, p), estimate x̂ (initialised if new), reference
        state x_ref and reference torque u_ref for this sample."""
        x_hat = np.array(state["x_hat"], float)
        nc = x_hat.shape[0]
        Y = self._measure(y, nc)
        started = np.asarray(state["started"], bool)
        t_prev = np.asarray(state["t"], float)
        gap = t - t_prev[started]
        if gap.size and np.any(np.abs(gap - self.dt) > DT_TOL * self.dt):
            raise FieldError(
                "dt",
                f"the law was built for a sample period of {self.dt:g} s but was "
                f"called {float(np.max(gap)):g} s after its previous sample (build it "
                "with the simulator's 1/control_rate)",
            )
        if not np.all(started):
            new = ~started
            x_hat[new] = Y[new] @ self._Cpinv.T
        th_r, thd_r, _, u_r = self.reference_at(t)
        x_ref = np.zeros_like(x_hat)
        i, j = self.reference_states
        x_ref[:, i] = th_r
        x_ref[:, j] = thd_r
        u_ref = np.broadcast_to(np.asarray(u_r, float), (nc,)) if self.feedforward else 0.0
        return Y, x_hat, x_ref, u_ref

    def _linear_pieces(
        self, dt: float, times: npt.ArrayLike, n_cases: int
    ) -> tuple[ReferenceGain, FloatArray, FloatArray | None, FloatArray | None]:
        """What every estimator law's linear form shares, tabulated on ``times``: a function
        giving K x_ref (n_t, C, 1) for a gain row K (x_ref = θ_ref e_θ + θ'_ref e_θ', never
        formed), u_ref (n_t, C, 1) (zero without feedforward), and the start: K0 = C⁺
        (x̂₀ = C⁺ y₀) or the given estimate s0 (C, n)."""
        period, grid = sample_times(dt, times)
        if abs(period - self.dt) > DT_TOL * self.dt:
            raise FieldError(
                "dt",
                f"the law was built for a sample period of {self.dt:g} s, the "
                f"run samples every {period:g} s (build it with the simulator's "
                "1/control_rate)",
            )
        th, thd, _, u_r = reference_tables(self, grid, n_cases)
        i, j = self.reference_states

        def gain_on_reference(K: FloatArray) -> FloatArray:
            return (K[0, i] * th + K[0, j] * thd)[..., None]

        u_ref = (u_r if self.feedforward else np.zeros((len(grid), 1)))[..., None]
        if self.initial_estimate is None:
            return gain_on_reference, u_ref, self._Cpinv, None
        s0 = per_case(self.initial_estimate, n_cases, "initial_estimate", (self.n_states,))
        return gain_on_reference, u_ref, None, s0

    def _linear_law(
        self,
        A: FloatArray,
        B: FloatArray,
        C: FloatArray,
        g: FloatArray,
        F: FloatArray,
        v: FloatArray,
        K0: FloatArray | None,
        s0: FloatArray | None,
    ) -> LinearLaw:
        """The LinearLaw of x̂_{k+1} = A x̂ + B y + F v_k, u = g_k + C x̂ (absolute
        coordinates, y_ref = 0), shifted by :func:`~flexsat.control.linear_form.absorb_affine`."""
        Ak, Ck = A[None, None], C[None, None]
        p, m = B.shape[1], Ck.shape[2]
        return LinearLaw(
            Ak,
            B[None, None],
            Ck,
            np.zeros((1, 1, m, p)),
            np.zeros((g.shape[0], 1, p)),
            absorb_affine(Ak, Ck, g, F, v, s0),
            None if K0 is None else K0[None],
            self.reads,
            self.writes,
            (1,) * p,
            (1,) * m,
        )

    def _propagate(
        self, t: float, x_hat: FloatArray, u: FloatArray, Y: FloatArray
    ) -> dict[str, FloatArray]:
        Phi, Gu, Gy = self.estimator
        nc = x_hat.shape[0]
        x_next = x_hat @ Phi.T + np.multiply.outer(u, Gu[:, 0]) + Y @ Gy.T
        return {"x_hat": x_next, "started": np.ones(nc, bool), "t": np.full(nc, float(t))}


class LQGController(EstimatorController):
    r"""Observer-based LQG compensator (module docstring; Hailey, Sortun
    & Agrawal c. 1992 Eqs. 38–45).

    Parameters
    ----------
    A, B, C : array_like
        Design plant (n, n), (n, 1), (p, n); continuous time. The state must contain θ and θ'
        at ``reference_states`` (default (0, n/2), the [q, q̇] ordering of every flexsat model).
    K : array_like (1, n)
        Regulator gain, u = −K (x̂ − x_ref) (+ u_ref); e.g. ``lqr(A, B, Q, R).gain`` or a
        reduced gain (:func:`~flexsat.control.estimation.truncate_gains`).
    L : array_like (n, p)
        Estimator gain (continuous, or discrete for ``gains="discrete"``).
    dt : float
        Control period, s (the simulator's 1 / control_rate).
    target : float or array
        Final angle for a step command (no reference), rad.
    reference : TorqueShape, optional
        Shaped reference to track; its torque is fed forward when ``feedforward``.
    measurements : sequence of str
        Keys of the measurement dict, one per row of C (default ("theta", "theta_dot")).
    reference_states : (int, int), optional
        Indices of θ and θ' in the state.
    gains : {"continuous", "discrete"}
        Whether K, L are continuous-time gains (exact ZOH implementation) or discrete-time
        gains for the ZOH plant (predictor estimator).
    initial_estimate : "measurement" or array (n,) / (n_cases, n)
        x̂₀ = C⁺ y₀ from the first sample, or the given absolute state.
    """

    #: the designs behind the gains, set by :meth:`design`
    regulator: RiccatiSolution
    filter: RiccatiSolution

    def __init__(
        self,
        A: npt.ArrayLike,
        B: npt.ArrayLike,
        C: npt.ArrayLike,
        K: npt.ArrayLike,
        L: npt.ArrayLike,
        dt: float,
        target: float | npt.ArrayLike = 0.0,
        reference: TorqueShape | None = None,
        measurements: str | Sequence[str] = DEFAULT_MEASUREMENTS,
        reference_states: Sequence[int] | None = None,
        feedforward: bool = True,
        gains: str = "continuous",
        initial_estimate: str | npt.ArrayLike = "measurement",
    ) -> None:
        self._setup(
            A,
            B,
            C,
            L,
            dt,
            target,
            reference,
            measurements,
            reference_states,
            feedforward,
            gains,
            initial_estimate,
        )
        n = self.n_states
        self.K = check_matrix(K, "K", 1, n, f"(1, n) = (1, {n})")

    @classmethod
    def design(
        cls,
        plant: Any,
        Q: npt.ArrayLike,
        R: npt.ArrayLike,
        Qn: npt.ArrayLike,
        Rn: npt.ArrayLike,
        dt: float,
        G: npt.ArrayLike | None = None,
        N: npt.ArrayLike | None = None,
        Nn: npt.ArrayLike | None = None,
        gains: str = "continuous",
        **kwargs: Any,
    ) -> LQGController:
        r"""Design K and L and build the law.

        ``plant`` is a continuous StateSpace, a SecondOrderModel or (A, B, C). Weights Q, R, N
        and noise intensities Qn (on G w; G defaults to B, the paper's Eq. 43 Q_xx = B Qn Bᵀ),
        Rn, Nn are continuous-time. With ``gains="discrete"`` the designs use the ZOH plant and
        the first-order equivalents Q dt, R dt, N dt (cost) and G Qn Gᵀ dt, Rn / dt
        (covariances), accurate for dt small against the closed-loop time constants.
        The designs are in ``.regulator`` and ``.filter`` (RiccatiSolution with residuals).
        """
        A, B, C = _plant_matrices(plant)
        noise_input = B if G is None else G
        h = float(require_positive(dt, "dt", "s"))
        if gains == "discrete":
            Phi, Gam = zoh(A, B, h)
            reg = dlqr(
                Phi,
                Gam,
                require_numeric(Q, "Q") * h,
                require_numeric(R, "R") * h,
                None if N is None else require_numeric(N, "N") * h,
            )
            Gm = check_matrix(noise_input, "G", A.shape[0], None, "(n, g)")
            W = Gm @ np.atleast_2d(require_numeric(Qn, "Qn")) @ Gm.T * h
            V = np.atleast_2d(require_numeric(Rn, "Rn")) / h
            NW = None if Nn is None else Gm @ np.atleast_2d(require_numeric(Nn, "Nn"))
            filt = dkalman(Phi, None, C, W, V, NW)
        else:
            reg = lqr(A, B, Q, R, N)
            filt = kalman(A, noise_input, C, Qn, Rn, Nn)
        law = cls(A, B, C, reg.gain, filt.gain, h, gains=gains, **kwargs)
        law.regulator, law.filter = reg, filt
        return law

    def __call__(
        self, t: float, y: Mapping[str, FloatArray], state: dict[str, FloatArray]
    ) -> tuple[FloatArray, dict[str, FloatArray]]:
        Y, x_hat, x_ref, u_ref = self._begin(t, y, state)
        u = u_ref - (x_hat - x_ref) @ self.K[0]
        return u, self._propagate(t, x_hat, u, Y)

    def linear_form(self, dt: float, times: npt.ArrayLike, n_cases: int) -> LinearLaw:
        r"""With w_k = u_ref,k + K x_ref,k the law is u_k = w_k − K x̂_k,
        x̂_{k+1} = (Φ − Γ_u K) x̂_k + Γ_y y_k + Γ_u w_k: an affine recursion in absolute
        coordinates, shifted into the linear form (:mod:`~flexsat.control.linear_form`)."""
        on_ref, u_ref, K0, s0 = self._linear_pieces(dt, times, n_cases)
        Phi, Gu, Gy = self.estimator
        w = u_ref + on_ref(self.K)
        return self._linear_law(Phi - Gu @ self.K, Gy, -self.K, w, Gu, w, K0, s0)

    # ------------------------------------------------------------------------------------------
    def closed_loop_matrix(
        self,
        A: npt.ArrayLike | None = None,
        B: npt.ArrayLike | None = None,
        C: npt.ArrayLike | None = None,
    ) -> FloatArray:
        r"""Sampled-data closed-loop transition matrix of a plant (default the design plant)
        with this law, state [x, x̂]:

        .. math::

            \begin{bmatrix} x \\ \hat x \end{bmatrix}_{k+1} =
            \begin{bmatrix} \Phi_p & -\Gamma_p K \\ \Gamma_y C & \Phi - \Gamma_u K \end{bmatrix}
            \begin{bmatrix} x \\ \hat x \end{bmatrix}_k .

        Stable iff every eigenvalue lies inside the unit circle.
        """
        if A is None:
            Phi_p, Gam_p = self.plant_zoh
            Cp = self.C
        else:
            if B is None or C is None:
                raise FieldError("B" if B is None else "C", "give A, B and C of the plant together")
            Phi_p, Gam_p = zoh(A, B, self.dt)
            Cp = np.asarray(C, float)
        Phi, Gu, Gy = self.estimator
        K = self.K
        return np.block([[Phi_p, -Gam_p @ K], [Gy @ Cp, Phi - Gu @ K]])

    def continuous_closed_loop(self) -> FloatArray:
        r"""Closed loop of the continuous design, [[A, −BK], [LC, A − BK − LC]] (separation
        principle: eigenvalues eig(A − BK) ∪ eig(A − LC)); only for continuous gains."""
        if self.gains != "continuous":
            raise FieldError("gains", "the continuous closed loop needs continuous gains")
        A, B, C, K, L = self.A, self.B, self.C, self.K, self.L
        return np.block([[A, -B @ K], [L @ C, A - B @ K - L @ C]])
