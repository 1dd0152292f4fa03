"""Maneuver scenarios (``kind: maneuver``, the default): the schema.

A scenario names a benchmark case (:data:`flexsat.cases.CASES`), the simulation settings and one
or more closed-loop runs (control law, gains, optional shaped reference)::

    name: TAMU 40 deg slew, Law I vs Law II
    case: tamu
    case_overrides: {hub_inertia: "50 ozf*in*s**2"}
    model: {n_modes: 10, stiffening: false}
    maneuver: {angle: "40 deg"}
    simulation: {duration: "15 s", control_rate: "75 Hz", integration_step: "3.34 ms"}
    actuator: {saturation: "400 ozf*in"}
    runs:
      - {label: "Law I", law: lyapunov_regulator, gains: {g1: "600 ozf*in/rad", g2: 5.6}}

Quantities are strings with units (``"400 ozf*in"``, ``"40 deg"``) or bare numbers taken in the
SI unit of the field (rad, s, Hz, N m, ...). They are converted to SI floats on load, so a loaded
:class:`Scenario` holds SI numbers only and ``scenario.model_dump()`` is itself a valid scenario.
Keys left out of ``actuator``, ``sensors``, ``disturbances`` and ``simulation`` take the
defaults of the runtime classes (:class:`flexsat.sim.SimConfig` and its parts: ideal sensors, no
saturation, no disturbance).

The laboratory hardware (amplifiers, reaction wheels, anti-alias filters, the computation
delay) is a ``hardware:`` section, at the top level for every run or in a run for that run
alone, and the cable spring on the hub is ``disturbances.cable``
(:mod:`flexsat.scenarios.hardware_section`).

Validation runs in two stages, both before any simulation, and each collects all its problems
into one :class:`~flexsat.scenarios.ScenarioError` whose lines read ``field.path: rule``:

1. :func:`~flexsat.scenarios.load_scenario` -- YAML syntax, the schema (unknown keys, types,
   units, finite numbers) and each section's own rules (its runtime object is built to check
   them);
2. :func:`~flexsat.scenarios.prepare_scenario` -- what needs the case: the case model (positive
   masses, stiffnesses and inertias), the references and the controllers (gain admissibility);
   then :func:`~flexsat.scenarios.run_scenario` simulates each run.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import typing
from collections.abc import Callable
from typing import Annotated, Any, ClassVar, Literal, Self

from pydantic import Field, field_validator, model_validator

from flexsat import limits
from flexsat.cases import CASES, get_case
from flexsat.dynamics.hybrid import HybridPlant
from flexsat.input_checks import FieldError
from flexsat.maneuvers import BangBang, PseudoSquare, Sinusoidal, SmoothBangBang, TorqueShape
from flexsat.scenarios.errors import item_path
from flexsat.scenarios.fields import (
    BuildableSection,
    Document,
    SchemaSection,
    check_unique_labels,
    given_fields,
    in_unit,
    integer_in,
)
from flexsat.scenarios.hardware_section import CableSpec, HardwareSpec
from flexsat.scenarios.laws import MANEUVER_LAWS, LawName
from flexsat.sim import (
    BearingFriction,
    Impulses,
    RandomTorque,
    Sensors,
    SimConfig,
    TorqueActuator,
)


class ModelSpec(SchemaSection):
    """Model options, forwarded to the case builder as overrides."""

    n_modes: int | None = None  # the builder checks it (positive, at most flexsat.limits.MAX_MODES)
    stiffening: bool | None = None


#: largest slew of a maneuver scenario, rad (ten turns)
MAX_SLEW = 20 * math.pi


class ManeuverSpec(SchemaSection):
    """The slew: ``angle`` (rad), from rest at 0, at most ten turns either way."""

    angle: Annotated[float, in_unit("rad")]

    @field_validator("angle")
    @classmethod
    def _sensible(cls, angle: float) -> float:
        if abs(angle) > MAX_SLEW:
            raise FieldError(
                "angle",
                f"a slew of at most ten turns ({MAX_SLEW:.4g} rad) either way, got {angle:.4g} rad",
            )
        return angle


class SimulationSpec(BuildableSection):
    """Run length and sampling; ``integration_step`` sets the substeps per control period."""

    duration: Annotated[float, in_unit("s")]
    control_rate: Annotated[float | None, in_unit("Hz")] = None
    integration_step: Annotated[float | None, in_unit("s")] = None
    settling_band: Annotated[float | None, in_unit("rad")] = None
    seed: Annotated[int | None, integer_in(0, limits.MAX_SEED, optional=True)] = None

    def build(self, **components: Any) -> SimConfig:
        """The :class:`SimConfig`; ``components`` are its actuator, sensors and disturbances."""
        config = SimConfig(**given_fields(self, exclude={"integration_step"}), **components)
        if self.integration_step is None:
            return config
        return dataclasses.replace(
            config, substeps=self._substeps(config.dt, self.integration_step)
        )

    def _substeps(self, period: float, step: float) -> int:
        if step <= 0:
            raise FieldError("integration_step", f"must be > 0, got {step:g} s")
        if step >= period:
            raise FieldError(
                "integration_step",
                "must be smaller than the control period 1/control_rate = "
                f"{1e3 * period:.4g} ms, got {1e3 * step:.4g} ms",
            )
        return math.ceil(period / step - 1e-9)


class ActuatorSpec(BuildableSection):
    saturation: Annotated[float | None, in_unit("N*m")] = None
    torque_constant_ratio: Annotated[float | None, in_unit("")] = None

    @field_validator("torque_constant_ratio")
    @classmethod
    def _sensible(cls, ratio: float | None) -> float | None:
        # actual / nominal torque constant: a motor off by more than 10x is a different motor
        if ratio is not None and ratio > 10:
            raise FieldError(
                "torque_constant_ratio",
                f"actual / nominal torque constant, at most 10, got {ratio:g}",
            )
        return ratio

    def build(self) -> TorqueActuator:
        return TorqueActuator(**given_fields(self))


class SensorsSpec(BuildableSection):
    encoder_resolution: Annotated[float | None, in_unit("rad")] = None
    rate: Literal["ideal", "ls_filter", "gyro"] | None = None
    # a least-squares rate over at most 1,000 samples, a polynomial of at most order 10
    rate_window: Annotated[int | None, integer_in(1, 1000, optional=True)] = None
    rate_order: Annotated[int | None, integer_in(0, 10, optional=True)] = None
    gyro_noise: Annotated[float | None, in_unit("rad/s")] = None
    strain_noise: Annotated[float | None, in_unit("N*m")] = None

    def build(self) -> Sensors:
        return Sensors(**given_fields(self))


class FrictionSpec(BuildableSection):
    coulomb: Annotated[float | None, in_unit("N*m")] = None
    viscous: Annotated[float | None, in_unit("N*m*s/rad")] = None
    smoothing: Annotated[float | None, in_unit("rad/s")] = None

    def build(self) -> BearingFriction:
        return BearingFriction(**given_fields(self))


class ImpulseSpec(SchemaSection):
    time: Annotated[float, in_unit("s")]
    impulse: Annotated[float, in_unit("N*m*s")]


class DisturbancesSpec(BuildableSection):
    """Bearing friction, random torque (1 sigma, N m), angular impulses and the cable spring
    (:class:`~flexsat.scenarios.hardware_section.CableSpec`) on the hub."""

    friction: FrictionSpec = Field(default_factory=FrictionSpec)
    random_torque: Annotated[float | None, in_unit("N*m")] = None
    impulses: list[ImpulseSpec] = Field(default_factory=list, max_length=limits.MAX_SAMPLES)
    cable: CableSpec | None = None

    def build(self) -> dict[str, Any]:
        """Keyword arguments ``friction``, ``random_torque``, ``impulses`` (and, with a cable,
        ``channel_disturbances``: the cable's torque on the hub's ``torque`` input, driven by
        ``theta``) of :class:`SimConfig`."""
        try:
            random = RandomTorque(*(() if self.random_torque is None else (self.random_torque,)))
        except FieldError as exc:  # its one input, std, is this section's random_torque
            raise FieldError("random_torque", exc.rule) from None
        impulses = Impulses(
            tuple(i.time for i in self.impulses), tuple(i.impulse for i in self.impulses)
        )
        out: dict[str, Any] = {
            "friction": self.friction.build(),
            "random_torque": random,
            "impulses": impulses,
        }
        if self.cable is not None:
            from flexsat.sim.channels import ChannelDisturbance

            out["channel_disturbances"] = {
                "torque": ChannelDisturbance(
                    force=self.cable.build(), force_output="theta", force_name="cable"
                )
            }
        return out


class GainsSpec(SchemaSection):
    """Feedback gains: g1, g2, g3 (Lyapunov laws) or kp, kd (PD)."""

    g1: Annotated[float | None, in_unit("N*m/rad")] = None
    g2: Annotated[float | None, in_unit("N*m*s/rad")] = None
    g3: Annotated[float | None, in_unit("")] = None
    kp: Annotated[float | None, in_unit("N*m/rad")] = None
    kd: Annotated[float | None, in_unit("N*m*s/rad")] = None


class PolesSpec(SchemaSection):
    """Rigid closed-loop poles of a PD law; ``natural_frequency`` in Hz or rad/s (a bare
    number is rad/s; :func:`flexsat.units.to_si` applies the 2π between the two)."""

    natural_frequency: Annotated[float, in_unit("rad/s")]
    damping_ratio: Annotated[float, in_unit("")]


class LQGSpec(SchemaSection):
    """Weights and noise intensities of an LQG law on the plant's modal state
    x = [θ, q, θ', q'] with measurements (θ, θ') (Hailey, Sortun & Agrawal c. 1992 Eqs. 38-53).

    ``mode_weights`` (one per retained mode, or one for all) weight q_i and q'_i alike;
    ``process_noise`` is the intensity of a torque disturbance (Q_xx = B·qn·Bᵀ, Eq. 43);
    ``refine``: "weighted" recomputes the filter with Q_xx = Kᵀ Bᵀ B K (Eq. 52), "truncated"
    also zeroes the gains of the modes beyond ``keep_modes`` first (Eq. 53).
    """

    rigid_weight: Annotated[float, in_unit("")] = 1.0
    mode_weights: list[Annotated[float, in_unit("")]] | float = 0.1
    control_weight: Annotated[float, in_unit("")]
    sensor_noise: list[Annotated[float, in_unit("")]]
    process_noise: Annotated[float, in_unit("")]
    refine: Literal["none", "weighted", "truncated"] = "none"
    keep_modes: Annotated[int | None, integer_in(0, limits.MAX_MODES, optional=True)] = None

    @model_validator(mode="after")
    def _truncation(self) -> Self:
        if self.refine == "truncated" and self.keep_modes is None:
            raise FieldError("keep_modes", "required by refine 'truncated'")
        if len(self.sensor_noise) != 2:
            raise FieldError(
                "sensor_noise", f"give the (θ, θ') intensities, got {len(self.sensor_noise)} values"
            )
        return self


#: the torque shapes a reference can name
ShapeName = Literal["bang_bang", "smooth_bang_bang", "pseudo_square", "sinusoidal"]
_SHAPES: dict[ShapeName, Callable[..., TorqueShape]] = {
    "bang_bang": BangBang,
    "smooth_bang_bang": SmoothBangBang,
    "pseudo_square": PseudoSquare,
    "sinusoidal": Sinusoidal,
}
_SHAPE_PARAMETERS = {"smooth_bang_bang": ("alpha",), "pseudo_square": ("rise_time",)}


class ReferenceSpec(SchemaSection):
    """Rigid reference maneuver: a torque shape with any two of u_max, duration and its own
    parameter (one of u_max, duration for bang_bang and sinusoidal)."""

    shape: ShapeName
    u_max: Annotated[float | None, in_unit("N*m")] = None
    duration: Annotated[float | None, in_unit("s")] = None
    alpha: Annotated[float | None, in_unit("")] = None
    rise_time: Annotated[float | None, in_unit("s")] = None

    @model_validator(mode="after")
    def _shape_parameters(self) -> Self:
        own = _SHAPE_PARAMETERS.get(self.shape, ())
        for name in ("alpha", "rise_time"):
            if getattr(self, name) is not None and name not in own:
                raise FieldError(name, f"not a parameter of shape {self.shape!r}")
        return self

    def build(self, angle: float, inertia: float) -> TorqueShape:
        """The torque shape slewing ``angle`` (rad) with the rigid ``inertia`` (kg m²)."""
        return _SHAPES[self.shape](angle, inertia, **given_fields(self, exclude={"shape"}))


class RunSpec(SchemaSection):
    """One closed-loop run.

    ``law`` is ``lyapunov_regulator`` (gains g1, g2, g3), ``lyapunov_tracker`` (same gains and a
    ``reference``) or ``pd`` (gains kp, kd or ``poles``; with a ``reference`` it tracks it,
    feeding its torque forward unless ``feedforward: false``). ``hardware`` is this run's
    (:class:`~flexsat.scenarios.hardware_section.HardwareSpec`) in place of the document's
    (``{preset: ideal}``: none).
    """

    label: str
    law: LawName
    gains: GainsSpec | None = None
    poles: PolesSpec | None = None
    reference: ReferenceSpec | None = None
    feedforward: bool | None = None
    lqg: LQGSpec | None = None
    hardware: HardwareSpec | None = None

    @model_validator(mode="after")
    def _law_inputs(self) -> Self:
        law = MANEUVER_LAWS[self.law]
        given = given_fields(self.gains) if self.gains is not None else {}
        for name in given:
            if name not in law.gains:
                raise FieldError(
                    f"gains.{name}",
                    f"not a gain of law {self.law!r} (its gains: {', '.join(law.gains)})",
                )
        for name in ("poles", "feedforward"):
            if getattr(self, name) is not None and not law.pd_options:
                raise FieldError(name, "only for law 'pd'")
        if (self.lqg is None) != (self.law != "lqg"):
            raise FieldError("lqg", "required by law 'lqg' and only for it")
        if self.poles is not None and self.gains is not None:
            raise FieldError("gains", "give gains or poles, not both")
        missing = [g for g in law.required if g not in given]
        if self.poles is None and missing:
            raise FieldError(
                f"gains.{missing[0]}",
                f"required by law {self.law!r}" + (" (or give poles)" if law.pd_options else ""),
            )
        if law.reference == "required" and self.reference is None:
            raise FieldError("reference", f"required by law {self.law!r}")
        if law.reference == "forbidden" and self.reference is not None:
            raise FieldError(
                "reference", f"law {self.law!r} tracks no reference (use lyapunov_tracker)"
            )
        return self


class Scenario(Document):
    """A validated scenario, quantities in SI (see the module docstring for the schema)."""

    kind: Literal["maneuver"] = "maneuver"
    name: str
    case: str
    case_overrides: dict[str, bool | int | float | str] = Field(default_factory=dict)
    model: ModelSpec = Field(default_factory=ModelSpec)
    maneuver: ManeuverSpec
    simulation: SimulationSpec
    actuator: ActuatorSpec = Field(default_factory=ActuatorSpec)
    sensors: SensorsSpec = Field(default_factory=SensorsSpec)
    disturbances: DisturbancesSpec = Field(default_factory=DisturbancesSpec)
    hardware: HardwareSpec | None = None
    runs: list[RunSpec] = Field(min_length=1, max_length=limits.MAX_RUNS)

    @field_validator("case")
    @classmethod
    def _known_case(cls, name: str) -> str:
        get_case(name)
        if name not in maneuver_cases():
            raise FieldError(
                "case",
                f"{name!r} has no maneuver model (a hub plant to slew); "
                f"cases with one: {', '.join(maneuver_cases())}",
            )
        return name

    @field_validator("case_overrides")
    @classmethod
    def _finite_overrides(
        cls, overrides: dict[str, bool | int | float | str]
    ) -> dict[str, bool | int | float | str]:
        for key, value in overrides.items():
            if _non_finite(value):
                raise FieldError(key, f"must be a finite number, got {value!r}")
        return overrides

    @model_validator(mode="after")
    def _consistent(self) -> Self:
        for name in given_fields(self.model):
            if name in self.case_overrides:
                raise FieldError(f"model.{name}", "also given in case_overrides; give it once")
        check_unique_labels(self.runs)
        return self

    @property
    def case_parameters(self) -> dict[str, Any]:
        """Keyword arguments of the case builder: ``case_overrides`` and the ``model`` options."""
        return {**self.case_overrides, **given_fields(self.model)}

    #: the document's field each input of :meth:`sim_config` (and the batch size, one case per
    #: run) comes from: where a value :func:`flexsat.sim.engine.check_resources` refuses is
    #: reported
    CONFIG_PATHS: ClassVar[dict[str, str]] = {
        "friction": "disturbances.friction",
        "duration": "simulation.duration",
        "n_cases": "runs",
        "substeps": "simulation.integration_step",
    }

    def sim_config(self) -> SimConfig:
        """The :class:`SimConfig` shared by every run (without hardware)."""
        return self.simulation.build(
            actuator=self.actuator.build(),
            sensors=self.sensors.build(),
            **self.disturbances.build(),
        )

    def run_hardware(self, index: int) -> tuple[str, HardwareSpec | None]:
        """(the field path of, the section of) run ``index``'s hardware: its own, else the
        document's."""
        run = self.runs[index]
        if run.hardware is not None:
            return "runs" + item_path(index, run.label) + ".hardware", run.hardware
        return "hardware", self.hardware


@functools.cache
def maneuver_cases() -> tuple[str, ...]:
    """The cases a maneuver scenario can simulate: their builder's case has a ``model()`` that
    gives a hub plant (:class:`flexsat.dynamics.hybrid.HybridPlant`), read from the type hints so
    that no case is built."""
    names: list[str] = []
    for name, info in CASES.items():
        model = getattr(typing.get_type_hints(info.builder).get("return"), "model", None)
        plant = typing.get_type_hints(model).get("return") if callable(model) else None
        if isinstance(plant, type) and issubclass(plant, HybridPlant):
            names.append(name)
    return tuple(names)


def _non_finite(value: bool | int | float | str) -> bool:
    """True for NaN and infinities, given as numbers or as bare strings ("nan", "inf")."""
    if isinstance(value, bool):
        return False
    try:
        return not math.isfinite(float(value))
    except (TypeError, ValueError):
        return False


__all__ = ["MAX_SLEW", "Scenario", "maneuver_cases"]
