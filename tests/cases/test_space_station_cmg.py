"""Space-station momentum management with CMGs (issue 14, F26, V9): the
Bryson-weighted LQR equals the Riccati solution of the unscaled problem, the station settles at
its torque-equilibrium attitude with the periodic disturbance filtered out of pitch, the CMG
loop delivers the attitude loop's momentum, and — the paper's point — σ(0) = 0 meets an
internal singularity early in the first orbit while [45, −45, 45, −45]° does not."""

import numpy as np
import pytest
import scipy.linalg as sl

from flexsat.cases import space_station_cmg as st
from flexsat.dynamics import cmg
from flexsat.dynamics import space_station as ss

DESIGN = st.design()
DATA = DESIGN.data
ALTERNATE = np.deg2rad([45.0, -45.0, 45.0, -45.0])


@pytest.mark.parametrize("group", ["pitch", "roll_yaw"])
def test_scaled_design_is_the_bryson_lqr(group):
    A, B, _, names, K, poles = getattr(DESIGN, group)
    D = DESIGN.maxima.scales(names, DATA.orbit_rate)
    # Q = diag(1/x_max²), R = I (python-control's K = R⁻¹BᵀS); scipy's balanced Schur solver
    # copes with the raw weights to ~1e-12 relative (measured), the bound used here is 1e-9
    S = sl.solve_continuous_are(A, B, np.diag(D**-2.0), np.eye(B.shape[1]))
    np.testing.assert_allclose(K, B.T @ S, rtol=0, atol=1e-9 * np.abs(K).max())
    assert np.all(poles.real < 0)
    # attitude-loop bandwidth: the paper's "of the order of .01 r/sec" (L4715); ours is 0.006
    assert 1e-3 < np.abs(poles).max() < 0.02


def test_station_settles_at_the_torque_equilibrium_attitude():
    # with ∫h in the loop the mean momentum goes to 0, so gravity gradient balances the
    # disturbance bias (Eq. 8 with u = 0): θ2 = w2/(3n²(I1 − I3)), θ1 = w1/(4n²(I2 − I3)),
    # θ3 = w3/(n²(I2 − I1)) = 8.58° (yaw)
    run = st.simulate_attitude(DESIGN, 12 * DATA.period, n_out=12 * 200 + 1)
    I1, I2, I3 = DATA.inertia
    n2 = DATA.orbit_rate**2
    tea = ss.FT_LB * np.array(
        [1.0 / (4 * n2 * (I2 - I3)), 4.0 / (3 * n2 * (I1 - I3)), 1.0 / (n2 * (I2 - I1))]
    )
    last = run.attitude[-200:]  # the 12th orbit
    # slowest closed-loop pole |Re| 4.9e-5 1/s: after 11 orbits e^-3 of the ~0.1° transient
    np.testing.assert_allclose(np.rad2deg(last.mean(axis=0)), np.rad2deg(tea), atol=0.005)
    # the pitch filters at n and 2n reject Eq. (11)'s harmonics from θ2 (the roll/yaw loops
    # have only 2n filters, so their attitude keeps an orbit-rate ripple)
    assert np.rad2deg(np.ptp(last[:, 1])) < 0.1 * np.rad2deg(np.ptp(last[:, 2]))


def test_v9_zero_gimbals_go_singular_in_the_first_orbit_and_the_alternate_set_does_not():
    run = st.simulate_attitude(DESIGN, 2 * DATA.period, disturbance="aero_substitute")
    zero = st.cmg_loop(run, np.zeros(4))
    # the paper: "a singularity is encountered quite early in the first orbit (in about 720
    # seconds)". With our Bryson maxima and the AERO1 substitute (neither is the paper's):
    # internal, at 494 s (measured; the weight scan in docs/cmg.md moves it)
    assert zero.singular and zero.t[-1] < DATA.period / 4
    assert zero.t[-1] == pytest.approx(494.3, abs=1.0)
    assert cmg.classify_singularity(zero.sigma[-1], threshold=1e-5).internal
    # "[45, −45, 45, −45]: no singular states ... momentum within limits" over two orbits
    alt = st.cmg_loop(run, ALTERNATE)
    assert not alt.singular and alt.t[-1] == pytest.approx(2 * DATA.period)
    assert alt.gain.min() > 0.01
    # the gimbals deliver the attitude loop's momentum (pseudo-inverse: ḣ = T exactly); the
    # alternate set holds h = 0; rtol 1e-10 on σ over 11,424 s gives ~1e-9 h_r
    np.testing.assert_allclose(alt.h, run.momentum / DATA.rotor_momentum, atol=1e-8)
    assert np.linalg.norm(alt.h, axis=1).max() < cmg.envelope([0.0, 1.0, 0.0])[0]


