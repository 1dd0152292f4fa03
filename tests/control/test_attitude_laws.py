"""Three-axis attitude laws (issue 10 acceptance), closed on the rigid-body propagator with ideal
sensors: along the simulated motion the Gibbs Lyapunov law of Att. 3 §II dissipates U at exactly
−Σ k_i ω_i² and the MRP PD law dissipates V at −ωᵀPω (pointwise to round-off, integrated to the
integrator's fourth-order error), both functions never increase, and from a 170° principal
rotation with a nonzero rate both laws bring the body to the target; batching and bad input."""

import numpy as np
import pytest

from flexsat.control import GibbsLyapunovLaw, MRPLaw
from flexsat.control.attitude_laws import error_quaternion
from flexsat.dynamics import attitude as att
from flexsat.dynamics import rigid_body as rb
from flexsat.units import ureg

EPS = np.finfo(float).eps
# asymmetric body with products of inertia (kg·m²): the laws need no principal axes
INERTIA = np.array([[10.0, 0.5, -0.3], [0.5, 15.0, 0.8], [-0.3, 0.8, 20.0]])
TARGET = att.principal_rotation_to_quaternion([0.0, 0.6, 0.8], 0.7)
# 170° principal rotation from the target about a skew axis, and a rate of ~0.1 rad/s
BETA0 = att.quaternion_multiply(att.principal_rotation_to_quaternion([1 / 3, 2 / 3, 2 / 3],
                                                                     np.deg2rad(170.0)), TARGET)
W0 = np.array([0.05, -0.1, 0.08])
# gains placing the linearised closed loop I θ'' + k θ' + (A/2) θ = 0 (q ≈ θ/2) and
# I θ'' + P θ' + (K/4) θ = 0 (σ ≈ θ/4) at the same poles: slowest decay rate 0.1755 /s
LAWS = {"gibbs": GibbsLyapunovLaw(k=12.0, A=3.6, beta_target=TARGET),
        "mrp": MRPLaw(K=7.2, P=12.0, beta_target=TARGET)}
T_END = 60.0


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
    """U(t) − U(0) − ∫₀ᵗ f dt, f = −Σ g_i ω_i², along a trajectory (g the rate gains); the integral by
    the corrected trapezoid rule h/2 (f0 + f1) + h²/12 (f0' − f1') (O(h⁴) like the propagator),
    with f' = −2 Σ g_i ω_i ω̇_i and ω̇ from Euler's equations under the law's torque."""
    U = law.lyapunov(beta, w, INERTIA)
    g = rate_gains(law)
    f = law.lyapunov_rate(w)
    fd = -2 * np.sum(g * w * rb.euler_rates(w, INERTIA, law(t, beta, w)), axis=-1)
    h = np.diff(t)
    steps = h / 2 * (f[1:] + f[:-1]) + h**2 / 12 * (fd[:-1] - fd[1:])
    return U - U[0] - np.concatenate([[0.0], np.cumsum(steps)]), U


@pytest.fixture(scope="module", params=list(LAWS))
def closed_loop(request):
    law = LAWS[request.param]
    t = graded_grid(0.04, T_END)
    beta, w = rb.propagate(BETA0, W0, INERTIA, t, law)
    return law, t, beta, w


@pytest.mark.numerics
def test_lyapunov_rate_is_minus_the_rate_gain_dissipation_pointwise(closed_loop):
    # U' from the chain rule on the simulated states, with the Gibbs / MRP kinematics of
    # flexsat.dynamics.attitude and Euler's equations: an algebraic identity, so round-off
    # bounds it (a few eps times the largest term |ω||u|)
    law, t, beta, w = closed_loop
    u = law(t, beta, w)
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
    beta_f, w_f = rb.propagate(BETA0, W0, INERTIA, t_fine, law)
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
    laws = [GibbsLyapunovLaw(k=[[12.0, 10.0, 8.0], [5.0, 6.0, 7.0]], A=[3.6, 1.0],
                             beta_target=targets),
            MRPLaw(K=[7.2, 2.0], P=[[12.0, 10.0, 8.0], [5.0, 6.0, 7.0]], beta_target=targets)]
    for law in laws:
        # the propagator takes its case axes from the state: one initial state per case
        beta, w = rb.propagate(np.stack([BETA0] * 2), W0, INERTIA, t, law)
        for case in range(2):
            fields = {name: np.asarray(getattr(law, name))[case] for name in
                      law.__dataclass_fields__}
            b1, w1 = rb.propagate(BETA0, W0, INERTIA, t, type(law)(**fields))
            np.testing.assert_allclose(beta[case], b1, rtol=0, atol=1e-15)
            np.testing.assert_allclose(w[case], w1, rtol=0, atol=1e-14)


