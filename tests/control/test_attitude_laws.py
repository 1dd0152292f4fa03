"""Three-axis attitude laws (issue 10 acceptance), closed on the rigid-body propagator with ideal
sensors: along the simulated motion the Gibbs Lyapunov law of Att. 3 §II dissipates U at exactly
−Σ k_i ω_i² and the MRP PD law dissipates V at −ωᵀPω (pointwise to round-off, integrated to the
integrator's fourth-order error), both functions never increase, and from a 170° principal
rotation with a nonzero rate both laws bring the body to the target; batching and bad input."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from flexsat.control import Controller, GibbsLyapunovLaw, MRPLaw, QuaternionPD
from flexsat.control.attitude_laws import error_quaternion
from flexsat.dynamics import attitude as att
from flexsat.dynamics import rigid_body as rb
from flexsat.units import ureg
from rkmk4_reference import propagate

EPS = np.finfo(float).eps
# asymmetric body with products of inertia (kg·m²): the laws need no principal axes
INERTIA = np.array([[10.0, 0.5, -0.3], [0.5, 15.0, 0.8], [-0.3, 0.8, 20.0]])
TARGET = att.principal_rotation_to_quaternion([0.0, 0.6, 0.8], 0.7)
# 170° principal rotation from the target about a skew axis, and a rate of ~0.1 rad/s
BETA0 = att.quaternion_multiply(
    att.principal_rotation_to_quaternion([1 / 3, 2 / 3, 2 / 3], np.deg2rad(170.0)), TARGET
)
W0 = np.array([0.05, -0.1, 0.08])
# gains placing the linearised closed loop I θ'' + k θ' + (A/2) θ = 0 (q ≈ θ/2) and
# I θ'' + P θ' + (K/4) θ = 0 (σ ≈ θ/4) at the same poles: slowest decay rate 0.1755 /s
LAWS = {
    "gibbs": GibbsLyapunovLaw(k=12.0, A=3.6, beta_target=TARGET),
    "mrp": MRPLaw(K=7.2, P=12.0, beta_target=TARGET),
}
T_END = 60.0


def as_torque(law):
    """The law through its controller interface, as the torque(t, β, ω) of the propagator."""
    return lambda t, beta, w: law(t, {"attitude": beta, "rate": w}, {})[0]


def graded_grid(h, t_end, h0=1e-4, growth=1.05):
    """Steps growing geometrically from h0 to h. Near 170° the Gibbs feedback A q (1 + qᵀq) is
    ~1500 A and its stiffness ~25000 A / k (/s): the first steps must resolve that transient."""
    t, step = [0.0], h0
    while t[-1] < t_end:
        t.append(t[-1] + step)
        step = min(step * growth, h)
    return np.array(t)


def rate_gains(law):
    return np.broadcast_to(law.k if isinstance(law, GibbsLyapunovLaw) else law.P, (3,))


def energy_balance_residual(law, t, beta, w):
    """U(t) − U(0) − ∫₀ᵗ f dt, f = −Σ g_i ω_i², along a trajectory (g the rate gains); the
    integral by the corrected trapezoid rule h/2 (f0 + f1) + h²/12 (f0' − f1') (O(h⁴) like the
    propagator), with f' = −2 Σ g_i ω_i ω̇_i and ω̇ from Euler's equations under the law's torque."""
    U = law.lyapunov(beta, w, INERTIA)
    g = rate_gains(law)
    f = law.lyapunov_rate(w)
    fd = -2 * np.sum(g * w * rb.euler_rates(w, INERTIA, law.torque(beta, w)), axis=-1)
    h = np.diff(t)
    steps = h / 2 * (f[1:] + f[:-1]) + h**2 / 12 * (fd[:-1] - fd[1:])
    return U - U[0] - np.concatenate([[0.0], np.cumsum(steps)]), U


@pytest.fixture(scope="module", params=list(LAWS))
def closed_loop(request):
    law = LAWS[request.param]
    t = graded_grid(0.04, T_END)
    beta, w = propagate(BETA0, W0, INERTIA, t, as_torque(law))
    return law, t, beta, w


