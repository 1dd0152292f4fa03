"""CMG scenarios (issue 14): ``kind: cmg``, gimbal steering of the SGCMG pyramid from chosen
initial sets under torque demands, and ``kind: cmg_station``, the space-station momentum
management with the CMG loop (Vadali, Oh & Walker; Junkins, Pollock & Rahman 1990, Att. 13)::

    kind: cmg
    name: Preferred gimbal angles, pseudo-inverse steering
    cluster: {skew: "54.74 deg", n_units: 4, steering: pi}
    runs:
      - {label: "x from zero", demand: [1, 0, 0], initial: zero, duration: "5 s"}
      - {label: "x preferred", demand: [1, 0, 0], initial: preferred, duration: "5 s"}
      - label: Kurokawa
        demand: {constant: [0, 0.3, 0], amplitude: [0.2, 0, 0], frequency: "2 Hz"}
        initial: ["-120 deg", "-60 deg", "60 deg", "120 deg"]
        duration: "20 s"
      - {label: reorient, reorient_to: alternate, initial: zero, duration: "10 s"}

A run's ``demand`` is the paper's torque demand T = ḣ of Eq. (5) in rotor momenta per second
(the spacecraft feels −ḣ): a constant 3-vector, or ``constant + amplitude · sin(2π f t)``.
``initial`` is ``zero``, ``alternate`` ([45, −45, 45, −45]°), ``preferred`` (the stored set for
the demand's direction, :data:`flexsat.dynamics.cmg.PREFERRED_SETS`, or the back integration for
another cluster) or n angles. ``null_motion: {target: ..., gain: "1 1/s"}`` runs the null motion
beside the torque law; ``reorient_to`` runs the null motion alone (§8.5, V8). ``cluster.steering``
``pi`` stops a run at the first singular set (and refuses to start on one), ``sr`` (with
``alpha``) steers through. ``cluster.gimbal_rate_limit`` flags runs whose gimbal rates exceed it.

    kind: cmg_station
    name: Space station, sigma(0) = 0 against [45, -45, 45, -45]
    lqr: {attitude: "1 deg", momentum: "2000 lbf*ft*s"}
    simulation: {orbits: 2, disturbance: aero_substitute}
    runs: [{label: zero, initial: zero}, {label: alternate, initial: alternate}]

The station defaults are the paper's Table 2; ``lqr`` holds the Bryson maxima and the filters
(:mod:`flexsat.cases.space_station_cmg`); ``initial: preferred`` there takes the stored set
nearest to the direction of the attitude loop's peak momentum.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Generator
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, Literal, Self

import numpy as np
from pydantic import Field, ValidationInfo, field_validator, model_validator

from flexsat import limits
from flexsat.dynamics.space_station import FT_LB as _FT_LB
from flexsat.input_checks import FieldError
from flexsat.report.page import ReportedResult
from flexsat.scenarios.errors import ScenarioError, item_path, locate
from flexsat.scenarios.fields import (
    Document,
    SchemaSection,
    check_unique_labels,
    in_unit,
    integer_in,
)
from flexsat.scenarios.kind import Run, ScenarioKind, Simulation

if TYPE_CHECKING:
    import xarray as xr

    from flexsat.cases.space_station_cmg import StationDesign, StationRun
    from flexsat.dynamics.cmg import GimbalRun
    from flexsat.dynamics.space_station import StationData
    from flexsat.units import FloatArray

SOURCE = (
    "S. R. Vadali, H.-S. Oh, S. R. Walker, 'Preferred Gimbal Angles for Single Gimbal "
    "Control Moment Gyros', JGCD (accepted); Junkins, Pollock & Rahman 1990, Attachment 13"
)
#: named initial sets
NAMED_SETS = ("zero", "alternate", "preferred")
ALTERNATE_DEG = (45.0, -45.0, 45.0, -45.0)
#: samples stored per run
N_OUT = 401


def _angles(value: object, field: str) -> str | list[float]:
    from flexsat.units import to_si_array

    if isinstance(value, str):
        if value not in NAMED_SETS:
            raise FieldError(
                field, f"must be one of {NAMED_SETS} or a list of angles, got {value!r}"
            )
        return value
    if not isinstance(value, list) or not value:
        raise FieldError(field, f"must be one of {NAMED_SETS} or a list of angles, got {value!r}")
    if any(isinstance(v, bool) or not isinstance(v, (int, float, str)) for v in value):
        raise FieldError(
            field, f"gimbal angles must be numbers or angles with units, got {value!r}"
        )
    out = np.array([to_si_array(v, "rad", field) for v in value], float)
    if out.shape != (len(value),):
        raise FieldError(field, f"each gimbal angle must be one value, got {value!r}")
    if not np.all(np.isfinite(out)):
        raise FieldError(field, f"angles must be finite, got {value!r}")
    return out.tolist()


#: largest demand component, rotor momenta per second: the whole envelope (~3 h) in 30 ms, far
#: beyond any gimbal motor; bounds the integrator's work (steps grow with |T| × duration)
MAX_DEMAND = 100.0
#: longest steering run, s (a constant unit demand saturates in ~3 s)
MAX_DURATION = 3600.0


def _vector3(value: object, field: str) -> list[float]:
    if isinstance(value, list) and any(isinstance(v, bool) for v in value):
        raise FieldError(field, f"must be three finite numbers, got {value!r}")
    try:
        v = np.asarray(value, float) if isinstance(value, list) else None
    except (TypeError, ValueError):
        v = None
    if v is None or v.shape != (3,) or not np.all(np.isfinite(v)):
        raise FieldError(field, f"must be three finite numbers, got {value!r}")
    if np.abs(v).max() > MAX_DEMAND:
        raise FieldError(
            field,
            f"components must be at most {MAX_DEMAND:g} rotor momenta per second, got {value!r}",
        )
    return v.tolist()


class Cluster(SchemaSection):
    """The SGCMG pyramid and its steering."""

    skew: Annotated[float, in_unit("rad", positive=True)] = float(np.deg2rad(54.74))
    n_units: Annotated[int, integer_in(3, 12)] = 4
    steering: Literal["pi", "sr"] = "pi"
    alpha: float = Field(1e-3, gt=0.0, allow_inf_nan=False)
    threshold: float = Field(1e-6, gt=0.0, allow_inf_nan=False)
    gimbal_rate_limit: Annotated[float | None, in_unit("rad/s", positive=True)] = None

    @field_validator("skew")
    @classmethod
    def _skew(cls, value: float) -> float:
        if not value < np.pi / 2:
            raise FieldError("skew", f"must lie in (0, 90°), got {np.rad2deg(value):.6g}°")
        return value


class HarmonicDemand(SchemaSection):
    """T(t) = constant + amplitude · sin(2π f t), rotor momenta per second."""

    constant: list[float]
    amplitude: list[float] = Field(default_factory=lambda: [0.0, 0.0, 0.0])
    frequency: Annotated[float, in_unit("Hz")] = 0.0

    @field_validator("frequency")
    @classmethod
    def _frequency(cls, value: float) -> float:
        if not 0.0 <= value <= 100.0:
            raise FieldError("frequency", f"must lie in [0, 100] Hz, got {value!r}")
        return value

    @field_validator("constant", "amplitude", mode="before")
    @classmethod
    def _three(cls, value: object, info: ValidationInfo) -> list[float]:
        return _vector3(value, info.field_name or "")


class NullMotion(SchemaSection):
    # a name or angles given as numbers or unit strings, read by _angles
    target: str | list[Any] = "preferred"
    gain: Annotated[float, in_unit("1/s", positive=True)] = 1.0

    @field_validator("target")
    @classmethod
    def _target(cls, value: object) -> str | list[float]:
        return _angles(value, "target")


class CmgRunSpec(SchemaSection):
    label: str
    initial: str | list[Any] = "zero"
    duration: Annotated[float, in_unit("s", positive=True)]
    demand: list[float] | HarmonicDemand | None = None

    @field_validator("duration")
    @classmethod
    def _duration(cls, value: float) -> float:
        if value > MAX_DURATION:
            raise FieldError("duration", f"at most {MAX_DURATION:g} s, got {value!r}")
        return value

    null_motion: NullMotion | None = None
    reorient_to: str | list[Any] | None = None

    @field_validator("initial", "reorient_to")
    @classmethod
    def _initial(cls, value: object, info: ValidationInfo) -> str | list[float] | None:
        return None if value is None else _angles(value, info.field_name or "")

    @field_validator("demand", mode="before")
    @classmethod
    def _demand(cls, value: object) -> object:
        return _vector3(value, "demand") if isinstance(value, list) else value

    @model_validator(mode="after")
    def _one_law(self) -> Self:
        if (self.demand is None) == (self.reorient_to is None):
            raise FieldError(
                "demand", "give a torque demand or reorient_to (null motion alone), one of them"
            )
        if self.reorient_to is not None and self.null_motion is not None:
            raise FieldError("null_motion", "not with reorient_to (that is the null motion)")
        uses_direction = "preferred" in (self.initial, self.reorient_to) or (
            self.null_motion is not None and self.null_motion.target == "preferred"
        )
        if uses_direction and self.demand_direction() is None:
            raise FieldError("initial", "'preferred' needs a demand with a nonzero mean direction")
        return self

    def demand_direction(self) -> np.ndarray | None:
        if self.demand is None:
            return None
        d = np.asarray(self.demand if isinstance(self.demand, list) else self.demand.constant)
        return None if not np.any(d) else d


class CmgScenario(Document):
    """A validated ``kind: cmg`` scenario (module docstring)."""

    kind: Literal["cmg"]
    name: str
    cluster: Cluster = Field(default_factory=Cluster)
    runs: list[CmgRunSpec] = Field(min_length=1, max_length=limits.MAX_RUNS)

    @model_validator(mode="after")
    def _checks(self) -> Self:
        check_unique_labels(self.runs)
        for run in self.runs:
            for value in (
                run.initial,
                run.reorient_to,
                None if run.null_motion is None else run.null_motion.target,
            ):
                if isinstance(value, list) and len(value) != self.cluster.n_units:
                    raise FieldError(
                        f"runs[{run.label!r}]",
                        "gimbal sets need "
                        f"{self.cluster.n_units} angles (cluster.n_units), got "
                        f"{len(value)}",
                    )
            if "alternate" in (run.initial, run.reorient_to) and self.cluster.n_units != 4:
                raise FieldError(
                    f"runs[{run.label!r}]", "'alternate' is the 4-unit set [45, -45, 45, -45] deg"
                )
        return self


class StationSection(SchemaSection):
    inertia: list[Any] = Field(
        default_factory=lambda: ["5.28e6 slug*ft**2", "10.80e6 slug*ft**2", "58.57e6 slug*ft**2"]
    )
    orbit_rate: Annotated[float, in_unit("rad/s", positive=True)] = 0.0011
    rotor_momentum: Annotated[float, in_unit("N*m*s", positive=True)] = 3500.0 * _FT_LB


class LqrSection(SchemaSection):
    attitude: Annotated[float, in_unit("rad", positive=True)] = float(np.deg2rad(1.0))
    rate: Annotated[float, in_unit("rad/s", positive=True)] = float(np.deg2rad(0.02))
    momentum: Annotated[float, in_unit("N*m*s", positive=True)] = 2000.0 * _FT_LB
    momentum_integral: Annotated[float, in_unit("N*m*s**2", positive=True)] = 2e5 * _FT_LB
    pitch_filters: list[int] = Field(default_factory=lambda: [1, 2])
    roll_yaw_filters: list[int] = Field(default_factory=lambda: [2])


class StationSimulation(SchemaSection):
    orbits: float = Field(2.0, gt=0.0, le=50.0, allow_inf_nan=False)
    disturbance: Literal["design", "aero_substitute"] = "aero_substitute"
    initial_attitude: Annotated[float, in_unit("rad")] = float(np.deg2rad(1.0))
    threshold: float = Field(1e-6, gt=0.0, allow_inf_nan=False)


class StationRunSpec(SchemaSection):
    label: str
    initial: str | list[Any] = "zero"

    @field_validator("initial")
    @classmethod
    def _initial(cls, value: object) -> str | list[float]:
        value = _angles(value, "initial")
        if isinstance(value, list) and len(value) != 4:
            raise FieldError("initial", f"the station's pyramid has 4 gimbals, got {len(value)}")
        return value


class CmgStationScenario(Document):
    """A validated ``kind: cmg_station`` scenario (module docstring)."""

    kind: Literal["cmg_station"]
    name: str
    station: StationSection = Field(default_factory=StationSection)
    lqr: LqrSection = Field(default_factory=LqrSection)
    simulation: StationSimulation = Field(default_factory=StationSimulation)
    runs: list[StationRunSpec] = Field(min_length=1, max_length=limits.MAX_RUNS)

    @model_validator(mode="after")
    def _checks(self) -> Self:
        check_unique_labels(self.runs)
        self.build_data()
        return self

    def build_data(self) -> StationData:
        from flexsat.dynamics.space_station import StationData

        s = self.station
        return StationData(tuple(s.inertia), s.orbit_rate, s.rotor_momentum)


# -- running -------------------------------------------------------------------------------------
@dataclass(frozen=True)
class CmgRun:
    """One run: its gimbal history (:class:`flexsat.dynamics.cmg.GimbalRun`), the initial set,
    the demand direction (None for a reorientation), peak gimbal rate and the outcome."""

    label: str
    gimbals: GimbalRun
    sigma0: np.ndarray
    direction: np.ndarray | None
    peak_rate: float
    outcome: str
    internal: bool | None


def _resolve(value: str | list[Any], direction: FloatArray | None, cluster: Cluster) -> FloatArray:
    """The gimbal angles (rad) a run names: given angles, or the zero, alternate or preferred
    set (the preferred one for the demand ``direction``)."""
    from flexsat.cases import cmg_pyramid
    from flexsat.dynamics import cmg

    if isinstance(value, list):
        return np.array(value)
    if value == "zero":
        return np.zeros(cluster.n_units)
    if value == "alternate":
        return np.deg2rad(ALTERNATE_DEG)
    # 'preferred' is refused without a demand direction (CmgRunSpec._one_law)
    assert direction is not None
    paper = cluster.n_units == 4 and abs(cluster.skew - cmg.SKEW) < 1e-12
    return (
        cmg.preferred_set(direction)
        if paper
        else cmg_pyramid.preferred_angles(direction, cluster.skew, cluster.n_units)
    )


def _demand_function(demand: list[float] | HarmonicDemand | None) -> Callable[[float], FloatArray]:
    """The spacecraft torque −T(t) of a run's demand (a constant or a harmonic one)."""
    assert demand is not None  # a steering run has a demand (CmgRunSpec._one_law)
    if isinstance(demand, list):
        c = np.array(demand)
        return lambda t: -c
    c, a, f = np.array(demand.constant), np.array(demand.amplitude), demand.frequency
    return lambda t: -(c + a * np.sin(2.0 * np.pi * f * t))


