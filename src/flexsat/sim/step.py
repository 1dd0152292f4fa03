"""The pieces of one closed-loop step, as plain numpy functions of arrays or scalars.

The same functions run in the Python loop of :func:`flexsat.sim.engine.simulate` (on the
(n_cases[, width]) arrays of a channel: :class:`~flexsat.sim.channels.ChannelSensor`,
:class:`~flexsat.sim.channels.ChannelActuator`,
:class:`~flexsat.sim.disturbances.BearingFriction`) and, compiled by numba, in the loops of
:mod:`flexsat.sim.kernels` (on one element of one case): one definition of each formula, so
the two loops differ only in the order of the sums of their matrix products. Each is a plain
Python function (``register_jitable``: numba compiles it where a kernel calls it).

Saturation is ``minimum(maximum(v, −b), b)``: ``np.clip``'s result (a NaN stays NaN), without
its dispatch cost on small arrays.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, TypeAlias, overload

import numpy as np
from numba.extending import register_jitable

if TYPE_CHECKING:
    from flexsat.units import FloatArray

#: what each formula takes: a (n_cases[, width]) channel array in the Python loop, one float in
#: a compiled kernel (numba ignores the annotations: it infers its own types). Each formula has
#: two overloads, all floats -> float and any array -> array; mypy calls them overlapping
#: (all floats match both), but the first is the one picked for floats, so the ignore on each
#: first overload is safe
Values: TypeAlias = "FloatArray | float"


@overload
def quantised(v: float, quantum: float) -> float: ...  # type: ignore[overload-overlap]


@overload
def quantised(v: Values, quantum: Values) -> FloatArray: ...


@register_jitable
def quantised(v: Values, quantum: Values) -> Values:
    """An encoder's reading of v: q · rint(v / q), q > 0 (round half to even)."""
    return quantum * np.rint(v / quantum)


@overload
def saturated(v: float, bound: float) -> float: ...  # type: ignore[overload-overlap]


@overload
def saturated(v: Values, bound: Values) -> FloatArray: ...


@register_jitable
def saturated(v: Values, bound: Values) -> Values:
    """v clipped to [−bound, bound] (bound > 0, inf for none)."""
    return np.minimum(np.maximum(v, -bound), bound)


@overload
def rate_limited(command: float, previous: float, step: float) -> float: ...  # type: ignore[overload-overlap]


@overload
def rate_limited(command: Values, previous: Values, step: Values) -> FloatArray: ...


@register_jitable
def rate_limited(command: Values, previous: Values, step: Values) -> Values:
    """The command moved from ``previous`` by at most ``step`` (rate limit × dt)."""
    return np.minimum(np.maximum(command, previous - step), previous + step)


@overload
def actuated(command: float, saturation: float, scale: float) -> float: ...  # type: ignore[overload-overlap]


@overload
def actuated(command: Values, saturation: Values, scale: Values) -> FloatArray: ...


@register_jitable
def actuated(command: Values, saturation: Values, scale: Values) -> Values:
    """An actuator's output scale · sat(command) (Junkins, Pollock & Rahman 1990, Att. 3:
    the torque constant's
    ratio times the amplifier's saturation)."""
    return scale * saturated(command, saturation)


@overload
def friction_torque(rate: float, coulomb: float, viscous: float, smoothing: float) -> float: ...  # type: ignore[overload-overlap]


@overload
def friction_torque(
    rate: Values, coulomb: Values, viscous: Values, smoothing: Values
) -> FloatArray: ...


@register_jitable
def friction_torque(rate: Values, coulomb: Values, viscous: Values, smoothing: Values) -> Values:
    """τ = −c1 tanh(θ'/ε) − c2 θ': the bearing friction of Junkins, Pollock & Rahman 1990,
    Att. 3 Eq. 23, its sign
    regularised over the smoothing rate ε (:class:`~flexsat.sim.disturbances.BearingFriction`)."""
    return -coulomb * np.tanh(rate / smoothing) - viscous * rate
