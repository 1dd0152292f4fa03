"""The gimbal runs of Vadali, Oh & Walker's SGCMG pyramid (:mod:`flexsat.cases.cmg_pyramid`;
issue 14, V3-V8, F24): the internal singularity met from zero gimbals under pseudo-inverse
steering, the back integration to the preferred set, the preferred-set table (V5), the
preferred-angle search (F24), time-varying torques (Kurokawa V6, Bedrossian V7), null motion
beside the torque law, the null-motion reorientation (V8) through :func:`flexsat.sim.simulate`
(the same run as the engine's continuous mode called directly, and Eq. 16's Lyapunov function
never rising); bad input named by field."""

import numpy as np
import pytest

from flexsat.cases import cmg_pyramid
from flexsat.dynamics import cmg
from flexsat.dynamics.gimbal_cluster import GimbalCluster
from flexsat.sim import continuous, simulate

DEG = np.deg2rad
EPS = np.finfo(float).eps
SKEW = DEG(54.74)
MAGIC = np.arccos(1.0 / np.sqrt(3.0))  # 54.7356°: the skew at which the paper's sets sum to 0
# the paper's "unit +x torque" is the torque demand T of Eq. (5), C σ̇ = T = ḣ; the spacecraft
# feels −ḣ (Eq. 4), and cmg's kernels take the spacecraft torque
PAPER_X = np.array([-1.0, 0.0, 0.0])


def test_v3_pseudo_inverse_from_zero_gimbals_meets_an_internal_singularity():
    threshold = 1e-6
    run = cmg_pyramid.integrate_gimbals(np.zeros(4), PAPER_X, 5.0, threshold=threshold)
    assert run.singular
    # the pseudo-inverse tracks ḣ = +x exactly, so |h| = t; the singular point is
    # h = 2cosδ = 1.1546 (the paper's 1.15h). Near it det(CCᵀ) ∝ (1 − h/h_s), so stopping at
    # det = 1e-6 leaves h a few 1e-7 short of it
    h_s = 2.0 * np.cos(SKEW)
    assert run.t[-1] == pytest.approx(h_s, abs=1e-5)
    np.testing.assert_allclose(run.h[-1], [run.t[-1], 0.0, 0.0], atol=1e-8)
    # σ ≈ [−90, 0, 90, 0]°, not the printed [−90, 0, −90, 0] (which gives h = [0, 0, −2 sinδ]);
    # σ1,3 = ∓asin(h/h_s) approach ±90° as √(1 − h/h_s): 0.04° at this stop
    np.testing.assert_allclose(np.rad2deg(run.sigma[-1]), [-90.0, 0.0, 90.0, 0.0], atol=0.1)
    printed = cmg.momentum(DEG([-90.0, 0.0, -90.0, 0.0]))
    np.testing.assert_allclose(printed, [0.0, 0.0, -2.0 * np.sin(SKEW)], atol=10 * EPS)
    # internal: below the envelope along x by 2 (rotor 2 points against it), rotors 2 and 4
    # antiparallel
    sing = cmg.classify_singularity(run.sigma[-1], threshold=10 * threshold)
    assert sing.singular and sing.internal
    np.testing.assert_allclose(abs(sing.direction), [1.0, 0.0, 0.0], atol=1e-6)
    np.testing.assert_array_equal(sing.signs, [1, -1, 1, 1])
    assert sing.margin == pytest.approx(2.0, abs=1e-6)
    _, a, b = cmg.pyramid_axes()
    h_units = np.cos(run.sigma[-1])[:, None] * a + np.sin(run.sigma[-1])[:, None] * b
    np.testing.assert_allclose(h_units[1], -h_units[3], atol=1e-12)
    # a +x torque on the spacecraft drives h to −x: the mirror singularity, h antiparallel to it
    mirror = cmg_pyramid.integrate_gimbals(np.zeros(4), -PAPER_X, 5.0, threshold=threshold)
    assert mirror.singular and mirror.t[-1] == pytest.approx(h_s, abs=1e-5)
    np.testing.assert_allclose(mirror.h[-1], [-mirror.t[-1], 0.0, 0.0], atol=1e-8)
    np.testing.assert_allclose(np.rad2deg(mirror.sigma[-1]), [90.0, 0.0, -90.0, 0.0], atol=0.1)


