"""Bainum & Reddy's beam in orbit (Bainum & Reddy 1979, NASA CR-158684).

Tolerances: an acceptance number printed with k decimals is matched to half a unit of its last
digit (e.g. -0.1717 to 5e-5); the report's gain matrices are matched to the figures they carry
(stated per test).
"""

import numpy as np
import pytest
import scipy.integrate
import scipy.linalg

from flexsat.analysis import controllability_rank, is_stabilizable, pbh_test
from flexsat.cases.bainum import (
    ERRATA,
    PUBLISHED,
    bainum,
    chapter2_case,
    chapter2_example,
    chapter3_case,
    closed_loop_matrix,
    decoupling_gains,
    first_order,
    free_free_lambda_l,
    modal_lqr_gains,
    modal_riccati,
    mode_shape,
    published_matrix,
    sorted_poles,
    theory_ratios,
    three_mass,
)
from flexsat.control import lqr


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


# -- Ch. II: controllability ------------------------------------------------------------------
@pytest.mark.parametrize("midspan", ["exact", "published"])
@pytest.mark.parametrize(
    "c,d,rank",
    [
        (3200.0, 28800.0, 3),  # generic
        (3200.0, 3200.0, 3),  # ω1 = ω2: not necessary (a)
        (3.0, 28800.0, 3),  # ω1 = √3 ω_c: not necessary (b)
        (3200.0, 3.0, 2),  # ω2 = √3 ω_c: rank lost (c)
        (3.0, 3.0, 2),  # 3 = c = d (d)
    ],
)
def test_case_4_loses_rank_only_when_omega2_is_sqrt3_omegac(c, d, rank, midspan):
    """Acceptance: Ch. II Case 4 (L377-L442), actuators at -l/2, +l/2, 0, pitch + 2 modes.
    Kalman rank of the reduced 3x9 pair, Balas' block test and PBH on the 6-state model agree;
    the uncontrollable modes are at ±j√3, where pitch and mode 2 (and mode 1 if c = 3) share
    κ = 3 with a rank-deficient block of B."""
    r = chapter2_case(4, c, d, midspan=midspan)
    assert r.kalman_rank == rank
    assert r.blocks.controllable == (rank == 3)
    if rank == 3:
        assert r.uncontrollable.size == 0
    else:
        np.testing.assert_allclose(r.uncontrollable, [-1j * np.sqrt(3), 1j * np.sqrt(3)], atol=1e-9)
        assert [g.modes for g in r.blocks.deficient] == [(0, 1, 2) if c == 3 else (0, 2)]


def test_case_4_rank_sweep_over_omega2():
    """Only d = (ω2/ω_c)² = 3 is a loss, for d on a grid through it and c = 3200 or 3."""
    for c in (3200.0, 3.0, 28800.0):
        for d in (0.5, 2.9, 2.999, 3.0, 3.001, 3.1, 10.0, 3200.0, 28800.0, 1e5):
            assert chapter2_case(4, c, d).kalman_rank == (2 if d == 3.0 else 3), (c, d)


def test_case_1_determinant_and_conditions():
    """Case 1 (one actuator at -l/2): det C = -a b² (c - d)(c - 3)(d - 3) (L331-L339)."""
    a, b = 59.52, 20.0
    for c, d in ((3200.0, 28800.0), (10.0, 50.0), (7.0, 2.0)):
        r = chapter2_case(1, c, d)
        C = np.hstack([r.B, np.diag(r.stiffness) @ r.B, np.diag(r.stiffness) ** 2 @ r.B])
        assert np.linalg.det(C) == pytest.approx(-a * b * b * (c - d) * (c - 3) * (d - 3), rel=1e-9)
        assert r.controllable
    for c, d in ((3.0, 28800.0), (3200.0, 3.0), (3200.0, 3200.0)):
        assert chapter2_case(1, c, d).kalman_rank == 2


