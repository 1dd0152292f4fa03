r"""The ``hardware:`` section of a scenario (the laboratory hardware of
:mod:`flexsat.sim.hardware` in a file) and the cable-spring disturbance of the hub.

A maneuver scenario takes the section at the document's top level (every run) and in a run
(that run alone, in place of the document's)::

    hardware:
      preset: tamu                 # the TAMU drive, 10 Hz filter and one-sample delay
      filters:                     # per measured (output) channel the law reads
        root_torque: {type: butterworth, order: 2, corner: "10 Hz"}
      amplifiers:                  # per command (input) channel the law writes
        torque: {mode: current, gain: "1.2 A/V", current_limit: "12 A",
                 bandwidth: "500 Hz", torque_constant: "52.77 ozf*in/A", dac_range: "10 V"}
      wheels:                      # or a reaction wheel on a command channel
        torque: {inertia: "2e-3 kg*m^2", torque_constant: "0.05 N*m/A", max_speed: "3000 rpm",
                 amplifier: {mode: current, current_limit: "4 A"}}
      delay_samples: 1             # or delay: "13.3 ms" (a time)

and, on a three-axis spacecraft's torque (a simulation scenario), a reaction-wheel array::

    hardware:
      wheel_arrays:
        torque: {axes: [[0.816, 0, 0.577], [0, 0.816, 0.577], [-0.816, 0, 0.577],
                        [0, -0.816, 0.577]], inertia: "0.05 kg*m^2", max_speed: "6000 rpm"}

Units: a filter's ``corner`` and an amplifier's ``bandwidth`` are frequencies — ``"10 Hz"`` or
``"62.83 rad/s"`` (the 2π is applied by the unit conversion), a bare number is Hz; a wheel's
``max_speed`` is an angular rate (``"3000 rpm"``, a bare number rad/s); an amplifier's ``gain``
is A/V in current mode and V/V in voltage mode. ``preset`` names a hardware set
(:data:`HARDWARE_PRESETS`: ``tamu``, :func:`flexsat.cases.tamu.tamu_hardware`; ``ideal``, no
hardware at all: a run's ``hardware: {preset: ideal}`` runs it ideal beside a document's
hardware); the section's own filters, amplifiers and wheels replace the preset's on their
channel, its delay replaces the preset's. A ``delay`` time is converted to samples of the
scenario's control period, d = τ f_s (a value within 1e-9 of a whole number is that number).

The cable spring (:class:`CableSpec`, ``disturbances.cable``): τ(θ) = T_D − k (θ − θ_c) +
τ_tab(θ) on the hub (:class:`flexsat.sim.disturbances.CableSpring`; Hailey, Sortun & Agrawal,
"Experimental verification of attitude control techniques for slew maneuvers of flexible
spacecraft", NPS, c. 1992, Eq. 23: θ_ss = T_D / k_p under PD control)::

    disturbances:
      cable: {constant: "1 mN*m", stiffness: "0.5 mN*m/rad", center: "0 deg",
              profile: [{angle: "0 deg", torque: "0 N*m"}, {angle: "60 deg", torque: "1 mN*m"}]}
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import replace
from typing import TYPE_CHECKING, Annotated, Any, Literal, Self, cast

import numpy as np
from pydantic import Field, ValidationInfo, field_validator, model_validator

from flexsat import limits
from flexsat.input_checks import FieldError
from flexsat.scenarios.errors import Problem, locate
from flexsat.scenarios.fields import (
    BuildableSection,
    SchemaSection,
    given_fields,
    in_unit,
    integer_in,
)
from flexsat.sim.disturbances import CableSpring
from flexsat.sim.hardware import Amplifier, AntiAliasFilter, Hardware, ReactionWheel
from flexsat.sim.wheel_array import ReactionWheelArray
from flexsat.units import to_si

if TYPE_CHECKING:
    from flexsat.control import Controller
    from flexsat.dynamics.plant import Plant


def _tamu() -> Hardware:
    from flexsat.cases.tamu import tamu_hardware

    return tamu_hardware()


#: the hardware sets a ``preset`` names: a builder each (no case is built)
HARDWARE_PRESETS: dict[str, Callable[[], Hardware]] = {"tamu": _tamu, "ideal": Hardware}


def _own_field(exc: FieldError) -> FieldError:
    """A runtime piece's error (``amplifier.gain``, ``wheel.inertia``) at the section's own
    field (``gain``, ``inertia``)."""
    return FieldError(exc.field.rsplit(".", 1)[-1], exc.rule)


class FilterSpec(BuildableSection):
    """An analog anti-alias low-pass on a measured channel: ``type`` (butterworth or bessel),
    ``order`` (1 .. 10 poles) and its −3 dB ``corner`` (Hz or rad/s; a bare number is Hz)."""

    type: Literal["butterworth", "bessel"] = "butterworth"
    order: Annotated[int, integer_in(1, 10)] = 2
    corner: Annotated[float, in_unit("Hz", positive=True)]

    def build(self) -> AntiAliasFilter:
        return AntiAliasFilter(self.corner, self.order, self.type)


class AmplifierSpec(BuildableSection):
    """A power amplifier (:class:`flexsat.sim.hardware.Amplifier`): a key left out is
    unlimited (limits), instantaneous (bandwidth) or 1 (gain, torque constant)."""

    mode: Literal["current", "voltage"] = "current"
    gain: float | None = None
    current_limit: Annotated[float | None, in_unit("A", positive=True)] = None
    bandwidth: Annotated[float | None, in_unit("Hz", positive=True)] = None
    torque_constant: Annotated[float | None, in_unit("N*m/A", positive=True)] = None
    dac_range: Annotated[float | None, in_unit("V", positive=True)] = None
    voltage_limit: Annotated[float | None, in_unit("V", positive=True)] = None

    @field_validator("gain", mode="before")
    @classmethod
    def _gain_in_its_mode(cls, value: Any, info: ValidationInfo) -> float | None:
        """A/V in current mode, V/V in voltage mode (the mode is read first)."""
        if value is None:
            return None
        unit = "V/V" if info.data.get("mode") == "voltage" else "A/V"
        si = to_si(value, unit, "gain")
        if not si > 0:
            raise FieldError("gain", f"must be > 0 ({unit}), got {value!r}")
        return si

    def build(self) -> Amplifier:
        try:
            return Amplifier(**given_fields(self))
        except FieldError as exc:
            raise _own_field(exc) from None


class WheelSpec(BuildableSection):
    """A reaction wheel on a command channel (:class:`flexsat.sim.hardware.ReactionWheel`):
    the hub feels the reaction of its motor and bearing torque; ``amplifier`` is its drive
    (current mode, ideal, when left out)."""

    inertia: Annotated[float, in_unit("kg*m^2", positive=True)]
    torque_constant: Annotated[float | None, in_unit("N*m/A", positive=True)] = None
    back_emf: Annotated[float | None, in_unit("V*s/rad")] = None
    resistance: Annotated[float | None, in_unit("ohm", positive=True)] = None
    viscous: Annotated[float | None, in_unit("N*m*s/rad")] = None
    coulomb: Annotated[float | None, in_unit("N*m")] = None
    max_speed: Annotated[float | None, in_unit("rad/s", positive=True)] = None
    smoothing: Annotated[float | None, in_unit("rad/s", positive=True)] = None
    rate_output: str | None = None
    amplifier: AmplifierSpec = Field(default_factory=AmplifierSpec)

    def build(self) -> ReactionWheel:
        values = given_fields(self, exclude={"amplifier"})
        try:
            return ReactionWheel(**values, amplifier=self.amplifier.build())
        except FieldError as exc:
            raise _own_field(exc) from None


class WheelArraySpec(BuildableSection):
    """A reaction-wheel array on a three-axis torque channel
    (:class:`flexsat.sim.wheel_array.ReactionWheelArray`): ``axes``, one spin-axis unit
    vector [x, y, z] (body axes) per wheel, three or more spanning the body; ``inertia`` of
    each wheel; its ``max_speed`` and ``viscous`` friction. The law's body torque goes to the
    wheels by the pseudo-inverse G⁺ = Gᵀ(G Gᵀ)⁻¹."""

    axes: list[list[float]] = Field(min_length=3, max_length=limits.MAX_RUNS)
    inertia: Annotated[float, in_unit("kg*m^2", positive=True)]
    max_speed: Annotated[float | None, in_unit("rad/s", positive=True)] = None
    viscous: Annotated[float | None, in_unit("N*m*s/rad")] = None
    rate_output: str | None = None

    def build(self) -> ReactionWheelArray:
        if any(len(a) != 3 for a in self.axes):
            raise FieldError("axes", "give each wheel's axis as three numbers [x, y, z]")
        return ReactionWheelArray(
            np.array(self.axes, float).T, **given_fields(self, exclude={"axes"})
        )


class HardwareSpec(SchemaSection):
    """The ``hardware:`` section (module docstring)."""

    preset: Literal["tamu", "ideal"] | None = None
    filters: dict[str, FilterSpec] = Field(default_factory=dict)
    amplifiers: dict[str, AmplifierSpec] = Field(default_factory=dict)
    wheels: dict[str, WheelSpec] = Field(default_factory=dict)
    wheel_arrays: dict[str, WheelArraySpec] = Field(default_factory=dict)
    delay: Annotated[float | None, in_unit("s")] = None
    delay_samples: Annotated[float | None, in_unit("")] = None

    @model_validator(mode="after")
    def _consistent(self) -> Self:
        if self.preset == "ideal" and (
            self.filters or self.amplifiers or self.wheels or self.wheel_arrays or self.has_delay
        ):
            raise FieldError("preset", "'ideal' is no hardware: give nothing else beside it")
        if self.delay is not None and self.delay_samples is not None:
            raise FieldError("delay", "give delay (a time) or delay_samples, not both")
        for name in ("delay", "delay_samples"):
            value = getattr(self, name)
            if value is not None and not value >= 0:
                raise FieldError(name, f"must be >= 0, got {value!r}")
        if self.delay_samples is not None and self.delay_samples > limits.MAX_SAMPLES:
            raise FieldError("delay_samples", f"at most {limits.MAX_SAMPLES} samples")
        for k in self.wheel_arrays:
            if k in self.amplifiers or k in self.wheels:
                raise FieldError(
                    f"wheel_arrays.{k}", f"channel {k!r} also has an amplifier or a wheel"
                )
        for k in self.wheels:
            if k in self.amplifiers:
                raise FieldError(
                    f"wheels.{k}",
                    f"channel {k!r} also has an amplifier: give a wheel's drive as its own "
                    "amplifier key",
                )
        for k, a in self.amplifiers.items():
            if a.mode == "voltage":
                raise FieldError(
                    f"amplifiers.{k}.mode",
                    "voltage mode needs a motor speed for the back-EMF: give the amplifier "
                    "to a wheel (wheels.<channel>.amplifier)",
                )
        return self

    @property
    def has_delay(self) -> bool:
        return self.delay is not None or self.delay_samples is not None

    def build(self, control_period: float) -> Hardware | None:
        """The :class:`~flexsat.sim.hardware.Hardware` of the section (None: ideal), a delay
        time converted to samples of ``control_period`` (s)."""
        base = HARDWARE_PRESETS[self.preset]() if self.preset else Hardware()
        actuators: dict[str, ReactionWheel | Amplifier | ReactionWheelArray] = dict(base.actuators)
        actuators.update({k: a.build() for k, a in self.amplifiers.items()})
        actuators.update({k: w.build() for k, w in self.wheels.items()})
        actuators.update({k: w.build() for k, w in self.wheel_arrays.items()})
        filters = {**base.filters, **{k: f.build() for k, f in self.filters.items()}}
        delay = float(base.delay)
        if self.delay_samples is not None:
            delay = self.delay_samples
        elif self.delay is not None:
            delay = self.delay / control_period
            if abs(delay - round(delay)) < 1e-9:
                delay = float(round(delay))
        if not (actuators or filters or delay):
            return None
        return replace(base, actuators=actuators, filters=filters, delay=delay)

    def origin(self, role: str, channel: str) -> str:
        """The section's key a channel's piece comes from: ``filters.<k>``, ``amplifiers.<k>``,
        ``wheels.<k>``, or ``preset`` (the preset's)."""
        if role == "filters":
            return f"filters.{channel}" if channel in self.filters else "preset"
        for name in ("amplifiers", "wheels", "wheel_arrays"):
            if channel in getattr(self, name):
                return f"{name}.{channel}"
        return "preset"


def check_hardware(
    hardware: Hardware,
    spec: HardwareSpec,
    plant: Plant,
    law: Controller,
    path: str,
    actuated: Iterable[str] = (),
) -> list[Problem]:
    """What a run's hardware cannot do on its plant and law, before anything runs: each
    filter on an output the plant has (linear) and the law reads, each amplifier or wheel on a
    one-wide input the law writes, each wheel's rate output on the plant; then the augmented
    plant is built (:class:`flexsat.sim.hardware.HardwarePlant`). ``path`` is the section's."""
    problems: list[Problem] = []
    outputs = {c.name: c for c in plant.outputs}
    inputs = {c.name: c for c in plant.inputs}
    owner = type(plant).__name__
    for k in hardware.filters:
        where = f"{path}.{spec.origin('filters', k)}"
        if k not in outputs:
            problems.append(
                Problem(
                    where,
                    f"the {owner} plant has no output {k!r} (its outputs: {', '.join(outputs)})",
                )
            )
        elif k not in law.reads:
            problems.append(
                Problem(where, f"the law does not read {k!r} (it reads: {', '.join(law.reads)})")
            )
    for k, piece in hardware.actuators.items():
        where = f"{path}.{spec.origin('actuators', k)}"
        if k not in inputs:
            problems.append(
                Problem(
                    where, f"the {owner} plant has no input {k!r} (its inputs: {', '.join(inputs)})"
                )
            )
        elif isinstance(piece, ReactionWheelArray) and inputs[k].size != 3:
            problems.append(
                Problem(where, f"a wheel array needs a torque 3 wide, {k!r} is {inputs[k].size}")
            )
        elif isinstance(piece, ReactionWheelArray) and k in actuated:
            problems.append(
                Problem(
                    where,
                    f"a wheel array's channel takes no actuators.{k} (its limits are the "
                    "wheels' speed limits)",
                )
            )
        elif not isinstance(piece, ReactionWheelArray) and inputs[k].size != 1:
            problems.append(Problem(where, f"needs a channel 1 wide, {k!r} is {inputs[k].size}"))
        elif k not in law.writes:
            problems.append(
                Problem(where, f"the law does not write {k!r} (it writes: {', '.join(law.writes)})")
            )
        elif (
            isinstance(piece, (ReactionWheel, ReactionWheelArray))
            and piece.rate_output not in outputs
        ):
            problems.append(
                Problem(
                    f"{where}.rate_output",
                    f"the {owner} plant has no output "
                    f"{piece.rate_output!r} (its outputs: {', '.join(outputs)})",
                )
            )
    if not problems:
        try:
            hardware.plant_for(plant)
        except FieldError as exc:
            problems.append(locate(path, exc))
    return problems


def describe_hardware(hardware: Hardware | None) -> str:
    """One line naming a run's hardware (the report's and the dataset's), SI units."""
    if hardware is None:
        return "ideal (no hardware)"
    parts = []
    for k, f in hardware.filters.items():
        parts.append(
            f"{k}: {f.kind} order {f.order} anti-alias filter, corner {cast(float, f.corner):g} Hz"
        )
    for k, a in hardware.actuators.items():
        if isinstance(a, ReactionWheelArray):
            parts.append(f"{k}: {a.n_wheels} reaction wheels (pseudo-inverse distribution)")
            continue
        if isinstance(a, ReactionWheel):
            amp = a.amplifier
            text = (
                f"{k}: reaction wheel J_w = {a.si('inertia'):g} kg m², K_t = "
                f"{a.si('torque_constant'):g} N m/A, max speed {a.si('max_speed'):g} rad/s, "
            )
        else:
            amp, text = a, f"{k}: "
        text += (
            f"{amp.mode}-mode amplifier, gain {amp.si('gain'):g}, current limit "
            f"{amp.si('current_limit'):g} A, bandwidth {amp.si('bandwidth'):g} Hz"
        )
        if not isinstance(a, ReactionWheel):
            text += f", K_t = {amp.si('torque_constant'):g} N m/A"
        parts.append(text)
    if hardware.delay:
        parts.append(f"computation delay {float(hardware.delay):g} samples")
    return "; ".join(parts) if parts else "ideal (no hardware)"


def hardware_html(rows: dict[str, str]) -> str:
    """The report's section naming each run's hardware."""
    from html import escape

    from flexsat.report.page import html_table

    if not rows:
        return ""
    table = html_table(["run", "hardware"], [[escape(k), escape(v)] for k, v in rows.items()])
    return f"<h2>Hardware</h2>\n{table}"


class ProfilePoint(SchemaSection):
    angle: Annotated[float, in_unit("rad")]
    torque: Annotated[float, in_unit("N*m")]


class CableSpec(BuildableSection):
    """The cable spring on the hub (module docstring): a ``constant`` torque T_D, a linear
    ``stiffness`` k about ``center`` θ_c, and a tabulated ``profile`` of (angle, torque)
    points, angles increasing, held at its end values outside them."""

    constant: Annotated[float | None, in_unit("N*m")] = None
    stiffness: Annotated[float | None, in_unit("N*m/rad")] = None
    center: Annotated[float | None, in_unit("rad")] = None
    profile: list[ProfilePoint] = Field(default_factory=list, max_length=limits.MAX_SAMPLES)

    def build(self) -> CableSpring:
        values = given_fields(self, exclude={"profile", "output"})
        try:
            return CableSpring(
                **values,
                angles=tuple(p.angle for p in self.profile),
                torques=tuple(p.torque for p in self.profile),
            )
        except FieldError as exc:
            field = "profile" if exc.field in ("angles", "torques") else exc.field
            raise FieldError(field, exc.rule) from None


class ChannelCableSpec(CableSpec):
    """A cable spring on an input channel of a simulation scenario's plant
    (``disturbances.<channel>.cable``): the fields of :class:`CableSpec` and the ``output``
    channel of the angle that drives it (default ``theta``)."""

    output: str = "theta"


def effective_hardware(
    document: HardwareSpec | None, run: HardwareSpec | None
) -> HardwareSpec | None:
    """A run's hardware section: its own, else the document's."""
    return run if run is not None else document


__all__ = [
    "HARDWARE_PRESETS",
    "AmplifierSpec",
    "CableSpec",
    "ChannelCableSpec",
    "FilterSpec",
    "HardwareSpec",
    "ProfilePoint",
    "WheelArraySpec",
    "WheelSpec",
    "check_hardware",
    "describe_hardware",
    "effective_hardware",
    "hardware_html",
]
