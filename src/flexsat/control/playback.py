"""An open-loop law that plays back a tabulated input: u_k = U[k] at t_k = k Δt.

The excitation of a vibration test (a hammer pulse, a shaker, a random force) is an input
history, not a feedback; given to the engine as this law, it goes through the engine's
zero-order hold like any command (held over [t_k, t_k + Δt)).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np

from flexsat.control.base import Controller
from flexsat.input_checks import FieldError, require_finite, require_positive

if TYPE_CHECKING:
    import numpy.typing as npt

    from flexsat.units import FloatArray

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

    def __init__(self, values: npt.ArrayLike, dt: float, writes: str) -> None:
        self.values = require_finite(values, "values")
        if self.values.ndim not in (1, 2) or self.values.shape[0] == 0:
            raise FieldError("values", f"must be (n_t,) or (n_t, m), got {self.values.shape}")
        self.dt = float(require_positive(dt, "dt", "s"))
        self.writes = (writes,)
        self.target = 0.0

    def initial_state(self, n_cases: int) -> dict[str, FloatArray]:
        """The index of the sample last played in each case (−1 before the first): the law
        reads no measurement, so its state is what carries the run's case axis."""
        return {"played": np.full(n_cases, -1)}

    def __call__(
        self, t: float, y: Mapping[str, FloatArray], state: dict[str, FloatArray]
    ) -> tuple[FloatArray, dict[str, FloatArray]]:
        """Sample k = round(t / dt) of the table (zeros after it) in every case: (n_cases,) for a
        1-wide channel (a 1-D or 1-column table), (n_cases, m) for an m-wide one (the Controller
        protocol's shapes)."""
        k = int(np.rint(t / self.dt))
        n = state["played"].shape
        row = self.values[k] if k < self.values.shape[0] else np.zeros(self.values.shape[1:])
        row = row.reshape(()) if row.shape == (1,) else row  # a 1-column table: a 1-wide channel
        return np.broadcast_to(row, n + row.shape).copy(), {"played": np.full(n, k)}
