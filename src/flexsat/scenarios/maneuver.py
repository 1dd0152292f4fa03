"""YAML scenarios: schema, validation with field-path messages, and the run loop.

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

Validation runs in two stages, both before any simulation, and each collects all its problems
into one :class:`ScenarioError` whose lines read ``field.path: rule``:

1. :func:`load_scenario` -- YAML syntax, the schema (unknown keys, types, units, finite numbers)
   and each section's own rules (its runtime object is built to check them);
2. :func:`prepare_scenario` -- what needs the case: the case model (positive masses, stiffnesses
   and inertias), the references and the controllers (gain admissibility).
"""

from __future__ import annotations

import dataclasses
import functools
import math
import re
import typing
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Annotated, Any, Callable, Literal, get_args

import numpy as np
import xarray as xr
import yaml
from pydantic import (
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Field,
    PrivateAttr,
    ValidationError,
    ValidationInfo,
    field_validator,
    model_validator,
)

from flexsat import limits
from flexsat.cases import CASES, get_case
from flexsat.limits import is_integral
from flexsat.control import (
    PD,
    Controller,
    LQGController,
    LyapunovRegulator,
    LyapunovTracker,
    refine_estimator,
)
from flexsat.dynamics.hub_appendage import HubAppendage
from flexsat.dynamics.hybrid import HybridPlant
from flexsat.maneuvers import BangBang, PseudoSquare, Sinusoidal, SmoothBangBang
from flexsat.sim import (
    BearingFriction,
    Impulses,
    RandomTorque,
    Sensors,
    SimConfig,
    SimResult,
    SimulationDiverged,
    TorqueActuator,
    simulate,
)
from flexsat.sim.engine import check_resources
from flexsat.units import to_si

DEFAULT_SCENARIO = "tamu_default.yaml"  # package data of flexsat.cases


class ScenarioError(ValueError):
    """An invalid scenario.

    Parameters
    ----------
    problems : list of str
        One ``field.path: rule`` message per problem; the exception message lists them all.
    """

    def __init__(self, problems):
        self.problems = list(problems)
        count = "1 problem" if len(self.problems) == 1 else f"{len(self.problems)} problems"
        super().__init__(f"invalid scenario ({count}):" + "".join(f"\n  {p}" for p in self.problems))


# -- messages ----------------------------------------------------------------------------------
_HEAD = re.compile(r"^([A-Za-z_][\w.]*): ")


def _head(message: str) -> str | None:
    """The field a ``"field: rule"`` message names, or None."""
    match = _HEAD.match(message)
    return match.group(1) if match else None


def _locate(path: str, message: str) -> str:
    """Prefix ``message`` with the field path ``path`` (``""`` is the scenario itself).

    A message that starts with a field name (``"g1: must be >= 0"``) gets the name appended to the
    path unless the path already ends with it.
    """
    head = _head(message)
    if head is None:
        return f"{path or 'scenario'}: {message}"
    if path == head or path.endswith("." + head):
        return path + message[len(head):]
    return f"{path}.{message}" if path else message


def _item(index: int, label) -> str:
    """Path element of list item ``index``; runs are named by their label."""
    return f"[{label!r}]" if isinstance(label, str) else f"[{index}]"


def _loc_path(loc: tuple, data) -> str:
    """Dotted field path of a pydantic error location, runs named by their label in ``data``."""
    path, node = "", data
    for key in loc:
        if isinstance(key, int):
            node = node[key] if isinstance(node, list) and 0 <= key < len(node) else None
            path += _item(key, node.get("label") if isinstance(node, dict) else None)
        else:
            path = f"{path}.{key}" if path else str(key)
            node = node.get(key) if isinstance(node, dict) else None
    return path


def _models_in(annotation) -> list[type[BaseModel]]:
    """The schema models inside a field annotation (``X | None``, ``list[X]``, ...)."""
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return [annotation]
    return [m for arg in get_args(annotation) for m in _models_in(arg)]


def _allowed_keys(loc: tuple, root: type[BaseModel]) -> str:
    """The keys allowed beside the unknown key at ``loc`` of a ``root`` document."""
    model = root
    for key in loc[:-1]:
        if isinstance(key, str):
            model = _models_in(model.model_fields[key].annotation)[0]
    return ", ".join(model.model_fields)


def _problem(error: dict, data, root: type[BaseModel] | None = None) -> str:
    """One message line for a pydantic error dict of a ``root`` document (default Scenario)."""
    cause = error.get("ctx", {}).get("error")
    if error["type"] == "extra_forbidden":
        message = f"unknown key (allowed: {_allowed_keys(error['loc'], root or Scenario)})"
    else:
        message = str(cause) if isinstance(cause, Exception) else error["msg"]
    return _locate(_loc_path(error["loc"], data), message)


