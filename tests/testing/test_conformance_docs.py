"""docs/conformance.md: its example runs as printed and its pytest form marks the skipped checks
(the checks' teeth -- a plant or law broken in one way fails the check that says so -- are
tested in tests/testing/test_plant_checks.py and test_law_checks.py)."""

from __future__ import annotations

import numpy as np
import pytest

from conformance_example import DOC, documented_example, python_blocks
from flexsat.testing import (
    parametrize_with_checks,
)


def test_the_documented_example_runs(capsys):
    ns = documented_example()
    assert capsys.readouterr().out.strip() == "conforms"
    # the pytest form of the page: one parametrized test per check
    blocks = python_blocks()
    exec(compile(blocks[1], str(DOC), "exec"), ns)
    marks = ns["test_conformance"].pytestmark
    params = marks[0].args[1]
    assert [p.id for p in params][:2] == [
        "TorsionPendulum-channels_declared",
        "TorsionPendulum-shapes",
    ]
    assert len(params) == 8 + 6
    for p in params:
        if not p.marks:
            ns["test_conformance"](p.values[0])


@pytest.fixture
def example():
    return documented_example()


def test_parametrize_with_checks_marks_the_skipped(example):
    cls = example["TorsionPendulum"]

    class NoEnergy(cls):
        energy = example["Plant"].energy

    mark = parametrize_with_checks(plants=[NoEnergy()])
    (energy,) = [p for p in mark.args[1] if p.id.endswith("-energy")]
    assert energy.marks[0].name == "skip"


def test_a_per_entry_bound_names_the_entry_furthest_over_it():
    """assert_close with one bound per entry (the energy and power checks' error estimates):
    the message gives that entry's error and bound instead of failing to format an array."""
    from flexsat.testing.checks import assert_close

    assert_close("power", [1.0, 2.0], [1.05, 2.0], np.array([0.1, 0.0]), "within")
    with pytest.raises(AssertionError, match=r"^power: differs by 0\.05 > 0\.01 \(rate\)$"):
        assert_close("power", [1.0, 2.0], [1.05, 2.0], np.array([0.01, 0.1]), "rate")
