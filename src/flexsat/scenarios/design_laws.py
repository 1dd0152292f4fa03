r"""The law-design stage of a design study (``kind: design_study``, ``laws:``): each law is
designed from the results upstream -- the rigid inertia and the modes of the modes stage, the
actuators the placement stage chose -- on the flexible spacecraft they make, and reduced to
arrays (gains, filter frequencies, closed-loop poles) that the stage cache stores and a run
turns back into a :class:`flexsat.control.Controller`.

Design plant: :class:`~flexsat.dynamics.flexible_spacecraft.FlexibleSpacecraft` in hybrid
coordinates, state :math:`x = [\beta, \omega, \eta, \dot\eta]`, inputs [torque, the placed point
forces], linearised about rest (``linear_part``). :math:`\beta_0` is dropped from the linear
design state: it is constant to first order (:math:`\dot\beta_0 = -\tfrac12 \beta_v^T\omega`),
an uncontrollable pole at 0 that no law moves, so the design state is
:math:`[\beta_v, \omega, \eta, \dot\eta]`.

Laws
----
``pd``
    Quaternion PD on the rigid body, :math:`u = -K_p \delta\beta_v - K_d \omega`
    (:class:`~flexsat.control.QuaternionPD`). Linearised, :math:`\beta_v = \theta / 2`, each axis
    is :math:`J_{ii}\ddot\theta + K_d\dot\theta + \tfrac12 K_p\theta = 0`, so the bandwidth
    :math:`\omega_c` and damping ratio :math:`\zeta` give :math:`K_p = 2 J_{ii}\omega_c^2`,
    :math:`K_d = 2\zeta\omega_c J_{ii}` (Wie, *Space Vehicle Dynamics and Control*, 2nd ed.,
    AIAA 2008, §7.3.1, with the quaternion error's factor ½).
``lqr``
    Constant-gain LQR, :math:`u = -Kx`, :math:`K = R^{-1}B^T S` with S the stabilising
    solution of :math:`A^T S + S A - S B R^{-1} B^T S + Q = 0` (Kwakernaak & Sivan, *Linear
    Optimal Control Systems*, 1972, §3.4) on the design model's first ``modes`` elastic modes,
    Q and R diagonal over :math:`[\beta_v, \omega, \eta, \dot\eta]` and [torque, forces]
    (:class:`~flexsat.design.slew_weights.SlewWeights` blocks). Full-state feedback of the
    modal coordinates of the design modes, as the slew kind's perturbation feedback.
``ppf``
    Positive position feedback (Agrawal & Bang 1996, :mod:`flexsat.control.ppf`) on the placed
    forces, each with a collocated displacement sensor, filters tuned to the first
    ``tuned_modes`` elastic modes; optionally with a quaternion PD on the torquers holding the
    attitude (``attitude:``). A design whose loop is unstable on the elastic modes (Eq. 6: S
    not positive definite) is refused.
``perturbation``
    The slew kind's method (:mod:`flexsat.scenarios.slew`, the EPS slew study c. 1989 after
    Chun, Turner & Juang 1987): the rigid-body optimal nominal ``maneuver``
    (:func:`~flexsat.maneuvers.three_axis_slew.three_axis_slew`), then frequency-shaped LQR
    perturbation feedback on the first ``modes`` modes at ``linearization_points`` times,
    gains interpolated in time (:func:`~flexsat.control.perturbation_design`), on the
    torquers and every placed force; the ``torque`` weight is on J⁻¹δτ as in the paper. The
    law is stored as its tables on the control grid
    (:meth:`~flexsat.control.PerturbationFeedback.tables`), so its fingerprint holds the
    control rate.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Annotated, Any, Literal, Self

import numpy as np
from pydantic import ConfigDict, Field, model_validator

from flexsat.input_checks import FieldError
from flexsat.scenarios.fields import SchemaSection, in_unit, integer_in
from flexsat.scenarios.slew import SlewManeuverSpec

if TYPE_CHECKING:
    from flexsat.control.base import Controller
    from flexsat.dynamics.flexible_spacecraft import FlexibleSpacecraft
    from flexsat.dynamics.plant import Channel

#: one weight, or one per component of its block
Weights = float | list[float]
#: a design's arrays by name (gains, filter frequencies, closed-loop poles)
Arrays = dict[str, Any]


class StudySection(SchemaSection):
    """Base of a design study's sections: unknown keys, NaN and infinities are refused (a
    stage's fingerprint is the JSON of its section)."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)


