"""The placement stage of a design study (flexsat.scenarios.design_placement) on a tiny model."""

from __future__ import annotations

import numpy as np
import pytest

from flexsat.analysis.placement import actuator_candidates, kim_junkins_score
from flexsat.input_checks import FieldError
from flexsat.scenarios.design_placement import (
    PlacementSpec,
    place_actuators,
    read_placement,
    spacecraft,
    write_placement,
)
from flexsat.structures.modal_model import ModalModel


def _model() -> ModalModel:
    """Three elastic modes on three nodes, random shapes (seeded), a 300 kg rigid body."""
    rigid = np.zeros((6, 6))
    rigid[:3, :3] = 300.0 * np.eye(3)
    rigid[3:, 3:] = np.diag([100.0, 150.0, 200.0])
    return ModalModel(
        node_ids=[1, 2, 3],
        coordinates=[[2.0, 0, 0], [0, 3.0, 0], [0, 0, 1.0]],
        frequencies=2 * np.pi * np.array([0.4, 0.9, 1.7]),
        damping=0.01,
        shapes=0.1 * np.random.default_rng(5).standard_normal((3, 3, 6)),
        rigid_mass=rigid,
        participation=np.zeros((3, 6)),
    )


def _spec(**changes) -> PlacementSpec:
    data = {
        "torque_node": 1,
        "candidates": {"nodes": [2, 3], "axes": ["x", "y"]},
        "number": 1,
        "criterion": "kim_junkins",
        "outputs": [2],
        **changes,
    }
    return PlacementSpec.model_validate(data)


def _single_scores(model: ModalModel) -> dict[str, float]:
    """The Kim–Junkins α of each candidate alone, computed here from the analysis functions."""
    elastic = model.elastic()
    vectors = actuator_candidates(elastic, [2, 3], ["x", "y"])
    rows = elastic.displacement_output(2, ["x", "y", "z"]).T
    score = kim_junkins_score(elastic, vectors, Cq=rows)
    return {str(k): score((k,)) for k in vectors}


@pytest.mark.parametrize("search", ["greedy", "exchange", "exhaustive"])
def test_one_actuator_every_search_finds_the_best_single_candidate(search):
    """With one actuator to place, greedy, exchange and exhaustive search all return the
    candidate of the largest α, and that α as the criterion (same arithmetic: rel 1e-12)."""
    model = _model()
    singles = _single_scores(model)
    best = max(singles, key=singles.__getitem__)
    result = place_actuators(model, _spec(search=search))
    assert result.selection == (best,)
    assert result.criterion_value == pytest.approx(singles[best], rel=1e-12)


def test_exhaustive_search_is_never_beaten_by_greedy_or_exchange():
    """Two of four candidates: exhaustive scores all six sets, so its α bounds the others'."""
    model = _model()
    value = {
        s: place_actuators(model, _spec(number=2, search=s)).criterion_value
        for s in ("greedy", "exchange", "exhaustive")
    }
    assert value["exhaustive"] >= max(value["greedy"], value["exchange"])


def test_h2_takes_the_best_ranked_candidates_and_sums_their_energies():
    model = _model()
    result = place_actuators(model, _spec(criterion="h2", number=2, disturbance_node=1))
    ranked = sorted(result.scores, key=result.scores.__getitem__, reverse=True)
    assert set(result.selection) == set(ranked[:2])
    assert result.criterion_value == pytest.approx(sum(result.scores[k] for k in ranked[:2]))


def test_each_placed_force_gets_a_collocated_sensor_and_the_result_round_trips(tmp_path):
    """The spacecraft senses the outputs' x, y, z and each placed force's own point and axis,
    once each (a force at an output point is not sensed twice)."""
    model = _model()
    spec = _spec(number=2, search="exhaustive", outputs=[2, 3])
    result = place_actuators(model, spec)
    plant = spacecraft(model, spec, result)
    outputs = [(n, a) for n in (2, 3) for a in "xyz"]
    assert set(result.forces()) <= set(outputs)  # the forces sit on output points here
    assert list(plant.displacements) == outputs
    write_placement(result, tmp_path)
    assert read_placement(tmp_path) == result


def test_forces_off_the_outputs_get_their_own_sensors():
    model = _model()
    spec = _spec(number=2, search="exhaustive")
    result = place_actuators(model, spec)
    plant = spacecraft(model, spec, result)
    outputs = [(2, a) for a in "xyz"]
    extra = [f for f in result.forces() if f not in outputs]
    assert extra  # this model's best pair is at node 3 (else the test would show nothing)
    assert list(plant.displacements) == outputs + extra


def test_no_actuators_and_unknown_nodes():
    assert place_actuators(_model(), _spec(number=0)).selection == ()
    with pytest.raises(FieldError, match="outputs: node 9 is not a node of the model"):
        place_actuators(_model(), _spec(outputs=[9]))
    with pytest.raises(ValueError, match="number.*at most the 4 candidates"):
        _spec(number=5)
