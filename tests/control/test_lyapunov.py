"""Control Laws I and II (Junkins, Pollock & Rahman 1990, Att. 3 Eqs. 11 and 17)."""

import numpy as np
import pytest

from flexsat.control import LyapunovRegulator, LyapunovTracker
from flexsat.maneuvers import SmoothBangBang

pytestmark = pytest.mark.numerics  # tolerances near round-off: re-run on other BLAS kernels


def _y(theta, rate, root):
    return {
        "theta": np.atleast_1d(theta),
        "theta_dot": np.atleast_1d(rate),
        "root_torque": np.atleast_1d(root),
    }


def test_law_i_is_eq_11():
    law = LyapunovRegulator(3.0, 2.0, 0.5, target=0.7)
    u, _ = law(0.0, _y(0.2, 0.1, 0.3), {})
    assert u == pytest.approx(-(3.0 * (0.2 - 0.7) + 2.0 * 0.1 + 0.5 * 0.3), rel=1e-15)


def test_law_ii_is_eq_17_and_becomes_law_i_after_the_reference():
    """Eq. 17 during the maneuver; for t >= T (u_ref, θ_ref, θ'_ref, θ''_ref) = (0, θ_f, 0, 0),
    so the command equals Law I's with the same gains (seamless hand-off, Att. 3 L1203)."""
    ref = SmoothBangBang(0.7, 15.0, u_max=2.8, alpha=0.2)
    Ib = 3.8
    law2 = LyapunovTracker(ref, 20.0, 5.0, 0.8, appendage_inertia=Ib)
    law1 = LyapunovRegulator(20.0, 5.0, 0.8, target=0.7)
    t = 0.3 * float(ref.end_time)
    r = ref(t)
    y = _y(0.1, 0.05, 0.4)
    u, _ = law2(t, y, {})
    expected = float(r.u) - (
        20.0 * (0.1 - float(r.theta))
        + 5.0 * (0.05 - float(r.theta_dot))
        + 0.8 * (0.4 - Ib * float(r.theta_ddot))
    )
    assert u == pytest.approx(expected, rel=1e-14)
    for t in (float(ref.end_time), float(ref.end_time) + 3.0):
        assert law2(t, y, {})[0] == pytest.approx(law1(t, y, {})[0], rel=1e-15, abs=1e-15)


def test_gains_broadcast_over_a_case_axis():
    ref = SmoothBangBang(0.7, 15.0, u_max=np.array([2.0, 2.5, 2.8]), alpha=0.1)
    law = LyapunovTracker(ref, np.array([10.0, 20.0, 30.0]), 5.0)
    assert law.n_cases == 3
    u, _ = law(1.0, _y(np.zeros(3), np.zeros(3), np.zeros(3)), {})
    assert u.shape == (3,)


@pytest.mark.parametrize(
    "kwargs,message",
    [
        (dict(g1=-1.0, g2=1.0), r"^g1: must be >= 0"),
        (dict(g1=1.0, g2=-0.1), r"^g2: must be >= 0"),
        (dict(g1=1.0, g2=1.0, g3=-4.0), r"^g3: must be > -4"),
        (dict(g1=float("nan"), g2=1.0), r"^g1: must be finite"),
    ],
)
def test_inadmissible_gains_are_refused(kwargs, message):
    """Global stability needs g1 >= 0, g2 >= 0, g3 > −n (Att. 3 Eq. 11, a3 > 0)."""
    with pytest.raises(ValueError, match=message):
        LyapunovRegulator(**kwargs)
    ref = SmoothBangBang(0.7, 15.0, u_max=2.8, alpha=0.2)
    with pytest.raises(ValueError, match=message):
        LyapunovTracker(ref, **kwargs)


def test_g3_bound_follows_the_number_of_appendages():
    LyapunovRegulator(1.0, 1.0, -3.0, n_appendages=4)
    with pytest.raises(ValueError, match=r"^g3: must be > -2"):
        LyapunovRegulator(1.0, 1.0, -3.0, n_appendages=2)
