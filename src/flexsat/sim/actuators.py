"""Torque actuator: a DC motor driving a reaction wheel through a current-commanded amplifier."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flexsat.input_checks import FieldError, require_positive, set_si
from flexsat.sim.step import actuated
from flexsat.units import to_si_array


@dataclass(frozen=True)
class TorqueActuator:
    """Applied torque = (K_t,actual / K_t,nominal) · sat(command).

    Parameters
    ----------
    saturation : float, str or pint.Quantity
        Largest torque magnitude the drive can command, N m (TAMU: ``"400 ozf*in"``); inf for
        no limit.
    torque_constant_ratio : float
        Actual over nominal motor torque constant; the controller converts its torque command to
        a current with the nominal constant (TAMU: 52.77 oz-in/A), so a mis-known constant
        scales the applied torque.
    """

    saturation: float = np.inf
    torque_constant_ratio: float = 1.0

    def __post_init__(self) -> None:
        saturation = to_si_array(self.saturation, "N*m", "saturation")
        if not np.all(saturation > 0):  # inf (no limit) is allowed, NaN and <= 0 are not
            raise FieldError("saturation", f"must be > 0 (inf for none), got {self.saturation!r}")
        object.__setattr__(
            self, "saturation", float(saturation) if saturation.ndim == 0 else saturation
        )
        set_si(self, "torque_constant_ratio", require_positive, "")

    def __call__(self, command: np.ndarray) -> np.ndarray:
        return actuated(command, self.saturation, self.torque_constant_ratio)
