"""Identification scenarios: test a structure, identify it, update its model (``kind:
identification``).

A scenario file with ``kind: identification`` runs
:func:`flexsat.cases.identification_campaign.run_campaign` on a case whose substructure
stiffnesses scale (the TAMU grid)::

    kind: identification
    name: TAMU grid, stiff-clamp a-priori model
    case: tamu_grid
    case_overrides: {motor_mass: "0.5 kg"}
    a_priori: {stiffness_scale: {clamp verticals: 1.15}, damping: 0.006}
    sensors:
      noise: 0.01
      strain_gauges: [[16, 21, x], [18, 23, x]]
      accelerometers: [[1, z]]
      targets: [1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17, 18, 19, 20]
    hammer: {node: 1, direction: z, impulse: "0.5 N*s"}
    video:
      cameras:
        - {position: ["-0.6 m", "0.55 m", "2.4 m"], aim: ["0.74 m", "0.55 m", "0 m"]}
        - {position: ["2.07 m", "0.55 m", "2.4 m"], aim: ["0.74 m", "0.55 m", "0 m"]}
    wheels: {nodes: [3, 7, 9], axes: [y, x, x], torque_rms: "0.05 N*m"}

Measured tests replace the simulated ones with ``records`` (universal files, dataset 58, paths
relative to the scenario file; ``truth``, ``sensors``, ``hammer``, ``video`` and ``wheels`` are
then left out)::

    records: {hammer: data/hammer.uff, wheels: data/wheels.uff, video: data/video.uff}
    identification: {torque_constants: true}      # identify the wheels' torque constants too

Quantities follow :mod:`flexsat.scenarios.fields` (unit strings or SI numbers); problems are
reported as ``field.path: rule`` before anything runs.
"""

from __future__ import annotations

from collections.abc import Callable, Generator
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, Literal, Self

import numpy as np
from pydantic import BeforeValidator, Field, ValidationInfo, field_validator, model_validator

from flexsat import limits
from flexsat.cases import get_case
from flexsat.input_checks import FieldError
from flexsat.references import cite
from flexsat.report.page import ReportedResult, ResultTable
from flexsat.scenarios.errors import Problem, ScenarioError, locate
from flexsat.scenarios.fields import Document, SchemaSection, in_unit, integer_in
from flexsat.scenarios.kind import Run, ScenarioKind
from flexsat.text import format_optional
from flexsat.units import to_si

if TYPE_CHECKING:  # the identification stack (scipy.signal) is imported when a campaign runs
    import xarray as xr

    from flexsat.cases.identification_campaign import (
        CampaignConfig,
        CampaignResult,
        SubstructuredCase,
        TestRecords,
    )

__all__ = [
    "SUMMARY_COLUMNS",
    "IdentificationKind",
    "IdentificationResult",
    "IdentificationScenario",
]


def _vector_in(unit: str) -> BeforeValidator:
    """Validator of a 3-vector of quantities in ``unit``, ``Annotated[tuple[float, float,
    float], _vector_in(unit)]`` (SI floats)."""

    def convert(value: Any, info: ValidationInfo) -> tuple[float, ...]:
        field = info.field_name or ""  # always set for a field validator
        if not isinstance(value, (list, tuple)) or len(value) != 3:
            raise FieldError(field, f"must be 3 quantities, e.g. ['1 {unit}', 0, 0]")
        return tuple(to_si(v, unit, field) for v in value)

    return BeforeValidator(convert)


def _sampled(spec: SchemaSection, duration: str, rate: str) -> None:
    """A simulated test's length and sample rate: positive, and at most
    :data:`flexsat.limits.MAX_SAMPLES` samples."""
    for name in (duration, rate):
        if not getattr(spec, name) > 0:
            raise FieldError(name, f"must be > 0, got {getattr(spec, name):g}")
    limits.check_count(
        getattr(spec, duration) * getattr(spec, rate),
        limits.MAX_SAMPLES,
        duration,
        f"samples ({duration} × {rate})",
        "shorten the test or lower the sample rate",
    )


