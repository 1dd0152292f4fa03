"""Bainum's beam in orbit on the plant protocol (issue #10): the case builds a BeamInOrbit
(nonlinear, eqs 1-2) and a StructuralPlant (linear, eqs 5-6), both in seconds, and its
simulation (Ch. II/III responses) runs on the plant's right-hand side."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from flexsat.cases.bainum import (
    PUBLISHED,
    bainum,
    mode_shape,
    published_matrix,
)

EPS = np.finfo(float).eps
POSITIONS = PUBLISHED["ch3_case1_positions"]  # -l/2, +l/2, +l/4


def _to_seconds(A_tau, B_tau, wc):
    """x_s = T x_τ with T = diag(I, ω_c I) and d/dt = ω_c d/dτ: A_s = ω_c T A_τ T⁻¹,
    B_s = ω_c T B_τ."""
    n = A_tau.shape[0] // 2
    T = np.diag(np.concatenate([np.ones(n), wc * np.ones(n)]))
    return wc * T @ A_tau @ np.linalg.inv(T), wc * T @ B_tau


def test_plant_linear_part_is_linear_model_in_seconds():
    """BeamInOrbit.linear_part and the StructuralPlant of eqs 5-6 both equal the case's
    linear_model (eq 16, τ) converted to seconds, to a few eps of each entry (one product by
    ω_c² against ω_c·ω_c, 2 roundings)."""
    beam = bainum()
    wc = beam.orbit_rate_value
    A_ref, B_ref = _to_seconds(*beam.linear_model(POSITIONS, 2), wc)
    for plant in (beam.plant(POSITIONS, 2), beam.linear_plant(POSITIONS, 2)):
        A, B = plant.linear_part()
        np.testing.assert_allclose(A, A_ref, rtol=4 * EPS, atol=0)
        np.testing.assert_allclose(B, B_ref, rtol=4 * EPS, atol=0)
    lin = beam.linear_plant(POSITIONS, 2)
    blocks = lin.modal_blocks
    np.testing.assert_allclose(
        blocks.frequencies, wc * np.sqrt([3.0, 3200.0, 28800.0]), rtol=2 * EPS
    )
    assert blocks.n_rigid == 0 and not blocks.damping.any()
    assert [c.name for c in lin.inputs] == ["f1", "f2", "f3"]
    assert [c.name for c in lin.outputs][:4] == ["pitch", "z1", "z2", "w_left"]


def test_plant_channels_and_stations():
    """Force channels f_j (N) at the case's positions: the columns of actuator_matrix; the
    station outputs are the Appendix A shapes (w/l; metres given a length)."""
    beam = bainum()
    plant = beam.plant(POSITIONS, 2, length=100.0)
    np.testing.assert_array_equal(plant.G, beam.actuator_matrix(POSITIONS, 2))
    assert [(c.name, c.unit) for c in plant.inputs] == [("f1", "N"), ("f2", "N"), ("f3", "N")]
    C = plant.output_matrices("w_middle")[0]
    np.testing.assert_allclose(
        C[0, 1:3], 100.0 * np.array([mode_shape(1, 0.0), mode_shape(2, 0.0)]), rtol=1e-15
    )
    plant = beam.plant(POSITIONS, 2, stations={"quarter": 0.25})
    assert [c.name for c in plant.outputs][-2:] == ["w_quarter", "state"]
    with pytest.raises(ValueError, match=r"^stations\['tip'\]: actuator positions are"):
        beam.plant(POSITIONS, 2, stations={"tip": 0.7})


def test_case_simulation_is_the_plant_trajectory():
    """Ch. III Case 1 layout (printed K, exact-shape G) over τ = 0.0401: the case's simulate
    (τ, DOP853 rtol 1e-10) equals solve_ivp on the public plant's derivative in seconds (rtol
    1e-11) at the same instants, to the integrators' tolerance (1e-8 of each state's peak)."""
    beam = bainum()
    plant = beam.plant(POSITIONS, 2)
    G = beam.actuator_matrix(POSITIONS, 2)
    K = published_matrix("ch3_case1_K")
    res = beam.simulate(G, None, K, [0.01] * 3, 0.0401, n_points=41)
    wc = plant.orbit_rate
    gain_s = np.hstack([np.zeros((3, 3)), K / wc])  # f = K x' = K ẋ/ω_c
    sol = solve_ivp(
        lambda t, x: plant.derivative(x, gain_s @ x),
        (0, res.tau[-1] / wc),
        np.concatenate([[0.01] * 3, np.zeros(3)]),
        method="DOP853",
        rtol=1e-11,
        atol=1e-16,
        t_eval=res.tau / wc,
    )
    states_tau = sol.y.T.copy()
    states_tau[:, 3:] /= wc
    peak = np.abs(res.states).max(axis=0)
    assert np.all(np.abs(states_tau - res.states).max(axis=0) <= 1e-8 * peak)


def test_three_mass_plant_gives_the_checked_numbers():
    """Ch. IV (L1063-L1101): the three-mass model as a StructuralPlant (M = [[a, b], [b, a]],
    K = cI) has v'' = -A_r v + B_r F of eq 4 (Cholesky against the closed-form inverse: a few
    eps), λ1, λ2 of eqs 7-8 as eig(K, M) and, under the coupled rate feedback of eq 13, the
    roots of eq 16 (eigenvalues against np.roots of the quartic: 1e-12 relative, the roots are
    simple and well separated). flexsat validate's Bainum rows are computed this way."""
    from flexsat.cases.bainum_three_mass import three_mass

    t = three_mass()
    plant = t.plant(2)
    A, B = plant.linear_part()
    A_r, B_r = t.reduced_pair(2)
    np.testing.assert_allclose(A[2:, :2], -A_r, rtol=8 * EPS)
    np.testing.assert_allclose(B[2:], B_r, rtol=8 * EPS)
    assert [c.name for c in plant.inputs] == ["F_v1", "F_v2"]
    assert [(c.name, c.unit) for c in plant.outputs][2] == ("v1_dot", "m/s")
    np.testing.assert_allclose(t.plant_lambdas(), t.lambdas, rtol=1e-14)
    eig = np.sort_complex(np.linalg.eigvals(t.coupled_rate_closed_loop(0.4728, 0.4)))
    np.testing.assert_allclose(eig, t.coupled_rate_poles(0.4728, 0.4), rtol=1e-12)
    with pytest.raises(ValueError, match=r"^n_actuators: must be 1 or 2"):
        t.plant(3)
