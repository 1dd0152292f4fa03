"""Draper/RPL hub + four appendages: Junkins & Kim 1990 (Att. 5 of Junkins, Pollock & Rahman
1990), Table 3 (L2156-L2166), Eqs. 50-59 and Table 4 (L2235-L2248)."""

import importlib

import numpy as np
import pytest

import control
from flexsat.cases.draper_rpl import comparison_functions, draper_rpl, published_gains
from flexsat.units import Q_

# the package re-exports the builder under the module's name, so fetch the module itself
module = importlib.import_module("flexsat.cases.draper_rpl")

# Att. 5 Table 4 (L2235-L2248)
TABLE4_OPEN = [0, 4.3724, 7.9070, 51.4510, 52.8058, 157.5566, 158.3659, 313.7099, 314.3402]
TABLE4_CLOSED_OMEGA = [
    0.3000,
    4.3726,
    7.9071,
    52.0041,
    53.0653,
    158.0285,
    158.5273,
    308.8039,
    311.7689,
]
TABLE4_CLOSED_ZETA_OMEGA = [
    0.2000,
    0.2061,
    0.2539,
    5.3354,
    8.0875,
    14.0467,
    21.4808,
    34.8815,
    22.6602,
]
TABLE4_CONDITION = 37210.8
# notes §4.5 [VERIFIED]: N = 10 per pair, 400 Gauss-Legendre points
NOTES_OPEN = [0, 4.37236, 7.90697, 51.45101, 52.80582, 157.55669, 158.36598, 313.71000, 314.34030]
NOTES_CLOSED_OMEGA = [
    0.29999,
    4.37261,
    7.90711,
    52.00388,
    53.06545,
    158.02834,
    158.52747,
    308.80517,
    311.76895,
]
NOTES_CLOSED_ZETA_OMEGA = [
    0.20000,
    0.20607,
    0.25393,
    5.33520,
    8.08694,
    14.04661,
    21.47869,
    34.87840,
    22.65996,
]
NOTES_CONDITION = 37828


@pytest.fixture(scope="module")
def case():
    return draper_rpl()


@pytest.fixture(scope="module")
def gains():
    return published_gains()


# -- Table 3 and units ---------------------------------------------------------------------------
def test_table_3_derived_quantities_via_pint(case):
    """Notes §4.5 [DERIVED]: EI = 74.5985 lb ft², J = 28.1963 slug ft²."""
    assert Q_(case.EI, "N*m**2").to("lbf*ft**2").magnitude == pytest.approx(74.5985, abs=5e-5)
    assert Q_(case.total_inertia, "kg*m**2").to("slug*ft**2").magnitude == pytest.approx(
        28.1963, abs=5e-5
    )
    assert case.matrices()[0][0, 0] == case.total_inertia
    assert case.length == pytest.approx(4 * 0.3048, rel=1e-15)
    assert case.n_functions == 10 and case.n_dof == 21


def test_gains_are_converted_from_ft_lbf(gains):
    g1, g2 = gains
    assert g1[0, 0] == pytest.approx(1.8342 * 1.3558179483314004, rel=1e-12)
    assert g2[2, 2] == pytest.approx(0.3509 * 1.3558179483314004, rel=1e-12)


# -- the Ritz model, Eqs. 53-54 ------------------------------------------------------------------
def test_comparison_functions_satisfy_clamped_free_conditions():
    L, n = 1.3, 6
    at = lambda z, d: comparison_functions(z, n, L, d)[0]  # noqa: E731
    assert np.allclose(at(0.0, 0), 0, atol=1e-15) and np.allclose(at(0.0, 1), 0, atol=1e-15)
    assert np.allclose(at(L, 2), 0, atol=1e-9)  # zero moment at the free end
    z, h = np.array([0.37]), 1e-5
    fd = (comparison_functions(z + h, n, L) - comparison_functions(z - h, n, L)) / (2 * h)
    assert np.allclose(fd, comparison_functions(z, n, L, 1), rtol=1e-8)
    fd2 = (comparison_functions(z + h, n, L, 1) - comparison_functions(z - h, n, L, 1)) / (2 * h)
    assert np.allclose(fd2, comparison_functions(z, n, L, 2), rtol=1e-7)


