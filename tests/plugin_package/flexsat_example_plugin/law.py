r"""A bang-off-bang force: accelerate, coast, brake -- rest to rest without residual vibration.

.. math::

    u(t) = \begin{cases} F & 0 \le t < t_1 \\ 0 & t_1 \le t < t_1 + t_c \\
    -F & t_1 + t_c \le t < 2 t_1 + t_c \\ 0 & \text{after} \end{cases}

Applied to a flexible system of total mass M starting at rest, it moves the centre of mass by

.. math::

    d = F t_1 (t_1 + t_c) / M

and, when the pulse width t1 is a whole number of periods of an undamped elastic mode
(t1 = 2πn/ω), each pulse leaves that mode at rest: a rectangular pulse of width t1 excites
the mode by a factor |sin(ω t1 / 2)|, which is zero there (Singh, T. and Vadali, S. R.,
"Robust time-optimal control: frequency domain approach", Journal of Guidance, Control, and
Dynamics 17(2), 346-353, 1994; the two-pulse profile cancels the rigid-body velocity).

The law is sampled: it counts control samples and switches on them, so t1 and tc must be
whole numbers of control periods (checked when it is built).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from pydantic import BaseModel, ConfigDict

from flexsat.control import Controller
from flexsat.input_checks import FieldError
from flexsat.scenarios import quantity

#: how far (in control periods) a switching time may sit from a sample and still count as on it
SAMPLE_TOLERANCE = 1e-6


class BangOffBang(Controller):
    """Open-loop bang-off-bang force (module docstring) on one input channel.

    Parameters
    ----------
    force : float or array (n_cases,)
        Pulse amplitude F, in the channel's unit (N).
    pulse_width : float or array (n_cases,)
        t1, s; a whole number of control periods.
    coast : float or array (n_cases,)
        tc, s; a whole number of control periods.
    dt : float
        Control period, s.
    channel : str
        The input channel it writes (default ``force``).
    """

    reads: tuple[str, ...] = ()

    class Parameters(BaseModel):
        """A run's ``gains:`` section."""

        model_config = ConfigDict(extra="forbid")

        force: quantity("N")
        pulse_width: quantity("s", positive=True)
        coast: quantity("s") = 0.0

    def __init__(self, force, pulse_width, coast, dt: float, channel: str = "force"):
        if not (np.isfinite(dt) and dt > 0):
            raise ValueError(f"dt: must be a finite number > 0, got {dt!r}")
        self.force = np.asarray(force, float)
        samples = {}
        for name, value, least in (("pulse_width", pulse_width, 1), ("coast", coast, 0)):
            n = np.asarray(value, float) / dt
            whole = np.round(n)
            if not np.all(np.isfinite(n)) or np.any(np.abs(n - whole) > SAMPLE_TOLERANCE):
                raise FieldError(
                    name, f"must be a whole number of control periods ({dt:g} s), got {value!r}"
                )
            if np.any(whole < least):
                raise FieldError(name, f"must be at least {least} control period(s)")
            samples[name] = whole.astype(int)
        if not np.all(np.isfinite(self.force)):
            raise FieldError("force", f"must be finite, got {force!r}")
        self.n_pulse, self.n_coast = samples["pulse_width"], samples["coast"]
        self.dt = float(dt)
        self.writes = (channel,)
        np.broadcast_shapes(self.force.shape, self.n_pulse.shape, self.n_coast.shape)

    @classmethod
    def from_scenario(cls, parameters: Parameters, context) -> BangOffBang:
        """The law of a run's ``gains:``, switching on the scenario's control samples."""
        return cls(**parameters.model_dump(), dt=context.dt)

    def _batched(self) -> list[tuple[int, ...]]:
        return [self.force.shape, self.n_pulse.shape, self.n_coast.shape]

    def initial_state(self, n_cases: int) -> dict[str, np.ndarray]:
        """The sample counter k of each case, from 0."""
        return {"sample": np.zeros(n_cases, dtype=int)}

    def __call__(
        self, t: float, y: Mapping[str, np.ndarray], state: dict[str, np.ndarray]
    ) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        """The force of sample k (n_cases,) and the next count; the law reads no measurement."""
        k = state["sample"]
        accelerating = k < self.n_pulse
        braking = (k >= self.n_pulse + self.n_coast) & (k < 2 * self.n_pulse + self.n_coast)
        u = (accelerating.astype(float) - braking.astype(float)) * self.force
        return np.broadcast_to(u, k.shape).copy(), {"sample": k + 1}


__all__ = ["BangOffBang"]
