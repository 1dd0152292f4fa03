"""Tethered-subsatellite retrieval scenarios (``kind: tether``): Vadali & Kim's Liapunov laws
(Junkins, Pollock & Rahman 1990, Att. 12; :mod:`flexsat.control.tether_laws`) on the
three-degree-of-freedom tether
(:mod:`flexsat.dynamics.tether`), one run per law and gain set (issue 14, F21-F22)::

    kind: tether
    name: Vadali & Kim retrieval
    system: {mass: 22.7 kg, length: 20 km, altitude: 220 km}   # or orbit_rate: 0.07068 rad/min
    initial: {length: 20 km, pitch: 5 deg, roll: 5 deg}
    simulation: {orbits: 2, samples_per_orbit: 1000, integrator: continuous}
    runs:
      - label: controller 2
        law: coupled                      # decoupled (controller 1), coupled (2) or rate
        gains: {K1: 1.0, K2: 0.0, K3: 3.0, K4: 2.0}
        final_length: 200 m

``system.length`` is the reference length L of the nondimensional form (λ = l/L); the initial
rates default to zero (``length_rate`` is the law's own under rate control and may not be
given). ``integrator: continuous`` integrates the continuous feedback (DOP853, the paper's
setting) and samples it ``samples_per_orbit`` times an orbit; ``sampled`` runs the simulation
core with the commands held between those samples (a digital controller; the zero-order hold
costs accuracy, docs/tether.md). A decoupled run may set ``printed_sign: true`` to use the
misprinted sign of Eq. 15 (it diverges).
"""

from __future__ import annotations

from collections.abc import Callable, Generator
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, Literal, Self

import numpy as np
from pydantic import Field, model_validator

from flexsat import limits
from flexsat.input_checks import FieldError
from flexsat.report.page import ReportedResult
from flexsat.scenarios.datasets import add_run_metrics
from flexsat.scenarios.errors import ScenarioError, item_path, locate
from flexsat.scenarios.fields import Document, SchemaSection, check_unique_labels, in_unit
from flexsat.scenarios.kind import Run, ScenarioKind, Simulation

if TYPE_CHECKING:
    import xarray as xr

    from flexsat.dynamics.tether import ClosedLoopRun, TetherScales

#: the gains each law takes (Junkins, Pollock & Rahman 1990, Att. 12 Eqs. 14-15, 18 and 20,
#: 24-25)
LAW_GAINS = {
    "decoupled": ("K1", "K2", "K3"),
    "coupled": ("K1", "K2", "K3", "K4"),
    "rate": ("K1", "K2", "K3"),
}


class TetherSystem(SchemaSection):
    """Subsatellite mass, reference length L and the orbit (altitude or rate)."""

    mass: Annotated[float, in_unit("kg", positive=True)]
    length: Annotated[float, in_unit("m", positive=True)]
    altitude: Annotated[float | None, in_unit("m")] = None
    orbit_rate: Annotated[float | None, in_unit("rad/s", positive=True)] = None

    @model_validator(mode="after")
    def _orbit(self) -> Self:
        self.scales()
        return self

    def scales(self) -> TetherScales:
        """The nondimensionalising scales (the orbit from its altitude or rate)."""
        from flexsat.dynamics.tether import TetherScales

        if self.altitude is None and self.orbit_rate is None:
            raise FieldError("altitude", "give the orbit's altitude or its orbit_rate")
        return TetherScales(
            mass=self.mass, length=self.length, altitude=self.altitude, orbit_rate=self.orbit_rate
        )


class TetherInitial(SchemaSection):
    """Initial length and libration (rates default to rest)."""

    length: Annotated[float, in_unit("m", positive=True)]
    pitch: Annotated[float, in_unit("rad")] = 0.0
    roll: Annotated[float, in_unit("rad")] = 0.0
    length_rate: Annotated[float | None, in_unit("m/s")] = None
    pitch_rate: Annotated[float, in_unit("rad/s")] = 0.0
    roll_rate: Annotated[float, in_unit("rad/s")] = 0.0

    @model_validator(mode="after")
    def _angles(self) -> Self:
        # Eq. 4 divides by cos φ (the roll is defined within ±90°), and a pitch is an angle of
        # one turn at most: a pitch of 1e12° is no libration, and its sine costs the adaptive
        # integrator every digit (minutes of vanishing steps)
        if not abs(self.pitch) <= np.pi:
            raise FieldError("pitch", f"must lie within ±180°, got {np.degrees(self.pitch):g}°")
        if not abs(self.roll) < 0.5 * np.pi:
            raise FieldError(
                "roll", f"must lie strictly within ±90° (Eq. 4), got {np.degrees(self.roll):g}°"
            )
        return self