def test_v4_back_integration_from_near_saturation_reaches_the_preferred_set():
    sigma0 = DEG([-89.0, 177.0, 90.0, -1.0])
    h0 = cmg.momentum(sigma0)
    # run backward for the time that removes the x momentum at unit rate (3.1530 s)
    run = cmg_pyramid.integrate_gimbals(sigma0, PAPER_X, -h0[0])
    assert not run.singular and run.gain.min() > 1e-3  # no singularity on the way
    assert run.h[-1, 0] == pytest.approx(0.0, abs=1e-8)
    # y, z momentum of the perturbation is untouched by an x torque
    np.testing.assert_allclose(run.h[-1, 1:], h0[1:], atol=1e-8)
    got = np.rad2deg(run.sigma[-1])
    np.testing.assert_allclose(got, [-59.6, 60.7, 118.0, -121.0], atol=0.5)  # the paper, ±0.5°
    # the notes' independent reproduction, printed to 0.01°
    np.testing.assert_allclose(got, [-59.66, 60.58, 117.98, -121.12], atol=0.01)


PREFERRED = [-60.0, 60.0, 120.0, -120.0]


PREFERRED_Y = [-120.0, -60.0, 60.0, 120.0]


ALTERNATE = [45.0, -45.0, 45.0, -45.0]


ZERO = [0.0, 0.0, 0.0, 0.0]


@pytest.mark.parametrize(
    "demand, sigma0, internal, h_stop, tol",
    [
        # the notes' forward runs (§8.3 [CHECK] table), |h| printed to 3 decimals
        ([1, 0, 0], PREFERRED, False, 3.155, 1e-3),
        ([1, 0, 0], ALTERNATE, False, 3.155, 1e-3),
        ([1, 0, 0], ZERO, True, 1.155, 1e-3),
        ([0, 1, 0], PREFERRED_Y, False, 3.155, 1e-3),
        ([0, 1, 0], ALTERNATE, False, 3.155, 1e-3),
        ([0, 1, 0], ZERO, True, 1.155, 1e-3),
        ([0, 0, 1], ZERO, False, 3.266, 1e-3),
        # the pseudo-inverse passes this singularity with finite rates: det(CCᵀ) touches 0 at
        # |h| = 1.2918 (between solve_ivp's steps); the notes stop at 1.282 on their own threshold
        ([0, 0, 1], ALTERNATE, True, 1.287, 5e-3),
        ([1, 1, 1], ZERO, False, 3.165, 1e-3),
        ([1, 1, 1], ALTERNATE, False, 3.165, 1e-3),
        ([4, 2, 0], PREFERRED, False, 3.221, 1e-3),
        ([4, 2, 0], ALTERNATE, False, 3.221, 1e-3),
        ([2, 4, 0], PREFERRED_Y, False, 3.221, 1e-3),
        ([2, 4, 0], ALTERNATE, False, 3.221, 1e-3),
        ([4, 2, 0], ZERO, True, 1.291, 1e-3),
    ],
)
def test_v5_preferred_sets_reach_saturation_and_zero_gimbals_do_not(
    demand, sigma0, internal, h_stop, tol
):
    u = np.asarray(demand, float) / np.linalg.norm(demand)
    run = cmg_pyramid.integrate_gimbals(DEG(sigma0), -u, 10.0)  # unit demand ḣ = u: torque −u
    assert run.singular
    assert np.linalg.norm(run.h[-1]) == pytest.approx(h_stop, abs=tol)
    assert cmg.classify_singularity(run.sigma[-1], threshold=1e-5).internal == internal
    if not internal:  # saturation on the ray: at most the envelope (support) value along u
        assert np.linalg.norm(run.h[-1]) <= cmg.envelope(u)[0] + 1e-12