# -- quantities --------------------------------------------------------------------------------
def _converter(unit: str) -> Callable:
    """Before-validator converting a quantity to SI (None passes through for optional fields)."""

    def convert(value, info: ValidationInfo):
        if value is None:
            return None
        field = info.field_name
        if isinstance(value, bool):
            raise ValueError(f"{field}: expected a number or a quantity such as '1 {unit}'")
        return to_si(value, unit, field)

    return convert


def quantity(unit: str, optional: bool = False):
    """Field type of a quantity in ``unit``, stored as its SI float.

    Parameters
    ----------
    unit : str
        Expected unit; a bare number is taken in it, ``""`` is dimensionless.
    optional : bool
        Accept ``None`` (the key left out).
    """
    return Annotated[float | None if optional else float, BeforeValidator(_converter(unit))]


def count(minimum: int = 1, maximum: int | None = None, optional: bool = False):
    """Field type of an integer in [minimum, maximum]; a float with an integral value (``1e3``)
    is accepted, bools and fractions are not.

    Parameters
    ----------
    minimum, maximum : int
        Inclusive bounds (``maximum`` None: no upper bound).
    optional : bool
        Accept ``None`` (the key left out).
    """
    rule = f"an integer in [{minimum}, {maximum}]" if maximum is not None else \
        f"an integer >= {minimum}"

    def check(value, info: ValidationInfo):
        if value is None and optional:
            return None
        if not is_integral(value) or value < minimum or (maximum is not None and value > maximum):
            raise ValueError(f"{info.field_name}: must be {rule}, got {value!r}")
        return int(value)

    return Annotated[int | None if optional else int, BeforeValidator(check)]


def _given(section: BaseModel, exclude=()) -> dict[str, Any]:
    """The fields of ``section`` that were set (not None), as keyword arguments."""
    return section.model_dump(exclude_none=True, exclude=set(exclude))


# -- schema ------------------------------------------------------------------------------------
class _Section(BaseModel):
    """Base of every schema model: unknown keys are errors."""

    model_config = ConfigDict(extra="forbid")


class _Document(_Section):
    """A whole scenario file: remembers the text it was loaded from."""

    _source: str | None = PrivateAttr(default=None)
    _folder: Path | None = PrivateAttr(default=None)

    @property
    def folder(self) -> Path:
        """The folder of the scenario file (relative paths in it start there), else the
        working directory."""
        return self._folder if self._folder is not None else Path.cwd()

    @property
    def yaml_text(self) -> str:
        """The scenario as YAML: the text it was loaded from, else a dump (SI numbers)."""
        if self._source is not None:
            return self._source
        return yaml.safe_dump(self.model_dump(exclude_none=True), sort_keys=False)


class _Buildable(_Section):
    """A section that maps onto a runtime object; building it checks the runtime's own rules."""

    def build(self):
        raise NotImplementedError

    @model_validator(mode="after")
    def _buildable(self):
        self.build()
        return self


class ModelSpec(_Section):
    """Model options, forwarded to the case builder as overrides."""

    n_modes: int | None = None  # the builder checks it (positive, at most flexsat.limits.MAX_MODES)
    stiffening: bool | None = None


#: largest slew of a maneuver scenario, rad (ten turns)
MAX_SLEW = 20 * math.pi


class ManeuverSpec(_Section):
    """The slew: ``angle`` (rad), from rest at 0, at most ten turns either way."""

    angle: quantity("rad")

    @field_validator("angle")
    @classmethod
    def _sensible(cls, angle: float) -> float:
        if abs(angle) > MAX_SLEW:
            raise ValueError(f"angle: a slew of at most ten turns ({MAX_SLEW:.4g} rad) either "
                             f"way, got {angle:.4g} rad")
        return angle


class SimulationSpec(_Buildable):
    """Run length and sampling; ``integration_step`` sets the substeps per control period."""

    duration: quantity("s")
    control_rate: quantity("Hz", optional=True) = None
    integration_step: quantity("s", optional=True) = None
    settling_band: quantity("rad", optional=True) = None
    seed: count(0, limits.MAX_SEED, optional=True) = None

    def build(self, **components) -> SimConfig:
        """The :class:`SimConfig`; ``components`` are its actuator, sensors and disturbances."""
        config = SimConfig(**_given(self, exclude={"integration_step"}), **components)
        if self.integration_step is None:
            return config
        return dataclasses.replace(config, substeps=self._substeps(config.dt))

    def _substeps(self, period: float) -> int:
        step = self.integration_step
        if step <= 0:
            raise ValueError(f"integration_step: must be > 0, got {step:g} s")
        if step >= period:
            raise ValueError(
                f"integration_step: must be smaller than the control period 1/control_rate = "
                f"{1e3 * period:.4g} ms, got {1e3 * step:.4g} ms"
            )
        return math.ceil(period / step - 1e-9)


