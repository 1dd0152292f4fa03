r"""Running many cases of one maneuver setup: vectorised chunks, dask scheduling, a zarr store.

Issue 13, "Execution" (trade studies and Monte Carlo at scale; the Junkins, Pollock & Rahman 1990
trade surfaces of Att. 3 Figs. 5–7 and the robustness sets of the EPS slew study c. 1989 and
Agrawal & Bang 1996 are sweeps of this kind). A run
is three pieces:

* a **case builder** ``build(parameters, seeds) -> (plant, law, config, initial_state)``: for a
  chunk of cases, or a group of it ("Calls" below; ``parameters`` maps each column name of
  the parameter table to its (n,) slice, SI; ``seeds`` the (n,) noise seeds) one batched call
  ``simulate(plant, law, config, n_cases=n, seeds=seeds, initial_state=initial_state)`` —
  the plant a :func:`~flexsat.dynamics.dispersion.stack_plants` batch when plant parameters
  vary, the law with per-case parameter arrays. :class:`HubManeuverBuilder` is the one for the
  hub + appendage maneuvers (the TAMU Law II slew). It lives in this layer because it needs
  only the layers below (plant, torque shape, law, engine); the TAMU numbers (plant, hardware
  settings, reference inertia, gains) are its arguments, taken from
  :func:`flexsat.cases.tamu` by the caller — design may not import cases;
* a **metrics extractor** ``extract(result) -> {name: (n,) array}`` (default: the engine's
  maneuver metrics, :attr:`~flexsat.sim.recording.SimResult.metrics`). A builder may instead
  run its chunk itself (``build.run_chunk``, :func:`run_chunk`): a batch over any scenario
  document runs each case through the scenario runner and reads the metrics of its result
  (:mod:`flexsat.scenarios.batch_cases`); the seeds, the scheduling and the store below are
  the same;
* a **parameter table**: n_cases rows, named SI columns.

Calls. A builder may name ``per_run_parameters``: columns one batched call cannot vary
(:class:`HubManeuverBuilder`: the encoder's resolution). :func:`run_chunk` then splits the
chunk into groups of cases with equal values in those columns, runs one call per group (each
case with its own seed) and puts the results back in case order; every other column goes into
the one call as per-case arrays.

Seeds. Case i's noise seed comes from the base seed and i alone, the i-th child of
``numpy.random.SeedSequence(base_seed)`` (its ``spawn_key`` is ``(i,)``, what
``SeedSequence.spawn`` gives the i-th child; computed directly so a chunk never spawns the
children before it), folded into the engine's seed range [0, 2⁶³):

.. math::

    s_i = \lfloor \mathrm{SeedSequence}(b, \mathrm{spawn\_key}=(i,))
          .\mathrm{generate\_state}(1, \mathrm{uint64})_0 / 2 \rfloor .

The engine gives every case its own noise stream from its seed (:func:`flexsat.sim.simulate`,
``seeds=``) and its batched products treat each case alone, so a case's result does not depend
on which chunk it is in, how large the chunk is, or which worker runs it: the stores of any
chunking and worker count are bit-identical (tests/design/test_batch_runner.py).

Scheduling. Every chunk is one task of a :mod:`distributed` client: by default an in-process
client (``LocalCluster(processes=False)``, one worker thread: the chunk is already vectorised,
and the one code path — futures, ``retries=``, completion order — is the same as on a cluster;
dask's synchronous scheduler would have no retries and no futures to stream from); ``workers=N``
starts a local cluster of N single-threaded worker processes; ``scheduler="tcp://HOST:PORT"``
uses an existing cluster, asked first whether it is one (no dask scheduler answering within
:data:`CONNECT_TIMEOUT` s is a :class:`~flexsat.input_checks.FieldError` of ``scheduler``
naming the address; :mod:`flexsat.design.batch_cluster`). A chunk whose worker dies, or whose
task fails otherwise, is run again (``retries``); a ValueError a chunk raises (a value its run
refuses, a history it does not record, a diverged case) would be raised again by every retry,
so it is sent back as the task's result and raised once on the client, with its own type and
attributes (a FieldError's ``field``).

Store. Results stream to a zarr store (xarray) as chunks finish, written by the client (a single
writer: no two writers share a zarr chunk, and workers need no access to the store's disk):
each metric over ``case``, the chosen time histories over (case, time), the parameter table,
each case's seed and a completion mask ``done`` over ``case``. A chunk's data are written whole
before its mask is set, so an interrupted run (Ctrl-C, a lost client) leaves at worst a chunk
written and not marked, which the next run computes again to the same numbers. At most
``2 × workers`` chunks are in flight, so the memory held is a few chunks' results whatever the
case count. The store's ``fingerprint`` attribute is the SHA-256 of the setup: the setup text
(the scenario as given), the builder's description, the parameter table (names, values), the
base seed and the recorded histories — nothing that depends on the chunking. Running the same
setup into an existing store resumes it (the chunks not all done are run, the rest skipped); a
store of a different setup is refused. The store's layout is built in a sibling folder,
``.<name>.partial``, and renamed into place when complete: a run killed while laying it out
leaves no store (the next run starts afresh) rather than a half-made one it would refuse. An
interrupted run (Ctrl-C) raises :class:`BatchInterrupted`, saying how many cases the store keeps.
Nothing is pickled into the store. One run at a time fills a store: a run holds a lock file next
to it, and a second run is refused at once with
:class:`~flexsat.design.batch_store.StoreInUse`, naming the first (its process, host, start
and command); a lock whose run died is stale and taken over. A store that cannot be written (a
read-only or full disk, a file-size limit, a folder that cannot be made) raises
:class:`~flexsat.design.batch_store.StoreError` saying what it keeps, and stays resumable
(:mod:`flexsat.design.batch_store`).
"""

