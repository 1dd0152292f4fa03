"""The CMG pyramid's gimbals as a plant (flexsat.dynamics.gimbal_cluster): σ̇ = u exactly (a
linear plant with A = 0, B = I, propagated exactly by the engine), the cluster momentum h(σ)
and the gain det(CCᵀ) as outputs, equal to the kernels of flexsat.dynamics.cmg."""

from __future__ import annotations

import numpy as np

from flexsat.control.base import Controller
from flexsat.dynamics import cmg
from flexsat.dynamics.gimbal_cluster import GimbalCluster
from flexsat.sim import SimConfig, simulate

SIGMA0 = np.deg2rad([10.0, -20.0, 30.0, 45.0])


class ConstantRates(Controller):
    """u = the given gimbal rates at every sample (reads the angles it does not need)."""

    reads = ("gimbal_angles",)
    writes = ("gimbal_rates",)

    def __init__(self, rates):
        self.rates = np.asarray(rates, float)

    def __call__(self, t, y, state):
        return np.broadcast_to(self.rates, y["gimbal_angles"].shape).copy(), state


def test_the_gimbals_integrate_their_rates_exactly_and_the_outputs_are_the_kernels():
    rates = np.array([0.1, -0.2, 0.05, 0.0])
    plant = GimbalCluster()
    result = simulate(
        plant,
        ConstantRates(rates),
        SimConfig(duration=2.0, control_rate=10.0),
        initial_state=plant.state_from(gimbal_angles=SIGMA0),
    )
    ds = result.dataset
    sigma = ds["gimbal_angles"].values[0]
    t = ds["time"].values
    # σ(t) = σ0 + u t: the exact step of a linear plant, to round-off of the sums
    np.testing.assert_allclose(sigma, SIGMA0 + np.outer(t, rates), rtol=0, atol=1e-14)
    np.testing.assert_allclose(ds["momentum"].values[0], cmg.momentum(sigma), atol=1e-14)
    np.testing.assert_allclose(ds["gain"].values[0].ravel(), cmg.gain(sigma), atol=1e-13)
