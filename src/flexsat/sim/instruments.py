"""What the engine evaluates at each control sample besides the law: the state-dependent input
forces (bearing friction) and the measurements of the channels the law reads.

True values come from the plant's output matrices, y = C x + D u + D_f f_in
(:meth:`~flexsat.dynamics.plant.Plant.output_matrices`), stacked so that one product gives every
linear channel, or from :meth:`~flexsat.dynamics.plant.Plant.output` for a nonlinear one; each
channel then goes through its sensor (:class:`~flexsat.sim.channels.ChannelSensor`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import TYPE_CHECKING, TypeAlias

import numpy as np

from flexsat.sim.channels import ChannelDisturbance, ChannelSensor, noise_column
from flexsat.sim.integrators import apply
from flexsat.sim.sensors import least_squares_derivative_weights
from flexsat.units import FloatArray

if TYPE_CHECKING:
    from flexsat.dynamics.plant import Plant

#: a linear output's (C, D, D_f); D or D_f None where the output does not depend on it
OutputMatrices: TypeAlias = tuple[FloatArray, FloatArray | None, FloatArray | None]
#: a state-dependent input force f(y) of its driving output y
InputForce: TypeAlias = Callable[[FloatArray], FloatArray]


def stacked_output_matrices(
    mats: Sequence[OutputMatrices], m: int
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """(C, D, D_f) of several linear outputs stacked row-wise; a missing D or D_f (None: the
    output does not depend on it) is zeros."""

    def block(M: FloatArray | None, C: FloatArray) -> FloatArray:
        return np.zeros(C.shape[:-1] + (m,)) if M is None else np.asarray(M, float)

    C = [np.asarray(mt[0], float) for mt in mats]
    if any(c.ndim == 3 for c in C):  # a dispersed plant: every block per case
        n = max(c.shape[0] for c in C if c.ndim == 3)
        C = [c if c.ndim == 3 else np.broadcast_to(c, (n,) + c.shape) for c in C]
    D = [np.broadcast_to(block(mt[1], c), c.shape[:-1] + (m,)) for mt, c in zip(mats, C)]
    Df = [np.broadcast_to(block(mt[2], c), c.shape[:-1] + (m,)) for mt, c in zip(mats, C)]
    return np.concatenate(C, axis=-2), np.concatenate(D, axis=-2), np.concatenate(Df, axis=-2)


def unit_row(plant: Plant, name: str) -> int | None:
    """Index i when output ``name`` is the state coordinate x_i for every case, else None."""
    if not any(c.name == name for c in plant.outputs):
        return None
    mats = plant.output_matrices(name)
    if mats is None or np.any(mats[1]):
        return None
    C = np.asarray(mats[0]).reshape(-1, plant.nx)
    i = int(np.argmax(C[0]))
    unit = np.zeros(plant.nx)
    unit[i] = 1.0
    return i if np.array_equal(C, np.broadcast_to(unit, C.shape)) else None


class InputForces:
    """State-dependent forces on input channels (bearing friction): each force f(y) of its
    driving output y, read off the state directly when y is one state coordinate."""

    def __init__(
        self, plant: Plant, forced: Mapping[str, ChannelDisturbance], batched: bool
    ) -> None:
        self.plant, self.forced, self.batched = plant, forced, batched
        self.m, slices = plant.n_inputs, plant.input_slices
        self.cols = [j for k in forced for j in range(slices[k].start, slices[k].stop)]
        # per force: f, and its driving output as a state index, a nonlinear output's name or
        # (None) the transposed output matrix Cᵀ
        self.drivers: list[tuple[InputForce, int | str | None, FloatArray | None]] = []
        for d in forced.values():
            force, output = d.force, d.force_output
            # forced: the disturbances with a force, each with its output (ChannelDisturbance)
            assert force is not None and output is not None
            mats = plant.output_matrices(output)
            if mats is None:
                self.drivers.append((force, output, None))
                continue
            row = unit_row(plant, output)
            if row is not None:
                self.drivers.append((force, row, None))  # y = x_i exactly
            else:
                self.drivers.append((force, None, np.swapaxes(mats[0], -1, -2).copy()))
        # one force of one state coordinate (the bearing on θ'): called several times per
        # substep, so the general path's bookkeeping is skipped
        self.single: tuple[InputForce, int] | None = None
        if len(self.drivers) == 1:
            force, index, _ = self.drivers[0]
            if isinstance(index, int):
                self.single = (force, index)

    def compact(self, xs: FloatArray, w: FloatArray) -> FloatArray:
        """The forces on the forced input columns only, (n_cases, n_forced)."""
        if self.single is not None:
            force, row = self.single
            f = force(xs[:, row])
            return f[:, None] if f.ndim == 1 else f
        out = []
        for force, index, CT in self.drivers:
            if isinstance(index, int):
                y = xs[:, index]
            elif CT is not None:
                y = apply(xs, CT, self.batched)
                y = y[:, 0] if y.shape[1] == 1 else y
            else:
                assert index is not None  # a nonlinear output's name (above)
                y = self.plant.output(index, xs, w, None)
            f = force(y)
            out.append(f[:, None] if f.ndim == 1 else f)
        return out[0] if len(out) == 1 else np.concatenate(out, axis=1)

    def full(self, compact: FloatArray) -> FloatArray:
        """f_in on every input channel, (n_cases, m)."""
        if len(self.cols) == self.m:
            return compact
        f = np.zeros((compact.shape[0], self.m))
        f[:, self.cols] = compact
        return f


class Instruments:
    """The measured channels of a run: true values by output matrices (or the plant's
    ``output``), then each channel's sensor; derivative sensors after their sources."""

    def __init__(
        self,
        plant: Plant,
        names: Sequence[str],
        sensors: Mapping[str, ChannelSensor],
        columns: Mapping[str, slice],
        dt: float,
        nc: int,
        batched: bool,
        forced: bool,
    ) -> None:
        self.plant, self.batched = plant, batched
        sources: dict[str, str] = {}  # derivative channel -> the channel it filters
        for k in names:
            s = sensors.get(k)
            if s is not None and s.derivative_of is not None:
                sources[k] = s.derivative_of
        derived = list(sources)
        direct = [k for k in names if k not in derived]
        for k in derived:  # the filtered channel is measured first
            src = sources[k]
            if src not in direct:
                direct.insert(0, src)
        self.names = tuple(direct + derived)
        mats = {k: plant.output_matrices(k) for k in direct}
        linear_mats = {k: m for k, m in mats.items() if m is not None}
        self.linear = list(linear_mats)
        self.nonlinear = [k for k in direct if mats[k] is None]
        self.CT: FloatArray | None = None
        self.DT: FloatArray | None = None
        self.DfT: FloatArray | None = None
        self.cols: dict[str, int | slice] = {}
        if self.linear:
            C, D, Df = stacked_output_matrices(list(linear_mats.values()), plant.n_inputs)
            self.CT = np.swapaxes(C, -1, -2).copy()
            self.DT = np.swapaxes(D, -1, -2).copy() if np.any(D) else None
            self.DfT = np.swapaxes(Df, -1, -2).copy() if forced and np.any(Df) else None
            col = 0
            for k, mk in linear_mats.items():
                size = mk[0].shape[-2]
                self.cols[k] = col if size == 1 else slice(col, col + size)
                col += size
        # (channel, its sensor, its noise column(s) or None); ideal sensors do nothing
        self.plan: list[tuple[str, ChannelSensor, int | slice | None]] = []
        for k in direct:
            sensor = sensors.get(k)
            if sensor is None:
                continue
            noisy = np.any(sensor.noise)
            self.plan.append(
                (k, sensor, noise_column(columns, k, "its sensor noise", plant) if noisy else None)
            )
        self.linear_cols = [(k, self.cols[k]) for k in self.linear]
        # (channel, sensor, source, filter weights, the source's window (from the first
        # sample), noise column(s))
        self.derived: list[
            tuple[str, ChannelSensor, str, FloatArray, FloatArray | None, int | slice | None]
        ] = []
        for k in derived:
            sensor = sensors[k]
            w = least_squares_derivative_weights(sensor.window, sensor.order, dt)
            noisy = np.any(sensor.noise)
            self.derived.append(
                (
                    k,
                    sensor,
                    sources[k],
                    w,
                    None,
                    noise_column(columns, k, "its sensor noise", plant) if noisy else None,
                )
            )

    def measure(
        self,
        x: FloatArray,
        w_prev: FloatArray,
        f_in: FloatArray | None,
        noise_k: FloatArray | None,
        first: bool,
    ) -> dict[str, FloatArray]:
        """Measurements at state x, held input w_prev and input force f_in."""
        y: dict[str, FloatArray] = {}
        if self.CT is not None:
            Y = apply(x, self.CT, self.batched)
            if self.DT is not None:
                Y = Y + apply(w_prev, self.DT, self.batched)
            if self.DfT is not None and f_in is not None:
                Y = Y + apply(f_in, self.DfT, self.batched)
            for k, col in self.linear_cols:
                y[k] = Y[:, col]
        for k in self.nonlinear:
            y[k] = self.plant.output(k, x, w_prev, f_in)
        for k, s, noise_col in self.plan:
            y[k] = s.measure(y[k], _noise(noise_k, noise_col))
        for i, (k, s, src, w, hist, noise_col) in enumerate(self.derived):
            v = y[src]
            if first:  # the filter starts from rest at the first measured value
                hist = np.repeat(v[:, None], len(w), axis=1)
                self.derived[i] = (k, s, src, w, hist, noise_col)
            assert hist is not None  # set at the first sample
            hist[:, :-1] = hist[:, 1:]
            hist[:, -1] = v
            y[k] = s.measure(hist @ w, _noise(noise_k, noise_col))
        return y


def _noise(noise_k: FloatArray | None, col: int | slice | None) -> FloatArray | float:
    """A sensor's standard-normal samples: its column(s) of the run's stream, 0 for a sensor
    without noise (``col`` None)."""
    if col is None:
        return 0.0
    assert noise_k is not None  # a sensor with a noise column makes the run noisy
    return noise_k[:, col]


__all__ = ["InputForces", "Instruments", "stacked_output_matrices", "unit_row"]
