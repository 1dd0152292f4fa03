"""Three-axis LQG attitude compensator (issue 22, deliverable 5): its gains are python-control's
``lqr`` and ``lqe`` to the Schur method's round-off, its compensator the textbook A − BK − LC
composition, its closed loop the separation principle's; on the nonlinear plants through
flexsat.sim.simulate a tiny error follows the sampled-data linear closed loop, small and large
slews settle (rigid and flexible, MRP and q_v), and a constant-rate reference is tracked."""

import numpy as np
import pytest
import scipy.linalg

import control as ct
from flexsat.control import AttitudeLQG
from flexsat.control.lqg import zoh
from flexsat.dynamics import FlexibleSpacecraft, RigidSpacecraft, linearize_attitude
from flexsat.dynamics import attitude as att
from flexsat.input_checks import FieldError
from flexsat.sim.config import SimConfig
from flexsat.sim.engine import simulate

EPS = np.finfo(float).eps
J = np.array([[120.0, 3.0, -2.0], [3.0, 150.0, 4.0], [-2.0, 4.0, 200.0]])
AXIS = np.array([1.0, 2.0, -1.0]) / np.sqrt(6)
DT = 0.1
R = 1e-3 * np.eye(3)
QN = np.eye(3)
RN = np.diag([1e-6] * 3 + [1e-4] * 3)


def weights(lin):
    """A ~0.5 rad/s regulator: the attitude weight scaled by 1/k² (k = ¼ for MRPs, ½ for q_v),
    so both coordinates weight the small rotation θ alike; modes weighted lightly."""
    k = {"mrp": 0.25, "quaternion": 0.5}[lin.coordinates]
    n = lin.A.shape[0]
    return np.diag([100.0 / k**2] * 3 + [10.0] * 3 + [1.0] * (n - 6))


def design(plant, coordinates="mrp", rate=(0.0, 0.0, 0.0), angle=0.0):
    lin = linearize_attitude(plant, coordinates, rate)
    target = att.principal_rotation_to_quaternion(AXIS, angle)
    return AttitudeLQG.design(lin, weights(lin), R, QN, RN, DT, beta_target=target)


def flexible():
    """Three elastic modes (0.4–1.7 Hz, 1 % damping) with rotational participation: the
    rigid rotation and the modes couple through the mass matrix."""
    from flexsat.structures.modal_model import ModalModel

    rigid = np.zeros((6, 6))
    rigid[:3, :3] = 300.0 * np.eye(3)
    rigid[3:, 3:] = J
    participation = np.zeros((3, 6))
    participation[:, 3:] = [[3.0, 0.5, 0.0], [0.0, 4.0, 1.0], [1.0, 0.0, 5.0]]
    modal = ModalModel(
        node_ids=[1, 2],
        coordinates=[[2.0, 0, 0], [0, 3.0, 0]],
        frequencies=2 * np.pi * np.array([0.4, 0.9, 1.7]),
        damping=0.01,
        shapes=0.1 * np.random.default_rng(5).standard_normal((3, 2, 6)),
        rigid_mass=rigid,
        participation=participation,
    )
    return FlexibleSpacecraft(modal, displacements=[(2, "z")])


def pointing_angle(beta, target):
    """Principal angle of the error between β (..., 4) and the target (..., 4), rad."""
    return 2 * np.arccos(np.abs(np.sum(beta * target, -1)).clip(max=1.0))