class TruthSpec(SchemaSection):
    """The simulated "real" structure: modes kept (default all) and modal damping (Att. 6
    Table 1 default)."""

    modes: Annotated[int, Field(ge=1)] | None = None
    damping: list[Annotated[float, Field(gt=0, lt=1)]] = Field(
        default_factory=lambda: [0.00603, 0.00489, 0.01105, 0.00596, 0.01293]
    )
    other_damping: Annotated[float, Field(gt=0, lt=1)] = 0.01


class APrioriSpec(SchemaSection):
    """The model to update: substructure stiffness factors on the truth, Eq. 15 damping."""

    stiffness_scale: dict[str, Annotated[float, Field(gt=0)]] = Field(default_factory=dict)
    damping: Annotated[float, Field(gt=0, lt=1)] = 0.006


class SensorSpec(SchemaSection):
    noise: Annotated[float, Field(ge=0)] = 0.01
    strain_gauges: list[tuple[int, int, Literal["x", "y", "z"]]] = Field(min_length=1)
    accelerometers: list[tuple[int, Literal["x", "y", "z"]]] = Field(default_factory=list)
    targets: list[int] = Field(min_length=1)


class HammerSpec(SchemaSection):
    node: int
    direction: Literal["x", "y", "z"] = "z"
    impulse: Annotated[float, in_unit("N*s")] = 0.5
    duration: Annotated[float, in_unit("s")] = 20.0
    sample_rate: Annotated[float, in_unit("Hz")] = 200.0

    @model_validator(mode="after")
    def _samples(self) -> Self:
        _sampled(self, "duration", "sample_rate")
        return self


class CameraSpec(SchemaSection):
    position: Annotated[tuple[float, float, float], _vector_in("m")]
    aim: Annotated[tuple[float, float, float], _vector_in("m")]


class VideoSpec(SchemaSection):
    cameras: list[CameraSpec] = Field(min_length=2)
    impulse: Annotated[float, in_unit("N*s")] = 0.3
    duration: Annotated[float, in_unit("s")] = 4.5
    field_rate: Annotated[float, in_unit("Hz")] = 200.0
    focal_length: Annotated[float, in_unit("m")] = 0.008
    pixel_size: Annotated[float, in_unit("m")] = 27e-6
    centroid_noise_px: Annotated[float, Field(gt=0)] = 0.05
    quantize: bool = False
    target_sigma: Annotated[float, in_unit("m")] = 1e-3
    static_fields: Annotated[int, integer_in(1, limits.MAX_SAMPLES)] = 50

    @model_validator(mode="after")
    def _samples(self) -> Self:
        _sampled(self, "duration", "field_rate")
        return self


class WheelSpec(SchemaSection):
    nodes: list[int] = Field(min_length=1)
    axes: list[Literal["x", "y", "z"]] = Field(min_length=1)
    torque_rms: Annotated[float, in_unit("N*m")] = 0.05
    torque_constants: list[Annotated[float, Field(gt=0)]] = Field(default_factory=list)
    duration: Annotated[float, in_unit("s")] = 300.0
    sample_rate: Annotated[float, in_unit("Hz")] = 50.0
    segment: Annotated[int, integer_in(16, limits.MAX_SAMPLES)] = 2000

    @model_validator(mode="after")
    def _one_axis_per_wheel(self) -> Self:
        _sampled(self, "duration", "sample_rate")
        if len(self.axes) != len(self.nodes):
            raise FieldError(
                "axes", f"one torque axis per wheel node ({len(self.nodes)}), got {len(self.axes)}"
            )
        if self.torque_constants and len(self.torque_constants) != len(self.nodes):
            raise FieldError(
                "torque_constants",
                f"one factor per wheel ({len(self.nodes)}), got {len(self.torque_constants)}",
            )
        return self