class ActuatorSpec(_Buildable):
    saturation: quantity("N*m", optional=True) = None
    torque_constant_ratio: quantity("", optional=True) = None

    @field_validator("torque_constant_ratio")
    @classmethod
    def _sensible(cls, ratio: float | None) -> float | None:
        # actual / nominal torque constant: a motor off by more than 10x is a different motor
        if ratio is not None and ratio > 10:
            raise ValueError(f"torque_constant_ratio: actual / nominal torque constant, at most "
                             f"10, got {ratio:g}")
        return ratio

    def build(self) -> TorqueActuator:
        return TorqueActuator(**_given(self))


class SensorsSpec(_Buildable):
    encoder_resolution: quantity("rad", optional=True) = None
    rate: Literal["ideal", "ls_filter", "gyro"] | None = None
    # a least-squares rate over at most 1,000 samples, a polynomial of at most order 10
    rate_window: count(1, 1000, optional=True) = None
    rate_order: count(0, 10, optional=True) = None
    gyro_noise: quantity("rad/s", optional=True) = None
    strain_noise: quantity("N*m", optional=True) = None

    def build(self) -> Sensors:
        return Sensors(**_given(self))


class FrictionSpec(_Buildable):
    coulomb: quantity("N*m", optional=True) = None
    viscous: quantity("N*m*s/rad", optional=True) = None
    smoothing: quantity("rad/s", optional=True) = None

    def build(self) -> BearingFriction:
        return BearingFriction(**_given(self))


class ImpulseSpec(_Section):
    time: quantity("s")
    impulse: quantity("N*m*s")


class DisturbancesSpec(_Buildable):
    """Bearing friction, random torque (1 sigma, N m) and angular impulses on the hub."""

    friction: FrictionSpec = Field(default_factory=FrictionSpec)
    random_torque: quantity("N*m", optional=True) = None
    impulses: list[ImpulseSpec] = Field(default_factory=list, max_length=limits.MAX_SAMPLES)

    def build(self) -> dict[str, Any]:
        """Keyword arguments ``friction``, ``random_torque``, ``impulses`` of :class:`SimConfig`."""
        try:
            random = RandomTorque(*(() if self.random_torque is None else (self.random_torque,)))
        except ValueError as exc:
            raise ValueError(str(exc).replace("std:", "random_torque:", 1)) from None
        impulses = Impulses(tuple(i.time for i in self.impulses),
                            tuple(i.impulse for i in self.impulses))
        return {"friction": self.friction.build(), "random_torque": random, "impulses": impulses}


class GainsSpec(_Section):
    """Feedback gains: g1, g2, g3 (Lyapunov laws) or kp, kd (PD)."""

    g1: quantity("N*m/rad", optional=True) = None
    g2: quantity("N*m*s/rad", optional=True) = None
    g3: quantity("", optional=True) = None
    kp: quantity("N*m/rad", optional=True) = None
    kd: quantity("N*m*s/rad", optional=True) = None


class PolesSpec(_Section):
    """Rigid closed-loop poles of a PD law; ``natural_frequency`` in Hz or rad/s (a bare
    number is rad/s; :func:`flexsat.units.to_si` applies the 2π between the two)."""

    natural_frequency: quantity("rad/s")
    damping_ratio: quantity("")


class LQGSpec(_Section):
    """Weights and noise intensities of an LQG law on the plant's modal state
    x = [θ, q, θ', q'] with measurements (θ, θ') (seed 001 Eqs. 38-53).

    ``mode_weights`` (one per retained mode, or one for all) weight q_i and q'_i alike;
    ``process_noise`` is the intensity of a torque disturbance (Q_xx = B·qn·Bᵀ, Eq. 43);
    ``refine``: "weighted" recomputes the filter with Q_xx = Kᵀ Bᵀ B K (Eq. 52), "truncated"
    also zeroes the gains of the modes beyond ``keep_modes`` first (Eq. 53).
    """

    rigid_weight: quantity("") = 1.0
    mode_weights: list[Annotated[float, BeforeValidator(_converter(""))]] | float = 0.1
    control_weight: quantity("")
    sensor_noise: list[Annotated[float, BeforeValidator(_converter(""))]]
    process_noise: quantity("")
    refine: Literal["none", "weighted", "truncated"] = "none"
    keep_modes: count(0, limits.MAX_MODES, optional=True) = None

    @model_validator(mode="after")
    def _truncation(self):
        if self.refine == "truncated" and self.keep_modes is None:
            raise ValueError("keep_modes: required by refine 'truncated'")
        if len(self.sensor_noise) != 2:
            raise ValueError(f"sensor_noise: give the (θ, θ') intensities, got "
                             f"{len(self.sensor_noise)} values")
        return self


