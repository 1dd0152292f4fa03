"""Linearisation of the flexible plant along a rigid nominal slew (seed 003 F8, §2.6-2.7):
the analytic A(t), B(t) equal central differences of the nonlinear perturbation dynamics, the
attitude error is the body-frame small rotation, the disturbance is Eq. 31's modal
acceleration, and the four Euler parameters could not be the LQR state."""

import numpy as np
import pytest

from flexsat.control import lqr
from flexsat.control.trajectory_linearization import TrajectoryLinearization, attitude_error
from flexsat.dynamics import FlexibleSpacecraft
from flexsat.dynamics.attitude import principal_rotation_to_quaternion, quaternion_multiply


def central_differences(f, n, h):
    """Columns (f(e_j h) − f(−e_j h)) / 2h: error h²/6 |f'''| + ε|f|/h."""
    cols = []
    for j in range(n):
        e = np.zeros(n)
        e[j] = h
        cols.append((f(e) - f(-e)) / (2 * h))
    return np.array(cols).T


COUPLED_FORCES = [(1, "y"), (1, "z"), (2, "x"), (2, "z"), (3, "x")]


@pytest.fixture(scope="module")
def coupled_plant(coupled_model):
    return FlexibleSpacecraft(coupled_model, forces=COUPLED_FORCES)


@pytest.fixture(scope="module")
def nominal_for(eigenaxis_slew):
    # 1 rad about a skew axis in 10 s: every component of ω_n, the gyroscopic terms live
    return lambda plant: eigenaxis_slew(plant.inertia, [1.0, 2.0, 2.0], 1.0, 10.0)


@pytest.mark.numerics
@pytest.mark.parametrize("which", ["eps", "coupled"])
def test_analytic_jacobians_equal_central_differences(
    which, eps_design_plant, coupled_plant, nominal_for
):
    # F8: the paper differenced DISCOS; here A(t), B(t) come from the plant's analytic
    # force_jacobian plus δα̇ = −ω_n × δα + δω, and are checked against central differences
    # (h = 1e-4 on states of order 1: rad, rad/s, m√kg) of the exact nonlinear perturbation
    # dynamics (error quaternion, plant rhs). The issue asks ≤ 1e-7 relative; measured
    # ≤ 3e-13 (the dynamics are nearly quadratic in δX, so h²f''' is tiny and round-off
    # ε|f|/h dominates). The EPS (Δ = 0) and the coupled model (Δ ≠ 0: the gyroscopic
    # −ω × Δᵀη̇ and the coupled mass matrix) both, with all their forces.
    plant = eps_design_plant if which == "eps" else coupled_plant
    lin = TrajectoryLinearization(plant, nominal_for(plant), forces="all")
    times = np.array([0.0, 2.5, 5.0, 8.1])
    A, B = lin.jacobians(times)
    N, m = lin.n_states, lin.n_inputs
    assert A.shape == (4, N, N) and B.shape == (4, N, m)
    for i, t in enumerate(times):
        A_fd = central_differences(lambda dx, t=t: lin.rhs(t, dx, np.zeros(m)), N, 1e-4)
        B_fd = central_differences(lambda du, t=t: lin.rhs(t, np.zeros(N), du), m, 1e-4)
        assert np.abs(A_fd - A[i]).max() <= 1e-7 * np.abs(A[i]).max()
        assert np.abs(B_fd - B[i]).max() <= 1e-7 * np.abs(B[i]).max()
    # the kinematic rows: −[ω_n ×] and I, nothing else
    w = lin.nominal.omega(times[2])
    np.testing.assert_array_equal(
        A[2, :3, :3], [[0, w[2], -w[1]], [-w[2], 0, w[0]], [w[1], -w[0], 0]]
    )
    np.testing.assert_array_equal(A[2, :3, 3:6], np.eye(3))
    assert not np.any(A[2, :3, 6:]) and not np.any(B[:, :3])


def test_the_torque_input_is_normalized_by_the_inertia(eps_design_plant, nominal_for):
    # δu_τ = J⁻¹δτ (rad/s², seed 003 Eq. 12) so D = 50 applies as published: on the rigid
    # rows, a unit normalized torque is a unit angular acceleration (Δ = 0 for the EPS's
    # free-free modes, so 𝓜⁻¹ = diag(J⁻¹, I) to round-off of Δ ~ 1e-13 |J|)
    lin = TrajectoryLinearization(eps_design_plant, nominal_for(eps_design_plant))
    _, B = lin.jacobians(np.array(3.0))
    np.testing.assert_allclose(B[3:6, :3], np.eye(3), rtol=0, atol=1e-12)
    assert lin.inputs == ("torque",) and lin.n_states == 26