def kurokawa(t):
    """V6's demand ḣ = [0.2 sin 4πt, 0.3, 0] (§8.3, L4640), as the spacecraft torque −ḣ."""
    return -np.array([0.2 * np.sin(4.0 * np.pi * t), 0.3, 0.0])


@pytest.mark.parametrize("sigma0", [PREFERRED_Y, ALTERNATE])
def test_v6_kurokawa_torque_saturates_at_about_ten_seconds_without_internal_singularity(sigma0):
    run = cmg_pyramid.integrate_gimbals(DEG(sigma0), kurokawa, 20.0, n_out=401)
    assert run.singular
    # the pseudo-inverse tracks the demand exactly: h(t) = h(0) + ∫ḣ, h(0) = 0 for both sets
    # (to the 1.1e-4 of the rounded skew for PREFERRED_Y, V1)
    h0 = cmg.momentum(DEG(sigma0))
    expect = h0 + np.stack(
        [0.2 * (1.0 - np.cos(4.0 * np.pi * run.t)) / (4.0 * np.pi), 0.3 * run.t, 0.0 * run.t],
        axis=-1,
    )
    np.testing.assert_allclose(run.h, expect, atol=1e-8)  # solve_ivp rtol 1e-10 on σ, |h| ~ 3
    # the stop is saturation (external), on the y envelope 3.1546: the x demand averages out
    sing = cmg.classify_singularity(run.sigma[-1], threshold=1e-5)
    assert not sing.internal
    h_env = cmg.envelope([0.0, 1.0, 0.0])[0]
    assert run.h[-1, 1] == pytest.approx(h_env, abs=1e-3)
    # so t_sat = (envelope − h_y(0)) / 0.3 = 10.515 s for both sets (the paper's "about ten
    # seconds"; the notes' 10.51 s, printed to 0.01 s). The gain stop at 1e-6 leaves h_y 1e-5
    # short of the envelope (measured), i.e. 3e-5 s: well inside 1e-3 s
    assert run.t[-1] == pytest.approx((h_env - h0[1]) / 0.3, abs=1e-3)
    assert run.t[-1] == pytest.approx(10.51, abs=0.01)
    # from zero gimbals the same demand goes internally singular at 3.85 s (the notes' [CHECK])
    zero = cmg_pyramid.integrate_gimbals(np.zeros(4), kurokawa, 20.0)
    assert zero.singular and zero.t[-1] == pytest.approx(3.85, abs=5e-3)
    assert cmg.classify_singularity(zero.sigma[-1], threshold=1e-5).internal


def test_v7_bedrossian_torque_is_singular_from_zero_gimbals_and_not_from_the_alternate_set():
    torque = -np.array([0.707, 0.707, 0.0])  # |Tx| = |Ty| = 0.707, the notes' (+, +) signs
    zero = cmg_pyramid.integrate_gimbals(np.zeros(4), torque, 10.0)
    assert zero.singular
    assert cmg.classify_singularity(zero.sigma[-1], threshold=1e-5).internal
    # the gain reaches 1e-6 at 1.531 s (h = 1.0825 [1, 1, 0]); the paper's "1.5 s" is read off
    # Fig. 6 (±0.05 s, the figure's resolution). The notes' 1.508 s (h = 1.066) is the same
    # approach stopped earlier: det(CCᵀ) = 1e-3 there
    assert zero.t[-1] == pytest.approx(1.5, abs=0.05)
    np.testing.assert_allclose(zero.h[-1], [1.0825, 1.0825, 0.0], atol=1e-4)
    early = cmg_pyramid.integrate_gimbals(np.zeros(4), torque, 10.0, threshold=1e-3)
    assert early.t[-1] == pytest.approx(1.508, abs=1e-3)  # the notes print 4 digits
    # from [45, −45, 45, −45]° no internal singularity: it runs to the envelope along [1, 1, 0]
    alt = cmg_pyramid.integrate_gimbals(DEG(ALTERNATE), torque, 10.0)
    assert alt.singular and not cmg.classify_singularity(alt.sigma[-1], threshold=1e-5).internal
    u = np.array([1.0, 1.0, 0.0]) / np.sqrt(2.0)
    assert alt.h[-1] @ u == pytest.approx(cmg.envelope(u)[0], abs=1e-3)
    np.testing.assert_allclose(alt.h[-1], [2.309, 2.309, 0.0], atol=1e-3)  # notes, 3.27 s
    assert alt.t[-1] == pytest.approx(3.27, abs=5e-3)


