import math

import pytest

from flexsat.units import UnitError, to_si


def test_published_imperial_units_convert_to_si():
    # 1 ozf = 0.278013851 N (avoirdupois ounce × standard gravity), 1 in = 0.0254 m exactly
    assert to_si("400 ozf*in", "N*m") == pytest.approx(400 * 0.278013851 * 0.0254, rel=1e-9)
    assert to_si("2128 ozf*in*s**2", "kg*m**2") == pytest.approx(15.02698, rel=1e-6)
    assert to_si("40 deg", "rad") == pytest.approx(math.radians(40), rel=1e-15)
    assert to_si(3.0, "N*m") == 3.0


def test_cyclic_and_angular_frequencies_carry_their_two_pi():
    """pint alone maps 1 Hz to 1 rad/s; flexsat applies the 2π (seed 001: ω_n = 0.06 Hz)."""
    assert to_si("0.06 Hz", "rad/s") == pytest.approx(2 * math.pi * 0.06, rel=1e-15)
    assert to_si("1 rad/s", "Hz") == pytest.approx(1 / (2 * math.pi), rel=1e-15)
    assert to_si("60 rpm", "rad/s") == pytest.approx(2 * math.pi, rel=1e-12)
    assert to_si("75 Hz", "Hz") == 75.0


def test_bad_quantities_name_the_field():
    with pytest.raises(UnitError, match=r"^angle: incompatible units"):
        to_si("40 kg", "rad", "angle")
    with pytest.raises(UnitError, match=r"^angle: cannot read"):
        to_si("forty deg", "rad", "angle")
    with pytest.raises(UnitError, match=r"^angle: must be a finite number"):
        to_si("nan deg", "rad", "angle")
