"""Issue #5 rows of ``flexsat validate`` (flexsat.checks.identification)."""

import numpy as np
import pytest

from flexsat.checks import run_checks
from flexsat.checks.identification import START_RAD_S, TRUE_RAD_S, _start_frequencies


def test_start_model_frequencies_scale_by_sqrt_of_0_9_over_1_1():
    """M x 1.1 and K x 0.9 scale every frequency by sqrt(0.9/1.1) = 0.904534 (Att. 7 Table 2
    [CHECK] in the spec notes), to rounding."""
    ratio = _start_frequencies() / np.asarray(TRUE_RAD_S)
    assert np.allclose(ratio, np.sqrt(0.9 / 1.1), rtol=1e-12)


def test_only_the_inconsistent_mode_2_start_value_is_a_discrepancy():
    """Att. 7 prints ω_ns,2 = 0.9617, 0.11 % off its own scaling: a discrepancy row that names
    the paper; every other row passes."""
    results = run_checks("identification")
    odd = [r for r in results if not r.passed]
    assert [r.check.quantity for r in odd] == ["ω_ns 2, M × 1.1, K × 0.9"]
    assert odd[0].status == "discrepancy"
    assert odd[0].computed == pytest.approx(1.062 * np.sqrt(0.9 / 1.1), rel=1e-12)
    assert odd[0].check.published == START_RAD_S[1]
    assert "Creamer & Junkins 1988" in odd[0].explanation
    assert len(results) == 10
