"""Star-tracker scenarios (``kind: star_tracker``): lost-in-space star-pattern identification
on seeded random attitudes (Junkins, Pollock & Rahman 1990 §2.3.4; issue 14 part 4)::

    kind: star_tracker
    name: two 12° cameras, synthetic sky
    catalog: {source: synthetic, magnitude_limit: 6.5, seed: 0}
    cameras:
      - {field_of_view: "12 deg", n_pixels: 4096, pixel_pitch: "5.5 um", centroid_noise: 0.1}
      - {field_of_view: "12 deg", n_pixels: 4096, pixel_pitch: "5.5 um", centroid_noise: 0.1,
         mounting: ["0 deg", "90 deg", "0 deg"]}
    identification: {tolerance: "5 arcsec", min_triplets: 3, min_fields: 2}
    runs:
      - {label: clean, attitudes: 1000, seed: 1}
      - {label: 2 false + 20 % missing, attitudes: 1000, seed: 2, false_stars: 2,
         missing_fraction: 0.2}

``catalog.source`` is ``synthetic`` (:func:`flexsat.attitude.star_catalog.synthetic_sky`) or
``hipparcos`` with ``path`` to a user-supplied ``hip_main.dat`` (relative to the scenario
file). Each run identifies ``attitudes`` random attitudes
(:func:`flexsat.attitude.star_tracker.monte_carlo`) with ``false_stars`` spurious centroids and
a ``missing_fraction`` of the visible stars dropped per frame.
"""

from __future__ import annotations

from collections.abc import Generator
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, Literal, Self

import numpy as np
from pydantic import Field, model_validator

from flexsat.input_checks import FieldError
from flexsat.report.json_data import NULL_REASONS
from flexsat.report.page import ReportedResult
from flexsat.scenarios.datasets import add_run_metrics
from flexsat.scenarios.errors import ScenarioError, item_path, locate
from flexsat.scenarios.fields import (
    BuildableSection,
    Document,
    SchemaSection,
    check_unique_labels,
    in_unit,
    integer_in,
)
from flexsat.scenarios.kind import Run, ScenarioKind

if TYPE_CHECKING:
    import xarray as xr

    from flexsat.attitude.star_camera import StarCamera
    from flexsat.attitude.star_catalog import StarCatalog
    from flexsat.attitude.star_tracker import MonteCarloResult, StarTracker

#: the paper this kind reproduces
SOURCE = (
    "Junkins, Pollock & Rahman 1990 §2.3.4 (Anderson, Pollock & Junkins 1990, "
    "'A testbed for autonomous star "
    "pattern recognition and attitude determination'; Junkins, White & Turner 1977)"
)
#: most attitudes one run may identify (a run costs ~5 ms per attitude)
MAX_ATTITUDES = 100_000


class CatalogSpec(SchemaSection):
    """The on-board catalogue."""

    source: Literal["synthetic", "hipparcos"] = "synthetic"
    magnitude_limit: float = Field(6.5, allow_inf_nan=False)
    seed: Annotated[int, integer_in(0)] = 0
    path: str | None = None

    @model_validator(mode="after")
    def _path(self) -> Self:
        if (self.source == "hipparcos") != (self.path is not None):
            raise FieldError(
                "path", "give the hip_main.dat path with source: hipparcos, and only then"
            )
        return self

    def build(self, folder: Path) -> StarCatalog:
        """The catalogue; a relative ``path`` starts at ``folder`` (the scenario's)."""
        from flexsat.attitude.star_catalog import load_hipparcos, synthetic_sky

        if self.source == "synthetic" or self.path is None:  # a path comes with hipparcos
            return synthetic_sky(self.magnitude_limit, self.seed)
        path = Path(self.path)
        return load_hipparcos(path if path.is_absolute() else folder / path, self.magnitude_limit)


