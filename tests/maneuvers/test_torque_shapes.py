"""Tests of flexsat.maneuvers.torque_shapes (seed 000 Att. 3 Eqs. 12-16; seed 001 Eqs. 25-37)."""

import numpy as np
import pytest
from scipy.integrate import quad

from flexsat.maneuvers import (
    BangBang,
    PseudoSquare,
    Reference,
    Sinusoidal,
    SmoothBangBang,
    TorqueShape,
)
from flexsat.units import to_si

# Junkins/Rahman/Bang hub experiment (seed 000, Att. 3 Table 1): I = 2128 oz-in-s^2, 40 deg slew.
I_TAMU = to_si("2128 ozf*in*s**2", "kg*m**2")
ANGLE_40 = np.deg2rad(40.0)
# NPS simulator (seed 001): 60 deg slew, I = 9.84 kg m^2.
I_NPS = 9.84
ANGLE_60 = np.deg2rad(60.0)


def shapes():
    """One representative of each shape, both slew directions, nonzero theta0."""
    return [
        BangBang(0.7, 3.0, u_max=0.5, theta0=0.2),
        BangBang(-1.3, 2.0, duration=4.0),
        SmoothBangBang(0.7, 3.0, u_max=0.5, alpha=0.1, theta0=0.2),
        SmoothBangBang(-1.3, 2.0, duration=6.0, alpha=0.25),
        SmoothBangBang(ANGLE_40, I_TAMU, u_max=2.0, duration=5.0, theta0=-0.3),
        PseudoSquare(0.7, 3.0, u_max=0.5, rise_time=0.5, theta0=0.2),
        PseudoSquare(-1.3, 2.0, duration=10.0, rise_time=2.5),
        PseudoSquare(ANGLE_60, I_NPS, u_max=0.45, duration=10.0),
        Sinusoidal(0.7, 3.0, u_max=0.5, theta0=0.2),
        Sinusoidal(-1.3, 2.0, duration=4.0),
    ]


def breakpoints(s):
    """Times where the published piecewise definitions switch branch."""
    T = float(s.duration)
    if isinstance(s, SmoothBangBang):
        d = float(s.alpha) * T
        return [0.0, d, T / 2 - d, T / 2, T / 2 + d, T - d, T]
    if isinstance(s, PseudoSquare):
        r = float(s.rise_time)
        return [0.0, r, T / 2 - r, T / 2, T / 2 + r, T - r, T]
    return [0.0, T / 2, T]


def ids(s):
    return f"{type(s).__name__}({float(s.angle):+.3g})"


SHAPES = shapes()


# --------------------------------------------------------------------------- published numbers


@pytest.mark.parametrize("alpha, T_pub", [(0.0, 3.8544), (0.1, 4.2986), (0.2, 4.9109)])
def test_junkins_maneuver_time_400_ozin(alpha, T_pub):
    # Published to 4 decimals: the exact value must round to it (|error| <= half a unit of 1e-4).
    s = SmoothBangBang(ANGLE_40, I_TAMU, u_max=to_si("400 ozf*in", "N*m"), alpha=alpha)
    assert abs(float(s.duration) - T_pub) <= 5e-5


@pytest.mark.parametrize(
    "u_ozin, row",
    [
        (100, [7.7088, 8.1212, 8.5972, 9.1551, 9.8219, 10.6391]),
        (600, [3.1471, 3.3155, 3.5098, 3.7375, 4.0098, 4.3434]),
    ],
)
def test_junkins_maneuver_time_table(u_ozin, row):
    # Table of T (Eq. 16) over alpha; 4 published decimals -> half-unit tolerance 5e-5 s.
    alphas = np.array([0.0, 0.05, 0.1, 0.15, 0.2, 0.25])
    s = SmoothBangBang(ANGLE_40, I_TAMU, u_max=to_si(f"{u_ozin} ozf*in", "N*m"), alpha=alphas)
    assert s.duration.shape == (6,)
    np.testing.assert_allclose(s.duration, row, rtol=0, atol=5e-5)