@pytest.mark.numerics
def test_the_disturbance_is_eq31s_modal_acceleration(eps_design_plant, coupled_plant, nominal_for):
    # Eq. 31: η̈_d = [0 I] 𝓜⁻¹ [I; σᵀ] τ_n with σ the rotational shapes at the torque node
    # (CG node 95) and 𝓜 the hybrid mass matrix; the EPS's Δ = 0, so the rate rows are zero
    # and the elastic rows are exactly that (agreement to round-off of the few products, 1e-13
    # relative). Generalised (coupled model, ideal torquers, Δ ≠ 0): d is the flexible model's
    # acceleration at the nominal minus the rigid nominal's, including the gyroscopic load.
    plant = eps_design_plant
    lin = TrajectoryLinearization(plant, nominal_for(plant))
    times = np.linspace(0.0, 10.0, 7)
    d = lin.disturbance(times)
    n = lin.n_modes
    tau = lin.nominal.torque(times)
    eq31 = tau @ (plant.rotation_mass_inverse @ np.vstack([np.eye(3), plant.torque_modal]))[3:].T
    assert np.abs(d[:, 6 + n :] - eq31).max() <= 1e-13 * np.abs(eq31).max()
    assert np.abs(d[:, : 6 + n]).max() <= 1e-13 * np.abs(eq31).max()
    assert np.abs(eq31).max() > 1.0  # the nominal torque does load the modes

    plant = coupled_plant
    lin = TrajectoryLinearization(plant, nominal_for(plant))
    beta, w, tau, w_dot = lin.nominal_at(times)
    J = plant.inertia
    load = np.concatenate([tau - np.cross(w, w @ J.T), np.zeros((7, n := plant.n_modes))], 1)
    acc = load @ plant.rotation_mass_inverse.T
    d = lin.disturbance(times)
    np.testing.assert_allclose(
        d[:, 3:6], acc[:, :3] - w_dot, rtol=0, atol=1e-13 * np.abs(acc).max()
    )
    np.testing.assert_allclose(d[:, 6 + n :], acc[:, 3:], rtol=0, atol=1e-13 * np.abs(acc).max())
    assert np.abs(d[:, 6 + n :]).max() > 1e-3  # Δ ≠ 0: the rigid acceleration moves the modes


def test_the_attitude_error_is_the_body_frame_small_rotation():
    # β = δq ⊗ β_n with δq the rotation φ about a body axis e: δα = 2 sin(φ/2) e, whatever
    # the sign of β (both signs are one attitude); and state() inverts it
    beta_n = principal_rotation_to_quaternion(np.array([0.0, 0.6, 0.8]), 1.3)
    e = np.array([2.0, -1.0, 2.0]) / 3
    phi = 0.05
    beta = quaternion_multiply(principal_rotation_to_quaternion(e, phi), beta_n)
    np.testing.assert_allclose(
        attitude_error(beta, beta_n), 2 * np.sin(phi / 2) * e, rtol=0, atol=1e-16
    )
    np.testing.assert_allclose(
        attitude_error(-beta, beta_n), 2 * np.sin(phi / 2) * e, rtol=0, atol=1e-16
    )


def test_state_and_attitude_error_are_inverse(coupled_plant, nominal_for):
    lin = TrajectoryLinearization(coupled_plant, nominal_for(coupled_plant))
    dX = np.random.default_rng(1).standard_normal((5, lin.n_states)) * 0.1
    x = lin.state(np.linspace(0, 12, 5), dX)  # past T: held at the end of the nominal
    np.testing.assert_allclose(
        attitude_error(x[:, :4], lin.nominal.beta(np.minimum(np.linspace(0, 12, 5), 10.0))),
        dX[:, :3],
        rtol=0,
        atol=1e-15,
    )
    np.testing.assert_allclose(x[:, 7:], dX[:, 6:], rtol=0, atol=0)


def test_the_four_euler_parameters_give_no_stabilising_riccati_solution(
    eps_design_plant, nominal_for
):
    # Why δα and not δβ (module docstring): linearised on [β, ω, η, η̇] (the plant's own
    # coordinates) the norm direction of β is an eigenvalue 0 no input reaches, so the LQR
    # Riccati equation has no stabilising solution; on [δα, δω, δη, δη̇] it has one.
    plant = eps_design_plant
    A0, B0 = plant.linear_part()
    with pytest.raises(ValueError, match="not stabilizable: eigenvalue"):
        lqr(A0, B0[:, :3], np.eye(plant.nx), np.eye(3))
    lin = TrajectoryLinearization(plant, nominal_for(plant))
    A, B = lin.jacobians(np.array(0.0))
    K, _, poles = lqr(A, B, np.eye(lin.n_states), np.eye(3))
    assert poles.real.max() < 0


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"forces": ["force_69X", "force_12Q"]}, "force_12Q: not a force channel of the plant"),
        ({"forces": ["force_69X", "force_69X"]}, "force_69X: given twice"),
        ({"forces": "some"}, "forces: must be 'all' or a sequence"),
    ],
)
def test_bad_forces_are_named(eps_design_plant, nominal_for, kwargs, message):
    with pytest.raises(ValueError, match=message):
        TrajectoryLinearization(eps_design_plant, nominal_for(eps_design_plant), **kwargs)


def test_bad_plant_and_nominal_are_named(coupled_plant, coupled_model, nominal_for, eigenaxis_slew):
    with pytest.raises(ValueError, match="plant: must be built without translation"):
        TrajectoryLinearization(
            FlexibleSpacecraft(coupled_model, translation=True), nominal_for(coupled_plant)
        )
    with pytest.raises(ValueError, match="plant: must be a FlexibleSpacecraft"):
        TrajectoryLinearization(object(), nominal_for(coupled_plant))

    class NoTorque:
        duration = 1.0

        def beta(self, t):
            return np.zeros(np.shape(t) + (4,))

        omega = beta

    with pytest.raises(ValueError, match="nominal: .* lacks torque"):
        TrajectoryLinearization(coupled_plant, NoTorque())
    bad = nominal_for(coupled_plant)
    bad.duration = -1.0
    with pytest.raises(ValueError, match="nominal.duration: must be > 0"):
        TrajectoryLinearization(coupled_plant, bad)

    class Skewed(eigenaxis_slew):
        def beta(self, t):
            return 1.01 * super().beta(t)

    lin = TrajectoryLinearization(coupled_plant, Skewed(np.eye(3), [0, 0, 1], 1.0, 5.0))
    with pytest.raises(ValueError, match="nominal.beta: must be unit Euler parameters"):
        lin.jacobians(np.array([1.0]))
