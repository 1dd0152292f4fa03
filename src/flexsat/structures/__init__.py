"""Structural models: exact beam modes, a finite-element core, modal models and their import.

The NASTRAN and UFF readers (``io_nastran``, ``io_uff``) need the optional extras
``flexsat[nastran]`` (pyyeti) and ``flexsat[uff]`` (pyuff); they import them on first use. The
plain SOL 103 OP2 reader (``io_op2``) needs numpy only.
"""

from flexsat.structures.beam import (
    CLAMPED_FREE_BETA_L,
    FREE_FREE_BETA_L,
    CantileverModes,
    TipMassCantilever,
    clamped_free_beta_L,
    hub_free_frequencies,
)
from flexsat.structures.fem import DOF_NAMES, Assembly, FEModes, Structure
from flexsat.structures.io_nastran import read_nastran_modes
from flexsat.structures.io_op2 import Op2Modes, read_op2, read_op2_modes
from flexsat.structures.io_uff import (
    modal_model_from_uff,
    read_uff,
    read_uff_functions,
    write_modal_uff,
)
from flexsat.structures.modal_model import ModalModel, hub_appendage_matrices
from flexsat.structures.modal_solve import check_mass_matrix, solve_modes
from flexsat.structures.mode_description import classify_modes, describe_modes
from flexsat.structures.sections import Material, Section

__all__ = [
    "CLAMPED_FREE_BETA_L",
    "DOF_NAMES",
    "FREE_FREE_BETA_L",
    "Assembly",
    "CantileverModes",
    "FEModes",
    "Material",
    "ModalModel",
    "Op2Modes",
    "Section",
    "Structure",
    "TipMassCantilever",
    "check_mass_matrix",
    "clamped_free_beta_L",
    "classify_modes",
    "describe_modes",
    "hub_appendage_matrices",
    "hub_free_frequencies",
    "modal_model_from_uff",
    "read_nastran_modes",
    "read_op2",
    "read_op2_modes",
    "read_uff",
    "read_uff_functions",
    "solve_modes",
    "write_modal_uff",
]
