"""Single-axis hybrid-coordinate plants: a rigid hub angle θ plus elastic coordinates q.

    M [θ'', q'']ᵀ + D [θ', q']ᵀ + K [θ, q]ᵀ = e_θ u + f,     x = [θ, q, θ', q']

(Hailey, Sortun & Agrawal c. 1992 Eqs. 15-16; Junkins, Pollock & Rahman 1990 Att. 3 Eq. 5
discretised). :class:`HybridPlant` holds what every
such plant shares — the first-order form, accelerations, energy, vibration energy and the
error-energy Lyapunov function — and implements the plant protocol
(:class:`~flexsat.dynamics.plant.Plant`) that :func:`flexsat.sim.simulate` drives: one input
channel ``torque`` (N m), outputs ``theta``, ``theta_dot``, ``root_torque`` and
``tip_deflection`` (and the root loads of a beam model), all linear in (x, u, f_in) unless the
rotational stiffening is on.
:class:`~flexsat.dynamics.hub_appendage.HubAppendage` (exact beam modes, root loads, rotational
stiffening) and :class:`ModalHybrid` (any cantilevered :class:`ModalModel`) build on it.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from functools import cached_property
from typing import TYPE_CHECKING, Self, TypeAlias

import numpy as np
from scipy.linalg import eigh

from flexsat.dynamics.plant import Channel, ManeuverChannels, Plant
from flexsat.input_checks import FieldError, require_count, require_finite, require_positive

if TYPE_CHECKING:
    import numpy.typing as npt

    import control
    from flexsat.structures.modal_model import Direction, ModalModel
    from flexsat.units import FloatArray, QuantityLike

    #: every output of a hybrid plant at once: ``(x, u, extra_force)`` -> {name: values}
    OutputEvaluator: TypeAlias = Callable[
        [FloatArray, npt.ArrayLike, float | FloatArray], dict[str, FloatArray]
    ]


class OutputChannels(tuple[Channel, ...]):
    """The output channels of a hybrid plant, callable as its historical ``outputs(x, u,
    extra_force)`` (every output at once, a dict); the plant protocol reads the tuple."""

    _evaluate: OutputEvaluator

    def __new__(cls, channels: Iterable[Channel], evaluate: OutputEvaluator) -> Self:
        obj = super().__new__(cls, channels)
        obj._evaluate = evaluate
        return obj

    def __call__(
        self, x: FloatArray, u: npt.ArrayLike, extra_force: float | FloatArray = 0.0
    ) -> dict[str, FloatArray]:
        return self._evaluate(x, u, extra_force)


#: channels every hybrid plant has
HYBRID_OUTPUTS = (
    Channel("theta", "rad", description="hub angle θ"),
    Channel("theta_dot", "rad/s", description="hub rate θ'"),
    Channel("root_torque", "N*m", description="reaction torque of one appendage on the hub"),
    Channel("tip_deflection", "m", description="elastic displacement of the tip"),
)


class HybridPlant(Plant):
    """Shared machinery of a hub + flexible-body plant in hybrid coordinates.

    Subclasses provide ``mass_matrix``, ``stiffness_matrix``, ``damping_matrix`` (ndof × ndof,
    coordinate 0 the hub angle), ``hub_inertia`` and ``n_appendages``, ``output_values`` (every
    output as a dict) and ``_output_coefficients`` (the linear form of each output).
    """

    stiffening = False
    inputs = (Channel("torque", "N*m", description="hub torque u"),)
    output_channels: tuple[Channel, ...] = HYBRID_OUTPUTS
    recorded = ("theta", "theta_dot", "root_torque", "tip_deflection")
    #: a slew of the hub angle: the maneuver metrics read theta, theta_dot, torque, tip_deflection
    maneuver = ManeuverChannels()
    #: measured values kept in the result as ``<name>_measured`` (the strain-gauge channel)
    recorded_measurements = ("root_torque",)
    #: input channels whose disturbance and friction histories are always in the result
    recorded_disturbances = ("torque",)
    # gyro, strain gauge, random torque: the order of today's streams, so each case's noise
    # is bit-identical whatever the engine measures (the stored order Plant.noise_channels reads)
    _noise_channels: tuple[str, ...] = ("theta_dot", "root_torque", "torque")

    if TYPE_CHECKING:
        # what a subclass provides, as an attribute or a property (class docstring)
        @property
        def mass_matrix(self) -> FloatArray: ...
        @property
        def damping_matrix(self) -> FloatArray: ...
        @property
        def stiffness_matrix(self) -> FloatArray: ...
        @property
        def hub_inertia(self) -> float: ...
        @property
        def n_appendages(self) -> int: ...
        @property
        def _tip_row(self) -> FloatArray: ...
        def output_values(
            self, x: FloatArray, u: npt.ArrayLike, extra_force: float | FloatArray = 0.0
        ) -> dict[str, FloatArray]: ...

    @property
    def outputs(self) -> OutputChannels:
        """Output channels (a tuple), callable as ``outputs(x, u, extra_force)`` → dict."""
        return OutputChannels(self.output_channels, self.output_values)

    @outputs.setter
    def outputs(self, channels: tuple[Channel, ...]) -> None:
        raise AttributeError(
            f"outputs: {type(self).__name__}'s are its output_channels (read-only)"
        )

    @property
    def nonlinear(self) -> bool:
        return bool(self.stiffening)

    @nonlinear.setter
    def nonlinear(self, value: bool) -> None:
        raise AttributeError(f"nonlinear: {type(self).__name__}'s is its stiffening (read-only)")

    @property
    def ndof(self) -> int:
        return self.mass_matrix.shape[0]

    @property
    def nx(self) -> int:
        return 2 * self.ndof

    @property
    def total_inertia(self) -> float:
        """Rigid inertia of the whole vehicle about the hub axis, M_θθ, kg m²."""
        return float(self.mass_matrix[0, 0])

    @property
    def appendage_inertia(self) -> float:
        """Rigid inertia of one appendage about the hub axis, (M_θθ − I_hub)/n, kg m²."""
        return (self.total_inertia - self.hub_inertia) / self.n_appendages

    @cached_property
    def mass_inverse(self) -> FloatArray:
        # numpy types inv() as floating[Any]; it is float64 here, so the astype copies nothing
        return np.linalg.inv(self.mass_matrix).astype(np.float64, copy=False)

    @cached_property
    def torque_input(self) -> FloatArray:
        """Generalized-force direction of a hub torque, e_θ."""
        b = np.zeros(self.ndof)
        b[0] = 1.0
        return b

    @cached_property
    def state_space(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        """First-order matrices (A, B_u, B_f) of x' = A x + B_u u + B_f f.

        u is the hub torque; f (ndof,) is any additional generalized force (friction, stiffening).
        """
        Minv = self.mass_inverse
        k1 = self.ndof
        A = np.zeros((2 * k1, 2 * k1))
        A[:k1, k1:] = np.eye(k1)
        A[k1:, :k1] = -Minv @ self.stiffness_matrix
        A[k1:, k1:] = -Minv @ self.damping_matrix
        Bf = np.vstack([np.zeros((k1, k1)), Minv])
        return A, Bf @ self.torque_input, Bf

    # -- plant protocol -------------------------------------------------------------------------
    def linear_part(self) -> tuple[FloatArray, FloatArray]:
        """(A, B) with B = B_u[:, None]: the single input column of the hub torque."""
        A, Bu, _ = self.state_space
        return A, Bu[:, None]

    @property
    def force_matrix(self) -> FloatArray | None:
        """B_f = [0; M⁻¹] (all generalized forces) when the stiffening is on, else None."""
        return self.state_space[2] if self.stiffening else None

    def output_matrices(self, name: str) -> tuple[FloatArray, FloatArray, FloatArray | None] | None:
        """(C, D, D_f) of an output linear in the state, the torque and the extra hub force.

        Each output is y = c_p·pos + c_v·vel + c_a·acc + c_u (u + f_in) with the accelerations
        acc = A[ndof:] x + B[ndof:] (u + f_in) (the second block row of the first-order form);
        None (nonlinear) for acceleration outputs when the stiffening is on.
        """
        c_pos, c_vel, c_acc, c_u = self._output_coefficients(name)
        if self.stiffening and np.any(c_acc):
            return None
        A, B = self.linear_part()
        k1 = self.ndof
        C = np.concatenate([c_pos, c_vel]) + c_acc @ A[k1:]
        D = c_acc @ B[k1:] + c_u
        return C[None, :], D[None, :], D[None, :].copy()

    def _output_coefficients(self, name: str) -> tuple[FloatArray, FloatArray, FloatArray, float]:
        """(c_pos, c_vel, c_acc, c_u) of the outputs every hybrid plant has."""
        k1 = self.ndof
        z = np.zeros(k1)
        e0 = self.torque_input
        if name == "theta":
            return e0, z, z, 0.0
        if name == "theta_dot":
            return z, e0, z, 0.0
        if name == "root_torque":  # (u + f − I_hub θ'')/n, the hub equation
            n = self.n_appendages
            return z, z, -self.hub_inertia * e0 / n, 1.0 / n
        if name == "tip_deflection":
            return np.concatenate([[0.0], self._tip_row]), z, z, 0.0
        raise FieldError(name, f"{type(self).__name__} has no output channel {name!r}")

    def output(
        self, name: str, x: FloatArray, u: FloatArray, f_in: FloatArray | None = None
    ) -> FloatArray:
        """Output ``name`` at x (..., n_x), u (..., 1) and extra hub force f_in (..., 1)."""
        if self.output_matrices(name) is not None:
            return super().output(name, x, u, f_in)
        extra: float | FloatArray = (
            0.0 if f_in is None else np.multiply.outer(np.asarray(f_in)[..., 0], self.torque_input)
        )
        return self.output_values(x, np.asarray(u)[..., 0], extra)[name]

    def momentum(self, x: FloatArray) -> FloatArray:
        """Angular momentum about the hub axis, h = (M x')_θ, N m s."""
        return self.split(x)[1] @ self.mass_matrix[0]

    def hub_free_frequencies(self) -> FloatArray:
        """Elastic natural frequencies of the free vehicle, rad/s (the rigid mode dropped)."""
        lam = eigh(self.stiffness_matrix, self.mass_matrix, eigvals_only=True)
        return np.sqrt(np.clip(lam[1:], 0.0, None))

    def to_statespace(self) -> control.StateSpace:
        """python-control StateSpace, input hub torque, outputs θ and θ'."""
        import control

        A, Bu, _ = self.state_space
        C = np.zeros((2, self.nx))
        C[0, 0] = 1.0
        C[1, self.ndof] = 1.0
        return control.ss(A, Bu[:, None], C, np.zeros((2, 1)))

    # -- state helpers (x has shape (..., nx)) ---------------------------------------------------
    def split(self, x: FloatArray) -> tuple[FloatArray, FloatArray]:
        k1 = self.ndof
        return x[..., :k1], x[..., k1:]

    def nonlinear_force(self, x: FloatArray, u: npt.ArrayLike) -> FloatArray:
        """Generalized force of nonlinear terms, shape (..., ndof); none in a linear plant."""
        return np.zeros(x.shape[:-1] + (self.ndof,))

    def _linear_force(self, pos: FloatArray, vel: FloatArray, u: npt.ArrayLike) -> FloatArray:
        return (
            -pos @ self.stiffness_matrix
            - vel @ self.damping_matrix
            + np.multiply.outer(_torque(u, pos), self.torque_input)
        )

    def acceleration(
        self, x: FloatArray, u: npt.ArrayLike, extra_force: float | FloatArray = 0.0
    ) -> FloatArray:
        """Generalized accelerations (θ'', q'') for state x, hub torque u and extra force."""
        pos, vel = self.split(x)
        force = self._linear_force(pos, vel, u) + extra_force
        if self.stiffening:
            force = force + self.nonlinear_force(x, u)
        return force @ self.mass_inverse

    def reaction_torque(
        self, x: FloatArray, u: npt.ArrayLike, extra_force: float | FloatArray = 0.0
    ) -> FloatArray:
        """Torque the flexible body exerts back on the hub, per appendage:
        I_hub θ'' = u − n·(this), the Lyapunov laws' ``root_torque`` (l0 S0 − M0 for beams)."""
        acc = self.acceleration(x, u, extra_force)
        extra = np.asarray(extra_force, float)
        tau = np.asarray(u, float) + (extra[..., 0] if extra.ndim else 0.0)
        return (tau - self.hub_inertia * acc[..., 0]) / self.n_appendages

    # -- energies (Att. 3 Eqs. 7, 8, 18) --------------------------------------------------------
    def energy(self, x: FloatArray) -> FloatArray:
        """Total mechanical energy ½ x'ᵀ M x' + ½ xᵀ K x, J."""
        pos, vel = self.split(x)
        # two-operand einsums: the three-operand form is several times slower on batches
        E = 0.5 * np.einsum("...i,...i->...", vel @ self.mass_matrix, vel)
        return E + 0.5 * np.einsum("...i,...i->...", pos @ self.stiffness_matrix, pos)

    def power(self, x: FloatArray, u: FloatArray) -> FloatArray:
        """dE/dt = θ' u − x'ᵀ D x', W: the hub torque's work less the structural damping's
        dissipation (M x'' + D x' + K x = e_θ u, Att. 3 Eq. 5, dotted with x'); the
        stiffening forces, when on, are conservative with the energy of
        :meth:`~flexsat.dynamics.hub_appendage.HubAppendage.energy` and do no net work."""
        _, vel = self.split(x)
        u = np.asarray(u, float)[..., 0]
        return vel[..., 0] * u - np.einsum("...i,...i->...", vel @ self.damping_matrix, vel)

    @property
    def energy_matrix(self) -> FloatArray | None:
        """Q = blockdiag(K, M) of :meth:`energy` = ½ xᵀ Q x (Att. 3 Eq. 7); None with the
        stiffening term on (its energy is quartic)."""
        if self.stiffening:
            return None
        return _block_diagonal(self.stiffness_matrix, self.mass_matrix)

    @energy_matrix.setter
    def energy_matrix(self, Q: FloatArray | None) -> None:
        raise AttributeError(
            f"energy_matrix: {type(self).__name__}'s follows its model (read-only)"
        )

    @property
    def momentum_row(self) -> FloatArray:
        """Row r (n_x,) of :meth:`momentum` = r · x: [0, M[0]] (h = (M x')_θ)."""
        return np.concatenate([np.zeros(self.ndof), self.mass_matrix[0]])

    def vibration_energy(self, x: FloatArray, energy: FloatArray | None = None) -> FloatArray:
        """Energy in the elastic modes of the free vehicle, E − h² / (2 I_tot), J.

        h = (M x')_θ is the angular momentum; the rigid mode is M-orthogonal to the elastic ones,
        so its kinetic energy is exactly h² / (2 I_tot) and the rest is vibration. Pass
        ``energy`` = E(x) when it is already known.
        """
        _, vel = self.split(x)
        h = vel @ self.mass_matrix[0]
        E = self.energy(x) if energy is None else energy
        return E - 0.5 * h**2 / self.total_inertia

    def lyapunov(
        self, x: FloatArray, theta_f: float | FloatArray, g1: float, g3: float
    ) -> FloatArray:
        """Error-energy Lyapunov function of Att. 3 Eq. 8 (normalised a1 = 1), J.

        U = ½ I_hub θ'² + ½ g1 (θ − θ_f)² + (1 + g3/n) E_flex, with g1 = a2/a1 and
        g3 = n (a3 − a1)/a1. For the tracking function (Eq. 18) pass x − x_r and θ_f = 0.
        """
        pos, vel = self.split(x)
        hub_ke = 0.5 * self.hub_inertia * vel[..., 0] ** 2
        flexible = self.energy(x) - hub_ke
        return (
            hub_ke
            + 0.5 * g1 * (pos[..., 0] - theta_f) ** 2
            + (1 + g3 / self.n_appendages) * flexible
        )


class ModalHybrid(HybridPlant):
    """A rigid hub carrying a cantilevered :class:`~flexsat.structures.modal_model.ModalModel`
    (Hailey, Sortun & Agrawal c. 1992 Eq. 16: M = [[I_zz, Dᵀ], [D, 1]], K =
    diag(0, ω²), C = diag(0, 2ζω)).

    Parameters
    ----------
    modal : ModalModel
        Cantilevered modal model, reference point on the hub axis (participation about it).
    hub_inertia : float, str or pint.Quantity
        Rigid hub inertia about the axis (without the flexible body), kg m² (a unit string
        such as ``"2 kg*m**2"`` or a Quantity is converted).
    axis : {0, 1, 2, "x", "y", "z"}
        Rotation axis through the modal model's reference point.
    n_modes : int, optional
        Keep the first modes only.
    tip : (node, direction), optional
        Output ``tip_deflection``: displacement of this node along this direction.
    """

    n_appendages = 1
    hub_inertia: float
    mass_matrix: FloatArray
    damping_matrix: FloatArray
    stiffness_matrix: FloatArray

    def __init__(
        self,
        modal: ModalModel,
        hub_inertia: QuantityLike,
        axis: int | str = 2,
        n_modes: int | None = None,
        tip: tuple[int, Direction] | None = None,
    ) -> None:
        from flexsat.structures.modal_model import hub_appendage_matrices

        if n_modes is not None:
            modal = modal.truncate(require_count(n_modes, "n_modes"))
        self.modal = modal
        self.hub_inertia = float(require_positive(hub_inertia, "hub_inertia", "kg*m**2"))
        M, D, K = hub_appendage_matrices(modal, self.hub_inertia, axis=axis)
        self.mass_matrix, self.damping_matrix, self.stiffness_matrix = M, D, K
        self._tip = (
            np.zeros(modal.n_modes)
            if tip is None
            else np.asarray(modal.displacement_output(*tip), float)
        )
        require_finite(self._tip, "tip")

    @property
    def _tip_row(self) -> FloatArray:
        return self._tip

    def output_values(
        self, x: FloatArray, u: npt.ArrayLike, extra_force: float | FloatArray = 0.0
    ) -> dict[str, FloatArray]:
        """Hub angle and rate, the reaction torque on the hub (``root_torque``) and the
        displacement of the ``tip`` node."""
        pos, vel = self.split(x)
        return {
            "theta": pos[..., 0],
            "theta_dot": vel[..., 0],
            "root_torque": self.reaction_torque(x, u, extra_force),
            "tip_deflection": pos[..., 1:] @ self._tip,
        }


def _torque(u: npt.ArrayLike, pos: FloatArray) -> FloatArray:
    """The hub torque as (...,): the protocol's (..., 1) input vector or the historical scalar
    torque per state."""
    torque = np.asarray(u, float)
    return torque[..., 0] if torque.ndim and torque.shape == pos.shape[:-1] + (1,) else torque


def _block_diagonal(a: FloatArray, b: FloatArray) -> FloatArray:
    """blockdiag(a, b) of two square matrices."""
    n, k = a.shape[0], b.shape[0]
    out = np.zeros((n + k, n + k))
    out[:n, :n], out[n:, n:] = a, b
    return out
