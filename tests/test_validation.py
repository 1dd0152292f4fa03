import numpy as np
import pytest

from flexsat.validation import require_count, require_finite, require_nonneg, require_positive


def test_accepts_good_values():
    assert require_positive(2.0, "x") == 2.0
    assert np.array_equal(require_nonneg([0.0, 1.0], "x"), [0.0, 1.0])
    assert require_count(3.0, "n") == 3


@pytest.mark.parametrize("check,value,rule", [
    (require_finite, float("nan"), "must be finite"),
    (require_finite, "3 m", "must be a number in SI units, got the string"),
    (require_finite, object(), "must be a number"),
    (require_positive, 0.0, "must be > 0"),
    (require_nonneg, -1e-9, "must be >= 0"),
    (require_count, 2.5, "must be a positive integer"),
    (require_count, True, "must be a positive integer"),
    (require_count, 0, "must be a positive integer"),
])
def test_refusals_name_the_field_and_the_rule(check, value, rule):
    with pytest.raises(ValueError, match=rf"^mass: {rule}"):
        check(value, "mass")