def test_nps_sinusoid_amplitude():
    # Seed 001 spec V5 quotes A = 0.6475 N m (4 significant digits). Eq. 36 with 60 deg = pi/3
    # rad exactly gives 0.64744605 N m, which rounds to 0.6474, not 0.6475 (0.6475 would need
    # I = 9.8408 kg m^2). So the quoted value is checked to one unit of its last digit (1e-4 N m),
    # and the exact Eq. 36 value to 1e-8 (rounding only).
    s = Sinusoidal(ANGLE_60, I_NPS, duration=10.0)
    assert abs(float(s.u_max) - 0.6475) <= 1e-4
    assert abs(float(s.u_max) - 0.64744605) <= 1e-8
    # Eq. 36 literally
    assert float(s.u_max) == pytest.approx(2 * np.pi * I_NPS * ANGLE_60 / 10.0**2, rel=1e-15)


def test_nps_pseudo_square_torque():
    # 4 significant digits -> half-unit tolerance 5e-5 N m.
    s = PseudoSquare(ANGLE_60, I_NPS, duration=10.0, rise_time=1.0)
    assert abs(float(s.u_max) - 0.4823) <= 5e-5


# --------------------------------------------------------------------------- literal equations


def junkins_f(t, T, alpha):
    """Att. 3 Eq. 12 written out piece by piece (alpha > 0)."""
    d = alpha * T
    t1, t2, t3 = T / 2 - d, T / 2 + d, T - d
    h = lambda x: x**2 * (3 - 2 * x)  # noqa: E731
    return np.select(
        [t <= d, t <= t1, t <= t2, t <= t3, t <= T],
        [h(t / d), 1.0, 1 - 2 * h((t - t1) / (2 * d)), -1.0, -1 + h((t - t3) / d)],
    )


def nps_f(t, P, r):
    """Seed 001 Eq. 26 with the third piece read as sin(pi (t - P/2 - 2 t_r) / (2 t_r))."""
    return np.select(
        [t <= r, t <= P / 2 - r, t <= P / 2 + r, t <= P - r, t <= P],
        [
            np.sin(np.pi * t / (2 * r)),
            1.0,
            np.sin(np.pi * (t - P / 2 - 2 * r) / (2 * r)),
            -1.0,
            np.sin(np.pi * (t - P + 4 * r) / (2 * r)),
        ],
    )


def test_smooth_bang_bang_torque_is_eq12():
    # The mirrored implementation must reproduce the five printed pieces; both are closed forms of
    # O(1) size, so they agree to rounding (1e-13 relative).
    s = SmoothBangBang(-0.9, 2.0, u_max=0.7, alpha=0.15)
    t = np.linspace(0, float(s.duration), 2001)[:-1]
    np.testing.assert_allclose(s(t).u, -0.7 * junkins_f(t, float(s.duration), 0.15), atol=1e-13)


def test_pseudo_square_torque_is_eq26():
    s = PseudoSquare(0.9, 2.0, duration=8.0, rise_time=1.5)
    t = np.linspace(0, 8.0, 2001)[:-1]
    np.testing.assert_allclose(s(t).u, float(s.u_max) * nps_f(t, 8.0, 1.5), atol=1e-13)
    # the OCR-fixed reversal passes through 1, 0, -1 (continuity of Eq. 26)
    np.testing.assert_allclose(nps_f(np.array([2.5, 4.0, 5.5]), 8.0, 1.5), [1, 0, -1], atol=1e-15)


