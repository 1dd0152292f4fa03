"""Modal 2×2-block propagation (flexsat.sim.integrators.ModalPropagator) is the exact
zero-order-hold step: it equals the matrix exponential of the full system.

Reference: scipy.linalg.expm of Van Loan's block matrix (:func:`phi_products`), whose own
relative error is ~ ‖hA‖ · eps: for ωh <= 13 (ω <= 1000 rad/s at 75 Hz) it stays below 3e-14
(checked against 50-digit arithmetic when the closed forms were written), so 1e-12 relative
leaves a margin of 30 on both sides.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import block_diag

from flexsat.cases.tamu import tamu
from flexsat.sim.integrators import (
    ExponentialStepper,
    ExpRK4Stepper,
    ModalPropagator,
    block_propagators,
    modal_coordinates,
    phi_products,
)
from flexsat.sim.kernels import Loop, Records, allocate_records, closed_loop

H = 1 / 75  # the TAMU control period


def rel(a, b):
    return np.abs(a - b).max() / np.abs(b).max()


# underdamped, critically damped (exactly and within 1e-9), overdamped; ω = 0 is rigid
BLOCKS = [(0.0, 0.0)] + [
    (w, z)
    for w in (1e-3, 0.3, 8.0, 75.0, 1000.0)
    for z in (0.0, 0.005, 0.5, 1.0, 1 + 1e-9, 1.001, 3.0, 50.0)
]


@pytest.mark.parametrize(("omega", "zeta"), BLOCKS)
def test_block_exponential_and_input_integrals_equal_expm(omega, zeta):
    A = np.array([[0.0, 1.0], [-(omega**2), -2 * zeta * omega]])
    E, P1, P2 = block_propagators([omega], [zeta], H)
    E_ref, P1_ref, P2_ref = phi_products(A, H, np.eye(2), 2)
    assert rel(E[0], E_ref) < 1e-12
    assert rel(P1[0], P1_ref) < 1e-12
    assert rel(P2[0], P2_ref) < 1e-12


def test_modal_plant_step_equals_full_exponential_with_force():
    rng = np.random.default_rng(0)
    omega = np.array([0.0, 0.5, 3.0, 40.0, 400.0])
    zeta = np.array([0.0, 0.01, 1.0, 0.2, 2.0])
    n = 2 * omega.size
    A = np.zeros((n, n))
    for i, (w, z) in enumerate(zip(omega, zeta)):
        A[2 * i : 2 * i + 2, 2 * i : 2 * i + 2] = [[0, 1], [-w * w, -2 * z * w]]
    B, Bf = rng.normal(size=(n, 1)), rng.normal(size=(n, 1))
    modal = ModalPropagator.build(omega, zeta, B, H, substeps=3, Bf=Bf)
    dense = ExponentialStepper.build(A, B[:, 0], Bf, H, substeps=3)
    x, w = rng.normal(size=(4, n)), rng.normal(size=(4, 1))

    def force(x, w):
        return -0.3 * np.tanh(x[:, 1:2] / 0.01)

    assert rel(modal.step(x, w), dense.step(x, w[:, 0])) < 1e-12
    assert rel(modal.step(x, w, force), dense.step(x, w[:, 0], force)) < 1e-12


def test_a_force_given_to_a_propagator_built_without_force_columns_is_refused():
    """Built without ``Bf`` the modal propagator has no φ-products for a force: a force given
    to its step is refused by name (it raised AttributeError on None before), as by
    :class:`ExponentialStepper`."""
    linear = ModalPropagator.build([0.0, 2.0], [0.0, 0.1], np.ones((4, 1)), H)
    dense = ExponentialStepper.build(np.zeros((4, 4)), np.ones(4), None, H)
    x, w = np.zeros((1, 4)), np.zeros((1, 1))

    def force(x, w):
        return np.zeros((x.shape[0], 1))

    for stepper in (linear, dense):
        with pytest.raises(ValueError, match=r"^force: this \w+ was built without force columns"):
            stepper.step(x, w[:, 0] if stepper is dense else w, force)
    # and the other way round: Krogstad's scheme is built for a force and needs one
    rk4 = ExpRK4Stepper.build(np.zeros((4, 4)), np.ones(4), np.ones((4, 1)), H)
    with pytest.raises(ValueError, match=r"^force: exp_rk4 needs the plant's nonlinear force"):
        rk4.step(x, w[:, 0], None)


@pytest.mark.parametrize("n_modes", [6, 100])
def test_hub_appendage_in_modal_coordinates_equals_full_expm(n_modes):
    # the coupled hub + appendage plant: damping diagonal in cantilever coordinates, so its
    # free-free modes are complex; the real companion-block form still makes A block-diagonal.
    # 100 modes per appendage puts ω_max h near 4000 and ‖A‖ near 1e11: the low modes must not
    # inherit eps ‖A‖ errors from the eigen-solvers (unrefined, they were off by 1e-10).
    plant = tamu(n_modes=n_modes).model()
    A, Bu, _ = plant.state_space
    M, K = plant.mass_matrix, plant.stiffness_matrix
    T, Tinv, omega, zeta = modal_coordinates(M, K, plant.damping_matrix)
    assert omega[0] == 0 and np.all(np.diff(omega) > 0)  # one rigid block, then ascending
    # with light damping the blocks' undamped frequencies are the hub-free ones to O(ζ²)
    np.testing.assert_allclose(omega[1:], plant.frequencies(), rtol=1e-3)
    E2, P12, _ = block_propagators(omega, zeta, H)
    Phi_modal = T @ block_diag(*E2) @ Tinv
    Gam_modal = T @ block_diag(*P12) @ (Tinv @ Bu)
    # reference: expm of the balanced matrix (positions scaled by the cantilever frequencies),
    # ‖hÃ‖ ~ ω_max h, so accurate to ~ ω_max h eps <= 1e-13 per block of Φ
    n = plant.ndof
    d = np.r_[np.sqrt(np.r_[1.0, np.diag(K)[1:] / plant.n_appendages]), np.ones(n)]
    Ab = (A * d[:, None]) / d[None, :]
    Eb, Gb, _ = phi_products(Ab, H, (d * Bu)[:, None])
    Phi_ref, Gam_ref = Eb / d[:, None] * d[None, :], Gb[:, 0] / d
    for rows in (slice(0, n), slice(n, None)):
        for cols in (slice(0, n), slice(n, None)):
            assert rel(Phi_modal[rows, cols], Phi_ref[rows, cols]) < 1e-11
        assert rel(Gam_modal[rows], Gam_ref[rows]) < 1e-11
    prop = ModalPropagator.build(omega, zeta, Tinv @ Bu, H)
    rng = np.random.default_rng(1)
    x, w = rng.normal(size=(3, A.shape[0])), rng.normal(size=(3, 1))
    np.testing.assert_allclose(
        prop.step(x @ Tinv.T, w) @ T.T,
        x @ Phi_modal.T + w @ Gam_modal[None],
        rtol=1e-12,
        atol=1e-12 * np.abs(x @ Phi_modal.T).max(),
    )


def test_kernel_in_modal_coordinates_equals_kernel_in_physical_coordinates():
    plant = tamu(n_modes=3).model()
    A, Bu, Bf = plant.state_space
    n, ndof = A.shape[0], plant.ndof
    T, Tinv, omega, zeta = modal_coordinates(
        plant.mass_matrix, plant.stiffness_matrix, plant.damping_matrix
    )
    n_t, substeps = 200, 2
    rate = np.zeros(n)
    rate[ndof] = 1.0
    dense = ExponentialStepper.build(A, Bu, Bf[:, :1], H, substeps)
    modal = ModalPropagator.build(omega, zeta, Tinv @ Bu, H, substeps, Bf=Tinv @ Bf[:, :1])
    Cm = np.zeros((1, 2, n))
    Cm[0, 0, 0] = Cm[0, 1, ndof] = 1.0
    common = dict(
        fric=np.array([[0.1, 0.001, 1e-3]]),
        substeps=substeps,
        imp_k=np.zeros(0, np.int64),
        imp_dx=np.zeros((0, 1, n)),
        Dm=np.zeros((1, 2, 1)),
        Dmf=np.zeros((1, 2)),
        sensor=np.tile([0.0, 0.0, 0.0, np.inf], (1, 2, 1)),
        sensor_slot=np.array([-1, -1]),
        fir_src=-1,
        fir_dst=0,
        fir_w=np.zeros(0),
        Ak=np.zeros((1, 1, 0, 0)),
        Bk=np.zeros((1, 1, 0, 2)),
        Ck=np.zeros((1, 1, 1, 0)),
        Dk=np.array([[[[-20.0, -8.0]]]]),
        y_ref=np.tile([0.7, 0.0], (n_t, 1, 1)),
        u_ff=np.zeros((n_t, 1, 1)),
        K0=np.zeros((0, 0, 2)),
        act=np.array([[[2.8, 1.0]]]),
        dist_std=np.zeros((1, 1)),
        dist_slot=np.array([-1]),
        noise=np.zeros((1, n_t, 1)),
        bound=1e12,
    )

    def run(x0, E, block, P1u, P1f, P2f, Cr, Cm_):
        rec = list(allocate_records(n_t, 1, n, 1, 2, True))
        c = common
        closed_loop(
            Loop(
                x0,
                E,
                block,
                P1u,
                P1f,
                P2f,
                Cr,
                c["fric"],
                c["substeps"],
                c["imp_k"],
                c["imp_dx"],
                Cm_,
                c["Dm"],
                c["Dmf"],
                c["sensor"],
                c["sensor_slot"],
                c["fir_src"],
                c["fir_dst"],
                c["fir_w"],
                c["Ak"],
                c["Bk"],
                c["Ck"],
                c["Dk"],
                c["y_ref"],
                c["u_ff"],
                c["K0"],
                c["act"],
                c["dist_std"],
                c["dist_slot"],
                c["noise"],
                c["bound"],
                np.zeros((1, 0, n)),
                np.zeros((1, 0, 1)),
                np.zeros((1, 0)),
                np.zeros((0, n, n)),
            ),
            Records(*rec),
        )
        return rec

    x0 = np.zeros((1, n))
    phys = run(
        x0,
        dense.Et.T[None].copy(),
        False,
        dense.P1u.T[None].copy(),
        dense.P1f.copy(),
        dense.P2f.copy(),
        rate[None],
        Cm,
    )
    mod = run(
        x0 @ Tinv.T,
        modal.E[None],
        True,
        modal.P1u[None],
        modal.P1f.T.copy(),
        modal.P2f.T.copy(),
        (rate @ T)[None],
        Cm @ T,
    )
    cond = np.linalg.cond(T)
    # friction makes the loop sensitive: bound by cond(T) eps amplified over the run
    assert rel(mod[0][0] @ T.T, phys[0][0]) < 1e3 * cond * np.finfo(float).eps
    assert rel(mod[2], phys[2]) < 1e3 * cond * np.finfo(float).eps


def test_modal_coordinates_reject_damped_rigid_mode_and_overdamped_modes():
    M, K = np.eye(2), np.diag([0.0, 4.0])
    with pytest.raises(ValueError, match="C: damps a rigid-body mode"):
        modal_coordinates(M, K, np.diag([1.0, 0.0]))
    with pytest.raises(ValueError, match="C: overdamped"):
        modal_coordinates(M, K, np.diag([0.0, 10.0]))  # ζ = 2.5
    with pytest.raises(ValueError, match="substeps"):
        ModalPropagator.build([0.0], [0.0], np.ones((2, 1)), H, substeps=0)


def test_proportionally_damped_modes_are_modal_coordinates_and_rates():
    # C = M Φ diag(2ζω) Φᵀ M: T = [[Φ, 0], [0, Φ]] up to column order, ω and ζ recovered
    rng = np.random.default_rng(2)
    R = rng.normal(size=(3, 3))
    M = R @ R.T + 3 * np.eye(3)
    L = np.linalg.cholesky(M)
    Q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    Phi = np.linalg.solve(L.T, Q)  # Φᵀ M Φ = I
    omega, zeta = np.array([1.0, 5.0, 20.0]), np.array([0.01, 0.1, 0.3])
    Minv_phi = M @ Phi
    K = Minv_phi @ np.diag(omega**2) @ Minv_phi.T
    C = Minv_phi @ np.diag(2 * zeta * omega) @ Minv_phi.T
    T, Tinv, w, z = modal_coordinates(M, K, C)
    np.testing.assert_allclose(Tinv @ T, np.eye(6), atol=1e-12)
    np.testing.assert_allclose(w, omega, rtol=1e-12)
    np.testing.assert_allclose(z, zeta, rtol=1e-10)
    for i in range(3):
        pos, rate = T[:, 2 * i], T[:, 2 * i + 1]
        assert np.abs(pos[3:]).max() < 1e-12 * np.abs(pos).max()  # z1: a displacement
        assert np.abs(rate[:3]).max() < 1e-12 * np.abs(rate).max()  # z2: its rate


def test_a_stack_of_blocks_is_each_block_alone():
    """Every block of BLOCKS in one (4, 41) stack: equal to the expm reference (1e-12, the
    module's bound) and bit for bit the block computed alone (each block's operations are
    its own)."""
    omega = np.array([w for w, _ in BLOCKS] * 4).reshape(4, -1)
    zeta = np.array([z for _, z in BLOCKS] * 4).reshape(4, -1)
    stack = block_propagators(omega, zeta, H)
    assert stack[0].shape == (4, len(BLOCKS), 2, 2)
    for i, (w, z) in enumerate(BLOCKS):
        alone = block_propagators([w], [z], H)
        A = np.array([[0.0, 1.0], [-(w**2), -2 * z * w]])
        for got, one, ref in zip(stack, alone, phi_products(A, H, np.eye(2), 2)):
            assert np.array_equal(got[2, i], one[0])
            assert rel(got[3, i], ref) < 1e-12


def test_modal_coordinates_of_a_stack_are_each_case_alone(tamu_case):
    """The hub + appendage plants of a dispersed batch (hub inertia and EI per case): the
    stacked call gives each case's (T, T⁻¹, ω, ζ) bit for bit as the call on that case alone,
    and T⁻¹ A T is the block-diagonal modal form of those ω, ζ (to cond(T) eps ≈ 1e-12 of
    ‖A‖; T⁻¹ T = I to 1e-12)."""
    from dataclasses import replace

    from flexsat.dynamics.dispersed_hub import DispersedHubAppendage

    p = tamu_case.params
    batch = DispersedHubAppendage.from_parameters(
        replace(p, hub_inertia=p.hub_inertia * np.array([0.8, 1.0, 1.3]), EI=p.EI * 1.1),
        5,
        damping=0.01,
    )
    M, K, C = batch.mass_matrix, batch.stiffness_matrix, batch.damping_matrix
    T, Ti, omega, zeta = modal_coordinates(M, K, C)
    A = batch.linear_part()[0]
    for c in range(3):
        for got, one in zip((T, Ti, omega, zeta), modal_coordinates(M[c], K[c], C[c])):
            assert np.array_equal(got[c], one)
        blocks = block_diag(
            *[np.array([[0.0, 1.0], [-(w * w), -2 * z * w]]) for w, z in zip(omega[c], zeta[c])]
        )
        assert rel(Ti[c] @ A[c] @ T[c], blocks) < 1e-12
        assert np.abs(Ti[c] @ T[c] - np.eye(12)).max() < 1e-12
