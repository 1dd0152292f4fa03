"""The slew design's public constructors and solvers refuse bad input by name (issue 21):
SlewWeights, frequency_shaped_slew, three_axis_slew, shaping_weights, before anything is
allocated."""

from __future__ import annotations

import math

import numpy as np
import pytest

from flexsat.control.frequency_shaped import shaping_weights
from flexsat.design.slew_weights import SlewWeights
from flexsat.input_checks import FieldError
from flexsat.limits import MAX_WEIGHT_RANGE
from flexsat.maneuvers import three_axis_slew
from flexsat.maneuvers.frequency_shaped_slew import frequency_shaped_slew
from flexsat.units import ureg

BASE = {"attitude": 1000.0, "rate": 1000.0, "modes": 1.0, "torque": 50.0}
#: the EPS's inertia, roughly (kg m²), with a product of inertia
INERTIA = np.array([[1.0e5, 1.0e3, 0.0], [1.0e3, 2.0e5, 0.0], [0.0, 0.0, 2.1e5]])


@pytest.mark.parametrize(
    "block, value",
    [
        ("attitude", math.nan),
        ("rate", math.inf),
        ("modes", -1.0),
        ("torque", 0.0),
        ("torque", []),
        ("modes", [[1.0, 2.0]]),
        ("rate", "1000"),
    ],
)
def test_slew_weights_refuse_a_bad_block_by_name(block, value):
    with pytest.raises(FieldError, match=f"^{block}: "):
        SlewWeights(**{**BASE, block: value})


def test_slew_weights_refuse_a_quantity_rather_than_drop_its_unit():
    with pytest.raises(ValueError, match="^attitude: .*plain number"):
        SlewWeights(**{**BASE, "attitude": 1000.0 * ureg("1/rad**2")})


def test_slew_weights_refuse_a_span_beyond_the_rounding_naming_the_outlying_block():
    weights = SlewWeights(**{**BASE, "attitude": 1e300})
    with pytest.raises(FieldError, match="^attitude: the weights span 1e\\+300"):
        weights.diagonals(10)
    # the examples' widest span (1000 beside a force weight of 1e-7) is accepted
    q, d = SlewWeights(**{**BASE, "force": 1e-7}).diagonals(10, 7)
    assert d.max() / d.min() == pytest.approx(5e8) and MAX_WEIGHT_RANGE > 1e10


@pytest.mark.parametrize(
    "options, field",
    [
        ({"omega_b": 1e12}, "omega_b"),
        ({"omega_b": 5.0, "zeta_b": 1e300}, "zeta_b"),
        ({"omega_b": 5.0, "zeta_b": 1e5}, "zeta_b"),
        ({"omega_b": 5.0, "q": 1e300}, "q"),
    ],
)
def test_a_single_axis_slew_needing_too_many_segments_is_refused_before_allocating(options, field):
    # 1e12 rad/s over 3 s would need 1e11 shooting segments (terabytes): refused by count
    with pytest.raises(FieldError, match=f"^{field}: .*shooting segments, above the limit"):
        frequency_shaped_slew(1.0, 1e5, 3.0, **options)


@pytest.mark.parametrize(
    "options, field",
    [
        ({"omega_b": 1e12}, "omega_b"),
        ({"omega_b": 1e6}, "omega_b"),  # few segments, but 3e7 RK4 steps per sweep
        ({"omega_b": 5.0, "zeta_b": 1e300}, "zeta_b"),
        # the start fits, but the continuation's Jacobian would need ~1.5 TB: the damping's
        ({"omega_b": 5.0, "zeta_b": 1e3}, "zeta_b"),
        ({"omega_b": 5.0, "Q": 1e300 * np.eye(3)}, "Q"),
        ({"omega_b": math.nan}, "omega_b"),
        ({"omega_b": "5 Hz*m"}, "omega_b"),
    ],
)
def test_a_three_axis_slew_beyond_the_limits_is_refused_by_name(options, field):
    with pytest.raises(ValueError, match=f"^{field}: "):
        three_axis_slew(INERTIA, [1.0, 1.0, 1.0], 3.0, **options)


@pytest.mark.parametrize(
    "options, field",
    [
        ({"break_frequency": 1e300}, "break_frequency"),
        ({"break_frequency": 5.0, "damping": 1e300}, "damping"),
        ({"break_frequency": math.inf}, "break_frequency"),
    ],
)
def test_shaping_weights_refuse_unrepresentable_weights_by_name(options, field):
    with pytest.raises(FieldError, match=f"^{field}: "):
        shaping_weights(np.eye(2), np.eye(1), **options)