def _steering_simulation(run: CmgRunSpec, cluster: Cluster, sigma0: np.ndarray) -> Simulation:
    """A torque-steering run from ``sigma0``: the pseudo-inverse (or SR) law on the gimbal
    cluster, stopped at the first singular set under ``pi``
    (:func:`flexsat.cases.cmg_pyramid.steering_simulation`)."""
    from flexsat.cases import cmg_pyramid

    null = run.null_motion
    alpha = cluster.alpha if cluster.steering == "sr" else 0.0
    plant, law, config, options = cmg_pyramid.steering_simulation(
        sigma0,
        _demand_function(run.demand),
        run.duration,
        skew=cluster.skew,
        n_units=cluster.n_units,
        n_out=N_OUT,
        alpha=alpha,
        threshold=cluster.threshold,
        stop_at_singular=cluster.steering == "pi",
        null_target=None
        if null is None
        else _resolve(null.target, run.demand_direction(), cluster),
        null_gain=1.0 if null is None else null.gain,
        null_alpha=alpha,
    )
    return Simulation(plant, law, config, options)


def _cmg_run(
    label: str,
    g: GimbalRun,
    sigma0: np.ndarray,
    direction: np.ndarray | None,
    cluster: Cluster,
    rates: np.ndarray,
) -> CmgRun:
    """The :class:`CmgRun` of a gimbal history ``g`` (:class:`flexsat.dynamics.cmg.GimbalRun`)
    and its recorded gimbal rates ``rates`` (n_t, n), the law's σ̇ at the samples (at a
    singular stop the rate there, which grows as the gain falls): its peak gimbal rate and
    outcome (the singularity met and its kind)."""
    from flexsat.dynamics import cmg

    internal = None
    if g.singular:
        k = int(np.argmin(g.gain))
        internal = bool(
            cmg.classify_singularity(
                g.sigma[k],
                cluster.skew,
                cluster.n_units,
                threshold=max(cluster.threshold, g.gain[k] * 1.000001),
            ).internal
        )
        outcome = ("internal singularity" if internal else "saturation") + (
            f" at t = {g.t[-1] if cluster.steering == 'pi' else g.t[k]:.4g} s"
        )
    else:
        outcome = "no singularity"
    return CmgRun(label, g, sigma0, direction, float(np.abs(rates).max()), outcome, internal)


