r"""Three-axis flexible spacecraft in hybrid coordinates (the DISCOS analogue of the
EPS slew study c. 1989; spec F3).

Coordinates (EPS slew study c. 1989, Eqs. 9–14 and "Model Development": DISCOS takes the
elastic modes, translational and
rotational shapes at the nodes and the lumped masses, and computes the inertial integrals):

* the attitude of a body frame B fixed to the undeformed structure with its origin at the centre
  of mass, Euler parameters β (inertial to body, scalar first; EPS slew study
  c. 1989 Eqs. 9–11), and the body
  rate ω (body axes);
* optionally the inertial position r and velocity v of the centre of mass;
* the elastic coordinates η of a free-free :class:`~flexsat.structures.modal_model.ModalModel`
  (its elastic modes; the rigid ones are the coordinates above): a node k deforms by
  :math:`u_k = \Phi_k\eta` in body axes.

Kinetic and potential energy (Likins 1967, hybrid coordinates, JPL TR 32-1329; Junkins & Kim,
*Introduction to Dynamics and Control of Flexible Structures*, §6), with the inertial integrals
evaluated on the undeformed structure, i.e. the rigid–elastic coupling linear in the
deformation:

.. math::

    T = \tfrac12 m\,v^Tv + \tfrac12\omega^TJ\omega + \omega^T\Delta^T\dot\eta
        + \tfrac12\dot\eta^T\dot\eta, \qquad V = \tfrac12\eta^T\Omega^2\eta,

with m, J the mass and inertia about the centre of mass and
:math:`\Delta = L_\theta(c) = L_\theta(p) + L_t[(c - p)\times]` (n × 3) the rotational
participation factors of the elastic modes about the centre of mass c, from those about the
model's reference p (:class:`ModalModel` module docstring; a rigid rotation θ about c moves a
node by θ × (r − c)). The translational participation L_t of free-free elastic modes is zero
(they do not move the centre of mass), so v does not couple to η; for exact free-free modes Δ is
zero too (M-orthogonality to the rigid rotations) and the coupling is the gyroscopic one below.
Lagrange's equations in quasi-coordinates for ω (Meirovitch, *Methods of Analytical Dynamics*,
§4.12) and in η, with ∂T/∂η = 0 (inertial integrals of the undeformed body), give

.. math::

    \dot h + \omega\times h &= u + \textstyle\sum_k (r_k - c)\times F_k, \qquad
        h = J\omega + \Delta^T\dot\eta, \\
    \Delta\dot\omega + \ddot\eta + 2Z\Omega\,\dot\eta + \Omega^2\eta &=
        \textstyle\sum_k \Phi_{t,k}^T F_k, \\
    \dot\beta = \Omega(\omega)\beta, \qquad m\dot v &= C(\beta)^T \textstyle\sum_k F_k,
    \qquad \dot r = v,

for ideal torquers u at the centre of mass and point forces F_k = F e_a along body axes at the
nodes (EPS slew study c. 1989; spec F15). Torquers mounted on a node k
(``torque_node``, the CG node of a DISCOS
model) add :math:`\Phi_{r,k}^T u` to the elastic equation. In matrix form, with
:math:`\mathcal M = [[J, \Delta^T], [\Delta, I]]`, F the vector of force magnitudes, E the
matrix of their body-axis directions e_a, G that of their moment arms (r_k − c) × e_a and
:math:`\Phi_t` that of their modal inputs,

.. math::

    \mathcal M \begin{bmatrix}\dot\omega\\ \ddot\eta\end{bmatrix} =
    \begin{bmatrix} u + G F - \omega\times(J\omega + \Delta^T\dot\eta) \\
    -2Z\Omega\dot\eta - \Omega^2\eta + \Phi_t^T F + \Phi_{r,k}^T u\end{bmatrix}.

The angular momentum about the centre of mass in inertial axes, :math:`H_N = C^T h`, obeys
:math:`\dot H_N = C^T(\dot h + \omega\times h)` = the applied moment, so it is conserved
without loads; with ζ = 0 the energy T + V is conserved too (ω × h does no work).
Neglected, as in the linear-coupling form of DISCOS: the dependence of J and Δ on η
(centrifugal stiffening, O(η ω²) forces) and the rotation of the force directions with the
node's elastic rotation.

Plant form (:class:`~flexsat.dynamics.plant.Plant`): state
:math:`x = [\beta, \omega, (r, v), \eta, \dot\eta]`; the linear part A, B is the linearisation
about rest (β = (1, 0, 0, 0), ω = 0), so the elastic modes are propagated exactly by the
exponential integrator; the rest is :math:`B_f f` with

.. math::

    f = \big[\Omega(\omega)\beta - (0, \tfrac12\omega),\;
    -\omega\times(J\omega + \Delta^T\dot\eta),\; (C^T - I)\,E F / m\big]

(the last block with translation), entering through I₄ on β, the first three columns of
:math:`\mathcal M^{-1}` on (ω, η̇) and I₃ on v.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import TYPE_CHECKING

import numpy as np

from flexsat.dynamics.plant import Channel, Plant
from flexsat.dynamics.rigid_body import cross3, matvec
from flexsat.dynamics.rigid_spacecraft import (
    ATTITUDE_OUTPUTS,
    attitude_output,
    attitude_state_from,
    dcm,
    kinematics_jacobians,
    normalize_quaternion,
    quaternion_kinematics,
    skew,
)
from flexsat.input_checks import FieldError
from flexsat.structures.modal_model import RIGID_FREQUENCY, ModalModel

if TYPE_CHECKING:
    import numpy.typing as npt

    from flexsat.units import FloatArray, QuantityArrayLike

__all__ = ["FlexibleSpacecraft"]

_AXES = {"x": 0, "y": 1, "z": 2}


def _check_node(modal: ModalModel, node: object, field: str) -> None:
    if not (isinstance(node, (int, np.integer)) and np.any(modal.node_ids == node)):
        shown = ", ".join(map(str, modal.node_ids[:8])) + (
            " ..." if modal.node_ids.size > 8 else ""
        )
        raise FieldError(field, f"unknown node {node!r} (nodes: {shown})")


def _points(
    items: Iterable[tuple[int, str]], field: str, modal: ModalModel
) -> list[tuple[int, str]]:
    """[(node, axis)] with known nodes, axes 'x'/'y'/'z' (any case), no repeats."""
    out = []
    for i, item in enumerate(items):
        try:
            node, axis = item
        except (TypeError, ValueError):
            raise FieldError(
                f"{field}[{i}]", f"must be a pair (node, 'x'|'y'|'z'), got {item!r}"
            ) from None
        if not isinstance(axis, str) or axis.lower() not in _AXES:
            raise FieldError(f"{field}[{i}]", f"axis must be 'x', 'y' or 'z', got {axis!r}")
        _check_node(modal, node, f"{field}[{i}]")
        pair = (int(node), axis.lower())
        if pair in out:
            raise FieldError(f"{field}[{i}]", f"{pair} given twice")
        out.append(pair)
    return out


class FlexibleSpacecraft(Plant):
    r"""Free-free flexible spacecraft in hybrid coordinates (module docstring).

    Outputs: the attitude channels (``attitude``, ``rate``, ``euler123``, ``mrp``), ``position``
    and ``velocity`` with translation, the node outputs below, and ``elastic`` = [η, η̇]
    (2 n_modes wide), the elastic state a perturbation law on the first modes reads
    (:mod:`flexsat.control.perturbation_feedback`).

    Parameters
    ----------
    modal : ModalModel
        Free-free modal model (``boundary="free"``); its modes at or below
        ``rigid_frequency`` are dropped (the rigid motion is carried by β, ω, r, v).
    forces : sequence of (node, axis)
        Point forces along body axis 'x', 'y' or 'z' at a node: input channels
        ``force_<node><AXIS>`` (N, size 1, e.g. ``force_69X``), after ``torque``.
    displacements : sequence of (node, axis)
        Outputs ``displacement_<node><AXIS>``: elastic displacement of the node along the body
        axis, Φ_t η (m).
    rotations : sequence of (node, axis)
        Outputs ``rotation_<node><AXIS>``: elastic rotation of the node about the body axis,
        Φ_r η (rad).
    torque_node : int, optional
        Node carrying the torquers (the CG node of a DISCOS model): the torque then also loads
        the elastic equations, by the node's rotational shapes :math:`\Phi_{r,k}^T u`. Default:
        a torque on the rigid body only (ideal torquers, no elastic load).
    translation : bool
        Carry the centre of mass's inertial position and velocity (outputs ``position``,
        ``velocity``).
    n_modes : int, optional
        Keep the first elastic modes only.
    rigid_frequency : float
        Rigid-mode threshold, rad/s (:data:`flexsat.structures.modal_model.RIGID_FREQUENCY`).
    """

    nonlinear = True
    #: the engine's fourth-order exponential integrator: the elastic modes exactly, f by RK4
    integrator = "exp_rk4"
    recorded: tuple[str, ...] = ("attitude", "euler123", "rate")

    def __init__(
        self,
        modal: ModalModel,
        forces: Iterable[tuple[int, str]] = (),
        displacements: Iterable[tuple[int, str]] = (),
        rotations: Iterable[tuple[int, str]] = (),
        torque_node: int | None = None,
        translation: bool = False,
        n_modes: int | None = None,
        rigid_frequency: float = RIGID_FREQUENCY,
    ) -> None:
        if not isinstance(modal, ModalModel):
            raise FieldError("modal", f"must be a ModalModel, got {type(modal).__name__}")
        if modal.boundary != "free":
            raise FieldError(
                "modal",
                "must be free-free (boundary 'free'), got "
                f"{modal.boundary!r}: hybrid coordinates here carry the rigid "
                f"motion of the whole structure",
            )
        elastic = modal.elastic(rigid_frequency)
        if n_modes is not None:
            elastic = elastic.truncate(n_modes)
        self.modal = elastic
        self.translation = bool(translation)
        n = elastic.n_modes
        self.n_modes = n
        self.mass = elastic.total_mass
        self.center_of_mass = elastic.center_of_mass
        J = elastic.inertia()
        d = self.center_of_mass - elastic.reference
        L = elastic.participation
        Delta = L[:, 3:] + L[:, :3] @ skew(d)
        self._set_rotation(J, Delta, "modal")
        self.stiffness = elastic.frequencies**2
        self.damping = 2 * elastic.damping * elastic.frequencies

        self.forces = _points(forces, "forces", elastic)
        self.displacements = _points(displacements, "displacements", elastic)
        self.rotations = _points(rotations, "rotations", elastic)
        nF = len(self.forces)
        E = np.zeros((3, nF))
        G = np.zeros((3, nF))
        Bq = np.zeros((n, nF))
        for j, (node, axis) in enumerate(self.forces):
            e = np.eye(3)[_AXES[axis]]
            r = elastic.coordinates[elastic.node_ids == node][0] - self.center_of_mass
            E[:, j], G[:, j] = e, np.cross(r, e)
            Bq[:, j] = elastic.force_input(node, axis)
        self.force_directions, self.force_moments, self.force_modal = E, G, Bq
        self.torque_node = None if torque_node is None else int(torque_node)
        self.torque_modal = np.zeros((n, 3))
        if torque_node is not None:
            _check_node(elastic, torque_node, "torque_node")
            self.torque_modal = elastic.torque_input(torque_node, ["x", "y", "z"])

        tag = "{}{}".format
        self.inputs = (
            Channel("torque", "N*m", 3, "ideal torquers at the centre of mass, body axes"),
        ) + tuple(
            Channel(
                f"force_{tag(node, axis.upper())}",
                "N",
                1,
                f"point force at node {node} along body {axis}",
            )
            for node, axis in self.forces
        )
        outputs = list(ATTITUDE_OUTPUTS)
        if self.translation:
            outputs += [
                Channel("position", "m", 3, "centre of mass, inertial axes"),
                Channel("velocity", "m/s", 3, "centre of mass, inertial axes"),
            ]
        outputs += [
            Channel(
                f"displacement_{tag(node, axis.upper())}",
                "m",
                1,
                f"elastic displacement of node {node} along body {axis}",
            )
            for node, axis in self.displacements
        ]
        outputs += [
            Channel(
                f"rotation_{tag(node, axis.upper())}",
                "rad",
                1,
                f"elastic rotation of node {node} about body {axis}",
            )
            for node, axis in self.rotations
        ]
        # last, so the node outputs keep their places (and their noise columns before it)
        outputs.append(
            Channel(
                "elastic", "", 2 * n, "elastic coordinates [η, η̇] (modal units: m √kg and m √kg/s)"
            )
        )
        self.outputs = tuple(outputs)
        # the node outputs are what a flexible run is about (the rim
        # deflections of EPS slew study c. 1989)
        self.recorded = type(self).recorded + tuple(
            c.name for c in self.outputs if c.name.startswith(("displacement_", "rotation_"))
        )
        self._rows = {
            f"displacement_{tag(node, axis.upper())}": elastic.displacement_output(node, axis)
            for node, axis in self.displacements
        }
        self._rows.update(
            {
                f"rotation_{tag(node, axis.upper())}": elastic.rotation_output(node, axis)
                for node, axis in self.rotations
            }
        )

        # index layout of x
        t = 6 if self.translation else 0
        self._eta = slice(7 + t, 7 + t + n)
        self._eta_dot = slice(7 + t + n, 7 + t + 2 * n)
        self._vel = np.r_[4:7, np.arange(self._eta_dot.start, self._eta_dot.stop)]
        self._linear = self._build_linear()
        self._force_matrix = self._build_force_matrix()

    def _set_rotation(self, J: FloatArray, Delta: FloatArray, field: str) -> None:
        """Inertia, coupling and 𝓜 = [[J, Δᵀ], [Δ, I]], refused unless positive definite."""
        n = Delta.shape[0]
        Mr = np.block([[J, Delta.T], [Delta, np.eye(n)]])
        if np.linalg.eigvalsh(Mr).min() <= 1e-12 * np.abs(J).max():
            raise FieldError(
                field,
                "the rotational participation exceeds the inertia "
                "(J − ΔᵀΔ not positive definite): not a free-free model",
            )
        self.inertia, self.coupling = J, Delta
        self.rotation_mass = Mr
        self.rotation_mass_inverse = np.linalg.inv(Mr)

    def with_parameters(
        self,
        inertia: QuantityArrayLike | None = None,
        frequencies: QuantityArrayLike | None = None,
        damping: npt.ArrayLike | None = None,
        coupling: npt.ArrayLike | None = None,
    ) -> FlexibleSpacecraft:
        """The same spacecraft (mode shapes, forces, outputs, torque node) with other rigid and
        modal parameters: one case of a dispersion (a Monte Carlo set stacked by
        :func:`~flexsat.dynamics.dispersion.stack_plants`).

        Parameters
        ----------
        inertia : array_like (3, 3), str or pint.Quantity, optional
            J about the centre of mass, kg m² (:func:`~flexsat.dynamics.rigid_body.
            require_inertia`).
        frequencies : array_like (n_modes,), str or pint.Quantity, optional
            Elastic frequencies Ω, rad/s, positive.
        damping : array_like (n_modes,) or float, optional
            Modal damping ratios ζ >= 0 (the damping 2ζΩ is formed with the new Ω).
        coupling : array_like (n_modes, 3), optional
            Rotational participation Δ about the centre of mass, m √kg.

        Raises
        ------
        FieldError
            Naming the parameter: a wrong shape, a non-positive frequency, a negative
            damping, an inertia violating the triangle inequality, a coupling exceeding the
            inertia.

        Notes
        -----
        Omitted parameters keep this plant's values; the result must keep 𝓜 positive
        definite. ``modal`` stays this plant's :class:`ModalModel` (its shapes and its own
        frequencies): :meth:`reduced` of the result starts from it again.
        """
        import copy

        from flexsat.dynamics.rigid_body import require_inertia
        from flexsat.input_checks import require_finite, require_nonneg, require_positive

        n = self.n_modes
        out = copy.copy(self)
        w = np.sqrt(self.stiffness)
        zeta = self.damping / (2 * w)
        if frequencies is not None:
            w = require_positive(frequencies, "frequencies", "rad/s")
            if w.shape != (n,):
                raise FieldError("frequencies", f"give {n} elastic frequencies, got {w.shape}")
        if damping is not None:
            zeta = np.broadcast_to(require_nonneg(damping, "damping"), (n,)).astype(float)
        J = self.inertia if inertia is None else require_inertia(inertia)
        if J.shape != (3, 3):
            raise FieldError("inertia", f"must have shape (3, 3), got {J.shape}")
        Delta = self.coupling if coupling is None else require_finite(coupling, "coupling")
        if Delta.shape != (n, 3):
            raise FieldError("coupling", f"must have shape ({n}, 3), got {Delta.shape}")
        out._set_rotation(J, Delta, "coupling" if coupling is not None else "inertia")
        out.stiffness = w**2
        out.damping = 2 * zeta * w
        out._linear = out._build_linear()
        out._force_matrix = out._build_force_matrix()
        return out

    def reduced(self, n_modes: int) -> FlexibleSpacecraft:
        """The same spacecraft on its first ``n_modes`` elastic modes (a controller's design
        model): the same modal model, forces, outputs and torque node. Use it rather than a
        separate eigen-solution with fewer modes, whose repeated pairs (the EPS's symmetric
        antenna) may come out rotated or of opposite sign, so that a law reading the first
        modes of this plant would read other coordinates."""
        from flexsat.input_checks import require_count

        n_modes = require_count(n_modes, "n_modes")
        if n_modes > self.n_modes:
            raise FieldError(
                "n_modes", f"at most the plant's {self.n_modes} elastic modes, got {n_modes}"
            )
        return FlexibleSpacecraft(
            self.modal,
            forces=self.forces,
            displacements=self.displacements,
            rotations=self.rotations,
            torque_node=self.torque_node,
            translation=self.translation,
            n_modes=n_modes,
        )

    # -- sizes -----------------------------------------------------------------------------
    @property
    def nx(self) -> int:
        return 7 + (6 if self.translation else 0) + 2 * self.n_modes

    @property
    def n_f(self) -> int:
        return 10 if self.translation else 7

    def initial_state(self, n_cases: int) -> FloatArray:
        """At rest, undeformed, in the inertial attitude β = (1, 0, 0, 0)."""
        x = np.zeros((n_cases, self.nx))
        x[:, 0] = 1.0
        return x

    def state_from(self, **values: QuantityArrayLike) -> FloatArray:
        """Initial state from ``attitude`` or ``euler123``, ``rate`` and ``state``
        (:func:`~flexsat.dynamics.rigid_spacecraft.attitude_state_from`); undeformed at rest
        otherwise."""
        return attitude_state_from(self, values)

    @property
    def initial_values(self) -> tuple[str, ...]:
        return ("attitude", "euler123", "rate", "state")

    def _velocity_rows(self) -> npt.NDArray[np.intp]:
        """Rows of (ω, η̇) in x."""
        return self._vel

    # -- linear part ---------------------------------------------------------------------------
    def _build_linear(self) -> tuple[FloatArray, FloatArray]:
        n, nx = self.n_modes, self.nx
        Minv = self.rotation_mass_inverse
        A = np.zeros((nx, nx))
        B = np.zeros((nx, 3 + len(self.forces)))
        A[1:4, 4:7] = 0.5 * np.eye(3)  # β_v' = ω/2 at β = (1, 0, 0, 0)
        A[self._eta, self._eta_dot] = np.eye(n)
        vel = self._velocity_rows()
        # generalized force of (ω, η̇): [u + G F; −Dη̇ − Kη + Φᵀ F]
        Q_x = np.zeros((3 + n, nx))
        Q_x[3:, self._eta] = -np.diag(self.stiffness)
        Q_x[3:, self._eta_dot] = -np.diag(self.damping)
        Q_u = np.zeros((3 + n, B.shape[1]))
        Q_u[:3, :3] = np.eye(3)
        Q_u[:3, 3:] = self.force_moments
        Q_u[3:, :3] = self.torque_modal
        Q_u[3:, 3:] = self.force_modal
        A[vel] = Minv @ Q_x
        B[vel] = Minv @ Q_u
        if self.translation:
            A[7:10, 10:13] = np.eye(3)
            B[10:13, 3:] = self.force_directions / self.mass
        return A, B

    def _build_force_matrix(self) -> FloatArray:
        Bf = np.zeros((self.nx, self.n_f))
        Bf[:4, :4] = np.eye(4)
        Bf[self._velocity_rows(), 4:7] = self.rotation_mass_inverse[:, :3]
        if self.translation:
            Bf[10:13, 7:10] = np.eye(3)
        return Bf

    def linear_part(self) -> tuple[FloatArray, FloatArray]:
        """(A, B): the linearisation about rest (module docstring)."""
        return self._linear

    @property
    def force_matrix(self) -> FloatArray:
        return self._force_matrix

    # -- nonlinear remainder ---------------------------------------------------------------
    def _momentum_body(self, x: FloatArray) -> FloatArray:
        """h = Jω + Δᵀη̇, body axes."""
        return matvec(self.inertia, x[..., 4:7]) + x[..., self._eta_dot] @ self.coupling

    def nonlinear_force(self, x: FloatArray, u: FloatArray) -> FloatArray:
        """f(x, u) (..., n_f) of the module docstring."""
        x = np.asarray(x, float)
        beta, w = x[..., :4], x[..., 4:7]
        shape = x.shape[:-1]
        if self.translation:
            shape = np.broadcast_shapes(shape, np.shape(u)[:-1])
        f = np.empty(shape + (self.n_f,))
        f[..., :4] = quaternion_kinematics(beta, w)
        f[..., 1:4] -= 0.5 * w
        f[..., 4:7] = -matvec(skew(w), self._momentum_body(x))
        if self.translation:
            F = np.asarray(u, float)[..., 3:] @ self.force_directions.T  # body axes
            # (Cᵀ − I) F: body-fixed force directions turned into inertial axes
            f[..., 7:10] = (np.einsum("...ji,...j->...i", dcm(beta), F) - F) / self.mass
        return f

    def force_jacobian(self, x: FloatArray, u: FloatArray) -> tuple[FloatArray, FloatArray]:
        r"""(∂f/∂x, ∂f/∂u), analytic:

        * β block: ∂/∂β = Ω(ω), ∂/∂ω = B(β) − [0; ½ I];
        * gyroscopic block, :math:`d(-\omega\times h) = [h\times]d\omega - [\omega\times]
          (J\,d\omega + \Delta^T d\dot\eta)`;
        * translation block: ∂(Cᵀ F)/∂β from
          :math:`C^T F = (\beta_0^2 - \beta_v^T\beta_v)F + 2\beta_v\beta_v^TF
          + 2\beta_0\,\beta_v\times F`, and ∂/∂u = (Cᵀ − I) E / m.
        """
        x = np.asarray(x, float)
        beta, w = x[..., :4], x[..., 4:7]
        shape = x.shape[:-1]
        if self.translation:
            shape = np.broadcast_shapes(shape, np.shape(u)[:-1])
        Jx = np.zeros(shape + (self.n_f, self.nx))
        Ju = np.zeros(shape + (self.n_f, self._linear[1].shape[1]))
        Om, Bq = kinematics_jacobians(beta, w)
        Jx[..., :4, :4] = Om
        Jx[..., :4, 4:7] = Bq
        Jx[..., 1:4, 4:7] -= 0.5 * np.eye(3)
        h = self._momentum_body(x)
        Wx = skew(w)
        Jx[..., 4:7, 4:7] = skew(h) - Wx @ self.inertia
        Jx[..., 4:7, self._eta_dot] = -Wx @ self.coupling.T
        if self.translation:
            F = np.asarray(u, float)[..., 3:] @ self.force_directions.T
            b0, bv = beta[..., :1], beta[..., 1:]
            dF = np.empty(shape + (3, 4))
            dF[..., :, 0] = 2 * b0 * F + 2 * cross3(bv, F)
            eye = np.eye(3)
            bF = np.sum(bv * F, axis=-1)[..., None, None]
            dF[..., :, 1:] = (
                -2 * F[..., :, None] * bv[..., None, :]
                + 2 * bF * eye
                + 2 * bv[..., :, None] * F[..., None, :]
                - 2 * b0[..., None] * skew(F)
            )
            Jx[..., 7:10, :4] = dF / self.mass
            Ct = np.swapaxes(dcm(beta), -1, -2)
            Ju[..., 7:10, 3:] = (Ct - eye) @ self.force_directions / self.mass
        return Jx, Ju

    def rhs(self, x: FloatArray, u: FloatArray) -> FloatArray:
        """ẋ = A x + B u + B_f f(x, u), the full right-hand side (for reference integrators)."""
        A, B = self._linear
        return (
            x @ A.T + np.asarray(u, float) @ B.T + self.nonlinear_force(x, u) @ self._force_matrix.T
        )

    def normalize(self, x: FloatArray) -> FloatArray:
        """β scaled back to unit norm after a step (the exponential integrator does not keep
        it: its error is the integrator's, O(h⁵) per step)."""
        return normalize_quaternion(x)

    # -- outputs -----------------------------------------------------------------------------
    def output_matrices(self, name: str) -> tuple[FloatArray, FloatArray, FloatArray | None] | None:
        """Linear outputs: the attitude β and body rate ω (components of x, as
        :meth:`RigidSpacecraft.output_matrices <flexsat.dynamics.rigid_spacecraft.
        RigidSpacecraft.output_matrices>`), the node displacements and rotations (Φ η),
        position, velocity and the elastic state ``elastic`` = [η, η̇] (what a perturbation
        law on a reduced model reads: its modes are the first ones of this plant when both
        come from one :class:`~flexsat.structures.modal_model.ModalModel`)."""
        m = self._linear[1].shape[1]
        if name in ("attitude", "rate"):
            C = np.eye(self.nx)[0:4] if name == "attitude" else np.eye(self.nx)[4:7]
        elif name in self._rows:
            C = np.zeros((1, self.nx))
            C[0, self._eta] = self._rows[name]
        elif name in ("position", "velocity") and self.translation:
            C = np.eye(self.nx)[7:10] if name == "position" else np.eye(self.nx)[10:13]
        elif name == "elastic":
            C = np.eye(self.nx)[self._eta.start : self._eta_dot.stop]
        else:
            return None
        return C, np.zeros((C.shape[0], m)), None

    def output(
        self, name: str, x: FloatArray, u: FloatArray | None = None, f_in: FloatArray | None = None
    ) -> FloatArray:
        self._size(name)  # unknown names: a ValueError naming the channel
        if name in self._rows:
            return x[..., self._eta] @ self._rows[name]
        if name == "elastic":
            return x[..., self._eta.start : self._eta_dot.stop]
        if name == "position":
            return x[..., 7:10]
        if name == "velocity":
            return x[..., 10:13]
        return attitude_output(name, x[..., :4], x[..., 4:7])

    # -- invariants ------------------------------------------------------------------------
    def energy(self, x: FloatArray) -> FloatArray:
        r"""T + V = ½[ω; η̇]ᵀ𝓜[ω; η̇] + ½ηᵀΩ²η (+ ½ m vᵀv), J."""
        p = x[..., self._velocity_rows()]
        eta = x[..., self._eta]
        E = 0.5 * np.sum(p * (p @ self.rotation_mass), -1) + 0.5 * np.sum(
            self.stiffness * eta * eta, -1
        )
        if self.translation:
            E = E + 0.5 * self.mass * np.sum(x[..., 10:13] ** 2, -1)
        return E

    def momentum(self, x: FloatArray) -> FloatArray:
        """Total angular momentum in inertial axes, N m s: C(β)ᵀ h about the centre of mass,
        plus r × m v about the inertial origin with translation."""
        H = np.einsum("...ji,...j->...i", dcm(x[..., :4]), self._momentum_body(x))
        if self.translation:
            H = H + self.mass * np.cross(x[..., 7:10], x[..., 10:13])
        return H
