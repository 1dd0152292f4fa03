"""Margins of continuous and sampled-data loops (issue 24) against closed forms, a published
disk margin, python-control, and a direct z-domain evaluation."""

import math

import numpy as np
import pytest
import scipy.optimize

import control as ct
from flexsat.analysis.frequency_domain import (
    angular_frequencies,
    build_loop,
    frequency_response,
)
from flexsat.analysis.loop_modes import closed_loop_poles, damping_table
from flexsat.analysis.margins import (
    UnstableLoopError,
    disk_margin,
    disk_margins,
    disk_variations,
    loop_margins,
)
from flexsat.input_checks import FieldError
from flexsat.units import Q_, FrequencyArray

S = ct.tf("s")
J, KP, KD = 2.0, 3.0, 4.0


def double_integrator(J=J):
    """θ'' = u/J measured as (θ, θ')."""
    return ct.ss(
        [[0, 1], [0, 0]],
        [[0], [1 / J]],
        np.eye(2),
        np.zeros((2, 1)),
        states=["theta", "theta_dot"],
        inputs=["torque"],
        outputs=["theta", "theta_dot"],
        name="hub",
    )


def pd(dt=0):
    return ct.ss(
        [], [], [], [[-KP, -KD]], dt, inputs=["theta", "theta_dot"], outputs=["torque"], name="pd"
    )


def crossover():
    """|kp + j kd ω| = J ω²  ⇔  J²ω⁴ − kd²ω² − kp² = 0."""
    return math.sqrt((KD**2 + math.sqrt(KD**4 + 4 * J**2 * KP**2)) / (2 * J**2))


@pytest.mark.parametrize("tau", [0.0, 0.1, 0.3])
def test_double_integrator_pd_with_delay_closed_forms(tau):
    r"""L = (kp + kd s) e^{−sτ}/(J s²): ω_c from the quartic, PM = atan(kd ω_c/kp) − ω_c τ,
    delay margin PM₀/ω_c − τ; the phase crossover solves atan(kd ω/kp) = ωτ (a scalar root,
    solved independently), GM = Jω²/|kp + j kd ω| there (∞ without delay). Tolerances: the
    crossings are solved to 1e-14 relative in ω, so 1e-9 covers the conditioning."""
    loop = build_loop(double_integrator(), pd(), "torque")
    m = loop_margins(loop, delay_s=tau)
    wc = crossover()
    pm0 = math.atan(KD * wc / KP)
    assert m.gain_crossover_rad_s == pytest.approx(wc, rel=1e-10)
    assert math.radians(m.phase_margin_deg) == pytest.approx(pm0 - wc * tau, rel=1e-9)
    assert m.delay_margin_s == pytest.approx(pm0 / wc - tau, rel=1e-9)
    if tau == 0:
        assert m.gain_margin == math.inf
    else:
        wp = scipy.optimize.brentq(lambda w: math.atan(KD * w / KP) - w * tau, 1e-3, 1e3)
        assert m.phase_crossover_rad_s == pytest.approx(wp, rel=1e-9)
        assert m.gain_margin == pytest.approx(J * wp**2 / abs(KP + 1j * KD * wp), rel=1e-9)


def test_a_delay_beyond_the_delay_margin_is_an_unstable_loop():
    loop = build_loop(double_integrator(), pd(), "torque")
    dm = loop_margins(loop).delay_margin_s
    with pytest.raises(UnstableLoopError, match="delay margin"):
        loop_margins(loop, delay_s=1.01 * dm)


def test_seiler_packard_gahinet_disk_margin():
    """Seiler, Packard & Gahinet 2020 (IEEE CSM 40(5)), example loop L = 25/(s³ + 10s² + 10s +
    10): balanced disk margin α = 0.46, disk gain margin [0.63, 1.59] (4.05 dB), disk phase
    margin 25.8° (the paper's printed digits set the tolerances); classical GM 3.6 (exact:
    the phase crossover at √10 rad/s, |L| = 25/90) and PM 29.1°."""
    L = ct.ss(ct.tf(25, [1, 10, 10, 10]))
    dm = disk_margin(L)
    assert dm.alpha == pytest.approx(0.46, abs=0.005)
    assert dm.gain_range[0] == pytest.approx(0.63, abs=0.005)
    assert dm.gain_range[1] == pytest.approx(1.59, abs=0.005)
    assert dm.gain_margin_db == pytest.approx(4.05, abs=0.005)
    assert dm.phase_deg == pytest.approx(25.8, abs=0.05)
    m = loop_margins(L)
    assert m.gain_margin == pytest.approx(3.6, rel=1e-12)
    assert m.phase_crossover_rad_s == pytest.approx(math.sqrt(10), rel=1e-12)
    assert m.phase_margin_deg == pytest.approx(29.1, abs=0.05)
    # the exact supremum is never below python-control's maximum on a grid of the same loop
    grid_alpha = ct.disk_margins(L, np.logspace(-1, 2, 3001))[0]
    assert dm.alpha <= grid_alpha and dm.alpha == pytest.approx(grid_alpha, rel=1e-4)
    # the S-based disk (σ = 1) is the distance from −1 to the Nyquist curve (stability margin)
    assert disk_margin(L, skew=1.0).alpha == pytest.approx(ct.stability_margins(L)[2], rel=1e-6)


