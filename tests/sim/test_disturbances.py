import numpy as np
import pytest

from flexsat.input_checks import FieldError
from flexsat.sim import BearingFriction, Impulses


def test_friction_is_coulomb_plus_viscous_away_from_zero_rate():
    f = BearingFriction(coulomb=0.14, viscous=7e-6, smoothing=1e-3)
    rate = np.array([-0.5, 0.5])
    assert np.allclose(f(rate), [0.14 + 3.5e-6, -0.14 - 3.5e-6], rtol=1e-12)
    assert f(np.array([0.0]))[0] == 0.0


def test_impulses_land_on_the_next_sample():
    imp = Impulses((0.0, 0.05, 1.0), (1.0, 2.0, 3.0))
    assert imp.at_samples(100, 0.02) == {0: 1.0, 3: 2.0, 50: 3.0}


def test_bad_disturbances():
    with pytest.raises(ValueError, match=r"^coulomb: must be >= 0"):
        BearingFriction(coulomb=-1.0)
    with pytest.raises(ValueError, match=r"^smoothing: must be > 0"):
        BearingFriction(smoothing=0.0)
    with pytest.raises(ValueError, match=r"^impulses.times: must be >= 0"):
        Impulses((-1.0,), (1.0,))


def test_cable_spring_profile_and_checks():
    from flexsat.sim.disturbances import CableSpring

    c = CableSpring(
        constant="1 mN*m", stiffness=2.0, center=0.5, angles=(0.0, 1.0), torques=(0.0, 3.0)
    )
    th = np.array([-1.0, 0.25, 2.0])
    # constant − k (θ − θ_c) + the table (held at its ends)
    np.testing.assert_allclose(c(th), 1e-3 - 2.0 * (th - 0.5) + np.array([0.0, 0.75, 3.0]))
    assert c.max_slope == pytest.approx(5.0)
    with pytest.raises(FieldError, match="angles"):
        CableSpring(angles=(1.0, 0.0), torques=(0.0, 1.0))
    with pytest.raises(FieldError, match="torques"):
        CableSpring(angles=(0.0, 1.0), torques=(0.0,))