def test_preferred_angles_for_x_land_on_the_v4_set():
    got = np.rad2deg(cmg_pyramid.preferred_angles([1.0, 0.0, 0.0]))
    # the paper's [−59.6, 60.7, 118, −121]° (±0.5°) and the notes' 0.01° reproduction (V4)
    np.testing.assert_allclose(got, [-59.6, 60.7, 118.0, -121.0], atol=0.5)
    np.testing.assert_allclose(got, [-59.66, 60.58, 117.98, -121.12], atol=0.01)


@pytest.mark.parametrize("u", [[1, 0, 0], [0, 1, 0], [0, 0, 1], [-1, 0, 0], [0, -1, 0], [0, 0, -1]])
def test_preferred_angles_run_forward_to_the_envelope_without_internal_singularity(u):
    u = np.asarray(u, float)
    sigma0 = cmg_pyramid.preferred_angles(u)
    assert np.all(np.abs(sigma0) <= np.pi)
    # near zero momentum: u·h = 0 to the integrator's error; the normal part is the
    # perturbation's (1–3° offsets from saturation leave |h| < 0.07)
    h0 = cmg.momentum(sigma0)
    assert h0 @ u == pytest.approx(0.0, abs=1e-8)
    assert np.linalg.norm(h0) < 0.07
    run = cmg_pyramid.integrate_gimbals(sigma0, -u, 10.0)  # the same unit demand ḣ = u
    assert run.singular and not cmg.classify_singularity(run.sigma[-1], threshold=1e-5).internal
    # saturation on the envelope along u, within V5's 1e-3 (the gain stop and the normal part)
    assert run.h[-1] @ u == pytest.approx(cmg.envelope(u)[0], abs=1e-3)


def test_null_motion_beside_the_torque_law_avoids_the_v3_singularity():
    # V3: the pseudo-inverse alone from zero gimbals under ḣ = +x stops at |h| = 1.1546.
    # With the null motion towards the stored +x set running beside it (k = 1/s, exact
    # projector), the delivered momentum is unchanged, h(t) = t x (Cτ = 0), and the gimbals
    # reach saturation on the envelope 2cosδ + 2 instead
    target = cmg.preferred_set([1.0, 0.0, 0.0])
    run = cmg_pyramid.integrate_gimbals(
        np.zeros(4), PAPER_X, 10.0, null_target=target, null_gain=1.0
    )
    assert run.singular and not cmg.classify_singularity(run.sigma[-1], threshold=1e-5).internal
    h_sat = 2.0 * np.cos(SKEW) + 2.0
    assert run.t[-1] == pytest.approx(h_sat, abs=1e-3)  # the gain stop, as V5
    # solve_ivp's rtol 1e-10 on σ (|σ| ~ 3) over ~3 s: momentum error well below 1e-8
    np.testing.assert_allclose(run.h, run.t[:, None] * [1.0, 0.0, 0.0], atol=1e-8)
    # the rates are the steering law's plus a null-space term: C σ̇ = −torque exactly
    sigma = DEG([10.0, -20.0, 30.0, 5.0])
    rates = cmg.steering_with_null_motion(sigma, [0.3, -0.2, 0.1], target, 2.0)
    c = cmg.jacobian(sigma)
    np.testing.assert_allclose(c @ rates, [-0.3, 0.2, -0.1], atol=100 * EPS)
    with pytest.raises(ValueError, match="gain_k: must be >= 0"):
        cmg.steering_with_null_motion(sigma, [0.0, 0.0, 0.0], target, -1.0)
    with pytest.raises(ValueError, match="null_target: one gimbal set"):
        cmg_pyramid.integrate_gimbals(np.zeros(4), PAPER_X, 1.0, null_target=np.zeros((2, 4)))


