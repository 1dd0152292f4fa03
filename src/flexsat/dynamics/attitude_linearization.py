r"""Linearisation of the three-axis spacecraft in attitude-error coordinates about a reference
attitude moving at a constant body rate (at rest when the rate is zero).

Plants: :class:`~flexsat.dynamics.rigid_spacecraft.RigidSpacecraft` and
:class:`~flexsat.dynamics.flexible_spacecraft.FlexibleSpacecraft` (without translation).

Reference. A target frame R with Euler parameters :math:`\beta_R(t)` turning at the constant
rate :math:`\omega_r` (R components): :math:`\dot\beta_R = \tfrac12[0, \omega_r]\otimes\beta_R`,
so :math:`\beta_R(t) = \exp(\omega_r t)\otimes\beta_R(0)`
(:func:`~flexsat.dynamics.attitude.quaternion_exp`). The body follows it exactly (ω = ω_r,
η̇ = 0) under the constant torque and static deflection

.. math::

    u_r = \omega_r\times J\omega_r, \qquad \Omega^2\eta_r = \Phi_{r,k}^T u_r,

the equilibrium of Euler's equation :math:`\dot h + \omega\times h = u` with
:math:`h = J\omega + \Delta^T\dot\eta` and of the modal equation (``torque_node`` torquers load
the modes; :mod:`~flexsat.dynamics.flexible_spacecraft`). No load depends on the attitude, so
the linearisation does not depend on :math:`\beta_R(0)`.

Error coordinates. The attitude error is the body relative to R,
:math:`\delta q = \beta\otimes\beta_R^*` (:math:`C(\beta) = C(\delta q)\,C(\beta_R)`, the
convention of :func:`~flexsat.control.attitude_laws.error_quaternion`), on its short rotation
(:math:`\delta q_0 \ge 0`), in one of

* MRPs :math:`\sigma = \delta q_v/(1 + \delta q_0) = \hat e\tan(\phi/4)`
  (Schaub & Junkins, *Analytical Mechanics of Space Systems*, 4th ed., AIAA 2018, Eq. 3.142;
  the short rotation keeps :math:`|\sigma| \le 1`, i.e. the shadow set is taken past 180°);
* the quaternion vector part :math:`q_v = \delta q_v = \hat e\sin(\phi/2)`.

For a small error rotation φ about ê, :math:`\sigma \approx \phi\hat e/4` and
:math:`q_v \approx \phi\hat e/2`, so :math:`\sigma \approx q_v/2 \approx \theta/4`, θ = φê the
small rotation vector. The rate error is :math:`\delta\omega = \omega - \omega_r` (body
components); :math:`\delta\eta = \eta - \eta_r`, :math:`\delta\dot\eta = \dot\eta`,
:math:`\delta u = u - u_r` (torque, then the plant's point forces, all about zero).

Kinematics. MRPs of B relative to R obey :math:`\dot\sigma = \tfrac14 B(\sigma)\,\omega_{B/R}`,
:math:`B(\sigma) = (1 - \sigma^T\sigma)I + 2[\sigma\times] + 2\sigma\sigma^T` (Schaub &
Junkins Eq. 3.163) with the relative rate :math:`\omega_{B/R} = \omega - C(\sigma)\omega_r` in
body components. To first order :math:`B \approx I + 2[\sigma\times]`,
:math:`C(\sigma) \approx I - 4[\sigma\times]` and :math:`\omega_{B/R} = O(\sigma, \delta\omega)`, so

.. math::

    \dot\sigma = \tfrac14\delta\omega - \omega_r\times\sigma, \qquad
    \dot q_v = \tfrac12\delta\omega - \omega_r\times q_v

(the second from :math:`\dot{\delta q}_v = \tfrac12(\delta q_0\,\delta\omega
- \omega\times\delta q_v - \omega_r\times\delta q_v)`, the vector part of
:math:`\dot{\delta q} = \tfrac12([0, \omega]\otimes\delta q - \delta q\otimes[0, \omega_r])`
that :math:`\dot\beta = \tfrac12[0, \omega]\otimes\beta` (EPS slew study c. 1989 Eq. 11)
gives for :math:`\delta q = \beta\otimes\beta_R^*`; it is twice the first, as
:math:`q_v \approx 2\sigma`).

Dynamics. With :math:`\mathcal M = [[J, \Delta^T], [\Delta, I]]` (for the rigid body
:math:`\mathcal M = J` and no modes), :math:`h_r = J\omega_r` and the input matrix
:math:`Q_u` of the plant (torque :math:`[I; \Phi_{r,k}^T]`, forces :math:`[G; \Phi_t^T]`), the
first variation of :math:`d(-\omega\times h) = [h\times]d\omega - [\omega\times]dh` gives

.. math::

    \mathcal M\begin{bmatrix}\delta\dot\omega \\ \delta\ddot\eta\end{bmatrix} =
    \begin{bmatrix} [h_r\times] - [\omega_r\times]J & 0 & -[\omega_r\times]\Delta^T \\
    0 & -\Omega^2 & -2Z\Omega \end{bmatrix}
    \begin{bmatrix}\delta\omega \\ \delta\eta \\ \delta\dot\eta\end{bmatrix} + Q_u\,\delta u .

At rest this is the double integrator :math:`\ddot\sigma = \tfrac14 J^{-1}\delta u` of a rigid
body (:math:`\ddot q_v = \tfrac12 J^{-1}\delta u`), one per axis for a principal J.

State :math:`z = [e, \delta\omega, \delta\eta, \delta\dot\eta]` (e = σ or q_v), outputs the
measured error :math:`[e, \delta\omega]` then the plant's linear node outputs (displacements,
rotations: :math:`\Phi\,\delta\eta`, deviations from their reference values), D = 0.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from flexsat.dynamics.attitude import require_shape
from flexsat.dynamics.flexible_spacecraft import FlexibleSpacecraft
from flexsat.dynamics.rigid_spacecraft import RigidSpacecraft, skew
from flexsat.input_checks import FieldError

if TYPE_CHECKING:
    import numpy.typing as npt

    import control
    from flexsat.units import FloatArray

__all__ = ["AttitudeLinearization", "COORDINATES", "linearize_attitude"]

#: the attitude-error coordinates, with the factor k of ė = k δω − ω_r × e
COORDINATES = {"mrp": 0.25, "quaternion": 0.5}
#: state and output label stems of the error coordinates (python-control ``name[i]`` signals)
_STEMS = {"mrp": "sigma", "quaternion": "q_v"}


@dataclass(frozen=True)
class AttitudeLinearization:
    r"""A continuous-time state space :math:`\dot z = Az + B\,\delta u`,
    :math:`\delta y = Cz + D\,\delta u` in attitude-error coordinates (module docstring).

    Attributes
    ----------
    A, B, C, D : ndarray
        (n, n), (n, m), (p, n), (p, m); n = 6 + 2 n_modes.
    states, inputs, outputs : tuple of str
        Signal labels (python-control's ``name[i]`` form): ``sigma[i]`` or ``q_v[i]``,
        ``rate_error[i]``, ``eta[j]``, ``eta_dot[j]``; ``torque[i]`` then the plant's force
        channels; the error coordinates and ``rate_error[i]``, then the plant's node outputs.
    coordinates : {"mrp", "quaternion"}
    rate : ndarray (3,)
        Reference body rate ω_r, rad/s.
    torque : ndarray (3,)
        Reference torque u_r = ω_r × Jω_r, N·m (the forces' reference is zero).
    deflection : ndarray (n_modes,)
        Reference elastic coordinates η_r (modal units).
    """

    A: FloatArray
    B: FloatArray
    C: FloatArray
    D: FloatArray
    states: tuple[str, ...]
    inputs: tuple[str, ...]
    outputs: tuple[str, ...]
    coordinates: str
    rate: FloatArray
    torque: FloatArray
    deflection: FloatArray

    @property
    def torque_columns(self) -> slice:
        """Columns of B of the three torque components."""
        return slice(0, 3)

    @property
    def measured_rows(self) -> slice:
        """Rows of C of the measured error [e, δω] (what an attitude law forms)."""
        return slice(0, 6)

    def to_statespace(self, name: str | None = None) -> control.StateSpace:
        """python-control ``StateSpace`` (continuous time) with the labelled signals."""
        import control

        return control.ss(
            self.A,
            self.B,
            self.C,
            self.D,
            states=list(self.states),
            inputs=list(self.inputs),
            outputs=list(self.outputs),
            name=name,
        )


def _output_row(plant: FlexibleSpacecraft, name: str) -> FloatArray:
    matrices = plant.output_matrices(name)
    if matrices is None:
        raise FieldError(name, "not a linear output of the plant")
    return matrices[0][0]


def _labels(stem: str, n: int) -> list[str]:
    return [f"{stem}[{i}]" for i in range(n)]


def linearize_attitude(
    plant: RigidSpacecraft | FlexibleSpacecraft,
    coordinates: str = "mrp",
    rate: npt.ArrayLike = (0.0, 0.0, 0.0),
) -> AttitudeLinearization:
    r"""The plant linearised in attitude-error coordinates about a reference turning at the
    constant body rate ``rate`` (module docstring).

    Parameters
    ----------
    plant : RigidSpacecraft or FlexibleSpacecraft
        One plant (a single inertia; a flexible one without translation).
    coordinates : {"mrp", "quaternion"}
        Attitude error as MRPs σ or as the quaternion vector part q_v.
    rate : array_like (3,)
        Reference body rate ω_r, rad/s (R components); zero: regulation at rest.

    Returns
    -------
    AttitudeLinearization
    """
    if coordinates not in COORDINATES:
        raise FieldError(
            "coordinates", f"must be one of {sorted(COORDINATES)}, got {coordinates!r}"
        )
    w_r = require_shape(rate, "rate", (3,))
    if w_r.shape != (3,):
        raise FieldError("rate", f"must be one body rate of shape (3,), got {w_r.shape}")
    if isinstance(plant, FlexibleSpacecraft):
        if plant.translation:
            raise FieldError(
                "plant",
                "must be built without translation (the error state is attitude, rate "
                "and elastic coordinates)",
            )
        J, Delta = plant.inertia, plant.coupling
        M = plant.rotation_mass
        n = plant.n_modes
        stiffness, damping = plant.stiffness, plant.damping
        Qu = np.zeros((3 + n, 3 + len(plant.forces)))
        Qu[:3, :3] = np.eye(3)
        Qu[:3, 3:] = plant.force_moments
        Qu[3:, :3] = plant.torque_modal
        Qu[3:, 3:] = plant.force_modal
        force_names = [c.name for c in plant.inputs[1:]]
        node_outputs = [
            c.name for c in plant.outputs if c.name.startswith(("displacement_", "rotation_"))
        ]
        # a node output is Φ η (FlexibleSpacecraft.output_matrices); η is x[7 : 7 + n]
        # without translation
        node_rows = [_output_row(plant, name)[7 : 7 + n] for name in node_outputs]
    elif isinstance(plant, RigidSpacecraft):
        if plant.inertia.ndim != 2:
            raise FieldError("plant", "must have one inertia (3, 3), not a dispersed batch of them")
        J, Delta, M, n = plant.inertia, np.zeros((0, 3)), plant.inertia, 0
        stiffness = damping = np.zeros(0)
        Qu, force_names, node_outputs, node_rows = np.eye(3), [], [], []
    else:
        raise FieldError(
            "plant",
            f"must be a RigidSpacecraft or FlexibleSpacecraft, got {type(plant).__name__}",
        )

    u_r = np.cross(w_r, J @ w_r)
    eta_r = Qu[3:, :3] @ u_r / stiffness if n else np.zeros(0)
    Wr = skew(w_r)
    nz, m = 6 + 2 * n, Qu.shape[1]
    e, w, eta, eta_dot = slice(0, 3), slice(3, 6), slice(6, 6 + n), slice(6 + n, nz)
    A = np.zeros((nz, nz))
    B = np.zeros((nz, m))
    A[e, e] = -Wr
    A[e, w] = COORDINATES[coordinates] * np.eye(3)
    A[eta, eta_dot] = np.eye(n)
    # generalized forces of (δω, δη̇) per unit (δω, δη, δη̇), then solved through 𝓜
    Q_z = np.zeros((3 + n, 3 + 2 * n))
    Q_z[:3, :3] = skew(J @ w_r) - Wr @ J
    Q_z[:3, 3 + n :] = -Wr @ Delta.T
    Q_z[3:, 3 : 3 + n] = -np.diag(stiffness)
    Q_z[3:, 3 + n :] = -np.diag(damping)
    vel = np.r_[3:6, 6 + n : nz]
    solved = np.linalg.solve(M, np.hstack([Q_z, Qu]))
    A[vel, 3:] = solved[:, : 3 + 2 * n]
    B[vel] = solved[:, 3 + 2 * n :]

    C = np.zeros((6 + len(node_outputs), nz))
    C[:6, :6] = np.eye(6)
    for i, row in enumerate(node_rows):
        C[6 + i, eta] = row
    stem = _STEMS[coordinates]
    states = _labels(stem, 3) + _labels("rate_error", 3) + _labels("eta", n) + _labels("eta_dot", n)
    return AttitudeLinearization(
        A,
        B,
        C,
        np.zeros((C.shape[0], m)),
        tuple(states),
        tuple(_labels("torque", 3) + force_names),
        tuple(_labels(stem, 3) + _labels("rate_error", 3) + node_outputs),
        coordinates,
        w_r.copy(),
        u_r,
        eta_r,
    )
