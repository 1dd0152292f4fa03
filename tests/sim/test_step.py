"""The step's formulas (flexsat.sim.step) are the same functions in the Python loop and, compiled
by numba, in the kernels: each against its definition, and compiled against plain numpy bit
for bit (the compiled loop must not drift from the Python one)."""

from __future__ import annotations

import numpy as np
import pytest
from numba import njit

from flexsat.sim.step import actuated, friction_torque, quantised, rate_limited, saturated

V = np.array([-2.5, -0.375, -0.125, 0.0, 0.124, 0.125, 0.376, 3.0, np.inf, -np.inf])


def test_the_quantiser_rounds_to_the_nearest_multiple_half_to_even():
    got = quantised(V[:8], 0.25)
    assert np.array_equal(got, [-2.5, -0.5, -0.0, 0.0, 0.0, 0.0, 0.5, 3.0])
    assert np.all(np.abs(got - V[:8]) <= 0.125)  # within half a quantum


def test_saturation_clips_to_the_bound_and_keeps_nan():
    assert np.array_equal(saturated(V, 0.25), np.clip(V, -0.25, 0.25))
    assert np.array_equal(saturated(V, np.inf), V)
    assert np.isnan(saturated(np.nan, 1.0))  # a diverging case stays visible


def test_the_rate_limit_moves_at_most_one_step_from_the_previous_command():
    previous = np.zeros_like(V)
    got = rate_limited(V, previous, 0.2)
    assert np.all(np.abs(got - previous) <= 0.2)
    inside = np.abs(V) <= 0.2
    assert np.array_equal(got[inside], V[inside])


def test_an_actuator_scales_the_saturated_command():
    assert np.array_equal(actuated(V, 1.0, 0.5), 0.5 * np.clip(V, -1.0, 1.0))


def test_friction_opposes_the_rate_and_tends_to_coulomb_plus_viscous():
    rate = np.array([-1.0, -1e-6, 0.0, 1e-6, 1.0])
    tau = friction_torque(rate, 0.02, 0.003, 1e-4)
    assert np.all(np.sign(tau) == -np.sign(rate))
    # far beyond the smoothing rate tanh -> 1: c1 + c2 |rate| (Att. 3 Eq. 23)
    assert tau[-1] == pytest.approx(-(0.02 + 0.003), rel=1e-15)
    # well inside it the law is linear: −(c1/ε + c2) rate to O((rate/ε)³)
    assert tau[3] == pytest.approx(-(0.02 / 1e-4 + 0.003) * 1e-6, rel=1e-3)


@pytest.mark.parametrize(
    "formula, args",
    [
        (quantised, (0.3, 0.25)),
        (saturated, (3.0, 0.5)),
        (rate_limited, (1.0, 0.2, 0.05)),
        (actuated, (-4.0, 1.5, 0.8)),
        (friction_torque, (0.01, 0.02, 0.003, 1e-3)),
    ],
)
def test_compiled_and_python_give_the_same_bits(formula, args):
    compiled = njit(lambda *a: formula(*a))
    assert compiled(*args) == formula(*args)