@pytest.mark.parametrize("angle, theta0", [(ANGLE_60, 0.0), (-0.4, 0.3)])
def test_sinusoid_is_eqs_33_to_35(angle, theta0):
    # Paper's reference is the error to go (Eqs. 33-35 with dtheta = angle); ours is
    # theta0 + angle - theta_paper. Same closed forms reordered: agreement to rounding (1e-13).
    P = 10.0
    s = Sinusoidal(angle, I_NPS, duration=P, theta0=theta0)
    t = np.linspace(0, P, 1001)[:-1]
    w = 2 * np.pi * t / P
    theta_p = angle * (1 + (1 / P) * ((P / (2 * np.pi)) * np.sin(w) - t))  # Eq. 33
    theta_dot_p = (angle / P) * (np.cos(w) - 1)  # Eq. 34
    theta_ddot_p = -(2 * np.pi * angle / P**2) * np.sin(w)  # Eq. 35
    r = s(t)
    np.testing.assert_allclose(r.theta, theta0 + angle - theta_p, rtol=0, atol=1e-13)
    np.testing.assert_allclose(r.theta_dot, -theta_dot_p, rtol=0, atol=1e-13)
    np.testing.assert_allclose(r.theta_ddot, -theta_ddot_p, rtol=0, atol=1e-13)
    # Eq. 35 second form: theta_ddot_paper = -(A/I) sin(2 pi t / P)
    np.testing.assert_allclose(
        r.theta_ddot, np.sign(angle) * float(s.u_max) / I_NPS * np.sin(w), rtol=0, atol=1e-13
    )


# --------------------------------------------------------------------------- rest-to-rest


@pytest.mark.parametrize("s", SHAPES, ids=ids)
def test_starts_and_ends_at_rest(s):
    T = float(s.duration)
    theta0, target = float(s.theta0), float(s.theta0 + s.angle)
    # Just below T the closed form itself is evaluated (t >= T is clamped to the target): its
    # error is rounding of O(|angle|) numbers, far below 1e-12 rad; rate ~ u/I * 1 ulp of T.
    r = s(np.nextafter(T, 0.0))
    assert abs(r.theta - target) < 1e-12
    assert abs(r.theta_dot) < 1e-12
    r0 = s(0.0)
    assert r0.theta == theta0 and r0.theta_dot == 0.0
    for t in (T, T + 1.0, 1e9):
        r = s(t)
        assert r.theta == target and r.theta_dot == 0.0 and r.u == 0.0 and r.theta_ddot == 0.0
    for t in (-1e-9, -5.0):
        r = s(t)
        assert r.theta == theta0 and r.theta_dot == 0.0 and r.u == 0.0 and r.theta_ddot == 0.0


@pytest.mark.parametrize("s", SHAPES, ids=ids)
def test_continuity_at_breakpoints(s):
    # Compare both sides of each breakpoint at +-delta, delta = 1e-10 T. A continuous x moves by
    # at most 2 delta sup|x'|; sup|u'| <= u_max * 3/(2 alpha T) or pi/(2 t_r) (<= 15 u_max/T for
    # the shapes here), so every smooth variation is < 1e-8 of its scale, while a jump (wrong
    # branch, wrong S) is O(1) of the scale. Tolerance 1e-7 of scale.
    T = float(s.duration)
    delta = 1e-10 * T
    a = abs(float(s.angle))
    scale = {"u": float(s.u_max), "theta": a, "theta_dot": a / T}
    names = ["theta", "theta_dot"] if isinstance(s, BangBang) else ["u", "theta", "theta_dot"]
    for b in breakpoints(s):
        lo, hi = s(b - delta), s(b + delta)
        for n in names:
            assert abs(getattr(hi, n) - getattr(lo, n)) <= 1e-7 * scale[n], (b, n)


def test_continuity_check_detects_a_jump():
    # The criterion above is not vacuous: bang-bang torque jumps by 2 u_max at T/2.
    s = BangBang(1.0, 1.0, u_max=1.0)
    T = float(s.duration)
    assert abs(s(T / 2 + 1e-10 * T).u - s(T / 2 - 1e-10 * T).u) > 1e-7


