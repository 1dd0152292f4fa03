"""The Check and CheckResult types behind `flexsat validate` (flexsat.checks.core)."""

import pytest

from flexsat.checks.core import Check, evaluate


def _check(compute, **tol):
    return Check("demo", "x", "seed 000, Eq. 1", 2.0, "s", compute, **tol)


def test_tolerances_combine_absolute_and_relative():
    assert _check(lambda: 2.0, rtol=1e-3).passes(2.0019)
    assert not _check(lambda: 2.0, rtol=1e-3).passes(2.0021)
    assert _check(lambda: 2.0, atol=0.1, rtol=1e-3).passes(2.101)
    assert not _check(lambda: 2.0, atol=0).passes(2.0 + 1e-12)  # exact (counts)
    assert _check(lambda: 2.0, rtol=1e-3).tolerance == "±0.1 %"


def test_evaluate_reports_values_and_failures_without_raising():
    good = evaluate(_check(lambda: 2.001, rtol=1e-3))
    assert good.passed and good.relative_error == pytest.approx(5e-4)
    assert good.as_dict()["status"] == "pass"
    bad = evaluate(_check(lambda: 1 / 0, rtol=1e-3))
    assert not bad.passed and bad.status == "error" and "division by zero" in bad.error


@pytest.mark.parametrize("kwargs,message", [
    (dict(), r"give rtol or atol"),
    (dict(rtol=-1.0), r"^rtol: must be a finite number >= 0"),
])
def test_bad_checks_are_refused(kwargs, message):
    with pytest.raises(ValueError, match=message):
        _check(lambda: 2.0, **kwargs)