class AttitudeHoldSpec(StudySection):
    """A quaternion PD on the torquers: closed-loop bandwidth and damping ratio per axis."""

    bandwidth: Annotated[float, in_unit("rad/s", positive=True)]
    damping: float = Field(0.7, gt=0.0)


class LQRWeightsSpec(StudySection):
    """Diagonal LQR weights over [β_v, ω, η, η̇] and [torque, forces]; one value fills its
    block. SI numbers (rad⁻², N⁻² m⁻², ...)."""

    attitude: Weights
    rate: Weights
    modes: Weights
    mode_rates: Weights | None = None
    torque: Weights
    force: Weights | None = None


#: the fields of each law type, required ones first (module docstring)
LAW_FIELDS = {
    "pd": (("bandwidth",), ("damping",)),
    "lqr": (("weights",), ("modes",)),
    "ppf": (("gains",), ("tuned_modes", "filter_damping", "attitude")),
    "perturbation": (
        ("maneuver", "weights", "break_frequency"),
        ("modes", "linearization_points", "shaping_damping", "feedforward"),
    ),
}


class LawSpec(StudySection):
    """One law: its ``label``, its ``type`` and the fields of that type (module docstring).

    pd: ``bandwidth`` (rad/s), ``damping`` (0.7). lqr: ``weights``, ``modes`` (every kept mode).
    ppf: ``gains`` (N/m, one or one per filter), ``tuned_modes`` (1), ``filter_damping`` (0.3),
    ``attitude`` (a PD on the torquers: ``bandwidth``, ``damping``). perturbation: ``maneuver``
    (the slew kind's), ``weights``, ``break_frequency`` (rad/s), ``modes``,
    ``linearization_points`` (11), ``shaping_damping`` (0), ``feedforward`` (constant).
    """

    label: str
    type: Literal["pd", "lqr", "ppf", "perturbation"]
    bandwidth: Annotated[float | None, in_unit("rad/s", positive=True)] = None
    damping: float = Field(0.7, gt=0.0)
    weights: LQRWeightsSpec | None = None
    modes: Annotated[int | None, integer_in(1, 500, optional=True)] = None
    gains: Weights | None = None
    tuned_modes: Annotated[int, integer_in(1, 500)] = 1
    filter_damping: float = Field(0.3, gt=0.0)
    attitude: AttitudeHoldSpec | None = None
    maneuver: SlewManeuverSpec | None = None
    break_frequency: Annotated[float | None, in_unit("rad/s", positive=True)] = None
    shaping_damping: float = Field(0.0, ge=0.0)
    linearization_points: Annotated[int, integer_in(1, 1000)] = 11
    feedforward: Literal["none", "constant", "time-varying"] = "constant"

    @model_validator(mode="after")
    def _fields_of_its_type(self) -> Self:
        required, optional = LAW_FIELDS[self.type]
        own = set(required) | set(optional) | {"label", "type"}
        for name in sorted(self.model_fields_set - own):
            raise FieldError(
                name,
                f"not a field of a {self.type} law (its fields: {', '.join(required + optional)})",
            )
        for name in required:
            if getattr(self, name) is None:
                raise FieldError(name, f"required by a {self.type} law")
        return self


def design_state(plant: FlexibleSpacecraft) -> tuple[np.ndarray, np.ndarray]:
    """(A, B) of ``plant``'s linear part on the design state [β_v, ω, η, η̇] (β₀ dropped)."""
    A, B = plant.linear_part()
    return A[1:, 1:], B[1:]


