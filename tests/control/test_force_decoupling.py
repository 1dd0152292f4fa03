"""Force/torque decoupling of the EPS point forces (seed 003 Eqs. 32-37, F12): the
moment-free parametrisation is Eq. 35's corrected R̂⁻¹ = M_W, the paper's printed R̂ does
not enforce the constraint, the full-coordinate Riccati equation has no stabilising
solution, and the decoupled commands exert no net moment."""

import numpy as np
import pytest
import scipy.linalg

from flexsat.control import lqr
from flexsat.control.force_decoupling import decoupled_input_map, moment_free_forces
from flexsat.control.frequency_shaped import augment, shaping_weights
from flexsat.control.perturbation_feedback import perturbation_design

EPS = np.finfo(float).eps
OMEGA_B = 2.5  # rad/s, case A
# D on [J⁻¹δτ (3), δF (7)]: 50 on the normalized torques (case A), a small weight on the
# forces so that newtons are affordable against them (notes §3.2 [AMBIG] case B)
D = np.diag([50.0] * 3 + [1e-4] * 7)


@pytest.fixture(scope="module")
def design(eps_design_plant, eigenaxis_slew):
    nominal = eigenaxis_slew(eps_design_plant.inertia, [1.0, 1.0, 1.0], 1.0, 10.0)
    Q = np.r_[[1000.0] * 6, [1.0] * 20]
    return perturbation_design(
        eps_design_plant, nominal, Q, D, OMEGA_B, n_points=3, forces="all", decouple=True
    )


def full_W(design):
    """W of Eq. 32 over δu₁ = [J⁻¹δτ, δF]: zero on the torquers, G on the forces."""
    G = design.linearization.force_moments
    return np.hstack([np.zeros((3, 3)), G])


def test_the_moment_matrix_is_the_plants_moment_arms(design, eps_design_plant):
    # W = Σ r̃_i S_i: (r_i − c) × e_i for the final 7 forces (69X, 63X, 66Y, 66Z, 60Y, 60Z,
    # 88X), moment arms of metres on a 25 m truss with 15 m and 7.5 m antennas
    G = design.linearization.force_moments
    assert G.shape == (3, 7) and np.linalg.matrix_rank(G) == 3
    np.testing.assert_array_equal(G, eps_design_plant.force_moments)
    Z = moment_free_forces(G)
    assert Z.shape == (7, 4)
    np.testing.assert_allclose(Z.T @ Z, np.eye(4), rtol=0, atol=10 * EPS)
    assert np.abs(G @ Z).max() <= 10 * EPS * np.abs(G).max()


def test_m_w_is_the_null_space_form_and_the_printed_r_hat_is_not(design):
    # notes §2.8 [VERIFIED]: M_W = R⁻¹ − R⁻¹Wᵀ(WR⁻¹Wᵀ)⁻¹WR⁻¹ = Z(ZᵀRZ)⁻¹Zᵀ and W M_W = 0, to
    # round-off (measured 3e-16 and 2e-16 relative; allowed 1e-12, R's diagonal weights
    # being exact the condition cond(R) = 5e5 does not enter the null-space form); the printed
    # R̂ = R + ½Wᵀ(WR⁻¹Wᵀ)⁻¹W of Eq. 35 has W R̂⁻¹ ≠ 0 (notes: 24.7 on their data; measured
    # max |W R̂⁻¹| = 4.0e6, 0.67 of |W| |R̂⁻¹|), so it does not enforce the constraint
    R = D / OMEGA_B**4
    W = full_W(design)
    Ri = np.linalg.inv(R)
    M_W = Ri - Ri @ W.T @ np.linalg.solve(W @ Ri @ W.T, W @ Ri)
    S = decoupled_input_map(design.linearization.force_moments)
    null_form = S @ np.linalg.solve(S.T @ R @ S, S.T)
    assert np.abs(M_W - null_form).max() <= 1e-12 * np.abs(M_W).max()
    assert np.abs(W @ M_W).max() <= 1e-12 * np.abs(W).max() * np.abs(M_W).max()
    R_hat = R + 0.5 * W.T @ np.linalg.solve(W @ Ri @ W.T, W)
    printed = np.abs(W @ np.linalg.inv(R_hat)).max()
    assert printed > 0.1 * np.abs(W).max() * np.abs(np.linalg.inv(R_hat)).max()
    assert np.abs(np.linalg.inv(R_hat) - M_W).max() > 0.1 * np.abs(M_W).max()


