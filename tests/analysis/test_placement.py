"""Placement measures (Hamdan–Nayfeh, modal cost, Kim–Junkins α, Gawronski, seed 003 H2
ranking) and the searches on them (TAMU grid); the searches alone: test_placement_search.py."""

import math

import numpy as np
import pytest
import scipy.linalg as sla

from flexsat.analysis.gramians import lyapunov_gramian, modal_state_matrices
from flexsat.analysis.placement import (
    actuator_candidates,
    exchange,
    exhaustive,
    gawronski_index,
    greedy,
    h2_actuator_ranking,
    h2_placement,
    hamdan_nayfeh,
    kim_junkins_index,
    kim_junkins_score,
    modal_controllability,
    modal_cost,
)
from flexsat.cases.eps_placement import eps_h2_setup

# ------------------------------------------------------------------------------------------------
# the 2-DOF textbook system: M = I, K = [[2, -1], [-1, 2]], force on mass 1, output x1
S2 = 1 / np.sqrt(2)
W2 = np.array([1.0, np.sqrt(3.0)])  # ω of modes (1, 1)/√2 and (1, −1)/√2
Z2 = np.array([0.02, 0.02])
D2 = np.array([[S2], [S2]])  # Φᵀ e1
C2 = np.array([[S2, S2]])  # x1 = (η1 + η2)/√2


def test_hamdan_nayfeh_two_mode_by_hand():
    mc = modal_controllability(W2, Z2, D2)
    # ρ_i = |D̄_i| / sqrt(1 + ω_i²): 1/2 and 1/(2√2); ||b|| = 1
    assert np.allclose(mc.rho, [0.5, 1 / (2 * np.sqrt(2))], rtol=1e-14)
    assert np.allclose(mc.cos_theta[:, 0], [0.5, 1 / (2 * np.sqrt(2))], rtol=1e-14)
    so = modal_controllability(W2, Z2, D2, form="second_order")
    assert np.allclose(so.rho, [S2, S2]) and np.allclose(so.cos_theta[:, 0], [S2, S2])


def test_hamdan_nayfeh_general_equals_closed_form_and_orthogonal_invariance():
    """The physical state (x, ẋ) = blockdiag(Φ, Φ)(η, η̇) is an orthogonal change (M = I), so
    the measures computed from the physical A, B by eigen-decomposition are the modal ones."""
    Phi = np.array([[S2, S2], [S2, -S2]])
    K = np.array([[2.0, -1.0], [-1.0, 2.0]])
    C = Phi @ np.diag(2 * Z2 * W2) @ Phi.T
    A = np.block([[np.zeros((2, 2)), np.eye(2)], [-K, -C]])
    B = np.array([[0.0], [0.0], [1.0], [0.0]])
    hn = hamdan_nayfeh(A, B)
    assert np.allclose(hn.rho, np.repeat(modal_controllability(W2, Z2, D2).rho, 2), rtol=1e-12)
    assert np.allclose(np.abs(hn.eigenvalues.imag), np.repeat(W2 * np.sqrt(1 - Z2**2), 2))
    # a non-orthogonal scaling changes them (Att. 4: use them only after all scaling)
    T = np.diag([1.0, 1.0, 10.0, 10.0])
    scaled = hamdan_nayfeh(T @ A @ np.linalg.inv(T), T @ B)
    assert not np.allclose(scaled.rho, hn.rho, rtol=1e-3)


def test_rigid_mode_controllability():
    mc = modal_controllability([0.0, 2.0], [0.0, 0.01], [[3.0, 4.0], [1.0, 0.0]])
    assert mc.rho[0] == pytest.approx(5.0) and mc.rho[1] == pytest.approx(1 / np.sqrt(5))