from __future__ import annotations

import hashlib
import math
import time
from collections.abc import Callable, Mapping
from contextlib import ExitStack
from dataclasses import dataclass, field, replace
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from flexsat import limits
from flexsat.control.lyapunov import LyapunovTracker
from flexsat.design.batch_cluster import CONNECT_TIMEOUT, batch_client, quiet_shutdown
from flexsat.design.batch_seeds import case_seeds, nonneg_int
from flexsat.design.batch_store import (
    STORE_LAYOUT,
    StoreLock,
    create_store,
    open_store_mask,
    store_faults,
    write_chunk,
)
from flexsat.dynamics.dispersed_hub import DispersedHubAppendage
from flexsat.dynamics.hub_appendage import HubAppendage, HubAppendageParams
from flexsat.input_checks import (
    FieldError,
    require_count,
    require_finite,
    require_nonneg,
    require_positive,
)
from flexsat.maneuvers.torque_shapes import SmoothBangBang
from flexsat.sim import SimConfig, SimulationDiverged, simulate
from flexsat.sim.channels import ChannelSensor
from flexsat.sim.disturbances import RandomTorque
from flexsat.sim.engine import offset_cases
from flexsat.sim.recording import SimResult


# -- the parameter table -----------------------------------------------------------------------
def _table(parameters: Mapping[str, Any], known: tuple[str, ...] | None) -> dict[str, np.ndarray]:
    """The parameter table as {name: (n_cases,) float array}; ValueError naming a bad column."""
    if not parameters:
        raise FieldError("parameters", "give at least one column (name -> one value per case)")
    table = {}
    for name, values in parameters.items():
        if known is not None and name not in known:
            raise FieldError(
                "parameters",
                f"unknown parameter {name!r}; the case builder knows {', '.join(known)}",
            )
        col = require_finite(values, f"parameters[{name!r}]")
        if col.ndim != 1:
            raise FieldError(
                f"parameters[{name!r}]", f"must be one value per case (1-D), got shape {col.shape}"
            )
        table[name] = np.ascontiguousarray(col, dtype=np.float64)
    sizes = {name: len(col) for name, col in table.items()}
    if len(set(sizes.values())) != 1 or not next(iter(sizes.values())):
        raise FieldError(
            "parameters", f"every column must have the same number (>= 1) of cases, got {sizes}"
        )
    return table


def fingerprint(
    setup_text: str,
    table: Mapping[str, np.ndarray],
    base_seed: int,
    histories: tuple[str, ...],
    builder_text: str = "",
) -> str:
    """SHA-256 (hex) of everything that fixes the results and nothing that depends on the
    chunking: the store layout, the setup text, the builder's description, the parameter table
    (names in order and the float64 values' bytes), the base seed and the recorded histories."""
    h = hashlib.sha256()
    for part in (
        STORE_LAYOUT,
        setup_text,
        builder_text,
        repr(int(base_seed)),
        repr(tuple(histories)),
    ):
        h.update(part.encode())
        h.update(b"\0")
    for name, col in table.items():
        h.update(name.encode())
        h.update(b"\0")
        h.update(np.ascontiguousarray(col, dtype="<f8").tobytes())
    return h.hexdigest()


