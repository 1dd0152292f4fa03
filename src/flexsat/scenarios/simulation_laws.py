"""The laws a simulation run names (``law:``): the built-in ones and the ``flexsat.laws``
plug-ins, all built through one protocol (:mod:`flexsat.scenarios.registry`).

A law is a class with ``Parameters`` (the schema of the run's ``gains:``), optionally
``Target`` (the schema of its ``target:``; None or absent: the law takes no target) and a
classmethod ``from_scenario(parameters, context)`` returning a
:class:`flexsat.control.Controller` that reads and writes the plant's channels by name;
``context`` is a :class:`LawContext`. :func:`simulation_laws` is the registry the scenario
schema and runner call. The builders import the control package when a run is built, so
reading a scenario does not.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Self, cast

import numpy as np
from pydantic import BaseModel, model_validator

from flexsat import limits
from flexsat.input_checks import FieldError
from flexsat.scenarios.fields import SchemaSection

if TYPE_CHECKING:
    from flexsat.control.base import Controller

#: a number as written in YAML: a plain (SI) number or a quantity string
Number = float | int | str
#: a value as written in YAML: a number, a list of numbers or a matrix (a list of rows); typed
#: down to its items so that the schema's refusal of a boolean where a number is expected
#: (:class:`flexsat.scenarios.fields.SchemaSection`) reaches a ``true`` inside a list
Value = Number | list[Number] | list[list[Number]]


@dataclass(frozen=True)
class LawContext:
    """What a law is built against.

    Attributes
    ----------
    plant : flexsat.dynamics.plant.Plant
        The scenario's plant (its channels, its linear part).
    dt : float
        Control period, s.
    target : pydantic model or None
        The run's validated ``target:`` (an instance of the law's ``Target``), or None when
        the run gives none.
    """

    plant: Any
    dt: float
    target: BaseModel | None = None


def target_quaternion(target: dict[str, Value]) -> np.ndarray | None:
    """Euler parameters of a target given as ``euler123`` (rad) or ``attitude``; None if empty."""
    from flexsat.dynamics.attitude import dcm_to_quaternion, euler123_to_dcm
    from flexsat.units import to_si_array

    if not target:
        return None
    unknown = set(target) - {"euler123", "attitude"}
    if unknown:
        raise FieldError(
            f"target.{sorted(unknown)[0]}",
            "not a target (give euler123 (rad) or attitude (a unit quaternion, scalar first))",
        )
    if len(target) > 1:
        raise FieldError("target", "give euler123 or attitude, not both")
    if "euler123" in target:
        angles = to_si_array(target["euler123"], "rad", "target.euler123")
        if angles.shape != (3,):
            raise FieldError("target.euler123", f"three angles, got shape {angles.shape}")
        return dcm_to_quaternion(euler123_to_dcm(angles))
    return to_si_array(target["attitude"], "", "target.attitude")


class AttitudeTarget(SchemaSection):
    """The attitude an attitude law turns to: 1-2-3 Euler angles (rad) or a unit quaternion
    (scalar first), one of them."""

    euler123: Value | None = None
    attitude: Value | None = None

    @model_validator(mode="after")
    def _one(self) -> Self:
        if self.euler123 is not None and self.attitude is not None:
            raise FieldError("target", "give euler123 or attitude, not both")
        return self

    def quaternion(self) -> np.ndarray | None:
        """The target's Euler parameters, or None when neither is given."""
        return target_quaternion(self.model_dump(exclude_none=True))


class AttitudeLaw:
    """A scenario law of an attitude law of :mod:`flexsat.control` (its gains named as the
    class's fields), turning to the run's ``target``; subclasses name the class."""

    #: the law's class in flexsat.control, imported when a run is built
    control_class: str
    Target = AttitudeTarget

    @classmethod
    def from_scenario(cls, parameters: BaseModel, context: LawContext) -> Controller:
        """The law with the gains ``parameters``, turning to ``context.target`` (an
        :class:`AttitudeTarget`, or None: the law's own default attitude)."""
        import flexsat.control

        # the run's target is an instance of cls.Target: AttitudeTarget (or a subclass)
        target = cast(AttitudeTarget | None, context.target)
        beta = None if target is None else target.quaternion()
        extra = {} if beta is None else {"beta_target": beta}
        return getattr(flexsat.control, cls.control_class)(**parameters.model_dump(), **extra)


class GibbsLyapunov(AttitudeLaw):
    """:class:`flexsat.control.GibbsLyapunovLaw`."""

    class Parameters(SchemaSection):
        k: Value
        A: Value

    control_class = "GibbsLyapunovLaw"


class MRP(AttitudeLaw):
    """:class:`flexsat.control.MRPLaw`."""

    class Parameters(SchemaSection):
        K: Value
        P: Value

    control_class = "MRPLaw"


class QuaternionPD(AttitudeLaw):
    """:class:`flexsat.control.QuaternionPD`."""

    class Parameters(SchemaSection):
        Kp: Value
        Kd: Value

    control_class = "QuaternionPD"


class LQRWeights(SchemaSection):
    state_weights: Value
    input_weights: Value = 1.0


class NoGains(SchemaSection):
    """A law without parameters."""


def _weights(value: Value, size: int, field: str) -> np.ndarray:
    w = np.atleast_1d(np.asarray(value, float))
    if w.size == 1:
        w = np.full(size, float(w[0]))
    if w.shape != (size,) or not np.all(np.isfinite(w)) or np.any(w < 0):
        raise FieldError(field, f"one weight >= 0 or {size} of them (finite), got {value!r}")
    return np.diag(w)


