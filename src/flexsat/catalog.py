"""The benchmark cases by name: where each comes from and what it is, without loading it.

``flexsat cases`` lists this catalogue and ``flexsat run`` / ``flexsat modes`` look a name up in
it before anything heavy is imported: a :class:`CaseInfo` holds the module and function of its
builder, which :attr:`CaseInfo.builder` imports on first use. :mod:`flexsat.cases` re-exports
the catalogue with the builders themselves.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class CaseInfo:
    """A case: its ``name``, the ``module`` of :mod:`flexsat.cases` and the ``function`` in it
    that builds the case, its ``source`` (seed file and where in it, or a reference; see
    :func:`flexsat.references.cite`) and a one-line ``description``."""

    name: str
    module: str
    function: str
    source: str
    description: str

    @property
    def builder(self) -> Callable[..., Any]:
        """The builder, imported on first use (with its numerical dependencies)."""
        builder: Callable[..., Any] = getattr(
            importlib.import_module(f"flexsat.cases.{self.module}"), self.function
        )
        return builder


_BEAMS = "Blevins, Formulas for Natural Frequency and Mode Shape (1979), Table 8-1"

CASES: dict[str, CaseInfo] = {
    info.name: info
    for info in (
        CaseInfo(
            "tamu",
            "tamu",
            "tamu",
            "seed 000_7bfdb62d2eacc22a.txt, Att. 3 Table 1 (L1302-L1323) and §V",
            "Texas A&M rigid hub with four flexible appendages and tip masses, single-axis slews",
        ),
        CaseInfo(
            "tamu_grid",
            "tamu_grid",
            "tamu_grid",
            "seed 000_7bfdb62d2eacc22a.txt, Att. 4 Table 1 (L1648-L1655), Att. 6 "
            "(L2405-L2705), Att. 8 Fig. 4 (L3234-L3246)",
            "Texas A&M 5 ft x 5 ft aluminium grid hanging in a vertical plane, "
            "plate-grid elements, optional gravity stiffening",
        ),
        CaseInfo(
            "draper_rpl",
            "draper_rpl",
            "draper_rpl",
            "seed 000_7bfdb62d2eacc22a.txt, Att. 5 Table 3 (L2156-L2166), Eqs. 50-59, Table 4",
            "Draper/RPL hub with four appendages, Ritz model with comparison functions (Table 4)",
        ),
        CaseInfo(
            "eps",
            "eps",
            "eps",
            "seed 003_6d17262716e94f5f.txt, L66-L136 (EPS model), L238-L295 (node numbers)",
            "Earth Pointing Satellite: 25 m graphite truss with 15 m and 7.5 m antennas",
        ),
        CaseInfo(
            "nps",
            "nps",
            "nps",
            "seed 001_79dfdfba94ed8e0d.txt (NPS FSS), L21, L181, L208-L220",
            "NPS Flexible Spacecraft Simulator: hub with a cantilevered astromast and "
            "reflector, hybrid coordinates",
        ),
        CaseInfo(
            "agrawal_bang",
            "agrawal_bang",
            "agrawal_bang",
            "seed 004_680d3fec9e1f8c83.txt, §4 L205-L303",
            "Agrawal-Bang two-beam L structure with three collocated piezoelectric pairs",
        ),
        CaseInfo(
            "bainum",
            "bainum",
            "bainum",
            "seed 002_c3272b32d7cac32e.txt (NASA CR-158684), Ch. II-IV, App. A",
            "Bainum & Reddy free-free beam in orbit: pitch + bending with gravity gradient, "
            "point-force actuators (controllability, decoupling, per-mode LQR)",
        ),
        CaseInfo(
            "cantilever_beam",
            "beams",
            "cantilever_beam",
            _BEAMS,
            "uniform cantilever, 3-D frame elements, against the exact beta L",
        ),
        CaseInfo(
            "free_free_beam",
            "beams",
            "free_free_beam",
            _BEAMS,
            "uniform free-free beam, 3-D frame elements, six rigid modes",
        ),
        CaseInfo(
            "nafems_fv2",
            "beams",
            "nafems_fv2",
            "NAFEMS R0015 Selected Benchmarks for Natural Frequency Analysis (1987), test FV2",
            "NAFEMS FV2 pin-ended double cross, in-plane frame vibration",
        ),
    )
}


def get_case(name: str) -> CaseInfo:
    """The catalogue entry of ``name``.

    Raises
    ------
    ValueError
        For an unknown name, listing the known ones.
    """
    try:
        return CASES[name]
    except KeyError:
        raise ValueError(f"case: unknown case {name!r}; known: {sorted(CASES)}") from None


__all__ = ["CASES", "CaseInfo", "get_case"]
