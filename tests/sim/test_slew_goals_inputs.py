"""SlewGoals refuses non-finite, non-positive, wrong-type and dimensioned numbers by name
(issue 21)."""

from __future__ import annotations

import math

import pytest

from flexsat.sim.slew_goals import SlewGoals
from flexsat.units import ureg


@pytest.mark.parametrize("field", ["angle_fraction", "deflection_ratio"])
@pytest.mark.parametrize("value", [math.nan, math.inf, 0.0, -1.0, "0.03", [0.03, 0.03]])
def test_a_goal_number_is_refused_by_name(field, value):
    with pytest.raises(ValueError, match=f"^{field}: "):
        SlewGoals(**{field: value})


@pytest.mark.parametrize("value", [math.nan, math.inf, 0.99, "1.25"])
def test_the_evaluation_time_is_refused_by_name(value):
    with pytest.raises(ValueError, match="^evaluation: "):
        SlewGoals(evaluation=value)


def test_a_quantity_is_refused_rather_than_stripped():
    with pytest.raises(ValueError, match="^angle_fraction: .*plain number"):
        SlewGoals(angle_fraction=0.03 * ureg.rad)