class TetherSimulation(SchemaSection):
    """Run length in orbits, output (or control) samples per orbit and the integrator."""

    orbits: float = Field(gt=0, allow_inf_nan=False)
    samples_per_orbit: int = Field(1000, ge=20)
    integrator: Literal["continuous", "sampled"] = "continuous"

    @model_validator(mode="after")
    def _samples(self) -> Self:
        n = self.orbits * self.samples_per_orbit
        if n > limits.MAX_SAMPLES:
            raise FieldError(
                "simulation.samples_per_orbit",
                f"{n:.3g} samples is more than {limits.MAX_SAMPLES:,} (flexsat.limits.MAX_SAMPLES)",
            )
        return self


class TetherRunSpec(SchemaSection):
    """One law with its gains and final length."""

    label: str
    law: Literal["decoupled", "coupled", "rate"]
    gains: dict[str, float]
    final_length: Annotated[float, in_unit("m", positive=True)]
    printed_sign: bool = False

    @model_validator(mode="after")
    def _gains(self) -> Self:
        need = LAW_GAINS[self.law]
        missing = [k for k in need if k not in self.gains]
        extra = [k for k in self.gains if k not in need]
        if missing or extra:
            raise FieldError(
                "gains",
                f"law {self.law!r} takes {', '.join(need)}"
                + (f"; missing {', '.join(missing)}" if missing else "")
                + (f"; unknown {', '.join(extra)}" if extra else ""),
            )
        for k, v in self.gains.items():
            if not np.isfinite(v) or v < 0 or (k == "K1" and v == 0):
                rule = "> 0" if k == "K1" else ">= 0"
                raise FieldError("gains", f"{k} must be finite and {rule}, got {v!r}")
        if self.printed_sign and self.law != "decoupled":
            raise FieldError("printed_sign", "only the decoupled law (Eq. 15) has a printed sign")
        return self


class TetherScenario(Document):
    """A validated tether scenario (module docstring)."""

    kind: Literal["tether"]
    name: str
    system: TetherSystem
    initial: TetherInitial
    simulation: TetherSimulation
    runs: list[TetherRunSpec] = Field(min_length=1, max_length=limits.MAX_RUNS)

    @property
    def case(self) -> str:
        return "Vadali & Kim tethered subsatellite"

    @model_validator(mode="after")
    def _checks(self) -> Self:
        check_unique_labels(self.runs)
        from flexsat.dynamics.tether import MIN_LENGTH

        for index, run in enumerate(self.runs):
            if run.final_length <= MIN_LENGTH * self.system.length:
                raise FieldError(
                    f"runs{item_path(index, run.label)}.final_length",
                    f"{run.final_length * 1e3:g} mm is below the collapse threshold "
                    f"{MIN_LENGTH:g} L = {MIN_LENGTH * self.system.length:g} m of the model",
                )
        if self.initial.length_rate is not None and any(r.law == "rate" for r in self.runs):
            raise FieldError(
                "initial.length_rate", "a rate-law run sets the length rate itself; leave it out"
            )
        return self