def test_v8_null_motion_reorients_zero_gimbals_to_the_alternate_set():
    # σ = s[1, −1, 1, −1] has h ≡ 0 (§8.5 [CHECK]), and d = k(σ_f − σ) lies along that line, so
    # the law moves s' = k(45° − s): s = 45°(1 − e^{−kt}), exactly, whatever the projector does
    run = cmg_pyramid.reorient(
        np.zeros(4), DEG(ALTERNATE), 10.0, gain_k=1.0, alpha=1e-3, n_out=1001
    )
    s = DEG(45.0) * (1.0 - np.exp(-run.t))
    np.testing.assert_allclose(run.sigma, s[:, None] * [1.0, -1.0, 1.0, -1.0], atol=1e-8)
    np.testing.assert_allclose(run.h, 0.0, atol=1e-12)  # no torque on the spacecraft
    # it crosses the singular set s = 30° at t = ln 3 = 1.0986 s (notes: 1.10); the gain there
    # is exactly 0 at the magic skew arccos(1/√3), 2.3e-8 at the paper's rounded 54.74°
    line30 = DEG(30.0) * np.array([1.0, -1.0, 1.0, -1.0])
    assert cmg.gain(line30, MAGIC) < 1e-14 and cmg.gain(line30) < 1e-7
    assert run.t[np.argmin(run.gain)] == pytest.approx(np.log(3.0), abs=run.t[1])


def test_sr_runs_can_pass_singular_sets_without_stopping():
    # stop_at_singular=False with α > 0: from the +x saturation set (V2, exactly singular) the
    # run goes on to t_final and says it met a singular set; the pseudo-inverse refuses to start
    saturated = DEG([-90.0, 180.0, 90.0, 0.0])
    run = cmg_pyramid.integrate_gimbals(
        saturated, -PAPER_X, 2.0, alpha=1e-3, stop_at_singular=False
    )
    assert run.singular and run.t[-1] == 2.0
    # the demand −x (torque +x) pulls the momentum back inside the envelope, at a reduced rate
    # while the SR inverse is near the singular set: |h| falls, never rises
    assert run.h[-1, 0] < run.h[0, 0] and np.all(np.diff(run.h[:, 0]) <= 1e-12)
    with pytest.raises(ValueError, match="starts singular"):
        cmg_pyramid.integrate_gimbals(saturated, -PAPER_X, 2.0)


def test_reorient_through_simulate_is_the_engines_continuous_run():
    # simulate's continuous-law mode (reorient_simulation's triple) and the engine's
    # continuous.run on the same grid, law and tolerances take the same DOP853 steps: the
    # sampled gimbal angles agree to the round-off of the two time grids (k·dt vs linspace)
    sigma0, target = np.zeros(4), DEG(ALTERNATE)
    run = cmg_pyramid.reorient(sigma0, target, 10.0, 1.0, alpha=1e-3, n_out=501)
    plant, law, config, options = cmg_pyramid.reorient_simulation(
        sigma0, target, 10.0, 1.0, alpha=1e-3, n_out=501
    )
    assert isinstance(plant, GimbalCluster) and config.law_mode == "continuous"
    direct = continuous.run(plant, law, np.linspace(0.0, 10.0, 501), sigma0, 1e-10, 1e-12)
    np.testing.assert_allclose(run.t, direct.t, rtol=4 * EPS)
    np.testing.assert_allclose(run.sigma, direct.states[0], rtol=0, atol=1e-14)
    # the runner's path: the triple handed to simulate, read back by gimbal_run
    again = cmg_pyramid.gimbal_run(plant, simulate(plant, law, config, **options).dataset)
    np.testing.assert_array_equal(again.sigma, run.sigma)
    assert not again.singular and again.sigma.shape == (501, 4)


