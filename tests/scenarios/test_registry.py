"""What a law or a plant implements to be built from a scenario section
(flexsat.scenarios.registry): the shape the registries accept, and the validation of its
section in the built-in laws' words."""

from __future__ import annotations

import pytest
from pydantic import BaseModel, ConfigDict, ValidationError

from flexsat.scenarios import quantity
from flexsat.scenarios.registry import component_rule, validate_section


class Gains(BaseModel):
    model_config = ConfigDict(extra="forbid")
    kp: quantity("N/m", positive=True)
    kd: quantity("N*s/m") = 0.0


class Law:
    Parameters = Gains

    @classmethod
    def from_scenario(cls, parameters, context):
        return None


def test_component_rule_names_what_is_missing():
    assert component_rule(Law) is None
    assert component_rule(Law, ("Parameters", "Target")) is None  # Target absent: none taken
    assert component_rule(object()).startswith("Parameters: a scenario component needs")
    assert component_rule(type("NoBuild", (), {"Parameters": Gains})).startswith("from_scenario")
    odd = type("OddTarget", (Law,), {"Target": dict})
    assert component_rule(odd, ("Parameters", "Target")).startswith("Target: ")


@pytest.mark.parametrize(
    "values, message",
    [
        ({"kp": 1, "ki": 2}, "ki: not a gain of law 'x' (its gains: kp, kd)"),
        ({"kd": 1}, "kp: required by law 'x'"),
        ([1, 2], "gains: a mapping of gains, got [1, 2]"),
    ],
)
def test_validate_section_words_its_refusals_like_the_built_ins(values, message):
    with pytest.raises(ValueError) as info:
        validate_section(Gains, values, "law 'x'", "gain", "gains")
    assert str(info.value) == message


def test_validate_section_converts_quantities_and_locates_bad_values():
    got = validate_section(Gains, {"kp": "2 N/mm"}, "law 'x'", "gain", "gains")
    assert got.kp == pytest.approx(2000.0, rel=1e-15) and got.kd == 0.0
    with pytest.raises(ValidationError) as info:
        validate_section(Gains, {"kp": "-1 N/m"}, "law 'x'", "gain", "gains")
    assert info.value.errors()[0]["loc"] == ("kp",)
