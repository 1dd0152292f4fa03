"""LQG compensator: stable closed loops (NPS paper weights), the exact ZOH estimator, the step /
regulation-offset equivalence of the slew command, the Controller interface, and a slew of the
TAMU plant through the simulator."""

import numpy as np
import pytest

from flexsat.cases import nps
from flexsat.control import LQGController, lqr
from flexsat.control.lqg import zoh
from flexsat.dynamics.second_order import SecondOrderModel
from flexsat.sim import simulate

RN = np.diag([1e-7, 5e-6])  # Eq. 44


@pytest.fixture(scope="module")
def nps_plant():
    sys = nps().to_statespace()
    w = np.full(14, 0.1)
    w[[0, 7]] = 1.0
    w[[1, 2, 8, 9]] = 0.5
    return sys.A, sys.B, sys.C, np.diag(w)


def run(law, A, B, C, x0, n_steps, n_cases=1):
    """Exact sampled-data loop: plant propagated by ZOH, law called every dt."""
    Phi, Gam = zoh(A, B, law.dt)
    x = np.broadcast_to(x0, (n_cases, A.shape[0])).copy()
    state = law.initial_state(n_cases)
    xs, us, xh = [], [], []
    for k in range(n_steps):
        y = C @ x.T
        u, state_next = law(k * law.dt, {"theta": y[0], "theta_dot": y[1]}, state)
        xs.append(x.copy())
        us.append(np.array(u))
        xh.append(state["x_hat"].copy() if k else np.full_like(x, np.nan))
        x = x @ Phi.T + np.multiply.outer(u, Gam[:, 0])
        state = state_next
    return np.array(xs), np.array(us), np.array(xh)


def test_nps_lqg_closed_loop_is_stable(nps_plant):
    """Paper weights (L375), Q_xx = B (0.1) Bᵀ (Eq. 43), Q_yy (Eq. 44): the continuous 28-state
    loop has the separation eigenvalues and the sampled-data loop is stable."""
    A, B, C, Q = nps_plant
    law = LQGController.design((A, B, C), Q, 7.0, 0.1, RN, dt=0.05)
    cont = np.linalg.eigvals(law.continuous_closed_loop())
    assert cont.real.max() < 0
    sep = np.concatenate([law.regulator.poles, law.filter.poles])
    assert max(np.abs(sep - c).min() for c in cont) < 1e-6 * np.abs(sep).max()
    assert np.abs(np.linalg.eigvals(law.closed_loop_matrix())).max() < 1
    assert law.regulator.gain[0, 0] == pytest.approx(np.sqrt(1 / 7), rel=1e-9)


def test_discrete_gains_closed_loop_is_stable_and_close(nps_plant):
    A, B, C, Q = nps_plant
    cont = LQGController.design((A, B, C), Q, 7.0, 0.1, RN, dt=0.01)
    disc = LQGController.design((A, B, C), Q, 7.0, 0.1, RN, dt=0.01, gains="discrete")
    assert np.abs(np.linalg.eigvals(disc.closed_loop_matrix())).max() < 1
    assert np.abs(disc.K - cont.K).max() < 0.02 * np.abs(cont.K).max()


def test_30_degree_slew_converges_and_estimator_tracks(nps_plant):
    A, B, C, Q = nps_plant
    target = np.radians(30.0)
    law = LQGController.design((A, B, C), Q, 7.0, 0.1, RN, dt=0.05, target=target)
    xs, us, xh = run(law, A, B, C, np.zeros(14), 2400)  # 120 s
    assert abs(xs[-1, 0, 0] - target) < 1e-3 * target
    assert abs(us[0, 0] - law.K[0, 0] * target) < 1e-12  # step: u0 = K_θ · 30°
    assert np.abs(xh[-1, 0] - xs[-1, 0]).max() < 1e-3 * target


def test_step_command_equals_regulation_offset(nps_plant):
    """The two readings of the paper's 30° LQG slew coincide for the free hub: start at 0 and
    step the reference to 30°, or start at −30° and regulate to 0."""
    A, B, C, Q = nps_plant
    th = np.radians(30.0)
    step = LQGController.design((A, B, C), Q, 7.0, 0.1, RN, dt=0.05, target=th)
    offset = LQGController.design((A, B, C), Q, 7.0, 0.1, RN, dt=0.05, target=0.0)
    x0 = np.zeros(14)
    x0[0] = -th
    xs1, us1, _ = run(step, A, B, C, np.zeros(14), 400)
    xs2, us2, _ = run(offset, A, B, C, x0, 400)
    np.testing.assert_allclose(us1, us2, atol=1e-12)
    np.testing.assert_allclose(xs1[:, 0, 0] - th, xs2[:, 0, 0], atol=1e-12)


def test_estimator_propagation_is_exact_zoh(nps_plant):
    """With L = 0 and the true initial state the estimate equals the plant state: the
    estimator is the plant propagated exactly under the held torque."""
    A, B, C, Q = nps_plant
    K = lqr(A, B, Q, 7.0).gain
    x0 = np.zeros(14)
    x0[[0, 1, 8]] = [0.1, 0.02, -0.01]
    law = LQGController(A, B, C, K, np.zeros((14, 2)), dt=0.05, target=0.3, initial_estimate=x0)
    xs, _, xh = run(law, A, B, C, x0, 200)
    assert np.abs(xh[1:] - xs[1:]).max() < 1e-12