def test_modal_cost_two_mode_by_hand():
    mc = modal_cost(W2, Z2, D2, Cq=C2)
    # Att. 4 Eq. 25 (corrected) by hand, W = D̄D̄ᵀ = ½ ones
    x11 = 0.5 / (4 * Z2[0] * W2[0] ** 3)
    x22 = 0.5 / (4 * Z2[1] * W2[1] ** 3)
    s = Z2[0] * W2[0] + Z2[1] * W2[1]
    delta = (W2[0] ** 2 - W2[1] ** 2) ** 2 + 4 * W2[0] * W2[1] * s * (Z2[0] * W2[1] + Z2[1] * W2[0])
    x12 = 2 * s * 0.5 / delta
    V1, V2 = 0.5 * (x11 + x12), 0.5 * (x12 + x22)  # Eq. 27 with Cᵀ C = ½ ones
    assert np.allclose(mc.costs, [V1, V2], rtol=1e-13)
    assert np.allclose(mc.velocity, 0.0)
    assert mc.total == pytest.approx(V1 + V2, rel=1e-13)
    assert np.allclose([V1, V2, V1 + V2], [3.131795, 0.608202, 3.739997], rtol=1e-6)  # by hand
    # Eq. 5 V = ∫ y² dt of the impulse response, through the dual (observability) Gramian
    A, Bz, Cz = modal_state_matrices(W2, Z2, D2, C2)
    Y = lyapunov_gramian(A, Cz, "observability")
    assert mc.total == pytest.approx((Bz.T @ Y @ Bz).item(), rel=1e-10)


def test_kim_junkins_two_mode_by_hand():
    kj = kim_junkins_index(W2, Z2, D2, Cq=C2)
    V = np.array([3.131795, 0.608202])
    alpha = (V[0] * 0.25 + V[1] * 0.125) / V.sum()
    assert kj.alpha == pytest.approx(alpha, rel=1e-6)
    assert kj.alpha == pytest.approx(0.229672, rel=1e-5)
    assert kj.contributions.sum() == pytest.approx(kj.alpha)


def test_kim_junkins_units_and_sign():
    """ρ² carries the units of D̄²: α scales with c² when the inputs are scaled by c; the sign
    of an actuator column (torque direction) does not matter."""
    rng = np.random.default_rng(0)
    w, z = np.array([1.0, 2.5, 6.0]), 0.01
    B, C = rng.normal(size=(3, 2)), rng.normal(size=(1, 3))
    a = kim_junkins_index(w, z, B, C).alpha
    assert kim_junkins_index(w, z, 0.3 * B, C).alpha == pytest.approx(0.09 * a, rel=1e-12)
    assert kim_junkins_index(w, z, B * [1, -1], C).alpha == pytest.approx(a, rel=1e-12)
    # output weight scale cancels in V_i/V
    assert kim_junkins_index(w, z, B, C, Q=7.0).alpha == pytest.approx(a, rel=1e-12)


def test_modal_cost_finite_horizon_allows_rigid_modes():
    w, z = np.array([0.0, 1.0, 3.0]), np.array([0.0, 0.01, 0.01])
    B, C = np.array([[1.0], [0.5], [0.2]]), np.array([[1.0, 1.0, 1.0]])
    with pytest.raises(ValueError, match="rigid-body"):
        modal_cost(w, z, B, C)
    mc = modal_cost(w, z, B, C, horizon=5.0)
    assert mc.total == pytest.approx(mc.costs.sum()) and mc.costs[0] > 0
    # the rigid mode alone: y = t for a unit impulse, V = T³/3
    assert modal_cost([0.0], [0.0], [1.0], [[1.0]], horizon=5.0).total == pytest.approx(125 / 3)
    assert kim_junkins_index(w, z, B, C, horizon=5.0).alpha > 0


