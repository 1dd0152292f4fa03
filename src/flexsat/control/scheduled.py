r"""Time-varying (gain-scheduled) state feedback.

EPS slew study c. 1989 ("Control Design Strategy"): the flexible plant
is linearised at several equally spaced times along the nominal maneuver, a constant-gain LQR is
designed at each point, and the gains are interpolated in time. With the state measured
(a plant output holding the full state, or the listed channels),

.. math::

    u(t) = u_{ff}(t) - K(t)\,(x - x_{ref}(t)), \qquad
    K(t) = (1 - w) K_i + w K_{i+1}, \quad w = \frac{t - t_i}{t_{i+1} - t_i}
    \text{ for } t_i \le t \le t_{i+1},

held at the end values outside the schedule [t_0, t_last]. The feedforward u_ff and the state
reference x_ref are tables at the schedule times (interpolated the same way) or functions of t.
At a knot the interpolation returns the designed gain exactly ((1 − 0)K_i + 0·K_{i+1} = K_i in
floating point). The law has no internal state, so its compiled-loop form is
D_k = −K(t_k), y_ref,k = x_ref(t_k), u_ff,k = u_ff(t_k) (:mod:`~flexsat.control.linear_form`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, TypeAlias

import numpy as np

from flexsat.control.base import Controller
from flexsat.control.linear_form import (
    cases_of,
    channel_spec,
    per_case,
    sample_times,
    split_channels,
    stack_channels,
    static_law,
)
from flexsat.input_checks import FieldError, require_finite

if TYPE_CHECKING:
    import numpy.typing as npt

    from flexsat.control.linear_form import ChannelItems, LinearLaw
    from flexsat.units import FloatArray, QuantityArrayLike

#: x_ref or u_ff as given: a table at the schedule times or a function of t (s)
ScheduleInput: TypeAlias = "npt.ArrayLike | Callable[[float], npt.ArrayLike]"
#: the same as kept: a (n_knots, C, width) table, the function, or None (zero)
ScheduleTable: TypeAlias = "FloatArray | Callable[[float], npt.ArrayLike] | None"

__all__ = ["ScheduledStateFeedback", "interpolate_schedule"]


def interpolate_schedule(knots: FloatArray, table: FloatArray, t: npt.ArrayLike) -> FloatArray:
    """Piecewise-linear interpolation of ``table`` (n_knots, ...) at times ``t`` (scalar or
    (n_t,)), held at the end values outside the knots; shape t.shape + table.shape[1:]."""
    tt = np.asarray(t, float)
    if len(knots) == 1:
        return np.broadcast_to(table[0], tt.shape + table.shape[1:])
    i = np.clip(np.searchsorted(knots, tt, side="right") - 1, 0, len(knots) - 2)
    w = np.clip((tt - knots[i]) / (knots[i + 1] - knots[i]), 0.0, 1.0)
    w = w.reshape(w.shape + (1,) * (table.ndim - 1))
    return (1 - w) * table[i] + w * table[i + 1]


class ScheduledStateFeedback(Controller):
    r"""u = u_ff(t) − K(t)(x − x_ref(t)) with K interpolated linearly between schedule times
    (module docstring; EPS slew study c. 1989, "Control Problem Formulation"; spec F10).

    Parameters
    ----------
    times : (n_knots,) array_like, str or pint.Quantity
        Schedule times, s, strictly increasing (one time: a constant gain).
    gains : array_like
        K at the schedule times, (n_knots, m, n) shared by the cases or (n_knots, n_cases, m, n)
        per case; SI numbers (command unit per state unit).
    measurements : str or sequence of str / (name, width) / Channel
        Where the state is read: one name is a channel n wide (a plant output holding the full
        state); a sequence lists channels whose widths sum to n.
    commands : str or sequence, default "torque"
        Channels written; one name is m wide.
    state_reference : array_like or callable, optional
        x_ref at the schedule times, (n_knots, n) or (n_knots, n_cases, n), or a function of t
        returning (n,) or (n_cases, n); default 0. SI numbers.
    feedforward : array_like or callable, optional
        u_ff likewise with width m; default 0.
    """

    def __init__(
        self,
        times: QuantityArrayLike,
        gains: npt.ArrayLike,
        measurements: ChannelItems,
        commands: ChannelItems = "torque",
        state_reference: ScheduleInput | None = None,
        feedforward: ScheduleInput | None = None,
    ) -> None:
        knots = require_finite(times, "times", "s")
        if knots.ndim != 1 or knots.size < 1 or np.any(np.diff(knots) <= 0):
            raise FieldError(
                "times",
                f"must be a 1-D strictly increasing array of schedule times, got {knots.tolist()}",
            )
        K = require_finite(gains, "gains")
        if K.ndim not in (3, 4) or K.shape[0] != knots.size:
            raise FieldError(
                "gains",
                "must have shape (n_knots, m, n) or (n_knots, n_cases, m, n) "
                f"with n_knots = {knots.size} schedule times, got {K.shape}",
            )
        self.knots = knots
        self.gains = K if K.ndim == 4 else K[:, None]
        m, n = self.gains.shape[-2:]
        self.reads, self.read_sizes = _channels(measurements, n, "measurements", "n", "columns")
        self.writes, self.write_sizes = _channels(commands, m, "commands", "m", "rows")
        self.state_reference = self._schedule_table(state_reference, n, "state_reference")
        self.feedforward = self._schedule_table(feedforward, m, "feedforward")

    def _schedule_table(self, value: ScheduleInput | None, width: int, field: str) -> ScheduleTable:
        if value is None or callable(value):
            return value
        v = require_finite(value, field)
        if v.ndim not in (2, 3) or v.shape[0] != self.knots.size or v.shape[-1] != width:
            raise FieldError(
                field,
                f"must have shape (n_knots, {width}) or (n_knots, n_cases, "
                f"{width}) at the {self.knots.size} schedule times, or be a function "
                f"of t; got {v.shape}",
            )
        return v if v.ndim == 3 else v[:, None]

    def _batched(self) -> list[tuple[int, ...]]:
        shapes: list[tuple[int, ...]] = [(self.gains.shape[1],)]
        for table in (self.state_reference, self.feedforward):
            if isinstance(table, np.ndarray):
                shapes.append((table.shape[1],))
        return shapes

    def gain(self, t: npt.ArrayLike) -> FloatArray:
        """K(t), shape t.shape + (C, m, n)."""
        return interpolate_schedule(self.knots, self.gains, t)

    def _at(
        self, table: ScheduleTable, t: FloatArray, width: int, field: str, n_cases: int
    ) -> FloatArray:
        """x_ref or u_ff at times t (n_t,): (n_t, C, width)."""
        if table is None:
            return np.zeros((len(t), 1, width))
        if isinstance(table, np.ndarray):
            return interpolate_schedule(self.knots, table, t)
        return np.stack([per_case(table(tk), n_cases, field, (width,)) for tk in t])

    def __call__(
        self, t: float, y: Mapping[str, FloatArray], state: dict[str, FloatArray]
    ) -> tuple[FloatArray | dict[str, FloatArray], dict[str, FloatArray]]:
        m, n = self.gains.shape[-2:]
        nc = max(self.n_cases, cases_of(y, self.reads, self.read_sizes))
        x = stack_channels(y, self.reads, self.read_sizes, nc)
        tt = np.array([t], float)
        e = x - self._at(self.state_reference, tt, n, "state_reference", nc)[0]
        u = self._at(self.feedforward, tt, m, "feedforward", nc)[0] - np.einsum(
            "cij,cj->ci", self.gain(tt)[0], np.broadcast_to(e, (nc, n))
        )
        commands = split_channels(u, self.writes, self.write_sizes)
        return (commands[self.writes[0]] if len(self.writes) == 1 else commands), state

    def linear_form(self, dt: float, times: npt.ArrayLike, n_cases: int) -> LinearLaw:
        """D_k = −K(t_k), y_ref = x_ref(t_k), u_ff = u_ff(t_k); D constant (T = 1) for a
        one-point schedule."""
        _, grid = sample_times(dt, times)
        m, n = self.gains.shape[-2:]
        for field, table in (
            ("gains", self.gains),
            ("state_reference", self.state_reference),
            ("feedforward", self.feedforward),
        ):
            if isinstance(table, np.ndarray) and table.shape[1] not in (1, n_cases):
                raise FieldError(
                    field, f"have {table.shape[1]} cases, the run has n_cases = {n_cases}"
                )
        D = -(self.gains if len(self.knots) == 1 else self.gain(grid))
        y_ref = self._at(self.state_reference, grid, n, "state_reference", n_cases)
        u_ff = self._at(self.feedforward, grid, m, "feedforward", n_cases)
        return static_law(
            D, y_ref, u_ff, self.reads, self.writes, self.read_sizes, self.write_sizes
        )


def _channels(
    spec: ChannelItems, width: int, field: str, symbol: str, axis: str
) -> tuple[tuple[str, ...], tuple[int, ...]]:
    """Names and widths; a single name takes the whole width."""
    if isinstance(spec, str):
        return (channel_spec(spec, field)[0], (width,))
    names, sizes, _ = channel_spec(spec, field)
    if sum(sizes) != width:
        raise FieldError(
            field,
            f"their widths {sizes} sum to {sum(sizes)}, the gains have {symbol} = {width} {axis}",
        )
    return names, sizes
