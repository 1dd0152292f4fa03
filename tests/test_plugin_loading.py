"""flexsat.plugins: a group is loaded once, every broken plug-in is recorded by name and never
raised, a built-in's name is refused naming both; and the scenario-component rules
(flexsat.scenarios.registry) that the law and plant registries apply."""

from __future__ import annotations

from importlib.metadata import EntryPoint

import pytest
from pydantic import BaseModel, ConfigDict

import flexsat.plugins as plugins
from flexsat.scenarios import quantity
from flexsat.scenarios.registry import component_rule, validate_section

POINTS = [
    EntryPoint("good", "math:sqrt", "flexsat.laws"),
    EntryPoint("missing_module", "flexsat_no_such_module:Law", "flexsat.laws"),
    EntryPoint("missing_attribute", "math:no_such_function", "flexsat.laws"),
    EntryPoint("refused", "math:pi", "flexsat.laws"),
    EntryPoint("lqr", "math:cos", "flexsat.laws"),
    EntryPoint("elsewhere", "math:tan", "flexsat.cases"),
]


@pytest.fixture
def fake_points(monkeypatch):
    """The entry points above in place of the installed ones, with a fresh cache."""
    loads = []

    def entry_points(group):
        loads.append(group)
        return [p for p in POINTS if p.group == group]

    monkeypatch.setattr(plugins, "entry_points", entry_points)
    monkeypatch.setattr(plugins, "_BROKEN", {})
    plugins._load_group.cache_clear()
    yield loads
    plugins._load_group.cache_clear()


def test_broken_plugins_are_recorded_by_name_and_never_raised(fake_points):
    import math

    def accept(name, obj):
        return None if callable(obj) else "not callable"

    objects = plugins.entry_point_objects(
        "flexsat.laws", accept, {"lqr": "the built-in law 'lqr' (somewhere:LQR)"}
    )
    assert objects == {"good": math.sqrt}
    broken = {b.name: b for b in plugins.broken_plugins()}
    assert set(broken) == {"missing_module", "missing_attribute", "refused", "lqr"}
    assert broken["missing_module"].reason.startswith("ModuleNotFoundError: ")
    assert broken["missing_attribute"].reason.startswith("AttributeError: ")
    assert broken["refused"].reason == "not callable"
    assert str(broken["lqr"]) == (
        "plug-in 'lqr' (flexsat.laws = 'math:cos') was not loaded: its name is taken by the "
        "built-in law 'lqr' (somewhere:LQR); rename the entry point"
    )
    # only the group asked for is read, and only once
    plugins.entry_point_objects("flexsat.laws", accept)
    assert "flexsat.cases" not in fake_points
    assert plugins._load_group.cache_info().misses == 1


def test_an_unknown_group_is_refused(fake_points):
    with pytest.raises(ValueError, match=r"^group: must be one of flexsat.kinds, "):
        plugins.entry_point_objects("flexsat.lawz")


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
    from pydantic import ValidationError

    got = validate_section(Gains, {"kp": "2 N/mm"}, "law 'x'", "gain", "gains")
    assert got.kp == pytest.approx(2000.0, rel=1e-15) and got.kd == 0.0
    with pytest.raises(ValidationError) as info:
        validate_section(Gains, {"kp": "-1 N/m"}, "law 'x'", "gain", "gains")
    assert info.value.errors()[0]["loc"] == ("kp",)
