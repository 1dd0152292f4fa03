"""Bainum & Reddy's beam in orbit (:mod:`flexsat.cases.bainum`; Bainum & Reddy 1979, NASA
CR-158684): free-free modes, the nonlinear equations, the case protocol, inputs and errata.

Tolerances: an acceptance number printed with k decimals is matched to half a unit of its last
digit (e.g. -0.1717 to 5e-5); the report's gain matrices are matched to the figures they carry
(stated per test).
"""

import numpy as np
import pytest
import scipy.integrate
import scipy.linalg

from flexsat.cases.bainum import (
    PUBLISHED,
    bainum,
    closed_loop_matrix,
    free_free_lambda_l,
    mode_shape,
    published_matrix,
    theory_ratios,
)
from flexsat.cases.bainum_control import (
    chapter2_case,
    chapter2_example,
    decoupling_gains,
    modal_lqr_gains,
    modal_riccati,
)
from flexsat.cases.bainum_three_mass import three_mass


# -- Appendix A: free-free modes ---------------------------------------------------------------
def test_free_free_modes_match_appendix_a():
    """Notes §1.5: λl, φ at the quarter points (φ = +2 at the left end), ∫φ² dχ = l, orthogonal."""
    np.testing.assert_allclose(
        free_free_lambda_l(5), [4.730041, 7.853205, 10.995608, 14.137165, 17.278760], atol=5e-7
    )
    lam = free_free_lambda_l(5)
    np.testing.assert_allclose(np.cos(lam) * np.cosh(lam), 1.0, rtol=1e-7)  # cosh λl ~ 1e7
    x = np.array([-0.5, -0.25, 0.0, 0.25, 0.5])
    table = {
        1: [2, -0.19839, -1.21564, -0.19839, 2],
        2: [2, -1.16950, 0, 1.16950, -2],
        3: [2, -1.24229, 1.42238, -1.24229, 2],
        4: [2, -0.51204, 0, 0.51204, -2],
        5: [2, 0.55450, -1.41386, 0.55450, 2],
    }
    for r, values in table.items():
        np.testing.assert_allclose(mode_shape(r, x), values, atol=5e-6)
    assert mode_shape(2, 0.0) == 0.0 and mode_shape(4, 0.0) == 0.0  # exact antisymmetry
    xs = np.linspace(-0.5, 0.5, 40001)
    Phi = np.array([mode_shape(r, xs) for r in range(1, 6)])
    gram = scipy.integrate.simpson(Phi[:, None, :] * Phi[None, :, :], x=xs)
    np.testing.assert_allclose(gram, np.eye(5), atol=1e-9)  # M_n = ρl for every mode
    np.testing.assert_allclose(theory_ratios(4), [3200, 24315.2, 93447.4, 255352.3], atol=0.05)


# -- nonlinear equations -----------------------------------------------------------------------
def test_nonlinear_equations_are_eqs_1_and_2_and_reduce_to_the_linear_ones():
    beam = bainum()
    state = np.array([0.3, 0.01, -0.02, 0.4, 0.1, 0.2])  # θ, z1, z2, θ', z1', z2'
    acc = beam.accelerations(state, np.zeros(3))
    th, dth = 0.3, 0.4
    k = 3200.0 - (3 * np.sin(th) ** 2 - 1) - (dth - 1) ** 2
    assert acc[0] == pytest.approx(-1.5 * np.sin(0.6), rel=1e-14)
    assert acc[1] == pytest.approx(-k * 0.01, rel=1e-14)
    # at θ = θ' = 0 the orbital terms -(3 sin²θ - 1) - (θ' - 1)² cancel: exactly linear
    flat = np.array([0.0, 0.01, -0.02, 0.0, 0.1, 0.2])
    np.testing.assert_array_equal(
        beam.accelerations(flat, [1.0, 2.0, 3.0]),
        beam.accelerations(flat, [1.0, 2.0, 3.0], nonlinear=False),
    )


def test_nonlinear_and_linear_agree_for_small_amplitudes():
    """Ch. II example from x(0) = amp in every position: the nonlinear response differs from
    the linear one by < 0.2 % of each state's peak at amp = 0.01, and the difference shrinks at
    least in proportion to the amplitude (pitch: sin 2θ is cubic; modes: θ'z is quadratic)."""
    beam = bainum()
    cl = chapter2_example()
    errors = []
    for amp in (0.01, 0.005):
        lin = beam.simulate(cl.G, None, cl.K_rate, [amp] * 3, 1.0, nonlinear=False, n_points=201)
        non = beam.simulate(cl.G, None, cl.K_rate, [amp] * 3, 1.0, nonlinear=True, n_points=201)
        errors.append(np.abs(non.states - lin.states).max(axis=0) / np.abs(lin.states).max(axis=0))
    assert errors[0].max() < 2e-3
    assert np.all(errors[1] < 0.55 * errors[0])


