"""An open-loop law that plays back a tabulated input: u_k = U[k] at t_k = k Δt.

The excitation of a vibration test (a hammer pulse, a shaker, a random force) is an input
history, not a feedback; given to the engine as this law, it goes through the engine's
zero-order hold like any command (held over [t_k, t_k + Δt)).
"""

from __future__ import annotations

import numpy as np

from flexsat.control.base import Controller
from flexsat.input_checks import require_finite, require_positive

__all__ = ["Playback"]


class Playback(Controller):
    """u_k = ``values[k]`` at t_k = k ``dt`` (zero after the table), on channel ``writes``.

    Parameters
    ----------
    values : array_like (n_t,) or (n_t, m)
        The samples, in the channel's unit.
    dt : float
        Sample period, s (the engine's control period).
    writes : str
        The input channel.
    """

    reads: tuple[str, ...] = ()

    def __init__(self, values, dt: float, writes: str):
        self.values = require_finite(values, "values")
        if self.values.ndim not in (1, 2) or self.values.shape[0] == 0:
            raise ValueError(f"values: must be (n_t,) or (n_t, m), got {self.values.shape}")
        self.dt = float(require_positive(dt, "dt", "s"))
        self.writes = (writes,)
        self.target = 0.0

    def __call__(self, t, y, state):
        k = int(np.rint(t / self.dt))
        if k >= self.values.shape[0]:
            return np.zeros(self.values.shape[1:]), state
        return self.values[k], state
