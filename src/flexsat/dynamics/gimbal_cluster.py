r"""The gimbal kinematics of a single-gimbal CMG pyramid as a plant: σ̇ = u.

Vadali, Oh & Walker's steering studies (Junkins, Pollock & Rahman 1990; :mod:`flexsat.dynamics.cmg`)
treat the cluster kinematically: the gimbal angles σ (n) follow the commanded gimbal rates, and
the steering law (a torque law, null motion) is a feedback of σ, evaluated continuously. In the
protocol's split that is the linear plant

.. math::

    \dot\sigma = A\sigma + B u, \qquad A = 0, \quad B = I_n,

with the law :class:`~flexsat.control.cmg_steering.PseudoInverseSteering` (or
:class:`~flexsat.control.cmg_steering.NullMotionSteering`) writing u = σ̇; the engine's
continuous-law mode (:mod:`flexsat.sim.continuous`) integrates the pair. Outputs: the angles,
the cluster momentum h(σ) (Eq. 1, units of one rotor's h) and the gain det(CCᵀ).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from flexsat.dynamics import cmg
from flexsat.dynamics.plant import Channel, Plant
from flexsat.input_checks import require_finite

if TYPE_CHECKING:
    from flexsat.units import FloatArray, QuantityLike

__all__ = ["GimbalCluster"]


class GimbalCluster(Plant):
    """Gimbal angles driven by their rates (module docstring).

    Parameters
    ----------
    n_units : int
        Units in the pyramid (>= 3).
    skew : float or str
        Skew angle δ of the gimbal axes (rad or a string with units), in (0, 90°).
    """

    recorded = ("gimbal_angles", "momentum", "gain")

    def __init__(self, n_units: int = 4, skew: QuantityLike = cmg.SKEW) -> None:
        self.g, self.a, self.b = cmg.pyramid_axes(n_units, skew)
        self.n_units = int(n_units)
        self.skew = float(require_finite(skew, "skew", "rad"))  # pyramid_axes checked it
        n = self.n_units
        self.inputs = (Channel("gimbal_rates", "rad/s", n, "commanded gimbal rates σ̇"),)
        self.outputs = (
            Channel("gimbal_angles", "rad", n, "gimbal angles σ"),
            Channel("momentum", "", 3, "cluster momentum h(σ), rotor momenta"),
            Channel("gain", "", 1, "gain det(CCᵀ)"),
        )

    @property
    def nx(self) -> int:
        return self.n_units

    def linear_part(self) -> tuple[FloatArray, FloatArray]:
        """A = 0, B = I (module docstring)."""
        return np.zeros((self.nx, self.nx)), np.eye(self.nx)

    def output_matrices(self, name: str) -> tuple[FloatArray, FloatArray, FloatArray | None] | None:
        if name == "gimbal_angles":
            return np.eye(self.nx), np.zeros((self.nx, self.nx)), None
        return None

    def output(
        self, name: str, x: FloatArray, u: FloatArray | None = None, f_in: FloatArray | None = None
    ) -> FloatArray:
        self._size(name)
        if name == "momentum":
            return cmg.momentum(x, self.skew, self.n_units)
        if name == "gain":
            return cmg.gain(x, self.skew, self.n_units)
        return super().output(name, x, np.zeros(np.shape(x)[:-1] + (self.nx,)), f_in)