def pd_gains(
    plant: FlexibleSpacecraft, bandwidth: float, damping: float
) -> tuple[np.ndarray, np.ndarray]:
    """(K_p, K_d) per body axis from the bandwidth (rad/s) and damping (module docstring)."""
    J = np.diag(plant.inertia)
    return 2.0 * J * bandwidth**2, 2.0 * damping * bandwidth * J


def _pd_matrix(plant: FlexibleSpacecraft, kp: np.ndarray, kd: np.ndarray) -> np.ndarray:
    """The PD law as u = −K x on the design state (torque rows, force rows zero)."""
    K = np.zeros((3 + len(plant.forces), plant.nx - 1))
    K[:3, 0:3] = np.diag(kp)
    K[:3, 3:6] = np.diag(kd)
    return K


def _poles(A: np.ndarray, B: np.ndarray, K: np.ndarray) -> np.ndarray:
    poles = np.linalg.eigvals(A - B @ K)
    return poles[np.lexsort((poles.imag, poles.real))]


def design_law(
    spec: Any, plant: FlexibleSpacecraft, dt: float
) -> tuple[dict[str, Any], dict[str, Any]]:
    """The arrays and the JSON-ready facts of the law ``spec`` designed on ``plant`` (a
    perturbation law is tabulated at the control period ``dt``, s).

    Raises
    ------
    ValueError
        Naming the field of the law's section (``weights.torque: ...``, ``gains: ...``).
    """
    if spec.type == "pd":
        assert spec.bandwidth is not None  # required of a pd law
        kp, kd = pd_gains(plant, spec.bandwidth, spec.damping)
        A, B = design_state(plant)
        return {"Kp": kp, "Kd": kd, "poles": _poles(A, B, _pd_matrix(plant, kp, kd))}, {}
    if spec.type == "lqr":
        return _design_lqr(spec, plant)
    if spec.type == "perturbation":
        return _design_perturbation(spec, plant, dt)
    return _design_ppf(spec, plant)


def _design_lqr(spec: LawSpec, plant: FlexibleSpacecraft) -> tuple[Arrays, dict[str, Any]]:
    from flexsat.control import lqr
    from flexsat.design.slew_weights import SlewWeights

    n = plant.n_modes if spec.modes is None else spec.modes
    if n > plant.n_modes:
        raise FieldError("modes", f"at most the {plant.n_modes} elastic modes kept, got {n}")
    design = plant.reduced(n)
    assert spec.weights is not None  # required of an lqr law
    try:
        q, d = SlewWeights(**spec.weights.model_dump()).diagonals(n, len(plant.forces))
    except FieldError as exc:  # named by its block: a field of ``weights``
        raise FieldError(f"weights.{exc.field}", exc.rule) from None
    A, B = design_state(design)
    K, _, poles = lqr(A, B, np.diag(q), np.diag(d))
    return {"K": K, "poles": poles[np.lexsort((poles.imag, poles.real))]}, {"design_modes": n}