# -- the hub + appendage maneuver builder --------------------------------------------------------
#: parameters of :class:`HubManeuverBuilder`: the reference maneuver, the Law II gains and the
#: plant (EI the appendage's bending stiffness, damping the modal damping ratio of every mode)
MANEUVER_PARAMETERS = ("alpha", "u_max", "duration")
GAIN_PARAMETERS = ("g1", "g2", "g3")
PLANT_PARAMETERS = ("hub_inertia", "EI", "damping", "tip_mass", "tip_inertia")
#: the bearing friction of the run (Att. 3 Eq. 23): Coulomb c1 (N m) and viscous c2
#: (N m s/rad), per case
FRICTION_PARAMETERS = ("friction_coulomb", "friction_viscous")
#: the sensors and the actuator of the run (Att. 3 §V's hardware): the torque limit (N m), the
#: encoder's resolution (rad), the gyro's and the strain gauge's 1σ noise per sample (rad/s,
#: N m) and the 1σ random hub torque (N m). All but the encoder's resolution are per case in
#: the batched call; cases differing in the resolution run in separate calls
#: (:attr:`HubManeuverBuilder.per_run_parameters`, :func:`run_chunk`)
SENSOR_ACTUATOR_PARAMETERS = (
    "saturation",
    "encoder_resolution",
    "gyro_noise",
    "strain_noise",
    "random_torque",
)
#: the SI unit and the rule of each sensor/actuator parameter
_SENSOR_ACTUATOR_RULES = {
    "saturation": ("N*m", require_positive),
    "encoder_resolution": ("rad", require_nonneg),
    "gyro_noise": ("rad/s", require_nonneg),
    "strain_noise": ("N*m", require_nonneg),
    "random_torque": ("N*m", require_nonneg),
}
#: the measured channel of each sensor noise parameter
_NOISE_CHANNELS = {"gyro_noise": "theta_dot", "strain_noise": "root_torque"}


