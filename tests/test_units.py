import math
import time

import numpy as np
import pytest

from flexsat.input_checks import require_finite, require_nonneg, require_numeric, require_positive
from flexsat.units import Q_, UnitError, to_si, to_si_array


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
    # any angular rate asked for in cycles per second: one revolution per second is 1 Hz
    # (pint alone gives 2π Hz for 60 rpm and 0.0175 Hz for 1 deg/s)
    assert to_si("60 rpm", "Hz") == pytest.approx(1.0, rel=1e-15)
    assert to_si("360 deg/s", "Hz") == pytest.approx(1.0, rel=1e-15)
    assert to_si("60 rpm", "kHz") == pytest.approx(1.0, rel=1e-15)  # SI: the result is in Hz
    assert to_si("75 Hz", "Hz") == 75.0


def test_bad_quantities_name_the_field():
    with pytest.raises(UnitError, match=r"^angle: incompatible units"):
        to_si("40 kg", "rad", "angle")
    with pytest.raises(UnitError, match=r"^angle: cannot read"):
        to_si("forty deg", "rad", "angle")
    with pytest.raises(UnitError, match=r"^angle: must be a finite number"):
        to_si("nan deg", "rad", "angle")


def test_a_dimensionless_unit_is_not_relabelled_with_the_expected_one():
    """pint calls deg and percent dimensionless; they are refused where a dimension is due
    (before, "15 deg" read as 15 s), but an angle in degrees still reads where rad is due."""
    with pytest.raises(
        UnitError,
        match=r"^duration: incompatible units \(degree given, s "
        r"expected\)$",
    ):
        to_si("15 deg", "s", "duration")
    with pytest.raises(
        UnitError,
        match=r"^natural_frequency: incompatible units \(percent "
        r"given, rad/s expected\)$",
    ):
        to_si("100 percent", "rad/s", "natural_frequency")
    assert to_si("2 deg/s", "rad/s") == pytest.approx(math.radians(2), rel=1e-15)
    assert to_si("100 percent", "") == 1.0
    assert to_si("3", "s") == 3.0  # a bare number in a string is in the field's unit
    assert to_si(" 2.5e-3 ", "kg*m**2") == 2.5e-3


@pytest.mark.parametrize(
    "text, reason",
    [
        ("1/0", "ZeroDivisionError"),
        ("(1", "TokenError"),
        ("10.0**400", "OverflowError"),
        ("10**10**10 s", "OverflowError"),  # pint alone computes 10**(10**10) with Python ints
        ("10⁹⁹⁹⁹⁹⁹⁹⁹⁹ s", "OverflowError"),  # the same through pint's superscript preprocessor
        ("((m**10)**10)**10", "a unit raised to the power 1000"),
        ("(-8)**0.5 s", "real number"),
        ("1 m + 1 s", "DimensionalityError"),
        ("x" * 1_000_000, "at most 200 characters, got 1000000"),
        ("x" * 201, "at most 200 characters"),
        ("   ", "empty string"),
    ],
)
def test_unreadable_expressions_fail_fast_naming_the_field(text, reason):
    """Every malformed or unbounded expression is a UnitError within milliseconds (measured
    about 0.1 ms each; the bound is generous for a loaded machine, where an unbounded power
    would run for hours; the unit registry is loaded before the clock starts)."""
    to_si("1 s", "s")
    start = time.perf_counter()
    with pytest.raises(UnitError, match=r"^duration: ") as info:
        to_si(text, "s", "duration")
    assert time.perf_counter() - start < 0.5
    assert reason in str(info.value)
    assert len(str(info.value)) < 400  # a megabyte of input is not echoed back


def test_arrays_and_lists_convert_element_by_element():
    assert np.array_equal(to_si_array(Q_([1, 2], "ms"), "s"), [1e-3, 2e-3])
    assert np.array_equal(to_si_array([Q_(1, "ms"), "2 s", 3], "s"), [1e-3, 2.0, 3.0])
    assert np.array_equal(to_si_array(np.array([1.0, 2.0]), "N*m"), [1.0, 2.0])
    assert to_si_array("1 Hz", "rad/s") == pytest.approx(2 * math.pi, rel=1e-15)
    with pytest.raises(UnitError, match=r"^t: incompatible units"):
        to_si_array([1.0, "2 m"], "s", "t")
    with pytest.raises(UnitError, match=r"^t: the items of .* differ in shape"):
        to_si_array([Q_([1, 2], "s"), "3 s"], "s", "t")
    with pytest.raises(UnitError, match=r"^x: must be a single number"):
        to_si([1.0, 2.0], "s", "x")
    for bad in (None, 1 + 2j, np.array([1 + 1j]), object()):
        with pytest.raises(UnitError, match=r"^x: cannot read .* as a real number"):
            to_si_array(bad, "s", "x")


def test_checks_convert_with_a_unit_and_refuse_a_quantity_without_one():
    assert require_positive("2 min", "duration", "s") == 120.0
    assert np.array_equal(require_nonneg(Q_([0, 5], "mm"), "gap", "m"), [0.0, 0.005])
    with pytest.raises(ValueError, match=r"^duration: must be > 0, got '-2 s'"):
        require_positive("-2 s", "duration", "s")
    with pytest.raises(ValueError, match=r"^band: must be finite"):
        require_finite("inf deg", "band", "rad")
    for value in (Q_(3, "m"), Q_(3), [1.0, Q_(2, "m")], Q_(np.eye(2), "N*m")):
        with pytest.raises(
            UnitError,
            match=r"^w: takes a plain number here \(no unit is "
            r"declared for it\)",
        ):
            require_finite(value, "w")
        with pytest.raises(UnitError, match=r"^w: takes a plain number here"):
            require_numeric(value, "w")