def test_with_the_design_disturbance_alone_zero_gimbals_do_not_go_singular():
    # the measured counterpoint: with Eq. (11) alone the momentum peaks at 1.20 h_r over two
    # orbits, but along a path that misses the internal singular surface met from zero gimbals
    # (at 1.155 h_r along x or y, 1.291 along [4, 2, 0]: V3, V5): no singularity from σ(0) = 0.
    # So with our weights the paper's V9 needs the extra aerodynamic torque
    run = st.simulate_attitude(DESIGN, 2 * DATA.period)
    peak = np.linalg.norm(run.momentum, axis=1).max() / DATA.rotor_momentum
    assert peak == pytest.approx(1.20, abs=0.01)
    assert not st.cmg_loop(run, np.zeros(4)).singular


def test_the_station_and_its_gimbals_are_one_simulation():
    # one plant (station state, then σ) under one law (u = −Kx, σ̇ = C⁺T): within the run the
    # cluster's momentum change is the station model's, h_r (h(σ) − h(σ0)) = h − h(0), since
    # ḣ = u + [n h3, 0, −n h1] = h_r T (Eq. 10) and C σ̇ = T; DOP853 at rtol 1e-10 over a
    # quarter orbit keeps both to ~1e-9 h_r
    from flexsat.dynamics.station_gimbals import StationWithGimbals
    from flexsat.sim import simulate

    quarter = DATA.period / 4
    plant, law, config, options = st.cmg_simulation(
        DESIGN, quarter, "aero_substitute", "1 deg", ALTERNATE
    )
    assert isinstance(plant, StationWithGimbals) and config.law_mode == "continuous"
    ds = simulate(plant, law, config, **options).dataset
    assert ds.attrs["stopped"] == 0 and np.isnan(ds.attrs["stop_time"])
    hr = DATA.rotor_momentum
    sig = ds["gimbal_angles"].values[0]
    h_model = ds["momentum"].values[0]
    np.testing.assert_allclose(
        hr * (cmg.momentum(sig) - cmg.momentum(ALTERNATE)), h_model - h_model[0], atol=1e-8 * hr
    )
    # the station part is the attitude loop alone (the same ODE, other step sizes): the two
    # runs' global errors at rtol 1e-10 differ by ~6e-10 of the largest value (measured);
    # bound 1e-8 of it
    alone = st.simulate_attitude(DESIGN, quarter, "aero_substitute")
    for name, ref in (("attitude", alone.attitude), ("torque", alone.torque)):
        np.testing.assert_allclose(ds[name].values[0], ref, rtol=0, atol=1e-8 * np.abs(ref).max())


@pytest.mark.parametrize(
    "call, message",
    [
        (
            lambda: st.cmg_simulation(
                DESIGN, 100.0, "design", "1 deg", np.deg2rad([-90.0, 180.0, 90.0, 0.0])
            ),
            "sigma0: starts singular",
        ),
        (
            lambda: st.cmg_simulation(DESIGN, 100.0, "design", "1 deg", [False, 0, 0, 0]),
            "sigma0: gimbal angles must be numbers",
        ),
        (
            lambda: st.cmg_simulation(DESIGN, 100.0, "design", "1 deg", np.zeros(3)),
            "sigma0: last axis must hold the 4",
        ),
        (
            lambda: st.cmg_simulation(DESIGN, 100.0, "design", "1 deg", np.zeros(4), 0.0),
            "threshold: must be > 0",
        ),
        (lambda: st.attitude_simulation(DESIGN, 100.0, n_out=1), "n_out: must be an integer"),
        (lambda: st.BrysonMaxima(attitude="0 deg"), "maxima.attitude: must be"),
        (lambda: st.BrysonMaxima(rate="1 furlong"), "maxima.rate"),
        (lambda: st.design(roll_yaw_filters=(1, 2)), "roll_yaw_filters: .*not stabilizable"),
        (lambda: st.simulate_attitude(DESIGN, 100.0, disturbance="AERO1"), "disturbance: must be"),
        (lambda: st.simulate_attitude(DESIGN, -1.0), "duration: must be"),
    ],
)
def test_bad_input_is_named(call, message):
    with pytest.raises(ValueError, match=message):
        call()