_SHAPES = {"bang_bang": BangBang, "smooth_bang_bang": SmoothBangBang,
           "pseudo_square": PseudoSquare, "sinusoidal": Sinusoidal}
_SHAPE_PARAMETERS = {"smooth_bang_bang": ("alpha",), "pseudo_square": ("rise_time",)}


class ReferenceSpec(_Section):
    """Rigid reference maneuver: a torque shape with any two of u_max, duration and its own
    parameter (one of u_max, duration for bang_bang and sinusoidal)."""

    shape: Literal[tuple(_SHAPES)]
    u_max: quantity("N*m", optional=True) = None
    duration: quantity("s", optional=True) = None
    alpha: quantity("", optional=True) = None
    rise_time: quantity("s", optional=True) = None

    @model_validator(mode="after")
    def _shape_parameters(self):
        own = _SHAPE_PARAMETERS.get(self.shape, ())
        for name in ("alpha", "rise_time"):
            if getattr(self, name) is not None and name not in own:
                raise ValueError(f"{name}: not a parameter of shape {self.shape!r}")
        return self

    def build(self, angle: float, inertia: float):
        """The torque shape slewing ``angle`` (rad) with the rigid ``inertia`` (kg m²)."""
        return _SHAPES[self.shape](angle, inertia, **_given(self, exclude={"shape"}))


@dataclass(frozen=True)
class _CaseContext:
    """What the controllers need from the case and the maneuver."""

    angle: float
    reference_inertia: float
    appendage_inertia: float
    n_appendages: int
    plant: Any = None
    dt: float = 0.0


def _regulator(run: "RunSpec", ctx: _CaseContext, reference) -> Controller:
    return LyapunovRegulator(**_given(run.gains), target=ctx.angle, n_appendages=ctx.n_appendages)


def _tracker(run: "RunSpec", ctx: _CaseContext, reference) -> Controller:
    return LyapunovTracker(reference, **_given(run.gains), appendage_inertia=ctx.appendage_inertia,
                           n_appendages=ctx.n_appendages)


def _pd(run: "RunSpec", ctx: _CaseContext, reference) -> Controller:
    options = {"target": ctx.angle, "reference": reference}
    if run.feedforward is not None:
        options["feedforward"] = run.feedforward
    if run.poles is None:
        return PD(**_given(run.gains), **options)
    return PD.from_rigid_poles(ctx.reference_inertia, run.poles.natural_frequency,
                               run.poles.damping_ratio, **options)


def _lqg(run: "RunSpec", ctx: _CaseContext, reference) -> Controller:
    spec, plant = run.lqg, ctx.plant
    A, B, _ = plant.state_space
    n, k = plant.ndof, plant.ndof - 1
    C = np.zeros((2, 2 * n))
    C[0, 0] = C[1, n] = 1.0
    modes = np.broadcast_to(np.asarray(spec.mode_weights, float), (k,)) if np.ndim(
        spec.mode_weights) == 0 or len(spec.mode_weights) == k else None
    if modes is None:
        raise ValueError(f"lqg.mode_weights: give one weight or one per mode ({k}), got "
                         f"{len(spec.mode_weights)}")
    per_dof = np.concatenate([[spec.rigid_weight], modes])
    Q = np.diag(np.concatenate([per_dof, per_dof]))
    R = np.array([[spec.control_weight]])
    Rn = np.diag(spec.sensor_noise)
    options = dict(target=ctx.angle, reference=reference)
    law = LQGController.design((A, B[:, None], C), Q, R, spec.process_noise, Rn, ctx.dt, **options)
    if spec.refine == "none":
        return law
    keep_modes = k if spec.refine == "weighted" else min(spec.keep_modes, k)
    kept = np.r_[0, 1:keep_modes + 1, n, n + 1:n + keep_modes + 1]
    refined = refine_estimator(A, B[:, None], C, law.K, kept, Rn,
                               truncate=spec.refine == "truncated")
    return LQGController(A, B[:, None], C, refined.gain, refined.filter.gain, ctx.dt, **options)


@dataclass(frozen=True)
class _Law:
    gains: tuple[str, ...]
    required: tuple[str, ...]
    reference: Literal["required", "optional", "forbidden"]
    build: Callable[["RunSpec", _CaseContext, Any], Controller]
    pd_options: bool = False