@pytest.mark.numerics
def test_lyapunov_rate_is_minus_the_rate_gain_dissipation_pointwise(closed_loop):
    # U' from the chain rule on the simulated states, with the Gibbs / MRP kinematics of
    # flexsat.dynamics.attitude and Euler's equations: an algebraic identity, so round-off
    # bounds it (a few eps times the largest term |ω||u|)
    law, t, beta, w = closed_loop
    u = law.torque(beta, w)
    wdot = rb.euler_rates(w, INERTIA, u)
    kinetic = np.einsum("...i,ij,...j->...", w, INERTIA, wdot)
    if isinstance(law, GibbsLyapunovLaw):
        q = law.gibbs(beta)
        potential = 2 * law.A * np.sum(q * att.gibbs_rate(q, w), axis=-1)
    else:
        s = law.mrp(beta)
        potential = 4 * law.K * np.sum(s * att.mrp_rate(s, w), -1) / (1 + np.sum(s * s, -1))
    scale = np.linalg.norm(w, axis=-1) * np.linalg.norm(u, axis=-1) + np.abs(law.lyapunov_rate(w))
    err = np.abs(kinetic + potential - law.lyapunov_rate(w))
    assert np.all(err <= 64 * EPS * scale)  # measured ≤ 2 eps·scale


@pytest.mark.numerics
def test_energy_balance_holds_along_the_motion_to_the_integrator_error(closed_loop):
    # U(t) − U(0) = −∫ Σ k_i ω_i² dt on the propagated motion. The residual is the propagator's
    # (and the quadrature's) O(h⁴) error, so it must shrink 16× when h halves; a wrong law or
    # Lyapunov function leaves an O(1) residual that does not. Over the first 10 s (the large-
    # angle transient) measured: Gibbs 1.0e-3 J at h = 40 ms, 6.4e-5 J at 20 ms (ratio 16, of
    # U(0) = 470 J); MRP 3.1e-8 J → 2.7e-9 J (ratio 11: the graded start is common to both).
    law, t, beta, w = closed_loop
    res_coarse, U = energy_balance_residual(law, t, beta, w)
    assert np.abs(res_coarse).max() <= 1e-5 * U[0]
    t_fine = graded_grid(0.02, 10.0)
    beta_f, w_f = propagate(BETA0, W0, INERTIA, t_fine, as_torque(law))
    res_fine, _ = energy_balance_residual(law, t_fine, beta_f, w_f)
    in_window = t <= t_fine[-1]
    ratio = np.abs(res_coarse[in_window]).max() / np.abs(res_fine).max()
    assert 8 <= ratio <= 32, ratio  # fourth order: 2⁴ = 16
    assert np.abs(res_fine).max() <= 1e-6 * U[0]


@pytest.mark.numerics
def test_lyapunov_function_never_increases(closed_loop):
    # U' = −Σ k_i ω_i² <= 0; a step may raise U only by the round-off of U (a few eps·U(0));
    # measured: every step lowers it (largest step change −1e-13 J Gibbs, −8e-12 J MRP)
    law, _, beta, w = closed_loop
    U = law.lyapunov(beta, w, INERTIA)
    assert np.all(np.diff(U) <= 16 * EPS * U[0])
    if isinstance(law, GibbsLyapunovLaw):
        # tan²(φ/2) <= U(0)/A: the 170° start can never reach the 180° singularity
        _, phi = att.quaternion_to_principal_rotation(error_quaternion(beta, TARGET))
        phi = np.minimum(phi, 2 * np.pi - phi)
        assert np.all(np.tan(phi / 2) ** 2 <= U[0] / law.A)


@pytest.mark.numerics
def test_converges_to_the_target_from_a_170_degree_rotation(closed_loop):
    # the linearised loop's slowest mode decays as exp(−0.1755 t): 2.7e-5 over 60 s, so from an
    # O(1) rad error the state ends below 1e-4 rad, 1e-4 rad/s (measured: Gibbs 2.9e-6 rad,
    # 5.1e-7 rad/s; MRP 2.2e-5 rad, 4.1e-6 rad/s)
    _, _, beta, w = closed_loop
    _, phi = att.quaternion_to_principal_rotation(error_quaternion(beta, TARGET))
    phi = np.minimum(phi, 2 * np.pi - phi)
    assert phi[0] == pytest.approx(np.deg2rad(170.0), abs=1e-12)
    assert phi[-1] < 1e-4 and np.linalg.norm(w[-1]) < 1e-4


