"""Structural models: exact modes of uniform cantilevers with tip bodies, free-hub frequencies."""

from flexsat.structures.beam import (
    CLAMPED_FREE_BETA_L,
    FREE_FREE_BETA_L,
    CantileverModes,
    TipMassCantilever,
    clamped_free_beta_L,
    hub_free_frequencies,
)

__all__ = [
    "CLAMPED_FREE_BETA_L",
    "FREE_FREE_BETA_L",
    "CantileverModes",
    "TipMassCantilever",
    "clamped_free_beta_L",
    "hub_free_frequencies",
]