def _design_perturbation(
    spec: LawSpec, plant: FlexibleSpacecraft, dt: float
) -> tuple[Arrays, dict[str, Any]]:
    """The slew kind's design (:mod:`flexsat.scenarios.slew`) on the placed forces: the
    rigid-body optimal nominal maneuver, then the frequency-shaped perturbation feedback of the
    first ``modes`` modes at ``linearization_points`` times, tabulated at ``dt``."""
    from flexsat.control import perturbation_design
    from flexsat.design.slew_weights import SlewWeights
    from flexsat.maneuvers import three_axis_slew
    from flexsat.scenarios.simulation import target_quaternion

    assert spec.maneuver is not None and spec.weights is not None  # required of the type
    assert spec.break_frequency is not None
    m = spec.maneuver
    n = plant.n_modes if spec.modes is None else spec.modes
    if n > plant.n_modes:
        raise FieldError("modes", f"at most the {plant.n_modes} elastic modes kept, got {n}")
    target = target_quaternion(m.target)
    assert target is not None  # the maneuver's schema refuses an empty target
    try:
        nominal = three_axis_slew(
            plant.inertia,
            target,
            m.duration,
            m.break_frequency,
            m.shaping_damping,
            Q=m.rate_weight * np.eye(3),
        )
    except FieldError as exc:
        raise FieldError(f"maneuver.{exc.field}", exc.rule) from None
    forces = [c.name for c in plant.inputs if c.name != "torque"]
    try:
        q, d = SlewWeights(**spec.weights.model_dump()).diagonals(n, len(forces))
    except FieldError as exc:
        raise FieldError(f"weights.{exc.field}", exc.rule) from None
    design = perturbation_design(
        plant.reduced(n),
        nominal,
        np.diag(q),
        np.diag(d),
        spec.break_frequency,
        spec.shaping_damping,
        spec.linearization_points,
        forces=forces,
    )
    law = design.controller(dt, spec.feedforward, plant=plant)
    arrays: Arrays = dict(law.tables())
    # the frozen-time closed-loop poles of each linearisation point's design
    arrays["poles"] = np.stack([fs.poles for fs in design.designs])
    info = {
        "design_modes": n,
        "continuation_steps": len(nominal.history),
        "boundary_error": float(nominal.boundary_error()),
        "peak_nominal_torque_N_m": float(np.abs(nominal.torque(law.knots)).max()),
    }
    return arrays, info


def _ppf_model(spec: LawSpec, plant: FlexibleSpacecraft) -> Any:
    from flexsat.control.ppf import PPFModel

    if not plant.forces:
        raise FieldError("type", "PPF needs placed force actuators (placement.number >= 1)")
    modal = plant.modal
    actuators = np.column_stack([modal.force_input(n, a) for n, a in plant.forces])
    sensors = np.vstack([modal.displacement_output(n, a) for n, a in plant.forces])
    return PPFModel(modal.frequencies, modal.damping, actuators, sensors)


def _design_ppf(spec: LawSpec, plant: FlexibleSpacecraft) -> tuple[Arrays, dict[str, Any]]:
    from flexsat.control.ppf import PPFBank, PPFProblem

    model = _ppf_model(spec, plant)
    if spec.tuned_modes > model.n_modes:
        raise FieldError(
            "tuned_modes", f"at most the {model.n_modes} elastic modes kept, got {spec.tuned_modes}"
        )
    bank = PPFBank.tuned(model, spec.filter_damping, spec.tuned_modes)
    assert spec.gains is not None  # required of a ppf law
    gains = np.atleast_1d(np.asarray(spec.gains, float))
    if gains.size == 1:
        gains = np.full(bank.n_filters, float(gains[0]))
    gains = bank.check_gains(gains)
    m = model.n_modes
    problem = PPFProblem(model, bank, np.eye(2 * m), 0.0, np.eye(2 * m))
    stability = problem.stability(gains)
    if not stability.stable:
        raise FieldError(
            "gains",
            f"the PPF loop is unstable on the {m} elastic modes (Agrawal & Bang 1996 Eq. 6: "
            f"smallest eigenvalue of S {stability.stiffness_eigenvalues[0]:.4g} rad²/s², "
            f"largest closed-loop real part {stability.max_real_pole:.4g} 1/s); lower the gains",
        )
    arrays: dict[str, Any] = {
        "omega_f": bank.omega_f,
        "zeta_f": bank.zeta_f,
        "gains": gains,
        "stiffness_eigenvalues": stability.stiffness_eigenvalues,
        "poles": problem.closed_loop_poles(gains),
    }
    if spec.attitude is not None:
        arrays["Kp"], arrays["Kd"] = pd_gains(plant, spec.attitude.bandwidth, spec.attitude.damping)
    return arrays, {"stability_decided_by": stability.decided_by}