class RecordsSpec(SchemaSection):
    """Measured tests as universal files (dataset 58, :meth:`Measurement.from_uff`), paths
    relative to the scenario file: the hammer test (outputs and the hammer's force), the
    reaction-wheel test (strain gauges and commanded torques) and, optionally, the target
    displacements normal to the structure with the blow's force."""

    hammer: str
    wheels: str
    video: str | None = None
    segment: Annotated[int, integer_in(16, limits.MAX_SAMPLES)] = 2000


class IdentificationSpec(SchemaSection):
    band: Annotated[float, in_unit("Hz")] = 10.0
    # the ERA Hankel matrix and the bootstrap's repeats grow with these: minutes at the bounds
    era_order: Annotated[int, integer_in(2, 1000)] = 80
    update: Literal["creamer_junkins", "differential_correction"] = "differential_correction"
    anti_alias: Annotated[float, Field(gt=0, lt=0.5)] = 0.4
    bootstrap_samples: Annotated[int, integer_in(0, 1000)] = 10
    torque_constants: bool = False


class IdentificationScenario(Document):
    """A validated identification scenario (SI; see the module docstring)."""

    kind: Literal["identification"]
    name: str
    case: str
    case_overrides: dict[str, bool | int | float | str] = Field(default_factory=dict)
    truth: TruthSpec = Field(default_factory=TruthSpec)
    a_priori: APrioriSpec = Field(default_factory=APrioriSpec)
    sensors: SensorSpec | None = None
    hammer: HammerSpec | None = None
    video: VideoSpec | None = None
    wheels: WheelSpec | None = None
    records: RecordsSpec | None = None
    identification: IdentificationSpec = Field(default_factory=IdentificationSpec)
    seed: Annotated[int, integer_in(0, limits.MAX_SEED)] = 0

    @field_validator("case")
    @classmethod
    def _known_case(cls, name: str) -> str:
        get_case(name)
        return name

    @model_validator(mode="after")
    def _simulated_or_recorded(self) -> Self:
        simulated = ("sensors", "hammer", "video", "wheels")
        if self.records is None:
            missing = [name for name in simulated if getattr(self, name) is None]
            if missing:
                raise FieldError(
                    f"{missing[0]}",
                    "required to simulate the tests (or give 'records' with measured data)",
                )
        else:
            given = [name for name in simulated + ("truth",) if name in self.model_fields_set]
            if given:
                raise FieldError(
                    f"{given[0]}",
                    "describes a simulated test; with 'records' the "
                    "tests are measured (leave it out)",
                )
        gains = self.identification.torque_constants or (
            self.wheels is not None and self.wheels.torque_constants
        )
        if gains and self.identification.update != "differential_correction":
            raise FieldError(
                "identification.update",
                "the wheels' torque constants are identified "
                "from the FRF, which only 'differential_correction' uses",
            )
        return self

    @property
    def recorded(self) -> bool:
        """True when the tests are measured data (``records``), not simulated."""
        return self.records is not None

    def config(self) -> CampaignConfig:
        """The :class:`CampaignConfig` of this scenario."""
        from flexsat.cases.identification_campaign import CameraRig, CampaignConfig

        ident = self.identification
        common: dict[str, Any] = dict(
            a_priori_scale=dict(self.a_priori.stiffness_scale),
            a_priori_damping=self.a_priori.damping,
            band=ident.band,
            era_order=ident.era_order,
            update=ident.update,
            anti_alias=ident.anti_alias,
            bootstrap_samples=ident.bootstrap_samples,
            identify_torque_constants=ident.torque_constants,
            seed=self.seed,
        )
        if self.records is not None:
            return CampaignConfig(frf_segment=self.records.segment, **common)
        v, w, h, s = self.video, self.wheels, self.hammer, self.sensors
        # the document requires the four sections of simulated tests (_simulated_or_recorded)
        assert v is not None and w is not None and h is not None and s is not None
        rig = CameraRig(
            tuple(c.position for c in v.cameras),
            tuple(c.aim for c in v.cameras),
            v.focal_length,
            v.pixel_size,
            v.centroid_noise_px,
            v.quantize,
            static_fields=v.static_fields,
        )
        return CampaignConfig(
            truth_damping=tuple(self.truth.damping),
            other_damping=self.truth.other_damping,
            truth_modes=self.truth.modes,
            strain_gauges=tuple(s.strain_gauges),
            accelerometers=tuple(s.accelerometers),
            targets=tuple(s.targets),
            hammer_node=h.node,
            hammer_direction=h.direction,
            hammer_impulse=h.impulse,
            hammer_duration=h.duration,
            sample_rate=h.sample_rate,
            noise=s.noise,
            video_impulse=v.impulse,
            video_duration=v.duration,
            field_rate=v.field_rate,
            target_sigma=v.target_sigma,
            rig=rig,
            wheel_nodes=tuple(w.nodes),
            wheel_axes=tuple(w.axes),
            wheel_torque_rms=w.torque_rms,
            wheel_torque_constants=tuple(w.torque_constants),
            wheel_duration=w.duration,
            wheel_sample_rate=w.sample_rate,
            frf_segment=w.segment,
            **common,
        )


