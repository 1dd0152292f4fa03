"""Scenario kinds from other packages (entry-point group ``flexsat.kinds``): the example of
docs/kinds.md runs through ``flexsat run`` like a built-in kind; a broken plug-in is named on
stderr and the command line works on."""

from __future__ import annotations

import re
import sys
import types
from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

import flexsat.plugins as plugins
from flexsat.cli import app
from flexsat.scenarios import ScenarioError, ScenarioKind, load_scenario, run_scenario
from flexsat.scenarios.kind import built_in_kinds, scenario_kinds

DOC = Path(__file__).resolve().parents[2] / "docs" / "kinds.md"


def _blocks(language: str) -> list[str]:
    return re.findall(rf"```{language}\n(.*?)```", DOC.read_text(), flags=re.S)


@pytest.fixture(scope="module")
def example_module():
    """The docs' example kind, as the module ``pole_slew_plugin`` of an outside package."""
    module = types.ModuleType("pole_slew_plugin")
    sys.modules[module.__name__] = module
    exec(compile(_blocks("python")[0], str(DOC), "exec"), module.__dict__)
    yield module
    del sys.modules[module.__name__]


class _EntryPoint:
    """What importlib.metadata lists for an installed plug-in: a name and what it points at."""

    def __init__(self, name: str, value: str, load):
        self.name, self.value, self.group, self._load = name, value, "flexsat.kinds", load

    def load(self):
        return self._load()


def _broken_import():
    raise ImportError("No module named 'missing_package'")


@pytest.fixture
def installed(monkeypatch, example_module):
    """The installed plug-ins: the docs' kind, one that fails to import, one that is not a
    kind, one that takes a built-in name; the loader's caches are reset around the test."""
    points = [
        _EntryPoint(
            "pole_slew", "pole_slew_plugin:PoleSlewKind", lambda: example_module.PoleSlewKind
        ),
        _EntryPoint("broken", "missing_package:Kind", _broken_import),
        _EntryPoint("not_a_kind", "pole_slew_plugin:PoleSlew", lambda: example_module.PoleSlew),
        _EntryPoint(
            "maneuver",
            "pole_slew_plugin:Impostor",
            lambda: type(
                "Impostor",
                (ScenarioKind,),
                {"kind": "maneuver", "document": example_module.PoleSlew},
            ),
        ),
    ]

    def entry_points(group=None):
        return [p for p in points if p.group == group]

    def reset():
        plugins._load_group.cache_clear()
        plugins._BROKEN.clear()

    reset()
    monkeypatch.setattr(plugins, "entry_points", entry_points)
    yield example_module
    reset()


def _example_file(tmp_path: Path) -> Path:
    path = tmp_path / "pole_slew.yaml"
    path.write_text(_blocks("yaml")[0])
    return path


def test_the_registry_holds_the_plugin_and_names_the_broken_ones(installed):
    kinds = scenario_kinds()
    assert kinds["pole_slew"] is installed.PoleSlewKind
    assert kinds["maneuver"] is built_in_kinds()["maneuver"]  # a plug-in cannot replace one
    broken = {b.name: b.reason for b in plugins.broken_plugins() if b.group == "flexsat.kinds"}
    assert broken.keys() == {"broken", "not_a_kind", "maneuver"}
    assert "ImportError: No module named 'missing_package'" in broken["broken"]
    assert "not a subclass" in broken["not_a_kind"]
    assert broken["maneuver"].startswith("its name is taken by the built-in kind 'maneuver'")


def test_an_unknown_kind_lists_the_plugins_too(installed, tmp_path):
    with pytest.raises(ScenarioError, match=r"kind: must be 'maneuver', .*'pole_slew'"):
        load_scenario("kind: survey\nname: x\n")


def test_a_plugin_document_reports_problems_by_field_path(installed):
    data = yaml.safe_load(_blocks("yaml")[0])
    data["runs"][1]["damping_ratio"] = -1
    data["runs"][0]["colour"] = "red"
    with pytest.raises(ScenarioError) as info:
        load_scenario(yaml.safe_dump(data))
    paths = sorted(p.path for p in info.value.problems)
    assert paths == ["runs['fast'].damping_ratio", "runs['slow'].colour"]


def test_the_plugin_kind_runs_and_places_faster_poles_first(installed, tmp_path):
    """The runner simulates each run; faster rigid poles (same ζ) settle sooner, by about the
    ratio of the natural frequencies for the rigid mode (t_s ∝ 1/(ζ ω_n))."""
    result = run_scenario(load_scenario(_example_file(tmp_path)))
    slow, fast = (r["settling_time_s"] for r in result.metrics_records())
    assert fast < slow
    assert 1.2 < slow / fast < 3.0


def test_flexsat_run_writes_the_plugin_report_and_warns_of_the_broken(installed, tmp_path):
    out = tmp_path / "report"
    done = CliRunner().invoke(app, ["run", str(_example_file(tmp_path)), "--out", str(out)])
    assert done.exit_code == 0, done.output
    assert "warning: plug-in 'broken' (flexsat.kinds = 'missing_package:Kind')" in done.stderr
    assert "settling_time_s" in done.stdout
    assert {"metrics.json", "results.nc", "index.html"} <= {p.name for p in out.iterdir()}
    assert "<h2>Settling</h2>" in (out / "index.html").read_text()


def test_workers_are_refused_by_a_kind_that_runs_no_batch(installed, tmp_path):
    done = CliRunner().invoke(
        app, ["run", str(_example_file(tmp_path)), "--workers", "2", "--out", str(tmp_path / "o")]
    )
    assert done.exit_code == 2
    assert "--workers/--scheduler: a pole_slew scenario runs in this process" in done.stderr