@dataclass(frozen=True)
class CmgResult(ReportedResult):
    """Runs of a ``kind: cmg`` scenario and the V1–V8 table (:func:`validation_table`)."""

    scenario: CmgScenario
    runs: tuple[CmgRun, ...]
    table: tuple[tuple[str, str, float, float, str], ...]
    case_source: str = SOURCE
    notes: tuple[str, ...] = ()

    def metrics_records(self) -> list[dict[str, Any]]:
        from flexsat.dynamics import cmg

        c = self.scenario.cluster
        out = []
        for r in self.runs:
            g = r.gimbals
            rec = {
                "run": r.label,
                "singular": bool(g.singular),
                "internal": r.internal,
                "end_time_s": float(g.t[-1]),
                "min_gain": float(g.gain.min()),
                "final_gain": float(g.gain[-1]),
                "final_momentum_h": float(np.linalg.norm(g.h[-1])),
                "peak_gimbal_rate_rad_s": r.peak_rate,
            }
            rec["envelope_h"] = rec["final_momentum_along_demand_h"] = None  # reorientation
            if r.direction is not None:
                u = r.direction / np.linalg.norm(r.direction)
                rec["envelope_h"] = float(cmg.envelope(u, c.skew, c.n_units)[0])
                rec["final_momentum_along_demand_h"] = float(g.h[-1] @ u)
            if c.gimbal_rate_limit is not None:
                rec["rate_limit_exceeded"] = bool(r.peak_rate > c.gimbal_rate_limit)
            out.append(rec)
        return out

    def dataset(self) -> xr.Dataset:
        import xarray as xr

        n = self.scenario.cluster.n_units
        # a run stopped at a singular set holds fewer samples: NaN after its end
        width = max(r.gimbals.t.size for r in self.runs)

        def stacked(name: str) -> np.ndarray:
            out = []
            for r in self.runs:
                a = np.asarray(getattr(r.gimbals, name), float)
                pad = np.full((width - a.shape[0],) + a.shape[1:], np.nan)
                out.append(np.concatenate([a, pad]))
            return np.array(out)

        ds = xr.Dataset(
            {
                "time": (("run", "sample"), stacked("t"), {"units": "s"}),
                "gimbal_angles": (
                    ("run", "sample", "gimbal"),
                    stacked("sigma"),
                    {"units": "rad"},
                ),
                "momentum": (
                    ("run", "sample", "axis"),
                    stacked("h"),
                    {"units": "rotor momenta h"},
                ),
                "gain": (("run", "sample"), stacked("gain")),
                "initial_angles": (
                    ("run", "gimbal"),
                    np.array([r.sigma0 for r in self.runs]),
                    {"units": "rad"},
                ),
            },
            coords={
                "run": [r.label for r in self.runs],
                "gimbal": np.arange(1, n + 1),
                "axis": ["x", "y", "z"],
            },
        )
        ds["outcome"] = ("run", [r.outcome for r in self.runs])
        ds.attrs.update(
            scenario_name=self.scenario.name,
            case_source=self.case_source,
            scenario_yaml=self.scenario.yaml_text,
        )
        return ds

    def report_case(self) -> str:
        return "SGCMG pyramid"

    def figures(self, folder: Path, ds: xr.Dataset) -> list[str]:
        from flexsat.report.cmg import draw_cmg_figures

        return draw_cmg_figures(self, ds, folder)

    def sections(self, ds: xr.Dataset, figures: list[str]) -> str:
        from flexsat.report.cmg import cmg_sections

        return cmg_sections(self, self.metrics_records(), figures)


