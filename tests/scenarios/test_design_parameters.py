"""``parameters:`` of a ``design`` scenario's reference problem take units
(flexsat.scenarios.design_parameters, issue 23): converted once to the SI the problem holds,
wrong dimensions, unknown names, booleans and fractional counts refused at
``parameters.<field>``."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

from flexsat.design.reference_problems import CantileverTube, HubBoomCodesign
from flexsat.input_checks import FieldError
from flexsat.scenarios.design_parameters import PARAMETER_UNITS, reference_parameters
from flexsat.scenarios.design_problem import REFERENCE_PROBLEMS, ConfiguredProblem
from flexsat.scenarios.documents import load_scenario
from flexsat.scenarios.errors import ScenarioError

EXAMPLE = Path(__file__).parents[2] / "examples" / "tamu_codesign_pareto.yaml"


def test_quantities_are_converted_to_the_si_the_problem_holds():
    got = reference_parameters(
        "hub_boom_codesign",
        HubBoomCodesign,
        {
            "hub_inertia": "4000 kg*cm**2",
            "tip_mass": "200 g",
            "length": 1.2,  # a bare number is SI
            "elements": 6.0,  # an integral float is a count
            "frequency_min_hz": "360 1/min",
            "thickness_bounds": ["0.5 mm", "3 mm"],
            "initial_angle": "30 deg",
        },
    )
    assert got["hub_inertia"] == pytest.approx(0.4, rel=1e-15)
    assert got["tip_mass"] == pytest.approx(0.2, rel=1e-15)
    assert got["length"] == 1.2 and got["elements"] == 6 and isinstance(got["elements"], int)
    assert got["frequency_min_hz"] == pytest.approx(6.0, rel=1e-15)
    assert got["thickness_bounds"] == pytest.approx((5e-4, 3e-3), rel=1e-15)
    assert got["initial_angle"] == pytest.approx(np.pi / 6, rel=1e-15)


@pytest.mark.parametrize(
    ("parameters", "field"),
    [
        ({"hub_inertia": "3 kg"}, "parameters.hub_inertia"),
        ({"hub_inertia": True}, "parameters.hub_inertia"),
        ({"colour": 1}, "parameters.colour"),
        ({"_memo": {}}, "parameters._memo"),
        ({"elements": 2.5}, "parameters.elements"),
        ({"elements": 10**9}, "parameters.elements"),
        ({"thickness_bounds": ["1 mm"]}, "parameters.thickness_bounds"),
        ({"thickness_bounds": "1 mm"}, "parameters.thickness_bounds"),
        ({"diameter_bounds": ["10 mm", "2 s"]}, "parameters.diameter_bounds[1]"),
    ],
    ids=[
        "dimension",
        "boolean",
        "unknown",
        "private",
        "fraction",
        "huge",
        "length",
        "scalar",
        "item",
    ],
)
def test_bad_parameters_are_refused_naming_the_field(parameters, field):
    with pytest.raises(FieldError) as info:
        reference_parameters("hub_boom_codesign", HubBoomCodesign, parameters)
    assert info.value.field == field


def test_every_registered_problem_declares_only_its_own_fields():
    import dataclasses

    for name, table in PARAMETER_UNITS.items():
        cls = REFERENCE_PROBLEMS[name][0]
        fields = {f.name for f in dataclasses.fields(cls) if f.init}
        assert set(table) <= fields, (name, set(table) - fields)


def test_a_document_with_units_builds_the_same_problem_as_si_numbers(tmp_path):
    data = yaml.safe_load(EXAMPLE.read_text())
    data.pop("pareto")
    si = dict(data, parameters={"hub_inertia": 0.4, "tip_mass": 0.2})
    units = dict(data, parameters={"hub_inertia": "0.4 kg*m**2", "tip_mass": "200 g"})
    built = []
    for i, doc in enumerate((si, units)):
        path = tmp_path / f"d{i}.yaml"
        path.write_text(yaml.safe_dump(doc, sort_keys=False))
        built.append(ConfiguredProblem.from_scenario(load_scenario(path)).reference)
    assert built[0] == built[1]


def test_a_wrong_dimension_in_a_document_is_refused_at_its_path(tmp_path):
    data = yaml.safe_load(EXAMPLE.read_text())
    data["parameters"]["hub_inertia"] = "0.4 kg"
    path = tmp_path / "d.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    assert [p.path for p in info.value.problems] == ["parameters.hub_inertia"]


def test_a_problem_without_a_unit_table_takes_its_fields_as_given():
    got = reference_parameters("unlisted", CantileverTube, {"length": 3.0})
    assert got == {"length": 3.0}