class CameraSpec(BuildableSection):
    """One star camera (:class:`flexsat.attitude.star_camera.StarCamera`)."""

    field_of_view: Annotated[float, in_unit("rad", positive=True)] = float(np.radians(12.0))
    n_pixels: Annotated[int, integer_in(2)] = 4096
    pixel_pitch: Annotated[float, in_unit("m", positive=True)] = 5.5e-6
    centroid_noise: float = Field(0.1, ge=0.0, allow_inf_nan=False)
    magnitude_limit: float = Field(6.5, allow_inf_nan=False)
    mounting: list[Annotated[float, in_unit("rad")]] = Field(
        default_factory=lambda: [0.0, 0.0, 0.0]
    )

    def build(self) -> StarCamera:
        """The camera (its constructor checks its own rules)."""
        from flexsat.attitude.star_camera import StarCamera

        return StarCamera(
            field_of_view=self.field_of_view,
            n_pixels=self.n_pixels,
            pixel_pitch=self.pixel_pitch,
            centroid_noise=self.centroid_noise,
            magnitude_limit=self.magnitude_limit,
            mounting=tuple(self.mounting),
        )


class IdentificationSpec(SchemaSection):
    """The paper's acceptance rule (Junkins, Pollock & Rahman 1990 §2.3.4)."""

    tolerance: Annotated[float, in_unit("rad", positive=True)] = float(np.radians(5.0 / 3600.0))
    min_triplets: Annotated[int, integer_in(1)] = 3
    min_fields: Annotated[int, integer_in(1)] = 2


class StarRunSpec(SchemaSection):
    """One Monte Carlo of random attitudes."""

    label: str
    attitudes: Annotated[int, integer_in(1, MAX_ATTITUDES)] = 1000
    seed: Annotated[int, integer_in(0)] = 0
    false_stars: Annotated[int, integer_in(0, 1000)] = 0
    missing_fraction: float = Field(0.0, ge=0.0, lt=1.0)


class StarTrackerScenario(Document):
    """A validated star-tracker scenario (module docstring)."""

    kind: Literal["star_tracker"]
    name: str
    catalog: CatalogSpec = Field(default_factory=CatalogSpec)
    cameras: list[CameraSpec] = Field(min_length=1, max_length=16)
    identification: IdentificationSpec = Field(default_factory=IdentificationSpec)
    runs: list[StarRunSpec] = Field(min_length=1, max_length=100)

    @model_validator(mode="after")
    def _checks(self) -> Self:
        check_unique_labels(self.runs)
        if len(self.cameras) < self.identification.min_fields:
            raise FieldError(
                "cameras",
                "identification.min_fields = "
                f"{self.identification.min_fields} needs as many cameras, got "
                f"{len(self.cameras)}",
            )
        return self

    @property
    def case(self) -> str:
        return f"{self.catalog.source} catalogue, {len(self.cameras)} star cameras"