def test_batched_laws_equal_their_single_cases():
    t = np.linspace(0.0, 0.5, 11)
    targets = np.stack([TARGET, att.principal_rotation_to_quaternion([1.0, 0.0, 0.0], -1.0)])
    laws = [
        GibbsLyapunovLaw(k=[[12.0, 10.0, 8.0], [5.0, 6.0, 7.0]], A=[3.6, 1.0], beta_target=targets),
        MRPLaw(K=[7.2, 2.0], P=[[12.0, 10.0, 8.0], [5.0, 6.0, 7.0]], beta_target=targets),
    ]
    for law in laws:
        # the propagator takes its case axes from the state: one initial state per case
        beta, w = propagate(np.stack([BETA0] * 2), W0, INERTIA, t, as_torque(law))
        for case in range(2):
            fields = {
                name: np.asarray(getattr(law, name))[case] for name in law.__dataclass_fields__
            }
            b1, w1 = propagate(BETA0, W0, INERTIA, t, as_torque(type(law)(**fields)))
            np.testing.assert_allclose(beta[case], b1, rtol=0, atol=1e-15)
            np.testing.assert_allclose(w[case], w1, rtol=0, atol=1e-14)


def test_mrp_law_takes_the_short_rotation_and_ignores_the_quaternion_sign():
    law = MRPLaw(K=2.0, P=1.0)
    # 190° about +z is −170° about +z: the short way is back about −z, σ = −z tan(42.5°)
    beta = att.principal_rotation_to_quaternion([0.0, 0.0, 1.0], np.deg2rad(190.0))
    np.testing.assert_allclose(law.mrp(beta), [0, 0, -np.tan(np.deg2rad(42.5))], atol=1e-15)
    np.testing.assert_array_equal(law.torque(beta, W0), law.torque(-beta, W0))
    gibbs = GibbsLyapunovLaw(k=1.0, A=1.0)
    np.testing.assert_allclose(gibbs.torque(beta, W0), gibbs.torque(-beta, W0), rtol=1e-15)


def test_gains_accept_units_and_are_stored_in_si():
    law = GibbsLyapunovLaw(k="12 N*m*s/rad", A=3.6 * ureg("N*m"))
    assert law.k == pytest.approx(12.0) and law.A == pytest.approx(3.6)
    law = MRPLaw(K="100 ozf*in", P=[1.0, 2.0, 3.0])
    assert law.K == pytest.approx(0.7061552, rel=1e-6)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(k=-1.0, A=1.0), "k: must be > 0"),
        (dict(k=1.0, A=0.0), "A: must be > 0"),
        (dict(k=[1.0, 2.0], A=1.0), "k: per-axis gains must be a scalar or have last axis 3"),
        (dict(k="1 m", A=1.0), "k"),
        (dict(k=1.0, A=1.0, beta_target=[1.0, 1.0, 0.0, 0.0]), "beta_target: must be a unit"),
    ],
)
def test_bad_gibbs_gains_are_named(kwargs, message):
    with pytest.raises(ValueError, match=message):
        GibbsLyapunovLaw(**kwargs)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(K=float("nan"), P=1.0), "K: must be finite"),
        (dict(K=1.0, P=[1.0, -2.0, 3.0]), "P: must be > 0"),
        (dict(K=1.0, P=np.ones(4)), "P: per-axis gains must be a scalar or have last axis 3"),
    ],
)
def test_bad_mrp_gains_are_named(kwargs, message):
    with pytest.raises(ValueError, match=message):
        MRPLaw(**kwargs)