@functools.cache
def validation_table() -> tuple[tuple[str, str, float, float, str], ...]:
    """V1–V8 computed live: (id, quantity, published, computed, unit) rows (the validate rows of
    :mod:`flexsat.checks.cmg` share them). They depend on nothing the scenario gives, so they are
    computed once per process (1.9 s): a sweep or Monte Carlo of a cmg run would otherwise
    recompute them in every case."""
    from flexsat.cases import cmg_pyramid
    from flexsat.dynamics import cmg

    D = np.deg2rad
    x = np.array([-1.0, 0.0, 0.0])  # the paper's +x demand as the spacecraft torque
    v3 = cmg_pyramid.integrate_gimbals(np.zeros(4), x, 5.0)
    v4 = np.rad2deg(cmg_pyramid.preferred_angles([1.0, 0.0, 0.0]))
    v5 = cmg_pyramid.integrate_gimbals(D(ALTERNATE_DEG), [0.0, 0.0, -1.0], 5.0)

    def kurokawa(t: float) -> FloatArray:
        return -np.array([0.2 * np.sin(4.0 * np.pi * t), 0.3, 0.0])

    v6 = cmg_pyramid.integrate_gimbals(D([-120.0, -60.0, 60.0, 120.0]), kurokawa, 20.0)
    v7 = cmg_pyramid.integrate_gimbals(np.zeros(4), [-0.707, -0.707, 0.0], 5.0)
    v8 = cmg_pyramid.reorient(np.zeros(4), D(ALTERNATE_DEG), 10.0, 1.0, alpha=1e-3, n_out=1001)
    return (
        (
            "V1",
            "gain det(CCᵀ) at [−60, 60, 120, −120]°",
            1.1854,
            float(cmg.gain(D([-60.0, 60.0, 120.0, -120.0]))),
            "",
        ),
        (
            "V2",
            "saturation momentum along +x",
            3.1545,
            float(cmg.momentum(D([-90.0, 180.0, 90.0, 0.0]))[0]),
            "h",
        ),
        (
            "V3",
            "|h| at the internal singularity from σ = 0, +x demand",
            1.15,
            float(np.linalg.norm(v3.h[-1])),
            "h",
        ),
        *(
            ("V4", f"back-integrated σ{i + 1}", p, float(v4[i]), "deg")
            for i, p in enumerate((-59.6, 60.7, 118.0, -121.0))
        ),
        (
            "V5",
            "|h| at the internal singularity, z demand from [45, −45, 45, −45]°",
            1.282,
            float(np.linalg.norm(v5.h[-1])),
            "h",
        ),
        (
            "V6",
            "Kurokawa demand: saturation time from [−120, −60, 60, 120]°",
            10.0,
            float(v6.t[-1]),
            "s",
        ),
        ("V7", "Bedrossian demand: singular time from σ = 0", 1.5, float(v7.t[-1]), "s"),
        (
            "V8",
            "null-motion gain minimum on the way to [45, −45, 45, −45]° at t",
            1.10,
            float(v8.t[np.argmin(v8.gain)]),
            "s",
        ),
    )


