"""The planned slew (flexsat.design.planned_slew): the QP against a closed form and its KKT
conditions, the LP's least peak, the terminal state on the engine, the feedback on a planned
modal motion, the refusals; and, slow, the EPS 6 s goals with torquers alone on the 45-mode
truth.

Cheap setup: the EPS on its first 10 modes (truth = design model), 1 rad about each axis in
6 s, 50 Hz control.
"""

from __future__ import annotations

import numpy as np
import pytest

from flexsat.cases.eps import eps
from flexsat.control import NominalTorque, PerturbationFeedback, perturbation_design
from flexsat.design.planned_slew import PlannedTrajectory, plan_slew, planned_slew
from flexsat.design.slew_shaping import terminal_map
from flexsat.design.slew_weights import SlewEvaluation, SlewWeights
from flexsat.dynamics.attitude import euler123_to_quaternion
from flexsat.maneuvers import three_axis_slew
from flexsat.sim import SimConfig, simulate

N_BASIS = 12


@pytest.fixture(scope="module")
def setup():
    truth = eps().plant(n_modes=10)
    nominal = three_axis_slew(truth.inertia, euler123_to_quaternion(np.ones(3)), 6.0, 5.0)
    config = SimConfig(duration=11.5, control_rate=50.0)
    terminal = terminal_map(truth, truth, nominal, config, N_BASIS)
    return truth, nominal, config, terminal


def _energy_by_quadrature(plan, T):
    t = np.linspace(0.0, T, 20001)
    dtau = plan.shaped.correction(t) @ plan.shaped.inertia.T
    f = np.sum(dtau**2, axis=1)
    return float(np.sum(0.5 * (f[1:] + f[:-1])) * (t[1] - t[0]))


def test_the_unlimited_energy_optimum_is_the_weighted_minimum_norm_solution(setup):
    truth, nominal, config, terminal = setup
    plan = plan_slew(terminal, nominal)
    # independent: the KKT system [[H, Xᵀ], [X, 0]] [c; μ] = [0; r] by least squares (X is rank
    # deficient, so the system is singular but consistent)
    T, J = terminal.duration, terminal.inertia
    H = 0.5 * T * np.kron(J.T @ J, np.eye(N_BASIS))
    X, r = terminal.X, terminal.target
    k = X.shape[0]
    # (H scaled to unit norm: the same minimiser, one scale for the rank cut-off)
    kkt = np.block([[2 * H / np.linalg.norm(H), X.T], [X, np.zeros((k, k))]])
    sol, *_ = np.linalg.lstsq(kkt, np.concatenate([np.zeros(H.shape[0]), r]), rcond=1e-13)
    c = sol[: H.shape[0]]
    # both solve the same convex problem; the tolerance is cond of the reduced Hessian (~1e2)
    # times the rank cut-off 1e-10 of the SVD of X
    np.testing.assert_allclose(
        plan.shaped.coefficients.reshape(-1), c, rtol=0, atol=1e-7 * abs(c).max()
    )
    assert plan.terminal_residual < 1e-10  # X c = r to rounding
    assert plan.kkt_residual < 1e-12  # ∇E on the null space of X: zero to rounding
    # E = T/2 Σ cⱼᵀJᵀJcⱼ (orthogonal sines) against the trapezoid rule on 20,000 intervals
    # (error h²/12 ‖f''‖ T: below 1e-6 relative for sines up to 12π/T)
    assert plan.energy == pytest.approx(_energy_by_quadrature(plan, T), rel=1e-6)


def test_a_binding_torque_limit_holds_and_the_kkt_conditions_certify_the_optimum(setup):
    truth, nominal, config, terminal = setup
    free = plan_slew(terminal, nominal)
    limit = 0.8 * free.peak_torques.max()
    plan = plan_slew(terminal, nominal, torque_limit=limit)
    assert plan.feasible and plan.active >= 1
    assert np.all(plan.multipliers >= 0.0)
    # a convex QP: KKT with λ ≥ 0 is optimality. SLSQP's ftol 1e-12 on an objective scaled
    # to O(1) leaves ∇E resolved to ~1e-6 relative
    assert plan.kkt_residual < 1e-5
    assert plan.terminal_residual < 1e-10
    assert plan.energy > free.energy
    # the limit is imposed at samples: between them the module's bound 1 - cos(πT/(n_b(n_s-1)))
    n_s = 16 * N_BASIS + 1
    assert plan.peak_torques.max() <= limit * (1.0 + (1.0 - np.cos(np.pi / (n_s - 1) * 16)))