def test_cases_2_and_3_are_controllable_for_any_frequencies():
    """rank B = 2 (L355, L373), so repeated frequencies do not matter."""
    for c, d in ((3200.0, 28800.0), (3200.0, 3200.0), (3.0, 3.0)):
        assert chapter2_case(2, c, d).controllable and chapter2_case(2, c, d).blocks.controllable
        assert chapter2_case(3, c).controllable and chapter2_case(3, 3.0).blocks.controllable
    B = chapter2_case(2, midspan="published").B
    assert B[0, 2] == pytest.approx(-10 * np.sqrt(2))  # the report's e = √2/(M l ω_c²)
    assert chapter2_case(2).B[0, 2] == pytest.approx(-12.1564446, abs=1e-6)  # erratum


def test_chapter2_example_closed_loop_poles():
    """Acceptance (L446-L468, errata L462/L466): one actuator, rate gains K = (-0.00577,
    -0.05656, -0.01695); poles printed to 4 decimals, matched to 5e-5."""
    poles = chapter2_example().poles
    expected = [
        -0.1717 - 1.7236j,
        -0.1717 + 1.7236j,
        -0.5656 - 56.5627j,
        -0.5656 + 56.5627j,
        -0.1695 - 169.7039j,
        -0.1695 + 169.7039j,
    ]
    np.testing.assert_allclose(poles.real, np.real(expected), atol=5e-5)
    np.testing.assert_allclose(poles.imag, np.imag(expected), atol=5e-5)
    # the gains are uncoupled ζ ≈ 0.1, 0.01, 0.001 designs
    zeta = (
        -np.array([59.52, 20.0, 20.0])
        * PUBLISHED["ch2_gains"]
        / (2 * np.sqrt([3.0, 3200.0, 28800.0]))
    )
    np.testing.assert_allclose(zeta, [0.09914, 0.009998, 0.000999], atol=5e-6)


# -- Ch. III: decoupling and per-mode regulator ------------------------------------------------
def test_chapter3_case1_decoupling_needs_g13_minus_29_76():
    """Erratum L800: with G13 = -29.76 (= -ξ/(Jω_c²) at ξ = +l/4) G K_printed is diagonal to the
    printed figures and -G⁻¹diag(2√F) reproduces the printed K (to 0.3 % of each column: the
    report's targets were 3.458, 113.4, 339.40 instead of 2√F = 3.4641, 113.137, 339.411);
    with the printed +29.76 the printed gains destabilize pitch."""
    F, G = chapter3_case(1)
    assert G[0, 2] == -29.76
    exact = chapter3_case(1, shapes="exact")[1]
    np.testing.assert_allclose(exact[0], G[0], rtol=1e-15)  # -2(ξ/l)·59.52
    np.testing.assert_allclose(exact[1:], [[20, 20, -1.98391], [20, -20, 11.69496]], atol=5e-5)
    K_printed = published_matrix("ch3_case1_K")
    GK = G @ K_printed
    np.testing.assert_allclose(np.diag(GK), [-3.458, -113.4, -339.40], rtol=5e-4)
    assert np.abs(GK - np.diag(np.diag(GK))).max() < 0.02
    _, K = decoupling_gains(G, F)
    np.testing.assert_allclose(
        K,
        [
            [-0.0110069, -2.82843, -5.27582],
            [0.0170380, -2.82843, 3.51722],
            [0.0603115, 0.0, -17.5861],
        ],
        rtol=1e-5,
        atol=1e-12,
    )
    for col in range(3):
        scale = np.abs(K_printed[:, col]).max()
        np.testing.assert_allclose(K[:, col], K_printed[:, col], rtol=0, atol=3e-3 * scale)
    poles = sorted_poles(closed_loop_matrix(F, G, None, K_printed))
    np.testing.assert_allclose(
        sorted(poles.real),
        [-169.70057, -169.70057, -60.55876, -52.84124, -1.72906, -1.72906],
        atol=5e-5,
    )
    G_printed = published_matrix("ch3_case1_G", errata=False)
    assert G_printed[0, 2] == 29.76
    unstable = np.linalg.eigvals(closed_loop_matrix(F, G_printed, None, K_printed))
    assert unstable.real.max() == pytest.approx(0.0625, abs=5e-4)
    # the exact decoupled loop: critically damped double roots -√3, -√3200, -√28800
    exact = sorted_poles(closed_loop_matrix(F, G, None, K))
    np.testing.assert_allclose(
        sorted(exact.real), np.repeat(-np.sqrt([28800, 3200, 3]), 2), rtol=1e-5
    )