@dataclass(frozen=True)
class StarTrackerResult(ReportedResult):
    """The runs of a star-tracker scenario: one
    :class:`~flexsat.attitude.star_tracker.MonteCarloResult` per run label."""

    report_title = "flexsat star tracker report"

    scenario: StarTrackerScenario
    labels: tuple[str, ...]
    runs: tuple[MonteCarloResult, ...]
    tracker: StarTracker
    case_source: str = SOURCE
    notes: tuple[str, ...] = ()

    def metrics_records(self) -> list[dict[str, Any]]:
        """One JSON-ready dict per run (arcseconds for angles). A run that accepted no attitude
        has no error statistics: those metrics are None and its ``null_reasons`` say so."""
        from flexsat.attitude.star_tracker import ARCSEC

        out = []
        for label, r in zip(self.labels, self.runs):
            acc = r.accepted
            rec: dict[str, Any] = {
                "run": label,
                "attitudes": int(acc.size),
                "identification_rate": float(r.identification_rate),
                "accepted_rate": float(acc.mean()),
                "wrong_accepted": int(r.wrong_accepted.sum()),
                "mean_stars": float(r.n_stars[acc].mean()) if acc.any() else None,
                "min_triplets": int(r.triplets[acc].min()) if acc.any() else 0,
                "nees_mean": float(np.nanmean(r.nees)) if acc.any() else None,
            }
            std = r.error_std / ARCSEC if acc.any() else None
            sig = np.nanmean(r.sigmas, 0) / ARCSEC if acc.any() else None
            for k, axis in enumerate("xyz"):
                rec[f"error_std_{axis}_arcsec"] = None if std is None else float(std[k])
                rec[f"quest_sigma_{axis}_arcsec"] = None if sig is None else float(sig[k])
            if not acc.any():
                why = f"no data: none of the {acc.size} attitudes was identified and accepted"
                rec[NULL_REASONS] = {k: why for k, v in rec.items() if v is None}
            out.append(rec)
        return out

    def dataset(self) -> xr.Dataset:
        """Per run and attitude: the error angles (arcsec), ``accepted``, ``correct``,
        ``n_stars``; the first attitude's frames (pixels, match status) for the sky plot."""
        import xarray as xr

        from flexsat.attitude.star_tracker import ARCSEC

        n = max(r.accepted.size for r in self.runs)
        n_cam = len(self.tracker.cameras)
        n_star = max(len(f) for r in self.runs for f in r.example_frames) or 1

        def pad(a: np.ndarray, shape: tuple[int, ...], fill: float = np.nan) -> np.ndarray:
            out = np.full(shape, fill, dtype=float)
            out[tuple(slice(0, s) for s in a.shape)] = a
            return out

        err = np.stack([pad(r.errors / ARCSEC, (n, 3)) for r in self.runs])
        acc = np.stack([pad(r.accepted.astype(float), (n,)) for r in self.runs])
        cor = np.stack([pad(r.correct.astype(float), (n,)) for r in self.runs])
        nst = np.stack([pad(r.n_stars.astype(float), (n,)) for r in self.runs])
        px = np.full((len(self.runs), n_cam, n_star, 2), np.nan)
        status = np.full((len(self.runs), n_cam, n_star), np.nan)
        for i, r in enumerate(self.runs):
            for c, (f, fm) in enumerate(zip(r.example_frames, r.example.fields)):
                px[i, c, : len(f)] = f.pixels
                # 1: matched to its true star, 0: true star deleted, -1: false star, 2: wrong
                s = np.where(f.truth < 0, -1.0, np.where(fm.matches < 0, 0.0, 1.0))
                s[(fm.matches >= 0) & (fm.matches != f.truth)] = 2.0
                status[i, c, : len(f)] = s
        ds = xr.Dataset(
            {
                "error": (("run", "attitude", "axis"), err, {"units": "arcsec"}),
                "accepted": (("run", "attitude"), acc),
                "correct": (("run", "attitude"), cor),
                "n_stars": (("run", "attitude"), nst),
                "example_pixels": (("run", "camera", "star", "pixel_axis"), px, {"units": "pixel"}),
                "example_status": (
                    ("run", "camera", "star"),
                    status,
                    {"meaning": "1 matched, 0 deleted true star, -1 false star, 2 wrong match"},
                ),
            },
            coords={
                "run": list(self.labels),
                "attitude": np.arange(n),
                "axis": ["x", "y", "z"],
                "camera": np.arange(n_cam),
                "star": np.arange(n_star),
                "pixel_axis": ["column", "row"],
            },
        )
        add_run_metrics(ds, self.metrics_records())
        ds.attrs.update(
            scenario_name=self.scenario.name,
            case=self.scenario.case,
            case_source=self.case_source,
            scenario_yaml=self.scenario.yaml_text,
            n_pixels=int(self.tracker.cameras[0].n_pixels),
            tolerance_arcsec=self.tracker.tolerance / ARCSEC,
            catalog_stars=len(self.tracker.catalog),
            catalog_pairs=len(self.tracker.index),
        )
        return ds

    def figures(self, folder: Path, ds: xr.Dataset) -> list[str]:
        from flexsat.report.star_tracker import draw_figures

        return draw_figures(ds, folder)

    def sections(self, ds: xr.Dataset, figures: list[str]) -> str:
        from flexsat.report.star_tracker import sections

        return sections(self, self.metrics_records(), figures)