# ------------------------------------------------------------------------------------------------
# Gawronski
def test_gawronski_index():
    rng = np.random.default_rng(5)
    w, z = np.array([1.0, 4.0, 11.0]), np.array([0.01, 0.02, 0.005])
    B, Cq, Cv = rng.normal(size=(3, 4)), rng.normal(size=(2, 3)), rng.normal(size=(2, 3))
    g = gawronski_index(w, z, B, Cq, Cv)
    assert g.sigma.shape == (3, 4)
    assert np.sum(g.sigma**2) == pytest.approx(1.0, rel=1e-12)
    assert np.allclose(g.actuator, np.sqrt(np.sum(g.sigma**2, axis=0)))
    # σ_ki ∝ |D̄_ik| within a mode; exact single-mode single-actuator H2 norm
    A, Bz, C = modal_state_matrices(w[:1], z[:1], B[:1, :1], Cq[:, :1], Cv[:, :1])
    h2 = np.sqrt(np.trace(C @ lyapunov_gramian(A, Bz) @ C.T))
    total = np.sqrt(
        np.sum(
            (
                np.linalg.norm(B, axis=1)
                * np.sqrt(np.sum(Cq**2, 0) / w**2 + np.sum(Cv**2, 0))
                / (2 * np.sqrt(z * w))
            )
            ** 2
        )
    )
    assert g.sigma[0, 0] == pytest.approx(h2 / total, rel=1e-10)
    hk = gawronski_index(w, z, B, Cq, Cv, norm="hankel")
    assert hk.mode.max() == pytest.approx(1.0) and hk.norm == "hankel"
    weighted = gawronski_index(w, z, B, Cq, Cv, weights=[1.0, 2.0, 1.0, 1.0])
    assert np.allclose(weighted.sigma[:, 1], 2 * g.sigma[:, 1])
    with pytest.raises(ValueError, match="norm"):
        gawronski_index(w, z, B, Cq, norm="hinf")
    with pytest.raises(ValueError, match="weights"):
        gawronski_index(w, z, B, Cq, weights=[1.0, 2.0])


# ------------------------------------------------------------------------------------------------
# seed 003 H2 placement
@pytest.fixture
def h2_system():
    rng = np.random.default_rng(7)
    w, z = np.array([0.8, 2.0, 4.5]), 0.01
    A, B, C = modal_state_matrices(w, z, rng.normal(size=(3, 4)), rng.normal(size=(2, 3)))
    _, b, _ = modal_state_matrices(w, z, rng.normal(size=(3, 2)))
    return A, B, b, C


def test_h2_identities(h2_system):
    A, B, b, C = h2_system
    r = h2_placement(A, B, b, C, gamma=3.0)
    # Eq. 4 residual, Eq. 5 [RECON]: β² = γ²||y||² + ||u||²
    res = A.T @ r.X + r.X @ A - r.X @ B @ B.T @ r.X + 9.0 * C.T @ C
    assert np.linalg.norm(res) < 1e-9 * np.linalg.norm(r.X)
    assert r.beta2 == pytest.approx(9.0 * r.y_norm2 + r.u_norm2, rel=1e-9)
    assert r.energy.sum() == pytest.approx(r.u_norm2, rel=1e-10)
    # Eq. 8 as printed = control energy of an impulse entering through actuator i
    Acl = A + B @ r.F
    for i in range(B.shape[1]):
        Wi = sla.solve_continuous_lyapunov(Acl, -np.outer(B[:, i], B[:, i]))
        assert r.printed[i] == pytest.approx(np.trace(r.F @ Wi @ r.F.T), rel=1e-8)


def test_h2_refuses_unstabilisable_rigid_mode():
    A, B, C = modal_state_matrices([0.0, 2.0], [0.0, 0.01], [[0.0], [1.0]], Cq=[[1.0, 1.0]])
    with pytest.raises(ValueError, match="stabilis"):
        h2_placement(A, B, B, C)
    with pytest.raises(ValueError, match="gamma"):
        h2_placement(A, B, B, C, gamma=0.0)
    with pytest.raises(ValueError, match="b: must have 4 rows"):
        h2_placement(A, B, np.ones((3, 1)), C)


