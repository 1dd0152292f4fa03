"""The plants a simulation scenario names (:mod:`flexsat.scenarios.simulation_plants`): the
simulation cases are exactly the cases whose built object has a ``plant`` (checked by building
every case, against the registry's reading of annotations that builds none); a case's plant is
the one its object builds, with the options checked against ``plant()``'s signature and each
refusal naming the field; a plug-in case class with a plant is offered."""

from __future__ import annotations

import numpy as np
import pytest

from flexsat.catalog import CASES, get_case
from flexsat.scenarios.simulation_plants import (
    CasePlant,
    CasePlantOptions,
    PlantContext,
    simulation_cases,
    simulation_plants,
)


def test_simulation_cases_are_the_cases_whose_object_builds_a_plant():
    # the registry reads return annotations so that reading a scenario builds nothing; building
    # every built-in case is the independent check of that reading
    built = {name for name in CASES if callable(getattr(get_case(name).builder(), "plant", None))}
    assert set(simulation_cases()) == built
    assert {"tamu", "nps"}.isdisjoint(built)  # hub-and-appendage maneuver cases: no plant()
    plants = simulation_plants()
    assert [n for n in plants if n in CASES] == list(simulation_cases())
    assert all(isinstance(plants[n], CasePlant) and plants[n].case == n for n in built)


def test_a_case_plant_is_the_plant_its_case_object_builds():
    plant = CasePlant("eps").from_scenario(
        CasePlantOptions(model="rigid"), PlantContext(case="eps")
    )
    direct = get_case("eps").builder().plant(model="rigid")
    assert type(plant) is type(direct) and plant.nx == direct.nx
    np.testing.assert_array_equal(plant.inertia, direct.inertia)
    assert [c.name for c in plant.inputs] == [c.name for c in direct.inputs]


@pytest.mark.parametrize(
    "case, options, context, message",
    [
        ("eps", {"stiffness": 3}, "eps", "stiffness: not an option of the eps plant (its options"),
        ("eps", {}, "bainum", "name: 'eps' is the plant of case 'eps', not of the scenario's"),
    ],
)
def test_a_case_plant_refuses_by_field(case, options, context, message):
    with pytest.raises(ValueError) as info:
        CasePlant(case).from_scenario(CasePlantOptions(**options), PlantContext(case=context))
    assert str(info.value).startswith(message)


class Carts:
    """A case builder that is a class with a plant: what a plug-in case may offer."""

    def plant(self, k: float = 1.0):
        from flexsat_example_plugin.plant import TwoMassSpring

        return TwoMassSpring(k=k)


def test_a_case_class_with_a_plant_offers_it(monkeypatch):
    """A case whose builder is a class with ``plant()`` is a simulation case, found on the
    class (a function builder: on its return annotation) without building it."""
    import flexsat.scenarios.simulation_plants as plants
    from flexsat.catalog import CASES, CaseInfo

    info = CaseInfo("carts", __name__, "Carts", "a test", "two carts")
    monkeypatch.setattr(plants, "all_cases", lambda: {**CASES, "carts": info})
    plants.simulation_cases.cache_clear()
    try:
        assert plants.simulation_cases()[-1] == "carts" and "tamu" not in plants.simulation_cases()
        assert isinstance(plants.simulation_plants()["carts"], plants.CasePlant)
    finally:
        plants.simulation_cases.cache_clear()