def test_bad_states_are_named():
    law = GibbsLyapunovLaw(k=1.0, A=1.0)
    with pytest.raises(ValueError, match="singular at a 180° error"):
        law.torque(att.principal_rotation_to_quaternion([0.0, 1.0, 0.0], np.pi), W0)
    with pytest.raises(ValueError, match="w: last axes must have shape"):
        law.torque(TARGET, [1.0, 2.0])
    with pytest.raises(ValueError, match="beta, w, k, A, beta_target: leading"):
        law.torque(np.stack([TARGET] * 2), np.zeros((3, 3)))
    batched = MRPLaw(K=[1.0, 2.0], P=1.0)
    with pytest.raises(ValueError, match=r"K \(2,\)"):
        batched.torque(np.stack([TARGET] * 3), np.zeros((3, 3)))
    with pytest.raises(ValueError, match="beta, beta_target: leading"):
        error_quaternion(np.stack([TARGET] * 3), np.stack([TARGET] * 2))


def closed_loop_rhs(law):
    """(β, ω, D) of the continuous closed loop with ideal sensors: β' = Ω(ω)β (seed 003
    Eq. 11), Iω' = −ω×Iω + u (Eq. 12), and D' = −U' claimed by the law, so that U + D stays
    at U(0) exactly when U' = −Σ k_i ω_i² holds."""
    Jinv = np.linalg.inv(INERTIA)

    def rhs(t, x):
        beta, w = x[:4], x[4:7]
        u = law(t, {"attitude": beta[None], "rate": w[None]}, {})[0][0]
        wdot = Jinv @ (u - np.cross(w, INERTIA @ w))
        return np.concatenate([att.omega_matrix(w) @ beta, wdot, [-law.lyapunov_rate(w)]])

    return rhs


@pytest.mark.numerics
def test_gibbs_lyapunov_rate_along_the_continuous_motion_from_170_degrees():
    # Att. 3 §II: U' = −Σ k_i ω_i², checked as U(t) + ∫₀ᵗ Σ k_i ω_i² dt = U(0) along a DOP853
    # solution of the continuous closed loop (rtol = atol = 1e-12). DOP853 keeps the local
    # error per step below ~1e-12 of the state; summed over its 163 accepted steps the global
    # error of U and of the integral is bounded by ~2e-10 U(0); we allow 1e-9 U(0) (measured
    # 1.1e-12 U(0)). A wrong law or U leaves an O(1) residual: the motion starts with
    # U(0) = 470 J and dissipates all of it.
    law = LAWS["gibbs"]
    x0 = np.concatenate([BETA0, W0, [0.0]])
    sol = solve_ivp(
        closed_loop_rhs(law),
        (0.0, T_END),
        x0,
        method="DOP853",
        rtol=1e-12,
        atol=1e-12,
        dense_output=True,
    )
    assert sol.success
    t = np.linspace(0.0, T_END, 2001)
    x = sol.sol(t).T
    beta = x[:, :4] / np.linalg.norm(x[:, :4], axis=-1, keepdims=True)
    U = law.lyapunov(beta, x[:, 4:7], INERTIA)
    assert np.abs(U + x[:, 7] - U[0]).max() <= 1e-9 * U[0]
    assert np.all(np.diff(U) <= 1e-9 * U[0])
    _, phi = att.quaternion_to_principal_rotation(error_quaternion(beta, TARGET))
    phi = np.minimum(phi, 2 * np.pi - phi)
    assert phi[0] == pytest.approx(np.deg2rad(170.0), abs=1e-12)
    # slowest linearised decay exp(−0.1755 t): 2.7e-5 of the O(1) error after 60 s
    assert phi[-1] < 1e-4 and np.linalg.norm(x[-1, 4:7]) < 1e-4


def test_laws_are_controllers_reading_attitude_and_rate_and_writing_torque():
    for law in [*LAWS.values(), QuaternionPD(Kp=2.0, Kd=3.0)]:
        assert isinstance(law, Controller)
        assert law.reads == ("attitude", "rate") and law.writes == ("torque",)
        u, state = law(0.0, {"attitude": BETA0[None], "rate": W0[None]}, {})
        assert u.shape == (1, 3) and state == {}
        np.testing.assert_array_equal(u[0], law.torque(BETA0, W0))
    batched = GibbsLyapunovLaw(k=[[1.0, 2.0, 3.0]] * 4, A=[1.0, 2.0, 3.0, 4.0])
    assert batched.n_cases == 4 and LAWS["mrp"].n_cases == 1