@dataclass(frozen=True)
class HubManeuverBuilder:
    r"""Control Law II slews of a hub + appendage plant, one batched call per chunk.

    Each case is the slew of Att. 3 §V (Junkins, Pollock & Rahman 1990): the
    smoothed bang-bang reference (Att. 3 Eqs. 12–16, :class:`~flexsat.maneuvers.SmoothBangBang`)
    tracked by Law II (Eq. 17, :class:`~flexsat.control.LyapunovTracker`) on
    :class:`~flexsat.dynamics.hub_appendage.HubAppendage`. Any of :data:`MANEUVER_PARAMETERS`,
    :data:`GAIN_PARAMETERS`, :data:`PLANT_PARAMETERS`, :data:`FRICTION_PARAMETERS` (the
    bearing friction of Att. 3 Eq. 23, in place of the config's) and
    :data:`SENSOR_ACTUATOR_PARAMETERS` (the hardware of Att. 3 §V, in place of the config's:
    ``saturation`` the actuator's torque limit, ``encoder_resolution`` the encoder's quantum,
    ``gyro_noise`` and ``strain_noise`` the 1σ noise per sample of the gyro rate (with
    ``sensors.rate="gyro"`` only) and of the strain-gauge root torque, ``random_torque`` the 1σ
    random hub torque) may be a column of the parameter table; the others keep the values
    given here. Each case equals the run alone with its values in the config: all but the
    encoder's resolution are per case in one batched call (the compiled loop holds a torque
    limit, a quantum and noise levels per case), and cases of different resolutions run in
    separate calls (:attr:`per_run_parameters`). Of α, u_max and T exactly two fix the reference
    (Eq. 15); a column of T with neither α nor u_max a column replaces u_max.

    The reference is designed with the inertia ``reference_inertia`` × I_model / I_base
    (I the model's rigid total inertia): a case with other plant parameters keeps the base
    case's design-to-model inertia ratio (the rule of :mod:`flexsat.cases.tamu`).

    Parameters
    ----------
    params : HubAppendageParams
        The base plant.
    n_modes : int
    config : SimConfig
        The run (rate, duration, sensors, actuator, friction, noise); its seed is not used, the
        per-case seeds are.
    angle : float
        Slew angle, rad.
    reference_inertia : float
        Inertia the base case's reference is designed with, kg m².
    u_max, g1, g2, g3, alpha : float
        The cases' values where the table has no column: the reference's peak torque (N m),
        the Law II gains (N m/rad, N m s/rad, dimensionless) and the shape's rise fraction α.
    stiffening : bool
    """

    params: HubAppendageParams
    n_modes: int
    config: SimConfig
    angle: float
    reference_inertia: float
    u_max: float
    g1: float
    g2: float
    g3: float = 0.0
    alpha: float = 0.2
    stiffening: bool = False
    parameter_names: tuple[str, ...] = field(
        default=MANEUVER_PARAMETERS
        + GAIN_PARAMETERS
        + PLANT_PARAMETERS
        + FRICTION_PARAMETERS
        + SENSOR_ACTUATOR_PARAMETERS,
        init=False,
    )
    #: columns one batched call takes one value of (:func:`run_chunk` splits a chunk by them):
    #: the encoder's resolution, a scalar of the :class:`~flexsat.sim.sensors.Sensors` preset,
    #: whose quantiser q·round(θ/q) in the engine's Python loop has no per-case "q = 0: exact"
    per_run_parameters: tuple[str, ...] = field(default=("encoder_resolution",), init=False)

    def describe(self) -> str:
        """The builder's settings as text (part of the store's fingerprint)."""
        return repr(self)

    def _inertias(self, table: Mapping[str, np.ndarray], n: int):
        """(rigid total inertia, appendage inertia I_b) per case, kg m²: the plant parameters
        of the table in the base parameters (their fields take arrays; their rules apply)."""
        varied = {k: table[k] for k in PLANT_PARAMETERS if k in table}
        p = replace(self.params, **varied) if varied else self.params
        return (np.broadcast_to(p.total_inertia, (n,)), np.broadcast_to(p.appendage_inertia, (n,)))

    def _plant(self, table: Mapping[str, np.ndarray], n: int):
        """The base plant, or with plant parameters in the table one
        :class:`~flexsat.dynamics.dispersed_hub.DispersedHubAppendage` of the chunk's cases:
        every case's modes, integrals and matrices in array operations, each case the same
        bits whichever chunk it is in."""
        varied = [k for k in PLANT_PARAMETERS if k in table]
        if not varied:
            return _hub_plant(self.params, self.n_modes, self.stiffening)
        fields = {k: np.broadcast_to(table[k], (n,)) for k in varied if k != "damping"}
        return DispersedHubAppendage.from_parameters(
            replace(self.params, **fields),
            self.n_modes,
            self.stiffening,
            damping=np.broadcast_to(table["damping"], (n,)) if "damping" in table else None,
        )

    def _law(self, table: Mapping[str, np.ndarray], n: int) -> LyapunovTracker:
        inertia, appendage = self._inertias(table, n)
        shape = {k: table[k] for k in MANEUVER_PARAMETERS if k in table}
        if len(shape) == 3:
            raise FieldError(
                "parameters",
                "give at most two of alpha, u_max, duration (Att. 3 Eq. 15 fixes the third)",
            )
        for k in ("alpha", "u_max"):
            if len(shape) < 2 and k not in shape:
                shape[k] = np.full(n, getattr(self, k))
        ref = SmoothBangBang(
            self.angle, self.reference_inertia * inertia / self.params.total_inertia, **shape
        )
        gains = {k: table.get(k, np.full(n, getattr(self, k))) for k in GAIN_PARAMETERS}
        return LyapunovTracker(
            ref, **gains, appendage_inertia=appendage, n_appendages=self.params.n_appendages
        )

    def _friction(self, table: Mapping[str, np.ndarray]):
        """The run's bearing friction with the table's columns (per case) in place of its
        Coulomb and viscous coefficients."""
        f = self.config.friction
        units = {"friction_coulomb": "N*m", "friction_viscous": "N*m*s/rad"}
        varied = {
            k[len("friction_") :]: require_nonneg(table[k], f"parameters[{k!r}]", units[k])
            for k in FRICTION_PARAMETERS
            if k in table
        }
        return replace(f, **varied) if varied else f

    def _sensor_actuator(self, table: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
        """The table's sensor/actuator columns in SI, their rules applied (ValueError naming
        the parameter)."""
        out = {}
        for k in SENSOR_ACTUATOR_PARAMETERS:
            if k in table:
                unit, rule = _SENSOR_ACTUATOR_RULES[k]
                out[k] = rule(table[k], f"parameters[{k!r}]", unit)
        if "gyro_noise" in out and self.config.sensors.rate != "gyro":
            raise FieldError(
                "parameters['gyro_noise']",
                "the run's rate measurement is "
                f"{self.config.sensors.rate!r}, not 'gyro'; a gyro noise would "
                f"change nothing",
            )
        return out

    def _config(self, table: Mapping[str, np.ndarray]) -> SimConfig:
        """The run of the chunk ``table``: the config with the table's friction and sensor/
        actuator columns. The torque limit and the random torque go in per case (their preset
        classes take arrays); the gyro and strain-gauge noise as per-case
        :class:`~flexsat.sim.channels.ChannelSensor` s on ``theta_dot`` and ``root_torque``
        (what the :class:`~flexsat.sim.sensors.Sensors` preset makes of a scalar noise, or the
        config's own sensor on that channel, with the noise replaced); the encoder's
        resolution, one value per call (:attr:`per_run_parameters`), in the preset."""
        config = self.config
        if any(k in table for k in FRICTION_PARAMETERS):
            config = replace(config, friction=self._friction(table))
        cols = self._sensor_actuator(table)
        if "saturation" in cols:
            config = replace(
                config, actuator=replace(config.actuator, saturation=cols["saturation"])
            )
        if "random_torque" in cols:
            config = replace(config, random_torque=RandomTorque(cols["random_torque"]))
        if "encoder_resolution" in cols:
            values = np.unique(cols["encoder_resolution"])
            if len(values) != 1:
                raise FieldError(
                    "parameters['encoder_resolution']",
                    "one value per call; run "
                    "the cases through run_chunk, which splits a chunk by it",
                )
            config = replace(
                config, sensors=replace(config.sensors, encoder_resolution=float(values[0]))
            )
        sensors = {
            ch: replace(config.channel_sensors.get(ch, ChannelSensor()), noise=cols[k])
            for k, ch in _NOISE_CHANNELS.items()
            if k in cols
        }
        if sensors:
            config = replace(config, channel_sensors={**config.channel_sensors, **sensors})
        return config

    def for_table(self, parameters: Mapping[str, np.ndarray]) -> HubManeuverBuilder:
        r"""The builder of the whole parameter table, its integrator substeps fixed once
        before the table is cut into chunks: the engine raises them for the stiffest friction
        of each call (:func:`flexsat.sim.config.stable_substeps`), so a chunk's step, and its
        results, would depend on which cases share the chunk.

        The friction's damping rate is λ = (c1/ε + c2) (M⁻¹)_θθ (h λ <= 1.5,
        :data:`~flexsat.sim.config.FRICTION_STEP_LIMIT`), and (M⁻¹)_θθ <= 1 / I_hub (the
        Schur complement I_tot − mᵀ M_ee⁻¹ m is the hub inertia plus the least kinetic
        energy of the appendages at a unit hub rate, >= I_hub): the substeps

        .. math:: \max\left(N_{\rm config},\ \left\lceil \frac{\Delta t}{1.5}
                  \max_i \frac{c_{1,i}/\varepsilon + c_{2,i}}{I_{{\rm hub},i}}
                  \right\rceil\right)

        over every case i of the table suffice for every chunk, so the engine keeps them.
        Without friction the builder is returned as is.
        """
        from flexsat.sim.config import FRICTION_STEP_LIMIT

        f = self._friction(parameters)
        if not f.active:
            return self
        hub = parameters.get("hub_inertia", self.params.hub_inertia)
        rate = float(np.max((f.coulomb / f.smoothing + f.viscous) / np.asarray(hub, float)))
        needed = self.config.dt * rate / FRICTION_STEP_LIMIT
        limits.check_count(
            needed,
            limits.MAX_SUBSTEPS,
            "friction",
            f"a stable integration of the stiffest friction of the table "
            f"(damping rate up to {rate:.3g} 1/s) needs substeps per control "
            f"period",
            "lower friction_coulomb or friction_viscous",
        )
        substeps = max(self.config.substeps, math.ceil(needed))
        return replace(self, config=replace(self.config, substeps=substeps))

    def check(self, parameters: Mapping[str, np.ndarray]) -> None:
        """Apply the rules of the plant parameters, the reference (α in [0, 1/4], u_max > 0,
        T between the bang-bang and the α = 1/4 time), the gains (g1, g2 ≥ 0, g3 > −n), the
        friction (c1, c2 ≥ 0) and the sensors/actuator (torque limit > 0; resolution, noise and
        random torque ≥ 0; a gyro noise only with a gyro rate) to the whole table at once,
        before any chunk runs.

        Raises
        ------
        ValueError
            Naming the parameter and the rule.
        """
        self._law(parameters, len(next(iter(parameters.values()))))
        self._friction(parameters)
        self._sensor_actuator(parameters)

    def __call__(self, parameters: Mapping[str, np.ndarray], seeds: np.ndarray):
        """(plant, law, config, initial_state) of the chunk ``parameters`` (module docstring)."""
        n = len(seeds)
        return (
            self._plant(parameters, n),
            self._law(parameters, n),
            self._config(parameters),
            None,
        )


@lru_cache(maxsize=4)
def _hub_plant(params: HubAppendageParams, n_modes: int, stiffening: bool) -> HubAppendage:
    """The base plant, built once per process: its modal integrals (a Gauss quadrature) cost
    0.4 s at 10 modes, as much as the simulation of a 1,000-case chunk."""
    return HubAppendage(params, n_modes=n_modes, stiffening=stiffening)


def maneuver_metrics(result: SimResult) -> dict[str, np.ndarray]:
    """The engine's maneuver metrics of every case (settling time, overshoot, peak torque,
    residual energy, ...): the default extractor. It reads ``result.metrics`` only
    (``reads_metrics_only``), so a chunk without histories runs with
    ``simulate(metrics_only=True)``."""
    return {k: np.asarray(v, float) for k, v in result.metrics.items()}


#: an extractor with this attribute true reads only ``result.metrics``: :func:`run_chunk` then
#: asks the engine for the metrics alone (no time history is computed or kept)
maneuver_metrics.reads_metrics_only = True


# -- one chunk ---------------------------------------------------------------------------------
def run_chunk(
    build: Callable,
    extract: Callable,
    parameters: Mapping[str, np.ndarray],
    start: int,
    base_seed: int,
    histories: tuple[str, ...] = (),
) -> dict[str, np.ndarray]:
    """Run the cases ``start .. start + n`` (n the length of the ``parameters`` columns) in one
    batched call: {metric: (n,)} plus {history: (n, n_t)} and ``seed`` (n,).

    Without histories and with an extractor that reads only the metrics
    (``extract.reads_metrics_only``, as :func:`maneuver_metrics`), the call is
    ``simulate(..., metrics_only=True)``: the metrics accumulated in the compiled loop. Either
    way the propagation does not depend on the chunk size (``batch_independent``): a case
    alone is a chunk of one, bit for bit.

    A builder whose ``per_run_parameters`` name columns of the chunk (values one call cannot
    vary) gets one call per group of cases with equal values in those columns, each case with
    its own seed; the results are put back in case order. The engine treats every case on its
    own, so a case's numbers do not depend on the group it ran in either.

    A builder with its own ``run_chunk(extract, parameters, start, base_seed, histories)``
    runs its cases itself (:class:`flexsat.scenarios.batch_cases.DocumentCases`: one scenario
    run per case, each with the seed of its index) and returns the same mapping."""
    own = getattr(build, "run_chunk", None)
    if own is not None:
        return own(extract, parameters, start, base_seed, histories)
    n = len(next(iter(parameters.values())))
    seeds = case_seeds(base_seed, np.arange(start, start + n))
    keys = [k for k in getattr(build, "per_run_parameters", ()) if k in parameters]
    if not keys:
        return _run_cases(build, extract, parameters, seeds, histories)
    _, group = np.unique(
        np.stack([parameters[k] for k in keys], axis=1), axis=0, return_inverse=True
    )
    group = group.reshape(-1)
    out: dict[str, np.ndarray] = {}
    for g in range(group.max() + 1):
        idx = np.flatnonzero(group == g)
        part = _run_cases(
            build, extract, {k: v[idx] for k, v in parameters.items()}, seeds[idx], histories
        )
        for name, values in part.items():
            if name == "time":
                out[name] = values
                continue
            if name not in out:
                out[name] = np.empty((n,) + values.shape[1:], dtype=values.dtype)
            out[name][idx] = values
    return out


def _run_cases(
    build: Callable,
    extract: Callable,
    parameters: Mapping[str, np.ndarray],
    seeds: np.ndarray,
    histories: tuple[str, ...],
) -> dict[str, np.ndarray]:
    """One batched call of the cases ``parameters`` with their ``seeds`` (:func:`run_chunk`)."""
    n = len(seeds)
    plant, law, config, x0 = build(parameters, seeds)
    lean = not histories and getattr(extract, "reads_metrics_only", False)
    result = simulate(
        plant,
        law,
        config,
        n_cases=n,
        seeds=seeds,
        initial_state=x0,
        metrics_only=lean,
        batch_independent=True,
    )
    out = {}
    for name, values in extract(result).items():
        values = np.asarray(values, float)
        if values.shape != (n,):
            raise FieldError(
                "extract",
                f"metric {name!r} has shape {values.shape}, expected ({n},) (one value per case)",
            )
        out["metric_" + name] = values
    for name in histories:
        if name not in result.dataset:
            recorded = [v for v in result.dataset.data_vars if "time" in result.dataset[v].dims]
            raise FieldError(
                "histories",
                f"{name!r} is not a recorded variable; the run records {', '.join(recorded)}",
            )
        out["history_" + name] = np.asarray(
            result.dataset[name].transpose("case", "time").values, float
        )
    out["time"] = np.asarray(result.dataset["time"].values, float)
    out["seed"] = seeds
    return out


@dataclass(frozen=True)
class _Refusal:
    """A ValueError a chunk raised on its worker (a value the engine refuses, a history it does
    not record, a diverged case), sent back as the task's result instead of raised.

    The same chunk would raise it again on every retry (the cases and their seeds fix the run),
    so it is not retried, nor logged by dask as a failed task; and the client raises it again
    with its own type and attributes (a :class:`~flexsat.input_checks.FieldError`'s ``field``,
    a :class:`~flexsat.sim.SimulationDiverged`'s ``cases``), which dask's own transport loses
    for a class whose ``__init__`` takes more than its message (it sends a bare ``Exception``).
    """

    kind: type[ValueError]
    args: tuple[Any, ...]
    state: dict[str, Any]

    def error(self) -> ValueError:
        """The exception again: its class, its arguments and its attributes, without calling
        its ``__init__``."""
        exc = self.kind.__new__(self.kind, *self.args)
        exc.args = self.args
        exc.__dict__.update(self.state)
        return exc


def _chunk_task(
    build: Callable,
    extract: Callable,
    parameters: Mapping[str, np.ndarray],
    start: int,
    base_seed: int,
    histories: tuple[str, ...],
) -> dict[str, np.ndarray] | _Refusal:
    """:func:`run_chunk` as a dask task: a ValueError is returned as a :class:`_Refusal`."""
    try:
        return run_chunk(build, extract, parameters, start, base_seed, histories)
    except SimulationDiverged as exc:  # named by the batch's case numbers, not the chunk's
        exc = offset_cases(exc, start)
        return _Refusal(type(exc), exc.args, dict(vars(exc)))
    except ValueError as exc:
        return _Refusal(type(exc), exc.args, dict(vars(exc)))


# -- progress ----------------------------------------------------------------------------------
@dataclass(frozen=True)
class BatchProgress:
    """Where a run stands, passed to the progress callback after every finished chunk.

    ``cases_per_s`` counts the cases computed in this call (skipped ones excluded) over the
    wall time since the first chunk was submitted; ``eta_s`` = remaining / cases_per_s."""

    cases_done: int
    cases_total: int
    chunks_done: int
    chunks_total: int
    cases_per_s: float
    eta_s: float


# -- the run -----------------------------------------------------------------------------------
class BatchInterrupted(KeyboardInterrupt):
    """A run stopped by Ctrl-C (or another KeyboardInterrupt): ``store``, ``cases_done`` (kept in
    the store) and ``n_cases``; running the same setup again resumes it."""

    def __init__(self, store: Path, cases_done: int, n_cases: int):
        super().__init__(store, cases_done, n_cases)
        self.store, self.cases_done, self.n_cases = store, cases_done, n_cases

    def __str__(self) -> str:
        return (
            f"interrupted: {self.cases_done} of {self.n_cases} cases are done and kept in "
            f"the store {str(self.store)!r}; run the same command again to resume"
        )


@dataclass(frozen=True)
class BatchSummary:
    """What a call did: ``store`` (path), ``n_cases``, ``chunks_run`` and ``chunks_skipped``
    (finished by an earlier call), ``wall_s`` and the fingerprint."""

    store: Path
    n_cases: int
    chunks_run: int
    chunks_skipped: int
    wall_s: float
    fingerprint: str


def run_batch(
    build: Callable,
    parameters: Mapping[str, Any],
    store: str | Path,
    *,
    extract: Callable[[Any], Mapping[str, Any]] = maneuver_metrics,
    base_seed: int = 0,
    chunk_size: int = 1000,
    histories: tuple[str, ...] = (),
    setup_text: str = "",
    workers: int | None = None,
    scheduler: str | None = None,
    retries: int = 2,
    progress: Callable[[BatchProgress], None] | None = None,
) -> BatchSummary:
    """Run every case of the parameter table in chunks on dask, streaming to a zarr store.

    Parameters
    ----------
    build : callable
        The case builder (module docstring); if it has ``parameter_names``, every column of
        ``parameters`` must be one of them; if it has ``check(table)``, it is called on the
        whole table before anything runs, then ``for_table(table)`` (if it has it) gives the
        builder the chunks run with; if it has ``describe()``, its text is part of the
        fingerprint (a plain function has none: give the setup in ``setup_text``).
    parameters : mapping of str to array_like
        The parameter table: one (n_cases,) column per name, SI.
    store : str or Path
        The zarr store (a directory). An existing store of the same setup is resumed.
    extract : callable
        ``SimResult -> {metric: (n,) array}`` (a builder with its own ``run_chunk``: what
        that reads its result with); picklable for process workers.
    base_seed : int
        The seed every case's noise seed derives from (:func:`case_seeds`).
    chunk_size : int
        Cases per chunk (one batched call, one task); also the zarr chunk along ``case`` of a
        new store. Does not change any result.
    histories : tuple of str
        Recorded time histories to keep over (case, time) (``"theta"``, ``"torque"``, ...).
    setup_text : str
        The scenario as given (part of the fingerprint).
    workers : int, optional
        Run on a local cluster of this many worker processes.
    scheduler : str, optional
        Address of an existing dask scheduler, ``tcp://HOST:PORT``.
    retries : int
        Times a chunk whose task failed or whose worker was lost is run again.
    progress : callable, optional
        Called with a :class:`BatchProgress` after every finished chunk (and once at the start
        with the cases already done); an exception it raises (KeyboardInterrupt) stops the run
        after the chunk is stored, cancelling the others.

    Raises
    ------
    ValueError
        Naming the field: an unknown parameter name (with the known ones), columns of different
        lengths or non-finite values, a value the builder's ``check`` refuses, a scheduler
        that does not answer within :data:`CONNECT_TIMEOUT` s, a store that belongs to another
        setup; or the ValueError a chunk raised, with its type and attributes.
    flexsat.design.batch_store.StoreInUse
        Another run holds the store (naming it); nothing is changed.
    flexsat.design.batch_store.StoreError
        The store cannot be locked, read or written (saying what it keeps).
    """
    from distributed import as_completed

    table = _table(parameters, getattr(build, "parameter_names", None))
    check = getattr(build, "check", None)
    if check is not None:
        check(table)
    for_table = getattr(build, "for_table", None)
    if for_table is not None:  # sweep-wide settings, fixed before the table is cut up
        build = for_table(table)
    n_cases = len(next(iter(table.values())))
    chunk_size = require_count(chunk_size, "chunk_size")
    histories = tuple(histories)
    retries = nonneg_int(retries, "retries")
    describe = getattr(build, "describe", None)
    fp = fingerprint(setup_text, table, base_seed, histories, describe() if describe else "")
    path = Path(store)
    created, cases_done = False, 0

    def kept() -> str:
        """What the store keeps, for a fault of the store (:func:`store_faults`)."""
        if not created:
            return "No store was made; run the same command again once it can be written."
        return (
            f"The store keeps {cases_done} of {n_cases} cases; run the same command again "
            f"to resume it."
        )

    with ExitStack() as held:
        with store_faults(path, kept):
            held.enter_context(StoreLock(path))  # one run at a time, until this one ends
            done = open_store_mask(path, fp, n_cases)
        created = done is not None
        starts = [
            s
            for s in range(0, n_cases, chunk_size)
            if done is None or not done[s : s + chunk_size].all()
        ]
        n_chunks = math.ceil(n_cases / chunk_size)
        cases_done = n_cases - sum(min(chunk_size, n_cases - s) for s in starts)
        t0 = time.perf_counter()
        if progress is not None:
            progress(
                BatchProgress(
                    cases_done,
                    n_cases,
                    n_chunks - len(starts),
                    n_chunks,
                    0.0,
                    math.inf if starts else 0.0,
                )
            )
        if not starts:
            return BatchSummary(path, n_cases, 0, n_chunks, time.perf_counter() - t0, fp)

        client, cluster = batch_client(workers, scheduler)
        window = 2 * max(1, len(client.scheduler_info().get("workers", {})) or 1)
        pending = list(reversed(starts))
        computed = 0
        try:

            def submit(start):
                chunk = {k: v[start : start + chunk_size] for k, v in table.items()}
                return client.submit(
                    _chunk_task,
                    build,
                    extract,
                    chunk,
                    start,
                    base_seed,
                    histories,
                    retries=retries,
                    pure=False,
                    key=f"chunk-{fp[:12]}-{start}",
                )

            futures = as_completed(
                [submit(pending.pop()) for _ in range(min(window, len(pending)))],
                with_results=False,
                loop=client.loop,
            )
            chunks_run, group = 0, None
            for future in futures:
                out = future.result()
                if isinstance(out, _Refusal):
                    raise out.error()
                start = int(future.key.rsplit("-", 1)[1])
                future.release()
                with store_faults(path, kept):
                    if not created:
                        create_store(path, fp, setup_text, table, out, chunk_size, n_cases)
                        created = True
                    if group is None:
                        import zarr

                        group = zarr.open_group(str(path), mode="r+")
                    write_chunk(group, start, out)
                n = len(out["seed"])
                del out
                computed += n
                cases_done += n
                chunks_run += 1
                if pending:
                    futures.add(submit(pending.pop()))
                if progress is not None:
                    rate = computed / max(time.perf_counter() - t0, 1e-9)
                    progress(
                        BatchProgress(
                            cases_done,
                            n_cases,
                            n_chunks - len(starts) + chunks_run,
                            n_chunks,
                            rate,
                            (n_cases - cases_done) / rate,
                        )
                    )
        except KeyboardInterrupt as exc:
            # the cluster is torn down mid-task: its event loop logs the cancelled callbacks
            # as errors with tracebacks, noise beside the one message the interruption gives
            with quiet_shutdown():
                client.close()
                if cluster is not None:
                    cluster.close()
            raise BatchInterrupted(path, cases_done, n_cases) from exc
        finally:
            client.close()
            if cluster is not None:
                cluster.close()
    return BatchSummary(
        path, n_cases, chunks_run, n_chunks - len(starts), time.perf_counter() - t0, fp
    )


def open_results(store) -> xr.Dataset:
    """The store as a lazy dataset (dask arrays): ``metric_*`` over case, ``history_*`` over
    (case, time), ``param_*``, ``seed`` and ``done``; attrs ``fingerprint``, ``setup_text``."""
    return xr.open_zarr(store, consolidated=False)


__all__ = [
    "BatchInterrupted",
    "BatchProgress",
    "BatchSummary",
    "CONNECT_TIMEOUT",
    "FRICTION_PARAMETERS",
    "GAIN_PARAMETERS",
    "HubManeuverBuilder",
    "MANEUVER_PARAMETERS",
    "PLANT_PARAMETERS",
    "SENSOR_ACTUATOR_PARAMETERS",
    "case_seeds",
    "fingerprint",
    "maneuver_metrics",
    "open_results",
    "run_batch",
    "run_chunk",
]
