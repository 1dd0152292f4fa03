"""The CMG steering laws as Controllers (flexsat.control.cmg_steering; Vadali, Oh & Walker's
pyramid, Junkins, Pollock & Rahman 1990): the torque law delivers the demanded torque through
the gimbal Jacobian, the null motion changes no momentum, and bad gains are refused by name."""

from __future__ import annotations

import numpy as np
import pytest

from flexsat.control.cmg_steering import NullMotionSteering, PseudoInverseSteering
from flexsat.dynamics import cmg
from flexsat.input_checks import FieldError

#: two nonsingular gimbal sets, one case each (deg)
SETS = np.deg2rad(np.array([[10.0, -20.0, 30.0, 45.0], [-60.0, 60.0, 120.0, -120.0]]))
EPS = np.finfo(float).eps


def _rates(law, sigma):
    rates, _ = law(0.0, {"gimbal_angles": sigma}, {})
    return rates


def test_the_pseudo_inverse_law_delivers_the_demanded_torque():
    """ḣ = C(σ) σ̇ = −T: the spacecraft feels −ḣ = T, exactly for α = 0 away from singular sets
    (to round-off: cond(C) · eps relative)."""
    torque = np.array([0.3, -0.2, 0.5])
    rates = _rates(PseudoInverseSteering(torque), SETS)
    assert rates.shape == (2, 4)
    hdot = np.einsum("...ij,...j->...i", cmg.jacobian(SETS), rates)
    bound = 100 * EPS * np.linalg.cond(cmg.jacobian(SETS)).max() * np.abs(torque).max()
    np.testing.assert_allclose(hdot, np.broadcast_to(-torque, hdot.shape), rtol=0, atol=bound)


def test_a_time_varying_demand_is_read_at_the_sample_time():
    law = PseudoInverseSteering(lambda t: np.array([0.0, 0.0, 0.2 * np.sin(4 * np.pi * t)]))
    rates = _rates(law, SETS[:1])
    np.testing.assert_array_equal(rates, 0.0 * rates)  # sin(0) = 0: no demand, no motion
    later, _ = law(0.125, {"gimbal_angles": SETS[:1]}, {})
    hdot = np.einsum("...ij,...j->...i", cmg.jacobian(SETS[:1]), later)
    np.testing.assert_allclose(hdot[0], [0.0, 0.0, -0.2], atol=1e-14)


def test_the_null_motion_changes_no_momentum():
    """σ̇ = k P(σ)(σ_f − σ) with the exact projector (α = 0) lies in the null space of C(σ)."""
    rates = _rates(NullMotionSteering(np.zeros(4), gain_k=2.0, alpha=0.0), SETS)
    assert np.abs(rates).max() > 0.1  # it does move the gimbals
    hdot = np.einsum("...ij,...j->...i", cmg.jacobian(SETS), rates)
    np.testing.assert_allclose(hdot, 0.0, atol=100 * EPS * np.abs(rates).max())


@pytest.mark.parametrize(
    "build, field",
    [
        (lambda: PseudoInverseSteering([0, 0, 1], alpha=-1.0), "alpha"),
        (lambda: PseudoInverseSteering([0, 0, 1], null_target=[0.0, 0.0]), "null_target"),
        (lambda: NullMotionSteering(np.zeros(4), gain_k=0.0), "gain_k"),
        (lambda: NullMotionSteering(np.zeros(3)), "sigma_target"),
        # refused when the law is made, not at its first call inside a run
        (lambda: NullMotionSteering(np.zeros(4), alpha=-1e-3), "alpha"),
        (
            lambda: PseudoInverseSteering([0, 0, 1], null_target=np.zeros(4), null_gain=-1),
            "null_gain",
        ),
        (lambda: PseudoInverseSteering([0, 0, 1], null_alpha=np.nan), "null_alpha"),
    ],
)
def test_bad_gains_are_refused_naming_the_field(build, field):
    with pytest.raises(FieldError) as caught:
        build()
    assert caught.value.field == field


def test_the_station_law_steers_the_momentum_its_attitude_feedback_demands():
    """u = −Kx, and C σ̇ = T = [u1 + n h3, u2, u3 − n h1]/h_r (Eq. 10, L4717–L4720) to
    round-off, on two states and gimbal sets."""
    from flexsat.control.cmg_steering import StationMomentumSteering

    rng = np.random.default_rng(3)
    K = rng.normal(size=(3, 6))
    n, hr = 0.0011, 4745.0
    law = StationMomentumSteering(K, (1, 3, 5), n, hr)
    x = rng.normal(size=(2, 6))
    cmd, _ = law(0.0, {"state": x, "gimbal_angles": SETS}, {})
    u = -x @ K.T
    np.testing.assert_allclose(cmd["torque"], u, rtol=1e-15)
    T = np.stack([u[:, 0] + n * x[:, 5], u[:, 1], u[:, 2] - n * x[:, 1]], axis=-1) / hr
    hdot = np.einsum("...ij,...j->...i", cmg.jacobian(SETS), cmd["gimbal_rates"])
    bound = 100 * EPS * np.linalg.cond(cmg.jacobian(SETS)).max() * np.abs(T).max()
    np.testing.assert_allclose(hdot, T, rtol=0, atol=bound)


@pytest.mark.parametrize(
    "kwargs, field",
    [
        ({"gain": np.zeros((2, 6))}, "gain"),
        ({"momentum_rows": (1, 3, 6)}, "momentum_rows"),
        ({"momentum_rows": (1.0, 3.0, 5.0)}, "momentum_rows"),
        ({"orbit_rate": 0.0}, "orbit_rate"),
        ({"rotor_momentum": -1.0}, "rotor_momentum"),
        ({"alpha": -1.0}, "alpha"),
    ],
)
def test_the_station_law_refuses_bad_parameters_by_name(kwargs, field):
    from flexsat.control.cmg_steering import StationMomentumSteering

    args = {
        "gain": np.zeros((3, 6)),
        "momentum_rows": (1, 3, 5),
        "orbit_rate": 0.0011,
        "rotor_momentum": 4745.0,
    }
    with pytest.raises(FieldError, match=f"^{field}: "):
        StationMomentumSteering(**{**args, **kwargs})
