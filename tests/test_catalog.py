"""The case catalogue (flexsat.catalog): every entry names the builder flexsat.cases exports,
importing it only on use; an unknown name is a ``case:`` error listing the known ones."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

import flexsat
from flexsat.catalog import CASES, all_cases, get_case

SRC = Path(flexsat.__file__).resolve().parents[1]


@pytest.mark.parametrize("name", sorted(CASES))
def test_every_entry_resolves_to_the_exported_builder(name):
    import flexsat.cases

    info = get_case(name)
    assert info is CASES[name] and info.name == name
    builder = info.builder
    assert builder.__module__ == info.module
    assert builder.__name__ == info.function
    assert builder is getattr(flexsat.cases, info.function)
    assert info.function in flexsat.cases.__all__
    assert info.source.strip() and info.description.strip()
    assert "\n" not in info.description  # one line of `flexsat cases`


def test_flexsat_cases_re_exports_the_same_catalogue():
    import flexsat.cases

    assert flexsat.cases.CASES is CASES and flexsat.cases.get_case is get_case


@pytest.mark.parametrize("name", ["hst", "TAMU", "tamu ", ""])
def test_an_unknown_case_is_refused_listing_the_known_ones(name):
    with pytest.raises(ValueError) as info:
        get_case(name)
    assert str(info.value) == f"case: unknown case {name!r}; known: {sorted(all_cases())}"


def test_looking_a_case_up_loads_no_numerical_code():
    """``flexsat cases`` and the first checks of ``flexsat run`` read the catalogue: only the
    builder property imports the case (measured by the modules loaded in a fresh interpreter)."""
    code = textwrap.dedent("""
        import sys
        from flexsat.catalog import get_case
        info = get_case("tamu")
        print(sorted(m for m in ("numpy", "flexsat.cases", "flexsat.cases.tamu")
                     if m in sys.modules))
        info.builder
        print("flexsat.cases.tamu" in sys.modules)
    """)
    done = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        env={**os.environ, "PYTHONPATH": str(SRC)},
        timeout=120,
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.split("\n")[:2] == ["[]", "True"]