def test_disk_variations_balanced_closed_form():
    """σ = 0: g ∈ [(2 − α)/(2 + α), (2 + α)/(2 − α)], φ = 2 atan(α/2)."""
    for alpha in (0.1, 0.5, 1.5):
        (lo, hi), phase = disk_variations(alpha, 0.0)
        assert lo == pytest.approx((2 - alpha) / (2 + alpha), rel=1e-14)
        assert hi == pytest.approx((2 + alpha) / (2 - alpha), rel=1e-14)
        assert math.radians(phase) == pytest.approx(2 * math.atan(alpha / 2), rel=1e-12)


def spinning_satellite():
    """The MIMO example of Doyle's spinning satellite as python-control's disk-margin tests
    build it: P = [[0, a], [−a, 0]], B = I, C = [[1, a], [−a, 1]], a = 10, K = [[1, −2], [0, 1]]
    here with the feedback sign inside the law (u = −K y)."""
    a = 10.0
    P = ct.ss(
        [[0, a], [-a, 0]],
        np.eye(2),
        [[1, a], [-a, 1]],
        0,
        inputs=["u1", "u2"],
        outputs=["y1", "y2"],
        name="sat",
    )
    K = ct.ss(
        [],
        [],
        [],
        -np.array([[1.0, -2.0], [0.0, 1.0]]),
        inputs=["y1", "y2"],
        outputs=["u1", "u2"],
        name="k",
    )
    return P, K


def smallest_destabilising_alpha(M):
    """Brute force on a 2 × 2 M: the least α with det(I − M diag(δ1, δ2)) = 0, |δi| <= α.
    Solving for δ2 = (1 − m11 δ1)/(m22 − det(M) δ1), the least α has |δ1| = |δ2| = r, the root
    of r − min over the phase of δ1 of |δ2| (a dense phase grid refined by a bounded search)."""
    det = np.linalg.det(M)

    def d2(r, th):
        d1 = r * np.exp(1j * th)
        return np.abs((1 - M[0, 0] * d1) / (M[1, 1] - det * d1))

    def gap(r):
        th = np.linspace(0, 2 * math.pi, 7201)
        k = int(np.argmin(d2(r, th)))
        res = scipy.optimize.minimize_scalar(
            lambda t: d2(r, t),
            bounds=(th[k] - 0.001, th[k] + 0.001),
            method="bounded",
            options={"xatol": 1e-13},
        )
        return min(res.fun, d2(r, th[k])) - r

    return scipy.optimize.brentq(gap, 0.01, 2.0, xtol=1e-14)


def test_spinning_satellite_multiloop_disk_margin():
    """Doyle's spinning satellite: the multiloop disk margin at the plant input and output is
    reached at ω = 0, where the D-scaled bound (exact for two loops) equals a brute-force
    search for the smallest simultaneous perturbation (to 1e-9). python-control's test of the
    same loop (slycot's μ) and MATLAB's example print 0.3754, a conservative bound 0.2 % below
    the exact 0.37615. Loop-at-a-time margins exceed the multiloop one."""
    P, K = spinning_satellite()
    for where in ("input", "output"):
        loop = build_loop(P, K, where)
        per_channel, multi = disk_margins(loop)
        M = frequency_response(loop.sensitivity(), omega_rad_s=np.array([0.0])).values[0]
        exact = smallest_destabilising_alpha(M - 0.5 * np.eye(2))
        assert multi.alpha == pytest.approx(exact, rel=1e-9)
        assert multi.alpha == pytest.approx(0.3754, rel=3e-3)
        assert all(dm.alpha > multi.alpha for dm in per_channel)


