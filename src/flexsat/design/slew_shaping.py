r"""A torquers-only slew that meets the EPS slew study c. 1989 goals:
the rigid nominal torque plus the
minimum-norm correction that brings the design modes to rest at T (the closing argument of the
F18 weight search, :mod:`flexsat.design.slew_weights`).

Why it is needed. The weight search finds no diagonal Q/D of the perturbation feedback (EPS
slew study c. 1989, Eqs. 22–31) meeting the 6 s goals with the
centre-of-mass torquers alone. That is not a
limit of the torquers: on the EPS they load the antenna modes through the CG node's rotational
shapes (:math:`\Phi_{r,CG}^T\tau`, ``torque_node``), a constant, strong input (for a unit
normalized torque J⁻¹δτ the modal accelerations of modes 1–4 are 116, 84, 114 and 36), so the
modes are controllable from the torque at every instant. What the torquers cannot do is excite
the modes independently of the rigid rotation: both respond to the same three inputs, and the
nominal's modal disturbance d(t) (Eq. 31) lies in the range of the torque input. The feedback's
cancellation of d(t) is therefore a cancellation of the slew itself, which the LQR trades
against the attitude error at each instant, and an infinite-horizon gain has no notion of the
modal state at T it should reach. A correction that does plan for T exists, as this module
constructs:

.. math::

    \tau(t) = \tau_n(t) + J\,v(t), \qquad
    v(t) = \sum_{j=1}^{n_b} c_j \sin\frac{j\pi t}{T} \ \ (\text{per axis; } v(0) = v(T) = 0),

with the coefficients c the minimum-norm solution of the linear terminal conditions

.. math::

    \delta X(T) = \int_0^T \Phi(T, s)\,B(s)\,v(s)\,ds
    = [\,0_6;\ -\eta_{ol}(T);\ -\dot\eta_{ol}(T)\,],

Φ the transition matrix of the perturbation dynamics linearised along the
nominal (EPS slew study c. 1989
Eq. 23, :class:`~flexsat.control.trajectory_linearization.TrajectoryLinearization` on the design
model, integrated by RK4 on the control grid with the Jacobians at the half steps) and
:math:`(\eta_{ol}, \dot\eta_{ol})(T)` the design modes' state at T when the nominal torque alone
drives the truth plant: the rigid rotation still ends on the target at rest, the design modes
at rest. Measured on the 45-mode EPS, 1 rad on each axis in 6 s, n_b = 30, 100 Hz, run to
11.5 s: Euler-angle error 0.8 mrad at 7.5 s (goal 30), rim deflection from 7.5 s reduced
1,200:1 (goal 10:1), peak torque perturbation 10 kN m (case D's feedback: 24 kN m), peak
torques 5.7, 14.0 and 34.9 kN m (the nominal's: 7.2, 23.4, 34.4). With n_b = 12 sines: 12.9
mrad, 4,400:1, 19 kN m.

The terminal conditions are built by :func:`terminal_map` (also along any planned trajectory,
with the rigid rows of the target), which :mod:`flexsat.design.planned_slew` optimises over:
least energy or least peak within torque limits, by successive linearisation.

Point forces as planned inputs. Given force channels of the plant (``force_<node><AXIS>``,
a force :math:`F_i` along body axis :math:`e_i` at node :math:`k_i`), each is planned as a
sine series of its own, :math:`F_i(t) = \sum_j d_{ij}\sin(j\pi t/T)` (N, zero at 0 and T);
its columns of X are those of the forces' columns of B(t) in the same integral. The model is
the plant's (:class:`~flexsat.dynamics.flexible_spacecraft.FlexibleSpacecraft`): a force
loads the modes through the node's translational shapes, :math:`\Phi_{t,k_i}^T e_i F_i`, and
the hub through its moment about the centre of mass, :math:`(r_{k_i} - c)\times e_i F_i`
(its line of action through the node, fixed in the body axes); its net translation is not
modelled (the design plant has none, and free-free elastic modes do not couple to it).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from flexsat.input_checks import FieldError, require_count
from flexsat.units import FloatArray

if TYPE_CHECKING:
    from flexsat.design.planned_slew import PlannedTrajectory
    from flexsat.design.slew_weights import SlewEvaluation
    from flexsat.dynamics.flexible_spacecraft import FlexibleSpacecraft
    from flexsat.maneuvers.three_axis_slew import ThreeAxisSlew
    from flexsat.sim import SimConfig

__all__ = ["ShapedSlew", "TerminalMap", "modal_cancelling_torque", "terminal_map"]


@dataclass(frozen=True, eq=False)
class ShapedSlew:
    """The nominal torque plus the correction J v(t) (module docstring); a nominal for
    :class:`~flexsat.control.perturbation_feedback.NominalTorque`.

    Attributes
    ----------
    nominal : ThreeAxisSlew
    coefficients : (3, n_b) array
        c of v (rad/s²) per axis and sine.
    inertia : (3, 3) array
        J, kg m².
    residual : float
        Relative residual of the linear terminal conditions (least squares).
    force_channels : tuple of str
        Planned point forces (plant channels ``force_<node><AXIS>``); empty for torquers
        alone.
    force_coefficients : (n_F, n_b) array, optional
        d of F_i(t) (N) per force and sine (module docstring); None without forces.
    """

    nominal: ThreeAxisSlew
    coefficients: FloatArray
    inertia: FloatArray
    residual: float
    force_channels: tuple[str, ...] = ()
    force_coefficients: FloatArray | None = None

    @property
    def duration(self) -> float:
        return self.nominal.duration

    @property
    def target(self) -> FloatArray:
        return self.nominal.target

    def correction(self, t: npt.ArrayLike) -> FloatArray:
        """v(t) (..., 3), rad/s²; zero outside [0, T]."""
        t = np.asarray(t, float)
        s = np.clip(t, 0.0, self.duration)
        n_b = self.coefficients.shape[1]
        basis = np.sin(s[..., None] * (np.pi / self.duration) * np.arange(1, n_b + 1))
        return basis @ self.coefficients.T

    def torque(self, t: npt.ArrayLike) -> FloatArray:
        """τ_n(t) + J v(t), N m."""
        return self.nominal.torque(t) + self.correction(t) @ self.inertia.T

    def forces(self, t: npt.ArrayLike) -> FloatArray:
        """The planned point forces F(t) (..., n_F), N, in the order of ``force_channels``;
        zero outside [0, T]."""
        t = np.asarray(t, float)
        d = self.force_coefficients
        if d is None or not self.force_channels:
            return np.zeros(t.shape + (0,))
        s = np.clip(t, 0.0, self.duration)
        basis = np.sin(s[..., None] * (np.pi / self.duration) * np.arange(1, d.shape[1] + 1))
        return np.where(((t >= 0.0) & (t <= self.duration))[..., None], basis @ d.T, 0.0)


@dataclass(frozen=True, eq=False)
class TerminalMap:
    """The linear terminal conditions of the sine-series correction (module docstring):
    X c = target, c the coefficients flattened axis by axis ((3, n_b) row-major).

    Attributes
    ----------
    X : (6 + 2n, (3 + n_F) n_b) array
        δX(T) per coefficient (rad, rad/s, modal units) on the design model: the torque
        sines axis by axis, then the force sines force by force.
    target : (6 + 2n,) array
        [0₆; −η_ol(T); −η̇_ol(T)].
    inertia : (3, 3) array
        J of the design model, kg m².
    duration : float
        T, s.
    n_basis : int
        Sines per axis.
    force_channels : tuple of str
        The planned forces (module docstring), in the order of their columns.
    """

    X: FloatArray
    target: FloatArray
    inertia: FloatArray
    duration: float
    n_basis: int
    force_channels: tuple[str, ...] = ()

    @property
    def n_forces(self) -> int:
        return len(self.force_channels)

    def basis(self, t: npt.ArrayLike) -> FloatArray:
        """S(t) (..., 3, 3 n_b): v(t) = S(t) c (zero outside [0, T])."""
        s = np.clip(np.asarray(t, float), 0.0, self.duration)
        sines = np.sin(s[..., None] * (np.pi / self.duration) * np.arange(1, self.n_basis + 1))
        sines = np.where(((s > 0.0) & (s < self.duration))[..., None], sines, 0.0)
        return np.einsum("...j,ab->...abj", sines, np.eye(3)).reshape(
            s.shape + (3, 3 * self.n_basis)
        )

    def force_basis(self, t: npt.ArrayLike) -> FloatArray:
        """S_F(t) (..., n_F, n_F n_b): F(t) = S_F(t) d, d the force coefficients flattened
        force by force (zero outside [0, T])."""
        s = np.clip(np.asarray(t, float), 0.0, self.duration)
        sines = np.sin(s[..., None] * (np.pi / self.duration) * np.arange(1, self.n_basis + 1))
        sines = np.where(((s > 0.0) & (s < self.duration))[..., None], sines, 0.0)
        n_f = self.n_forces
        return np.einsum("...j,ab->...abj", sines, np.eye(n_f)).reshape(
            s.shape + (n_f, n_f * self.n_basis)
        )


def terminal_map(
    truth: FlexibleSpacecraft,
    design_plant: FlexibleSpacecraft,
    nominal: ThreeAxisSlew | PlannedTrajectory,
    config: SimConfig,
    n_basis: int = 30,
    rigid: bool = False,
    forces: Sequence[str] = (),
) -> TerminalMap:
    """The terminal conditions X c = target of the correction of ``nominal`` (module
    docstring): X by RK4 on the control grid of ``config`` along the nominal linearised on
    ``design_plant``, the target from the nominal torque alone flown on ``truth`` (whose first
    modes are the design model's) on the one engine.

    ``nominal`` is any rigid nominal with ``beta``, ``omega``, ``torque``, ``duration`` and
    ``target`` (:mod:`~flexsat.control.trajectory_linearization`). With ``rigid`` the target's
    first six rows are −[δα(T), ω(T)] of that run (the attitude error from ``nominal.target``,
    :func:`~flexsat.control.trajectory_linearization.attitude_error`): the conditions of a
    correction of a nominal that does not end on the target at rest (a planned slew's
    successive linearisation, :mod:`flexsat.design.planned_slew`); without, zero (the rigid
    nominal ends there on the rigid body). ``forces`` names force channels of
    ``design_plant`` planned beside the torque (module docstring): their sine columns follow
    the torque's in X. A nominal that carries planned forces of its own (``forces(t)``,
    ``force_channels``) is flown with them.

    Raises
    ------
    ValueError
        ``n_basis`` < 1, or a control period that does not divide T (under ``config``).
    """
    from dataclasses import replace

    from flexsat.control import NominalTorque, TrajectoryLinearization
    from flexsat.control.trajectory_linearization import attitude_error
    from flexsat.sim import simulate

    n_basis = require_count(n_basis, "n_basis")
    T, h = float(nominal.duration), float(config.dt)
    n_steps = int(round(T / h))
    if abs(n_steps * h - T) > 1e-9 * T:
        raise FieldError(
            "config",
            f"the control period {h:g} s must divide the "
            f"maneuver time {T:g} s (the correction is integrated on that grid)",
        )
    short = replace(config, duration=min(config.duration, (n_steps + 1) * h))
    run = simulate(truth, NominalTorque(nominal, h), short, n_cases=1, record_states=True)
    x_T = run.dataset["state"].isel(case=0).values[n_steps]
    elastic = truth.output("elastic", x_T)
    n = design_plant.n_modes
    start = (
        -np.concatenate([attitude_error(x_T[:4], nominal.target), x_T[4:7]])
        if rigid
        else np.zeros(6)
    )
    target = np.concatenate([start, -elastic[:n], -elastic[truth.n_modes : truth.n_modes + n]])

    lin = TrajectoryLinearization(design_plant, nominal, forces=tuple(forces))
    times = np.linspace(0.0, T, 2 * n_steps + 1)
    A, B = lin.jacobians(times)
    basis = np.sin(times[:, None] * (np.pi / T) * np.arange(1, n_basis + 1))  # (2K+1, n_b)
    # inputs of every basis function at once: U[k] (3 + n_F, (3 + n_F) n_b), input a's sines
    # in block a (the torque's per normalized torque, B's torque columns carrying J)
    m = lin.n_inputs
    U = np.einsum("kj,ab->kabj", basis, np.eye(m)).reshape(len(times), m, m * n_basis)
    X = np.zeros((lin.n_states, m * n_basis))
    for k in range(n_steps):  # RK4: the Jacobians at t_k, t_k + h/2, t_k + h
        i = 2 * k
        k1 = A[i] @ X + B[i] @ U[i]
        k2 = A[i + 1] @ (X + 0.5 * h * k1) + B[i + 1] @ U[i + 1]
        k3 = A[i + 1] @ (X + 0.5 * h * k2) + B[i + 1] @ U[i + 1]
        k4 = A[i + 2] @ (X + h * k3) + B[i + 2] @ U[i + 2]
        X = X + (h / 6.0) * (k1 + 2 * k2 + 2 * k3 + k4)
    return TerminalMap(X, target, np.asarray(lin.inertia, float), T, n_basis, lin.inputs[1:])


def modal_cancelling_torque(evaluation: SlewEvaluation, n_basis: int = 30) -> ShapedSlew:
    """The torquers-only correction of ``evaluation``'s nominal that brings its design modes to
    rest at T (module docstring): the minimum-norm solution of :func:`terminal_map`.

    Parameters
    ----------
    evaluation : SlewEvaluation
        Truth plant, design model, nominal and control grid.
    n_basis : int
        Sines per axis (n_b).
    """
    try:
        m = terminal_map(
            evaluation.truth,
            evaluation.design_plant,
            evaluation.nominal,
            evaluation.config,
            n_basis,
        )
    except FieldError as exc:
        if exc.field != "config":
            raise
        raise FieldError("evaluation.config", exc.rule) from None
    # minimum norm: repeated antenna pairs leave combinations the nominal does not excite and
    # the torque cannot reach (zero rows of the target), so X is rank deficient by design
    c = np.asarray(np.linalg.lstsq(m.X, m.target, rcond=None)[0], np.float64)
    residual = float(np.linalg.norm(m.X @ c - m.target) / np.linalg.norm(m.target))
    return ShapedSlew(evaluation.nominal, c.reshape(3, n_basis), m.inertia, residual)