def test_matrix_structure_of_eq_54(case):
    M, K, B = case.matrices()
    n = case.n_functions
    p1, p2 = slice(1, n + 1), slice(n + 1, None)
    assert np.allclose(M, M.T, rtol=1e-14, atol=0) and np.array_equal(K, K.T)
    assert np.all(M[p1, p2] == 0) and np.all(K[0] == 0) and np.all(K[p1, p2] == 0)
    assert np.array_equal(M[0, p1], M[0, p2]) and np.array_equal(K[p1, p1], K[p2, p2])
    dphi_L = comparison_functions(case.length, n, case.length, 1)[0]
    assert np.array_equal(B[0], [1, 2, 2])
    assert np.array_equal(B[p1, 1], 2 * dphi_L) and np.all(B[p1, [0, 2]] == 0)
    assert np.array_equal(B[p2, 2], 2 * dphi_L) and np.all(B[p2, :2] == 0)


def test_closed_form_stiffness_matches_quadrature(case):
    """K_qq = 2 EI ∫ φ_i'' φ_j'' dx in closed form against 400-point Gauss-Legendre."""
    n, L = case.n_functions, case.length
    x, w = np.polynomial.legendre.leggauss(400)
    z, w = L * (x + 1) / 2, w * L / 2
    d2 = comparison_functions(z, n, L, 2)
    K = case.matrices()[1]
    assert np.allclose(
        K[1 : n + 1, 1 : n + 1], 2 * case.EI * d2.T @ (w[:, None] * d2), rtol=1e-11, atol=0
    )


def test_quadrature_points_are_enough(case, monkeypatch):
    """400 Gauss-Legendre points: doubling them moves the Table 4 frequencies by
    less than 1e-9 rad/s and every frequency by less than 1e-10 relative (eigensolver noise)."""
    monkeypatch.setattr(module, "QUADRATURE_POINTS", 800)
    finer = draper_rpl().frequencies()
    assert finer[:9] == pytest.approx(case.frequencies()[:9], rel=0, abs=1e-9)
    assert finer[1:] == pytest.approx(case.frequencies()[1:], rel=1e-10)


# -- open loop, Eqs. 56-58 and Table 4 -------------------------------------------------------------
def test_open_loop_frequencies_reproduce_table_4(case):
    """Att. 5 Table 4 open loop (L2239-L2247) to 1e-4 rad/s; notes' values to 1e-5."""
    w = case.frequencies()[:9]
    assert w == pytest.approx(TABLE4_OPEN, abs=1e-4)
    assert w == pytest.approx(NOTES_OPEN, abs=1e-5)
    assert case.frequencies_hz(3) == pytest.approx(w[:3] / (2 * np.pi), rel=1e-15)
    assert case.frequencies().shape == (21,)


@pytest.mark.numerics
def test_modes_are_mass_normalised_eq_56(case):
    M, K, _ = case.matrices()
    phi, w = case.modes(), case.frequencies()
    # the product round-off bound of test_reduced_model_eqs_57_58 (measured: 0.07 of it for M,
    # 0.2 of the largest entry for K; M alone has condition 4e7, so an atol of 1e-10 was at 0.7)
    gamma = len(M) * np.finfo(float).eps
    a = np.abs(phi)
    assert np.all(np.abs(phi.T @ M @ phi - np.eye(21)) <= gamma * a.T @ np.abs(M) @ a)
    assert np.abs(phi.T @ K @ phi - np.diag(w**2)).max() <= gamma * (a.T @ np.abs(K) @ a).max()


