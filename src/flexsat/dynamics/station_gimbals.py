r"""The space station's attitude and momentum model with the gimbal kinematics of its CMG pyramid:
one plant for the momentum-management run (Vadali, Oh & Walker, space-station example, in
Junkins, Pollock & Rahman 1990, Att. 13 "Space Station Example").

The state is the station's x (:class:`~flexsat.dynamics.space_station.SpaceStation`: attitude,
rates, the CMG momentum h of Eq. (10), its integral, the filters) followed by the gimbal angles
σ of the pyramid (:class:`~flexsat.dynamics.gimbal_cluster.GimbalCluster`),

.. math::

    \dot x = A_s x + B_s [u;\ w], \qquad \dot\sigma = \dot\sigma_c,

block-diagonal: the station model carries the momentum the CMGs must deliver, and the gimbals
follow the commanded rates σ̇_c of a steering law that reads both (the paper's CMG loop,
:class:`flexsat.control.cmg_steering.StationMomentumSteering`). The paper runs the two loops
separately for that reason (the attitude bandwidth, ~0.01 rad/s, is far below the gimbals'); as
one plant the pair is one run of the engine's continuous-law mode.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from flexsat.dynamics import cmg
from flexsat.dynamics.plant import Channel, Plant
from flexsat.dynamics.space_station import SpaceStation
from flexsat.input_checks import FieldError, require_finite

if TYPE_CHECKING:
    from flexsat.units import FloatArray, QuantityLike

__all__ = ["StationWithGimbals"]


class StationWithGimbals(Plant):
    """A :class:`~flexsat.dynamics.space_station.SpaceStation` and its CMG pyramid's gimbal
    angles (module docstring).

    Parameters
    ----------
    station : SpaceStation
    n_units : int
        Units in the pyramid (>= 3).
    skew : float or str
        Skew angle of the gimbal axes (rad or a string with units), in (0, 90°).

    Notes
    -----
    Inputs: the station's ``torque`` and ``disturbance`` (N m) and ``gimbal_rates`` (rad/s).
    Outputs: the station's ``state``, ``attitude`` and ``momentum`` (N m s), and
    ``gimbal_angles`` (rad), ``cluster_momentum`` h(σ) (rotor momenta) and ``gain`` det(CCᵀ).
    """

    recorded = ("attitude", "momentum", "gimbal_angles", "gain")

    def __init__(
        self, station: SpaceStation, n_units: int = 4, skew: QuantityLike = cmg.SKEW
    ) -> None:
        if not isinstance(station, SpaceStation):
            raise FieldError("station", f"must be a SpaceStation, got {station!r}")
        cmg.pyramid_axes(n_units, skew)  # checks both
        self.station = station
        self.n_units = int(n_units)
        self.skew = float(require_finite(skew, "skew", "rad"))
        self.n_station = station.nx
        n = self.n_units
        self.inputs = station.inputs + (
            Channel("gimbal_rates", "rad/s", n, "commanded gimbal rates σ̇"),
        )
        self.outputs = station.outputs + (
            Channel("gimbal_angles", "rad", n, "gimbal angles σ"),
            Channel("cluster_momentum", "", 3, "cluster momentum h(σ), rotor momenta"),
            Channel("gain", "", 1, "gain det(CCᵀ)"),
        )

    @property
    def nx(self) -> int:
        return self.n_station + self.n_units

    def linear_part(self) -> tuple[FloatArray, FloatArray]:
        """A = blkdiag(A_s, 0), B = blkdiag(B_s, I) (module docstring)."""
        As, Bs = self.station.linear_part()
        ns, n = self.n_station, self.n_units
        A = np.zeros((self.nx, self.nx))
        A[:ns, :ns] = As
        B = np.zeros((self.nx, Bs.shape[1] + n))
        B[:ns, : Bs.shape[1]] = Bs
        B[ns:, Bs.shape[1] :] = np.eye(n)
        return A, B

    def output_matrices(self, name: str) -> tuple[FloatArray, FloatArray, FloatArray | None] | None:
        m = self.n_inputs
        if name == "gimbal_angles":
            C = np.zeros((self.n_units, self.nx))
            C[:, self.n_station :] = np.eye(self.n_units)
            return C, np.zeros((self.n_units, m)), None
        mats = self.station.output_matrices(name)
        if mats is None:
            return None
        C, D, _ = mats
        return (
            np.hstack([C, np.zeros((C.shape[0], self.n_units))]),
            np.hstack([D, np.zeros((D.shape[0], self.n_units))]),
            None,
        )

    def output(
        self, name: str, x: FloatArray, u: FloatArray | None = None, f_in: FloatArray | None = None
    ) -> FloatArray:
        self._size(name)
        sig = np.asarray(x)[..., self.n_station :]
        if name == "cluster_momentum":
            return cmg.momentum(sig, self.skew, self.n_units)
        if name == "gain":
            return cmg.gain(sig, self.skew, self.n_units)
        return super().output(name, x, np.zeros(np.shape(x)[:-1] + (self.n_inputs,)), f_in)