@pytest.mark.parametrize("target", [ALTERNATE, [30.0, -80.0, 10.0, 100.0]])
def test_reorientation_lyapunov_function_never_rises(target):
    # Eq. 16: V = ½|σ_f − σ|², V' = −k dᵀτd with τ = I − Cᵀ(CCᵀ + αI)⁻¹C, whose eigenvalues
    # α/(s² + α) and 1 lie in (0, 1]: V' <= 0 for any α > 0. On the samples V falls, to the
    # integrator's error (rtol 1e-10 on σ ~ 1 rad: 1e-9 on V)
    run = cmg_pyramid.reorient(np.zeros(4), DEG(target), 8.0, 2.0, alpha=1e-2, n_out=401)
    V = 0.5 * np.sum((DEG(target) - run.sigma) ** 2, axis=-1)
    assert np.all(np.diff(V) <= 1e-9)
    assert V[-1] < V[0]
    # the momentum the null motion leaves behind: σ_f off the null manifold of σ(0) cannot be
    # reached without torque, so V stalls above 0 there; along the h ≡ 0 line it goes to 0
    if target == ALTERNATE:
        assert V[-1] < 1e-6


def test_bad_input_is_named_by_field():
    triple = cmg_pyramid.reorient_simulation
    for call, message in [
        (lambda: triple(np.zeros(4), np.ones(4), 1.0, n_out=1), "n_out"),
        (
            lambda: cmg_pyramid.reorient_simulation(np.zeros(4), np.ones(4), 1.0, n_out=True),
            "n_out",
        ),
        (lambda: triple(np.zeros(4), np.ones(4), -1.0), "t_final"),
        (lambda: triple(np.zeros(5), np.ones(4), 1.0), "sigma"),
        (
            lambda: cmg_pyramid.reorient_simulation(np.zeros(4), np.ones(4), 1.0, alpha=-1.0),
            "alpha",
        ),
    ]:
        with pytest.raises(ValueError, match=message):
            call()


@pytest.mark.parametrize(
    "call, message",
    [
        (
            lambda: cmg_pyramid.integrate_gimbals(np.zeros(4), [1.0, 0.0, 0.0], 0.0),
            "t_final: must be",
        ),
        (
            lambda: cmg_pyramid.reorient(np.zeros(4), np.ones(4), 1.0, gain_k=0.0),
            "gain_k: must be > 0",
        ),
        (
            lambda: cmg_pyramid.reorient(np.zeros(4), np.ones(3), 1.0),
            "sigma_target: last axis must hold the 4",
        ),
        (
            lambda: cmg_pyramid.integrate_gimbals([True, 0.0, 0.0, 0.0], [1.0, 0.0, 0.0], 1.0),
            "sigma0: gimbal angles must be numbers",
        ),
        (
            lambda: cmg_pyramid.integrate_gimbals(
                np.zeros(4), [1.0, 0.0, 0.0], -1.0, null_target=np.zeros(4)
            ),
            "null_target: null motion runs forward only",
        ),
        (
            lambda: cmg_pyramid.integrate_gimbals(
                DEG([-90.0, 180.0, 90.0, 0.0]), [1.0, 0.0, 0.0], 1.0
            ),
            "sigma0: starts singular",
        ),
        (
            lambda: cmg_pyramid.preferred_angles([1.0, 0.0, 0.0], n_units=3),
            "perturbation: required",
        ),
        (
            lambda: cmg_pyramid.preferred_angles([1.0, 0.0, 0.0], perturbation=np.zeros(4)),
            "perturbation: must be a nonzero",
        ),
        (lambda: cmg_pyramid.preferred_angles([0.0, 0.0, 0.0]), "direction: must be nonzero"),
        (
            lambda: cmg_pyramid.integrate_gimbals(np.zeros(4), lambda t: [1.0, 0.0], 1.0),
            "torque: the callable must return 3",
        ),
        (
            lambda: cmg_pyramid.integrate_gimbals(np.zeros(4), lambda t: [np.nan, 0.0, 0.0], 1.0),
            "torque: must be finite",
        ),
    ],
)
def test_bad_input_is_named(call, message):
    with pytest.raises(ValueError, match=message):
        call()