def test_the_full_coordinate_riccati_equation_has_no_stabilising_solution(design):
    # Eq. 35 in the full augmented coordinates [δX, δu₁, δu₂] (all 10 inputs): with
    # R̂⁻¹ = M_W it is the LQR of (Â, B̂S, Q̂, SᵀR S, N S), and Wδu₁, Wδu₂ are integrators that
    # no admissible δu₃ reaches: eigenvalue 0, uncontrollable, so no stabilising solution:
    # the flexsat solver refuses it by name and scipy's finds none (measured:
    # LinAlgError "Failed to find a finite solution")
    i = 1
    A, B = design.A[i], design.B[i]
    S = design.input_map
    Qa, Na, Ra = shaping_weights(design.Q, D, OMEGA_B)
    Aa, Ba = augment(A, B)
    with pytest.raises(ValueError, match=r"not stabilizable: eigenvalue\(s\) 0"):
        lqr(Aa, Ba @ S, Qa, S.T @ Ra @ S, Na @ S)
    try:
        P = scipy.linalg.solve_continuous_are(Aa, Ba @ S, Qa, S.T @ Ra @ S, s=Na @ S)
    except (np.linalg.LinAlgError, ValueError):
        return
    K = np.linalg.solve(S.T @ Ra @ S, (Ba @ S).T @ P + (Na @ S).T)
    assert np.linalg.eigvals(Aa - Ba @ S @ K).real.max() >= -1e-8


def test_the_reduced_design_is_eq37_on_the_admissible_set(design):
    # Designed on v (δu = S v before augmenting), the law in physical coordinates is
    # δu₃ = −S K_v [δX; S⁺δu₁; S⁺δu₂]; Eq. 37 gives −M_W(B̂ᵀP + Nᵀ)δX with P = TᵀP_vT,
    # T = blockdiag(I, S⁺, S⁺) (S⁺ the left inverse: S = [I, 0; 0, Z] L⁻ᵀ is scaled to unit
    # weights). On admissible states (δu_k = S v_k) they agree to round-off
    # (measured 2.5e-16 of the gain; allowed 1e-12)
    i = 2
    sol = design.designs[i]
    S = design.input_map
    N = design.linearization.n_states
    m, mv = S.shape
    Sp = np.linalg.pinv(S)
    T = scipy.linalg.block_diag(np.eye(N), Sp, Sp)
    P = T.T @ sol.solution.solution @ T
    R = D / OMEGA_B**4
    Ri = np.linalg.inv(R)
    W = full_W(design)
    M_W = Ri - Ri @ W.T @ np.linalg.solve(W @ Ri @ W.T, W @ Ri)
    _, Na, _ = shaping_weights(design.Q, D, OMEGA_B)
    _, Ba = augment(design.A[i], design.B[i])
    K_eq37 = M_W @ (Ba.T @ P + Na.T)
    admissible = scipy.linalg.block_diag(np.eye(N), S, S)  # [δX; v1; v2] -> [δX; δu1; δu2]
    K_reduced = S @ sol.gain  # acts on [δX; v1; v2]
    assert np.abs(K_eq37 @ admissible - K_reduced).max() <= 1e-12 * np.abs(K_reduced).max()


def test_the_decoupled_commands_exert_no_net_moment(design):
    # δF = Z v: W u = 0 for any law state, to 1e-12 relative (issue acceptance); measured
    # ~1e-16. The gains, the feedforward and so every command lie in range(S).
    W = full_W(design)
    S = design.input_map
    rng = np.random.default_rng(0)
    v = rng.standard_normal((100, S.shape[1]))
    u = v @ S.T
    assert np.abs(u @ W.T).max() <= 1e-12 * np.abs(W).max() * np.abs(u).max()
    assert (
        np.abs(W @ S @ design.gains[1]).max()
        <= 1e-12 * np.abs(W).max() * np.abs(design.gains[1]).max()
    )


def test_forces_without_a_moment_free_combination_are_refused():
    G = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 2.0], [3.0, 0.0, 0.0]])
    with pytest.raises(ValueError, match="moments: the 3 forces have no combination with zero"):
        moment_free_forces(G)
    with pytest.raises(ValueError, match=r"moments: must have shape \(3, n_F\)"):
        moment_free_forces(np.ones((2, 4)))