#: the columns of the console's table of identified modes
SUMMARY_COLUMNS = ("true Hz", "ERA Hz", "a priori Hz", "updated Hz", "true zeta", "ERA zeta")


@dataclass(frozen=True)
class IdentificationResult(ReportedResult):
    """An identification scenario and its campaign result; its report holds
    ``identification.json`` and ``results.nc`` (:mod:`flexsat.report.identification`)."""

    report_title = "flexsat identification report"

    scenario: IdentificationScenario
    campaign: CampaignResult
    case_source: str

    def metrics_records(self) -> list[dict[str, Any]]:
        """One JSON-ready dict per identified mode (``"run"``: ``mode k``): true, ERA, a priori
        and updated frequencies (Hz) and the true and ERA damping ratios (None: no value, the
        truth of recorded tests)."""
        m = self.campaign.modes
        keys = ("true_hz", "era_hz", "a_priori_hz", "updated_hz", "true_damping", "era_damping")
        return [
            {
                "run": f"mode {k + 1}",
                **{key: _number(m[key][k]) for key in keys},
            }
            for k in range(len(m["era_hz"]))
        ]

    def dataset(self) -> xr.Dataset:
        from flexsat.report.identification import dataset

        return dataset(self)

    def write_data(self, folder: Path, ds: xr.Dataset) -> None:
        from flexsat.report.identification import write_data

        write_data(self, ds, folder)

    def figures(self, folder: Path, ds: xr.Dataset) -> list[str]:
        from flexsat.report.identification import draw_figures

        return draw_figures(self.campaign, folder)

    def sections(self, ds: xr.Dataset, figures: list[str]) -> str:
        from flexsat.report.identification import sections

        return sections(self)

    def console_table(self) -> ResultTable:
        """The identified modes: per mode, true / ERA / a priori / updated frequencies and the
        true and ERA damping ratios; the caption gives the substructure scalings."""
        caption = "".join(
            f"{name}: a priori x{v['a_priori']:.3f}, updated x{v['updated']:.4f} of nominal\n"
            for name, v in self.campaign.scalings.items()
        )
        return ResultTable(
            "identified modes",
            ("mode", *SUMMARY_COLUMNS),
            tuple((mode, *values) for mode, values in _summary_rows(self)),
            caption or None,
        )