# -- case protocol, inputs, errata -------------------------------------------------------------
def test_frequencies_and_mode_details():
    beam = bainum()
    wc = beam.orbit_rate_value
    assert wc == pytest.approx(1.11577e-3, rel=5e-6)  # 250 n.mi. circular orbit
    f = beam.frequencies_hz(5)
    np.testing.assert_allclose(f, np.sqrt([3, 3200, 28800, 93079.5, 255331.4]) * wc / (2 * np.pi))
    assert f[1] == pytest.approx(0.01, rel=5e-3)  # the published 1/100 cps
    f7 = beam.frequencies_hz(7)
    np.testing.assert_array_equal(f7[:5], f)
    assert f7[5] == pytest.approx(np.sqrt(theory_ratios(5)[4]) * wc / (2 * np.pi), rel=1e-12)
    d = beam.mode_descriptions(7)
    assert d[0].startswith("rigid pitch") and "antisymmetric" in d[2] and "theory" in d[5]
    details = beam.mode_details(5)
    assert details["ratio_sq_used"][1:] == list(PUBLISHED["frequency_ratios"])
    assert details["shape_at_xi_over_l"]["mode_1"][2] == pytest.approx(-1.21564, abs=5e-6)
    assert bainum(orbit_rate="1.115e-3 rad/s").orbit_rate_value == 1.115e-3
    assert bainum(frequency_ratios=[3200, 3]).stiffness(2).tolist() == [3.0, 3200.0, 3.0]
    assert bainum(frequency_ratios="[3200, 24315.2]").frequency_ratios == (3200.0, 24315.2)
    assert bainum(frequency_ratios=3200).frequency_ratios == (3200.0,)


def test_published_matrix_applies_the_errata():
    assert published_matrix("ch3_case1_G")[0, 2] == -29.76
    assert published_matrix("ch3_case2_K")[4, 0] == -1.167
    lqr = published_matrix("ch3_case2_lqr")
    assert lqr[[1, 2, 4], 7].tolist() == [-1091.7, -810.35, -390.27]
    assert lqr[[0, 4], 9].tolist() == [1682.6, 1681.2]
    assert published_matrix("ch3_case2_G").tolist() == [list(r) for r in PUBLISHED["ch3_case2_G"]]
    with pytest.raises(ValueError, match=r"^item: unknown published item"):
        published_matrix("ch5")


@pytest.mark.parametrize(
    "call,message",
    [
        (lambda: bainum(frequency_ratio=(1.0,)), r"^bainum: unknown parameter\(s\)"),
        (
            lambda: bainum(frequency_ratios=(3200.0, -1.0)),
            r"^frequency_ratios: must be a non-empty",
        ),
        (
            lambda: bainum(frequency_ratios="3200, x"),
            r"^frequency_ratios: must be a comma-separated",
        ),
        (lambda: bainum(orbit_altitude="250 kg"), r"^orbit_altitude: incompatible units"),
        (
            lambda: bainum(pitch_influence=float("nan")),
            r"^pitch_influence: must be a finite number",
        ),
        (lambda: three_mass(total_mass=0.0), r"^total_mass: must be > 0"),
        (lambda: bainum().actuator_matrix([0.7], 2), r"^positions: actuator positions are"),
        (lambda: bainum().frequencies_hz(0), r"^n_modes: must be a positive integer"),
        (lambda: chapter2_case(5), r"^case: must be one of \[1, 2, 3, 4\]"),
        (lambda: chapter2_case(4, midspan="x"), r"^midspan: must be 'exact' or 'published'"),
        (lambda: chapter2_example([1.0, 2.0]), r"^gains: must be the three rate gains"),
        (lambda: modal_riccati(3.0, R=0.0), r"^R: must be > 0"),
        (lambda: modal_riccati(3.0, R=-1.0), r"^R: must be > 0"),
        (lambda: modal_riccati(3.0, Q1=-1.0), r"^Q1: must be >= 0"),
        (lambda: modal_riccati(0.0, Q1=0.0, Q2=1.0), r"^Q1, Q2: no stabilizing solution"),
        (
            lambda: modal_lqr_gains(np.ones((3, 2)), [3.0, 3200.0, 28800.0]),
            r"^G: per-mode regulator needs as many actuators",
        ),
        (
            lambda: decoupling_gains(np.ones((2, 2)), [3.0, 3200.0, 28800.0]),
            r"^G: must have 3 rows",
        ),
        (
            lambda: decoupling_gains([[1.0], [1.0]], [3.0, 3200.0]),
            r"^G: decoupling impossible: rate column 1",
        ),
        (lambda: decoupling_gains(np.eye(2), [[3.0, 1.0], [0.0, 2.0]]), r"^stiffness: must be"),
        (lambda: closed_loop_matrix([3.0], [[1.0]], None, [[1.0, 2.0]]), r"^K_rate: must be 1x1"),
        (lambda: bainum().simulate(np.eye(2), None, np.eye(2), [0.01], 1.0), r"^x0: must have 2"),
        (
            lambda: bainum().simulate(np.eye(2), None, np.eye(2), [0.01, 0.0], 0.0),
            r"^tau_end: must be > 0",
        ),
        (lambda: three_mass().reduced_pair(3), r"^n_actuators: must be 1 or 2"),
    ],
)
def test_bad_inputs_name_the_field(call, message):
    with pytest.raises(ValueError, match=message):
        call()