_LAWS = {
    "lyapunov_regulator": _Law(("g1", "g2", "g3"), ("g1", "g2"), "forbidden", _regulator),
    "lyapunov_tracker": _Law(("g1", "g2", "g3"), ("g1", "g2"), "required", _tracker),
    "pd": _Law(("kp", "kd"), ("kp", "kd"), "optional", _pd, pd_options=True),
    "lqg": _Law((), (), "optional", _lqg),
}


class RunSpec(_Section):
    """One closed-loop run.

    ``law`` is ``lyapunov_regulator`` (gains g1, g2, g3), ``lyapunov_tracker`` (same gains and a
    ``reference``) or ``pd`` (gains kp, kd or ``poles``; with a ``reference`` it tracks it,
    feeding its torque forward unless ``feedforward: false``).
    """

    label: str
    law: Literal[tuple(_LAWS)]
    gains: GainsSpec | None = None
    poles: PolesSpec | None = None
    reference: ReferenceSpec | None = None
    feedforward: bool | None = None
    lqg: LQGSpec | None = None

    @model_validator(mode="after")
    def _law_inputs(self):
        law = _LAWS[self.law]
        given = _given(self.gains) if self.gains is not None else {}
        for name in given:
            if name not in law.gains:
                raise ValueError(f"gains.{name}: not a gain of law {self.law!r} "
                                 f"(its gains: {', '.join(law.gains)})")
        for name in ("poles", "feedforward"):
            if getattr(self, name) is not None and not law.pd_options:
                raise ValueError(f"{name}: only for law 'pd'")
        if (self.lqg is None) != (self.law != "lqg"):
            raise ValueError("lqg: required by law 'lqg' and only for it")
        if self.poles is not None and self.gains is not None:
            raise ValueError("gains: give gains or poles, not both")
        missing = [g for g in law.required if g not in given]
        if self.poles is None and missing:
            raise ValueError(f"gains.{missing[0]}: required by law {self.law!r}"
                             + (" (or give poles)" if law.pd_options else ""))
        if law.reference == "required" and self.reference is None:
            raise ValueError(f"reference: required by law {self.law!r}")
        if law.reference == "forbidden" and self.reference is not None:
            raise ValueError(f"reference: law {self.law!r} tracks no reference "
                             "(use lyapunov_tracker)")
        return self


class Scenario(_Document):
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
    runs: list[RunSpec] = Field(min_length=1, max_length=limits.MAX_RUNS)

    @field_validator("case")
    @classmethod
    def _known_case(cls, name: str) -> str:
        get_case(name)
        if name not in maneuver_cases():
            raise ValueError(f"case: {name!r} has no maneuver model (a hub plant to slew); "
                             f"cases with one: {', '.join(maneuver_cases())}")
        return name

    @field_validator("case_overrides")
    @classmethod
    def _finite_overrides(cls, overrides: dict) -> dict:
        for key, value in overrides.items():
            if _non_finite(value):
                raise ValueError(f"{key}: must be a finite number, got {value!r}")
        return overrides

    @model_validator(mode="after")
    def _consistent(self):
        for name in _given(self.model):
            if name in self.case_overrides:
                raise ValueError(f"model.{name}: also given in case_overrides; give it once")
        labels = [run.label for run in self.runs]
        for label in labels:
            if labels.count(label) > 1:
                raise ValueError(f"runs: duplicate label {label!r}; each run needs its own label")
        return self

    @property
    def case_parameters(self) -> dict[str, Any]:
        """Keyword arguments of the case builder: ``case_overrides`` and the ``model`` options."""
        return {**self.case_overrides, **_given(self.model)}

    def sim_config(self) -> SimConfig:
        """The :class:`SimConfig` shared by every run."""
        return self.simulation.build(actuator=self.actuator.build(), sensors=self.sensors.build(),
                                     **self.disturbances.build())



@functools.cache
def maneuver_cases() -> tuple[str, ...]:
    """The cases a maneuver scenario can simulate: their builder's case has a ``model()`` that
    gives a hub plant (:class:`flexsat.dynamics.hybrid.HybridPlant`), read from the type hints so
    that no case is built."""
    names = []
    for name, info in CASES.items():
        model = getattr(typing.get_type_hints(info.builder).get("return"), "model", None)
        plant = typing.get_type_hints(model).get("return") if callable(model) else None
        if isinstance(plant, type) and issubclass(plant, HybridPlant):
            names.append(name)
    return tuple(names)


def _non_finite(value) -> bool:
    """True for NaN and infinities, given as numbers or as bare strings ("nan", "inf")."""
    if isinstance(value, bool):
        return False
    try:
        return not math.isfinite(float(value))
    except (TypeError, ValueError):
        return False


