"""Benchmark library: one module per published system, parameters entered as published.

Every case builder returns an object with ``frequencies_hz(n_modes)`` (the first natural
frequencies of its structural model, rigid-body modes included where the published table lists
them); it may add ``mode_descriptions(n_modes)`` (one phrase per mode) and
``mode_details(n_modes)`` (further JSON-ready tables for ``flexsat modes``).

The catalogue (:data:`CASES`: name, source, description, and the builder imported on use) lives
in :mod:`flexsat.catalog`, which loads no numerical code; importing this package loads every
case.
"""

from __future__ import annotations

from flexsat.cases.agrawal_bang import agrawal_bang
from flexsat.cases.bainum import bainum
from flexsat.cases.beams import cantilever_beam, free_free_beam, nafems_fv2
from flexsat.cases.draper_rpl import draper_rpl
from flexsat.cases.eps import eps
from flexsat.cases.nps import nps
from flexsat.cases.tamu import tamu
from flexsat.cases.tamu_grid import tamu_grid
from flexsat.catalog import CASES, CaseInfo, get_case

__all__ = [
    "CASES",
    "CaseInfo",
    "agrawal_bang",
    "bainum",
    "cantilever_beam",
    "draper_rpl",
    "eps",
    "free_free_beam",
    "get_case",
    "nafems_fv2",
    "nps",
    "tamu",
    "tamu_grid",
]