@pytest.mark.numerics
def test_reduced_model_eqs_57_58(case):
    M, K, B = case.matrices()
    Mb, Kb, Db = case.reduced(9)
    phi = case.modes()[:, :9]
    # round-off of a product of inner length n: |fl(XᵀY) - XᵀY| <= n eps |X|ᵀ|Y| entrywise; the
    # eigen-solve's M-orthogonality and Rayleigh quotients stay within the same order
    # (measured: 0.07 of it for Mb, 0.5 of the largest for Kb); Db and φᵀB are two
    # evaluations of the same product (their BLAS paths differ), so twice that
    gamma = len(M) * np.finfo(float).eps
    a = np.abs(phi)
    assert np.all(np.abs(Mb - np.eye(9)) <= gamma * a.T @ np.abs(M) @ a)
    assert (
        np.abs(Kb - np.diag(case.frequencies()[:9] ** 2)).max()
        <= gamma * (a.T @ np.abs(K) @ a).max()
    )
    assert np.all(np.abs(Db - phi.T @ B) <= 2 * gamma * a.T @ np.abs(B))


def test_n_functions_counts_one_pair_not_both():
    """Notes §4.5 [VERIFIED resolution]: N = 5 per pair converges from above (4.37305 for mode 2);
    N = 20 per pair gives 305.876 for mode 8, far from the paper's 313.7099, so the paper's
    "N = 20" is 10 functions per pair (21 DOF, 42 states)."""
    coarse, fine = draper_rpl(n_functions=5), draper_rpl(n_functions=20)
    assert coarse.frequencies()[1] == pytest.approx(4.37305, abs=1e-5)
    assert coarse.frequencies()[1] > draper_rpl().frequencies()[1] > fine.frequencies()[1]
    assert fine.frequencies()[7] == pytest.approx(305.876, abs=1e-3)
    assert fine.n_dof == 41


def test_mode_descriptions(case):
    assert case.mode_descriptions(5) == [
        "rigid rotation",
        "1st bending, pairs 1&3 and 2&4 in anti-phase, hub at rest",
        "1st bending, pairs 1&3 and 2&4 in phase, hub counter-rotating",
        "2nd bending, pairs 1&3 and 2&4 in anti-phase, hub at rest",
        "2nd bending, pairs 1&3 and 2&4 in phase, hub counter-rotating",
    ]
    assert case.mode_descriptions(9)[8] == (
        "4th bending, pairs 1&3 and 2&4 in phase, hub counter-rotating"
    )


# -- closed loop, Eq. 59 and Table 4 -------------------------------------------------------------
def test_closed_loop_reproduces_table_4(case, gains):
    """Att. 5 Table 4 closed loop, gains G1, G2 (L2229-L2233) on the full 42-state model.

    Tolerance 2e-3 relative: rounding the gains to 4 decimals (±5e-5) moves these values by up
    to 3.6e-4 relative (measured, docs/draper_rpl.md); the largest deviation found is 1.7e-4."""
    w, zw = case.closed_loop_modes(*gains)
    assert w == pytest.approx(TABLE4_CLOSED_OMEGA, rel=2e-3)
    assert zw == pytest.approx(TABLE4_CLOSED_ZETA_OMEGA, rel=2e-3)
    assert w == pytest.approx(NOTES_CLOSED_OMEGA, abs=1e-5)
    assert zw == pytest.approx(NOTES_CLOSED_ZETA_OMEGA, abs=1e-5)
    lam = case.closed_loop_eigenvalues(*gains)
    assert lam.shape == (42,) and np.all(lam.real < 0)


def test_closed_loop_condition_number(case, gains):
    """Table 4 cond 37210.8. With φᵀEφ = 1 (plain transpose, the convention that reproduces
    Example 1) it is 37 828 as in the notes, 1.7 % off; with φᴴEφ = 1 it is the paper's value."""
    plain = case.condition_number(*gains)
    assert plain == pytest.approx(NOTES_CONDITION, abs=1)
    assert plain == pytest.approx(TABLE4_CONDITION, rel=0.03)
    assert case.condition_number(*gains, normalisation="hermitian") == pytest.approx(
        TABLE4_CONDITION, rel=1e-4
    )