def test_an_unreachable_limit_reports_the_least_peak(setup):
    truth, nominal, config, terminal = setup
    least = plan_slew(terminal, nominal, objective="peak")
    s = least.least_peak  # N m: no limit given
    assert least.peak_torques.max() <= s * 1.02  # between the samples (module bound, 1.9 %)
    plan = plan_slew(terminal, nominal, torque_limit=0.9 * s)
    assert not plan.feasible
    # the least peak in units of the limit: the same LP scaled (HiGHS's tolerance 1e-7)
    assert plan.least_peak == pytest.approx(1.0 / 0.9, rel=1e-6)
    with_room = plan_slew(terminal, nominal, torque_limit=1.05 * s)
    assert with_room.feasible and with_room.active >= 1


def test_the_planned_torque_brings_the_design_modes_to_rest_on_the_engine(setup):
    truth, nominal, config, terminal = setup
    plan = planned_slew(truth, truth, nominal, config, N_BASIS)
    # Newton's method on the terminal conditions with an approximate Jacobian (RK4 of the
    # linearisation on the control grid against the engine's integration): quadratic until
    # that Jacobian error dominates, then linear at its rate; measured reductions 9e-4, 6e-3,
    # 8e-4
    r = np.asarray(plan.iterates) / plan.iterates[0]
    assert r[-1] < 1e-6 and np.all(r[1:] / r[:-1] < 2e-2)

    def terminal_state(law):
        run = simulate(truth, law, config, n_cases=1, record_states=True)
        x = run.dataset["state"].isel(case=0).values[int(round(6.0 / config.dt))]
        return x, truth.output("elastic", x)

    _, open_loop = terminal_state(NominalTorque(nominal, config.dt))
    x, elastic = terminal_state(NominalTorque(plan, config.dt))
    # the modes at rest at T to the stopping tolerance 1e-6 of the iteration (the run is the
    # one the iteration measured, on the same grid: the linearisation's integration error
    # enters only through the convergence, not the check)
    assert np.linalg.norm(elastic) < 1e-5 * np.linalg.norm(open_loop)
    np.testing.assert_allclose(x[4:7], 0.0, atol=1e-6)  # at rest, rad/s


def test_the_feedback_on_a_planned_modal_motion_leaves_the_plan_alone(setup):
    truth, nominal, config, terminal = setup
    plan = planned_slew(truth, truth, nominal, config, N_BASIS, iterations=2)
    trajectory = PlannedTrajectory(plan, truth, config)
    q, d = SlewWeights(attitude=1000, rate=1000, modes=1, torque=1000).diagonals(10, 0)
    design = perturbation_design(truth, trajectory, np.diag(q), np.diag(d), 5.0, 0.0, 7)
    law = design.controller(config.dt, "none", plant=truth)
    evaluation = SlewEvaluation(truth, truth, nominal, config, n_points=7)
    alone = evaluation.run(NominalTorque(plan, config.dt))
    closed = evaluation.run(law)
    # on the plant it was planned on the plan is flown to its integration error: the law's
    # perturbation torque stays a small fraction of the correction the plan makes
    correction = np.abs(
        plan.torque(np.linspace(0, 6, 601)) - nominal.torque(np.linspace(0, 6, 601))
    )
    rebuilt = PerturbationFeedback.from_tables(law.tables(), config.dt, law.writes, 10, 10)
    np.testing.assert_array_equal(
        rebuilt.tables()["elastic_reference"], law.tables()["elastic_reference"]
    )
    assert closed["goals_met"] and alone["goals_met"]
    assert abs(closed["angle_error_mrad"] - alone["angle_error_mrad"]) < 0.1
    assert (
        closed["peak_torque_perturbation_Nm"]
        < alone["peak_torque_perturbation_Nm"] + 0.05 * correction.max()
    )
    # without the reference the same law fights the planned modal motion
    law_plain = perturbation_design(truth, nominal, np.diag(q), np.diag(d), 5.0, 0.0, 7)
    fought = evaluation.run(law_plain.controller(config.dt, "none", plant=truth))
    assert not fought["goals_met"]


