"""Model update: the undamped and damping identification of Creamer-Junkins (Junkins,
Pollock & Rahman 1990, Att. 7) in one call, returning the scaled model.

The differential correction of Att. 6 (free and forced response together) is in
:mod:`flexsat.identify.differential_correction`."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from flexsat.identify.structural.damping import DampingIdentification, identify_damping
from flexsat.identify.structural.substructures import (
    SubstructureModel,
)
from flexsat.identify.structural.undamped import UndampedIdentification, identify_undamped
from flexsat.input_checks import (
    FieldError,
)
from flexsat.units import FloatArray

__all__ = [
    "UpdatedModel",
    "update_model",
]


@dataclass(frozen=True)
class UpdatedModel:
    """Result of :func:`update_model`.

    Attributes
    ----------
    model : SubstructureModel whose blocks are scaled by the identified parameters (its nominal
        ``p = q = r = 1`` is the updated model).
    p, q, r : identified scalings.
    covariance : covariance of ``(p, q, r)`` stacked.
    undamped : UndampedIdentification; damping : DampingIdentification or None.
    """

    model: SubstructureModel
    p: FloatArray
    q: FloatArray
    r: FloatArray
    covariance: FloatArray
    undamped: UndampedIdentification
    damping: DampingIdentification | None


def update_model(
    model: SubstructureModel,
    measured_frequencies: npt.ArrayLike,
    measured_eigenvalues: npt.ArrayLike | None = None,
    damping_kwargs: dict[str, Any] | None = None,
    **kwargs: Any,
) -> UpdatedModel:
    """Identify ``p, q`` (and ``r`` from ``measured_eigenvalues``) and return the scaled model.

    ``kwargs`` go to :func:`identify_undamped`, ``damping_kwargs`` to :func:`identify_damping`.
    """
    if damping_kwargs is not None and not isinstance(damping_kwargs, Mapping):
        raise FieldError("damping_kwargs", f"must be a mapping, got {damping_kwargs!r}")
    und = identify_undamped(model, measured_frequencies, **kwargs)
    dmp = None
    R = model.n_damping
    r = np.ones(R)
    cov = np.zeros((model.n_stiffness + model.n_mass + R,) * 2)
    P_Q = model.n_stiffness + model.n_mass
    cov[:P_Q, :P_Q] = und.covariance
    if measured_eigenvalues is not None:
        dmp = identify_damping(model, measured_eigenvalues, und.p, und.q, **(damping_kwargs or {}))
        r = dmp.r
        cov[P_Q:, P_Q:] = dmp.covariance
    return UpdatedModel(model.scaled(und.p, und.q, r), und.p, und.q, r, cov, und, dmp)
