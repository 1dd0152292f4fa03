"""docs/conformance.md: its example runs as printed, and its checks have teeth (a plant or law
broken in one way fails the check that says so)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from flexsat.testing import (
    check_controller,
    check_plant,
    controller_checks,
    parametrize_with_checks,
    plant_checks,
)

DOC = Path(__file__).parents[2] / "docs" / "conformance.md"


def _example() -> dict:
    blocks = re.findall(r"```python\n(.*?)```", DOC.read_text(), re.S)
    namespace: dict = {}
    exec(compile(blocks[0], str(DOC), "exec"), namespace)
    return namespace


def test_the_documented_example_runs(capsys):
    ns = _example()
    assert capsys.readouterr().out.strip() == "conforms"
    # the pytest form of the page: one parametrized test per check
    blocks = re.findall(r"```python\n(.*?)```", DOC.read_text(), re.S)
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
    return _example()


def _fails(check_name: str, run, *args):
    with pytest.raises(AssertionError, match=rf"fails {check_name}: "):
        run(*args)


def test_a_non_si_unit_fails_channels_declared(example):
    plant = example["TorsionPendulum"]()
    Channel = type(plant.outputs[0])
    plant.outputs = (Channel("angle", "deg"), Channel("rate", "rad/s"))
    _fails("channels_declared", check_plant, plant)


def test_a_wrong_power_fails_energy(example):
    """Power without the dissipation: dE/dt differs by c θ'² (the difference quotient of the
    quadratic energy is exact to round-off)."""
    cls = example["TorsionPendulum"]

    class Undamped(cls):
        def power(self, x, u):
            return x[..., 1] * u[..., 0]

    _fails("energy", check_plant, Undamped())


def test_an_energy_that_grows_fails_without_a_declared_power(example):
    cls = example["TorsionPendulum"]

    class Active(cls):
        power = example["Plant"].power  # not declared: the passivity check applies

        def __init__(self):
            super().__init__(damping=-0.5)

    _fails("energy", check_plant, Active())


def test_a_case_axis_dropped_fails_shapes(example):
    cls = example["TorsionPendulum"]

    class Scalar(cls):
        def output(self, name, x, u, f_in=None):
            return np.asarray(super().output(name, x, u, f_in))[..., :1]

    _fails("shapes", check_plant, Scalar())


def test_an_unknown_name_as_a_key_error_fails_bad_input(example):
    cls = example["TorsionPendulum"]

    class Careless(cls):  # its own output(): Plant.output's check of the name is bypassed
        def output(self, name, x, u, f_in=None):
            return x[..., {"angle": 0, "rate": 1}[name]]

    _fails("bad_input", check_plant, Careless())


def test_a_linear_form_that_disagrees_fails(example):
    cls = example["RateDamper"]

    class Off(cls):
        def linear_form(self, dt, times, n_cases):
            form = super().linear_form(dt, times, n_cases)
            return type(form)(**{**form.__dict__, "Dk": 1.001 * form.Dk})

    _fails("linear_form", check_controller, Off(0.5), example["TorsionPendulum"]())


def test_a_law_with_hidden_state_fails_determinism(example):
    cls = example["RateDamper"]

    class Drifting(cls):
        calls = 0

        def __call__(self, t, y, state):
            type(self).calls += 1
            return -(self.gain + 1e-3 * self.calls) * y["rate"], state

        linear_form = example["Controller"].linear_form

    checks = controller_checks(Drifting(0.5), example["TorsionPendulum"]())
    _fails("batch_equals_singles", check_controller, Drifting(0.5), example["TorsionPendulum"]())
    (determinism,) = [c for c in checks if c.name == "determinism"]
    _fails("determinism", determinism)


def test_a_law_reading_a_missing_channel_fails_channels_declared(example):
    cls = example["RateDamper"]

    class Misnamed(cls):
        reads = ("omega",)

    checks = controller_checks(Misnamed(0.5), example["TorsionPendulum"]())
    assert [c.skip is None for c in checks] == [True] + [False] * 5
    _fails("channels_declared", checks[0])


def test_skips_follow_the_declarations(example):
    cls = example["TorsionPendulum"]

    class NoEnergy(cls):
        energy = example["Plant"].energy

    skipped = {c.name: c.skip for c in plant_checks(NoEnergy()) if c.skip}
    assert skipped == {"energy": "the plant declares no energy (energy() is None)"}
    law_skips = {
        c.name for c in controller_checks(example["RateDamper"]([0.4, 0.5, 0.6]), cls()) if c.skip
    }
    assert law_skips == {"batch_equals_singles"}


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