# -- loading -----------------------------------------------------------------------------------
def _file_of(source) -> Path | None:
    """The file a source names: a Path, or a one-line string that ends in ``.yaml``/``.yml`` or
    names an existing file; None for the text itself."""
    if isinstance(source, Path):
        return source
    if not isinstance(source, str) or "\n" in source:
        return None
    try:
        return Path(source) if source.endswith((".yaml", ".yml")) or Path(source).is_file() \
            else None
    except (OSError, ValueError):  # too long or otherwise impossible as a file name: text
        return None


def _read(source: str | bytes | Path) -> str:
    """Scenario text from a file (:func:`_file_of`) or as given (bytes are decoded as UTF-8);
    at most :data:`flexsat.limits.MAX_DOCUMENT_BYTES`."""
    name = "scenario: the document"
    if _file_of(source) is not None:
        name = f"scenario: {str(source)!r}"
        try:
            with open(source, "rb") as file:
                source = file.read(limits.MAX_DOCUMENT_BYTES + 1)
        except OSError as exc:
            raise ScenarioError([f"scenario: cannot read {str(source)!r} ({exc.strerror})"]
                                ) from None
    if isinstance(source, bytes):
        try:
            source = source.decode("utf-8")
        except UnicodeDecodeError as exc:
            if len(source) <= limits.MAX_DOCUMENT_BYTES:
                raise ScenarioError([f"{name} is not UTF-8 text (byte 0x{source[exc.start]:02x} "
                                     f"at offset {exc.start}); save it as UTF-8"]) from None
    if len(source) > limits.MAX_DOCUMENT_BYTES:
        raise ScenarioError([f"{name} is larger than {limits.MAX_DOCUMENT_BYTES:,} bytes "
                             "(flexsat.limits.MAX_DOCUMENT_BYTES); a scenario is a few kB"])
    return source


class _Loader(yaml.SafeLoader):
    """YAML's safe loader, refusing as it composes nesting deeper than
    :data:`flexsat.limits.MAX_NESTING` (PyYAML recurses once per level) and more than
    :data:`flexsat.limits.MAX_DOCUMENT_NODES` values."""

    def __init__(self, stream):
        super().__init__(stream)
        self._depth = self._nodes = 0

    def compose_node(self, parent, index):
        self._depth += 1
        self._nodes += 1
        try:
            line = self.peek_event().start_mark.line + 1
            if self._depth > limits.MAX_NESTING:
                raise ScenarioError([f"scenario: nested deeper than {limits.MAX_NESTING} levels "
                                     f"at line {line} (flexsat.limits.MAX_NESTING)"])
            if self._nodes > limits.MAX_DOCUMENT_NODES:
                raise ScenarioError([f"scenario: more than {limits.MAX_DOCUMENT_NODES:,} values "
                                     f"(at line {line}; flexsat.limits.MAX_DOCUMENT_NODES)"])
            return super().compose_node(parent, index)
        finally:
            self._depth -= 1


_MERGE = "tag:yaml.org,2002:merge"


def _check_nodes(node, path: str, loader: _Loader, sizes: dict, open_: set) -> int:
    """Number of values under ``node`` with aliases expanded; refuses duplicate keys (the last
    would silently win), recursive aliases and more than MAX_DOCUMENT_NODES values."""
    if id(node) in sizes:
        return sizes[id(node)]
    if id(node) in open_:
        raise ScenarioError([f"{path or 'scenario'}: an alias refers to the value that "
                             "contains it (recursive anchor)"])
    open_.add(id(node))
    size = 1
    if isinstance(node, yaml.MappingNode):
        lines: dict = {}
        for key_node, value_node in node.value:
            key = loader.construct_object(key_node) if isinstance(key_node, yaml.ScalarNode) \
                and key_node.tag != _MERGE else None
            here = f"{path}.{key}" if path else str(key)
            line = key_node.start_mark.line + 1
            if key is not None and key in lines:
                raise ScenarioError([f"{here}: duplicate key (lines {lines[key]} and {line}); "
                                     "give it once"])
            if key is not None:
                lines[key] = line
            size += (_check_nodes(key_node, here, loader, sizes, open_)
                     + _check_nodes(value_node, here, loader, sizes, open_))
    elif isinstance(node, yaml.SequenceNode):
        size += sum(_check_nodes(item, f"{path}[{i}]", loader, sizes, open_)
                    for i, item in enumerate(node.value))
    open_.discard(id(node))
    if size > limits.MAX_DOCUMENT_NODES:
        raise ScenarioError([f"{path or 'scenario'}: more than {limits.MAX_DOCUMENT_NODES:,} "
                             "values once aliases are expanded (flexsat.limits."
                             "MAX_DOCUMENT_NODES)"])
    sizes[id(node)] = size
    return size


