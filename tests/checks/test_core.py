"""The Check and CheckResult types behind `flexsat validate` (flexsat.checks.core)."""

import pytest

from flexsat.checks.core import COLUMNS, STATUSES, Check, Discrepancy, evaluate


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


@pytest.mark.parametrize(
    "kwargs,message",
    [
        (dict(), r"give rtol or atol"),
        (dict(rtol=-1.0), r"^rtol: must be a finite number >= 0"),
    ],
)
def test_bad_checks_are_refused(kwargs, message):
    with pytest.raises(ValueError, match=message):
        _check(lambda: 2.0, **kwargs)


def _erratum(compute):
    """Printed 2.0; the paper's own inputs give 2.5 (tolerance 0.1 %)."""
    return Check(
        "demo",
        "x",
        "seed 000_7bfdb62d2eacc22a.txt, Eq. 1",
        2.0,
        "s",
        compute,
        rtol=1e-3,
        discrepancy=Discrepancy(2.5, "the paper misprints 2.5 as 2.0"),
    )


def test_a_discrepancy_holds_only_at_the_explained_value():
    """Outside the published tolerance and at the explained value: discrepancy; anywhere else
    outside it: fail (a regression is not hidden by the explanation); inside it: pass, with the
    explanation flagged stale."""
    at = evaluate(_erratum(lambda: 2.5005))
    assert (at.status, at.passed, at.failed, at.stale) == ("discrepancy", False, False, False)
    assert at.explanation == "the paper misprints 2.5 as 2.0"
    elsewhere = evaluate(_erratum(lambda: 3.0))
    assert (elsewhere.status, elsewhere.failed) == ("fail", True)
    assert "2.5" in elsewhere.explanation and "misprints" in elsewhere.explanation
    fixed = evaluate(_erratum(lambda: 2.0))
    assert (fixed.status, fixed.failed, fixed.stale) == ("pass", False, True)
    assert fixed.explanation.startswith("stale discrepancy note")
    crashed = evaluate(_erratum(lambda: 1 / 0))
    assert crashed.status == "error" and "ZeroDivisionError" in crashed.explanation


def test_every_status_but_a_plain_pass_has_an_explanation():
    plain = evaluate(_check(lambda: 2.0, rtol=1e-3))
    assert plain.explanation is None
    unexplained = evaluate(_check(lambda: 3.0, rtol=1e-3))
    assert unexplained.status == "fail"
    assert "no erratum or model deviation explains it" in unexplained.explanation
    for result in (unexplained, evaluate(_erratum(lambda: 2.5))):
        d = result.as_dict()
        assert d["explanation"] and d["status"] in STATUSES
        assert list(d)[: len(COLUMNS)] == list(COLUMNS)


def test_a_discrepancy_must_differ_from_the_published_value():
    with pytest.raises(ValueError, match="within the tolerance of the published 2.0"):
        _check(lambda: 2.0, rtol=1e-3, discrepancy=Discrepancy(2.001, "no real difference"))
    with pytest.raises(ValueError, match="^discrepancy.explanation: must be a non-empty"):
        Discrepancy(2.5, " ")
    with pytest.raises(ValueError, match="^discrepancy.value: must be finite"):
        Discrepancy(float("inf"), "why")


def test_json_cites_the_paper_not_the_seed_file():
    d = evaluate(_erratum(lambda: 2.5)).as_dict()
    assert d["source"] == "Junkins, Pollock & Rahman 1990, Eq. 1"
    assert d["references"][0].startswith("Junkins, Pollock & Rahman 1990: J. L. Junkins")
    assert d["discrepancy_value"] == 2.5
