"""The one interface every control law implements.

A law is called once per control sample with the time, the measurements and its own internal
state, and returns its commands and its next state. It declares the measurement channels it
``reads`` and the input channels it ``writes`` (names of the plant's
:class:`~flexsat.dynamics.plant.Channel` s); the simulator checks them against the plant before
the run. Every argument may carry a leading case axis: gains and references are arrays of shape
(n_cases,) and a batch of maneuvers runs in one call (python-control's conventions apply to the
linear designs built on top of this).

A command is returned as a mapping {channel: array}; a law writing one channel may return the
bare array. A size-1 channel's values have shape (n_cases,), a wider one's (n_cases, size).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Mapping
from typing import TYPE_CHECKING, Protocol

import numpy as np

if TYPE_CHECKING:
    import numpy.typing as npt

    from flexsat.control.linear_form import LinearLaw
    from flexsat.maneuvers.torque_shapes import TorqueShape
    from flexsat.units import FloatArray


class TorqueNominal(Protocol):
    """An open-loop torque history on [0, ``duration``] (s): ``torque(t)`` (N·m, body axes,
    shape t.shape + (3,))."""

    @property
    def duration(self) -> float: ...

    def torque(self, t: FloatArray) -> npt.ArrayLike: ...


class RigidNominal(TorqueNominal, Protocol):
    """A rigid three-axis nominal maneuver (e.g. :class:`flexsat.maneuvers.three_axis_slew.
    ThreeAxisSlew`): its torque and ``beta(t)`` (unit Euler parameters, t.shape + (4,)) and
    ``omega(t)`` (body rate, rad/s, t.shape + (3,))."""

    def beta(self, t: FloatArray) -> npt.ArrayLike: ...

    def omega(self, t: FloatArray) -> npt.ArrayLike: ...


class Controller(ABC):
    """Discrete control law ``u_k, state_{k+1} = law(t_k, y_k, state_k)``.

    Measurements ``y`` are a mapping of arrays by channel name. Every law declares the
    channels it reads and writes, on its class or its instance (there is no default: the
    simulator refuses a law that does not, naming it): a single-axis slew law reads
    ``theta`` (rad), ``theta_dot`` (rad/s) and perhaps ``root_torque`` (N m) and writes
    ``torque`` (N m); an attitude law reads ``attitude`` and ``rate``.
    """

    #: measurement channels the law reads (names of the plant's outputs); no default
    reads: tuple[str, ...]
    #: input channels the law writes (names of the plant's inputs); no default
    writes: tuple[str, ...]

    @property
    def n_cases(self) -> int:
        """Number of cases implied by the law's parameter arrays (1 for scalars)."""
        return int(np.prod(np.broadcast_shapes(*self._batched())))

    def _batched(self) -> list[tuple[int, ...]]:
        """Shapes of the law's per-case parameters (none here: a law with per-case gains or
        set points lists them)."""
        return []

    def initial_state(self, n_cases: int) -> dict[str, FloatArray]:
        return {}

    @abstractmethod
    def __call__(
        self, t: float, y: Mapping[str, FloatArray], state: dict[str, FloatArray]
    ) -> tuple[FloatArray | Mapping[str, FloatArray], dict[str, FloatArray]]:
        """Return the commands (a dict by written channel, or a bare array when the law writes
        one) and the next internal state."""

    def linear_form(self, dt: float, times: FloatArray, n_cases: int) -> LinearLaw | None:
        """The law's compiled-loop form for a run, or None when it is not linear.

        Parameters
        ----------
        dt : float
            Control period, s.
        times : (n_t,) array
            Sample times, s (references and schedules are tabulated on them).
        n_cases : int
            Cases of the run; the law's per-case parameters number 1 or n_cases.

        Returns
        -------
        :class:`~flexsat.control.linear_form.LinearLaw` or None
            None (this default): the law is nonlinear or user-written, and the engine calls it
            sample by sample in Python.
        """
        return None


class SlewLaw(Controller):
    """A law that slews a maneuver plant's angle (:attr:`~flexsat.dynamics.plant.Plant.
    maneuver`) to ``target``, rad, along an optional open-loop ``reference`` (a torque shape
    of :mod:`flexsat.maneuvers.torque_shapes`: ``theta0``, ``theta``, ``theta_dot``,
    ``theta_ddot``, ``u``, ``end_time``). The engine starts such a run at the reference's start
    angle and reads it against the reference for the maneuver metrics
    (:func:`flexsat.sim.metrics.maneuver_metrics`).
    """

    #: final maneuver angle, rad (array over cases)
    target: FloatArray
    #: open-loop reference the law tracks, or None (a step to the target)
    reference: TorqueShape | None = None
    #: the reference on the sample grid (times, θ, θ', θ'', u), set by :meth:`tabulate_reference`
    _table: tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray] | None

    def _batched(self) -> list[tuple[int, ...]]:
        return [np.shape(self.target)]

    def tabulate_reference(self, times: npt.ArrayLike) -> None:
        """Evaluate the reference once on the sample grid; :meth:`reference_at` then looks the
        samples up instead of re-evaluating the shape (the simulator calls this before its time
        loop; the shapes are analytic, so the table holds exactly what a direct call returns)."""
        self._table = None
        if self.reference is not None:
            grid = np.asarray(times, float)
            r = self.reference(grid[:, None])
            self._table = (grid, r.theta, r.theta_dot, r.theta_ddot, r.u)

    def reference_at(self, t: float) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """(θ_ref, θ'_ref, θ''_ref, u_ref) at time t; a step to the target when no reference."""
        table = getattr(self, "_table", None)
        if table is not None:
            k = int(np.searchsorted(table[0], t))
            if k < len(table[0]) and table[0][k] == t:
                return table[1][k], table[2][k], table[3][k], table[4][k]
        if self.reference is None:
            z = np.zeros(np.shape(self.target))
            return np.asarray(self.target, float) + z, z, z, z
        r = self.reference(t)
        return r.theta, r.theta_dot, r.theta_ddot, r.u
