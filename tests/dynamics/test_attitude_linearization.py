"""Linearisation of the three-axis spacecraft in attitude-error coordinates (issue 22,
deliverable 5): at rest the rigid body is the double integrator σ̈ = ¼ J⁻¹ u exactly; about a
constant rate, with modes, torquers on a node and point forces, (A, B) equal central differences
of the nonlinear plant's right-hand side mapped to error coordinates; at rest in q_v
coordinates the flexible linearisation is the plant's own linear part; bad input is named."""

import numpy as np
import pytest

from flexsat.dynamics import FlexibleSpacecraft, RigidSpacecraft
from flexsat.dynamics import attitude as att
from flexsat.dynamics.attitude_linearization import linearize_attitude
from flexsat.input_checks import FieldError
from flexsat.structures.modal_model import ModalModel

EPS = np.finfo(float).eps
J = np.array([[120.0, 3.0, -2.0], [3.0, 150.0, 4.0], [-2.0, 4.0, 200.0]])
RATE = np.array([0.1, -0.05, 0.2])
BETA_R = att.principal_rotation_to_quaternion(np.array([1.0, 2.0, -1.0]) / np.sqrt(6), 0.7)


def coupled_modal():
    """Three elastic modes with rotational participation Δ ≠ 0 (so rigid and elastic motion
    couple through the mass matrix), rotational shapes at node 1 (torquers there load the
    modes) and two nodes for forces and outputs."""
    rigid = np.zeros((6, 6))
    rigid[:3, :3] = 300.0 * np.eye(3)
    rigid[3:, 3:] = J
    participation = np.zeros((3, 6))
    participation[:, 3:] = [[3.0, 0.5, 0.0], [0.0, 4.0, 1.0], [1.0, 0.0, 5.0]]
    return ModalModel(
        node_ids=[1, 2],
        coordinates=[[2.0, 0, 0], [0, 3.0, 0]],
        frequencies=2 * np.pi * np.array([0.4, 0.9, 1.7]),
        damping=0.01,
        shapes=0.1 * np.random.default_rng(5).standard_normal((3, 2, 6)),
        rigid_mass=rigid,
        participation=participation,
    )


def flexible():
    return FlexibleSpacecraft(
        coupled_modal(),
        forces=[(1, "y"), (2, "x")],
        displacements=[(2, "z")],
        rotations=[(1, "x")],
        torque_node=1,
    )


def error_rate(plant, lin, z, du, beta_r):
    """ż of the nonlinear plant at error state z, input perturbation δu, reference attitude
    β_R(0) = beta_r: the state built from the definitions (β = δq ⊗ β_R, ω = ω_r + δω,
    η = η_r + δη), ẋ from ``plant.rhs``, and the error's rate from the exact derivative of
    δq = β ⊗ β_R* along β̇ and β̇_R = ½[0, ω_r] ⊗ β_R (products are bilinear)."""
    n = (len(z) - 6) // 2
    e = z[:3]
    if lin.coordinates == "mrp":
        dq = att.mrp_to_quaternion(e)
    else:
        dq = np.r_[np.sqrt(1 - e @ e), e]
    beta = att.quaternion_multiply(dq, beta_r)
    x = np.r_[beta, lin.rate + z[3:6], lin.deflection + z[6 : 6 + n], z[6 + n :]]
    u = du.copy()
    u[:3] += lin.torque
    xdot = plant.rhs(x, u)
    conj = np.array([1.0, -1.0, -1.0, -1.0])
    beta_r_dot = 0.5 * att.quaternion_multiply(np.r_[0.0, lin.rate], beta_r)
    dq_dot = att.quaternion_multiply(xdot[:4], beta_r * conj) + att.quaternion_multiply(
        beta, beta_r_dot * conj
    )
    if lin.coordinates == "mrp":
        e_dot = dq_dot[1:] / (1 + dq[0]) - dq[1:] * dq_dot[0] / (1 + dq[0]) ** 2
    else:
        e_dot = dq_dot[1:]
    return np.r_[e_dot, xdot[4:]]


def central_jacobians(plant, lin, step):
    nz, m = lin.B.shape
    f = lambda z, du: error_rate(plant, lin, z, du, BETA_R)  # noqa: E731
    A = np.empty((nz, nz))
    B = np.empty((nz, m))
    for j in range(nz):
        d = np.zeros(nz)
        d[j] = step
        A[:, j] = (f(d, np.zeros(m)) - f(-d, np.zeros(m))) / (2 * step)
    for j in range(m):
        d = np.zeros(m)
        d[j] = step
        B[:, j] = (f(np.zeros(nz), d) - f(np.zeros(nz), -d)) / (2 * step)
    return A, B, f(np.zeros(nz), np.zeros(m))


PLANTS = {"rigid": lambda: RigidSpacecraft(J), "flexible": flexible}


