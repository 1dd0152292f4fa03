r"""Three-axis rigid spacecraft as a :class:`~flexsat.dynamics.plant.Plant`: Euler parameters
and body rates driven by a body-axis torque.

State :math:`x = [\beta_0, \beta_1, \beta_2, \beta_3, \omega_1, \omega_2, \omega_3]`
(β inertial to body, scalar first; ω body rate in body axes, rad/s), input the torque u about
the centre of mass in body axes (N m):

.. math::

    \dot\beta = \Omega(\omega)\,\beta \quad \text{(EPS slew study c. 1989 Eq. 11)}, \qquad
    I\dot\omega = -\omega\times I\omega + u \quad \text{(Eq. 12)}.

In the plant protocol's form :math:`\dot x = A x + B u + B_f f(x)` the linear part is
:math:`A = 0`, :math:`B = [0;\ I^{-1}]` and the whole motion is the nonlinear force
:math:`f = [\Omega(\omega)\beta;\ -I^{-1}\,\omega\times I\omega]` with :math:`B_f = I_7`, so a
generic exponential integrator runs it too; the plant's own :meth:`RigidSpacecraft.step` is
the norm-preserving RKMK4 of :mod:`flexsat.dynamics.rigid_body` with u held over the step
(fourth order, ‖β‖ = 1 to round-off).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

from flexsat.dynamics.attitude import case_shape, require_quaternion, require_shape
from flexsat.dynamics.plant import Channel, Plant
from flexsat.dynamics.rigid_body import (
    cross3,
    dexpinv,
    euler_acceleration,
    matvec,
    require_inertia,
    rkmk4_step,
)
from flexsat.input_checks import FieldError

if TYPE_CHECKING:
    import numpy.typing as npt

    from flexsat.units import FloatArray, QuantityArrayLike

__all__ = ["RigidSpacecraft", "ATTITUDE_OUTPUTS", "attitude_state_from"]

#: the attitude outputs every three-axis plant gives
ATTITUDE_OUTPUTS = (
    Channel("attitude", "", 4, "Euler parameters β (inertial to body, scalar first)"),
    Channel("rate", "rad/s", 3, "body angular velocity ω, body axes"),
    Channel("euler123", "rad", 3, "1-2-3 Euler angles (θ1, θ2, θ3) of β"),
    Channel("mrp", "", 3, "modified Rodrigues parameters of β on its short rotation, |σ| <= 1"),
)


def attitude_state_from(plant: Plant, values: Mapping[str, QuantityArrayLike]) -> FloatArray:
    """Initial state of a three-axis plant whose state starts [β, ω]: the attitude as
    ``attitude`` (unit Euler parameters, scalar first) or ``euler123`` (rad), the body ``rate``
    (rad/s); other names as :meth:`Plant.state_from` (``state``, outputs reading state
    coordinates). Each a number in SI, a pint Quantity or a unit string."""
    from flexsat.dynamics.attitude import dcm_to_quaternion, euler123_to_dcm
    from flexsat.units import to_si_array

    values = dict(values)
    if "attitude" in values and "euler123" in values:
        raise FieldError("attitude", "give attitude or euler123, not both")
    own = {k: values.pop(k) for k in ("attitude", "euler123", "rate") if k in values}
    x = Plant.state_from(plant, **values)
    if "attitude" in own:
        x[:4] = require_quaternion(to_si_array(own["attitude"], "", "attitude"), "attitude")
    if "euler123" in own:
        angles = to_si_array(own["euler123"], "rad", "euler123")
        if angles.shape != (3,) or not np.all(np.isfinite(angles)):
            raise FieldError("euler123", f"three finite angles, got {own['euler123']!r}")
        x[:4] = dcm_to_quaternion(euler123_to_dcm(angles))
    if "rate" in own:
        w = to_si_array(own["rate"], "rad/s", "rate")
        if w.shape != (3,) or not np.all(np.isfinite(w)):
            raise FieldError("rate", f"three finite body rates, got {own['rate']!r}")
        x[4:7] = w
    return x


def _tensor(entries: list[tuple[int, int, int, float]], shape: tuple[int, int]) -> FloatArray:
    """Constant (3, prod(shape)) with (v @ T).reshape(shape) linear in v as ``entries`` say:
    (row, col, component, sign) per non-zero entry."""
    T = np.zeros((3,) + shape)
    for i, j, k, sign in entries:
        T[(k, i, j)] = sign
    return T.reshape(3, -1)


# On the tiny arrays of one case a product with a constant matrix is one numpy call where
# component-wise formulas are a dozen, each ~1 µs of overhead: these make [v×] and Ω(ω) so.
_SKEW = _tensor(
    [(0, 1, 2, -1), (0, 2, 1, 1), (1, 0, 2, 1), (1, 2, 0, -1), (2, 0, 1, -1), (2, 1, 0, 1)], (3, 3)
)
_OMEGA = _tensor(
    [
        (0, 1, 0, -0.5),
        (0, 2, 1, -0.5),
        (0, 3, 2, -0.5),
        (1, 0, 0, 0.5),
        (1, 2, 2, 0.5),
        (1, 3, 1, -0.5),
        (2, 0, 1, 0.5),
        (2, 1, 2, -0.5),
        (2, 3, 0, 0.5),
        (3, 0, 2, 0.5),
        (3, 1, 1, 0.5),
        (3, 2, 0, -0.5),
    ],
    (4, 4),
)


def skew(v: FloatArray) -> FloatArray:
    """[v×] (..., 3, 3) of vectors (..., 3), unchecked."""
    return (v @ _SKEW).reshape(v.shape[:-1] + (3, 3))


def omega(w: FloatArray) -> FloatArray:
    """Ω(ω) (..., 4, 4) of EPS slew study c. 1989 Eq. 11, the ½ included
    (:func:`flexsat.dynamics.attitude.omega_matrix`, unchecked)."""
    return (w @ _OMEGA).reshape(w.shape[:-1] + (4, 4))


def quaternion_kinematics(beta: FloatArray, w: FloatArray) -> FloatArray:
    r""":math:`\dot\beta = \Omega(\omega)\beta = B(\beta)\,\omega` (EPS slew study
    c. 1989 Eq. 11), unchecked."""
    return (omega(w) @ beta[..., None])[..., 0]


def kinematics_jacobians(beta: FloatArray, w: FloatArray) -> tuple[FloatArray, FloatArray]:
    r"""(∂β̇/∂β, ∂β̇/∂ω) = (Ω(ω), B(β)) of :func:`quaternion_kinematics`, (..., 4, 4), (..., 4, 3)
    (:func:`flexsat.dynamics.attitude.omega_matrix`, ``quaternion_rate_matrix``)."""
    shape = np.broadcast_shapes(beta.shape[:-1], w.shape[:-1])
    Om = np.broadcast_to(omega(w), shape + (4, 4))
    Bq = np.empty(shape + (4, 3))
    Bq[..., 0, :] = -0.5 * beta[..., 1:]
    Bq[..., 1:, :] = 0.5 * (beta[..., :1, None] * np.eye(3) + skew(beta[..., 1:]))
    return Om, Bq


def dcm(beta: FloatArray) -> FloatArray:
    """C(β), inertial to body (Schaub & Junkins Eq. 3.98), unchecked."""
    b0, b1, b2, b3 = (beta[..., i] for i in range(4))
    C = np.empty(beta.shape[:-1] + (3, 3))
    C[..., 0, 0] = b0 * b0 + b1 * b1 - b2 * b2 - b3 * b3
    C[..., 0, 1] = 2 * (b1 * b2 + b0 * b3)
    C[..., 0, 2] = 2 * (b1 * b3 - b0 * b2)
    C[..., 1, 0] = 2 * (b1 * b2 - b0 * b3)
    C[..., 1, 1] = b0 * b0 - b1 * b1 + b2 * b2 - b3 * b3
    C[..., 1, 2] = 2 * (b2 * b3 + b0 * b1)
    C[..., 2, 0] = 2 * (b1 * b3 + b0 * b2)
    C[..., 2, 1] = 2 * (b2 * b3 - b0 * b1)
    C[..., 2, 2] = b0 * b0 - b1 * b1 - b2 * b2 + b3 * b3
    return C


def attitude_output(name: str, beta: FloatArray, w: FloatArray) -> FloatArray:
    """The :data:`ATTITUDE_OUTPUTS` channel ``name`` from β (..., 4) and ω (..., 3)."""
    if name == "attitude":
        return beta
    if name == "rate":
        return w
    if name == "euler123":
        # Schaub & Junkins Table B.1 (as flexsat.dynamics.attitude.dcm_to_euler123)
        C = dcm(beta)
        return np.stack(
            [
                np.arctan2(-C[..., 2, 1], C[..., 2, 2]),
                np.arctan2(C[..., 2, 0], np.hypot(C[..., 0, 0], C[..., 1, 0])),
                np.arctan2(-C[..., 1, 0], C[..., 0, 0]),
            ],
            -1,
        )
    if name == "mrp":
        # σ = β_v / (1 + β0) with β0 >= 0 (the short rotation): 1 + β0 >= 1, never singular
        b = np.where(beta[..., :1] < 0, -beta, beta)
        return b[..., 1:] / (1 + b[..., :1])
    raise KeyError(name)


def normalize_quaternion(x: FloatArray) -> FloatArray:
    """x with its first four components (β) scaled to unit norm."""
    out = np.array(x, float)
    out[..., :4] /= np.linalg.norm(out[..., :4], axis=-1, keepdims=True)
    return out


class RigidSpacecraft(Plant):
    """Rigid body with Euler-parameter attitude and a body-axis torque (module docstring).

    Parameters
    ----------
    inertia : array_like (3, 3) or (n_cases, 3, 3), str or pint.Quantity
        Inertia about the centre of mass in body axes, kg m²: symmetric, positive definite,
        principal moments obeying the triangle inequality
        (:func:`flexsat.dynamics.rigid_body.require_inertia`). A leading axis disperses it over
        cases.
    """

    inputs = (Channel("torque", "N*m", 3, "torque about the centre of mass, body axes"),)
    outputs = ATTITUDE_OUTPUTS
    recorded = ("attitude", "euler123", "rate")
    nonlinear = True

    def __init__(self, inertia: QuantityArrayLike) -> None:
        J = require_inertia(inertia)
        if J.ndim > 3:
            raise FieldError("inertia", f"must have shape (3, 3) or (n_cases, 3, 3), got {J.shape}")
        self.inertia = J
        # numpy types inv() as floating[Any]; it is float64 here, so the astype copies nothing
        self.inertia_inverse = np.linalg.inv(J).astype(np.float64, copy=False)

    @classmethod
    def stacked(cls, plants: Sequence[RigidSpacecraft]) -> RigidSpacecraft:
        """One plant whose cases are those of ``plants`` in order (each shared or with its
        own case axis): their inertias stacked (what
        :func:`~flexsat.dynamics.dispersion.stack_plants` returns for rigid spacecraft, which
        keep their own integrator)."""
        return cls(np.concatenate([np.reshape(p.inertia, (-1, 3, 3)) for p in plants]))

    @property
    def nx(self) -> int:
        return 7

    @property
    def n_cases(self) -> int:
        return 1 if self.inertia.ndim == 2 else self.inertia.shape[0]

    def initial_state(self, n_cases: int) -> FloatArray:
        """At rest in the inertial attitude, β = (1, 0, 0, 0)."""
        x = np.zeros((n_cases, 7))
        x[:, 0] = 1.0
        return x

    def state_from(self, **values: QuantityArrayLike) -> FloatArray:
        """Initial [β, ω] from ``attitude`` or ``euler123`` and ``rate``
        (:func:`attitude_state_from`)."""
        return attitude_state_from(self, values)

    @property
    def initial_values(self) -> tuple[str, ...]:
        return ("attitude", "euler123", "rate", "state")

    def state(self, beta: npt.ArrayLike, w: npt.ArrayLike) -> FloatArray:
        """The state vector [β, ω] (..., 7) of attitude ``beta`` (unit) and rate ``w``."""
        b = require_quaternion(beta)
        rate = require_shape(w, "w", (3,))
        shape = case_shape(beta=b.shape[:-1], w=rate.shape[:-1])
        return np.concatenate(
            [np.broadcast_to(b, shape + (4,)), np.broadcast_to(rate, shape + (3,))], -1
        )

    def linear_part(self) -> tuple[FloatArray, FloatArray]:
        """A = 0, B = [0; I⁻¹] (7 × 3), with a leading case axis when the inertia has one."""
        Jinv = self.inertia_inverse
        A = np.zeros(Jinv.shape[:-2] + (7, 7))
        B = np.zeros(Jinv.shape[:-2] + (7, 3))
        B[..., 4:, :] = Jinv
        return A, B

    @property
    def force_matrix(self) -> FloatArray:
        """B_f = I₇: f carries the whole kinematics and the gyroscopic acceleration."""
        return np.eye(7)

    def nonlinear_force(self, x: FloatArray, u: FloatArray) -> FloatArray:
        r"""f = [Ω(ω)β, −I⁻¹ ω × Iω] (..., 7)."""
        beta, w = x[..., :4], x[..., 4:]
        f = np.empty(np.broadcast_shapes(x.shape, np.shape(u)[:-1] + (7,)))
        f[..., :4] = quaternion_kinematics(beta, w)
        f[..., 4:] = -matvec(self.inertia_inverse, cross3(w, matvec(self.inertia, w)))
        return f

    def force_jacobian(self, x: FloatArray, u: FloatArray) -> tuple[FloatArray, FloatArray]:
        r"""∂f/∂x (..., 7, 7): [[Ω(ω), B(β)], [0, I⁻¹([h×] − [ω×] I)]] with h = Iω, because
        :math:`d(-\omega\times h) = h\times d\omega - \omega\times I\,d\omega`; ∂f/∂u = 0."""
        beta, w = x[..., :4], x[..., 4:]
        Om, Bq = kinematics_jacobians(beta, w)
        h = matvec(self.inertia, w)
        Jx = np.zeros(x.shape[:-1] + (7, 7))
        Jx[..., :4, :4], Jx[..., :4, 4:] = Om, Bq
        Jx[..., 4:, 4:] = self.inertia_inverse @ (skew(h) - skew(w) @ self.inertia)
        return Jx, np.zeros(x.shape[:-1] + (7, 3))

    def rhs(self, x: FloatArray, u: FloatArray) -> FloatArray:
        """ẋ = A x + B u + B_f f(x, u), the full right-hand side (for reference integrators)."""
        f = self.nonlinear_force(x, u)
        f[..., 4:] += matvec(self.inertia_inverse, u)
        return f

    def step(self, x: FloatArray, u: FloatArray, h: float) -> FloatArray:
        """One RKMK4 step h (s) with the torque u held (:func:`~flexsat.dynamics.rigid_body.
        rkmk4_step`): fourth order, β unit to round-off."""
        J, Jinv = self.inertia, self.inertia_inverse
        u = np.asarray(u, float)

        def rates(tau: float, theta: FloatArray, w: FloatArray) -> tuple[FloatArray, FloatArray]:
            return dexpinv(theta, w), euler_acceleration(w, J, Jinv, u)

        beta, w = rkmk4_step(x[..., :4], x[..., 4:], h, rates)
        return np.concatenate([beta, w], -1)

    def normalize(self, x: FloatArray) -> FloatArray:
        """β scaled back to unit norm (after a generic integrator's step)."""
        return normalize_quaternion(x)

    def output_matrices(self, name: str) -> tuple[FloatArray, FloatArray, FloatArray | None] | None:
        """Attitude and rate are components of x: C selects them (D = 0, no input force)."""
        if name not in ("attitude", "rate"):
            return None
        rows = slice(0, 4) if name == "attitude" else slice(4, 7)
        C = np.eye(7)[rows]
        return C, np.zeros((C.shape[0], 3)), None

    def output(
        self, name: str, x: FloatArray, u: FloatArray | None = None, f_in: FloatArray | None = None
    ) -> FloatArray:
        self._size(name)  # unknown names: a ValueError naming the channel
        return attitude_output(name, x[..., :4], x[..., 4:7])

    def energy(self, x: FloatArray) -> FloatArray:
        """Kinetic energy ½ ωᵀIω, J."""
        w = x[..., 4:]
        return 0.5 * np.sum(w * matvec(self.inertia, w), axis=-1)

    def power(self, x: FloatArray, u: FloatArray) -> FloatArray:
        """dE/dt = ω · τ, W: Euler's equations I ω' = τ − ω × I ω dotted with ω (the
        gyroscopic term does no work)."""
        return np.sum(x[..., 4:] * np.asarray(u, float), axis=-1)

    def momentum(self, x: FloatArray) -> FloatArray:
        """Angular momentum about the centre of mass in inertial axes, C(β)ᵀ I ω, N m s."""
        h = matvec(self.inertia, x[..., 4:])
        return np.einsum("...ji,...j->...i", dcm(x[..., :4]), h)