def test_statespace_feedback_is_eq_59(case, gains):
    """u = −[G1 G2] y with the six collocated outputs gives the same closed loop."""
    sys = case.to_statespace()
    assert (sys.ninputs, sys.noutputs, sys.nstates) == (3, 6, 42)
    assert sys.input_labels == ["u1_hub", "u2_tips_1_3", "u3_tips_2_4"]
    assert sys.output_labels[:3] == ["theta", "rot_tips_1_3", "rot_tips_2_4"]
    open_poles = np.sort(np.abs(sys.poles().imag))[::2]
    assert open_poles == pytest.approx(case.frequencies(), abs=1e-6)
    closed = control.feedback(sys, np.hstack(gains)).poles()
    expected = case.closed_loop_eigenvalues(*gains)
    distance = np.abs(closed[:, None] - expected[None, :]).min(axis=0) / np.abs(expected)
    assert closed.shape == (42,) and distance.max() < 1e-8


def test_gains_on_the_reduced_model_differ(case, gains):
    """Notes §4.5: on the 9-mode reduced model the high modes differ (51.94, 157.19, 304.67), so
    Table 4 is the full-order verification."""
    poles = control.feedback(case.to_statespace(9), np.hstack(gains)).poles()
    assert poles.shape == (18,)
    w = np.sort(poles.imag[poles.imag > 0])
    assert w[[3, 5, 7]] == pytest.approx([51.94, 157.19, 304.67], abs=5e-3)


# -- overrides and bad input ---------------------------------------------------------------------
def test_overrides_by_name_with_units():
    c = draper_rpl(hub_inertia="16 slug*ft**2", tip_mass=0.0, n_functions=4.0)
    assert c.hub_inertia == pytest.approx(2 * draper_rpl().hub_inertia, rel=1e-15)
    assert c.tip_mass == 0.0 and c.n_functions == 4 and isinstance(c.n_functions, int)
    assert draper_rpl(length=1.2192).length == pytest.approx(draper_rpl().length, rel=1e-12)


@pytest.mark.parametrize(
    "field,value,message",
    [
        ("length", 0.0, r"^length: must be > 0"),
        ("length", "-4 ft", r"^length: must be > 0"),
        ("modulus", 0.0, r"^modulus: must be > 0"),  # EI = E h t³/12
        ("thickness", "0 in", r"^thickness: must be > 0"),
        ("height", -0.1, r"^height: must be > 0"),
        ("density", 0.0, r"^density: must be > 0"),
        ("hub_inertia", "-8 slug*ft**2", r"^hub_inertia: must be > 0"),
        ("tip_mass", "-0.1 slug", r"^tip_mass: must be >= 0"),
        ("tip_inertia", -1e-3, r"^tip_inertia: must be >= 0"),
        ("hub_radius", "-1 ft", r"^hub_radius: must be >= 0"),
        ("density", "3 kg", r"^density: incompatible units"),
        ("n_functions", 0, r"^n_functions: must be a positive integer"),
        ("n_functions", 2.5, r"^n_functions: must be a positive integer"),
        ("n_functions", True, r"^n_functions: must be a positive integer"),
    ],
)
def test_bad_input_names_the_field(field, value, message):
    with pytest.raises(ValueError, match=message):
        draper_rpl(**{field: value})


def test_unknown_override_is_refused():
    with pytest.raises(ValueError, match=r"^draper_rpl: unknown parameter\(s\) \['n_function'\]"):
        draper_rpl(n_function=20)


def test_bad_method_arguments(case, gains):
    with pytest.raises(ValueError, match=r"^g1: must be a 3x3 matrix"):
        case.closed_loop_modes(np.eye(2), gains[1])
    with pytest.raises(ValueError, match=r"^normalisation: must be 'plain' or 'hermitian'"):
        case.condition_number(*gains, normalisation="unit")
    with pytest.raises(ValueError, match=r"^n_modes: the model has 21 modes, got 22"):
        case.reduced(22)
    with pytest.raises(ValueError, match=r"^derivative: must be 0, 1 or 2"):
        comparison_functions(0.5, 3, 1.0, 3)