@pytest.mark.parametrize("s", SHAPES, ids=ids)
def test_matches_numerical_integration(s):
    # theta_dot = int_0^t u/I, theta - theta0 = int_0^t (t - s) u(s)/I ds (Cauchy), by adaptive
    # quadrature split at the breakpoints (integrand smooth within pieces; epsabs 1e-13 ->
    # errors ~1e-13). Required agreement 1e-9; t = T also checks u_max against the angle relation.
    T = float(s.duration)
    I = float(s.inertia)
    acc = lambda x: float(s(x).u) / I  # noqa: E731
    pts = breakpoints(s)
    for t in np.concatenate([np.linspace(0, T, 13)[1:], pts[1:-1] + [0.37 * T]]):
        inner = [p for p in pts if 0 < p < t]
        kw = dict(points=inner or None, epsabs=1e-13, epsrel=1e-13, limit=200)
        rate = quad(acc, 0, t, **kw)[0]
        ang = quad(lambda x, t=t: (t - x) * acc(x), 0, t, **kw)[0]
        r = s(t)
        assert abs(r.theta_dot - rate) < 1e-9, t
        assert abs(r.theta - s.theta0 - ang) < 1e-9, t


@pytest.mark.parametrize("s", SHAPES, ids=ids)
def test_acceleration_is_torque_over_inertia(s):
    t = np.linspace(-1, float(s.duration) + 1, 777)
    r = s(t)
    assert isinstance(r, Reference)
    np.testing.assert_array_equal(r.theta_ddot, r.u / s.inertia)
    # and it is the derivative of theta_dot: central differences, h = 1e-6 T, error
    # O(h^2 sup|u'''|/I) + O(eps/h) ~ 1e-9 -> 1e-6 of u_max/I. Skip the kinks of bang-bang.
    T = float(s.duration)
    h = 1e-6 * T
    tt = np.linspace(0.013 * T, 0.987 * T, 301)
    if isinstance(s, BangBang):
        tt = tt[np.abs(tt - T / 2) > 2 * h]
    fd = (s(tt + h).theta_dot - s(tt - h).theta_dot) / (2 * h)
    np.testing.assert_allclose(fd, s(tt).theta_ddot, rtol=0, atol=1e-6 * float(s.u_max / s.inertia))


def test_negative_angle_mirrors_positive():
    t = np.linspace(-1, 12, 500)
    for make in (
        lambda a: SmoothBangBang(a, 2.0, u_max=0.3, alpha=0.2, theta0=0.1),
        lambda a: PseudoSquare(a, 2.0, u_max=0.3, rise_time=1.0, theta0=0.1),
        lambda a: Sinusoidal(a, 2.0, u_max=0.3, theta0=0.1),
        lambda a: BangBang(a, 2.0, u_max=0.3, theta0=0.1),
    ):
        p, n = make(0.8)(t), make(-0.8)(t)
        assert np.all(p.u[(t > 0) & (t < 1.0)] > 0)  # positive slew: torque first positive
        np.testing.assert_array_equal(n.u, -p.u)
        np.testing.assert_array_equal(n.theta_dot, -p.theta_dot)
        np.testing.assert_allclose(n.theta - 0.1, -(p.theta - 0.1), rtol=0, atol=1e-15)


# --------------------------------------------------------------------------- special cases


def test_pseudo_square_quarter_rise_is_sinusoid():
    # Different closed forms (piecewise quarter sines vs one sine): agreement to rounding, 1e-13.
    ps = PseudoSquare(-1.1, 3.0, duration=7.0, rise_time=7.0 / 4, theta0=0.4)
    sn = Sinusoidal(-1.1, 3.0, duration=7.0, theta0=0.4)
    assert float(ps.u_max) == pytest.approx(float(sn.u_max), rel=1e-14)
    t = np.linspace(-0.5, 7.5, 1601)
    a, b = ps(t), sn(t)
    for n in ("u", "theta", "theta_dot", "theta_ddot"):
        np.testing.assert_allclose(getattr(a, n), getattr(b, n), rtol=0, atol=1e-13)


def test_alpha_zero_is_bang_bang():
    sb = SmoothBangBang(-1.1, 3.0, u_max=0.6, alpha=0.0, theta0=0.4)
    bb = BangBang(-1.1, 3.0, u_max=0.6, theta0=0.4)
    assert float(sb.duration) == float(bb.duration)
    t = np.linspace(-0.5, float(bb.duration) + 0.5, 1601)
    t = np.append(t, float(bb.duration) / 2)
    a, b = sb(t), bb(t)
    for n in ("u", "theta", "theta_dot", "theta_ddot"):
        np.testing.assert_allclose(getattr(a, n), getattr(b, n), rtol=0, atol=1e-15)


