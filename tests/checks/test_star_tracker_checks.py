"""Issue 14 star-tracker rows of ``flexsat validate`` (flexsat.checks.star_tracker)."""

import pytest

from flexsat.checks import MODULES, run_checks
from flexsat.checks.core import Check
from flexsat.checks.star_tracker import CHECKS


def test_the_papers_claims_pass_live():
    results = run_checks("star_tracker")
    assert [r.status for r in results] == ["pass"] * 3
    by = {r.check.quantity: r.computed for r in results}
    assert by["correct identification rate"] >= 0.999
    assert by["wrong identifications accepted"] == 0
    assert 0 < by["attitude error 1σ, worst body axis (< 5″)"] < 5


def test_the_bound_is_an_interval():
    # "< 5″" as 2.5 ± 2.5″: 5.01″ would fail, a negative value cannot occur
    row = next(c for c in CHECKS if c.unit == "arcsec")
    assert row.passes(4.99) and not row.passes(5.01) and row.passes(0.0)
    assert "star_tracker" in MODULES
    with pytest.raises(ValueError, match="give rtol or atol"):
        Check("star_tracker", "x", "s", 1.0, "", lambda: 1.0)