@pytest.mark.parametrize(
    "kwargs, field",
    [
        ({"objective": "fastest"}, "objective"),
        ({"torque_limit": -1.0}, "torque_limit"),
        ({"torque_limit": [1.0, np.nan, 1.0]}, "torque_limit"),
        ({"n_samples": 1}, "n_samples"),
        ({"start": np.zeros((3, 2))}, "start"),
    ],
)
def test_bad_input_is_named(setup, kwargs, field):
    truth, nominal, config, terminal = setup
    with pytest.raises(ValueError, match=rf"^{field}:"):
        plan_slew(terminal, nominal, **kwargs)


@pytest.mark.parametrize(
    "kwargs, field",
    [
        ({"iterations": -1}, "iterations"),
        ({"tolerance": 0.0}, "tolerance"),
        ({"n_basis": 0}, "n_basis"),
    ],
)
def test_bad_iteration_settings_are_named(setup, kwargs, field):
    truth, nominal, config, terminal = setup
    with pytest.raises(ValueError, match=rf"^{field}:"):
        planned_slew(truth, truth, nominal, config, **kwargs)


@pytest.mark.slow
@pytest.mark.parametrize("duration, omega_b", [(6.0, 5.0), (10.0, 2.5)], ids=["6s", "10s"])
def test_the_eps_goals_with_torquers_alone_within_the_nominal_peak(duration, omega_b):
    # the 45-mode truth, a 10-mode design model, 50 Hz: the torque kept within the nominal
    # maneuver's own peak (34.4 kN m about z at 6 s, 11.6 at 10 s) still meets 3 % and 10:1
    # (docs/eps.md; cases D and A with the feedback miss them)
    truth = eps().plant(n_modes=45)
    design = truth.reduced(10)
    nominal = three_axis_slew(truth.inertia, euler123_to_quaternion(np.ones(3)), duration, omega_b)
    # the deflection judged over 2 s past 1.25 T (half a period of the first mode, 0.25 Hz)
    config = SimConfig(duration=1.25 * duration + 2.0, control_rate=50.0)
    limit = float(np.abs(nominal.torque(np.linspace(0, duration, 601))).max())
    plan = planned_slew(truth, design, nominal, config, 20, torque_limit=limit, iterations=2)
    assert plan.feasible
    m = SlewEvaluation(truth, design, nominal, config).run(NominalTorque(plan, config.dt))
    assert m["angle_goal_met"] and m["deflection_goal_met"], m
    assert max(m[f"peak_torque_{a}_Nm"] for a in "xyz") <= limit * 1.02


# -- point forces planned beside the torque ----------------------------------------------------


@pytest.fixture(scope="module")
def forces_setup(setup):
    truth, nominal, config, _ = setup
    channels = tuple(c.name for c in truth.inputs[1:])  # the EPS's 7 force actuators
    return channels, terminal_map(truth, truth, nominal, config, N_BASIS, forces=channels)


def test_the_force_columns_of_the_terminal_map_are_the_engine_response(setup, forces_setup):
    # independent: the plant flown on the engine with the nominal torque plus one force sine
    # of 1 N; the change of the terminal modal state against X's column. The response is
    # linear in the force (the forces enter the plant linearly, their moment changes the
    # path only to second order: 1 N against 34 kN m), so the difference is the RK4 error of
    # the linearisation on the 50 Hz grid against the engine's exact modal propagation
    # (measured 2e-4 relative)
    truth, nominal, config, terminal = setup
    channels, fmap = forces_setup
    assert fmap.force_channels == channels and fmap.X.shape[1] == (3 + 7) * N_BASIS
    np.testing.assert_array_equal(fmap.X[:, : 3 * N_BASIS], terminal.X)  # the torque columns
    d = np.zeros((7, N_BASIS))
    d[3, 1] = 1.0  # 66Z, second sine
    from flexsat.design.slew_shaping import ShapedSlew

    pushed = ShapedSlew(nominal, np.zeros((3, N_BASIS)), truth.inertia, 0.0, channels, d)
    n_T = int(round(6.0 / config.dt))

    def elastic_at_T(law):
        run = simulate(truth, law, config, n_cases=1, record_states=True)
        return truth.output("elastic", run.dataset["state"].isel(case=0).values[n_T])

    change = elastic_at_T(NominalTorque(pushed, config.dt)) - elastic_at_T(
        NominalTorque(nominal, config.dt)
    )
    column = fmap.X[6:, 3 * N_BASIS + 3 * N_BASIS + 1]
    np.testing.assert_allclose(change, column, rtol=0, atol=2e-3 * np.abs(column).max())