def build_tracker(scenario: StarTrackerScenario) -> StarTracker:
    """The :class:`~flexsat.attitude.star_tracker.StarTracker` of a scenario.

    Raises
    ------
    ScenarioError
        For a catalogue or tracker the runtime refuses (naming the section).
    """
    from flexsat.attitude.star_tracker import StarTracker

    try:
        catalog = scenario.catalog.build(scenario.folder)
    except ValueError as exc:
        raise ScenarioError([locate("catalog", exc)]) from None
    idn = scenario.identification
    try:
        return StarTracker(
            [c.build() for c in scenario.cameras],
            catalog,
            idn.tolerance,
            idn.min_triplets,
            idn.min_fields,
        )
    except ValueError as exc:
        field = getattr(exc, "field", None)
        section = field if field in ("cameras", "catalog") else "identification"
        raise ScenarioError([locate(section, exc)]) from None


class StarTrackerKind(ScenarioKind):
    """``kind: star_tracker``: build the tracker once (catalogue, k-vector index) and identify
    every run's attitudes (module docstring)."""

    kind = "star_tracker"
    document = StarTrackerScenario

    def steps(self, scenario: StarTrackerScenario) -> int:
        return len(scenario.runs)

    def plan(self, scenario: StarTrackerScenario) -> Generator[Run, Any, StarTrackerResult]:
        import functools

        from flexsat.attitude.star_tracker import (
            check_field_load,
            check_identifiable,
            monte_carlo,
        )

        tracker = build_tracker(scenario)
        problems = []
        # every run's load, before the first runs; the runs in order of size, so that a sky the
        # cameras cannot identify in is named for the largest run
        for index, run in sorted(enumerate(scenario.runs), key=lambda ir: -ir[1].attitudes):
            try:
                check_field_load(tracker, run.false_stars, run.missing_fraction)
                check_identifiable(tracker, run.attitudes, run.missing_fraction)
            except ValueError as exc:
                # a sky, cameras or acceptance rule that fails every run is named once, in
                # its own section
                field = getattr(exc, "field", None)
                if field in ("cameras", "min_triplets", "tolerance"):
                    where = "" if field == "cameras" else "identification"
                    raise ScenarioError([locate(where, exc)]) from None
                problems.append(locate("runs" + item_path(index, run.label), exc))
        if problems:
            raise ScenarioError(problems)
        runs = []
        for index, run in enumerate(scenario.runs):
            identify = functools.partial(
                monte_carlo, tracker, run.attitudes, run.seed, run.false_stars, run.missing_fraction
            )
            runs.append((yield Run(run.label, identify, "runs" + item_path(index, run.label))))
        notes = (
            f"Catalogue: {tracker.catalog.source}, {len(tracker.catalog)} stars, "
            f"{len(tracker.index)} pairs within {np.degrees(tracker.index.max_angle):.3g}° in "
            "the k-vector.",
            "Accepted: >= min_triplets matched inter-star-angle triplets (triangles whose three "
            "angles match the catalogue within the tolerance) in >= min_fields fields of view, "
            "confirmed by one q-method attitude fitting every kept star within the tolerance "
            "(Junkins, Pollock & Rahman 1990 §2.3.4).",
            "Error: body-axis rotation from the true to the estimated attitude; σ_QUEST: the "
            "covariance of the q-method fit (Shuster & Oh 1981).",
        )
        return StarTrackerResult(
            scenario, tuple(r.label for r in scenario.runs), tuple(runs), tracker, SOURCE, notes
        )


__all__ = ["StarTrackerKind", "StarTrackerResult", "StarTrackerScenario", "build_tracker"]
