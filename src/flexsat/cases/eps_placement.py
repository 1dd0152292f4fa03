"""The actuator-placement study of the EPS slew study c. 1989 ("Actuator Placement") on the
reconstructed EPS.

The generic H2 ranking is :func:`flexsat.analysis.placement.h2_actuator_ranking`; this module
supplies the EPS candidates, disturbance and outputs of the paper and its published top 5
(docs/placement.md, "EPS reproduction").
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from flexsat.analysis.placement import H2Ranking, actuator_candidates, h2_actuator_ranking
from flexsat.cases.eps import EPSCase, eps
from flexsat.units import FloatArray

if TYPE_CHECKING:
    from flexsat.structures.modal_model import ModalModel

#: EPS slew study c. 1989, "Actuator Placement": candidate force-actuator nodes (x, y, z
#: each), outputs, published top 5.
EPS_CANDIDATE_NODES = (69, 66, 63, 60, 52, 95, 94, 88, 78)
EPS_OUTPUT_NODES = (69, 66, 95)
EPS_DISTURBANCE_NODE = 95
EPS_PUBLISHED_TOP5 = ("69X", "66X", "63X", "60X", "88X")


def eps_h2_setup(
    case: EPSCase | None = None, n_modes: int = 20
) -> tuple[ModalModel, dict[str, FloatArray], FloatArray, FloatArray]:
    """The placement set-up of the EPS slew study c. 1989 ("Actuator Placement") on the
    reconstructed EPS model.

    Candidates: force actuators at nodes 69, 66, 63, 60, 52, 95, 94, 88, 78 along x, y, z
    (27, labelled "69X" …; the paper's axis letters are taken as ours, an assumption: the
    paper's frame is lost with Fig. 1). Disturbance: the torquers at the CG node 95 about x, y,
    z. Outputs: displacements of nodes 69, 66, 95 along x, y, z. Paper nodes are mapped with
    ``case.node_roles``.

    Returns
    -------
    model : ModalModel (6 rigid + ``n_modes`` elastic modes, 0.5 % damping)
    actuators : dict label -> (n,) ; disturbance : (n, 3) ; outputs : (9, n)
    """
    case = eps() if case is None else case
    model = case.modal_model(n_modes)
    roles = case.node_roles
    actuators = actuator_candidates(
        model,
        [roles[p] for p in EPS_CANDIDATE_NODES],
        ("x", "y", "z"),
        label=lambda kind, node, axis: f"{_paper(roles, node)}{axis.upper()}",
    )
    disturbance = model.torque_input(roles[EPS_DISTURBANCE_NODE], ["x", "y", "z"])
    outputs = np.vstack(
        [model.displacement_output(roles[p], ["x", "y", "z"]).T for p in EPS_OUTPUT_NODES]
    )
    return model, actuators, disturbance, outputs


def _paper(roles: dict, node: int) -> int:
    inverse = {v: k for k, v in roles.items()}
    return inverse.get(node, node)


def eps_h2_ranking(
    case: EPSCase | None = None,
    n_modes: int = 20,
    gamma: float = 1.0,
    rigid: str = "project",
    measure: str = "energy",
) -> H2Ranking:
    """:func:`~flexsat.analysis.placement.h2_actuator_ranking` on :func:`eps_h2_setup`; compare
    ``.top(5)`` with ``EPS_PUBLISHED_TOP5`` = 69X, 66X, 63X, 60X, 88X (EPS
    slew study c. 1989, "Actuator Placement")."""
    model, actuators, disturbance, outputs = eps_h2_setup(case, n_modes)
    return h2_actuator_ranking(
        model, actuators, disturbance, outputs, gamma=gamma, rigid=rigid, measure=measure
    )


__all__ = [
    "EPS_CANDIDATE_NODES",
    "EPS_DISTURBANCE_NODE",
    "EPS_OUTPUT_NODES",
    "EPS_PUBLISHED_TOP5",
    "eps_h2_ranking",
    "eps_h2_setup",
]
