"""The conformance checks of a control law (:mod:`flexsat.testing.law_checks`) have teeth:
the documented RateDamper (docs/conformance.md) passes every one on its pendulum, and a copy
broken in one way fails the check that says so -- a linear form that disagrees, hidden state,
a missing channel, a command that drops the case axis, a refusal that does not name the
channel; the skips follow the law's declarations."""

from __future__ import annotations

import numpy as np
import pytest

from conformance_example import assert_fails, documented_example, one_check
from flexsat.testing import check_controller, controller_checks


@pytest.fixture
def example():
    return documented_example()


def test_a_linear_form_that_disagreesassert_fails(example):
    cls = example["RateDamper"]

    class Off(cls):
        def linear_form(self, dt, times, n_cases):
            form = super().linear_form(dt, times, n_cases)
            return type(form)(**{**form.__dict__, "Dk": 1.001 * form.Dk})

    assert_fails("linear_form", check_controller, Off(0.5), example["TorsionPendulum"]())


def test_a_law_with_hidden_state_fails_determinism(example):
    cls = example["RateDamper"]

    class Drifting(cls):
        calls = 0

        def __call__(self, t, y, state):
            type(self).calls += 1
            return -(self.gain + 1e-3 * self.calls) * y["rate"], state

        linear_form = example["Controller"].linear_form

    checks = controller_checks(Drifting(0.5), example["TorsionPendulum"]())
    assert_fails(
        "batch_equals_singles", check_controller, Drifting(0.5), example["TorsionPendulum"]()
    )
    (determinism,) = [c for c in checks if c.name == "determinism"]
    assert_fails("determinism", determinism)


def test_a_law_reading_a_missing_channel_fails_channels_declared(example):
    cls = example["RateDamper"]

    class Misnamed(cls):
        reads = ("omega",)

    checks = controller_checks(Misnamed(0.5), example["TorsionPendulum"]())
    assert [c.skip is None for c in checks] == [True] + [False] * 5
    assert_fails("channels_declared", checks[0])


def test_the_documented_law_passes_every_check(example):
    checks = controller_checks(example["RateDamper"](0.5), example["TorsionPendulum"]())
    assert [c.name for c in checks] == [
        "channels_declared",
        "shapes",
        "batch_equals_singles",
        "linear_form",
        "determinism",
        "bad_input",
    ]
    for check in checks:
        assert check.skip is None, check
        check()


def test_a_command_without_its_case_axis_fails_shapes(example):
    cls = example["RateDamper"]

    class FirstCaseOnly(cls):
        def __call__(self, t, y, state):
            return -self.gain * np.asarray(y["rate"])[:1], state

    plant = example["TorsionPendulum"]()
    assert_fails("shapes", one_check(controller_checks(FirstCaseOnly(0.5), plant), "shapes"))


def test_a_refusal_that_does_not_name_the_channel_fails_bad_input(example, monkeypatch):
    import flexsat.testing.law_checks as law_checks

    def vague(plant, law):
        if "rate" not in {c.name for c in plant.outputs}:
            raise ValueError("the plant does not fit the law")

    monkeypatch.setattr(law_checks, "check_law", vague)
    checks = controller_checks(example["RateDamper"](0.5), example["TorsionPendulum"]())
    assert_fails("bad_input", one_check(checks, "bad_input"))


def test_skips_follow_the_declarations(example):
    law_skips = {
        c.name
        for c in controller_checks(
            example["RateDamper"]([0.4, 0.5, 0.6]), example["TorsionPendulum"]()
        )
        if c.skip
    }
    assert law_skips == {"batch_equals_singles"}