def pd_closed_loop(law, beta0, w0, t_end):
    x0 = np.concatenate([beta0, w0, [0.0]])
    return solve_ivp(
        closed_loop_rhs(law),
        (0.0, t_end),
        x0,
        method="DOP853",
        rtol=1e-11,
        atol=1e-12,
        dense_output=True,
    )


@pytest.mark.numerics
def test_quaternion_pd_converges_and_takes_the_short_way():
    # 190° about +z from the target is the same attitude as 170° about −z: the short way turns
    # the body back by 170°, so the error angle never exceeds its start (the long way would
    # first pass through 180°). Gains Kp = 2 I ω_n², Kd = 2ζ ω_n I with the largest principal
    # moment, ω_n = 0.3 rad/s, ζ = 0.9 (linearised loop I θ'' + Kd θ' + (Kp/2) θ = 0, δβ ≈ θ/2):
    # the slowest linearised pole (the least-inertia axis, overdamped) decays at 0.20 /s,
    # 5e-6 over 60 s, so from 3 rad the error ends below 1e-4 (measured 1.2e-6).
    I_max = np.linalg.eigvalsh(INERTIA).max()
    law = QuaternionPD(Kp=2 * I_max * 0.09, Kd=2 * 0.9 * 0.3 * I_max, beta_target=TARGET)
    start = att.quaternion_multiply(
        att.principal_rotation_to_quaternion([0.0, 0.0, 1.0], np.deg2rad(190.0)), TARGET
    )
    for sign in (1.0, -1.0):  # either sign of the same attitude: the same motion
        sol = pd_closed_loop(law, sign * start, np.zeros(3), 60.0)
        t = np.linspace(0.0, 60.0, 1201)
        x = sol.sol(t).T
        e = law.error(x[:, :4] / np.linalg.norm(x[:, :4], axis=-1, keepdims=True))
        phi = 2 * np.arccos(np.clip(e[:, 0], -1, 1))
        assert phi[0] == pytest.approx(np.deg2rad(170.0), rel=1e-12)
        assert np.all(phi <= phi[0] + 1e-9)  # never through 180°: the short way
        assert phi[-1] < 1e-4 and np.linalg.norm(x[-1, 4:7]) < 1e-4


@pytest.mark.numerics
def test_quaternion_pd_lyapunov_function_decreases_at_minus_w_kd_w():
    law = QuaternionPD(Kp=3.0, Kd=[4.0, 5.0, 6.0], beta_target=TARGET)
    sol = pd_closed_loop(law, BETA0, W0, 20.0)
    t = np.linspace(0.0, 20.0, 801)
    x = sol.sol(t).T
    beta = x[:, :4] / np.linalg.norm(x[:, :4], axis=-1, keepdims=True)
    V = law.lyapunov(beta, x[:, 4:7], INERTIA)
    # as for the Gibbs law: DOP853 at rtol 1e-11 keeps V + ∫ωᵀKdω within its global error,
    # ~1e-9 V(0) over the run; measured 5.7e-12 V(0)
    assert np.abs(V + x[:, 7] - V[0]).max() <= 1e-8 * V[0]
    with pytest.raises(ValueError, match="Kp: the Lyapunov function"):
        QuaternionPD(Kp=[1.0, 2.0, 3.0], Kd=1.0).lyapunov(BETA0, W0, INERTIA)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(Kp=0.0, Kd=1.0), "Kp: must be > 0"),
        (dict(Kp=1.0, Kd=[1.0, 2.0]), "Kd: per-axis gains must be a scalar or have last axis 3"),
        (dict(Kp=1.0, Kd=1.0, w_ref=[0.0, 1.0]), "w_ref: last axes must have shape"),
        (
            dict(
                Kp=[1.0, 2.0, 3.0],
                Kd=1.0,
                beta_target=np.stack([TARGET] * 2),
                w_ref=np.zeros((3, 3)),
            ),
            "Kp, Kd, beta_target, w_ref: leading",
        ),
    ],
)
def test_bad_pd_gains_are_named(kwargs, message):
    with pytest.raises(ValueError, match=message):
        QuaternionPD(**kwargs)
