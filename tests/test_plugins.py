"""flexsat.plugins: entry-point groups are loaded once, and a plug-in that cannot be loaded is
reported by name instead of raised (a broken plug-in must not break the others or the CLI)."""

from __future__ import annotations

import sys
import types
from importlib.metadata import EntryPoint

import pytest

from flexsat import plugins


@pytest.fixture
def fake_points(monkeypatch):
    """Entry points of ``flexsat.laws`` pointing at a module made here, plus broken ones."""
    module = types.ModuleType("fake_plugin_module")

    class Good:
        pass

    module.Good = Good
    module.not_a_class = 3
    monkeypatch.setitem(sys.modules, "fake_plugin_module", module)
    points = [
        EntryPoint("good", "fake_plugin_module:Good", "flexsat.laws"),
        EntryPoint("missing_module", "no_such_module_here:Law", "flexsat.laws"),
        EntryPoint("missing_attribute", "fake_plugin_module:Absent", "flexsat.laws"),
        EntryPoint("refused", "fake_plugin_module:not_a_class", "flexsat.laws"),
    ]

    def entry_points(group):
        return [p for p in points if p.group == group]

    monkeypatch.setattr(plugins, "entry_points", entry_points)
    monkeypatch.setattr(plugins, "_BROKEN", {})
    plugins._load_group.cache_clear()
    yield module
    plugins._load_group.cache_clear()


def test_good_plugins_load_and_broken_ones_are_reported_by_name(fake_points):
    def accept(name, obj):
        return None if isinstance(obj, type) else "not a class"

    loaded = plugins.entry_point_objects("flexsat.laws", accept=accept)
    assert loaded == {"good": fake_points.Good}
    broken = {b.name: b for b in plugins.broken_plugins()}
    assert set(broken) == {"missing_module", "missing_attribute", "refused"}
    assert broken["missing_module"].reason.startswith("ModuleNotFoundError")
    assert broken["missing_attribute"].reason.startswith("AttributeError")
    assert broken["refused"].reason == "not a class"
    text = str(broken["missing_module"])
    assert "'missing_module'" in text and "flexsat.laws" in text and "no_such_module_here" in text


def test_a_builtin_name_is_refused_naming_both(fake_points):
    """A plug-in never replaces a built-in silently: its entry point is reported, naming the
    built-in it would have shadowed."""
    reserved = {"good": "the built-in law 'good' (flexsat.somewhere:Good)"}
    assert "good" not in plugins.entry_point_objects("flexsat.laws", reserved=reserved)
    broken = {b.name: b for b in plugins.broken_plugins()}
    assert str(broken["good"]) == (
        "plug-in 'good' (flexsat.laws = 'fake_plugin_module:Good') was not loaded: its name is "
        "taken by the built-in law 'good' (flexsat.somewhere:Good); rename the entry point"
    )


def test_a_group_is_loaded_once_per_process(fake_points, monkeypatch):
    first = plugins.entry_point_objects("flexsat.laws")
    monkeypatch.setattr(plugins, "entry_points", lambda group: [])
    assert plugins.entry_point_objects("flexsat.laws") == first


def test_an_unknown_group_is_refused_by_name():
    with pytest.raises(
        ValueError, match=r"^group: must be one of flexsat\.kinds, .*'flexsat\.lawz'"
    ):
        plugins.entry_point_objects("flexsat.lawz")