def test_mrp_law_takes_the_short_rotation_and_ignores_the_quaternion_sign():
    law = MRPLaw(K=2.0, P=1.0)
    # 190° about +z is −170° about +z: the short way is back about −z, σ = −z tan(42.5°)
    beta = att.principal_rotation_to_quaternion([0.0, 0.0, 1.0], np.deg2rad(190.0))
    np.testing.assert_allclose(law.mrp(beta), [0, 0, -np.tan(np.deg2rad(42.5))], atol=1e-15)
    np.testing.assert_array_equal(law(0.0, beta, W0), law(0.0, -beta, W0))
    gibbs = GibbsLyapunovLaw(k=1.0, A=1.0)
    np.testing.assert_allclose(gibbs(0.0, beta, W0), gibbs(0.0, -beta, W0), rtol=1e-15)


def test_gains_accept_units_and_are_stored_in_si():
    law = GibbsLyapunovLaw(k="12 N*m*s/rad", A=3.6 * ureg("N*m"))
    assert law.k == pytest.approx(12.0) and law.A == pytest.approx(3.6)
    law = MRPLaw(K="100 ozf*in", P=[1.0, 2.0, 3.0])
    assert law.K == pytest.approx(0.7061552, rel=1e-6)


@pytest.mark.parametrize("kwargs, message", [
    (dict(k=-1.0, A=1.0), "k: must be > 0"),
    (dict(k=1.0, A=0.0), "A: must be > 0"),
    (dict(k=[1.0, 2.0], A=1.0), "k: per-axis gains must be a scalar or have last axis 3"),
    (dict(k="1 m", A=1.0), "k"),
    (dict(k=1.0, A=1.0, beta_target=[1.0, 1.0, 0.0, 0.0]), "beta_target: must be a unit"),
])
def test_bad_gibbs_gains_are_named(kwargs, message):
    with pytest.raises(ValueError, match=message):
        GibbsLyapunovLaw(**kwargs)


@pytest.mark.parametrize("kwargs, message", [
    (dict(K=float("nan"), P=1.0), "K: must be finite"),
    (dict(K=1.0, P=[1.0, -2.0, 3.0]), "P: must be > 0"),
    (dict(K=1.0, P=np.ones(4)), "P: per-axis gains must be a scalar or have last axis 3"),
])
def test_bad_mrp_gains_are_named(kwargs, message):
    with pytest.raises(ValueError, match=message):
        MRPLaw(**kwargs)


def test_bad_states_are_named():
    law = GibbsLyapunovLaw(k=1.0, A=1.0)
    with pytest.raises(ValueError, match="singular at a 180° error"):
        law(0.0, att.principal_rotation_to_quaternion([0.0, 1.0, 0.0], np.pi), W0)
    with pytest.raises(ValueError, match="w: last axes must have shape"):
        law(0.0, TARGET, [1.0, 2.0])
    with pytest.raises(ValueError, match="beta, w, k, A, beta_target: leading"):
        law(0.0, np.stack([TARGET] * 2), np.zeros((3, 3)))
    batched = MRPLaw(K=[1.0, 2.0], P=1.0)
    with pytest.raises(ValueError, match=r"K \(2,\)"):
        batched(0.0, np.stack([TARGET] * 3), np.zeros((3, 3)))
    with pytest.raises(ValueError, match="beta, beta_target: leading"):
        error_quaternion(np.stack([TARGET] * 3), np.stack([TARGET] * 2))