def _parse(text: str):
    """The YAML document, checked for nesting, duplicate keys and expanded size first."""
    loader = None
    try:
        loader = _Loader(text)  # its reader refuses non-printable characters
        node = loader.get_single_node()
        if node is None:
            return None
        _check_nodes(node, "", loader, {}, set())
        return loader.construct_document(node)
    except yaml.YAMLError as exc:
        raise ScenarioError([f"yaml: {exc}"]) from None
    finally:
        if loader is not None:
            loader.dispose()


def load_scenario(source: str | bytes | Path):
    """Parse and validate a scenario (stage 1: YAML, schema, units, section rules).

    ``kind: maneuver`` (the default) gives a :class:`Scenario`; ``kind: identification`` an
    :class:`flexsat.scenarios.identification.IdentificationScenario`.

    Parameters
    ----------
    source : str, bytes or Path
        A path to a YAML file, or the YAML text itself (bytes: UTF-8).

    Raises
    ------
    ScenarioError
        Listing every problem found, each as ``field.path: rule``.
    """
    text = _read(source)
    data = _parse(text)
    if not isinstance(data, dict):
        raise ScenarioError(["scenario: must be a YAML mapping (name, case, simulation, runs, ...)"])
    kind = data.get("kind", "maneuver")
    if kind == "identification":
        from flexsat.scenarios.identification import IdentificationScenario as model
    elif kind == "maneuver":
        model = Scenario
    else:
        raise ScenarioError([f"kind: must be 'maneuver' or 'identification', got {kind!r}"])
    try:
        scenario = model.model_validate(data)
    except ValidationError as exc:
        raise ScenarioError([_problem(e, data, model) for e in exc.errors()]) from None
    scenario._source = text
    if _file_of(source) is not None:
        scenario._folder = Path(source).resolve().parent
    return scenario


def default_scenario() -> Scenario:
    """The embedded default: the TAMU 40 deg slew, Law I against Law II (``flexsat run``)."""
    return load_scenario(resources.files("flexsat.cases").joinpath(DEFAULT_SCENARIO).read_text())


# -- preparing and running ---------------------------------------------------------------------
@dataclass(frozen=True)
class ScenarioPlan:
    """A fully validated scenario, ready to run.

    Attributes
    ----------
    scenario : Scenario
    case : object
        The built case (e.g. :class:`flexsat.cases.tamu.TamuCase`).
    model : HubAppendage
    config : SimConfig
    controllers : dict of str to Controller
        One controller per run, by label, in the scenario's order.
    """

    scenario: Scenario
    case: Any
    model: HubAppendage
    config: SimConfig
    controllers: dict[str, Controller]


def _build_case(scenario: Scenario):
    """(case, model); problems are located in ``model`` or ``case_overrides``."""
    try:
        case = get_case(scenario.case).builder(**scenario.case_parameters)
        return case, case.model()
    except ValueError as exc:
        message = str(exc)
        head = _head(message)
        if head in _given(scenario.model):
            raise ScenarioError([_locate("model", message)]) from None
        if head in scenario.case_overrides:
            raise ScenarioError([_locate("case_overrides", message)]) from None
        raise ScenarioError([f"case_overrides: {message}"]) from None
    except (ArithmeticError, RuntimeError) as exc:
        # the model's numerics (overflow, root finding) fail on values far outside a physical
        # range that the case's own rules do not bound
        raise ScenarioError([f"case_overrides: the {scenario.case} model cannot be built from "
                             f"these values ({type(exc).__name__}: {exc}); give physically "
                             "sensible values"]) from None


def _build_controller(index: int, run: RunSpec, ctx: _CaseContext) -> Controller:
    """The run's controller; problems are located in the run's reference, gains or poles."""
    path = "runs" + _item(index, run.label)
    reference = None
    if run.reference is not None:
        try:
            reference = run.reference.build(ctx.angle, ctx.reference_inertia)
        except ValueError as exc:
            raise ScenarioError([_locate(path + ".reference", str(exc))]) from None
    try:
        return _LAWS[run.law].build(run, ctx, reference)
    except ValueError as exc:
        head = _head(str(exc))
        section = next((name for name, spec in (("gains", GainsSpec), ("poles", PolesSpec))
                        if head in spec.model_fields), None)
        raise ScenarioError([_locate(f"{path}.{section}" if section else path, str(exc))]) from None
    except (ArithmeticError, RuntimeError) as exc:
        raise ScenarioError([f"{path}: the {run.law} law cannot be designed from these values "
                             f"({type(exc).__name__}: {exc})"]) from None


def _collect(problems: list[str], build: Callable, *args):
    """``build(*args)``, or None with its ScenarioError problems appended to ``problems``."""
    try:
        return build(*args)
    except ScenarioError as exc:
        problems.extend(exc.problems)
        return None


