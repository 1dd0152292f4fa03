"""NPS rows of ``flexsat validate`` (flexsat.checks.nps): every row recomputed passes,
including the steady-state error of the simulated PD slew under the cable torque (Eq. 23)."""

import math

import pytest

from flexsat.checks import run_checks


@pytest.fixture(scope="module")
def results():
    return run_checks("nps")


def test_rows_pass(results):
    assert len(results) >= 5
    assert all(r.passed for r in results), [r.check.quantity for r in results if not r.passed]


def test_cable_row_is_t_d_over_k(results):
    # the row's computed value is the run's final error: T_D / k of the printed gain to the
    # printed digits, and of the model's own gain to 1e-6 (tests/cases/test_nps.py)
    (row,) = [r for r in results if "θ_ss" in r.check.quantity]
    assert row.check.published == 0.041
    assert row.computed == pytest.approx(math.degrees(1e-3 / 1.3985), abs=5e-5)