def test_hz_and_rad_s_never_confused():
    """'1 Hz', Q_(1, 'Hz') and FrequencyArray([1], 'Hz') are all 2π rad/s; a plain number is
    refused, and the arrays returned say rad/s in their name."""
    for given in ("1 Hz", Q_(1.0, "Hz"), FrequencyArray([1.0], "Hz"), ["1 Hz"]):
        assert np.allclose(angular_frequencies(given), 2 * math.pi, rtol=1e-15)
    with pytest.raises(FieldError, match="cannot say Hz from rad/s"):
        angular_frequencies(np.array([1.0]))
    L = ct.ss(1 / (S + 1))
    r = frequency_response(L, "1 Hz")
    assert r.omega_rad_s == pytest.approx([2 * math.pi])
    assert r.values[0, 0, 0] == pytest.approx(1 / (2j * math.pi + 1))


def test_unstable_loop_stated_as_such_not_nan():
    """kp < 0 on a double integrator: a closed-loop pole at +√(|kp|/J); margins refused."""
    K = ct.ss([], [], [], [[3.0, -1.0]], inputs=["theta", "theta_dot"], outputs=["torque"])
    loop = build_loop(double_integrator(), K, "torque")
    assert not loop.stable
    for fn in (loop_margins, disk_margin, disk_margins):
        with pytest.raises(UnstableLoopError, match="closed loop is unstable.*pole"):
            fn(loop)


def test_break_point_and_signals_checked_by_name():
    P = double_integrator()
    with pytest.raises(FieldError, match="break_at.*'torque'"):
        build_loop(P, pd(), "thrust")
    K = ct.ss([], [], [], [[-1.0]], inputs=["angle"], outputs=["torque"])
    with pytest.raises(FieldError, match=r"\['angle'\] are not signals of the plant"):
        build_loop(P, K)
    with pytest.raises(FieldError, match="SISO"):
        loop_margins(build_loop(P, pd(), "output"))
    with pytest.raises(FieldError, match="Nyquist frequency"):
        frequency_response(ct.c2d(ct.ss(1 / (S + 1)), 0.1), "10 Hz")


def test_sensitivity_identities():
    """S = 1/(1 + L), T = L/(1 + L), S + T = 1 on a grid (round-off)."""
    loop = build_loop(double_integrator(), pd(), "torque")
    w = np.geomspace(0.01, 100, 50)
    L = frequency_response(loop.transfer, omega_rad_s=w).values[:, 0, 0]
    Sv = frequency_response(loop.sensitivity(), omega_rad_s=w).values[:, 0, 0]
    Tv = frequency_response(loop.complementary_sensitivity(), omega_rad_s=w).values[:, 0, 0]
    assert np.allclose(Sv, 1 / (1 + L), rtol=1e-12)
    assert np.allclose(Tv, L / (1 + L), rtol=1e-12)
    assert np.allclose(Sv + Tv, 1, atol=1e-12)


def test_closed_loop_poles_damping_and_mode():
    """J s² + kd s + kp: ω_n = √(kp/J), ζ = kd/(2√(kp J)); both poles belong to 'theta'."""
    loop = build_loop(double_integrator(), pd(), "torque")
    poles = closed_loop_poles(loop)
    wn, zeta = math.sqrt(KP / J), KD / (2 * math.sqrt(KP * J))
    assert len(poles) == 2
    for p in poles:
        assert p.mode == "theta" and p.participation == pytest.approx(1.0)
        if zeta < 1:
            assert p.natural_frequency_rad_s == pytest.approx(wn, rel=1e-12)
            assert p.damping_ratio == pytest.approx(zeta, rel=1e-12)
    assert np.prod([p.pole for p in poles]).real == pytest.approx(KP / J, rel=1e-12)
    assert "theta" in damping_table(poles)


@pytest.mark.parametrize("delay", [0, 1, 2])
def test_sampled_data_margins_equal_a_direct_z_domain_evaluation(delay):
    """The sampled loop built by name (plant ZOH + law + d samples as states) against the
    z-domain formula written out: Φ = [[1, T], [0, 1]], Γ = [T²/2J, T/J] (the exact ZOH of a
    double integrator), L(z) = [kp, kd](zI − Φ)⁻¹Γ z^{−d} on z = e^{jωT}, crossings solved by
    brentq here; GM, PM and crossovers agree to the root solvers' tolerance."""
    dt = 0.05
    Phi, Gam = np.array([[1, dt], [0, 1]]), np.array([dt**2 / (2 * J), dt / J])

    def L(w):
        z = np.exp(1j * w * dt)
        return np.array([KP, KD]) @ np.linalg.solve(z * np.eye(2) - Phi, Gam) * z**-delay

    nyq = math.pi / dt
    wgc = scipy.optimize.brentq(lambda w: abs(L(w)) - 1, 1e-3, nyq, xtol=1e-15)
    pm = math.degrees(np.angle(-L(wgc)))
    m = loop_margins(build_loop(double_integrator(), pd(dt), "torque", delay=delay))
    assert m.gain_crossover_rad_s == pytest.approx(wgc, rel=1e-10)
    assert m.phase_margin_deg == pytest.approx(pm, rel=1e-10)
    w = np.linspace(wgc, nyq, 20001)
    im = np.array([L(x).imag for x in w])
    flips = np.nonzero(np.sign(im[:-1]) != np.sign(im[1:]))[0]
    if delay == 0:
        # [kp, kd](zI − Φ)⁻¹Γ is real at z = −1: the crossing sits at the Nyquist frequency
        wpc = nyq
    else:
        wpc = scipy.optimize.brentq(lambda x: L(x).imag, w[flips[0]], w[flips[0] + 1], xtol=1e-15)
    assert m.phase_crossover_rad_s == pytest.approx(wpc, rel=1e-10)
    assert m.gain_margin == pytest.approx(-1 / L(wpc).real, rel=1e-9)
    assert m.delay_margin_samples == math.floor(m.delay_margin_s / dt)


