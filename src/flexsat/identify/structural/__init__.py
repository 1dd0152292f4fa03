"""Creamer-Junkins structural identification and model update (Junkins, Pollock & Rahman
1990, Att. 7).

* :mod:`~flexsat.identify.structural.substructures`: the substructure parameterisation;
* :mod:`~flexsat.identify.structural.undamped`: stiffness and mass scalings;
* :mod:`~flexsat.identify.structural.damping`: damping scalings;
* :mod:`~flexsat.identify.structural.model_update`: both in one call.
"""

from flexsat.identify.structural.damping import (
    DampingIdentification,
    damped_eigenvalues,
    identify_damping,
)
from flexsat.identify.structural.model_update import UpdatedModel, update_model
from flexsat.identify.structural.normalization import fit_modal_normalization
from flexsat.identify.structural.substructures import (
    SubstructureModel,
    modal_energy_distribution,
    substructures_from_builder,
)
from flexsat.identify.structural.undamped import UndampedIdentification, identify_undamped
from flexsat.identify.structural.validation import check_iterations

__all__ = [
    "SubstructureModel",
    "UndampedIdentification",
    "DampingIdentification",
    "UpdatedModel",
    "substructures_from_builder",
    "modal_energy_distribution",
    "fit_modal_normalization",
    "identify_undamped",
    "identify_damping",
    "update_model",
    "damped_eigenvalues",
    "check_iterations",
]