def test_chapter3_case2_decoupling_gains_and_k51_erratum():
    """L839-L841 from the printed 5x5 G: -G⁻¹diag(2√F) matches the printed gains to 4
    significant figures (rtol 2e-4, atol 5e-4) once K51 = -1.167 (erratum; recomputed
    -1.16685); with the printed -1.669 the loop is unstable (+0.114, +26.34)."""
    F, G = chapter3_case(2)
    np.testing.assert_allclose(F, [3.0, 3200.0, 28800.0, 93079.5, 255331.4])
    _, K = decoupling_gains(G, F)
    printed = published_matrix("ch3_case2_K")
    assert printed[4, 0] == -1.167
    np.testing.assert_allclose(K, printed, rtol=2e-4, atol=5e-4)
    assert K[4, 0] == pytest.approx(-1.16685, abs=5e-6)
    assert np.linalg.eigvals(closed_loop_matrix(F, G, None, printed)).real.max() < 0
    wrong = published_matrix("ch3_case2_K", errata=False)
    growth = np.sort(np.linalg.eigvals(closed_loop_matrix(F, G, None, wrong)).real)[-2:]
    np.testing.assert_allclose(growth, [0.114, 26.34], atol=5e-3)
    assert np.linalg.cond(G) == pytest.approx(1879, rel=1e-3)


def test_exact_shapes_make_the_symmetric_five_actuator_layout_singular():
    """Notes §3.3: with Appendix A shapes, G for (-l/2, -l/4, 0, l/4, l/2) has rank 4, so
    neither decoupling nor the per-mode regulator (u = E⁻¹u') exists; the errors say so."""
    F, G = chapter3_case(2, shapes="exact")
    s = np.linalg.svd(G, compute_uv=False)
    assert s[-1] / s[0] < 1e-12
    with pytest.raises(ValueError, match=r"^G: decoupling impossible: rate column"):
        decoupling_gains(G, F)
    with pytest.raises(ValueError, match=r"^G: singular"):
        modal_lqr_gains(G, F)


def test_pitch_riccati_solution():
    """Acceptance (Ch. III eqs 25-27, Q = diag(1, F), R = 1): pitch S = (5.76590, 0.162278,
    1.823336), matched to half a unit of the last printed digit."""
    S11, S12, S22 = modal_riccati(3.0)
    assert S11 == pytest.approx(5.76590, abs=5e-6)
    assert S12 == pytest.approx(0.162278, abs=5e-7)
    assert S22 == pytest.approx(1.823336, abs=5e-7)