def test_sampled_data_margins_converge_to_the_continuous_ones_by_the_hold_lag():
    """PD on a double integrator at rising sample rates: the sampled phase margin falls short
    of the continuous one by the zero-order hold's lag ω_c dt/2 (Franklin, Powell & Workman
    §6.3.1) to O(dt²), so the ratio (PM_c − PM_d)/(ω_c dt/2) tends to 1 as dt → 0."""
    cont = loop_margins(build_loop(double_integrator(), pd(), "torque"))
    wc = cont.gain_crossover_rad_s
    errors = []
    for dt in (0.1, 0.03, 0.01, 0.003):
        d = loop_margins(build_loop(double_integrator(), pd(dt), "torque"))
        lag = math.degrees(wc * dt / 2)
        errors.append(abs((cont.phase_margin_deg - d.phase_margin_deg) / lag - 1))
        assert d.phase_margin_deg < cont.phase_margin_deg
    assert all(b < a for a, b in zip(errors, errors[1:]))
    assert errors[-1] < 0.01


@pytest.mark.parametrize("seed", range(20))
def test_margins_equal_python_control_on_random_loops(seed):
    """20 random loops k p2 (s + z)/((s + p1)(s + p2)(s² + 2ζωs + ω²)) (relative degree 3, so
    each has a phase crossover): GM, PM and crossovers equal python-control's
    stability_margins (its crossings are polynomial roots, ours brentq on the response: both
    to round-off)."""
    rng = np.random.default_rng(seed)
    z, p1, p2 = rng.uniform(0.2, 3), rng.uniform(0.1, 2), rng.uniform(2, 10)
    w, zeta = rng.uniform(0.5, 5), rng.uniform(0.05, 0.7)
    G = p2 * (S + z) / ((S + p1) * (S + p2) * (S**2 + 2 * zeta * w * S + w**2))
    k = rng.uniform(0.3, 1) / abs(ct.evalfr(G, 1j * w))
    L = ct.ss(k * G)
    assert np.all(np.linalg.eigvals(ct.feedback(L, 1).A).real < 0)  # gains kept below GM
    gm, pm, _, wpc, wgc, _ = ct.stability_margins(L)
    m = loop_margins(L)
    if np.isfinite(pm):
        assert m.phase_margin_deg == pytest.approx(pm, rel=1e-7)
        assert m.gain_crossover_rad_s == pytest.approx(wgc, rel=1e-7)
    assert 1 < gm < 1e6
    assert m.gain_margin == pytest.approx(gm, rel=1e-7)
    assert m.phase_crossover_rad_s == pytest.approx(wpc, rel=1e-7)


@pytest.mark.parametrize("delay", [0, 1])
def test_the_multiloop_disk_margin_of_one_loop_is_its_disk_margin(delay):
    """With one channel μ is |S + (σ − 1)/2| itself: the multiloop margin (grid, then Brent on
    frequency) equals the exact SISO one (Hamiltonian bracket of relative width 2e-8), to
    that bracket plus Brent's ε^{1/2} in frequency, ε in the value at a smooth peak."""
    loop = build_loop(double_integrator(), pd(0.05), "input", delay=delay)
    per_channel, multi = disk_margins(loop)
    exact = disk_margin(loop)
    assert per_channel[0].alpha == pytest.approx(exact.alpha, rel=1e-12)
    assert multi.alpha == pytest.approx(exact.alpha, rel=3e-8)
    assert multi.frequency_rad_s == pytest.approx(exact.frequency_rad_s, rel=1e-4)