# --------------------------------------------------------------------------- solved parameters


@pytest.mark.parametrize("alpha", [0.0, 0.03, 0.125, 0.2, 0.25])
def test_smooth_bang_bang_round_trip(alpha):
    # closed-form inversions of Eq. 15/16: round trip to rounding (1e-13 relative / absolute)
    a = SmoothBangBang(0.6, 2.0, u_max=0.8, alpha=alpha)
    b = SmoothBangBang(0.6, 2.0, u_max=0.8, duration=a.duration)
    assert float(b.alpha) == pytest.approx(alpha, abs=1e-13)
    c = SmoothBangBang(0.6, 2.0, u_max=0.8, alpha=b.alpha)
    assert float(c.duration) == pytest.approx(float(a.duration), rel=1e-13)
    d = SmoothBangBang(0.6, 2.0, duration=a.duration, alpha=alpha)
    assert float(d.u_max) == pytest.approx(0.8, rel=1e-13)


@pytest.mark.parametrize("ratio", [0.01, 0.1, 0.2, 0.25])
def test_pseudo_square_round_trip(ratio):
    P = 9.0
    a = PseudoSquare(-0.6, 2.0, duration=P, rise_time=ratio * P)
    b = PseudoSquare(-0.6, 2.0, u_max=a.u_max, duration=P)
    assert float(b.rise_time) == pytest.approx(ratio * P, rel=1e-12)
    c = PseudoSquare(-0.6, 2.0, u_max=a.u_max, rise_time=ratio * P)
    assert float(c.duration) == pytest.approx(P, rel=1e-13)


@pytest.mark.parametrize("cls", [BangBang, Sinusoidal])
def test_one_parameter_round_trip(cls):
    a = cls(0.6, 2.0, u_max=0.8)
    b = cls(0.6, 2.0, duration=a.duration)
    assert float(b.u_max) == pytest.approx(0.8, rel=1e-14)
    assert float(b.end_time) == float(a.duration)


# --------------------------------------------------------------------------- batch


def batch_cases(rng, n=1000):
    angle = rng.uniform(0.05, 2.0, n) * rng.choice([-1.0, 1.0], n)
    inertia = rng.uniform(0.5, 20.0, n)
    u_max = rng.uniform(0.1, 3.0, n)
    theta0 = rng.uniform(-1, 1, n)
    frac = rng.uniform(0.0, 0.25, n)
    frac[:3] = [0.0, 0.25, 0.125]  # bang-bang limit, pure-sine limit, midpoint
    duration = rng.uniform(2.0, 10.0, n)
    return angle, inertia, u_max, theta0, frac, duration


def batch_makers():
    return {
        "BangBang": lambda a, i, u, t0, f, T: BangBang(a, i, u_max=u, theta0=t0),
        "SmoothBangBang": lambda a, i, u, t0, f, T: SmoothBangBang(
            a, i, u_max=u, alpha=f, theta0=t0
        ),
        "PseudoSquare": lambda a, i, u, t0, f, T: PseudoSquare(
            a, i, duration=T, rise_time=np.maximum(f, 1e-3) * T, theta0=t0
        ),
        "Sinusoidal": lambda a, i, u, t0, f, T: Sinusoidal(a, i, duration=T, theta0=t0),
    }


@pytest.mark.parametrize("name", list(batch_makers()))
def test_batch_equals_per_case(name):
    make = batch_makers()[name]
    args = batch_cases(np.random.default_rng(7))
    batch = make(*args)
    assert isinstance(batch, TorqueShape)
    assert batch.duration.shape == (1000,)
    singles = [make(*(x[i] for x in args)) for i in range(1000)]
    T = np.array([float(s.duration) for s in singles])
    np.testing.assert_array_equal(batch.end_time, T)
    for t in [-0.1, 0.0, 0.3, 1.0, 2.5, float(np.median(T)), 6.0, float(T.max()) + 1]:
        r = batch(t)
        assert r.u.shape == r.theta.shape == r.theta_dot.shape == r.theta_ddot.shape == (1000,)
        per = [s(t) for s in singles]
        for n in ("u", "theta", "theta_dot", "theta_ddot"):
            np.testing.assert_array_equal(getattr(r, n), [getattr(p, n) for p in per], err_msg=n)