@pytest.fixture(scope="module")
def eps_setup():
    """A model and candidates of realistic size: the seed 003 EPS set-up."""
    return eps_h2_setup(n_modes=10)


def test_h2_ranking_bad_inputs(eps_setup):
    model, act, dist, out = eps_setup
    with pytest.raises(ValueError, match="rigid"):
        h2_actuator_ranking(model, act, dist, out, rigid="finite")
    with pytest.raises(ValueError, match="measure"):
        h2_actuator_ranking(model, act, dist, out, measure="power")
    with pytest.raises(ValueError, match="actuators"):
        h2_actuator_ranking(model, {}, dist, out)
    with pytest.raises(ValueError, match=r"actuators\['x'\]"):
        h2_actuator_ranking(model, {"x": np.ones(3)}, dist, out)


# ------------------------------------------------------------------------------------------------
# TAMU grid: Kim–Junkins index and the searches
@pytest.fixture(scope="module")
def tamu():
    from flexsat.cases import tamu_grid

    model = tamu_grid().modal_model(10, damping=0.005)
    cands = actuator_candidates(model, range(1, 21), ("x", "y"), kind="torque")
    Cq = model.displacement_output(1, "z")[None, :]  # Att. 4: lower-left corner, normal
    return model, cands, Cq


def test_tamu_kim_junkins_symmetric_configurations(tamu):
    model, cands, Cq = tamu
    score = kim_junkins_score(model, cands, Cq)
    att6 = score(("3RY", "7RX", "9RX"))  # motor layout of Att. 6 (Fig. 1 = configuration 6?)
    assert 0 < att6 < 1
    # near the clamp the grid barely moves: the top row scores far below the bottom row
    assert score(("16RX", "18RX", "20RX")) < 0.5 * score(("1RX", "3RX", "5RX"))
    # a mirror image scores almost alike: only the cross terms of symmetric and antisymmetric
    # modes in V_i differ, because the output (node 1) is not on the axis of symmetry
    assert score(("1RX",)) == pytest.approx(score(("5RX",)), rel=1e-3)


def test_tamu_greedy_and_exchange_match_exhaustive(tamu):
    model, cands, Cq = tamu
    sub = [k for k in cands if int(k[:-2]) <= 10]  # the two lower rows: 20 candidates
    score = kim_junkins_score(model, cands, Cq)
    ex = exhaustive(sub, 3, score)
    gr, xc = greedy(sub, 3, score), exchange(sub, 3, score)
    assert ex.evaluations == math.comb(20, 3)
    assert gr.selection == xc.selection == ex.selection == ("2RX", "3RX", "4RX")
    assert gr.evaluations < 0.1 * ex.evaluations


def test_force_and_torque_candidates_at_one_node_are_both_kept_and_told_apart(tamu):
    """A force along x and a torque about x at node 3 are two candidates (before, both were
    "3X" and the second replaced the first without a word)."""
    model = tamu[0]
    both = actuator_candidates(model, (3, 7), ("x", "y"), kind=("force", "torque"))
    assert len(both) == 8 and {"3X", "3RX", "7Y", "7RY"} <= set(both)
    np.testing.assert_array_equal(both["3X"], model.force_input(3, "x"))
    np.testing.assert_array_equal(both["3RX"], model.torque_input(3, "x"))
    assert not np.allclose(both["3X"], both["3RX"])
    forces = actuator_candidates(model, (3,), ("x",))
    torques = actuator_candidates(model, (3,), ("x",), kind="torque")
    assert set(forces).isdisjoint(torques)  # sets built apart merge without loss too
    with pytest.raises(ValueError, match=r"^label: the force 3x and the torque 3x are both "):
        actuator_candidates(
            model, (3,), ("x",), ("force", "torque"), label=lambda k, n, a: f"{n}{a}"
        )
    with pytest.raises(ValueError, match=r"^kind: must be 'force', 'torque' or both"):
        actuator_candidates(model, (3,), ("x",), kind=("force", "force"))