def law_controller(
    spec: Any, arrays: dict[str, np.ndarray], plant: FlexibleSpacecraft, dt: float
) -> Controller:
    """The sampled law of a design (``arrays`` of :func:`design_law`) on the run's ``plant``
    (the spacecraft of every kept mode), at control period ``dt``."""
    from flexsat.control import QuaternionPD, ScheduledStateFeedback

    outputs = {c.name: c for c in plant.outputs}
    inputs = list(plant.inputs)
    if spec.type == "pd":
        return QuaternionPD(Kp=arrays["Kp"], Kd=arrays["Kd"])
    if spec.type == "perturbation":
        from flexsat.control import PerturbationFeedback

        m_v, width = arrays["gains"].shape[1:]
        return PerturbationFeedback.from_tables(
            arrays,
            dt,
            [c.name for c in inputs],
            (width - 6 - 2 * m_v) // 2,
            plant.n_modes,
            spec.feedforward,
        )
    if spec.type == "lqr":
        K = arrays["K"]
        n_design, n = (K.shape[1] - 6) // 2, plant.n_modes
        full = np.zeros((K.shape[0], 7 + 2 * n))
        full[:, 1:7] = K[:, :6]  # β₀ (column 0) carries no gain
        full[:, 7 : 7 + n_design] = K[:, 6 : 6 + n_design]
        full[:, 7 + n : 7 + n + n_design] = K[:, 6 + n_design :]
        reads = [outputs["attitude"], outputs["rate"], outputs["elastic"]]
        return ScheduledStateFeedback([0.0], full[None], reads, inputs)
    return _ppf_controller(arrays, plant, outputs, dt)


def _ppf_controller(
    arrays: Arrays, plant: FlexibleSpacecraft, outputs: dict[str, Channel], dt: float
) -> Controller:
    import control as ct
    from flexsat.control import StateSpaceCompensator
    from flexsat.control.ppf import PPFBank, ppf_compensator

    bank = PPFBank(arrays["omega_f"], arrays["zeta_f"])
    system = ppf_compensator(bank, arrays["gains"])
    names = [f"{node}{axis.upper()}" for node, axis in plant.forces]
    reads = [outputs[f"displacement_{name}"] for name in names]
    writes = [c for c in plant.inputs if c.name != "torque"]
    if "Kp" in arrays:
        # the attitude hold: u_torque = −K_p β_v − K_d ω, a feedthrough beside the filters
        pd = np.hstack([np.zeros((3, 1)), -np.diag(arrays["Kp"]), -np.diag(arrays["Kd"])])
        system = ct.append(system, ct.ss([], [], [], pd))
        reads += [outputs["attitude"], outputs["rate"]]
        writes += [c for c in plant.inputs if c.name == "torque"]
    return StateSpaceCompensator(system, reads, writes, dt=dt)


def law_summary(spec: Any, arrays: dict[str, np.ndarray], info: dict[str, Any]) -> dict[str, Any]:
    """The key numbers of a design for the report: gains and the closed-loop poles' slowest
    decay and least damping."""
    poles = np.ravel(arrays["poles"])
    moving = poles[np.abs(poles) > 1e-9]
    damping = -moving.real / np.abs(moving)
    summary: dict[str, Any] = {
        "type": spec.type,
        "max_pole_real_1_per_s": float(poles.real.max()),
        "min_pole_damping": float(damping.min()) if moving.size else None,
        "n_poles": int(poles.size),
    }
    for name in ("Kp", "Kd"):
        if name in arrays:
            summary[name] = [float(v) for v in arrays[name]]
    if "K" in arrays:
        summary["K_norm"] = float(np.linalg.norm(arrays["K"], 2))
    summary.update(info)
    if spec.type == "ppf":
        summary["ppf_gains"] = [float(v) for v in arrays["gains"]]
        summary["min_stiffness_eigenvalue"] = float(arrays["stiffness_eigenvalues"][0])
    return summary


__all__ = [
    "LAW_FIELDS",
    "StudySection",
    "LawSpec",
    "design_law",
    "design_state",
    "law_controller",
    "law_summary",
    "pd_gains",
]
