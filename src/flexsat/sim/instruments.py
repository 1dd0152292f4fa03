"""What the engine evaluates at each control sample besides the law: the state-dependent input
forces (bearing friction) and the measurements of the channels the law reads.

True values come from the plant's output matrices, y = C x + D u + D_f f_in
(:meth:`~flexsat.dynamics.plant.Plant.output_matrices`), stacked so that one product gives every
linear channel, or from :meth:`~flexsat.dynamics.plant.Plant.output` for a nonlinear one; each
channel then goes through its sensor (:class:`~flexsat.sim.channels.ChannelSensor`).
"""

from __future__ import annotations

import numpy as np

from flexsat.sim.channels import noise_column
from flexsat.sim.integrators import apply
from flexsat.sim.sensors import least_squares_derivative_weights


def stacked_output_matrices(mats: list, m: int):
    """(C, D, D_f) of several linear outputs stacked row-wise; a missing D or D_f (None: the
    output does not depend on it) is zeros."""

    def block(M, C):
        return np.zeros(C.shape[:-1] + (m,)) if M is None else np.asarray(M, float)

    C = [np.asarray(mt[0], float) for mt in mats]
    if any(c.ndim == 3 for c in C):  # a dispersed plant: every block per case
        n = max(c.shape[0] for c in C if c.ndim == 3)
        C = [c if c.ndim == 3 else np.broadcast_to(c, (n,) + c.shape) for c in C]
    D = [np.broadcast_to(block(mt[1], c), c.shape[:-1] + (m,)) for mt, c in zip(mats, C)]
    Df = [np.broadcast_to(block(mt[2], c), c.shape[:-1] + (m,)) for mt, c in zip(mats, C)]
    return tuple(np.concatenate(M, axis=-2) for M in (C, D, Df))


def unit_row(plant, name: str):
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

    def __init__(self, plant, forced: dict, batched: bool):
        self.plant, self.forced, self.batched = plant, forced, batched
        self.m, slices = plant.n_inputs, plant.input_slices
        self.cols = [j for k in forced for j in range(slices[k].start, slices[k].stop)]
        self.drivers = []
        for d in forced.values():
            mats = plant.output_matrices(d.force_output)
            if mats is None:
                self.drivers.append((d, d.force_output, None))
                continue
            row = unit_row(plant, d.force_output)
            if row is not None:
                self.drivers.append((d, row, None))  # y = x_i exactly
            else:
                self.drivers.append((d, None, np.swapaxes(mats[0], -1, -2).copy()))
        if len(self.drivers) == 1 and isinstance(self.drivers[0][1], int):
            # one force of one state coordinate (the bearing on θ'): called several times per
            # substep, so the general path's bookkeeping is skipped
            force, index = self.drivers[0][0].force, self.drivers[0][1]

            def compact(xs, w):
                f = force(xs[:, index])
                return f[:, None] if f.ndim == 1 else f

            self.compact = compact

    def compact(self, xs, w) -> np.ndarray:
        """The forces on the forced input columns only, (n_cases, n_forced)."""
        out = []
        for d, index, CT in self.drivers:
            if isinstance(index, int):
                y = xs[:, index]
            elif CT is not None:
                y = apply(xs, CT, self.batched)
                y = y[:, 0] if y.shape[1] == 1 else y
            else:
                y = self.plant.output(index, xs, w, None)
            f = d.force(y)
            out.append(f[:, None] if f.ndim == 1 else f)
        return out[0] if len(out) == 1 else np.concatenate(out, axis=1)

    def full(self, compact) -> np.ndarray:
        """f_in on every input channel, (n_cases, m)."""
        if len(self.cols) == self.m:
            return compact
        f = np.zeros((compact.shape[0], self.m))
        f[:, self.cols] = compact
        return f


class Instruments:
    """The measured channels of a run: true values by output matrices (or the plant's
    ``output``), then each channel's sensor; derivative sensors after their sources."""

    def __init__(self, plant, names, sensors, columns, dt, nc, batched, forced):
        self.plant, self.batched = plant, batched
        derived = [k for k in names if k in sensors and sensors[k].derivative_of is not None]
        direct = [k for k in names if k not in derived]
        for k in derived:  # the filtered channel is measured first
            src = sensors[k].derivative_of
            if src not in direct:
                direct.insert(0, src)
        self.names = tuple(direct + derived)
        mats = {k: plant.output_matrices(k) for k in direct}
        self.linear = [k for k in direct if mats[k] is not None]
        self.nonlinear = [k for k in direct if mats[k] is None]
        self.CT = self.DT = self.DfT = None
        self.cols = {}
        if self.linear:
            C, D, Df = stacked_output_matrices([mats[k] for k in self.linear], plant.n_inputs)
            self.CT = np.swapaxes(C, -1, -2).copy()
            self.DT = np.swapaxes(D, -1, -2).copy() if np.any(D) else None
            self.DfT = np.swapaxes(Df, -1, -2).copy() if forced and np.any(Df) else None
            col = 0
            for k in self.linear:
                size = mats[k][0].shape[-2]
                self.cols[k] = col if size == 1 else slice(col, col + size)
                col += size
        self.plan = []
        for k in direct:
            s = sensors.get(k)
            noisy = s is not None and np.any(s.noise)
            self.plan.append(
                (k, s, noise_column(columns, k, "its sensor noise", plant) if noisy else None)
            )
        self.plan = [p for p in self.plan if p[1] is not None]  # ideal sensors do nothing
        self.linear_cols = [(k, self.cols[k]) for k in self.linear]
        self.derived = []
        for k in derived:
            s = sensors[k]
            w = least_squares_derivative_weights(s.window, s.order, dt)
            noisy = np.any(s.noise)
            self.derived.append(
                (
                    k,
                    s,
                    s.derivative_of,
                    w,
                    None,
                    noise_column(columns, k, "its sensor noise", plant) if noisy else None,
                )
            )

    def measure(self, x, w_prev, f_in, noise_k, first: bool) -> dict:
        """Measurements at state x, held input w_prev and input force f_in."""
        y = {}
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
        for k, s, col in self.plan:
            y[k] = s.measure(y[k], None if col is None else noise_k[:, col])
        for i, (k, s, src, w, hist, col) in enumerate(self.derived):
            v = y[src]
            if first:  # the filter starts from rest at the first measured value
                hist = np.repeat(v[:, None], len(w), axis=1)
                self.derived[i] = (k, s, src, w, hist, col)
            hist[:, :-1] = hist[:, 1:]
            hist[:, -1] = v
            y[k] = s.measure(hist @ w, None if col is None else noise_k[:, col])
        return y


__all__ = ["InputForces", "Instruments", "stacked_output_matrices", "unit_row"]