def test_planned_forces_the_weighted_minimum_energy_and_less_torque(setup, forces_setup):
    truth, nominal, config, terminal = setup
    channels, fmap = forces_setup
    alone = plan_slew(terminal, nominal)
    w = 0.5
    plan = plan_slew(fmap, nominal, force_weight=w)
    # independent: with H = RᵀR (Cholesky), y = R c is the minimum-norm solution of
    # X R⁻¹ y = r (lstsq), whatever the scales of torque and force
    T, J, n_b = fmap.duration, fmap.inertia, N_BASIS
    H = (
        0.5
        * T
        * np.block(
            [
                [np.kron(J.T @ J, np.eye(n_b)), np.zeros((3 * n_b, 7 * n_b))],
                [np.zeros((7 * n_b, 3 * n_b)), w * np.eye(7 * n_b)],
            ]
        )
    )
    R = np.linalg.cholesky(H).T
    y, *_ = np.linalg.lstsq(np.linalg.solve(R.T, fmap.X.T).T, fmap.target, rcond=1e-10)
    c = np.concatenate(
        [plan.shaped.coefficients.reshape(-1), plan.shaped.force_coefficients.reshape(-1)]
    )
    # the scaled map's condition number (5e4 measured) times the module's rank cut-off 1e-10
    # on the unscaled X (smallest kept singular value 6e-8 of the largest): measured 5e-7
    np.testing.assert_allclose(c, np.linalg.solve(R, y), rtol=0, atol=1e-5 * abs(c).max())
    assert plan.terminal_residual < 1e-9
    # E = ∫ ‖J v‖² + w ‖F‖² dt against the trapezoid rule on 20,000 intervals (as above)
    t = np.linspace(0.0, T, 20001)
    f = np.sum((plan.shaped.correction(t) @ J.T) ** 2, 1) + w * np.sum(plan.forces(t) ** 2, 1)
    assert plan.energy == pytest.approx(float(np.sum(0.5 * (f[1:] + f[:-1])) * t[1]), rel=1e-6)
    # zero forces are feasible, so the optimum with forces costs at most the torquers' alone,
    # and the forces take over most of the torque correction
    assert plan.energy < alone.energy
    assert plan.torque_energy < 0.2 * alone.torque_energy
    # a dearer force buys less force and more torque
    dear = plan_slew(fmap, nominal, force_weight=50 * w)
    assert dear.peak_forces.max() < plan.peak_forces.max()
    assert dear.torque_energy > plan.torque_energy


def test_a_binding_force_limit_holds_with_the_kkt_conditions(setup, forces_setup):
    truth, nominal, config, terminal = setup
    _, fmap = forces_setup
    free = plan_slew(fmap, nominal)
    limit = 0.5 * free.peak_forces.max()
    plan = plan_slew(fmap, nominal, force_limit=limit)
    assert plan.feasible and plan.active >= 1 and np.all(plan.multipliers >= 0)
    # SLSQP's point polished on its active set (the KKT system solved): rounding
    assert plan.kkt_residual < 1e-8
    assert plan.terminal_residual < 1e-9
    n_s = 16 * N_BASIS + 1  # the between-samples bound of the module docstring
    assert plan.peak_forces.max() <= limit * (1.0 + (1.0 - np.cos(np.pi / (n_s - 1) * 16)))
    assert plan.energy > free.energy
    # least peak relative to both limits: the LP's optimum scales with the limits
    peak = plan_slew(fmap, nominal, "peak", torque_limit=4e4, force_limit=1e3)
    half = plan_slew(fmap, nominal, "peak", torque_limit=2e4, force_limit=5e2)
    assert half.least_peak == pytest.approx(2 * peak.least_peak, rel=1e-6)  # HiGHS 1e-7


