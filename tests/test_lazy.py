"""Lazy re-exports (flexsat.lazy): a package's names are imported from their modules on first
access, once; an unknown name is an AttributeError naming the package; ``dir()`` lists the
names before they are loaded. flexsat.scenarios and flexsat.report use them."""

from __future__ import annotations

import importlib
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

import flexsat

SRC = Path(flexsat.__file__).resolve().parents[1]


@pytest.fixture
def package(tmp_path, monkeypatch):
    """A throw-away package ``lazy_probe`` re-exporting ``VALUE`` from ``lazy_probe.heavy``,
    which counts how often it is executed in ``lazy_probe.LOADS``."""
    root = tmp_path / "lazy_probe"
    root.mkdir()
    (root / "__init__.py").write_text(
        textwrap.dedent("""
        from flexsat.lazy import lazy_exports

        LOADS = []
        __getattr__, __dir__ = lazy_exports(__name__, {"VALUE": "heavy"})
    """)
    )
    (root / "heavy.py").write_text(
        "import lazy_probe\nlazy_probe.LOADS.append(1)\nVALUE = object()\n"
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    yield importlib.import_module("lazy_probe")
    for name in ("lazy_probe", "lazy_probe.heavy"):
        sys.modules.pop(name, None)


def test_a_name_is_imported_on_first_access_only(package):
    assert "lazy_probe.heavy" not in sys.modules
    value = package.VALUE
    assert value is sys.modules["lazy_probe.heavy"].VALUE
    assert package.LOADS == [1]


def test_the_first_access_is_cached_in_the_package(package):
    value = package.VALUE
    assert vars(package)["VALUE"] is value  # later look-ups do not reach __getattr__
    del sys.modules["lazy_probe.heavy"]  # a second import would run heavy.py again
    assert package.VALUE is value
    assert package.LOADS == [1]


def test_an_unknown_name_is_an_attribute_error_naming_the_package(package):
    with pytest.raises(AttributeError, match=r"^module 'lazy_probe' has no attribute 'VALEU'$"):
        package.VALEU  # noqa: B018 -- the attribute access is the test
    assert not hasattr(package, "VALEU")
    assert "lazy_probe.heavy" not in sys.modules


def test_dir_lists_the_exports_before_they_are_loaded(package):
    names = dir(package)
    assert "VALUE" in names and "LOADS" in names
    assert names == sorted(names)
    assert "lazy_probe.heavy" not in sys.modules


@pytest.mark.parametrize("name", ["flexsat.scenarios", "flexsat.report"])
def test_every_export_of_the_flexsat_packages_is_defined_where_the_map_says(name):
    package = importlib.import_module(name)
    for export, module in package._EXPORTS.items():
        assert getattr(package, export) is getattr(
            importlib.import_module(f"{name}.{module}"), export
        ), export
    assert set(package.__all__) <= set(dir(package))


def test_importing_flexsat_scenarios_loads_only_what_is_used():
    """The package docstring's promise: load_scenario does not load the identification stack
    (measured by the modules loaded in a fresh interpreter)."""
    code = textwrap.dedent("""
        import sys
        import flexsat.scenarios as s
        before = {m for m in ("flexsat.scenarios.documents", "numpy") if m in sys.modules}
        s.load_scenario
        print(sorted(before), "flexsat.scenarios.documents" in sys.modules,
              "flexsat.scenarios.identification" in sys.modules)
    """)
    done = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        env={**os.environ, "PYTHONPATH": str(SRC)},
        timeout=120,
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["[]", "True", "False"]