def test_batch_time_grid_broadcasts():
    s = SmoothBangBang([0.5, -1.0, 2.0], 2.0, u_max=0.5, alpha=[0.0, 0.1, 0.25])
    t = np.linspace(0, 10, 7)
    r = s(t[:, None])
    assert r.theta.shape == (7, 3)
    one = SmoothBangBang(-1.0, 2.0, u_max=0.5, alpha=0.1)
    np.testing.assert_array_equal(r.theta[:, 1], one(t).theta)


# --------------------------------------------------------------------------- bad input


@pytest.mark.parametrize(
    "make, msg",
    [
        (
            lambda: SmoothBangBang(1.0, 1.0, u_max=1.0),
            r"exactly 2 of \{u_max, duration, alpha\}; got 1: u_max",
        ),
        (lambda: SmoothBangBang(1.0, 1.0, u_max=1.0, duration=3.0, alpha=0.1), r"got 3"),
        (
            lambda: PseudoSquare(1.0, 1.0, duration=3.0),
            r"exactly 2 of \{u_max, duration, rise_time\}; got 1: duration",
        ),
        (
            lambda: BangBang(1.0, 1.0, u_max=1.0, duration=2.0),
            r"exactly 1 of \{u_max, duration\}; got 2",
        ),
        (lambda: Sinusoidal(1.0, 1.0), r"exactly 1 of \{u_max, duration\}; got 0: none"),
    ],
)
def test_wrong_parameter_count(make, msg):
    with pytest.raises(ValueError, match=msg):
        make()


@pytest.mark.parametrize("inertia", [0.0, -2.0, [1.0, 0.0]])
def test_inertia_must_be_positive(inertia):
    with pytest.raises(ValueError, match="^inertia: must be > 0"):
        BangBang(1.0, inertia, u_max=1.0)


@pytest.mark.parametrize(
    "make, field",
    [
        (lambda: BangBang(np.nan, 1.0, u_max=1.0), "angle"),
        (lambda: Sinusoidal(1.0, np.inf, u_max=1.0), "inertia"),
        (lambda: SmoothBangBang(1.0, 1.0, u_max=[1.0, np.inf], alpha=0.1), "u_max"),
        (lambda: PseudoSquare(1.0, 1.0, duration=np.nan, rise_time=0.1), "duration"),
        (lambda: SmoothBangBang(1.0, 1.0, u_max=1.0, alpha=np.nan), "alpha"),
        (lambda: PseudoSquare(1.0, 1.0, u_max=1.0, rise_time=np.inf), "rise_time"),
        (lambda: BangBang(1.0, 1.0, u_max=1.0, theta0=np.nan), "theta0"),
    ],
)
def test_non_finite(make, field):
    with pytest.raises(ValueError, match=f"^{field}: must be finite"):
        make()


@pytest.mark.parametrize(
    "make, field",
    [
        (lambda: BangBang(1.0, 1.0, u_max=0.0), "u_max"),
        (lambda: Sinusoidal(1.0, 1.0, duration=-3.0), "duration"),
        (lambda: PseudoSquare(1.0, 1.0, u_max=-1.0, rise_time=0.1), "u_max"),
    ],
)
def test_torque_and_duration_must_be_positive(make, field):
    with pytest.raises(ValueError, match=f"^{field}: must be > 0"):
        make()


def test_angle_must_be_nonzero():
    with pytest.raises(ValueError, match="^angle: must be nonzero"):
        SmoothBangBang([1.0, 0.0], 1.0, duration=3.0, alpha=0.1)


@pytest.mark.parametrize("alpha", [-0.01, 0.26, [0.1, 0.3]])
def test_given_alpha_out_of_range(alpha):
    msg = r"^alpha: out of range \(alpha = rise time / duration must lie in \[0, 1/4\]"
    with pytest.raises(ValueError, match=msg):
        SmoothBangBang(1.0, 1.0, u_max=1.0, alpha=alpha)


