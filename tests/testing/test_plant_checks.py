"""The conformance checks of a plant (:mod:`flexsat.testing.plant_checks`) have teeth: the
documented TorsionPendulum (docs/conformance.md) passes every one, and a copy broken in one way
fails the check that says so -- a non-SI unit, a wrong power, a growing energy, a dropped case
axis, an unknown name as a KeyError, cases coupled in a batch, an ``rhs`` that is not the split
form; the skips follow the plant's declarations."""

from __future__ import annotations

import numpy as np
import pytest

from conformance_example import assert_fails, documented_example, one_check
from flexsat.testing import check_plant, plant_checks


@pytest.fixture
def example():
    return documented_example()


def test_a_non_si_unit_fails_channels_declared(example):
    plant = example["TorsionPendulum"]()
    Channel = type(plant.outputs[0])
    plant.outputs = (Channel("angle", "deg"), Channel("rate", "rad/s"))
    assert_fails("channels_declared", check_plant, plant)


def test_a_wrong_power_fails_energy(example):
    """Power without the dissipation: dE/dt differs by c θ'² (the difference quotient of the
    quadratic energy is exact to round-off)."""
    cls = example["TorsionPendulum"]

    class Undamped(cls):
        def power(self, x, u):
            return x[..., 1] * u[..., 0]

    assert_fails("energy", check_plant, Undamped())


def test_an_energy_that_grows_fails_without_a_declared_power(example):
    cls = example["TorsionPendulum"]

    class Active(cls):
        power = example["Plant"].power  # not declared: the passivity check applies

        def __init__(self):
            super().__init__(damping=-0.5)

    assert_fails("energy", check_plant, Active())


def test_a_case_axis_dropped_fails_shapes(example):
    cls = example["TorsionPendulum"]

    class Scalar(cls):
        def output(self, name, x, u, f_in=None):
            return np.asarray(super().output(name, x, u, f_in))[..., :1]

    assert_fails("shapes", check_plant, Scalar())


def test_an_unknown_name_as_a_key_error_fails_bad_input(example):
    cls = example["TorsionPendulum"]

    class Careless(cls):  # its own output(): Plant.output's check of the name is bypassed
        def output(self, name, x, u, f_in=None):
            return x[..., {"angle": 0, "rate": 1}[name]]

    assert_fails("bad_input", check_plant, Careless())


def test_the_documented_plant_passes_every_check(example):
    checks = plant_checks(example["TorsionPendulum"]())
    assert [c.name for c in checks] == [
        "channels_declared",
        "shapes",
        "batch_equals_singles",
        "dispersion",
        "linear_form",
        "energy",
        "determinism",
        "bad_input",
    ]
    for check in checks:
        assert check.skip is None, check
        check()


def test_cases_coupled_in_a_batch_fail_batch_equals_singles(example):
    cls = example["TorsionPendulum"]

    class Coupled(cls):  # each case's angle less the batch mean: zero alone, not in a batch
        def output(self, name, x, u, f_in=None):
            y = np.asarray(super().output(name, x, u, f_in), float)
            return y - y.mean(axis=-1, keepdims=True) if name == "angle" else y

    assert_fails("batch_equals_singles", one_check(plant_checks(Coupled()), "batch_equals_singles"))


def test_an_rhs_that_is_not_the_split_form_fails_linear_form(example):
    cls = example["TorsionPendulum"]

    class Stiffer(cls):  # its rhs has 1 % more stiffness than its linear part
        def rhs(self, x, u):
            A, B = self.linear_part()
            A = A.copy()
            A[1, 0] *= 1.01
            return x @ A.T + u @ B.T

    assert_fails("linear_form", one_check(plant_checks(Stiffer()), "linear_form"))


def test_skips_follow_the_declarations(example):
    cls = example["TorsionPendulum"]

    class NoEnergy(cls):
        energy = example["Plant"].energy

    skipped = {c.name: c.skip for c in plant_checks(NoEnergy()) if c.skip}
    assert skipped == {"energy": "the plant declares no energy (energy() is None)"}
