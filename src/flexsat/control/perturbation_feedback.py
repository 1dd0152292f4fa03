r"""Gain-scheduled frequency-shaped perturbation feedback about a rigid nominal slew, with
disturbance feedforward and force/torque decoupling (EPS slew study c. 1989,
Eqs. 22–37).

Design (:func:`perturbation_design`). The flexible design model (a few elastic modes) is
linearised at ``n_points`` equally spaced times :math:`t_i` of [0, T] along the nominal
(:class:`~flexsat.control.trajectory_linearization.TrajectoryLinearization`: δX = [δα, δω,
δη, δη̇], δu = [J⁻¹δτ, δF]). At each point the frequency-shaped LQR with cross weight
(:func:`~flexsat.control.frequency_shaped.frequency_shaped_lqr`, Eqs. 22–28: augmented state
[δX, δu₁, δu₂], control δu₃ = δü₁, weights Q on δX and D on δu₁, break frequency ω_B and
shaping damping ζ_B, 0 the paper's literal weight) gives

.. math::

    \delta u_3 = -K_i\,[\delta X; \delta u_1; \delta u_2] + K_{d,i}\, d \qquad
    \text{(Eqs. 26, 30)},

with :math:`K_{d,i}` the coefficient of the disturbance d (Eq. 29–30,
:attr:`~flexsat.control.frequency_shaped.FrequencyShapedDesign.disturbance_gain`) and
d(t) the modal accelerations the nominal torque causes (Eq. 31). With forces and
``decouple=True`` the inputs are δu_k = S v_k, S = blockdiag(I₃, Z), Z the moment-free force
combinations (:mod:`~flexsat.control.force_decoupling`, Eqs. 32–37 as corrected there),
and the design runs on (A, B S) with weight SᵀDS, in inputs scaled to unit weight
(S ← S L⁻ᵀ with SᵀDS = LLᵀ: the same optimal law, one scale for the Riccati solver).

Gain scheduling (F10): :math:`K(t)` is interpolated linearly between the :math:`t_i`
(:func:`~flexsat.control.scheduled.interpolate_schedule`) and held at :math:`K(T)` after T.
Feedforward (F11), three forms:

* ``"constant"`` (the paper's default, "Simulation Results"): the command :math:`K_{d,i}\,d(t_i)`
  evaluated at the linearisation times and interpolated;
* ``"time-varying"``: the gains :math:`K_d(t)` interpolated and d(t) recomputed every sample;
* ``"none"``.

The law (:class:`PerturbationFeedback`). Per control sample t_k it reads the attitude β, the
rate ω and the elastic state of the first n design modes (the plant output ``elastic``;
the first n modes of a larger plant built from the same modal model are the design model's
modes; less the nominal's planned [η, η̇] when it has ``elastic(t)``, a slew planned with its
modal motion, :mod:`flexsat.design.planned_slew`), forms δX (δα = 2 δq_v of
δq = β ⊗ β_n*, nonlinear in β), and with the shaping chain [δu₁, δu₂] of its internal
state computes δu₃ (held over the period, ZOH). The chain is then
propagated exactly, :math:`\delta u_1 \leftarrow \delta u_1 + h\,\delta u_2 + \tfrac{h^2}{2}
\delta u_3`, :math:`\delta u_2 \leftarrow \delta u_2 + h\,\delta u_3`. The plant receives,
held over [t_k, t_k + h), the interval means of the continuous commands:

.. math::

    \tau = \bar\tau_n + J\,\overline{\delta u}_{1,\tau}, \qquad
    F = \overline{\delta u}_{1,F}\ (Z\bar v_{1,F}\text{ decoupled}), \qquad
    \overline{\delta u}_1 = \delta u_1 + \tfrac h2\delta u_2 + \tfrac{h^2}{6}\delta u_3,

:math:`\bar\tau_n` the mean of the nominal torque over the interval by Simpson's rule (error
O(h⁵) per interval). A hold of the sampled value :math:`\tau_n(t_k)` would delay the torque by
h/2, an O(h) trajectory error; the mean gives each interval the nominal's exact impulse, so
the trajectory error of the hold is O(h²). (Measured, the nominal torque alone on the 45-mode
EPS, whose rotation is the rigid body's: peak attitude error during a 1 rad, 10 s slew
1.2e-6 rad at h = 0.01 s, 4.6e-6 at 0.02 s with the mean; 1.1e-3 and 2.2e-3 with the sampled
value.)
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from flexsat import limits
from flexsat.control.base import Controller
from flexsat.control.force_decoupling import decoupled_input_map
from flexsat.control.frequency_shaped import FrequencyShapedDesign, frequency_shaped_lqr
from flexsat.control.linear_form import sample_times
from flexsat.control.lqr import check_matrix, check_psd
from flexsat.control.scheduled import interpolate_schedule
from flexsat.control.trajectory_linearization import TrajectoryLinearization
from flexsat.dynamics.attitude import quaternion_multiply
from flexsat.input_checks import (
    FieldError,
    require_count,
    require_finite,
    require_nonneg,
    require_positive,
)

if TYPE_CHECKING:
    import numpy.typing as npt

    from flexsat.control.base import RigidNominal, TorqueNominal
    from flexsat.control.linear_form import LinearLaw
    from flexsat.dynamics.flexible_spacecraft import FlexibleSpacecraft
    from flexsat.units import FloatArray, QuantityArrayLike

__all__ = [
    "FEEDFORWARD",
    "NominalTorque",
    "PerturbationDesign",
    "interval_means",
    "planned_forces",
    "PerturbationFeedback",
    "perturbation_design",
]

#: the feedforward forms of EPS slew study c. 1989 and none
FEEDFORWARD = ("constant", "time-varying", "none")


def _weight(value: npt.ArrayLike, size: int, field: str, strict: bool) -> FloatArray:
    """A (size, size) symmetric PSD (PD when strict) weight; a 1-D array is its diagonal."""
    arr = require_finite(value, field)
    if arr.ndim == 1:
        if arr.size != size:
            raise FieldError(field, f"a diagonal must have {size} entries, got {arr.size}")
        arr = np.diag(arr)
    return check_psd(
        check_matrix(arr, field, size, size, f"({size}, {size}) or ({size},) for a diagonal"),
        field,
        strict=strict,
    )


@dataclass(frozen=True, eq=False)
class PerturbationDesign:
    """Frequency-shaped LQR designs at the linearisation times (:func:`perturbation_design`).

    Attributes
    ----------
    linearization : TrajectoryLinearization
        Design model, nominal and inputs.
    times : (n_p,) array
        Linearisation times t_i, s.
    A, B, d : arrays (n_p, N, N), (n_p, N, m), (n_p, N)
        Perturbation dynamics and disturbance at t_i (N = 6 + 2n; m = 3 + n_F physical
        inputs [J⁻¹δτ, δF]).
    input_map : (m, m_v) array
        S: δu = S v (identity, or blockdiag(I₃, Z) with ``decouple``), times L⁻ᵀ so that the
        design inputs v have unit weight.
    designs : tuple of FrequencyShapedDesign
        The design at each t_i, on (A_i, B_i S).
    gains : (n_p, m_v, N + 2 m_v) array
        K_i on [δX, v₁, v₂].
    disturbance_gains : (n_p, m_v, N) array
        K_d,i, the coefficient of d (Eq. 30).
    constant_feedforward : (n_p, m_v) array
        K_d,i d(t_i), the paper's "constant" feedforward at the t_i.
    Q, D : arrays
        Weights on δX and on the physical δu₁.
    omega_b, zeta_b : float
        Shaping break frequency (rad/s) and damping.
    decouple : bool
        Forces restricted to zero net moment.
    """

    linearization: TrajectoryLinearization
    times: FloatArray
    A: FloatArray
    B: FloatArray
    d: FloatArray
    input_map: FloatArray
    designs: tuple[FrequencyShapedDesign, ...]
    gains: FloatArray
    disturbance_gains: FloatArray
    constant_feedforward: FloatArray
    Q: FloatArray
    D: FloatArray
    omega_b: float
    zeta_b: float
    decouple: bool

    @property
    def n_modes(self) -> int:
        return self.linearization.n_modes

    def controller(
        self,
        dt: QuantityArrayLike,
        feedforward: str = "constant",
        n_modes_plant: int | None = None,
        plant: FlexibleSpacecraft | None = None,
    ) -> PerturbationFeedback:
        """The law at control period ``dt`` (:class:`PerturbationFeedback`)."""
        return PerturbationFeedback(self, dt, feedforward, n_modes_plant, plant)


def perturbation_design(
    plant: FlexibleSpacecraft,
    nominal: RigidNominal,
    Q: npt.ArrayLike,
    D: npt.ArrayLike,
    omega_b: QuantityArrayLike,
    zeta_b: float = 0.0,
    n_points: int = 11,
    forces: str | Sequence[str] = (),
    decouple: bool = False,
) -> PerturbationDesign:
    r"""Gain-scheduled frequency-shaped perturbation design (module docstring).

    Parameters
    ----------
    plant : FlexibleSpacecraft
        Reduced design model (e.g. 10 elastic modes), without translation.
    nominal : object
        Rigid nominal with ``beta(t)``, ``omega(t)``, ``torque(t)``, ``duration``
        (:mod:`~flexsat.control.trajectory_linearization`).
    Q : array_like (N, N) or (N,)
        Weight on δX = [δα, δω, δη, δη̇] (N = 6 + 2n), symmetric PSD; 1-D: its diagonal. The
        paper's Q = diag(1000 I₃ on ω, I₂₀ on the modes, 1000 I₃ on the angles) reads
        ``[1000]*3 + [1000]*3 + [1]*20`` in this order.
    D : array_like (m, m) or (m,)
        Weight on δu₁ = [J⁻¹δτ (rad/s²), δF (N)], symmetric PD (the paper: D = 50 I₃ on the
        normalized torques, case A).
    omega_b : float, str or Quantity
        Break frequency ω_B, rad/s (> 0).
    zeta_b : float
        Shaping damping ζ_B (≥ 0; 0 the paper's literal weight).
    n_points : int
        Number of equally spaced linearisation times over [0, T] (1: t = 0 only, a constant
        gain).
    forces : sequence of str or "all"
        Force channels of ``plant`` used besides the torquers (default none).
    decouple : bool
        Restrict the forces to zero net moment about the centre of mass (Eqs. 32–37).

    Raises
    ------
    ValueError
        Naming the field: bad Q or D (shape, symmetry, definiteness), ω_B ≤ 0, ζ_B < 0,
        n_points < 1, an unknown force channel, ``decouple`` without forces or with no
        moment-free force combination, a nominal without the attributes, with ζ_B = 0 inputs
        of which a combination moves no design state (more inputs than 3 + n: that
        combination's shaping chain would ring at ω_B with zero penalty), or a
        Riccati equation without a stabilising solution at a linearisation time (naming t_i).
    """
    lin = TrajectoryLinearization(plant, nominal, forces)
    N, m = lin.n_states, lin.n_inputs
    Qw = _weight(Q, N, "Q", strict=False)
    Dw = _weight(D, m, "D", strict=True)
    wb = float(require_positive(omega_b, "omega_b", "rad/s"))
    zb = float(require_nonneg(zeta_b, "zeta_b", ""))
    # the shaped weights hold D/ω_B⁴ and 4ζ_B² D/ω_B² beside Q: refuse them unrepresentable
    # here, by name, rather than as a failed Riccati solution at every linearisation point
    with np.errstate(over="ignore", under="ignore"):
        if not 0.0 < np.float64(wb) ** -4 < np.inf:
            raise FieldError(
                "omega_b",
                f"ω_B⁻⁴ = {np.float64(wb) ** -4:.3g} (the weight D/ω_B⁴ "
                f"of the shaped input) is not a representable float, got {wb:.3g}",
            )
        # at ω_B the torque-rate weight 4ζ_B²/ω_B² costs 4ζ_B² times the torque's own weight:
        # beyond the weight range the torque's weight is lost in its rounding
        if not 4.0 * np.float64(zb) ** 2 <= limits.MAX_WEIGHT_RANGE:
            raise FieldError(
                "zeta_b",
                f"the shaping weight 4ζ_B²/ω_B² weighs the torque at ω_B 4ζ_B² = "
                f"{4.0 * np.float64(zb) ** 2:.3g} times its own weight, above "
                f"{limits.MAX_WEIGHT_RANGE:.0e} (flexsat.limits.MAX_WEIGHT_RANGE), got "
                f"ζ_B = {zb:.3g}",
            )
    n_p = require_count(n_points, "n_points")
    if decouple:
        if m == 3:
            raise FieldError(
                "decouple",
                "needs force channels (forces=...); the torquers alone have nothing to decouple",
            )
        S = decoupled_input_map(lin.force_moments)
    else:
        S = np.eye(m)
    times = np.linspace(0.0, lin.duration, n_p)
    A, B = lin.jacobians(times)
    d = lin.disturbance(times)
    # Design in inputs of unit weight, w = Lᵀ v with Sᵀ D S = L Lᵀ (so S ← S L⁻ᵀ, D_w = I):
    # the optimal law is the same (an input change of variables), but the Riccati checks and
    # solver then see one scale. Forces weighted 1e-7 N⁻² beside normalized torques weighted
    # 50 (rad/s²)⁻² (EPS slew study c. 1989 case B) put 9 decades between the
    # chain states' weights, and the
    # detectability test judged the forces' shaping chains unseen (refused at t = 0.5 s).
    L = np.linalg.cholesky(S.T @ Dw @ S)
    S = np.asarray(np.linalg.solve(L, S.T).T, np.float64)
    Dv = np.eye(S.shape[1])
    if zb == 0.0:
        _check_inputs_act(B @ S, times, lin.inputs)
    designs = []
    for i, t in enumerate(times):
        try:
            designs.append(frequency_shaped_lqr(A[i], B[i] @ S, Qw, Dv, wb, 2, zb))
        except ValueError as exc:
            raise ValueError(f"linearisation point {i} (t = {t:.6g} s): {exc}") from None
    Kd = np.stack([x.disturbance_gain for x in designs])
    return PerturbationDesign(
        linearization=lin,
        times=times,
        A=A,
        B=B,
        d=d,
        input_map=S,
        designs=tuple(designs),
        gains=np.stack([x.gain for x in designs]),
        disturbance_gains=Kd,
        constant_feedforward=np.einsum("imn,in->im", Kd, d),
        Q=Qw,
        D=Dw,
        omega_b=wb,
        zeta_b=zb,
        decouple=bool(decouple),
    )


def _check_inputs_act(B: FloatArray, times: FloatArray, inputs: Sequence[str]) -> None:
    """With ζ_B = 0 every input combination must move the design model (B full column rank,
    at numpy's rank tolerance max(N, m) ε σ_max)."""
    for i, t in enumerate(times):
        s = np.linalg.svd(B[i], compute_uv=False)
        rank = int(np.sum(s > max(B[i].shape) * np.finfo(float).eps * s[0]))
        if rank < B[i].shape[1]:
            raise FieldError(
                "forces",
                f"at t = {t:.6g} s some combination of the inputs {', '.join(inputs)} "
                f"moves no state of the design model (B has rank {rank} < {B[i].shape[1]}). "
                f"With zeta_b = 0 the shaping weight vanishes at ω_B, so such a "
                f"combination would ring at ω_B unpenalised and unseen: the Riccati equation "
                f"has no stabilising solution. Use zeta_b > 0, fewer forces, more design modes "
                f"or decouple=True",
            )


def _check_same_modes(design_plant: FlexibleSpacecraft, plant: FlexibleSpacecraft) -> None:
    """The first modes of ``plant`` are the design model's (:class:`PerturbationFeedback`)."""
    n = design_plant.n_modes
    if getattr(plant, "n_modes", 0) < n or not hasattr(plant, "modal"):
        raise FieldError(
            "plant",
            f"must be a FlexibleSpacecraft with at least the design model's {n} elastic modes",
        )
    a, b = design_plant.modal, plant.modal
    for k in range(n):
        scale = np.abs(a.shapes[k]).max()
        if (
            abs(a.frequencies[k] - b.frequencies[k]) > 1e-9 * a.frequencies[k]
            or np.abs(a.shapes[k] - b.shapes[k]).max() > 1e-9 * scale
        ):
            raise FieldError(
                "plant",
                f"its elastic mode {k + 1} is not the design model's (frequency "
                f"{b.frequencies[k]:.6g} against {a.frequencies[k]:.6g} rad/s, or another "
                f"shape: a sign or a rotated repeated pair), so the law would read the wrong "
                f"coordinates; build the design model from the plant's modal model "
                f"(FlexibleSpacecraft(plant.modal, ..., n_modes={n}))",
            )


class PerturbationFeedback(Controller):
    r"""The gain-scheduled perturbation law of a :class:`PerturbationDesign` (module
    docstring).

    Reads ``attitude``, ``rate`` and ``elastic`` (the plant's [η, η̇], of which the first n
    design modes are used); writes ``torque`` (N m) and the design's force channels (N).
    Internal state ``z1``, ``z2``: the shaping chain [v₁, v₂] (n_cases, m_v), zero at start.
    The nominal, the error-quaternion maps, the interval-mean nominal torque and the
    feedforward are tabulated at construction on the sample grid k·dt through T (held after
    it), so a sample costs a few small array products.

    Parameters
    ----------
    design : PerturbationDesign
    dt : float, str or Quantity
        Control period, s: the law must be called at the times k·dt (the simulator's grid).
    feedforward : {"constant", "time-varying", "none"}
    n_modes_plant : int, optional
        Elastic modes of the simulated plant (its ``elastic`` channel is 2·n_modes_plant
        wide); default the design model's, or ``plant``'s.
    plant : FlexibleSpacecraft, optional
        The simulated plant: its mode count is taken and its first n modes are checked to be
        the design model's (frequencies and shapes to 1e-9 relative). Two eigen-solutions of
        one structure need not agree: a repeated pair (the EPS's 12-fold symmetric antenna)
        may come out rotated, a mode with the opposite sign, and the law would then read the
        wrong coordinates; build the design model from the plant's modal model
        (``FlexibleSpacecraft(plant.modal, ..., n_modes=n)``).
    """

    reads = ("attitude", "rate", "elastic")
    #: the design it was built from; None for a law rebuilt from its tables
    design: PerturbationDesign | None

    def __init__(
        self,
        design: PerturbationDesign,
        dt: QuantityArrayLike,
        feedforward: str = "constant",
        n_modes_plant: int | None = None,
        plant: FlexibleSpacecraft | None = None,
    ) -> None:
        if not isinstance(design, PerturbationDesign):
            raise FieldError("design", f"must be a PerturbationDesign, got {type(design).__name__}")
        if feedforward not in FEEDFORWARD:
            raise FieldError(
                "feedforward", f"must be one of {', '.join(FEEDFORWARD)}, got {feedforward!r}"
            )
        self.design, self.feedforward = design, feedforward
        self.dt = h = float(require_positive(dt, "dt", "s"))
        lin = design.linearization
        n = lin.n_modes
        if plant is not None:
            _check_same_modes(lin.plant, plant)
            n_modes_plant = plant.n_modes if n_modes_plant is None else n_modes_plant
        self.n_modes_plant = (
            n if n_modes_plant is None else require_count(n_modes_plant, "n_modes_plant")
        )
        if self.n_modes_plant < n:
            raise FieldError(
                "n_modes_plant",
                f"must be >= the design model's {n} modes, got {self.n_modes_plant}",
            )
        self.writes = lin.inputs
        self.knots, self.gains = design.times, design.gains
        # the sample grid through T and one beyond (held after it)
        grid = h * np.arange(int(np.ceil(lin.duration / h)) + 2, dtype=np.float64)
        beta_n, self._omega, _, _ = lin.nominal_at(grid)
        # δq = β ⊗ β_n* is linear in β: δq = β @ E_k with row j of E_k the product e_j ⊗ β_n*
        conj = beta_n * np.array([1.0, -1.0, -1.0, -1.0])
        self._error_maps = np.swapaxes(quaternion_multiply(np.eye(4)[:, None], conj), 0, 1)
        self._torque = interval_means(lambda t: lin.nominal_at(t)[2], grid, h)
        m_v = design.input_map.shape[1]
        if feedforward == "constant":
            self._ff = interpolate_schedule(self.knots, design.constant_feedforward, grid)
        elif feedforward == "time-varying":
            self._ff = np.einsum(
                "kmn,kn->km",
                interpolate_schedule(self.knots, design.disturbance_gains, grid),
                lin.disturbance(grid),
            )
        else:
            self._ff = np.zeros((grid.size, m_v))
        # a nominal that plans the modes' motion (flexsat.design.planned_slew) gives it as
        # elastic(t): the law feeds back the departures from it
        planned = getattr(lin.nominal, "elastic", None)
        self._elastic_ref = (
            np.asarray(planned(np.clip(grid, 0.0, lin.duration)), float)
            if callable(planned)
            else np.zeros((grid.size, 2 * n))
        )
        if self._elastic_ref.shape != (grid.size, 2 * n):
            raise FieldError(
                "nominal.elastic",
                f"must return [η, η̇] of the {n} design modes, shape (..., {2 * n}), got "
                f"{self._elastic_ref.shape[1:]}",
            )
        # a nominal that plans point forces (flexsat.design.planned_slew) has them added to
        # the law's commands on those channels, which the law must write
        planned_f, channels = planned_forces(lin.nominal, grid, h, lin.duration)
        self._force_ref = np.zeros((grid.size, len(self.writes) - 1))
        for i, name in enumerate(channels[1:]):
            if name not in self.writes[1:]:
                raise FieldError(
                    "forces",
                    f"the nominal plans {name}, which the law does not write (its forces: "
                    f"{', '.join(self.writes[1:]) or 'none'}): design it with that force",
                )
            self._force_ref[:, self.writes.index(name) - 1] = planned_f[:, i]
        self._inputs_T = design.input_map.T.copy()
        self._inertia_T = lin.inertia.T.copy()
        self.n_design_modes = n
        self.beta_target = self.target = beta_n[-1]

    #: the arrays a law is made of once tabulated (:meth:`tables`), by name
    TABLES = (
        "knots",
        "gains",
        "error_maps",
        "omega",
        "torque",
        "feedforward",
        "inputs_T",
        "inertia_T",
        "beta_target",
    )
    #: tables a stored law may lack (zero when absent: a nominal without planned modal motion
    #: or planned forces)
    OPTIONAL_TABLES = ("elastic_reference", "force_reference")

    def tables(self) -> dict[str, FloatArray]:
        """The law's tables on its sample grid (:data:`TABLES`): with the control period, the
        written channels and the mode counts they rebuild it (:meth:`from_tables`), so that a
        designed law can be stored as plain arrays (netCDF) and flown again without its
        nominal maneuver or its Riccati designs. ``elastic_reference`` (the planned [η, η̇]
        the law feeds back the departures from) only when the nominal plans modal motion."""
        tables = {
            "knots": self.knots,
            "gains": self.gains,
            "error_maps": self._error_maps,
            "omega": self._omega,
            "torque": self._torque,
            "feedforward": self._ff,
            "inputs_T": self._inputs_T,
            "inertia_T": self._inertia_T,
            "beta_target": np.asarray(self.beta_target),
        }
        if np.any(self._elastic_ref):  # a planned modal motion (OPTIONAL_TABLES)
            tables["elastic_reference"] = self._elastic_ref
        if np.any(self._force_ref):  # planned forces (OPTIONAL_TABLES)
            tables["force_reference"] = self._force_ref
        return tables

    @classmethod
    def from_tables(
        cls,
        tables: Mapping[str, npt.ArrayLike],
        dt: float,
        writes: Sequence[str],
        n_design_modes: int,
        n_modes_plant: int,
        feedforward: str = "constant",
    ) -> PerturbationFeedback:
        """The law of :meth:`tables` (the same commands, bit for bit); ``design`` is then
        None.

        Raises
        ------
        ValueError
            For a missing table or tables whose sizes disagree.
        """
        missing = [name for name in cls.TABLES if name not in tables]
        if missing:
            raise FieldError("tables", f"missing {', '.join(missing)}")
        t = {name: np.array(tables[name], dtype=float) for name in cls.TABLES}
        m_v = t["inputs_T"].shape[0]
        width = 6 + 2 * require_count(n_design_modes, "n_design_modes") + 2 * m_v
        if t["gains"].shape[1:] != (m_v, width) or t["gains"].shape[0] != t["knots"].size:
            raise FieldError(
                "tables",
                f"gains of shape {t['gains'].shape} do not match {t['knots'].size} knots, "
                f"{m_v} design inputs and {n_design_modes} design modes",
            )
        law = cls.__new__(cls)
        law.design, law.feedforward = None, feedforward
        law.dt = float(require_positive(dt, "dt", "s"))
        law.n_modes_plant = require_count(n_modes_plant, "n_modes_plant")
        law.n_design_modes = n_design_modes
        law.writes = tuple(writes)
        law.knots, law.gains = t["knots"], t["gains"]
        law._error_maps, law._omega, law._torque = t["error_maps"], t["omega"], t["torque"]
        law._ff, law._inputs_T, law._inertia_T = t["feedforward"], t["inputs_T"], t["inertia_T"]
        law.beta_target = law.target = t["beta_target"]
        reference = tables.get("elastic_reference")
        law._elastic_ref = (
            np.zeros((t["torque"].shape[0], 2 * n_design_modes))
            if reference is None
            else np.array(reference, dtype=float)
        )
        if law._elastic_ref.shape != (t["torque"].shape[0], 2 * n_design_modes):
            raise FieldError(
                "tables",
                f"elastic_reference of shape {law._elastic_ref.shape} does not match the "
                f"{t['torque'].shape[0]} samples and {n_design_modes} design modes",
            )
        forces = tables.get("force_reference")
        law._force_ref = (
            np.zeros((t["torque"].shape[0], len(law.writes) - 1))
            if forces is None
            else np.array(forces, dtype=float)
        )
        if law._force_ref.shape != (t["torque"].shape[0], len(law.writes) - 1):
            raise FieldError(
                "tables",
                f"force_reference of shape {law._force_ref.shape} does not match the "
                f"{t['torque'].shape[0]} samples and {len(law.writes) - 1} forces written",
            )
        return law

    def _batched(self) -> list[tuple[int, ...]]:
        return [()]

    def initial_state(self, n_cases: int) -> dict[str, FloatArray]:
        m_v = self._inputs_T.shape[0]
        return {"z1": np.zeros((n_cases, m_v)), "z2": np.zeros((n_cases, m_v))}

    def __call__(
        self, t: float, y: Mapping[str, FloatArray], state: dict[str, FloatArray]
    ) -> tuple[dict[str, FloatArray], dict[str, FloatArray]]:
        h = self.dt
        k = int(round(t / h))
        if k < 0 or abs(t - k * h) > 1e-6 * h:
            raise FieldError(
                "t",
                f"{type(self).__name__} runs on its sample grid k·dt with dt = "
                f"{h:g} s (the simulator's control period); called at t = {t!r}",
            )
        j = min(k, len(self._torque) - 1)
        n, n_p = self.n_design_modes, self.n_modes_plant
        elastic = np.asarray(y["elastic"], float)
        if elastic.shape[-1] != 2 * n_p:
            raise FieldError(
                "elastic",
                f"expected 2·n_modes_plant = {2 * n_p} columns, got "
                f"{elastic.shape[-1]} (set n_modes_plant to the plant's modes)",
            )
        dq = np.asarray(y["attitude"], float) @ self._error_maps[j]
        z1, z2 = state["z1"], state["z2"]
        X = np.concatenate(
            [
                np.where(dq[:, :1] < 0, -2.0, 2.0) * dq[:, 1:],
                np.asarray(y["rate"], float) - self._omega[j],
                elastic[:, :n] - self._elastic_ref[j, :n],
                elastic[:, n_p : n_p + n] - self._elastic_ref[j, n:],
                z1,
                z2,
            ],
            axis=1,
        )
        u3 = self._ff[j] - X @ interpolate_schedule(self.knots, self.gains, t).T
        du = (z1 + (0.5 * h) * z2 + (h * h / 6) * u3) @ self._inputs_T
        commands = {"torque": self._torque[j] + du[:, :3] @ self._inertia_T}
        for i, name in enumerate(self.writes[1:]):
            commands[name] = du[:, 3 + i] + self._force_ref[j, i]
        return commands, {"z1": z1 + h * z2 + (0.5 * h * h) * u3, "z2": z2 + h * u3}

    def linear_form(self, dt: float, times: npt.ArrayLike, n_cases: int) -> LinearLaw:
        r"""The law as the compiled loop's linear form (:mod:`~flexsat.control.linear_form`),
        y = [β, ω, η, η̇] (the channels ``attitude``, ``rate``, ``elastic``), ξ = [v₁, v₂].

        With j = min(k, last tabulated sample), :math:`\delta X_k = M_k e_k`,
        e = y − [0, ω_n,j, η_p,j, η̇_p,j] (η_p, η̇_p the planned modal motion of a nominal
        with ``elastic(t)``, zero otherwise) and M_k the rows 2 E_j[:, 1:]ᵀ on β
        (δα = 2 δq_v, δq = β E_j: linear in β), I on ω and on the first n modal amplitudes
        and rates, and G_k = [G_x, G_1, G_2] the interpolated gain, the law of :meth:`__call__` is

        .. math::

            v_3 &= f_j - G_x M_k e_k - G_1 v_1 - G_2 v_2, \\
            \xi_{k+1} &= \begin{bmatrix} I - \tfrac{h^2}2 G_1 & hI - \tfrac{h^2}2 G_2 \\
                -h G_1 & I - h G_2 \end{bmatrix}\xi_k
                - \begin{bmatrix}\tfrac{h^2}2 \\ h\end{bmatrix} G_x M_k e_k
                + \begin{bmatrix}\tfrac{h^2}2 \\ h\end{bmatrix} f_j, \\
            u_k &= [\bar\tau_{n,j}; \bar F_{n,j}] + P S \big[(I - \tfrac{h^2}6 G_1) v_1
                + (\tfrac h2 I - \tfrac{h^2}6 G_2) v_2 - \tfrac{h^2}6 G_x M_k e_k
                + \tfrac{h^2}6 f_j\big],

        P = blockdiag(J, I) (the torque is J δu_τ), S the input map, :math:`\bar F_{n,j}`
        the planned forces of a nominal that plans them (zero otherwise); the feedforward's affine
        term is shifted into u_ff (:func:`~flexsat.control.linear_form.absorb_affine`). Equal
        to :meth:`__call__` to round-off while the error quaternion's scalar part
        δq₀ = (β E_j)₀ is >= 0 (an attitude error from the nominal below π, which the law's
        sign choice otherwise folds back): a caller flying cases that far off the nominal
        checks δq₀ (:meth:`hemisphere`) and reruns them on the law itself.

        Raises
        ------
        ValueError
            ``dt``: another control period than the law's (it is tabulated on its grid).
        """
        from flexsat.control.linear_form import LinearLaw, absorb_affine

        dt, grid = sample_times(dt, times)
        h = self.dt
        if abs(dt - h) > 1e-9 * h:
            raise FieldError("dt", f"the law is tabulated at dt = {h:g} s, the run has {dt:g} s")
        n, n_p = self.n_design_modes, self.n_modes_plant
        S = self._inputs_T.T  # (m, m_v)
        m, m_v = S.shape
        nx = 6 + 2 * n
        p = 7 + 2 * n_p
        j = np.minimum(np.rint(grid / h).astype(int), len(self._torque) - 1)
        G = interpolate_schedule(self.knots, self.gains, grid)  # (n_t, m_v, nx + 2 m_v)
        Gx, G1, G2 = G[..., :nx], G[..., nx : nx + m_v], G[..., nx + m_v :]
        M = np.zeros((grid.size, nx, p))
        M[:, :3, :4] = 2.0 * np.swapaxes(self._error_maps[j][:, :, 1:], 1, 2)
        M[:, 3:6, 4:7] = np.eye(3)
        M[:, 6 : 6 + n, 7 : 7 + n] = np.eye(n)
        M[:, 6 + n :, 7 + n_p : 7 + n_p + n] = np.eye(n)
        GM = Gx @ M  # (n_t, m_v, p)
        eye = np.eye(m_v)
        A = np.block(
            [
                [eye - 0.5 * h * h * G1, h * eye - 0.5 * h * h * G2],
                [-h * G1, eye - h * G2],
            ]
        )
        B = np.concatenate([-0.5 * h * h * GM, -h * GM], axis=1)
        P = np.eye(m)
        P[:3, :3] = self._inertia_T.T
        PS = P @ S
        C = PS @ np.concatenate([eye - (h * h / 6) * G1, 0.5 * h * eye - (h * h / 6) * G2], -1)
        D = -(h * h / 6) * (PS @ GM)
        ff = self._ff[j]  # (n_t, m_v)
        g = np.zeros((grid.size, m))
        g[:, :3] = self._torque[j]
        g[:, 3:] = self._force_ref[j]  # planned forces, zero without
        g += (h * h / 6) * ff @ PS.T
        F = np.concatenate([0.5 * h * h * eye, h * eye])
        A4, C4 = A[:, None], C[:, None]
        u_ff = absorb_affine(A4, C4, g[:, None], F, ff[:, None])
        y_ref = np.zeros((grid.size, 1, p))
        y_ref[:, 0, 4:7] = self._omega[j]
        # a planned modal motion: the departures from it are fed back (as in __call__)
        y_ref[:, 0, 7 : 7 + n] = self._elastic_ref[j, :n]
        y_ref[:, 0, 7 + n_p : 7 + n_p + n] = self._elastic_ref[j, n:]
        return LinearLaw(
            A4,
            B[:, None],
            C4,
            D[:, None],
            y_ref,
            u_ff,
            None,
            ("attitude", "rate", "elastic"),
            tuple(self.writes),
            (4, 3, 2 * n_p),
            (3,) + (1,) * (m - 3),
        )

    def hemisphere(self, times: npt.ArrayLike, attitude: npt.ArrayLike) -> FloatArray:
        """δq₀ = (β E_j)₀, the scalar part of the error quaternion from the nominal, at the
        sample ``times`` (n_t,) for the attitudes (..., n_t, 4): where it is negative the law
        takes the other sign of δq (:meth:`linear_form`)."""
        grid = np.asarray(times, float)
        j = np.minimum(np.rint(grid / self.dt).astype(int), len(self._torque) - 1)
        first = self._error_maps[j][:, :, 0]
        return np.einsum("...ki,ki->...k", np.asarray(attitude, float), first)


def interval_means(
    signal: Callable[[FloatArray], FloatArray], grid: FloatArray, h: float
) -> FloatArray:
    """Means of ``signal(t)`` over [t_k, t_k + h) for the grid times t_k, by Simpson's rule
    (error O(h⁵) per interval for a smooth signal): the value a zero-order hold must carry for
    the held signal to have the exact impulse of each interval (module docstring)."""
    values = [signal(grid + s * h) for s in (0.0, 0.5, 1.0)]
    return (values[0] + 4 * values[1] + values[2]) / 6


class NominalTorque(Controller):
    """Open loop: the nominal torque alone, held per control period at its interval mean as
    :class:`PerturbationFeedback` holds it (the open-loop run the EPS
    slew study c. 1989 goals compare
    with). Zero after the maneuver.

    A nominal that plans point forces too (:class:`~flexsat.design.slew_shaping.ShapedSlew`
    with ``force_channels``: ``forces(t)`` (..., n_F), N) has them written on those channels,
    held the same way.

    Parameters
    ----------
    nominal : object
        ``torque(t)`` (N m, body axes) on [0, ``duration``]; optionally ``force_channels`` and
        ``forces(t)``.
    dt : float, str or Quantity
        Control period, s; the law is called on the grid k·dt.
    """

    reads = ("attitude",)
    writes: tuple[str, ...] = ("torque",)

    def __init__(self, nominal: TorqueNominal, dt: QuantityArrayLike) -> None:
        missing = [a for a in ("torque", "duration") if not hasattr(nominal, a)]
        if missing:
            raise FieldError(
                "nominal",
                "must have torque(t) and duration; "
                f"{type(nominal).__name__} lacks {', '.join(missing)}",
            )
        T = float(require_positive(nominal.duration, "nominal.duration", "s"))
        self.dt = h = float(require_positive(dt, "dt", "s"))
        grid = h * np.arange(int(np.ceil(T / h)) + 2, dtype=np.float64)

        def torque(t: FloatArray) -> FloatArray:
            return np.where((t > T)[..., None], 0.0, nominal.torque(np.clip(t, 0.0, T)))

        self._torque = interval_means(torque, grid, h)
        self._forces, self.writes = planned_forces(nominal, grid, h, T)
        self.target = np.zeros(1)

    def _batched(self) -> list[tuple[int, ...]]:
        return [()]

    def __call__(
        self, t: float, y: Mapping[str, FloatArray], state: dict[str, FloatArray]
    ) -> tuple[FloatArray | dict[str, FloatArray], dict[str, FloatArray]]:
        k = min(int(round(t / self.dt)), len(self._torque) - 1)
        n = np.shape(y["attitude"])[0]
        torque = np.broadcast_to(self._torque[k], (n, 3)).copy()
        if len(self.writes) == 1:
            return torque, state
        commands = {"torque": torque}
        for i, name in enumerate(self.writes[1:]):
            commands[name] = np.full(n, self._forces[k, i])
        return commands, state


def planned_forces(
    nominal: object, grid: FloatArray, h: float, T: float
) -> tuple[FloatArray, tuple[str, ...]]:
    """The interval means (:func:`interval_means`) of a nominal's planned point forces on the
    sample ``grid`` (zero after T) and the channels written: ``("torque",)`` and its
    ``force_channels``; (len(grid), 0) and ``("torque",)`` for a nominal without forces."""
    channels = tuple(getattr(nominal, "force_channels", ()) or ())
    if not channels:
        return np.zeros((grid.size, 0)), ("torque",)
    forces = getattr(nominal, "forces", None)
    if not callable(forces):
        raise FieldError("nominal", "has force_channels but no forces(t)")

    def held(t: FloatArray) -> FloatArray:
        f = np.asarray(forces(np.clip(t, 0.0, T)), float)
        if f.shape != t.shape + (len(channels),):
            raise FieldError(
                "nominal.forces",
                f"must return shape (..., {len(channels)}) for its force_channels, got {f.shape}",
            )
        return np.where((t > T)[..., None], 0.0, f)

    return interval_means(held, grid, h), ("torque",) + channels