# -- the plant protocol (issue #10) ---------------------------------------------------------------
def test_plant_is_the_statespace_model(case):
    """StructuralPlant with the paper's three torques and six collocated outputs (Eq. 59): its
    first-order form equals to_statespace's (Cholesky against LU solves of M⁻¹K, M⁻¹B, both
    backward stable: within cond(M)·eps = 8e-9 relative to the largest entry; measured 1e-10),
    the outputs are Bᵀx and Bᵀẋ exactly, with names and units."""
    plant, sys = case.plant(), case.to_statespace()
    A, B = plant.linear_part()
    M = case.matrices()[0]
    bound = np.linalg.cond(M) * np.finfo(float).eps
    assert np.abs(A - sys.A).max() <= bound * np.abs(sys.A).max()
    assert np.abs(B - sys.B).max() <= bound * np.abs(sys.B).max()
    C = np.vstack([plant.output_matrices(c.name)[0] for c in plant.outputs[:-1]])
    np.testing.assert_array_equal(C, sys.C)
    assert [c.name for c in plant.inputs] == list(sys.input_labels)
    assert [c.name for c in plant.outputs[:-1]] == list(sys.output_labels)
    assert {c.unit for c in plant.inputs} == {"N*m"}
    assert [c.unit for c in plant.outputs[:-1]] == ["rad"] * 3 + ["rad/s"] * 3
    assert plant.modal_blocks is None  # Ritz coordinates: coupled through M


def test_reduced_plant_exposes_its_modes(case):
    """The Eq. 58 model as a plant: decoupled modes whose (ω, ζ) are the open-loop frequencies
    (rigid rotation first, undamped) and whose first-order form equals to_statespace(5) to the
    size of Φ1ᵀMΦ1 − I (the plant takes M̄ = I, K̄ = diag exactly)."""
    plant, sys = case.plant(5), case.to_statespace(5)
    blocks = plant.modal_blocks
    assert blocks.n_rigid == 1 and not blocks.damping.any()
    w = case.frequencies()[:5]
    np.testing.assert_allclose(blocks.frequencies[1:], w[1:], rtol=1e-10)
    Mbar, Kbar, _ = case.reduced(5)
    off = (
        np.abs(Mbar - np.eye(5)).max()
        + np.abs(Kbar - np.diag(np.diag(Kbar))).max() / np.abs(Kbar).max()
    )
    A, B = plant.linear_part()
    assert np.abs(A - sys.A).max() <= 10 * off * np.abs(sys.A).max()
    assert np.abs(B - sys.B).max() <= 10 * off * np.abs(sys.B).max()


def test_modal_plant_with_damping_has_the_damping_ratio(case):
    """plant(n, damping=ζ): D = 2ζΩ on the modal coordinates, so every elastic pole has damping
    ratio ζ and the undamped frequency of the undamped plant (eigenvalues of a 2×2 block:
    exact to the eigen-solver's round-off); the rigid mode stays at the origin."""
    from flexsat.dynamics.linear_model import plant_state_space

    undamped = np.linalg.eigvals(plant_state_space(case.plant(n_modes=4)).A)
    lam = np.linalg.eigvals(plant_state_space(case.plant(n_modes=4, damping=0.02)).A)
    osc = lam[lam.imag > 1e-6]
    osc = osc[np.argsort(np.abs(osc))]
    freq = np.sort(np.abs(undamped[undamped.imag > 1e-6]))
    np.testing.assert_allclose(np.abs(osc), freq, rtol=1e-9)
    np.testing.assert_allclose(-osc.real / np.abs(osc), 0.02, rtol=1e-9)
    assert np.sum(np.abs(lam) < 1e-9) == 2


def test_damping_is_checked(case):
    with pytest.raises(ValueError, match="^damping: must be in \\[0, 1\\)"):
        case.plant(n_modes=3, damping=1.5)
    with pytest.raises(ValueError, match="^damping: modal damping needs a modal model"):
        case.plant(damping=0.01)