@pytest.mark.parametrize("rate", [np.zeros(3), np.array([0.02, -0.01, 0.03])])
def test_gains_equal_python_control_lqr_and_lqe(rate, schur_error_bound):
    """K = control.lqr(A, B, Q, R), L = control.lqe(A, I, C, G Qn Gᵀ, Rn) (G = B, the torque
    noise; the intensity formed and symmetrised as flexsat's kalman does): both solve the same
    Riccati equations by the Schur method, so they differ by at most twice its error bound
    n ε (κ(U11) + 3) (Laub 1979; :func:`flexsat.control.lqr.riccati_error_bound`)."""
    law = design(RigidSpacecraft(J), rate=rate)
    A, B, C = law.A, law.B, law.C
    assert (A.shape, B.shape, C.shape) == ((6, 6), (6, 3), (6, 6))
    K, S, E = ct.lqr(A, B, weights(law.linearization), R)
    W = B @ QN @ B.T
    L, P, F = ct.lqe(A, np.eye(6), C, 0.5 * (W + W.T), RN)
    tol_k = 2 * schur_error_bound(S)
    tol_l = 2 * schur_error_bound(P)
    assert np.abs(law.K - K).max() <= tol_k * np.linalg.norm(K, 2)
    assert np.abs(law.L - L).max() <= tol_l * np.linalg.norm(L, 2)
    assert np.abs(law.regulator.solution - S).max() <= tol_k * np.linalg.norm(S, 2)
    assert np.abs(law.filter.solution - P).max() <= tol_l * np.linalg.norm(P, 2)

    # the compensator is the textbook composition of these gains
    comp = law.compensator()
    textbook = (A - B @ K - L @ C, L, -K, np.zeros((3, 6)))
    bound = (np.abs(B).max() * tol_k * np.linalg.norm(K, 2) + tol_l * np.linalg.norm(L, 2)) * 6
    for got, want in zip((comp.A, comp.B, comp.C, comp.D), textbook):
        assert np.abs(got - want).max() <= bound + 6 * EPS * np.abs(want).max()
    assert comp.input_labels == law.linearization.to_statespace().output_labels[:6]
    assert comp.output_labels == ["torque[0]", "torque[1]", "torque[2]"]

    # separation: plant (its measured outputs) and compensator in positive feedback (the
    # compensator's output is already −K ẑ) have eig(A − BK) ∪ eig(A − LC)
    plant = ct.ss(A, B, C, np.zeros((6, 3)))
    loop = ct.feedback(plant, comp, sign=1)
    M = loop.A
    lam, vl, vr = scipy.linalg.eig(M, left=True, right=True)
    kappa = np.abs(1 / np.sum(vl.conj() * vr, axis=0)) * np.linalg.norm(vl, axis=0)
    kappa *= np.linalg.norm(vr, axis=0)
    expected = np.concatenate([E, F])
    for value, k in zip(lam, kappa):
        assert np.min(np.abs(expected - value)) <= 100 * k * EPS * np.linalg.norm(M, 2)


def test_a_tiny_error_follows_the_sampled_data_linear_closed_loop():
    """A 1e-4 rad error on the nonlinear rigid plant (simulate, RKMK4) against the law's
    sampled-data loop on the linearisation: z_{k+1} = Φ_p z_k + Γ_p δu_k, δu_k = −K ẑ_k,
    ẑ_{k+1} = Φ ẑ_k + Γ_u δu_k + Γ_y C z_k, ẑ_0 = C⁺ C z_0. The neglected terms are second
    order, so each history agrees to twice the amplitude times its own scale (relative 2e-4;
    measured 1e-5 to 1.5e-5), far from the O(1) of a wrong sign, hold or delay."""
    plant = RigidSpacecraft(J)
    law = design(plant, "mrp")
    angle = 1e-4
    beta0 = att.principal_rotation_to_quaternion(AXIS, angle)
    result = simulate(
        plant,
        law,
        SimConfig(duration=8.0, control_rate=1 / DT),
        n_cases=1,
        initial_state=plant.state(beta0, np.zeros(3)),
    )
    beta = result.dataset.attitude.values[0]
    w = result.dataset.rate.values[0]
    sigma = att.quaternion_to_mrp(np.where(beta[:, :1] < 0, -beta, beta))
    z_sim = np.hstack([sigma, w])

    Phi_p, Gam_p = zoh(law.A, law.B, DT)
    Phi, Gu, Gy = law.estimator
    z = z_sim[0].copy()
    z_hat = np.linalg.pinv(law.C) @ law.C @ z
    z_lin = [z]
    for _ in range(len(z_sim) - 1):
        du = -law.K @ z_hat
        z_hat = Phi @ z_hat + Gu @ du + Gy @ law.C @ z
        z = Phi_p @ z + Gam_p @ du
        z_lin.append(z)
    z_lin = np.array(z_lin)
    scale = np.abs(z_lin).max(axis=0)
    assert np.all(np.abs(z_sim - z_lin).max(axis=0) <= 2 * angle * scale)
    assert np.abs(z_sim[-1]).max() < 0.05 * np.abs(z_sim[0]).max()  # and it regulates


@pytest.mark.parametrize("coordinates", ["mrp", "quaternion"])
@pytest.mark.parametrize("kind", ["rigid", "flexible"])
@pytest.mark.parametrize("degrees", [10.0, 150.0])
def test_slews_settle_on_the_nonlinear_plant(kind, coordinates, degrees):
    """From rest at the inertial attitude to a target 10° (small) or 150° (large: σ = 0.77,
    far outside the linear range) away about a skew axis: the spacecraft turns the short way
    (never beyond the initial error), ends within 0.01° and settles within 0.5° in 25 s."""
    plant = RigidSpacecraft(J) if kind == "rigid" else flexible()
    law = design(plant, coordinates, angle=np.radians(degrees))
    result = simulate(plant, law, SimConfig(duration=60.0, control_rate=1 / DT), n_cases=1)
    ds = result.dataset
    angle = pointing_angle(ds.attitude.values[0], law.beta_target)
    assert angle.max() <= np.radians(degrees) * (1 + 1e-9)
    assert np.degrees(angle[-1]) < 0.01
    assert float(ds.pointing_settling_time_s[0]) < 25.0
    assert np.all(np.isfinite(ds.torque.values))


