"""Benchmark library: one module per published system, parameters entered as published.

Every case builder returns an object with ``frequencies_hz(n_modes)`` (the first natural
frequencies of its structural model, rigid-body modes included where the published table lists
them); it may add ``mode_descriptions(n_modes)`` (one phrase per mode) and
``mode_details(n_modes)`` (further JSON-ready tables for ``flexsat modes``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from flexsat.cases.agrawal_bang import SOURCE as AGRAWAL_BANG_SOURCE
from flexsat.cases.agrawal_bang import agrawal_bang
from flexsat.cases.bainum import SOURCE as BAINUM_SOURCE
from flexsat.cases.bainum import bainum
from flexsat.cases.beams import SOURCE_BEAMS, SOURCE_FV2, cantilever_beam, free_free_beam, nafems_fv2
from flexsat.cases.draper_rpl import SOURCE as DRAPER_RPL_SOURCE
from flexsat.cases.draper_rpl import draper_rpl
from flexsat.cases.eps import SOURCE as EPS_SOURCE
from flexsat.cases.eps import eps
from flexsat.cases.nps import SOURCE as NPS_SOURCE
from flexsat.cases.nps import nps
from flexsat.cases.tamu import SOURCE as TAMU_SOURCE
from flexsat.cases.tamu import tamu
from flexsat.cases.tamu_grid import SOURCE as TAMU_GRID_SOURCE
from flexsat.cases.tamu_grid import tamu_grid


@dataclass(frozen=True)
class CaseInfo:
    name: str
    builder: Callable
    source: str
    description: str


CASES: dict[str, CaseInfo] = {
    info.name: info
    for info in (
        CaseInfo("tamu", tamu, TAMU_SOURCE,
                 "Texas A&M rigid hub with four flexible appendages and tip masses, "
                 "single-axis slews"),
        CaseInfo("tamu_grid", tamu_grid, TAMU_GRID_SOURCE,
                 "Texas A&M 5 ft x 5 ft aluminium grid hanging in a vertical plane, "
                 "plate-grid elements, optional gravity stiffening"),
        CaseInfo("draper_rpl", draper_rpl, DRAPER_RPL_SOURCE,
                 "Draper/RPL hub with four appendages, Ritz model with comparison functions "
                 "(Table 4)"),
        CaseInfo("eps", eps, EPS_SOURCE,
                 "Earth Pointing Satellite: 25 m graphite truss with 15 m and 7.5 m antennas"),
        CaseInfo("nps", nps, NPS_SOURCE,
                 "NPS Flexible Spacecraft Simulator: hub with a cantilevered astromast and "
                 "reflector, hybrid coordinates"),
        CaseInfo("agrawal_bang", agrawal_bang, AGRAWAL_BANG_SOURCE,
                 "Agrawal-Bang two-beam L structure with three collocated piezoelectric pairs"),
        CaseInfo("bainum", bainum, BAINUM_SOURCE,
                 "Bainum & Reddy free-free beam in orbit: pitch + bending with gravity gradient, "
                 "point-force actuators (controllability, decoupling, per-mode LQR)"),
        CaseInfo("cantilever_beam", cantilever_beam, SOURCE_BEAMS,
                 "uniform cantilever, 3-D frame elements, against the exact beta L"),
        CaseInfo("free_free_beam", free_free_beam, SOURCE_BEAMS,
                 "uniform free-free beam, 3-D frame elements, six rigid modes"),
        CaseInfo("nafems_fv2", nafems_fv2, SOURCE_FV2,
                 "NAFEMS FV2 pin-ended double cross, in-plane frame vibration"),
    )
}


def get_case(name: str) -> CaseInfo:
    try:
        return CASES[name]
    except KeyError:
        raise ValueError(f"case: unknown case {name!r}; known: {sorted(CASES)}") from None


__all__ = ["CASES", "CaseInfo", "agrawal_bang", "bainum", "cantilever_beam", "draper_rpl", "eps",
           "free_free_beam", "get_case", "nafems_fv2", "nps", "tamu", "tamu_grid"]