@pytest.mark.parametrize("factor", [0.99, 1.01])
def test_solved_alpha_out_of_range(factor):
    # T below the bang-bang time (alpha < 0) or above the alpha = 1/4 time (alpha > 1/4)
    T_lo = float(SmoothBangBang(1.0, 1.0, u_max=1.0, alpha=0.0).duration)
    T_hi = float(SmoothBangBang(1.0, 1.0, u_max=1.0, alpha=0.25).duration)
    T = T_lo * factor if factor < 1 else T_hi * factor
    msg = r"^alpha: out of range \(alpha solved from \(u_max, duration\) must lie in \[0, 1/4\]"
    with pytest.raises(ValueError, match=msg):
        SmoothBangBang(1.0, 1.0, u_max=1.0, duration=T)


@pytest.mark.parametrize("rise_time", [0.0, -0.5, 2.6])
def test_given_rise_time_out_of_range(rise_time):
    msg = r"^rise_time: out of range \(rise_time must satisfy 0 < rise_time <= duration/4"
    with pytest.raises(ValueError, match=msg):
        PseudoSquare(1.0, 1.0, duration=10.0, rise_time=rise_time)


def test_rise_time_too_long_for_u_max():
    # given (u_max, t_r), the solved period must still satisfy t_r <= P/4 (t_r <= sqrt(pi S / 8));
    # S = I|angle|/u_max = 1, t_r = 1 > sqrt(pi/8): P = 2 (c + sqrt(c^2 + 1)), c = 1 - 2/pi
    c = 1 - 2 / np.pi
    P = 2 * (c + np.sqrt(c * c + 1))
    msg = rf"^rise_time: out of range.*rise_time/duration = {1 / P:.6g}$"
    with pytest.raises(ValueError, match=msg):
        PseudoSquare(1.0, 1.0, u_max=1.0, rise_time=1.0)
    PseudoSquare(1.0, 1.0, u_max=1.0, rise_time=np.sqrt(np.pi / 8))  # the limit is admissible


@pytest.mark.parametrize("factor", [0.99, 1.01])
def test_solved_rise_time_out_of_range(factor):
    # I|angle|/u_max must lie in [P^2/(2 pi), P^2/4): P just below the bang-bang time or just above
    # the pure-sinusoid time
    T_bb = float(BangBang(1.0, 1.0, u_max=1.0).duration)
    T_sin = float(Sinusoidal(1.0, 1.0, u_max=1.0).duration)
    T = T_bb * factor if factor < 1 else T_sin * factor
    msg = r"^rise_time: out of range.*I \|angle\| / u_max must lie in"
    with pytest.raises(ValueError, match=msg):
        PseudoSquare(1.0, 1.0, u_max=1.0, duration=T)


# --------------------------------------------------------------------------- sampled (ZOH) slews


def _zoh_slew(s, dt, n):
    """Rigid body ``I theta'' = u`` driven by ``u(k dt)`` held over each step (exact ZOH
    propagation), sampled as the simulator does (``t = dt * arange``); returns the net impulse
    ``sum u_k dt`` [N m s] and the end angle [rad] and rate [rad/s]."""
    u = s(dt * np.arange(n)).u
    I = float(s.inertia)
    theta, rate = float(s.theta0), 0.0
    for uk in u:
        theta += rate * dt + 0.5 * uk * dt * dt / I
        rate += uk * dt / I
    return float(np.sum(u) * dt), theta, rate


ZOH_SHAPES = [
    lambda T: BangBang(0.7, 3.0, duration=T, theta0=0.2),
    lambda T: BangBang(-1.3, 2.0, duration=T),
    lambda T: SmoothBangBang(ANGLE_40, I_TAMU, duration=T, alpha=0.0),
    lambda T: SmoothBangBang(-0.7, 3.0, duration=T, alpha=0.1, theta0=0.2),
    lambda T: PseudoSquare(0.7, 3.0, duration=T, rise_time=T / 8),
    lambda T: Sinusoidal(-1.3, 2.0, duration=T),
]