def _check_span(q: np.ndarray, r: np.ndarray) -> None:
    """Refuse LQR weights spanning more than :data:`flexsat.limits.MAX_WEIGHT_RANGE`, naming
    the weights that hold the extreme value farther (in decades) from 1."""
    values = np.concatenate([q, r])
    positive = values[values > 0]
    if positive.size == 0 or positive.max() <= limits.MAX_WEIGHT_RANGE * positive.min():
        return
    low, high = positive.min(), positive.max()
    # weights are SI numbers of natural scale 1: the one farther from 1 is out of place
    extreme = high if abs(np.log10(high)) >= abs(np.log10(low)) else low
    field = "gains.state_weights" if extreme in q else "gains.input_weights"
    raise FieldError(
        field,
        f"the weights span {high / low:.3g} (from {low:.3g} to {high:.3g}), above "
        f"{limits.MAX_WEIGHT_RANGE:.0e} (flexsat.limits.MAX_WEIGHT_RANGE: the smaller "
        "would be below the rounding of the larger in the Riccati equation)",
    )


class LQR:
    """Constant LQR state feedback on the plant's linear part, reading its ``state`` output."""

    Parameters = LQRWeights

    @classmethod
    def from_scenario(cls, parameters: LQRWeights, context: LawContext) -> Controller:
        """LQR with the diagonal weights of ``parameters`` on the plant's linear part."""
        from flexsat.control import ScheduledStateFeedback, lqr

        plant = context.plant
        A, B = plant.linear_part()
        n, m = B.shape
        Q = _weights(parameters.state_weights, n, "gains.state_weights")
        R = _weights(parameters.input_weights, m, "gains.input_weights")
        _check_span(np.diag(Q), np.diag(R))
        K, _, _ = lqr(A, B, Q, R)
        return ScheduledStateFeedback([0.0], K[None], "state", [c.name for c in plant.inputs])


class AttitudeLQGWeights(SchemaSection):
    coordinates: str = "mrp"
    state_weights: Value
    input_weights: Value = 1.0
    process_noise: Value = 1.0
    measurement_noise: Value


class AttitudeLQG:
    """:class:`flexsat.control.AttitudeLQG` designed on the plant's attitude-error
    linearisation at rest (:func:`flexsat.dynamics.linearize_attitude`, ``coordinates`` "mrp"
    or "quaternion"), turning to the run's ``target``: diagonal weights on the error state and
    the three torques, torque process noise (one intensity per axis) and measurement noise on
    the measured [e, δω] (six), all SI numbers."""

    Parameters = AttitudeLQGWeights
    Target = AttitudeTarget

    @classmethod
    def from_scenario(cls, parameters: AttitudeLQGWeights, context: LawContext) -> Controller:
        """The LQG of ``parameters`` on ``context.plant``, at ``context.dt``."""
        from flexsat.control import AttitudeLQG as Law
        from flexsat.dynamics import linearize_attitude

        lin = linearize_attitude(context.plant, parameters.coordinates)
        Q = _weights(parameters.state_weights, lin.A.shape[0], "gains.state_weights")
        R = _weights(parameters.input_weights, 3, "gains.input_weights")
        _check_span(np.diag(Q), np.diag(R))
        Qn = _weights(parameters.process_noise, 3, "gains.process_noise")
        Rn = _weights(parameters.measurement_noise, 6, "gains.measurement_noise")
        target = cast(AttitudeTarget | None, context.target)
        beta = None if target is None else target.quaternion()
        extra = {} if beta is None else {"beta_target": beta}
        return Law.design(lin, Q, R, Qn, Rn, context.dt, **extra)


class OpenLoop:
    """No feedback: zero commands on every input (disturbances and initial values drive the
    plant)."""

    Parameters = NoGains

    @classmethod
    def from_scenario(cls, parameters: NoGains, context: LawContext) -> Controller:
        """A compensator of no state whose zero outputs are the plant's inputs."""
        import control
        from flexsat.control import StateSpaceCompensator

        plant = context.plant
        first = plant.outputs[0]
        # the channels themselves, not their names: a name alone counts as one wide
        system = control.ss([], [], [], np.zeros((plant.n_inputs, first.size)))
        return StateSpaceCompensator(system, [first], list(plant.inputs), dt=context.dt)


#: the built-in laws of a simulation run, by name
BUILTIN_LAWS: dict[str, Any] = {
    "gibbs_lyapunov": GibbsLyapunov,
    "mrp_pd": MRP,
    "quaternion_pd": QuaternionPD,
    "lqr": LQR,
    "attitude_lqg": AttitudeLQG,
    "open_loop": OpenLoop,
}


def simulation_laws() -> dict[str, Any]:
    """The laws a simulation run can name: :data:`BUILTIN_LAWS`, then the ``flexsat.laws``
    plug-ins (read on the first call; a broken or colliding one is left out and reported by
    :func:`flexsat.plugins.broken_plugins`)."""
    from flexsat.scenarios.registry import merge_builtins

    return merge_builtins(
        "flexsat.laws",
        BUILTIN_LAWS,
        lambda name, law: f"the built-in law {name!r} ({law.__module__}:{law.__qualname__})",
    )


__all__ = [
    "BUILTIN_LAWS",
    "AttitudeTarget",
    "LawContext",
    "simulation_laws",
    "target_quaternion",
]
