"""The placement stage of a design study (``kind: design_study``, ``placement:``):
``number`` point-force actuators along body axes chosen among ``candidates`` (every node ×
axis) of the kept modes, and the spacecraft the placement makes.

Criteria: ``h2`` ranks the candidates by the energy of the EPS slew study c. 1989 Eq. (8)
(:func:`~flexsat.analysis.placement.h2_actuator_ranking`; disturbance: torques about x, y, z
at ``disturbance_node``, outputs: the displacements of ``outputs`` along x, y, z) and takes the
best; ``kim_junkins`` searches the sets (``search``: greedy, exchange or exhaustive) for the
largest α of Kim & Junkins (Y. Kim and J. L. Junkins, "A Measure of Controllability for
Actuator Placement", AIAA GNC 1990; :func:`~flexsat.analysis.placement.kim_junkins_score`, on
the elastic modes, output rows as above). Each placed force has a collocated displacement
sensor.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Literal, Self

import numpy as np
from pydantic import Field, model_validator

from flexsat.design.stages import read_arrays, write_arrays
from flexsat.input_checks import FieldError
from flexsat.scenarios.design_laws import StudySection
from flexsat.scenarios.fields import integer_in

if TYPE_CHECKING:
    from flexsat.dynamics.flexible_spacecraft import FlexibleSpacecraft
    from flexsat.structures.modal_model import ModalModel

Axis = Literal["x", "y", "z"]


class CandidatesSpec(StudySection):
    """Candidate force actuators: every node along every axis."""

    nodes: list[int] = Field(min_length=1, max_length=1000)
    axes: list[Axis] = Field(default=["x", "y", "z"], min_length=1)

    @model_validator(mode="after")
    def _distinct(self) -> Self:
        for name in ("nodes", "axes"):
            values = getattr(self, name)
            if len(set(values)) != len(values):
                raise FieldError(name, f"must be distinct, got {values}")
        return self


class PlacementSpec(StudySection):
    """Actuator placement (module docstring)."""

    torque_node: int | None = None
    candidates: CandidatesSpec
    number: Annotated[int, integer_in(0, 100)]
    criterion: Literal["h2", "kim_junkins"] = "h2"
    search: Literal["greedy", "exchange", "exhaustive"] = "greedy"
    disturbance_node: int | None = None
    outputs: list[int] = Field(min_length=1, max_length=100)
    gamma: float = Field(1.0, gt=0.0)

    @model_validator(mode="after")
    def _sizes(self) -> Self:
        n = len(self.candidates.nodes) * len(self.candidates.axes)
        if self.number > n:
            raise FieldError(
                "number", f"at most the {n} candidates (nodes × axes), got {self.number}"
            )
        if self.criterion == "h2" and self.disturbance_node is None and self.torque_node is None:
            raise FieldError("disturbance_node", "the h2 criterion needs a disturbance node")
        return self


@dataclass(frozen=True)
class PlacementResult:
    """The placement stage's result.

    Attributes
    ----------
    selection : tuple of str
        The placed forces, ``"<node><AXIS>"`` (``"69X"``).
    scores : dict of str to float
        The criterion of every candidate (h2) or of the best set after each step (search).
    criterion_value : float
        The criterion of the selection (h2: the sum of its energies; kim_junkins: α).
    """

    selection: tuple[str, ...]
    scores: dict[str, float]
    criterion_value: float

    def forces(self) -> list[tuple[int, str]]:
        """The placed forces as (node, axis)."""
        return [(int(label[:-1]), label[-1].lower()) for label in self.selection]


def _check_nodes(model: ModalModel, nodes: list[int], field: str) -> None:
    known = set(model.node_ids.tolist())
    for node in nodes:
        if node not in known:
            raise FieldError(field, f"node {node} is not a node of the model")


def place_actuators(model: ModalModel, spec: PlacementSpec) -> PlacementResult:
    """The placement stage (module docstring).

    Raises
    ------
    ValueError
        Naming the field of ``placement``.
    """
    from flexsat.analysis.placement import (
        actuator_candidates,
        exchange,
        exhaustive,
        greedy,
        h2_actuator_ranking,
        kim_junkins_score,
    )

    _check_nodes(model, spec.candidates.nodes, "candidates.nodes")
    _check_nodes(model, spec.outputs, "outputs")
    for name in ("torque_node", "disturbance_node"):
        node = getattr(spec, name)
        if node is not None:
            _check_nodes(model, [node], name)
    if spec.number == 0:
        return PlacementResult((), {}, 0.0)
    candidates = actuator_candidates(model, spec.candidates.nodes, spec.candidates.axes)
    outputs = np.vstack([model.displacement_output(n, ["x", "y", "z"]).T for n in spec.outputs])
    if spec.criterion == "h2":
        node = spec.disturbance_node if spec.disturbance_node is not None else spec.torque_node
        assert node is not None  # the schema requires one for h2
        disturbance = model.torque_input(node, ["x", "y", "z"])
        ranking = h2_actuator_ranking(model, candidates, disturbance, outputs, gamma=spec.gamma)
        selection = tuple(str(label) for label in ranking.top(spec.number))
        scores = {str(k): float(v) for k, v in ranking.scores.items()}
        return PlacementResult(selection, scores, float(sum(scores[k] for k in selection)))
    elastic = model.elastic()
    vectors = actuator_candidates(elastic, spec.candidates.nodes, spec.candidates.axes)
    rows = np.vstack([elastic.displacement_output(n, ["x", "y", "z"]).T for n in spec.outputs])
    score = kim_junkins_score(elastic, vectors, Cq=rows)
    labels = list(vectors)
    if spec.search == "greedy":
        found = greedy(labels, spec.number, score)
    elif spec.search == "exchange":
        found = exchange(labels, spec.number, score)
    else:
        found = exhaustive(labels, spec.number, score)
    path = {", ".join(map(str, chosen)): float(value) for value, chosen in found.best}
    return PlacementResult(tuple(str(k) for k in found.selection), path, float(found.score))


def write_placement(result: PlacementResult, folder: Path) -> None:
    write_arrays(
        folder,
        {},
        {
            "selection": list(result.selection),
            "scores": result.scores,
            "criterion_value": result.criterion_value,
        },
    )


def read_placement(folder: Path) -> PlacementResult:
    _, info = read_arrays(folder)
    return PlacementResult(
        tuple(info["selection"]), dict(info["scores"]), float(info["criterion_value"])
    )


def spacecraft(
    model: ModalModel, spec: PlacementSpec, placement: PlacementResult
) -> FlexibleSpacecraft:
    """The spacecraft of the kept modes with the torquers, the placed forces, their collocated
    displacement sensors and the ``outputs`` displacements."""
    from flexsat.dynamics.flexible_spacecraft import FlexibleSpacecraft

    forces = placement.forces()
    outputs = [(n, a) for n in spec.outputs for a in "xyz"]
    sensors = outputs + [f for f in forces if f not in outputs]
    return FlexibleSpacecraft(
        model, forces=forces, displacements=sensors, torque_node=spec.torque_node
    )


__all__ = [
    "CandidatesSpec",
    "PlacementResult",
    "PlacementSpec",
    "place_actuators",
    "read_placement",
    "spacecraft",
    "write_placement",
]