class CmgKind(ScenarioKind):
    """``kind: cmg``: every steering run, then the V1–V8 table (module docstring); a run the
    steering refuses (a singular initial set under the pseudo-inverse, a preferred-angle
    search that meets a singularity) is reported under its label."""

    kind = "cmg"
    document = CmgScenario

    def steps(self, scenario: CmgScenario) -> int:
        return len(scenario.runs) + 1

    def plan(self, scenario: CmgScenario) -> Generator[Run, Any, CmgResult]:
        """Each run in turn, a :class:`~flexsat.scenarios.kind.Simulation` on the gimbal
        cluster: a torque-steering run the pseudo-inverse (or SR) law, stopped at the first
        singular set (:func:`flexsat.cases.cmg_pyramid.steering_simulation`), a reorientation
        the null-motion law (:func:`flexsat.cases.cmg_pyramid.reorient_simulation`)."""
        from flexsat.cases import cmg_pyramid
        from flexsat.dynamics.gimbal_cluster import GimbalCluster

        cluster = scenario.cluster
        runs = []
        for index, run in enumerate(scenario.runs):
            path = "runs" + item_path(index, run.label)
            d = run.demand_direction()
            try:
                sigma0 = _resolve(run.initial, d, cluster)
                if run.reorient_to is None:
                    task = _steering_simulation(run, cluster, sigma0)
                else:
                    target = _resolve(run.reorient_to, d, cluster)
                    alpha = cluster.alpha if cluster.steering == "sr" else 0.0
                    task = Simulation(
                        *cmg_pyramid.reorient_simulation(
                            sigma0,
                            target,
                            run.duration,
                            1.0,
                            cluster.skew,
                            cluster.n_units,
                            alpha=max(alpha, 1e-3),
                            n_out=N_OUT,
                        )
                    )
            except ValueError as exc:
                raise ScenarioError([locate(path, exc)]) from None
            result = yield Run(run.label, task, path)
            assert isinstance(task.plant, GimbalCluster)  # both builders make one
            g = cmg_pyramid.gimbal_run(task.plant, result.dataset)
            rates = result.dataset["gimbal_rates"].values[0]
            runs.append(_cmg_run(run.label, g, sigma0, d, cluster, rates))
        table = yield Run("V1–V8 table", validation_table)
        notes = (
            "Demands are the paper's T = ḣ (Eq. 5) in rotor momenta per second; the spacecraft "
            "feels −ḣ. The paper's V3 singular set [−90, 0, −90, 0]° is a misprint for "
            "[−90, 0, 90, 0]°.",
        )
        return CmgResult(scenario, tuple(runs), table, SOURCE, notes)