def _node_fields(
    scenario: IdentificationScenario, records: TestRecords | None
) -> list[tuple[str, int, bool]]:
    """(field path, node id, may be clamped) of every sensor and input of the scenario."""
    if records is not None:
        out: list[tuple[str, int, bool]] = []
        for name in ("hammer", "wheels", "video"):
            test = getattr(records, name)
            for c in () if test is None else test.output_channels + test.input_channels:
                # a strain gauge's clamped end is legitimate (the gauge sits at the root)
                out.append((f"records.{name}", c.node, c.kind == "strain"))
                if c.node_a is not None:
                    out.append((f"records.{name}", c.node_a, True))
        return out
    sensors, hammer, wheels = scenario.sensors, scenario.hammer, scenario.wheels
    assert sensors is not None and hammer is not None and wheels is not None  # simulated tests
    return (
        [("sensors.strain_gauges", node, True) for g in sensors.strain_gauges for node in g[:2]]
        + [("sensors.accelerometers", a[0], False) for a in sensors.accelerometers]
        + [("sensors.targets", n, False) for n in sensors.targets]
        + [("hammer.node", hammer.node, False)]
        + [("wheels.nodes", n, False) for n in wheels.nodes]
    )


def _check_against_case(
    scenario: IdentificationScenario, case: Any, records: TestRecords | None = None
) -> list[str]:
    """Stage-2 problems that need the built case (any case's object: one without substructures
    is refused): substructure names and node ids."""
    problems: list[str] = []
    names = tuple(getattr(case, "substructures", ()))
    if not names or not hasattr(case, "structure"):
        return [f"case: {scenario.case!r} has no substructures to update (use tamu_grid)"]
    for key in scenario.a_priori.stiffness_scale:
        if key not in names:
            problems.append(
                f"a_priori.stiffness_scale: unknown substructure {key!r}; known: {', '.join(names)}"
            )
    asm = case.structure().assemble()
    free = {int(n) for n, _ in asm.dofs}
    fields = _node_fields(scenario, records)
    known = {int(n) for n in asm.node_ids}
    for path, node, may_be_clamped in fields:
        if node not in known:
            problems.append(f"{path}: node {node} is not a node of {scenario.case}")
        elif node not in free and not may_be_clamped:
            problems.append(f"{path}: node {node} is clamped (it does not move)")
    targets = [] if records is not None or scenario.sensors is None else scenario.sensors.targets
    if len(set(targets)) != len(targets):
        problems.append("sensors.targets: node ids must be distinct")
    if scenario.truth.modes is not None and scenario.truth.modes > asm.n_dofs:
        problems.append(
            f"truth.modes: {scenario.truth.modes} is more than the {asm.n_dofs} modes of "
            f"{scenario.case}'s model"
        )
    problems.extend(_band_problems(scenario, records))
    return list(dict.fromkeys(problems))


def _band_problems(scenario: IdentificationScenario, records: object) -> list[str]:
    """The identification band inside every simulated test's anti-aliased bandwidth: the
    campaign filters each channel at ``anti_alias`` × its sample rate, so a band above the
    slowest test's cut-off holds no measured mode, and the FRF grid over it (0.4 Hz to the band
    in fixed steps) would grow without bound."""
    band = scenario.identification.band
    if not band > 0:
        return [f"identification.band: must be > 0 Hz, got {band:g} Hz"]
    if records is not None:
        return []
    # without records every test is simulated: the schema requires all three sections then
    assert scenario.hammer and scenario.wheels and scenario.video
    rates = {
        "hammer.sample_rate": scenario.hammer.sample_rate,
        "wheels.sample_rate": scenario.wheels.sample_rate,
        "video.field_rate": scenario.video.field_rate,
    }
    slowest = min(rates, key=lambda name: rates[name])
    cutoff = scenario.identification.anti_alias * rates[slowest]
    if band > cutoff:
        return [
            f"identification.band: {band:g} Hz is above the anti-alias cut-off {cutoff:g} Hz "
            f"of the slowest test ({slowest} {rates[slowest]:g} Hz × anti_alias "
            f"{scenario.identification.anti_alias:g}): no mode above it is measured"
        ]
    return []


