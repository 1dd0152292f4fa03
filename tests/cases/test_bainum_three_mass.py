"""Bainum & Reddy's Ch. IV three-mass model (:mod:`flexsat.cases.bainum_three_mass`;
Bainum & Reddy 1979, NASA CR-158684).

Tolerances: an acceptance number printed with k decimals is matched to half a unit of its last
digit (e.g. -0.1717 to 5e-5); the report's gain matrices are matched to the figures they carry
(stated per test).
"""

import numpy as np
import pytest

from flexsat.analysis import controllability_rank, is_stabilizable, pbh_test
from flexsat.cases.bainum import (
    ERRATA,
    PUBLISHED,
)
from flexsat.cases.bainum_three_mass import three_mass


# -- Ch. IV: three-mass model --------------------------------------------------------------------
def test_three_mass_parameters_and_controllability():
    """L1063-L1081: M* = 111.11, a = 222.22, b = 111.11, λ1 = 5.5876e-4, λ2 = 1.67627e-3, g = 3
    with the printed c; the formula gives c = 0.1862132 (printed 0.1862522); one
    actuator is enough: det C = bc/(a² - b²)² = 1.509e-8."""
    t = three_mass()
    assert (t.m_star, t.a, t.b) == pytest.approx((111.11, 222.22, 111.11), abs=5e-3)
    assert t.c_value == 0.1862522
    assert t.c_formula == pytest.approx(0.1862132, abs=5e-8)
    assert three_mass(c=None).c_value == t.c_formula
    np.testing.assert_allclose(t.lambdas, PUBLISHED["ch4_lambda"], rtol=5e-5)
    assert t.g == pytest.approx(3.0, rel=1e-14)
    assert t.controllability_det() == pytest.approx(
        t.b * t.c_value / (t.a**2 - t.b**2) ** 2, rel=1e-12
    )
    assert t.controllability_det() == pytest.approx(1.509e-8, rel=5e-4)
    A_r, B_r = t.reduced_pair(1)
    assert controllability_rank(A_r, B_r) == 2


def test_three_mass_coupled_rate_roots():
    """Acceptance (eq 16, K1 = 0.4728, K2 = 0.4; erratum L1097-L1101): roots -6.40515e-4,
    -8.654e-5 ± 2.95733e-2j, -1.671986, each to half a unit of its last digit; the same
    eigenvalues from the physical (v1, v2) closed loop; the printed roots are 3-figure values."""
    t = three_mass()
    K1, K2 = PUBLISHED["ch4_gains"]
    roots = t.coupled_rate_poles(K1, K2)
    assert roots[0].real == pytest.approx(-1.671986, abs=5e-7)
    assert roots[1].real == pytest.approx(-6.40515e-4, abs=5e-10)
    assert roots[2].real == pytest.approx(-8.654e-5, abs=5e-9)
    assert roots[2].real == roots[3].real
    assert sorted(roots[2:].imag) == pytest.approx([-2.95733e-2, 2.95733e-2], abs=5e-8)
    np.testing.assert_allclose(
        np.sort_complex(np.linalg.eigvals(t.coupled_rate_closed_loop(K1, K2))), roots, rtol=1e-7
    )
    np.testing.assert_allclose(
        t.characteristic_polynomial(K1, K2),
        [1, 1.6728, 2.2350264e-3, 1.4630483e-3, 9.366268e-7],
        rtol=1e-7,
    )
    erratum = next(e for e in ERRATA if e.item == "ch4_roots")
    np.testing.assert_allclose(np.sort_complex(np.array(erratum.corrected)), roots, rtol=1e-6)
    printed = np.array(PUBLISHED["ch4_roots"])  # -6.4019e-4, -8.58139e-4 ± ..., -1.670404
    np.testing.assert_allclose(printed[[0, 3]].real, roots[[1, 0]].real, rtol=1e-3)
    np.testing.assert_allclose(abs(printed[1].imag), roots[3].imag, rtol=2e-3)
    assert printed[1].real / roots[2].real == pytest.approx(9.92, abs=0.01)  # pair 10x off


def test_independent_modal_control_leaves_an_undamped_mode():
    """Eq 12 (L1039-L1041): u1 = -f1 q1 - f2 q1' with f1 = f2 = 1 leaves ±j√λ2 = ±0.0409423j
    (spillover) although the pair is controllable; coupled rate feedback is Hurwitz."""
    t = three_mass()
    poles = t.imc_poles(1.0, 1.0)
    np.testing.assert_allclose(np.sort(np.abs(poles.imag))[:2], np.sqrt(t.lambdas[1]), rtol=1e-9)
    assert np.sqrt(t.lambdas[1]) == pytest.approx(0.0409423, abs=5e-8)
    M = t.imc_closed_loop(1.0, 1.0)
    np.testing.assert_allclose(np.sort_complex(np.linalg.eigvals(M)), poles, atol=1e-9)
    A_r, B_r = t.reduced_pair(1)
    A = np.block([[np.zeros((2, 2)), np.eye(2)], [-A_r, np.zeros((2, 2))]])
    B = np.vstack([np.zeros((2, 1)), B_r])
    assert is_stabilizable(A, B) and pbh_test(A, B).size == 0
    assert np.abs(np.linalg.eigvals(M).real).min() < 1e-12
    assert np.all(t.coupled_rate_poles(0.4728, 0.4).real < 0)
