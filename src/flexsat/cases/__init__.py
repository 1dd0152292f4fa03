"""Benchmark library: one module per published system, parameters entered as published.

Every case builder returns an object with ``frequencies_hz(n_modes)`` (the first natural
frequencies of its structural model, rigid-body modes included where the published table lists
them); it may add ``mode_descriptions(n_modes)`` (one phrase
per mode) and ``mode_details(n_modes)`` (further JSON-ready tables for ``flexsat modes``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from flexsat.cases.draper_rpl import SOURCE as DRAPER_RPL_SOURCE
from flexsat.cases.draper_rpl import draper_rpl
from flexsat.cases.tamu import tamu


@dataclass(frozen=True)
class CaseInfo:
    name: str
    builder: Callable
    source: str
    description: str


CASES: dict[str, CaseInfo] = {
    "tamu": CaseInfo(
        "tamu",
        tamu,
        "seed 000_7bfdb62d2eacc22a.txt, Att. 3 Table 1 (Junkins, Rahman & Bang 1990)",
        "Texas A&M rigid hub with four flexible appendages and tip masses, single-axis slews",
    ),
    "draper_rpl": CaseInfo(
        "draper_rpl",
        draper_rpl,
        DRAPER_RPL_SOURCE,
        "Draper/RPL hub with four appendages, Ritz model with comparison functions (Table 4)",
    ),
}


def get_case(name: str) -> CaseInfo:
    try:
        return CASES[name]
    except KeyError:
        raise ValueError(f"case: unknown case {name!r}; known: {sorted(CASES)}") from None


__all__ = ["CASES", "CaseInfo", "draper_rpl", "get_case", "tamu"]