@dataclass(frozen=True)
class StationResult(ReportedResult):
    """The attitude loop (:class:`flexsat.cases.space_station_cmg.StationRun`) and one CMG loop
    per run."""

    scenario: CmgStationScenario
    station: StationRun
    runs: tuple[GimbalRun, ...]
    labels: tuple[str, ...]
    initial: tuple[FloatArray, ...]
    case_source: str = SOURCE
    notes: tuple[str, ...] = ()

    def metrics_records(self) -> list[dict[str, Any]]:
        from flexsat.dynamics import cmg

        hr = self.station.design.data.rotor_momentum
        peak = float(np.linalg.norm(self.station.momentum, axis=1).max())
        out = []
        for label, g in zip(self.labels, self.runs):
            rec = {
                "run": label,
                "singular": bool(g.singular),
                "singular_time_s": float(g.t[-1]) if g.singular else None,
                "internal": bool(cmg.classify_singularity(g.sigma[-1], threshold=1e-5).internal)
                if g.singular
                else None,
                "min_gain": float(g.gain.min()),
                "peak_momentum_ft_lb_s": peak / _FT_LB,
                "peak_momentum_h": peak / hr,
                "peak_attitude_deg": float(np.rad2deg(np.abs(self.station.attitude).max())),
            }
            out.append(rec)
        return out

    def dataset(self) -> xr.Dataset:
        import xarray as xr

        st = self.station
        t = st.t
        n = len(self.runs)
        sig = np.full((n, t.size, 4), np.nan)
        gain = np.full((n, t.size), np.nan)
        for i, g in enumerate(self.runs):
            keep = t <= g.t[-1] * (1 + 1e-12)
            for k in range(4):
                sig[i, keep, k] = np.interp(t[keep], g.t, g.sigma[:, k])
            gain[i, keep] = np.interp(t[keep], g.t, g.gain)
        ds = xr.Dataset(
            {
                "attitude": (("time", "axis"), st.attitude, {"units": "rad"}),
                "cmg_momentum": (("time", "axis"), st.momentum, {"units": "N*m*s"}),
                "torque": (("time", "axis"), st.torque, {"units": "N*m"}),
                "disturbance": (("time", "axis"), st.disturbance, {"units": "N*m"}),
                "gimbal_angles": (("run", "time", "gimbal"), sig, {"units": "rad"}),
                "gain": (("run", "time"), gain),
                "initial_angles": (("run", "gimbal"), np.array(self.initial), {"units": "rad"}),
            },
            coords={
                "time": t,
                "axis": ["roll", "pitch", "yaw"],
                "run": list(self.labels),
                "gimbal": [1, 2, 3, 4],
            },
        )
        ds["time"].attrs["units"] = "s"
        ds.attrs.update(
            scenario_name=self.scenario.name,
            case_source=self.case_source,
            scenario_yaml=self.scenario.yaml_text,
            rotor_momentum_N_m_s=st.design.data.rotor_momentum,
        )
        return ds

    def report_case(self) -> str:
        return "space station (Table 2)"

    def figures(self, folder: Path, ds: xr.Dataset) -> list[str]:
        from flexsat.report.cmg import draw_station_figures

        return draw_station_figures(ds, folder)

    def sections(self, ds: xr.Dataset, figures: list[str]) -> str:
        from flexsat.report.cmg import station_sections

        return station_sections(self, self.metrics_records(), figures)


