import numpy as np
import pytest

from flexsat.sim import TorqueActuator


def test_saturation_and_torque_constant_ratio():
    act = TorqueActuator(saturation=2.0, torque_constant_ratio=1.1)
    assert np.allclose(act(np.array([-5.0, 1.0, 5.0])), [-2.2, 1.1, 2.2])


def test_bad_actuator():
    with pytest.raises(ValueError, match=r"^saturation: must be > 0"):
        TorqueActuator(saturation=0.0)
    with pytest.raises(ValueError, match=r"^torque_constant_ratio: must be > 0"):
        TorqueActuator(torque_constant_ratio=-1.0)
