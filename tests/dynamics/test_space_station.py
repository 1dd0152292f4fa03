"""Space-station LVLH model (issue 14, Eq. 8–12, F26): the pitch
gravity-gradient libration, the roll/yaw characteristic equation of Eq. (8)–(9), the momentum
turning at orbit rate (Eq. 10), the filters' poles at kn (Eq. 12), the design disturbance
(Eq. 11) and the stated AERO1 substitute; bad input named."""

import numpy as np
import pytest

from flexsat.cases.space_station_cmg import PAPER_STATION
from flexsat.control.lqr import lqr
from flexsat.dynamics import space_station as ss

DATA = PAPER_STATION  # the published data, from the case
I1, I2, I3 = DATA.inertia
N = DATA.orbit_rate


def test_table_2_in_si():
    # 1 slug ft² = 1.35582 kg m², 1 ft-lb = 1.35582 N m (pint's definitions, exact to 1e-12)
    assert I1 == pytest.approx(5.28e6 * 1.3558179483314, rel=1e-12)
    assert DATA.rotor_momentum == pytest.approx(3500 * 1.3558179483314, rel=1e-12)
    assert DATA.period == pytest.approx(2 * np.pi / 0.0011)


def _imag_sorted(vals):
    return np.sort(np.abs(vals.imag))


def test_pitch_gravity_gradient_diverges_at_its_rate_and_filters_ring_at_kn():
    A, B, E, names = ss.pitch_model(DATA, filters=(1, 2))
    assert names[:4] == ["theta2", "theta2_rate", "h2", "h2_integral"]
    # I2 θ2'' + 3n²(I1 − I3)θ2 = 0 with I3 > I1: the station is unstable in pitch about LVLH,
    # θ2 ~ exp(±λt), λ = n√(3(I3 − I1)/I2) = 0.00423 rad/s
    lam = N * np.sqrt(3 * (I3 - I1) / I2)
    eig = np.linalg.eigvals(A)
    # block triangular: ±λ, two zeros (h2, ∫h2), filters at ±jn, ±2jn. The zero block is
    # defective (a Jordan chain), so its eigenvalues come out ~sqrt(eps)·‖A‖ ~ 1e-10 off zero
    np.testing.assert_allclose(np.sort(eig.real), np.sort([-lam, lam, 0, 0, 0, 0, 0, 0]), atol=1e-9)
    np.testing.assert_allclose(
        np.sort(np.abs(eig.imag)), [0, 0, 0, 0, N, N, 2 * N, 2 * N], atol=1e-9
    )
    assert B[1, 0] == -1 / I2 and E[1, 0] == 1 / I2 and B[2, 0] == 1


def test_roll_yaw_attitude_has_the_coupled_gravity_gradient_characteristic_equation():
    A, B, E, names = ss.roll_yaw_model(DATA, filters=())
    att = [0, 1, 4, 5]  # θ1, ω1, θ3, ω3
    A4 = A[np.ix_(att, att)]
    # eliminating ω with Eq. (9): (I1 s² + 4n²(I2 − I3))(I3 s² + n²(I2 − I1))
    # + n²(I1 − I2 + I3)² s² = 0 (Wie et al.'s roll/yaw equations)
    poly = np.polyadd(
        np.polymul([I1, 0, 4 * N**2 * (I2 - I3)], [I3, 0, N**2 * (I2 - I1)]),
        [N**2 * (I1 - I2 + I3) ** 2, 0, 0],
    )
    # coefficient k of det(sI − A) is a sum of k-fold products of A's entries: round-off
    # ~ 100 eps ‖A‖^k on top of the relative 1e-12
    scale = np.linalg.norm(A4) ** np.arange(5)
    assert np.all(
        np.abs(np.poly(A4) - poly / (I1 * I3))
        <= 1e-12 * np.abs(poly / (I1 * I3)) + 100 * np.finfo(float).eps * scale
    )
    # roll is gravity-gradient unstable too (4n²(I2 − I3) < 0): a real root pair
    assert np.max(np.linalg.eigvals(A4).real) > 1e-3
    # the CMG momentum turns with LVLH (Eq. 10): its block has eigenvalues ±jn
    h = [2, 6]
    np.testing.assert_allclose(_imag_sorted(np.linalg.eigvals(A[np.ix_(h, h)])), [N, N], rtol=1e-12)


def test_an_orbit_rate_roll_yaw_filter_is_not_controllable():
    # three modes at +jn (momentum, filters on θ1 and θ3) and two inputs: PBH fails
    A, B, _, names = ss.roll_yaw_model(DATA, filters=(1, 2))
    scale = np.array([1e-2, 1e-4, 3e3, 3e5, 1e-2, 1e-4, 3e3, 3e5] + [1e4, 10, 2e3, 5] * 2)
    with pytest.raises(ValueError, match="not stabilizable.*0.0011j"):
        lqr(A / scale[:, None] * scale, B / scale[:, None], np.eye(len(scale)), np.eye(2))


def test_design_disturbance_is_eq_11_and_the_substitute_adds_its_stated_terms():
    t = np.linspace(0.0, DATA.period, 4001)
    w = ss.design_disturbance(t, DATA) / ss.FT_LB
    np.testing.assert_allclose(w[0], [1.0, 4.0, 1.0], atol=1e-12)
    # the orbit mean is the bias (trapezoid on a periodic integrand: exact to round-off)
    mean = np.trapezoid(w, t, axis=0) / DATA.period
    np.testing.assert_allclose(mean, [1.0, 4.0, 1.0], atol=1e-9)
    quarter = ss.design_disturbance(DATA.period / 4, DATA) / ss.FT_LB  # sin = 1, sin π = 0
    np.testing.assert_allclose(quarter, [2.0, 6.0, 2.0], atol=1e-12)
    aero = ss.aero_substitute(t, DATA, harmonic="0.5 lbf*ft", secular="1 lbf*ft") / ss.FT_LB
    extra = aero - w
    np.testing.assert_allclose(
        extra[:, 0], 0.5 * (np.sin(3 * N * t) + np.sin(4 * N * t)), atol=1e-12
    )
    np.testing.assert_allclose(extra[-1, 1], 1.0, atol=1e-12)  # +1 ft-lb after one orbit


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda: ss.pitch_model(DATA, filters=(0,)), "filters: multiples of the orbit rate"),
        (lambda: ss.roll_yaw_model(DATA, filters=(2, 2)), "filters: each frequency once"),
        (lambda: ss.StationData((1.0, 2.0), 0.001, 1.0), "inertia: three principal moments"),
        (lambda: ss.StationData((1.0, 2.0, -3.0), 0.001, 1.0), r"inertia\[2\]: must be"),
        (lambda: ss.StationData((1.0, 2.0, 3.0), 0.0, 1.0), "orbit_rate: must be"),
        (lambda: ss.aero_substitute(0.0, DATA, secular=-1.0), "harmonic, secular"),
        (lambda: ss.design_disturbance(np.nan, DATA), "t: must be finite"),
    ],
)
def test_bad_input_is_named(call, message):
    with pytest.raises(ValueError, match=message):
        call()


def test_the_foot_pound_written_out_is_pints():
    """FT_LB is written from the exact definitions (no unit registry at import): it equals
    pint's lbf·ft to the one rounding of either product."""
    from flexsat.units import to_si

    assert ss.FT_LB == pytest.approx(to_si("1 lbf*ft", "N*m"), rel=2e-16)
