"""Three-axis rigid spacecraft plant (issue 10): its own RKMK4 step keeps ‖β‖ = 1 to round-off
and conserves angular momentum and energy of the torque-free body; it follows the analytic
Euler–Poinsot motion; its linear part plus nonlinear force is the full right-hand side, which a
tight DOP853 solution agrees with; the analytic force Jacobian matches central differences;
small sampled loops under the MRP and quaternion PD laws reach their target; inertia and
outputs are checked."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from flexsat.control import MRPLaw, QuaternionPD
from flexsat.control.attitude_laws import error_quaternion
from flexsat.dynamics import RigidSpacecraft
from flexsat.dynamics import attitude as att
from flexsat.dynamics import rigid_body as rb
from flexsat.units import ureg
from rkmk4_reference import propagate

EPS = np.finfo(float).eps
MOMENTS = np.array([10.0, 15.0, 20.0])
INERTIA = np.array([[10.0, 0.5, -0.3], [0.5, 15.0, 0.8], [-0.3, 0.8, 20.0]])
BETA0 = att.principal_rotation_to_quaternion([0.0, 0.6, 0.8], 0.5)
TARGET = att.principal_rotation_to_quaternion([0.0, 0.6, 0.8], 0.7)


def run(plant, x0, u, h, n):
    xs = [x0]
    for _ in range(n):
        xs.append(plant.step(xs[-1], u, h))
    return np.stack(xs)


@pytest.mark.numerics
def test_torque_free_tumble_keeps_its_invariants_and_is_euler_poinsot():
    # Principal axes, large rates (|ω| ~ 1.2 rad/s), 100 s at h = 5 ms. RKMK4 is fourth order:
    # its global error at this step is ~2e-10 in ω after 100 s (rigid_body.propagate, the same
    # kernel), so the Jacobi-elliptic solution is matched to 1e-8 and H, T drift ≤ 1e-10
    # relative; β is a product of exact unit quaternions: unit to √N·eps ≈ 3e-14 ≤ 1e-12.
    plant = RigidSpacecraft(np.diag(MOMENTS))
    w0 = np.array([0.8, 0.05, 0.9])
    x0 = plant.state(BETA0, w0)[None]
    xs = run(plant, x0, np.zeros((1, 3)), 0.005, 20000)[:, 0]
    t = 0.005 * np.arange(xs.shape[0])
    H, E = plant.momentum(xs), plant.energy(xs)
    assert np.abs(H - H[0]).max() <= 1e-10 * np.linalg.norm(H[0])
    assert np.abs(E - E[0]).max() <= 1e-10 * E[0]
    assert np.abs(np.linalg.norm(xs[:, :4], axis=-1) - 1).max() <= 1e-12
    exact = rb.euler_poinsot_rates(MOMENTS, w0, t)
    assert np.abs(xs[:, 4:] - exact).max() <= 1e-8


def test_step_is_the_propagators_kernel():
    # the plant's step with the torque held is rigid_body.propagate with a constant torque
    plant = RigidSpacecraft(INERTIA)
    u = np.array([[0.2, -0.1, 0.05]])
    t = np.linspace(0.0, 1.0, 51)
    beta, w = propagate(BETA0, [0.3, -0.2, 0.1], INERTIA, t, u[0])
    xs = run(plant, plant.state(BETA0, [0.3, -0.2, 0.1])[None], u, t[1], 50)[:, 0]
    np.testing.assert_allclose(xs[:, :4], beta, rtol=0, atol=4 * EPS)
    np.testing.assert_allclose(xs[:, 4:], w, rtol=0, atol=4 * EPS)


@pytest.mark.numerics
def test_linear_part_and_force_are_the_full_right_hand_side():
    # A x + B u + B_f f = [Ω(ω)β, I⁻¹(u − ω × Iω)] (seed 003 Eqs. 11–12): algebraically equal,
    # to round-off; then a DOP853 solution of it (rtol 1e-12) and the RKMK4 steps (h = 10 ms,
    # error ~1e-9) agree to 1e-8 after 10 s
    plant = RigidSpacecraft(INERTIA)
    rng = np.random.default_rng(1)
    x = rng.standard_normal((5, 7))
    x[:, :4] /= np.linalg.norm(x[:, :4], axis=-1, keepdims=True)
    u = rng.standard_normal((5, 3))
    A, B = plant.linear_part()
    xdot = x @ A.T + u @ B.T + plant.nonlinear_force(x, u) @ plant.force_matrix.T
    expected = np.concatenate(
        [
            np.einsum("...ij,...j->...i", att.omega_matrix(x[:, 4:]), x[:, :4]),
            rb.euler_rates(x[:, 4:], INERTIA, u),
        ],
        -1,
    )
    np.testing.assert_allclose(xdot, expected, rtol=0, atol=16 * EPS * np.abs(expected).max())
    np.testing.assert_allclose(plant.rhs(x, u), xdot, rtol=0, atol=4 * EPS * np.abs(xdot).max())
    u0 = np.array([0.3, -0.2, 0.1])
    x0 = plant.state(BETA0, [0.5, -0.4, 0.3])
    sol = solve_ivp(
        lambda t, z: plant.rhs(z, u0), (0.0, 10.0), x0, method="DOP853", rtol=1e-12, atol=1e-12
    )
    xs = run(plant, x0[None], u0[None], 0.01, 1000)[-1, 0]
    np.testing.assert_allclose(xs, sol.y[:, -1], rtol=0, atol=1e-8)


@pytest.mark.numerics
def test_force_jacobian_matches_central_differences():
    # f is quadratic in x: central differences are exact up to round-off eps|f|/h ~ 1e-10
    # at h = 1e-6; tolerance 1e-8 of the largest entry
    plant = RigidSpacecraft(INERTIA)
    rng = np.random.default_rng(2)
    x = rng.standard_normal(7)
    x[:4] /= np.linalg.norm(x[:4])
    u = rng.standard_normal(3)
    Jx, Ju = plant.force_jacobian(x, u)
    fd = np.stack(
        [
            (plant.nonlinear_force(x + 1e-6 * e, u) - plant.nonlinear_force(x - 1e-6 * e, u)) / 2e-6
            for e in np.eye(7)
        ],
        -1,
    )
    assert np.abs(Jx - fd).max() <= 1e-8 * np.abs(Jx).max()
    assert not Ju.any()


@pytest.mark.numerics
@pytest.mark.parametrize(
    "law",
    [MRPLaw(K=7.2, P=12.0, beta_target=TARGET), QuaternionPD(Kp=7.2, Kd=12.0, beta_target=TARGET)],
)
def test_a_sampled_loop_on_the_plant_steps_reaches_the_target_from_170_degrees(law):
    # a 20 Hz zero-order-hold loop written out: the law reads (attitude, rate) and writes the
    # torque held over the sample. Both laws' attitude feedback is bounded (|σ| <= 1,
    # |δβ| <= 1), so the sampled loop is well inside its stability margin (rate gain / inertia
    # 1.2 /s against 20 Hz sampling); the linearised loop's slowest mode decays at ~0.18 /s
    # (MRP) and 0.30 /s (PD): below 1e-3 from 3 rad after 60 s (the continuous-time Gibbs law
    # at 170°, whose feedback A q (1 + qᵀq) is ~1500 A, is tested on its continuous loop in
    # tests/control/test_attitude_laws.py)
    plant = RigidSpacecraft(INERTIA)
    target = TARGET
    beta0 = att.quaternion_multiply(
        att.principal_rotation_to_quaternion([1 / 3, 2 / 3, 2 / 3], np.deg2rad(170.0)), target
    )
    x = plant.state(np.stack([beta0, target]), [[0.05, -0.1, 0.08], [0.0, 0.0, 0.0]])
    for k in range(1200):
        y = {name: plant.output(name, x) for name in law.reads}
        u, _ = law(k * 0.05, y, {})
        x = plant.step(x, u, 0.05)
    _, phi = att.quaternion_to_principal_rotation(error_quaternion(x[:, :4], target))
    phi = np.minimum(phi, 2 * np.pi - phi)
    assert np.all(phi < 1e-3) and np.abs(x[:, 4:]).max() < 1e-3


def test_outputs_and_channels():
    plant = RigidSpacecraft(INERTIA)
    assert [c.name for c in plant.inputs] == ["torque"] and plant.n_inputs == 3
    assert [c.name for c in plant.outputs] == ["attitude", "rate", "euler123", "mrp"]
    beta = att.dcm_to_quaternion(att.euler123_to_dcm([1.0, 1.0, 1.0]))
    # seed 003 F4: β_f = [0.565676, 0.570941, 0.167519, 0.570941] for (1, 1, 1) rad
    np.testing.assert_allclose(beta, [0.565676, 0.570941, 0.167519, 0.570941], atol=1e-6)
    x = plant.state(np.stack([beta, -beta]), [0.1, 0.2, 0.3])
    np.testing.assert_allclose(plant.output("euler123", x), np.ones((2, 3)), atol=1e-14)
    sigma = plant.output("mrp", x)
    np.testing.assert_allclose(sigma[0], att.quaternion_to_mrp(beta), rtol=1e-15)
    np.testing.assert_array_equal(sigma[0], sigma[1])  # the short rotation for either sign
    C, D, _ = plant.output_matrices("rate")
    np.testing.assert_array_equal(x @ C.T, plant.output("rate", x))
    assert plant.output_matrices("mrp") is None
    np.testing.assert_allclose(
        plant.momentum(x)[0],
        rb.angular_momentum_inertial(beta, [0.1, 0.2, 0.3], INERTIA),
        rtol=1e-15,
    )
    with pytest.raises(ValueError, match="has no output channel 'theta'"):
        plant.output("theta", x)


def test_normalize_restores_a_unit_quaternion():
    plant = RigidSpacecraft(INERTIA)
    x = plant.state(BETA0, [0.1, 0.2, 0.3])
    x[:4] *= 1 + 1e-6
    y = plant.normalize(x)
    assert abs(np.linalg.norm(y[:4]) - 1) <= 2 * EPS and np.array_equal(y[4:], x[4:])


def test_inertia_accepts_units_and_dispersion():
    plant = RigidSpacecraft(np.diag(MOMENTS) * ureg("kg*m**2"))
    np.testing.assert_array_equal(plant.inertia, np.diag(MOMENTS))
    slug = RigidSpacecraft(np.diag(MOMENTS) * ureg("slug*ft**2"))
    np.testing.assert_allclose(slug.inertia, np.diag(MOMENTS) * 1.3558179483314004, rtol=1e-12)
    cases = RigidSpacecraft(np.stack([INERTIA, 2 * INERTIA]))
    assert cases.n_cases == 2
    A, B = cases.linear_part()
    assert B.shape == (2, 7, 3)
    np.testing.assert_allclose(B[1, 4:], np.linalg.inv(2 * INERTIA), rtol=1e-14)


@pytest.mark.parametrize(
    "inertia, message",
    [
        (np.eye(2), r"inertia: last axes must have shape \(3, 3\)"),
        ([[1.0, 0.1, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], "inertia: must be symmetric"),
        (np.diag([1.0, -1.0, 1.0]), "inertia: must be positive definite"),
        (np.diag([1.0, 1.0, 3.0]), "inertia: principal moments .* violate the triangle inequality"),
        (np.diag([1.0, np.nan, 1.0]), "inertia: must be finite"),
        (
            np.broadcast_to(np.eye(3), (2, 2, 3, 3)),
            r"inertia: must have shape \(3, 3\) or \(n_cases, 3, 3\)",
        ),
        ("1 kg", "inertia"),
    ],
)
def test_bad_inertia_is_named(inertia, message):
    with pytest.raises(ValueError, match=message):
        RigidSpacecraft(inertia)


def test_initial_state_from_euler_angles_and_rate_with_units():
    """A scenario's ``initial``: 1-2-3 Euler angles (seed 003 Eq. 12 convention) and body rate,
    in any unit; the quaternion is the one of the DCM of those angles."""
    from flexsat.dynamics.attitude import dcm_to_euler123, quaternion_to_dcm

    plant = RigidSpacecraft(np.diag([10.0, 20.0, 30.0]))
    x = plant.state_from(euler123=["30 deg", "-20 deg", "10 deg"], rate=["1 deg/s", 0, 0])
    np.testing.assert_allclose(
        dcm_to_euler123(quaternion_to_dcm(x[:4])), np.radians([30.0, -20.0, 10.0]), atol=1e-15
    )
    np.testing.assert_allclose(x[4:], [np.radians(1.0), 0, 0], rtol=1e-15)
    with pytest.raises(ValueError, match="attitude: give attitude or euler123, not both"):
        plant.state_from(attitude=[1, 0, 0, 0], euler123=[0, 0, 0])
    with pytest.raises(ValueError, match="euler123: three finite angles"):
        plant.state_from(euler123=[0, 0])
    with pytest.raises(ValueError, match="spin: not an initial value of RigidSpacecraft"):
        plant.state_from(spin=1.0)