@pytest.mark.parametrize("coordinates", ["mrp", "quaternion"])
@pytest.mark.parametrize("kind", ["rigid", "flexible"])
@pytest.mark.parametrize("rate", [np.zeros(3), RATE], ids=["rest", "spinning"])
def test_linearisation_equals_central_differences_of_the_nonlinear_plant(kind, coordinates, rate):
    """A and B against central differences of the nonlinear plant (error_rate), and the
    reference is an equilibrium (ż = 0 there). The central difference errs by h²|F'''|/6 +
    ε|F|/h; F is a low-order rational function of z with coefficients of the size of A (rates
    0.2 rad/s, modes to 11 rad/s), so each row errs by less than 10 (h² + ε/h) times its
    largest coefficient in [A, B], with h = 1e-5."""
    plant = PLANTS[kind]()
    lin = linearize_attitude(plant, coordinates, rate)
    h = 1e-5
    A, B, rest = central_jacobians(plant, lin, h)
    row_scale = np.abs(np.hstack([lin.A, lin.B])).max(axis=1, keepdims=True)
    tol = 10 * (h**2 + EPS / h) * row_scale
    assert np.all(np.abs(rest) <= 100 * EPS * row_scale[:, 0])
    assert np.all(np.abs(A - lin.A) <= tol)
    assert np.all(np.abs(B - lin.B) <= tol)
    if np.any(rate) and kind == "flexible":
        assert np.abs(lin.deflection).max() > 0  # the torquers on node 1 deflect the modes


def test_rigid_at_rest_is_three_double_integrators():
    """The exact known result: σ̈ = ¼ J⁻¹ u, q̈_v = ½ J⁻¹ u (small rotation θ: σ ≈ θ/4, q_v ≈
    θ/2); A = [[0, kI], [0, 0]], B = [0; J⁻¹], to the inverse's round-off cond(J) ε; the
    transfer function is k J⁻¹ / s²."""
    Jinv = np.linalg.inv(J)
    tol = 10 * np.linalg.cond(J) * EPS * np.abs(Jinv).max()
    for coordinates, k in (("mrp", 0.25), ("quaternion", 0.5)):
        lin = linearize_attitude(RigidSpacecraft(J), coordinates)
        expected_A = np.zeros((6, 6))
        expected_A[:3, 3:] = k * np.eye(3)
        assert np.array_equal(lin.A, expected_A)
        assert np.array_equal(lin.B[:3], np.zeros((3, 3)))
        assert np.abs(lin.B[3:] - Jinv).max() <= tol
        assert np.array_equal(lin.torque, np.zeros(3))
        sys = lin.to_statespace()
        s = 0.7j
        G = sys(s)
        assert np.abs(G[:3] - k * Jinv / s**2).max() <= 10 * tol / abs(s) ** 2
        assert np.abs(G[3:] - Jinv / s).max() <= 10 * tol / abs(s)


def test_flexible_at_rest_in_quaternion_coordinates_is_the_plants_linear_part():
    """An independent construction: the plant's own linearisation about rest (state [β, ω, η,
    η̇], β_v' = ω/2) restricted to (β_v, ω, η, η̇) is the q_v linearisation at rest."""
    plant = flexible()
    lin = linearize_attitude(plant, "quaternion")
    A0, B0 = plant.linear_part()
    keep = np.r_[1:4, 4:7, 7 : plant.nx]
    scale = np.abs(A0).max()
    assert np.abs(A0[np.ix_(keep, keep)] - lin.A).max() <= 100 * EPS * scale
    assert np.abs(B0[keep] - lin.B).max() <= 100 * EPS * np.abs(B0).max()


def test_quaternion_kinematics_rows_are_twice_the_mrp_ones_and_the_rest_is_shared():
    plant = flexible()
    mrp = linearize_attitude(plant, "mrp", RATE)
    qv = linearize_attitude(plant, "quaternion", RATE)
    assert np.array_equal(qv.A[:3, 3:6], 2 * mrp.A[:3, 3:6])
    assert np.array_equal(qv.A[:3, :3], mrp.A[:3, :3])
    assert np.array_equal(qv.A[3:], mrp.A[3:])
    assert np.array_equal(qv.B, mrp.B)


def test_labels_and_the_node_outputs():
    plant = flexible()
    lin = linearize_attitude(plant, "mrp")
    sys = lin.to_statespace("flexible")
    assert sys.state_labels[:7] == ["sigma[0]", "sigma[1]", "sigma[2]"] + [
        f"rate_error[{i}]" for i in range(3)
    ] + ["eta[0]"]
    assert sys.state_labels[-1] == "eta_dot[2]"
    assert sys.input_labels == ["torque[0]", "torque[1]", "torque[2]", "force_1Y", "force_2X"]
    assert sys.output_labels[6:] == ["displacement_2Z", "rotation_1X"]
    # a node output is Φ δη: compare with the plant's output at a deflected state
    x = plant.initial_state(1)[0]
    x[7:10] = [0.01, -0.02, 0.03]
    z = np.r_[np.zeros(6), x[7:10], np.zeros(3)]
    for i, name in enumerate(("displacement_2Z", "rotation_1X")):
        assert lin.C[6 + i] @ z == pytest.approx(float(plant.output(name, x)), rel=1e-14)
    assert lin.C[lin.measured_rows].tolist() == np.eye(6, lin.A.shape[0]).tolist()
    assert lin.B[:, lin.torque_columns].shape == (12, 3)


@pytest.mark.parametrize(
    "call, field",
    [
        (lambda: linearize_attitude(RigidSpacecraft(J), "gibbs"), "coordinates"),
        (lambda: linearize_attitude(RigidSpacecraft(J), rate=[0.1, 0.2]), "rate"),
        (lambda: linearize_attitude(RigidSpacecraft(J), rate=np.zeros((2, 3))), "rate"),
        (lambda: linearize_attitude(RigidSpacecraft(np.stack([J, J])), "mrp"), "plant"),
        (
            lambda: linearize_attitude(FlexibleSpacecraft(coupled_modal(), translation=True)),
            "plant",
        ),
        (lambda: linearize_attitude(object()), "plant"),
    ],
)
def test_bad_input_is_named(call, field):
    with pytest.raises(FieldError) as err:
        call()
    assert err.value.field == field
