"""Structural models: exact beam modes (beam.py) and a finite-element core (fem.py)."""

from flexsat.structures.beam import (
    CLAMPED_FREE_BETA_L,
    FREE_FREE_BETA_L,
    CantileverModes,
    TipMassCantilever,
    clamped_free_beta_L,
    hub_free_frequencies,
)
from flexsat.structures.fem import DOF_NAMES, Assembly, FEModes, Structure
from flexsat.structures.modal_solve import check_mass_matrix, solve_modes
from flexsat.structures.sections import Material, Section

__all__ = [
    "CLAMPED_FREE_BETA_L",
    "DOF_NAMES",
    "FREE_FREE_BETA_L",
    "Assembly",
    "CantileverModes",
    "FEModes",
    "Material",
    "Section",
    "Structure",
    "TipMassCantilever",
    "check_mass_matrix",
    "clamped_free_beta_L",
    "hub_free_frequencies",
    "solve_modes",
]
