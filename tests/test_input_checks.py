import numpy as np
import pytest

from flexsat.input_checks import (
    require_count,
    require_finite,
    require_nonneg,
    require_numeric,
    require_physical_inertia,
    require_positive,
)


def test_accepts_good_values():
    assert require_positive(2.0, "x") == 2.0
    assert np.array_equal(require_nonneg([0.0, 1.0], "x"), [0.0, 1.0])
    assert require_count(3.0, "n") == 3


@pytest.mark.parametrize(
    "check,value,rule",
    [
        (require_finite, float("nan"), "must be finite"),
        (require_finite, "3 m", "must be a number in SI units, got the string"),
        (require_finite, object(), "must be a number"),
        (require_positive, 0.0, "must be > 0"),
        (require_nonneg, -1e-9, "must be >= 0"),
        (require_count, 2.5, "must be a positive integer"),
        (require_count, True, "must be a positive integer"),
        (require_count, 0, "must be a positive integer"),
    ],
)
def test_refusals_name_the_field_and_the_rule(check, value, rule):
    with pytest.raises(ValueError, match=rf"^mass: {rule}"):
        check(value, "mass")


def test_numeric_arrays_refuse_strings_objects_and_nan():
    from flexsat.input_checks import require_numeric

    assert require_numeric([[1, 2], [3, 4]], "A").shape == (2, 2)
    with pytest.raises(ValueError, match=r"^A: must be a numeric matrix, got the string"):
        require_numeric("eye", "A", "matrix")
    with pytest.raises(ValueError, match=r"^A: must be a numeric array, got object"):
        require_numeric(object(), "A")
    with pytest.raises(
        ValueError,
        match=r"^A: must be finite \(no NaN or inf\), got shape \(2,\) "
        r"with 1 non-finite entries",
    ):
        require_numeric([1.0, np.nan], "A")


@pytest.mark.parametrize("value", [1j, [1.0, 2j], np.array([[1.0 + 1e-20j]])])
def test_complex_is_refused_naming_the_field(value):
    # the float conversion would drop the imaginary part without a word
    with pytest.raises(ValueError, match=r"^x: must be a real number, got a complex value"):
        require_finite(value, "x")
    with pytest.raises(ValueError, match=r"^x: must be a real matrix, got a complex value"):
        require_numeric(value, "x", "matrix")


def test_complex_with_zero_imaginary_part_is_its_real_part():
    np.testing.assert_array_equal(require_finite(np.array([1.0 + 0j, 2.0]), "x"), [1.0, 2.0])
    np.testing.assert_array_equal(require_numeric([3.0 + 0j], "x"), [3.0])


def test_a_positive_scalar_is_one_finite_number_above_zero_in_si():
    from flexsat.input_checks import require_positive_scalar

    assert require_positive_scalar("2 km", "length", "m") == 2000.0
    for bad, rule in (
        (0, "must be > 0"),
        (float("nan"), "must be finite"),
        ([1.0, 2.0], "must be one number"),
    ):
        with pytest.raises(ValueError, match=f"^length: {rule}"):
            require_positive_scalar(bad, "length", "m")


@pytest.mark.parametrize(
    "moments, definite, rule",
    [
        ((4.0, 1.6, 1.8), True, "triangle inequality"),  # 1.6 + 1.8 < 4
        ((0.0, 0.0, 1.0), False, "triangle inequality"),  # a single-axis inertia: no body
        ((0.0, 1.0, 1.0), True, "positive definite"),  # a thin rod: semi-definite only
        ((-1e-3, 1.0, 1.0), False, "positive semi-definite"),
    ],
)
def test_an_inertia_no_body_has_is_refused(moments, definite, rule):
    with pytest.raises(ValueError, match=rf"^J: .*{rule}"):
        require_physical_inertia(np.diag(moments), "J", definite)


def test_physical_inertias_pass_with_the_flat_plate_and_rod_limits():
    """The triangle inequality's equality (a flat plate: I1 + I2 = I3, here 0.1 + 0.2 with its
    round-off) and, semi-definite, a thin rod (0, I, I) and a point mass (0, 0, 0) pass."""
    plate = np.diag([0.1, 0.2, 0.1 + 0.2])
    assert require_physical_inertia(plate, "J") is plate
    require_physical_inertia(np.diag([0.0, 2.0, 2.0]), "J", definite=False)
    require_physical_inertia(np.zeros((3, 3)), "J", definite=False)
    rotated = np.array([[2.0, 0.5, 0.0], [0.5, 2.0, 0.0], [0.0, 0.0, 4.2]])  # moments 1.5, 2.5
    with pytest.raises(ValueError, match=r"\[1\.5, 2\.5, 4\.2\]"):
        require_physical_inertia(rotated, "J")
