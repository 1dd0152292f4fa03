r"""Perturbation coordinates about a rigid nominal slew and their linearisation along it
(EPS slew study c. 1989, Eq. 23).

The nominal. The EPS slew study c. 1989 slews the flexible spacecraft with a
rigid-body optimal maneuver: Euler
parameters :math:`\beta_n(t)` (inertial to body, scalar first), body rate :math:`\omega_n(t)`
and torque :math:`\tau_n(t)` on [0, T], with the elastic coordinates at rest
(:math:`\eta = \dot\eta = 0`) and no point forces. Any object with ``beta(t)`` (..., 4),
``omega(t)`` (..., 3), ``torque(t)`` (..., 3, N m) and ``duration`` (T, s) serves; beyond T it
is held at its end (a rest-to-rest maneuver ends at rest with zero torque, so this is its
continuation). Its angular acceleration is that of the rigid body it was designed on,
:math:`\dot\omega_n = J^{-1}(\tau_n - \omega_n\times J\omega_n)` (EPS slew
study c. 1989 Eq. 12) with J the
plant's inertia about the centre of mass.

Perturbation state. :math:`\delta X = [\delta\alpha, \delta\omega, \delta\eta, \delta\dot\eta]`
(6 + 2n) with the attitude error the body-frame small rotation

.. math::

    \beta = \delta q \otimes \beta_n \;\;(C(\beta) = C(\delta q)\,C(\beta_n),
    \text{ the product of } :func:`~flexsat.dynamics.attitude.quaternion_multiply`), \qquad
    \delta\alpha = 2\,\delta q_v \ (\delta q_0 \ge 0),

:math:`\delta\omega = \omega - \omega_n` (body components) and δη = η, δη̇ = η̇. Three
parameters, not the four Euler parameters: δβ has a component along β (the norm direction)
that the dynamics leave constant whatever the input, an uncontrollable eigenvalue at 0, so an
LQR Riccati equation on δβ has no stabilising solution; δα spans exactly the rotations.
Inputs :math:`\delta u = [\delta u_\tau, \delta F]`: the torque perturbation normalized by the
inertia, :math:`\delta u_\tau = J^{-1}\delta\tau` (rad/s², so the paper's D weights on
"normalized torques" apply as published, EPS slew study c. 1989 Eq. 12 and "Control Problem
Formulation"), then the selected
point forces (N).

Attitude-error kinematics. With :math:`\dot\beta = \tfrac12[0, \omega]\otimes\beta` (Eq. 11 in
that product), :math:`\delta q = \beta\otimes\beta_n^*` obeys

.. math::

    \dot{\delta q} = \tfrac12\left([0, \omega]\otimes\delta q - \delta q\otimes[0, \omega_n]
    \right), \qquad
    \dot{\delta q}_v = \tfrac12\left(\delta q_0(\omega - \omega_n)
    - \omega\times\delta q_v - \omega_n\times\delta q_v\right)

(the vector parts of the two products), so to first order, with :math:`\delta q_0 = 1`,
:math:`\omega\times\delta q_v \approx \omega_n\times\delta q_v`:

.. math::

    \delta\dot\alpha = -\omega_n\times\delta\alpha + \delta\omega .

Linearisation (F8; the paper differenced DISCOS numerically with quadratic fits, here the
Jacobians are analytic). The plant :math:`\dot x = A_0x + B_0u + B_f f(x, u)`
(:class:`~flexsat.dynamics.flexible_spacecraft.FlexibleSpacecraft`) gives, at
:math:`(x_n, u_n)`, the full Jacobians :math:`A_0 + B_f\,\partial f/\partial x` and
:math:`B_0 + B_f\,\partial f/\partial u` (its analytic ``force_jacobian``); the rows and
columns of (ω, η, η̇) of the first carry over (the β columns of those rows are zero: the
rigid–elastic equations do not depend on the attitude), the δα rows are the kinematics above:

.. math::

    A(t_i) = \begin{bmatrix} -[\omega_n\times] & [I\ 0\ 0] \\
    0 & \partial(\dot\omega, \dot\eta, \ddot\eta)/\partial(\omega, \eta, \dot\eta)
    \end{bmatrix}, \qquad
    B(t_i) = \begin{bmatrix} 0 \\ \partial(\dot\omega, \dot\eta, \ddot\eta)/\partial u\;
    \mathrm{diag}(J, I) \end{bmatrix}.

Disturbance (EPS slew study c. 1989 Eq. 31, generalised): the rigid nominal is
not a solution of the flexible
model, :math:`\delta\dot X = A\,\delta X + B\,\delta u + d(t)` with

.. math::

    d = \dot{\delta X}\big|_{\delta X = 0,\ \delta u = 0} = f_{pert}(x_n, u_n) - \dot x_n,

the modal accelerations (and any rate mismatch) the nominal torque causes in the flexible
model. With the hybrid mass matrix :math:`\mathcal M = [[J, \Delta^T], [\Delta, I]]` and the
torquers at the CG node (modal load :math:`\sigma^T\tau`, σ the node's rotational mode shapes)
its η̈ rows are :math:`[0\ I]\,\mathcal M^{-1}[I; \sigma^T]\,\tau_n` plus the gyroscopic
term :math:`-[0\ I]\mathcal M^{-1}[\omega_n\times J\omega_n; 0]` (zero when Δ = 0, free-free
modes): Eq. 31 without the translational block, which free-free elastic modes do not couple to.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from flexsat.dynamics.attitude import quaternion_multiply
from flexsat.dynamics.flexible_spacecraft import FlexibleSpacecraft
from flexsat.dynamics.rigid_body import cross3, matvec
from flexsat.dynamics.rigid_spacecraft import quaternion_kinematics, skew
from flexsat.input_checks import FieldError, require_finite, require_positive

if TYPE_CHECKING:
    import numpy.typing as npt

    from flexsat.control.base import RigidNominal
    from flexsat.units import FloatArray, QuantityArrayLike

__all__ = ["TrajectoryLinearization", "attitude_error"]

#: |β| − 1 accepted from a nominal (a propagated or solved trajectory keeps the norm to round-off
#: of its integrator; 1e-9 is the unit check of flexsat.dynamics.attitude)
_UNIT_TOL = 1e-9


def _conjugate(beta: FloatArray) -> FloatArray:
    return beta * np.array([1.0, -1.0, -1.0, -1.0])


def attitude_error(beta: npt.ArrayLike, beta_nominal: npt.ArrayLike) -> FloatArray:
    r"""Body-frame attitude error δα = 2 δq_v (δq₀ ≥ 0) with δq = β ⊗ β_n* (module docstring).

    Parameters
    ----------
    beta, beta_nominal : array_like (..., 4)
        Unit Euler parameters (inertial to body, scalar first), broadcast together.

    Returns
    -------
    ndarray (..., 3)
        rad to first order; |δα| = 2 sin(φ/2) for an error rotation by φ.
    """
    dq = quaternion_multiply(beta, _conjugate(np.asarray(beta_nominal, float)))
    return np.where(dq[..., :1] < 0, -2.0, 2.0) * dq[..., 1:]


def _require_nominal(nominal: RigidNominal) -> float:
    missing = [
        name for name in ("beta", "omega", "torque", "duration") if not hasattr(nominal, name)
    ]
    if missing:
        raise FieldError(
            "nominal",
            "must have beta(t), omega(t), torque(t) and duration; "
            f"{type(nominal).__name__} lacks {', '.join(missing)}",
        )
    return float(require_positive(nominal.duration, "nominal.duration", "s"))


class TrajectoryLinearization:
    r"""A flexible plant's perturbation dynamics about a rigid nominal (module docstring).

    Parameters
    ----------
    plant : FlexibleSpacecraft
        Design model without translation (its elastic modes are the δη of the perturbation
        state).
    nominal : object
        ``beta(t)``, ``omega(t)``, ``torque(t)``, ``duration`` (module docstring).
    forces : sequence of str or "all"
        Force input channels of ``plant`` (``force_<node><AXIS>``) in the perturbation input,
        after the three normalized torques; ``"all"`` takes every one, ``()`` none.

    Attributes
    ----------
    n_modes, n_states, n_inputs : int
        n, 6 + 2n and 3 + number of forces.
    inputs : tuple of str
        ``torque`` then the selected force channels.
    duration : float
        T of the nominal, s.
    """

    def __init__(
        self,
        plant: FlexibleSpacecraft,
        nominal: RigidNominal,
        forces: str | Sequence[str] = (),
    ) -> None:
        if not isinstance(plant, FlexibleSpacecraft):
            raise FieldError("plant", f"must be a FlexibleSpacecraft, got {type(plant).__name__}")
        if plant.translation:
            raise FieldError(
                "plant",
                "must be built without translation (the perturbation "
                "state is attitude, rate and elastic coordinates)",
            )
        self.plant = plant
        self.nominal = nominal
        self.duration = _require_nominal(nominal)
        names = [c.name for c in plant.inputs[1:]]
        if isinstance(forces, str):
            if forces != "all":
                raise FieldError(
                    "forces", f"must be 'all' or a sequence of force channel names, got {forces!r}"
                )
        chosen: list[str] = []
        for name in names if isinstance(forces, str) else forces:
            if name not in names:
                raise FieldError(
                    name,
                    "not a force channel of the plant (its force "
                    f"channels: {', '.join(names) or 'none'})",
                )
            if name in chosen:
                raise FieldError(name, "given twice in forces")
            chosen.append(name)
        self.inputs = ("torque",) + tuple(chosen)
        self._columns = np.r_[0:3, [3 + names.index(c) for c in chosen]].astype(int)
        #: G of the selected forces (3, n_F): their moment arms about the centre of mass, m
        self.force_moments = plant.force_moments[:, self._columns[3:] - 3]
        self.n_modes = plant.n_modes
        self.n_states = 6 + 2 * plant.n_modes
        self.n_inputs = 3 + len(chosen)
        self.inertia = plant.inertia
        self._inertia_inverse = np.linalg.inv(plant.inertia).astype(np.float64, copy=False)

    # -- the nominal -------------------------------------------------------------------------
    def nominal_at(
        self, t: QuantityArrayLike
    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        r"""(β_n, ω_n, τ_n, ω̇_n) at times t (any shape; held beyond [0, T]), shapes
        t.shape + (4,), (3,), (3,), (3,); ω̇_n from the rigid Euler equation (module
        docstring)."""
        held = np.clip(require_finite(t, "t", "s"), 0.0, self.duration)
        beta = np.asarray(self.nominal.beta(held), float)
        w = np.asarray(self.nominal.omega(held), float)
        tau = np.asarray(self.nominal.torque(held), float)
        for field, value, width in (("beta", beta, 4), ("omega", w, 3), ("torque", tau, 3)):
            if value.shape != held.shape + (width,) or not np.all(np.isfinite(value)):
                raise FieldError(
                    f"nominal.{field}",
                    "must return finite values of shape "
                    f"{held.shape + (width,)} at times of shape {held.shape}, got "
                    f"{value.shape}",
                )
        norm = np.abs(np.linalg.norm(beta, axis=-1) - 1.0)
        if np.any(norm > _UNIT_TOL):
            raise FieldError(
                "nominal.beta",
                "must be unit Euler parameters (largest ||β| − 1| "
                f"{norm.max():.3g} > {_UNIT_TOL:g})",
            )
        J = self.inertia
        w_dot = matvec(self._inertia_inverse, tau - cross3(w, matvec(J, w)))
        return beta, w, tau, w_dot

    # -- coordinates -------------------------------------------------------------------------
    def _plant_point(
        self,
        beta_n: FloatArray,
        w_n: FloatArray,
        tau_n: FloatArray,
        dX: FloatArray,
        du: FloatArray,
    ) -> tuple[FloatArray, FloatArray]:
        """Plant state and input (..., n_x), (..., m_plant) of perturbation (δX, δu)."""
        n = self.n_modes
        half = 0.5 * dX[..., :3]
        dq = np.concatenate([np.sqrt(1.0 - np.sum(half * half, -1, keepdims=True)), half], -1)
        shape = np.broadcast_shapes(dX.shape[:-1], beta_n.shape[:-1], du.shape[:-1])
        x = np.empty(shape + (7 + 2 * n,))
        x[..., :4] = quaternion_multiply(dq, beta_n)
        x[..., 4:7] = w_n + dX[..., 3:6]
        x[..., 7:] = dX[..., 6:]
        u = np.zeros(shape + (self.plant.n_inputs,))
        u[..., :3] = tau_n + matvec(self.inertia, du[..., :3])
        u[..., self._columns[3:]] = du[..., 3:]
        return x, u

    def state(self, t: QuantityArrayLike, dX: npt.ArrayLike) -> FloatArray:
        """Plant state x (..., 7 + 2n) of perturbation δX (..., 6 + 2n) at times t (|δα| < 2)."""
        beta_n, w_n, tau_n, _ = self.nominal_at(t)
        dx = require_finite(dX, "dX")
        self._check_width(dx, self.n_states, "dX")
        return self._plant_point(beta_n, w_n, tau_n, dx, np.zeros(self.n_inputs))[0]

    @staticmethod
    def _check_width(value: FloatArray, width: int, field: str) -> None:
        if value.ndim < 1 or value.shape[-1] != width:
            raise FieldError(field, f"last axis must have {width} entries, got shape {value.shape}")

    # -- dynamics ----------------------------------------------------------------------------
    def rhs(self, t: QuantityArrayLike, dX: npt.ArrayLike, du: npt.ArrayLike) -> FloatArray:
        r"""Nonlinear perturbation dynamics :math:`\delta\dot X(t, \delta X, \delta u)`: the
        plant's right-hand side at (x, u) of the perturbation, minus the nominal's rates, with
        the exact error-quaternion kinematics for δα (module docstring); (..., 6 + 2n)."""
        beta_n, w_n, tau_n, w_dot_n = self.nominal_at(t)
        dx, dv = require_finite(dX, "dX"), require_finite(du, "du")
        self._check_width(dx, self.n_states, "dX")
        self._check_width(dv, self.n_inputs, "du")
        x, u = self._plant_point(beta_n, w_n, tau_n, dx, dv)
        x_dot = self.plant.rhs(x, u)
        beta_n_dot = quaternion_kinematics(beta_n, w_n)
        # δq = β ⊗ β_n*, differentiated as a bilinear product
        dq = quaternion_multiply(x[..., :4], _conjugate(beta_n))
        dq_dot = quaternion_multiply(x_dot[..., :4], _conjugate(beta_n)) + quaternion_multiply(
            x[..., :4], _conjugate(beta_n_dot)
        )
        out = np.empty(x_dot.shape[:-1] + (self.n_states,))
        out[..., :3] = np.where(dq[..., :1] < 0, -2.0, 2.0) * dq_dot[..., 1:]
        out[..., 3:6] = x_dot[..., 4:7] - w_dot_n
        out[..., 6:] = x_dot[..., 7:]
        return out

    def disturbance(self, t: QuantityArrayLike) -> FloatArray:
        """d(t) = δẊ at δX = 0, δu = 0 (module docstring, Eq. 31), shape t.shape + (6 + 2n,)."""
        tt = require_finite(t, "t", "s")
        return self.rhs(tt, np.zeros(tt.shape + (self.n_states,)), np.zeros(self.n_inputs))

    def jacobians(self, t: QuantityArrayLike) -> tuple[FloatArray, FloatArray]:
        r"""Analytic (A(t), B(t)) of the perturbation dynamics (module docstring) at times t:
        shapes t.shape + (6 + 2n, 6 + 2n) and t.shape + (6 + 2n, 3 + n_F); B's torque columns
        per normalized torque (J applied)."""
        beta_n, w_n, tau_n, _ = self.nominal_at(t)
        x, u = self._plant_point(
            beta_n, w_n, tau_n, np.zeros(self.n_states), np.zeros(self.n_inputs)
        )
        A0, B0 = self.plant.linear_part()
        Bf = self.plant.force_matrix
        Jx, Ju = self.plant.force_jacobian(x, u)
        Ax = A0 + Bf @ Jx
        Bu = (B0 + Bf @ Ju)[..., self._columns]
        N = self.n_states
        A = np.zeros(x.shape[:-1] + (N, N))
        A[..., :3, :3] = -skew(w_n)
        A[..., :3, 3:6] = np.eye(3)
        A[..., 3:, 3:] = Ax[..., 4:, 4:]
        B = np.zeros(x.shape[:-1] + (N, self.n_inputs))
        B[..., 3:, :3] = Bu[..., 4:, :3] @ self.inertia
        B[..., 3:, 3:] = Bu[..., 4:, 3:]
        return A, B