# -- running -------------------------------------------------------------------------------------
@dataclass(frozen=True)
class TetherResult(ReportedResult):
    """The runs of a tether scenario.

    Attributes
    ----------
    scenario : TetherScenario
    labels : tuple of str
    runs : tuple of flexsat.dynamics.tether.ClosedLoopRun
        Nondimensional (τ, [λ, θ, φ, λ', θ', φ'], (T̂ or λ', F̂), ∫|F̂|dτ).
    scales : flexsat.dynamics.tether.TetherScales
    case_source : str
    notes : tuple of str
    """

    report_title = "flexsat tether report"

    scenario: TetherScenario
    labels: tuple[str, ...]
    runs: tuple[ClosedLoopRun, ...]
    scales: TetherScales
    case_source: str
    notes: tuple[str, ...] = ()

    def metrics_records(self) -> list[dict[str, Any]]:
        """One JSON-ready dict per run: the paper's measures
        (:func:`flexsat.cases.tether.measures`)."""
        from flexsat.cases.tether import measures

        records = []
        for spec, label, run in zip(self.scenario.runs, self.labels, self.runs):
            lf = spec.final_length / self.scales.length
            records.append({"run": label, **measures(run, lf, self.scales, spec.law)})
        return records

    def dataset(self) -> xr.Dataset:
        """Every run in one dataset over (run, time): time in s and ``orbits``; ``length`` (m),
        ``pitch``, ``roll`` (rad), ``tension`` (N, NaN under rate control), ``reel_rate`` (m/s,
        NaN under tension control), ``thrust`` (N), ``integral_of_motion`` (V1),
        ``thrust_index`` (∫|F̂|dτ), and the metrics per run."""
        import xarray as xr

        s = self.scales
        tau = self.runs[0].tau
        rate = np.array([spec.law == "rate" for spec in self.scenario.runs])

        def stack(f: Callable[[ClosedLoopRun], np.ndarray]) -> np.ndarray:
            return np.stack([f(r) for r in self.runs])

        command = stack(lambda r: r.control[0, :, 0])
        ds = xr.Dataset(
            {
                "length": (
                    ("run", "time"),
                    stack(lambda r: r.state[0, :, 0]) * s.length,
                    {"units": "m"},
                ),
                "pitch": (("run", "time"), stack(lambda r: r.state[0, :, 1]), {"units": "rad"}),
                "roll": (("run", "time"), stack(lambda r: r.state[0, :, 2]), {"units": "rad"}),
                "tension": (
                    ("run", "time"),
                    np.where(rate[:, None], np.nan, command * s.force),
                    {"units": "N"},
                ),
                "reel_rate": (
                    ("run", "time"),
                    np.where(rate[:, None], command * s.speed, np.nan),
                    {"units": "m/s"},
                ),
                "thrust": (
                    ("run", "time"),
                    stack(lambda r: r.control[0, :, 1]) * s.force,
                    {"units": "N"},
                ),
                "integral_of_motion": (("run", "time"), stack(lambda r: r.integral_of_motion[0])),
                "thrust_index": (("run", "time"), stack(lambda r: r.thrust_index[0])),
            },
            coords={
                "run": list(self.labels),
                "time": tau / s.orbit_rate,
                "orbits": ("time", tau / (2 * np.pi)),
            },
        )
        ds["time"].attrs["units"] = "s"
        add_run_metrics(ds, self.metrics_records())
        ds["law"] = ("run", [spec.law for spec in self.scenario.runs])
        ds.attrs.update(
            scenario_name=self.scenario.name,
            case=self.scenario.case,
            case_source=self.case_source,
            scenario_yaml=self.scenario.yaml_text,
            orbit_rate_rad_s=s.orbit_rate,
            mass_kg=s.mass,
            length_m=s.length,
            integrator=self.scenario.simulation.integrator,
        )
        return ds

    def figures(self, folder: Path, ds: xr.Dataset) -> list[str]:
        from flexsat.report.tether import draw_figures

        return draw_figures(ds, folder)

    def sections(self, ds: xr.Dataset, figures: list[str]) -> str:
        from flexsat.report.tether import sections

        return sections(self, self.metrics_records(), figures)


class TetherKind(ScenarioKind):
    """``kind: tether``: every law of the scenario from its initial state (module docstring);
    a run whose tether collapses or whose integration fails is reported under its label."""

    kind = "tether"
    document = TetherScenario

    def steps(self, scenario: TetherScenario) -> int:
        return len(scenario.runs)

    def plan(self, scenario: TetherScenario) -> Generator[Run, Any, TetherResult]:
        from flexsat.cases.tether import SOURCE, closed_loop_run, make_law, tether_simulation
        from flexsat.references import cite

        scales, sim = scenario.system.scales(), scenario.simulation
        tau = np.linspace(
            0.0, 2 * np.pi * sim.orbits, int(round(sim.orbits * sim.samples_per_orbit)) + 1
        )
        ini = scenario.initial
        x_si = np.array(
            [ini.length, ini.pitch, ini.roll, ini.length_rate or 0.0, ini.pitch_rate, ini.roll_rate]
        )
        runs = []
        for index, spec in enumerate(scenario.runs):
            path = "runs" + item_path(index, spec.label)
            try:
                law = make_law(
                    spec.law,
                    spec.gains,
                    spec.final_length / scales.length,
                    scales=scales,
                    printed_sign=spec.printed_sign,
                )
                plant, config, options = tether_simulation(
                    law, scales.state_from_si(x_si), tau, sim.integrator
                )
            except ValueError as exc:
                raise ScenarioError([locate(path, exc)]) from None
            result = yield Run(spec.label, Simulation(plant, law, config, options), path)
            runs.append(closed_loop_run(law, tau, result.dataset))
        notes = (
            "Straight massless tether, no aerodynamics, circular orbit (the paper's model, "
            "Att. 12, 'Equations of Motion'). Eq. 15 with the repaired sign −K3λφ' (the paper "
            "prints +, which "
            "diverges).",
            "Thrust index ∫|F̂|dτ over the run; impulse = index × mΩL "
            f"({scales.impulse:.4g} N s here). Settling: the time after which |θ| <= 5° and λ "
            "stays within 2 % of its change from the final length.",
        )
        return TetherResult(
            scenario,
            tuple(r.label for r in scenario.runs),
            tuple(runs),
            scales,
            cite(SOURCE),
            notes,
        )


__all__ = ["LAW_GAINS", "TetherKind", "TetherResult", "TetherScenario"]
