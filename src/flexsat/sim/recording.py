"""What a run keeps, and the result dataset built from it.

The time loop stores only what it must: the states of the current chunk of :data:`CHUNK`
samples (or every state when asked), the commands, applied and disturbed inputs, the input
forces and the recorded measurements. At the end of each chunk the recorded outputs, the
energy and the vibration energy are computed for the whole chunk in large array products
(outputs y = C x + D u + D_f f_in of :meth:`~flexsat.dynamics.plant.Plant.output_matrices`),
so neither a per-sample Python call per output nor the full state history is needed.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, cast

import numpy as np
import xarray as xr

from flexsat.sim.instruments import stacked_output_matrices
from flexsat.sim.metrics import METRIC_UNITS, channel_metrics, maneuver_metrics

if TYPE_CHECKING:
    from flexsat.control.base import Controller
    from flexsat.dynamics.plant import Channel, ManeuverChannels, Plant
    from flexsat.sim.config import SimConfig
    from flexsat.units import FloatArray

#: samples per chunk of states kept in the loop before its outputs are computed; 32 keeps the
#: buffer (32 × n_x values per case) small next to the recorded histories
CHUNK = 32
#: cases per block of the metrics: their temporaries (a few histories) stay small next to the
#: recorded histories of a large batch
METRIC_BLOCK = 32


@dataclass
class SimResult:
    """Time histories (``dataset``, dims case × time) and per-case ``metrics``."""

    dataset: xr.Dataset
    metrics: dict[str, np.ndarray]

    def metrics_records(self, labels: Sequence[Any] | None = None) -> list[dict[str, Any]]:
        """One JSON-ready dict per case (NaN → None)."""
        n = self.dataset.sizes["case"]
        rows = []
        for i in range(n):
            row: dict[str, Any] = {} if labels is None else {"run": labels[i]}
            for key, val in self.metrics.items():
                v = float(val[i])
                row[key] = None if not np.isfinite(v) else v
            rows.append(row)
        return rows


def _unit(unit: str) -> str:
    """A channel's unit for the dataset: products as spaces (``N m``, as units are written),
    powers as ``^`` (``kg m/s^2``): both read back by pint."""
    return unit.replace("**", "^").replace("*", " ")


def _history(n: int, nc: int, size: int) -> np.ndarray:
    return np.zeros((n, nc) if size == 1 else (n, nc, size))


def attitude_targets(controller: Controller, t: FloatArray, nc: int) -> FloatArray | None:
    """The law's target attitude at every recorded time, (nc, n_t, 4), or None without one.

    A law whose reference turns (it has ``target_at(t)``, e.g.
    :class:`flexsat.control.AttitudeLQG` about a constant-rate frame) is scored against the
    reference at each time; a fixed ``beta_target`` against itself throughout.
    """
    target_at = getattr(controller, "target_at", None)
    if callable(target_at):
        history = np.stack([np.broadcast_to(target_at(float(tk)), (nc, 4)) for tk in t], axis=1)
        return np.asarray(history, float)
    target = getattr(controller, "beta_target", None)
    if target is None:
        return None
    return np.broadcast_to(np.asarray(target, float).reshape(-1, 1, 4), (nc, len(t), 4))


class Recorder:
    """Histories of one run (module docstring); arrays are (n_t, n_cases[, size])."""

    def __init__(
        self,
        plant: Plant,
        n: int,
        nc: int,
        measured: tuple[str, ...],
        force_names: Mapping[str, str],
        record_states: bool,
        batched: bool,
        random_channels: Iterable[str] = (),
        allocate: bool = True,
        input_lag: int = 1,
    ) -> None:
        self.plant, self.n, self.nc, self.batched = plant, n, nc, batched
        # the input an output's feedthrough sees at sample k: the one held before it (1, a
        # sampled-data run) or the one at t_k itself (0, a continuous law)
        self.input_lag = input_lag
        m = plant.n_inputs
        # the compiled loop (flexsat.sim.compiled) writes its own records and hands views of
        # them over (allocate=False): the histories are then never allocated twice. They are
        # typed as what they hold once the loop runs; None only until that hand-over
        zeros: Callable[[tuple[int, ...]], Any] = np.zeros if allocate else (lambda shape: None)
        self.commands: FloatArray = zeros((n, nc, m))
        self.applied: FloatArray = zeros((n, nc, m))
        self.disturbed: FloatArray = zeros((n, nc, m))  # applied + disturbance: the plant's input
        self.forces: FloatArray | None = zeros((n, nc, m)) if force_names else None
        self.force_names = force_names
        # disturbance and force histories: of the channels that have them, and of those the
        # plant always records (the planar torque: a stable dataset for reports)
        always = set(getattr(plant, "recorded_disturbances", ()))
        self.with_disturbance = set(random_channels) | always
        self.with_force = set(force_names) | always
        history: Callable[[str], Any] = (
            (lambda k: _history(n, nc, _size(plant.outputs, k))) if allocate else (lambda k: None)
        )
        self.measured: dict[str, FloatArray] = {k: history(k) for k in measured}
        self.states: FloatArray | None = zeros((n, nc, plant.nx)) if record_states else None
        # recording states: the states themselves; allocate=False: None, never read (the
        # compiled loop computes its outputs itself)
        self.buffer: FloatArray = (
            cast("FloatArray", self.states)
            if record_states or not allocate
            else np.empty((min(CHUNK, n), nc, plant.nx))
        )
        names = [c for c in plant.recorded]
        self.outputs: dict[str, FloatArray] = {k: history(k) for k in names}
        mats = [plant.output_matrices(k) for k in names]
        self.linear = [k for k, mt in zip(names, mats) if mt is not None]
        self.nonlinear = [k for k, mt in zip(names, mats) if mt is None]
        if self.linear:
            C, D, Df = stacked_output_matrices(
                [mt for mt in mats if mt is not None], plant.n_inputs
            )
            self.CT, self.DT, self.DfT = (np.swapaxes(M, -1, -2) for M in (C, D, Df))
        has_vib = hasattr(plant, "vibration_energy")
        probe = np.zeros((plant.n_cases, plant.nx))  # (cases, n_x): one state per parameter case
        self.has_energy = plant.energy(probe) is not None
        self.has_vibration = has_vib and self.has_energy
        self.energy: FloatArray | None = zeros((n, nc)) if self.has_energy else None
        self.vibration: FloatArray | None = zeros((n, nc)) if self.has_vibration else None
        self.done = 0

    def flush(self, end: int) -> None:
        """Compute the recorded outputs and energies of samples [done, end)."""
        k0, T = self.done, end - self.done
        if T <= 0:
            return
        X = self.buffer[k0:end] if self.states is not None else self.buffer[:T]
        if self.input_lag == 0:
            Wp = self.disturbed[k0:end]
        else:
            Wp = np.empty((T, self.nc, self.plant.n_inputs))  # the input held before each sample
            Wp[1:] = self.disturbed[k0 : end - 1]
            Wp[0] = self.disturbed[k0 - 1] if k0 > 0 else 0.0
        F = None if self.forces is None else self.forces[k0:end]
        if self.linear:
            Y = self._linear(X, self.CT) + self._linear(Wp, self.DT)
            if F is not None:
                Y = Y + self._linear(F, self.DfT)
            col = 0
            for k in self.linear:
                size = self.outputs[k].shape[2] if self.outputs[k].ndim == 3 else 1
                self.outputs[k][k0:end] = Y[..., col] if size == 1 else Y[..., col : col + size]
                col += size
        for k in self.nonlinear:
            self.outputs[k][k0:end] = self.plant.output(k, X, Wp, F)
        if self.energy is not None:
            E = self.plant.energy(X)
            self.energy[k0:end] = E
            if self.vibration is not None:
                # has_vibration (set in __init__): the plant has vibration_energy
                self.vibration[k0:end] = self.plant.vibration_energy(X, E)  # type: ignore[attr-defined]
        self.done = end

    def _linear(self, X: FloatArray, MT: FloatArray) -> FloatArray:
        if not self.batched or MT.ndim == 2:
            return X @ MT
        return np.einsum("tci,cip->tcp", X, MT)

    def dataset(
        self,
        t: FloatArray,
        controller: Controller,
        theta0: FloatArray | None,
        config: SimConfig,
        substeps: int,
        engine: str = "python",
    ) -> SimResult:
        """The xarray dataset (case × time; views, no copies) and the maneuver metrics;
        ``engine`` (``"python"`` or ``"compiled"``: which loop ran) goes to its attributes."""
        plant, nc = self.plant, self.nc
        data: dict[str, tuple[tuple[str, ...], Any, dict[str, str]]] = {}

        def put(name: str, arr: FloatArray, unit: str, channel: str | None = None) -> None:
            # every history of one channel (command, applied, disturbance, measured) shares
            # its component axis, so they combine element-wise
            axis = f"{channel or name}_component"
            dims = ("case", "time") if arr.ndim == 2 else ("case", "time", axis)
            data[name] = (dims, np.swapaxes(arr, 0, 1), {"units": _unit(unit)})

        outs = {c.name: c for c in plant.outputs}
        # a single-axis maneuver is read against its law's reference: its angle and rate
        # first, the reference histories and the maneuver metrics
        axis = plant.maneuver
        for k in () if axis is None else (axis.angle, axis.rate):
            if k in self.outputs:
                put(k, self.outputs[k], outs[k].unit)
        refs = reference_histories(controller, t, nc) if axis is not None else None
        if axis is not None and refs is not None:  # refs is None without an axis
            put(f"{axis.angle}_ref", refs[0], "rad")
            put(f"{axis.rate}_ref", refs[1], "rad/s")
        self.disturbed -= self.applied  # the loop is over: keep the disturbance alone
        for ch, sl in plant.input_slices.items():
            unit = next(c.unit for c in plant.inputs if c.name == ch)

            def pick(a: FloatArray, sl: slice = sl) -> FloatArray:
                return a[..., sl.start] if sl.stop - sl.start == 1 else a[..., sl]

            put(f"{ch}_command", pick(self.commands), unit, ch)
            put(ch, pick(self.applied), unit)
            if ch in self.with_disturbance:
                put(f"disturbance_{ch}", pick(self.disturbed), unit, ch)
            if ch in self.with_force:
                name = f"{self.force_names.get(ch, 'friction')}_{ch}"
                if ch in self.force_names:
                    assert self.forces is not None  # kept whenever force_names is given
                    force = pick(self.forces)
                else:
                    force = np.broadcast_to(0.0, pick(self.applied).shape)  # no memory
                put(name, force, unit, ch)
        for k, v in self.outputs.items():
            if k not in data:
                put(k, v, outs[k].unit)
            if k in self.measured:
                put(f"{k}_measured", self.measured[k], outs[k].unit, k)
        for k, v in self.measured.items():
            if f"{k}_measured" not in data:
                put(f"{k}_measured", v, outs[k].unit, k)
        if self.energy is not None:
            put("energy", self.energy, "J")
        if self.vibration is not None:
            put("vibration_energy", self.vibration, "J")
        if self.states is not None:
            data["state"] = (("case", "time", "state_index"), np.swapaxes(self.states, 0, 1), {})
        histories = {k: v[1] for k, v in data.items()}
        metrics = _metrics(histories, axis, t, controller, theta0, config, refs, nc)
        units = METRIC_UNITS
        if not metrics:  # not a single-axis maneuver: the summary of every channel
            metrics, units = channel_metrics(
                histories,
                {c.name: c.unit for c in plant.outputs + plant.inputs},
                [c.name for c in plant.outputs],
                [c.name for c in plant.inputs],
                t,
                attitude_targets(controller, t, nc),
                config.settling_band,
            )
        for key, val in metrics.items():  # one Dataset call: each later insertion re-aligns
            data[key] = (("case",), val, {"units": units[key]})
        ds = xr.Dataset(data, coords={"time": ("time", t, {"units": "s"}), "case": np.arange(nc)})
        ds.attrs.update(
            control_rate_Hz=config.control_rate,
            settling_band_rad=config.settling_band,
            substeps=substeps,
            engine=engine,
        )
        return SimResult(ds, metrics)


def _size(channels: Iterable[Channel], name: str) -> int:
    return next(c.size for c in channels if c.name == name)


def reference_histories(
    controller: Controller, t: FloatArray, nc: int
) -> tuple[FloatArray, FloatArray] | None:
    """(θ_ref, θ'_ref) on the sample grid, (n_t, n_cases), or None for a law without them (no
    ``target`` for the maneuver angle: a state-space compensator, a scheduled gain)."""
    if not hasattr(controller, "reference_at") or not hasattr(controller, "target"):
        return None
    table = getattr(controller, "_table", None)
    if table is not None and len(table[0]) == len(t) and np.array_equal(table[0], t):
        th_ref, thd_ref = (
            np.broadcast_to(np.asarray(a, float).reshape(len(t), -1), (len(t), nc))
            for a in table[1:3]
        )
        return th_ref, thd_ref
    th, thd = np.zeros((len(t), nc)), np.zeros((len(t), nc))
    for k, tk in enumerate(t):
        th[k], thd[k] = controller.reference_at(tk)[:2]
    return th, thd


def _metrics(
    ds: Mapping[str, FloatArray],
    axis: ManeuverChannels | None,
    t: FloatArray,
    controller: Controller,
    theta0: FloatArray | None,
    config: SimConfig,
    refs: tuple[FloatArray, FloatArray] | None,
    nc: int,
) -> dict[str, FloatArray]:
    """The single-axis maneuver metrics from the (case, time) histories ``ds`` of the channels
    ``axis`` (:class:`~flexsat.dynamics.plant.ManeuverChannels`) names, for a plant with those
    histories (else none)."""
    if axis is None:
        return {}
    need = (axis.angle, axis.rate, axis.torque, axis.deflection, "vibration_energy")
    if refs is None or theta0 is None or not all(k in ds and ds[k].ndim == 2 for k in need):
        return {}
    # refs is not None: the law has a target (reference_histories checked) and, a slew law,
    # a reference (flexsat.control.base.SlewLaw)
    goal = controller.target  # type: ignore[attr-defined]
    target = np.broadcast_to(np.asarray(goal, float), (nc,))
    ref = controller.reference  # type: ignore[attr-defined]
    ref_end = None if ref is None else np.broadcast_to(np.asarray(ref.end_time, float), (nc,))
    blocks = []
    for start in range(0, nc, METRIC_BLOCK):
        c = slice(start, start + METRIC_BLOCK)
        blocks.append(
            maneuver_metrics(
                t,
                ds[axis.angle][c],
                ds[axis.rate][c],
                refs[1].T[c],
                ds[axis.torque][c],
                ds[axis.deflection][c],
                ds["vibration_energy"][c],
                theta0[c],
                target[c],
                None if ref_end is None else ref_end[c],
                config.settling_band,
            )
        )
    return {k: np.concatenate([b[k] for b in blocks]) for k in blocks[0]}