def test_batched_cases_match_single_runs(nps_plant):
    A, B, C, Q = nps_plant
    targets = np.radians([10.0, 20.0, 30.0])
    batch = LQGController.design((A, B, C), Q, 7.0, 0.1, RN, dt=0.05, target=targets)
    assert batch.n_cases == 3
    state = batch.initial_state(3)
    assert state["x_hat"].shape == (3, 14) and not state["started"].any()
    xs, us, _ = run(batch, A, B, C, np.zeros(14), 100, n_cases=3)
    for i, th in enumerate(targets):
        single = LQGController.design((A, B, C), Q, 7.0, 0.1, RN, dt=0.05, target=th)
        _, u1, _ = run(single, A, B, C, np.zeros(14), 100)
        np.testing.assert_allclose(us[:, i], u1[:, 0], rtol=1e-12, atol=1e-15)


def test_initial_estimate_from_first_measurement(nps_plant):
    A, B, C, Q = nps_plant
    law = LQGController.design((A, B, C), Q, 7.0, 0.1, RN, dt=0.05)
    u, state = law(
        0.0, {"theta": np.array([0.2]), "theta_dot": np.array([0.01])}, law.initial_state(1)
    )
    x0 = np.zeros(14)
    x0[[0, 7]] = [0.2, 0.01]
    np.testing.assert_allclose(u, -law.K[0] @ x0)
    assert state["started"].all() and state["t"][0] == 0.0


def test_slew_of_the_tamu_plant_through_the_simulator(tamu_case, tamu_model):
    """Design on SecondOrderModel.from_hub_appendage, run by flexsat.sim.simulate at 75 Hz:
    a 40° step and a shaped-reference slew both end on target."""
    som = SecondOrderModel.from_hub_appendage(tamu_model)
    n, k = som.n_states, som.n_dof
    Q = np.eye(n)
    Q[0, 0], Q[k, k] = 100.0, 10.0
    cfg = tamu_case.sim_config(duration=15.0, friction=False, noise=False)
    step = LQGController.design(
        som, Q, 1.0, 1.0, np.diag([1e-8, 1e-6]), dt=cfg.dt, target=tamu_case.angle
    )
    r = simulate(tamu_model, step, cfg)
    assert abs(r.dataset.theta.values[0, -1] - tamu_case.angle) < np.radians(0.05)
    ref = tamu_case.reference()
    track = LQGController.design(som, Q, 1.0, 1.0, np.diag([1e-8, 1e-6]), dt=cfg.dt, reference=ref)
    ds = simulate(tamu_model, track, cfg).dataset
    assert abs(ds.theta.values[0, -1] - tamu_case.angle) < np.radians(0.05)
    assert np.abs(ds.theta.values[0] - ds.theta_ref.values[0]).max() < np.radians(2.0)
    # tracking the shaped reference excites the appendages less than the step
    assert (
        np.abs(ds.tip_deflection.values[0]).max() < np.abs(r.dataset.tip_deflection.values[0]).max()
    )


def test_closed_loop_matrix_of_a_given_plant(nps_plant):
    """The design plant given explicitly yields the default matrix (the same ZOH and output
    matrix, so bit for bit); a plant given without its output matrix is refused naming C."""
    A, B, C, Q = nps_plant
    law = LQGController.design((A, B, C), Q, 7.0, 0.1, RN, dt=0.05)
    np.testing.assert_array_equal(law.closed_loop_matrix(A, B, C), law.closed_loop_matrix())
    with pytest.raises(ValueError, match="^C: give A, B and C of the plant together"):
        law.closed_loop_matrix(A, B)


# ------------------------------------------------------------------------------------------------
# bad inputs
def test_wrong_sample_period_is_refused(nps_plant):
    A, B, C, Q = nps_plant
    law = LQGController.design((A, B, C), Q, 7.0, 0.1, RN, dt=0.05)
    y = {"theta": np.zeros(1), "theta_dot": np.zeros(1)}
    _, state = law(0.0, y, law.initial_state(1))
    with pytest.raises(ValueError, match="dt: the law was built for a sample period of 0.05"):
        law(0.1, y, state)


def test_missing_measurement_key(nps_plant):
    A, B, C, Q = nps_plant
    law = LQGController.design((A, B, C), Q, 7.0, 0.1, RN, dt=0.05, measurements=("theta", "gyro"))
    with pytest.raises(ValueError, match="measurements: key 'gyro'"):
        law(0.0, {"theta": np.zeros(1), "theta_dot": np.zeros(1)}, law.initial_state(1))


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(measurements=("theta",)), "measurements: give 2 measurement keys"),
        (dict(reference_states=(0, 0)), "reference_states: must be two distinct"),
        (dict(gains="hybrid"), "gains: must be"),
        (dict(dt=0.0), "dt: must be > 0"),
        (dict(initial_estimate=np.zeros(3)), "initial_estimate: must have shape"),
        (dict(initial_estimate="zero"), "initial_estimate: must be 'measurement'"),
        (dict(K=np.ones((1, 13))), "K: must have shape"),
        (dict(L=np.ones((14, 3))), "L: must have shape"),
        (dict(B=np.ones((14, 2))), "B: the controller interface commands one torque"),
    ],
)
def test_bad_construction(nps_plant, kwargs, match):
    A, B, C, Q = nps_plant
    args = dict(A=A, B=B, C=C, K=np.ones((1, 14)), L=np.ones((14, 2)), dt=0.05)
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        LQGController(**args)