def _read_records(scenario: IdentificationScenario) -> TestRecords:
    """The measured tests of ``records`` (paths relative to the scenario file)."""
    from flexsat.cases.identification_campaign import TestRecords
    from flexsat.identify.measurements import Measurement

    problems: list[str] = []
    read: dict[str, Measurement] = {}
    for name in ("hammer", "wheels", "video"):
        path = getattr(scenario.records, name)
        if path is None:
            continue
        full = scenario.folder / path
        try:
            test = Measurement.from_uff(full)
        except (OSError, ValueError) as exc:
            problems.append(f"records.{name}: cannot read {str(full)!r} ({exc})")
            continue
        if test.domain != "time" or test.inputs is None:
            problems.append(
                f"records.{name}: must hold time histories with the input "
                "(force or torque) channels"
            )
        read[name] = test
    if problems:
        raise ScenarioError(problems)
    return TestRecords(read["hammer"], read["wheels"], read.get("video"))  # video optional


def _number(value: float | None) -> float | None:
    """A JSON-ready number: None (no value) and NaN become None."""
    return None if value is None or not np.isfinite(value) else float(value)


def _campaign(
    scenario: IdentificationScenario,
    case: SubstructuredCase,
    records: TestRecords | None,
    progress: Callable[[str], None] | None = None,
) -> CampaignResult:
    """The campaign (one call into :mod:`flexsat.cases.identification_campaign`): on the test
    records, or simulating the tests; a value it refuses is reported at the scenario's field
    for it."""
    from flexsat.cases.identification_campaign import identify_and_update, run_campaign

    try:
        if records is not None:
            return identify_and_update(case, scenario.config(), records, progress=progress)
        return run_campaign(case, scenario.config(), progress=progress)
    except ValueError as exc:
        field = exc.field if isinstance(exc, FieldError) else None
        if isinstance(exc, FieldError) and exc.field == "wheel_torque_constants":
            raise ScenarioError([Problem("wheels.torque_constants", exc.rule)]) from None
        path = {
            "rig": "video",
            "records": "records",
            "measurement": "records.wheels",
            "segment": "records.segment",
        }.get(field or "", "")
        raise ScenarioError([locate(path, exc)]) from None


class IdentificationKind(ScenarioKind):
    """``kind: identification``: validate against the case, then test the structure, identify
    it and update its model (module docstring); the campaign announces its own steps."""

    kind = "identification"
    document = IdentificationScenario

    def steps(self, scenario: IdentificationScenario) -> int:
        """The campaign's steps, without the simulated tests when the scenario brings its
        records."""
        from flexsat.cases.identification_campaign import IDENTIFY_STEPS, SIMULATE_STEPS

        return len(IDENTIFY_STEPS) + (0 if scenario.recorded else len(SIMULATE_STEPS))

    def plan(self, scenario: IdentificationScenario) -> Generator[Run, Any, IdentificationResult]:
        """Raises ScenarioError for unknown substructures, nodes that are not in the case or
        are clamped, case overrides the case rejects, or a camera rig that does not see every
        target."""
        import functools

        try:
            case = get_case(scenario.case).builder(**scenario.case_overrides)
        except ValueError as exc:
            raise ScenarioError([Problem("case_overrides", str(exc))]) from None
        records = _read_records(scenario) if scenario.recorded else None
        problems = _check_against_case(scenario, case, records)
        if problems:
            raise ScenarioError(problems)
        campaign = yield Run(
            "campaign",
            functools.partial(_campaign, scenario, case, records),
            reports_progress=True,
        )
        return IdentificationResult(scenario, campaign, cite(get_case(scenario.case).source))


def _summary_rows(result: IdentificationResult) -> list[tuple[str, list[str]]]:
    """Frequency table rows for the console: per mode, true / ERA / a priori / updated."""
    m = result.campaign.modes
    rows: list[tuple[str, list[str]]] = []
    for k in range(len(m["era_hz"])):
        rows.append(
            (
                str(k + 1),
                [
                    format_optional(m["true_hz"][k], ".4f"),
                    f"{m['era_hz'][k]:.4f}",
                    f"{m['a_priori_hz'][k]:.4f}",
                    f"{m['updated_hz'][k]:.4f}",
                    format_optional(m["true_damping"][k], ".5f"),
                    f"{m['era_damping'][k]:.5f}",
                ],
            )
        )
    return rows