def test_a_constant_rate_reference_is_tracked():
    """Linearised about a reference turning at ω_r (u_r = ω_r × Jω_r fed forward), the law
    pulls a spacecraft started 5° and 0.01 rad/s off onto the turning target frame
    β_R(t) = exp(ω_r t) ⊗ β_R(0)."""
    plant = RigidSpacecraft(J)
    rate = np.array([0.02, -0.01, 0.03])
    law = design(plant, "quaternion", rate=rate)
    start = att.principal_rotation_to_quaternion(AXIS, np.radians(5.0))
    x0 = plant.state(start, rate + 0.01)
    result = simulate(
        plant, law, SimConfig(duration=40.0, control_rate=1 / DT), n_cases=1, initial_state=x0
    )
    ds = result.dataset
    t = ds.time.values
    target = np.array([law.target_at(tk) for tk in t])
    angle = pointing_angle(ds.attitude.values[0], target)
    assert angle[0] > np.radians(4.9)
    assert np.degrees(angle[-1]) < 1e-3
    assert np.abs(ds.rate.values[0, -1] - rate).max() < 1e-5
    assert np.abs(law.linearization.torque).max() > 0
    # the run's pointing metric is scored against the turning frame, not its start attitude
    assert ds.final_pointing_error_deg.values[0] == pytest.approx(np.degrees(angle[-1]), abs=1e-9)
    band = SimConfig(duration=40.0, control_rate=1 / DT).settling_band
    assert ds.pointing_settling_time_s.values[0] < 40.0 and band > 0


def test_the_law_commands_all_three_axes_for_a_batch_of_targets():
    """One call on three cases with three targets: per-case errors, torques (3, 3), each
    that of the case alone (to the round-off of its products)."""
    plant = RigidSpacecraft(J)
    lin = linearize_attitude(plant)
    targets = att.principal_rotation_to_quaternion(np.eye(3), np.full(3, np.radians(20.0)))
    law = AttitudeLQG.design(lin, weights(lin), R, QN, RN, DT, beta_target=targets)
    assert law.n_cases == 3
    y = {"attitude": np.tile([1.0, 0, 0, 0], (3, 1)), "rate": np.zeros((3, 3))}
    u, _ = law(0.0, y, law.initial_state(3))
    assert u.shape == (3, 3) and np.all(np.abs(u) > 0)
    for i in range(3):
        alone = AttitudeLQG(lin, law.K, law.L, DT, targets[i])
        ui, _ = alone(0.0, {k: v[i : i + 1] for k, v in y.items()}, alone.initial_state(1))
        # the same products, perhaps by another BLAS kernel: u = −K C⁺ y, C⁺ = [I₆; 0], |y| <= 1
        # (MRPs, at rest): 6-term sums of terms below max|K|, apart by at most 6 ε each
        assert np.abs(ui[0] - u[i]).max() <= 6 * 6 * EPS * np.abs(law.K).max()


@pytest.mark.parametrize(
    "call, field",
    [
        (
            lambda lin: AttitudeLQG(object(), np.zeros((3, 6)), np.zeros((6, 6)), DT),
            "linearization",
        ),
        (lambda lin: AttitudeLQG(lin, np.zeros((1, 6)), np.zeros((6, 6)), DT), "K"),
        (lambda lin: AttitudeLQG(lin, np.zeros((3, 6)), np.zeros((6, 3)), DT), "L"),
        (lambda lin: AttitudeLQG(lin, np.zeros((3, 6)), np.zeros((6, 6)), -1.0), "dt"),
        (
            lambda lin: AttitudeLQG(lin, np.zeros((3, 6)), np.zeros((6, 6)), DT, [1.0, 1, 0, 0]),
            "beta_target",
        ),
        (lambda lin: AttitudeLQG.design((1, 2), np.eye(6), R, QN, RN, DT), "linearization"),
    ],
)
def test_bad_input_is_named(call, field):
    lin = linearize_attitude(RigidSpacecraft(J))
    with pytest.raises(FieldError) as err:
        call(lin)
    assert err.value.field == field


def test_a_call_off_the_design_period_is_refused():
    law = design(RigidSpacecraft(J))
    y = {"attitude": np.array([[1.0, 0, 0, 0]]), "rate": np.zeros((1, 3))}
    _, state = law(0.0, y, law.initial_state(1))
    with pytest.raises(FieldError) as err:
        law(0.25, y, state)
    assert err.value.field == "dt"