@pytest.mark.numerics
def test_closed_form_riccati_equals_care_and_stays_accurate_for_stiff_modes(schur_error_bound):
    """Eqs 25-27 against scipy's CARE (with damping, a non-unit R, an unstable and a rigid
    coordinate), and for the stiff modes, where the printed form -F + √(F² + Q1/R) cancels,
    against the notes' S values and the scalar Riccati equations themselves (scipy's CARE loses
    5 digits of S12 at F = 255331.4)."""
    for F, Q1, Q2, R, D in (
        (3.0, 1.0, 3.0, 1.0, 0.0),
        (3200.0, 1.0, 3200.0, 1.0, 0.0),
        (5.0, 2.0, 0.5, 0.3, 0.7),
        (-2.0, 1.0, 1.0, 2.0, 0.1),
        (0.0, 1.0, 0.0, 1.0, 0.0),
    ):
        S11, S12, S22 = modal_riccati(F, Q1, Q2, R, D)
        A = np.array([[0.0, 1.0], [-F, -D]])
        S = scipy.linalg.solve_continuous_are(
            A, np.array([[0.0], [1.0]]), np.diag([Q1, Q2]), np.array([[R]])
        )
        # scipy's S carries the Schur method's error (tests/conftest.py), the closed form
        # rounding only: 2x the bound.  At F = 3200 (κ(U11) = 2e5) that is 3e-5 absolute, 20 %
        # of S12: scipy cannot check the stiff S12, the scalar equations below do
        assert np.all(
            np.abs(np.array([[S11, S12], [S12, S22]]) - S)
            <= 2 * schur_error_bound(S) * np.linalg.norm(S, 2)
        )
    F = np.array([3200.0, 28800.0, 93079.5, 255331.4])
    S11, S12, S22 = modal_riccati(F)
    np.testing.assert_allclose(S11, [181019.35, 4.8875221e6, 2.8397562e7, 1.2901979e8], rtol=1e-7)
    np.testing.assert_allclose(
        S12, [1.5625e-4, 1.7361111e-5, 5.3717521e-6, 1.9582394e-6], rtol=1e-7
    )
    np.testing.assert_allclose(S22, [56.568545, 169.70563, 305.08933, 505.30328], rtol=1e-7)
    # (1,1), (1,2), (2,2) entries of eq 24 with D = 0, R = 1, Q = diag(1, F)
    np.testing.assert_allclose(2 * F * S12 + S12**2, 1.0, rtol=1e-13)
    np.testing.assert_allclose(F * S22 + S12 * S22, S11, rtol=1e-13)
    np.testing.assert_allclose(S22**2 - 2 * S12, F, rtol=1e-13)


@pytest.mark.numerics
def test_chapter3_case2_per_mode_regulator_gains():
    """L873-L880: Q = diag(1, F), R = 1. Recomputed rate columns 6, 7, 8, 10 match the printed
    matrix to 4 significant figures (rtol 2e-4, atol 5e-4) after the errata of columns 8 and
    10; the pitch position column to 3 figures (printed -0.0545 for -0.05466); column 9 is
    the notes' unresolved mismatch. Modes get ζ = 0.5 and pitch -0.911668 ± 1.526807j."""
    F, G = chapter3_case(2)
    K_pos, K_rate = modal_lqr_gains(G, F)
    printed = published_matrix("ch3_case2_lqr")
    for col in (0, 1, 2, 4):
        np.testing.assert_allclose(K_rate[:, col], printed[:, 5 + col], rtol=2e-4, atol=5e-4)
    np.testing.assert_allclose(K_pos[:, 0], printed[:, 0], rtol=5e-3)
    assert not np.allclose(K_rate[:, 3], printed[:, 8], rtol=0.05)  # unresolved
    np.testing.assert_allclose(K_rate[[0, 2], 3], [-3.78926, -10.82645], rtol=1e-5)
    # the same gains from the full 10x10 regulator (cross-check of eq 18's mapping)
    A, B = first_order(F, G)
    Q = np.diag(np.concatenate([np.ones(5), F]))
    R = G.T @ G  # u' = G f: u'ᵀu' = fᵀ GᵀG f
    K_full, S, _ = lqr(A, B, Q, R)
    # ‖S‖ ≈ 1e8: the full solve resolves each gain only to the effect of round-off in its data
    # (|δA| <= eps|A|, ..., GᵀG formed to 5 eps |G|ᵀ|G|); 0.1 to 0.2 of that bound is used
    floor = _gain_roundoff(A, B, Q, R, 5 * np.finfo(float).eps * np.abs(G).T @ np.abs(G), S, K_full)
    assert np.all(np.abs(K_full + np.hstack([K_pos, K_rate])) <= floor)
    # which checks the rate gains and the pitch position gain to 1e-8, while the stiff modes'
    # position gains (~1/(2 F_i) through GᵀG, cond 3.5e6) are below what the full solve resolves
    assert np.all(floor[:, 5:] <= 1e-8 * np.abs(K_rate).max(0))
    assert np.all(floor[:, 0] <= 1e-8 * np.abs(K_pos[:, 0]).max())
    assert floor[:, 4].max() > np.abs(K_pos[:, 4]).max()
    poles = sorted_poles(closed_loop_matrix(F, G, K_pos, K_rate))
    np.testing.assert_allclose(poles[:2], [-0.911668 - 1.526807j, -0.911668 + 1.526807j], atol=5e-7)
    zeta = -poles.real / np.abs(poles)
    np.testing.assert_allclose(zeta[2:], 0.5, atol=1e-6)