@pytest.mark.parametrize("rate, k", [(75.0, 289), (64.0, 128), (100.0, 200), (1000.0, 1927)])
@pytest.mark.parametrize("make", ZOH_SHAPES, ids=lambda m: ids(m(4.0)))
def test_sampled_slew_has_zero_net_impulse(make, rate, k):
    # T = 2 k dt puts T/2 = k dt exactly on a sample (doubling is exact), so the 2k samples of
    # [0, T) split k / k between the halves. The switch belongs to the second half [T/2, T): a
    # bang-bang sample at T/2 carrying the first-half sign would leave 2 u_max dt of momentum.
    # Odd symmetry u(T - t) = -u(t) cancels the samples in pairs up to the rounding of T - t_j
    # against t_(2k-j) (|du| <= eps T sup|u'|, sup|u'| <= 15 u_max / T here) and of the sum:
    # |impulse| <= 2k * 16 eps u_max dt.
    dt = 1.0 / rate
    s = make(2 * (dt * k))
    assert float(s.duration) / 2 == dt * k
    n = 2 * k
    impulse, theta, theta_dot = _zoh_slew(s, dt, n)
    eps = np.finfo(float).eps
    u_max, I, angle = float(s.u_max), float(s.inertia), float(s.angle)
    assert abs(impulse) <= n * 16 * eps * u_max * dt
    assert abs(theta_dot) <= n * 16 * eps * u_max * dt / I
    target = float(s.theta0 + s.angle)
    if isinstance(s, BangBang) or (isinstance(s, SmoothBangBang) and float(s.alpha) == 0):
        # the held samples reproduce the piecewise-constant torque exactly: rounding only,
        # n steps each adding O(eps |angle|)
        assert abs(theta - target) <= 4 * n * eps * (abs(angle) + abs(float(s.theta0)))
    else:
        # a hold differs from u by at most dt sup|u'|: angle error <= dt sup|u'| T^2 / (2 I)
        T = float(s.duration)
        assert abs(theta - target) <= dt * 15 * u_max / T * T * T / (2 * I)


def test_bang_bang_switches_at_half_time():
    # the documented halves: +u_max on [0, T/2), -u_max on [T/2, T) (sign of angle)
    for s in (BangBang(0.5, 2.0, duration=4.0), SmoothBangBang(0.5, 2.0, duration=4.0, alpha=0.0)):
        u = s(np.array([0.0, np.nextafter(2.0, 0.0), 2.0, np.nextafter(4.0, 0.0)])).u
        np.testing.assert_array_equal(u, float(s.u_max) * np.array([1.0, 1.0, -1.0, -1.0]))


@pytest.mark.parametrize("angle", [np.radians(40.0), -np.radians(25.0)])
def test_smooth_bang_bang_table_is_the_array_expression_bit_for_bit(angle):
    """A sweep's reference table (samples × cases) comes from a compiled loop
    (torque_shapes._smooth_table) performing the array expression's operations element by
    element: every value is the same float, before, during and after the slew, for α from
    the bang-bang 0 to the plateau-free 1/4 and for a shared (scalar) shape."""
    rng = np.random.default_rng(13)
    n = 300
    alpha = np.r_[0.0, 0.25, rng.uniform(0.0, 0.25, n - 2)]
    t = np.r_[-0.5, np.arange(1126) / 75.0, 20.0][:, None]
    for shape in (
        SmoothBangBang(angle, 3.0, u_max=rng.uniform(1.0, 4.0, n), alpha=alpha, theta0=0.1),
        SmoothBangBang(angle, 3.0, u_max=2.0, alpha=0.1),
    ):
        fast = shape(t)
        slow = TorqueShape.__call__(shape, t)  # the array expression
        for field in ("u", "theta", "theta_dot", "theta_ddot"):
            a, b = getattr(fast, field), getattr(slow, field)
            assert a.shape == b.shape, field
            assert np.array_equal(a, b), field