def prepare_scenario(scenario: Scenario) -> ScenarioPlan:
    """Validate what needs the case (stage 2) and build the model and the controllers.

    Raises
    ------
    ScenarioError
        Listing every problem: case parameters, references, controller gains, and a run beyond
        the limits of :mod:`flexsat.limits` (substeps, integrator steps, memory).
    """
    problems: list[str] = []
    built = _collect(problems, _build_case, scenario)
    controllers: dict[str, Controller] = {}
    if built is not None:
        case, model = built
        ctx = _CaseContext(scenario.maneuver.angle, case.reference_inertia,
                           model.appendage_inertia, int(model.n_appendages), model,
                           scenario.sim_config().dt)
        for index, run in enumerate(scenario.runs):
            controllers[run.label] = _collect(problems, _build_controller, index, run, ctx)
    config = scenario.sim_config()
    if built is not None and not problems:
        _collect(problems, _check_resources, model, config, controllers)
    if problems:
        raise ScenarioError(problems)
    return ScenarioPlan(scenario, case, model, config, controllers)


#: the scenario field a resource message of :func:`flexsat.sim.engine.check_resources` blames
_RESOURCE_FIELDS = {"friction": "disturbances.friction", "duration": "simulation.duration",
                    "n_cases": "runs", "substeps": "simulation.integration_step"}


def _check_resources(model, config: SimConfig, controllers: dict[str, Controller]) -> None:
    """Refuse runs beyond :mod:`flexsat.limits`; every run's history is kept until the report
    is written, so the memory estimate counts the cases of all runs together."""
    try:
        check_resources(model, config, sum(c.n_cases for c in controllers.values()))
    except ValueError as exc:
        message, head = str(exc), _head(str(exc))
        located = _RESOURCE_FIELDS[head] + message[len(head):] if head in _RESOURCE_FIELDS \
            else f"simulation: {message}"
        raise ScenarioError([located]) from None


@dataclass(frozen=True)
class ScenarioResult:
    """The runs of a scenario.

    Attributes
    ----------
    scenario : Scenario
    labels : tuple of str
        Run labels, in the scenario's order.
    results : tuple of SimResult
        One single-case result per run (every run uses the same noise seed).
    case_source : str
        Where the case's data come from (:attr:`flexsat.cases.CaseInfo.source`).
    """

    scenario: Scenario
    labels: tuple[str, ...]
    results: tuple[SimResult, ...]
    case_source: str

    def metrics_records(self) -> list[dict]:
        """One JSON-ready dict per run: ``"run"`` (the label) and the metrics (NaN -> None)."""
        return [row for label, result in zip(self.labels, self.results)
                for row in result.metrics_records([label])]

    def dataset(self) -> xr.Dataset:
        """All runs in one dataset, dims (run, time); ``run`` holds the labels.

        Attributes: ``scenario_name``, ``case``, ``case_source``, ``scenario_yaml`` and those of
        the simulation (``control_rate_Hz``, ``settling_band_rad``).
        """
        runs = [r.dataset.isel(case=0, drop=True) for r in self.results]
        ds = xr.concat(runs, dim="run", data_vars="all", coords="minimal", compat="override",
                       join="exact", combine_attrs="override")
        ds = ds.assign_coords(run=("run", list(self.labels)))
        ds.attrs.update(scenario_name=self.scenario.name, case=self.scenario.case,
                        case_source=self.case_source, scenario_yaml=self.scenario.yaml_text)
        return ds


def run_scenario(scenario: Scenario, progress: Callable[[str], None] | None = None
                 ) -> ScenarioResult:
    """Validate the whole scenario, then simulate each run.

    Parameters
    ----------
    scenario : Scenario
    progress : callable, optional
        Called with each run's label just before it is simulated.

    Raises
    ------
    ScenarioError
        Before any run, if :func:`prepare_scenario` finds problems.
    SimulationDiverged
        If a run diverges (the message starts with the run, ``runs['Law I']: ...``); no result
        is returned.
    """
    plan = prepare_scenario(scenario)
    results = []
    for index, (label, controller) in enumerate(plan.controllers.items()):
        if progress is not None:
            progress(label)
        try:
            results.append(simulate(plan.model, controller, plan.config))
        except SimulationDiverged as exc:
            raise SimulationDiverged(f"runs{_item(index, label)}: {exc}", exc.cases, exc.time,
                                     exc.cause) from None
    return ScenarioResult(scenario, tuple(plan.controllers), tuple(results),
                          get_case(scenario.case).source)


__all__ = ["Scenario", "ScenarioError", "ScenarioPlan", "ScenarioResult", "default_scenario",
           "load_scenario", "prepare_scenario", "quantity", "run_scenario"]