def _gain_roundoff(A, B, Q, R, dR, S, K):
    """First-order bound on |δK| of the regulator K = R⁻¹BᵀS when every entry of A, B, Q is
    perturbed by its round-off eps|x| and R by ``dR``: the sum over entries of |∂K/∂x| δx,
    with δS from the closed-loop Lyapunov equation (A-BK)ᵀδS + δS(A-BK) = -(δAᵀS + SδA
    - SδBK - KᵀδBᵀS + KᵀδRK + δQ) and δK = R⁻¹(δBᵀS + BᵀδS - δRK) (componentwise condition
    of the gain; a backward-stable solve cannot resolve K more finely)."""
    eps, n = np.finfo(float).eps, len(A)
    Acl = A - B @ K
    lyap = np.kron(np.eye(n), Acl.T) + np.kron(Acl.T, np.eye(n))  # vec(AclᵀX + XAcl), by column
    bound = np.zeros_like(K)
    for name, _matrix, size in (
        ("A", A, eps * np.abs(A)),
        ("B", B, eps * np.abs(B)),
        ("Q", Q, eps * np.abs(Q)),
        ("R", R, dR),
    ):
        for i, j in zip(*np.nonzero(size)):
            d = {
                key: np.zeros_like(value) for key, value in (("A", A), ("B", B), ("Q", Q), ("R", R))
            }
            d[name][i, j] = size[i, j]
            rhs = (
                d["A"].T @ S
                + S @ d["A"]
                - S @ d["B"] @ K
                - K.T @ d["B"].T @ S
                + K.T @ d["R"] @ K
                + d["Q"]
            )
            dS = np.linalg.solve(lyap, -rhs.ravel(order="F")).reshape(n, n, order="F")
            bound += np.abs(np.linalg.solve(R, d["B"].T @ S + B.T @ dS - d["R"] @ K))
    return bound


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


def test_chapter3_case1_response_at_36_seconds():
    """Notes §3.2 [DERIVED]: printed K with G13 = -29.76, τ = 0.0401 (36 s): θ = 9.98e-3,
    z1 = 3.39e-3, z2 = 8.6e-5; peak forces 3.69, 1.83, 10.98; nonlinear within 1e-6 of linear."""
    beam = bainum()
    _, G = chapter3_case(1)
    K = published_matrix("ch3_case1_K")
    lin = beam.simulate(G, None, K, [0.01] * 3, 0.0401, nonlinear=False, n_points=2001)
    non = beam.simulate(G, None, K, [0.01] * 3, 0.0401, n_points=2001)
    assert np.all(np.abs(lin.states[-1, :3] - [9.98e-3, 3.39e-3, 8.6e-5]) <= [5e-6, 5e-6, 5e-7])
    np.testing.assert_allclose(np.abs(lin.forces).max(axis=0), [3.69, 1.83, 10.98], atol=5e-3)
    assert np.abs(non.states - lin.states).max() < 1e-6
    assert beam.seconds(0.0401) == pytest.approx(35.94, abs=0.01)


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