def test_planned_forces_bring_the_modes_to_rest_on_the_engine_and_under_the_feedback(setup):
    truth, nominal, config, _ = setup
    channels = ("force_66Z", "force_60Z")
    plan = planned_slew(truth, truth, nominal, config, N_BASIS, iterations=6, forces=channels)
    assert plan.force_channels == channels
    r = np.asarray(plan.iterates) / plan.iterates[0]
    assert r[-1] < 1e-6  # the stopping tolerance, reached within the iterations

    law = NominalTorque(plan, config.dt)
    assert law.writes == ("torque",) + channels
    run = simulate(truth, law, config, n_cases=1, record_states=True)
    n_T = int(round(6.0 / config.dt))
    open_loop = simulate(
        truth, NominalTorque(nominal, config.dt), config, n_cases=1, record_states=True
    )
    el = truth.output("elastic", run.dataset["state"].isel(case=0).values[n_T])
    el0 = truth.output("elastic", open_loop.dataset["state"].isel(case=0).values[n_T])
    assert np.linalg.norm(el) < 1e-5 * np.linalg.norm(el0)  # the stopping tolerance, as above
    # the forces flown are the plan's, held at their interval means: the midpoint value to
    # h²F''/24, F'' ≤ (12π/6)² F at the 12th sine: 7e-4 of the peak at 50 Hz
    t = run.dataset["time"].values
    inside = (t > 0.5) & (t < 5.5)
    flown = run.dataset["force_66Z"].isel(case=0).values
    np.testing.assert_allclose(
        flown[inside],
        plan.forces(t[inside] + 0.5 * config.dt)[:, 0],
        rtol=0,
        atol=1e-3 * plan.peak_forces.max(),
    )

    # the feedback on top adds its force perturbations to the plan's
    trajectory = PlannedTrajectory(plan, truth, config)
    q, d = SlewWeights(attitude=1000, rate=1000, modes=1, torque=1000, force=1e-6).diagonals(10, 2)
    design = perturbation_design(
        truth, trajectory, np.diag(q), np.diag(d), 5.0, 0.0, 7, forces=list(channels)
    )
    closed_law = design.controller(config.dt, "none", plant=truth)
    assert np.any(closed_law.tables()["force_reference"])
    rebuilt = PerturbationFeedback.from_tables(
        closed_law.tables(), config.dt, closed_law.writes, 10, 10
    )
    np.testing.assert_array_equal(
        rebuilt.tables()["force_reference"], closed_law.tables()["force_reference"]
    )
    # the compiled loop's linear form carries the planned forces as the Python law does:
    # measurements along the plan, perturbed; agreement to rounding of the largest command
    from flexsat.control.linear_form import run_controller, run_linear_law

    times = config.dt * np.arange(int(round(6.5 / config.dt)))
    rng = np.random.default_rng(23)
    Y = np.concatenate(
        [trajectory.beta(times), trajectory.omega(times), trajectory.elastic(times)], axis=-1
    )[:, None, :] + 1e-4 * rng.normal(size=(times.size, 1, 4 + 3 + 20))
    form = closed_law.linear_form(config.dt, times, 1)
    slow = run_controller(closed_law, times, Y, (4, 3, 20), (3, 1, 1))
    fast = run_linear_law(form, Y)
    np.testing.assert_allclose(fast, slow, rtol=0, atol=1e-9 * np.abs(slow).max())
    assert np.abs(slow[:, 0, 3:]).max() > 0.5 * plan.peak_forces.max()  # the plan's forces

    evaluation = SlewEvaluation(truth, truth, nominal, config, n_points=7)
    closed = evaluation.run(closed_law)
    alone = evaluation.run(law)
    assert closed["goals_met"] and alone["goals_met"]
    assert abs(closed["angle_error_mrad"] - alone["angle_error_mrad"]) < 0.1
    # a law that does not write the planned forces is refused
    torque_only = perturbation_design(truth, trajectory, np.diag(q[:]), np.diag(d[:3]), 5.0, 0.0, 7)
    with pytest.raises(ValueError, match="^forces:.*force_66Z"):
        torque_only.controller(config.dt, "none", plant=truth)


@pytest.mark.parametrize(
    "kwargs, field",
    [
        ({"force_limit": -1.0}, "force_limit"),
        ({"force_weight": 0.0}, "force_weight"),
        ({"objective": "peak", "torque_limit": 1e4}, "force_limit"),
        ({"objective": "peak", "force_limit": 1e3}, "torque_limit"),
        ({"start": np.zeros((3, N_BASIS))}, "start"),
    ],
)
def test_bad_force_input_is_named(setup, forces_setup, kwargs, field):
    truth, nominal, config, terminal = setup
    with pytest.raises(ValueError, match=rf"^{field}:"):
        plan_slew(forces_setup[1], nominal, **kwargs)


def test_a_force_limit_without_forces_is_refused(setup):
    truth, nominal, config, terminal = setup
    with pytest.raises(ValueError, match=r"^force_limit:.*without forces"):
        plan_slew(terminal, nominal, force_limit=100.0)