def _station_design(scenario: CmgStationScenario) -> StationDesign:
    """The LQR design (:func:`flexsat.cases.space_station_cmg.design`); Bryson maxima or filters
    the design refuses are reported under ``lqr``."""
    from flexsat.cases import space_station_cmg as st

    q = scenario.lqr
    data = scenario.build_data()
    try:
        maxima = st.BrysonMaxima(q.attitude, q.rate, q.momentum, q.momentum_integral)
        return st.design(data, maxima, tuple(q.pitch_filters), tuple(q.roll_yaw_filters))
    except ValueError as exc:
        raise ScenarioError([locate("lqr", exc)]) from None


def _initial_set(spec: StationRunSpec, peak_direction: np.ndarray) -> np.ndarray:
    """A run's initial gimbal angles (rad)."""
    from flexsat.dynamics import cmg

    if spec.initial == "zero":
        return np.zeros(4)
    if spec.initial == "alternate":
        return np.deg2rad(ALTERNATE_DEG)
    if spec.initial == "preferred":
        return cmg.preferred_set(peak_direction)
    return np.array(spec.initial)


class CmgStationKind(ScenarioKind):
    """``kind: cmg_station``: LQR design and attitude loop, then one CMG loop per run (module
    docstring)."""

    kind = "cmg_station"
    document = CmgStationScenario

    def steps(self, scenario: CmgStationScenario) -> int:
        return len(scenario.runs) + 1

    def plan(self, scenario: CmgStationScenario) -> Generator[Run, Any, StationResult]:
        """The attitude loop, a :class:`~flexsat.scenarios.kind.Simulation` of the station
        under its LQR law (:func:`flexsat.cases.space_station_cmg.attitude_simulation`), then
        per run the station with its gimbals under the attitude law and the steering of the
        momentum it demands, stopped at the first singular set
        (:func:`flexsat.cases.space_station_cmg.cmg_simulation`)."""
        from flexsat.cases import space_station_cmg as st

        design = _station_design(scenario)
        sim = scenario.simulation
        duration = sim.orbits * design.data.period
        try:
            attitude = st.attitude_simulation(
                design, duration, sim.disturbance, sim.initial_attitude
            )
        except ValueError as exc:
            raise ScenarioError([locate("simulation", exc)]) from None
        result = yield Run("LQR design and attitude loop", Simulation(*attitude), "simulation")
        run = st.station_run(design, result.dataset, sim.disturbance, sim.initial_attitude)
        peak_dir = run.momentum[np.argmax(np.linalg.norm(run.momentum, axis=1))]
        loops, initial = [], []
        for index, spec in enumerate(scenario.runs):
            path = "runs" + item_path(index, spec.label)
            s0 = _initial_set(spec, peak_dir)
            initial.append(s0)
            try:
                plant, law, config, options = st.cmg_simulation(
                    design, duration, sim.disturbance, sim.initial_attitude, s0, sim.threshold
                )
            except ValueError as exc:
                raise ScenarioError([locate(path, exc)]) from None
            result = yield Run(spec.label, Simulation(plant, law, config, options), path)
            loops.append(st.gimbal_history(plant, result.dataset))
        notes = (
            "The paper's AERO1 disturbance is not given (Geller, private communication): "
            "'aero_substitute' is Eq. (11) plus 0.5 ft-lb 3n and 4n harmonics on each axis and "
            "a pitch torque growing by 1 ft-lb per orbit, a stated assumption (docs/cmg.md).",
            "The paper's Bryson maxima are not given: these are the scenario's 'lqr' section.",
            "Roll/yaw filters at the orbit rate make the design uncontrollable (three modes at "
            "jn, two inputs); the default roll/yaw filters are at 2n only.",
        )
        return StationResult(
            scenario,
            run,
            tuple(loops),
            tuple(s.label for s in scenario.runs),
            tuple(initial),
            SOURCE,
            notes,
        )


__all__ = [
    "CmgKind",
    "CmgResult",
    "CmgScenario",
    "CmgStationKind",
    "CmgStationScenario",
    "StationResult",
    "validation_table",
]
