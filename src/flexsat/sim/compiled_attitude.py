"""The compiled path of :func:`flexsat.sim.engine.simulate` for three-axis spacecraft: the run
handed to the lane kernel of :mod:`flexsat.sim.kernels_attitude`.

Taken (:func:`unsupported` names the first reason it is not) for a
:class:`~flexsat.dynamics.rigid_spacecraft.RigidSpacecraft` (shared, or a batch with an
inertia per case: :func:`~flexsat.dynamics.dispersion.stack_plants`) or a
:class:`~flexsat.dynamics.flexible_spacecraft.FlexibleSpacecraft` without translation
(shared, or a :class:`~flexsat.dynamics.dispersion.DispersedPlant` of them: inertia,
frequencies, damping, coupling per case), under a law with a linear form of its own or one of
the attitude laws of :mod:`flexsat.control.attitude_laws` (MRP PD, quaternion PD, Gibbs
Lyapunov law), with linear measured channels, no derivative sensor, no input force and no
actuator rate limit or bias.

The arguments are those of the Python loop, built by the same functions as for the hub
kernels (:class:`~flexsat.sim.compiled_arguments.LoopArguments`: sensors, actuators, disturbances,
impulses, each case's noise stream from its own seed, the law's linear form); the
propagation is the plant's own integrator: the RKMK4 step of the rigid body (the same
formulas as :meth:`RigidSpacecraft.step`, in another order of the sums: the two paths agree to
round-off carried by the closed loop), Krogstad's exp_rk4 scheme of the flexible plant in the
modal coordinates of :mod:`flexsat.sim.spacecraft_modal` (equal to the Python loop's scheme
in x up to cond(T) · eps per step).

The kernel records the states (in its coordinates) of a block of cases; the recorded outputs
and energies are computed from them afterwards, block by block, as
:class:`~flexsat.sim.recording.Recorder` does, for the flexible plant straight from the modal
coordinates z (the rows C T, the seven rows of β and ω, the energy's form in z: no change
back x = T z unless the states are asked for). A case that diverges ends the run with the
Python loop's :class:`~flexsat.sim.engine.SimulationDiverged` (the batch rerun up to the first
sample where any case stops: the same cases, time and growth); a case that meets the Gibbs
law's singularity ends it with None: the engine then runs the Python loop, whose law refuses
the attitude by name.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, NamedTuple, cast

import numpy as np
import xarray as xr

from flexsat.analysis.settling import settled_at
from flexsat.control.attitude_laws import GibbsLyapunovLaw, MRPLaw, QuaternionPD
from flexsat.dynamics.attitude import SINGULAR_TOL
from flexsat.dynamics.dispersion import DispersedPlant
from flexsat.dynamics.flexible_spacecraft import FlexibleSpacecraft
from flexsat.dynamics.rigid_spacecraft import RigidSpacecraft, attitude_output
from flexsat.input_checks import FieldError
from flexsat.sim.compiled import block_size, own_linear_form
from flexsat.sim.compiled_arguments import CompiledRun, LoopArguments, channel_width
from flexsat.sim.kernels_attitude import (
    ATTITUDE_LAWS,
    LANES,
    AttitudeLoop,
    AttitudeMetrics,
    AttitudeRecords,
    attitude_loop,
    attitude_loop_parallel,
)
from flexsat.sim.recording import Recorder, SimResult
from flexsat.sim.spacecraft_modal import HEAD, modal_propagators, spacecraft_modal_form

if TYPE_CHECKING:
    from flexsat.control.base import Controller
    from flexsat.control.linear_form import LinearLaw
    from flexsat.dynamics.plant import Plant
    from flexsat.sim.channels import ChannelActuator, ChannelDisturbance, ChannelSensor
    from flexsat.sim.config import SimConfig

__all__ = ["attitude_law_of", "run", "run_metrics", "spacecraft_kind", "unsupported"]

#: groups of lanes from which a block runs on every core
PARALLEL_GROUPS = 2
#: groups of lanes per block at least (their records held at once: 32 cases of 97 states
#: over 1,201 samples are 30 MB)
MIN_GROUPS = 4
_LAWS = (MRPLaw, QuaternionPD, GibbsLyapunovLaw)


def spacecraft_kind(plant: Plant) -> str | None:
    """``"rigid"``, ``"flexible"`` or None (not a plant of this path)."""
    parts = plant.plants if isinstance(plant, DispersedPlant) else (plant,)
    if all(type(p) is RigidSpacecraft for p in parts):
        return "rigid"
    if all(type(p) is FlexibleSpacecraft and not p.translation for p in parts):
        return "flexible"
    return None


def attitude_law_of(controller: Controller) -> bool:
    """Whether ``controller`` is an attitude law the kernel runs itself (not a subclass:
    one that changes the commands is not this law)."""
    return type(controller) in _LAWS


def unsupported(
    plant: Plant,
    controller: Controller,
    sensors: Mapping[str, ChannelSensor],
    actuators: Mapping[str, ChannelActuator],
    disturbances: Mapping[str, ChannelDisturbance],
    measured: Sequence[str],
) -> str | None:
    """Why the run cannot take this path (module docstring), or None when it can."""
    if spacecraft_kind(plant) is None:
        return "not a rigid or flexible three-axis spacecraft without translation"
    if any(d.force is not None for d in disturbances.values()):
        return "an input force"
    for k in measured:
        if k in sensors and sensors[k].derivative_of is not None:
            return f"{k}: a derivative sensor"
        if plant.output_matrices(k) is None:
            return f"{k}: measured output is nonlinear"
    for k in controller.writes:
        a = actuators.get(k)
        if a is not None and (np.any(np.isfinite(a.rate_limit)) or np.any(a.bias)):
            return f"{k}: actuator rate limit or bias"
    if attitude_law_of(controller):
        return None
    if not own_linear_form(type(controller)):
        return f"{type(controller).__name__} has no linear form of its own commands"
    return None


def _c(a) -> np.ndarray:
    return np.require(a, np.float64, ["C", "W"])


def _law_arrays(controller, nc: int):
    """(law code, gains (Cg, 7), target (Cg, 4), w_ref (Cg, 3)) of an attitude law, Cg = 1 or
    the law's cases; zeros (code 0) for a linear law."""
    if not attitude_law_of(controller):
        return 0, np.zeros((1, 7)), np.zeros((1, 4)), np.zeros((1, 3))
    vectors = {"P", "k", "Kp", "Kd", "beta_target", "w_ref"}  # last axis: body or quaternion
    fields = ("K", "P", "A", "k", "Kp", "Kd", "beta_target", "w_ref")
    shape = np.broadcast_shapes(
        *(
            np.shape(getattr(controller, f))[: -1 if f in vectors else None]
            for f in fields
            if hasattr(controller, f)
        )
    )
    cg = int(np.prod(shape))

    def scalar(v):
        return np.broadcast_to(np.asarray(v, float), shape).reshape(cg)

    def vector(v, width):
        v = np.asarray(v, float)
        return np.broadcast_to(v, shape + (width,)).reshape(cg, width)

    gains = np.zeros((cg, 7))
    w_ref = np.zeros((cg, 3))
    if isinstance(controller, MRPLaw):
        gains[:, 0], gains[:, 1:4] = scalar(controller.K), vector(controller.P, 3)
    elif isinstance(controller, QuaternionPD):
        gains[:, 1:4], gains[:, 4:7] = vector(controller.Kp, 3), vector(controller.Kd, 3)
        w_ref = vector(controller.w_ref, 3)
    else:
        gains[:, 0], gains[:, 1:4] = scalar(controller.A), vector(controller.k, 3)
    target = vector(controller.beta_target, 4)
    return ATTITUDE_LAWS[type(controller).__name__], _c(gains), _c(target), _c(w_ref)


class _Plant:
    """The propagation arrays of the batch: per case (C) or shared (1), the change of
    coordinates x = T z of the flexible plant (None: z = x) and its energy's elastic form
    (``elastic_energy`` of :class:`~flexsat.sim.spacecraft_modal.SpacecraftModes`: vectors
    when every case's is diagonal, else matrices)."""

    def __init__(self, plant: Plant, kind: str, dt: float, substeps: int) -> None:
        parts = plant.plants if isinstance(plant, DispersedPlant) else (plant,)
        m = plant.n_inputs
        if kind == "rigid":
            J = _c(cast(RigidSpacecraft, plant).inertia).reshape(-1, 3, 3)
            self.J, self.Jinv = J, _c(np.linalg.inv(J))
            self.T = self.Ti = self.elastic_energy = None
            self.E2 = self.E = np.zeros((1, 0, 2))
            self.Q1u = self.P1u = np.zeros((1, 0, m))
            self.F, self.R = np.zeros((1, 5, 0, 7)), np.zeros((1, 6, 0))
            return
        arrays = [self._modal(cast(FlexibleSpacecraft, p), dt, substeps) for p in parts]
        # one stack per quantity, over the cases: T, T⁻¹, J, E2, E, Q1u, P1u, F, Qe
        columns = [list(column) for column in zip(*arrays)]
        diagonal = all(q.ndim == 1 for q in columns[8])
        columns[8] = [q if diagonal or q.ndim == 2 else np.diag(q) for q in columns[8]]
        T, Ti, J, E2, E, Q1u, P1u, F, Qe = (np.stack(column) for column in columns)
        self.T, self.Ti, self.elastic_energy = T, Ti, Qe
        self.J = _c(J)
        self.Jinv = _c(np.linalg.inv(self.J))
        self.E2, self.E, self.Q1u, self.P1u, self.F = (_c(a) for a in (E2, E, Q1u, P1u, F))
        self.R = _c(T[:, 1:7])

    @staticmethod
    def _modal(p: FlexibleSpacecraft, dt: float, substeps: int):
        modes = spacecraft_modal_form(p.inertia, p.coupling, p.stiffness, p.damping)
        A, B = p.linear_part()
        Ti = modes.T_inv
        E2, E, Q1u, P1u, F = modal_propagators(
            modes.blocks, Ti @ B, Ti @ p.force_matrix, dt, substeps
        )
        if np.any(F[:, HEAD:, :4]):  # the kernel skips these products
            raise FieldError("coupling", "the attitude force columns reach the elastic modes")
        return modes.T, Ti, p.inertia, E2, E, Q1u, P1u, F, modes.elastic_energy


def _to_z(M: np.ndarray, T: np.ndarray | None) -> np.ndarray:
    """Rows over x (lead, r, n) as rows over z: M T per case."""
    return M if T is None else _c(np.matmul(M, T))


def _case_plant(plant, c: int):
    """The plant of case c (the energy's parameters)."""
    if isinstance(plant, DispersedPlant):
        return plant.plants[c]
    if isinstance(plant, RigidSpacecraft) and plant.n_cases > 1:
        return RigidSpacecraft(plant.inertia[c])
    return plant


class _Setup(NamedTuple):
    """What both paths of :func:`run` and :func:`run_metrics` build before the kernel."""

    job: CompiledRun
    kind: str
    pl: _Plant
    a: LoopArguments
    code: int
    gains: np.ndarray
    target: np.ndarray
    w_ref: np.ndarray


def _setup(job: CompiledRun, law: LinearLaw | None) -> _Setup | None:
    """The propagation arrays and the loop's arguments in kernel coordinates, or None where
    the kernel does not take the run after all (module docstring)."""
    plant, controller, nc, x0 = job.plant, job.controller, job.nc, job.x0
    kind = spacecraft_kind(plant)
    if kind is None:
        raise FieldError("plant", f"{type(plant).__name__} is not a three-axis spacecraft")
    try:
        pl = _Plant(plant, kind, job.config.dt, job.substeps)
    except (FieldError, np.linalg.LinAlgError):  # an overdamped mode: the dense path
        return None
    a = LoopArguments(job, law, modal=False, propagate=False)
    n = a.n
    if pl.Ti is not None:  # the loop's state, measurements and impulses in z
        Ti = np.broadcast_to(pl.Ti, (nc, n, n))
        a.x0 = _c(np.einsum("cij,cj->ci", Ti, x0))
        a.Cm = _to_z(a.Cm, pl.T)
        if a.imp_dx.shape[0]:
            dx = np.broadcast_to(a.imp_dx, (a.imp_dx.shape[0], nc, n))
            a.imp_dx = _c(np.einsum("cij,kcj->kci", Ti, dx))
    code, gains, target, w_ref = _law_arrays(controller, nc)
    if gains.shape[0] not in (1, nc):  # the Python loop names the mismatch
        return None
    return _Setup(job, kind, pl, a, code, gains, target, w_ref)


def _cases(arr: np.ndarray, c0: int, c1: int) -> np.ndarray:
    """A shared array (leading axis 1) as is, a per-case one's cases [c0, c1)."""
    return arr if arr.shape[0] == 1 else _c(arr[c0:c1])


def _block_loop(s: _Setup, c0: int, c1: int, samples: int) -> AttitudeLoop:
    """The kernel's arguments for cases [c0, c1) over the first ``samples`` samples."""
    a, pl, job = s.a, s.pl, s.job
    hub = a.inputs(c0, c1, job.seeds, samples)
    return AttitudeLoop(
        hub.x0,
        0 if s.kind == "rigid" else 1,
        a.substeps,
        job.config.dt / a.substeps,
        _cases(pl.J, c0, c1),
        _cases(pl.Jinv, c0, c1),
        _cases(pl.E2, c0, c1),
        _cases(pl.E, c0, c1),
        _cases(pl.Q1u, c0, c1),
        _cases(pl.P1u, c0, c1),
        _cases(pl.F, c0, c1),
        _cases(pl.R, c0, c1),
        hub.imp_k,
        hub.imp_dx,
        hub.Cm,
        hub.Dm,
        hub.sensor,
        hub.sensor_slot,
        s.code,
        hub.Ak,
        hub.Bk,
        hub.Ck,
        hub.Dk,
        hub.y_ref[:samples],
        hub.u_ff[:samples],
        hub.K0,
        _cases(s.gains, c0, c1),
        _cases(s.target, c0, c1),
        _cases(s.w_ref, c0, c1),
        hub.act,
        hub.dist_std,
        hub.dist_slot,
        hub.noise,
        hub.bound,
        SINGULAR_TOL,
    )


def _kernel(c0: int, c1: int):
    """The parallel kernel for a block of at least :data:`PARALLEL_GROUPS` groups."""
    return attitude_loop_parallel if c1 - c0 >= PARALLEL_GROUPS * LANES else attitude_loop


def _no_metrics() -> AttitudeMetrics:
    """The records path's (empty) metrics argument: ``n_t`` 0."""
    e2, e3 = np.zeros((0, 0)), np.zeros((1, 0, 0))
    return AttitudeMetrics(
        0,
        e3,
        np.zeros(0, np.int64),
        e3,
        np.zeros((0, 3), np.int64),
        np.zeros((0, 4)),
        1.0,
        0.0,
        e2,
        e2,
        e2,
        np.zeros((0, 4)),
        np.zeros(0, np.int64),
    )


def run(job: CompiledRun, record_states: bool, law: LinearLaw | None) -> SimResult | None:
    """The run of :func:`~flexsat.sim.engine.simulate` on the three-axis kernel (module
    docstring), or None when the kernel does not take it after all (an overdamped elastic
    mode, a singular attitude law): the engine then runs the Python loop.

    Raises
    ------
    SimulationDiverged
        As the Python loop does, for a case beyond the divergence bound.
    """
    plant: Plant = job.plant
    controller: Controller = job.controller
    config: SimConfig = job.config
    nc, theta0 = job.nc, job.theta0
    disturbances, substeps, kept = job.disturbances, job.substeps, job.kept
    s = _setup(job, law)
    if s is None:
        return None
    pl, a, dt, n_t = s.pl, s.a, config.dt, config.n_steps + 1
    n, m = a.n, a.m
    batched = plant.n_cases != 1
    rec = Recorder(
        plant,
        n_t,
        nc,
        tuple(kept),
        {},
        record_states,
        batched,
        [k for k, d in disturbances.items() if np.any(d.random)],
        allocate=False,
    )
    Y, Ucmd, U, Dist = (np.empty((nc, n_t, w)) for w in (a.p_rec, m, m, m))
    stop = np.full(nc, -1, dtype=np.int64)
    X_all = np.empty((nc, n_t, n)) if record_states else None
    outs = {
        k: np.empty((nc, n_t) + ((w,) if w > 1 else ()))
        for k, w in ((k, channel_width(plant, k)) for k in plant.recorded)
    }
    energy = np.empty((nc, n_t)) if rec.has_energy else None
    size = block_size(nc, n_t, n + (a.width if a.noisy else 0) + a.law_values)
    # at least MIN_GROUPS groups of lanes per block, so that a block runs on every core
    size = min(nc, -(-max(size, MIN_GROUPS * LANES) // LANES) * LANES)
    X = np.empty((min(size, nc), n_t, n))

    def run_block(c0, c1, samples, Xb, Yb, Ucmdb, Ub, Distb, stopb):
        """The kernel on cases [c0, c1) over the first ``samples`` samples."""
        loop = _block_loop(s, c0, c1, samples)
        records = AttitudeRecords(Xb, Yb, Ucmdb, Ub, Distb, stopb)
        _kernel(c0, c1)(loop, records, _no_metrics())

    for c0 in range(0, nc, size):
        c1 = min(nc, c0 + size)
        Xb = X[: c1 - c0]
        sl = slice(c0, c1)
        run_block(c0, c1, n_t, Xb, Y[sl], Ucmd[sl], U[sl], Dist[sl], stop[sl])
        if (stop[sl] >= 0).any():
            k = int(stop[sl][stop[sl] >= 0].min())
            _raise_divergence(run_block, pl, nc, size, k, a.p_rec, m, n, config)
            return None  # not a divergence: the Gibbs law's singularity (the Python loop's error)
        if X_all is not None:  # in the plant's coordinates, x = T z
            T = None if pl.T is None else np.swapaxes(_of_block(pl.T, c0, c1), -1, -2)
            X_all[c0:c1] = Xb if T is None else np.matmul(Xb, T)
        _outputs(rec, plant, pl, c0, Xb, U[c0:c1], Dist[c0:c1], outs, energy)
    Dist += U  # the plant's input u + d, as the Python loop records it
    rec.commands, rec.applied, rec.disturbed = (np.swapaxes(v, 0, 1) for v in (Ucmd, U, Dist))
    for name in kept:
        sl = a.offsets[name]
        lo, hi = sl.start - a.rec_start, sl.stop - a.rec_start
        rec.measured[name] = np.swapaxes(Y[..., lo] if hi - lo == 1 else Y[..., lo:hi], 0, 1)
    rec.outputs = {k: np.swapaxes(v, 0, 1) for k, v in outs.items()}
    rec.energy = None if energy is None else energy.T
    rec.vibration = None
    rec.states = None if X_all is None else np.swapaxes(X_all, 0, 1)
    t = dt * np.arange(n_t, dtype=np.float64)
    result = rec.dataset(t, controller, theta0, config, substeps, engine="compiled")
    result.dataset.attrs["propagation"] = "modal" if pl.T is not None else "rkmk4"
    return result


def _raise_divergence(run_block, pl, nc, size, k, p_rec, m, n, config) -> None:
    """Raise the Python loop's :class:`~flexsat.sim.engine.SimulationDiverged` for a batch
    with a case stopped at sample k: every case rerun up to k (the same numbers), at the first
    sample where any stops, the cases beyond the bound there and the growth over the last
    period (:func:`~flexsat.sim.engine.divergence_error`); returns when no case is beyond the
    bound there (a stop of the law itself)."""
    from flexsat.sim.engine import DIVERGENCE_BOUND, divergence_error

    stop = np.full(nc, -1, dtype=np.int64)
    x = np.empty((nc, 2, n))
    u = np.empty((nc, m))
    for first in (True, False):  # the first stop of any case, then the states around it
        for c0 in range(0, nc, size):
            c1 = min(nc, c0 + size)
            Xb = np.empty((c1 - c0, k + 1, n))
            Yb, Ucmd, Ub, Db = (np.empty((c1 - c0, k + 1, w)) for w in (p_rec, m, m, m))
            run_block(c0, c1, k + 1, Xb, Yb, Ucmd, Ub, Db, stop[c0:c1])
            x[c0:c1], u[c0:c1] = Xb[:, [max(k - 1, 0), k]], Ucmd[:, k]
        if first:
            k = int(stop[stop >= 0].min())
    if pl.T is not None:
        x = np.matmul(x, np.swapaxes(pl.T, -1, -2))
    xk, uk = x[:, 1], u
    bad = ~(np.abs(xk) <= DIVERGENCE_BOUND).all(axis=1) | ~(np.abs(uk) <= DIVERGENCE_BOUND).all(
        axis=1
    )
    if not bad.any():
        return
    prev = float(np.abs(x[:, 0]).max()) if k > 0 else 0.0
    raise divergence_error(xk, uk, config.dt * k, k, prev, config)


def _of_block(a: np.ndarray, c0: int, c1: int) -> np.ndarray:
    """A shared (leading axis 1) array as is, a per-case one's cases [c0, c1)."""
    return a if a.shape[0] == 1 else a[c0:c1]


def _rows(V: np.ndarray, M: np.ndarray) -> np.ndarray:
    """V (cb, n_t, i) times M (i, j), or (1, i, j) or (cb, i, j) case by case (one matrix
    product per case whatever the block: the same sums for a case alone and in a batch)."""
    return V @ M if M.ndim == 2 else np.matmul(V, M)


def _outputs(rec, plant, pl: _Plant, c0: int, Z, U, Dist, outs, energy) -> None:
    """Recorded outputs and energies of the cases from c0 on, from their states Z (cb, n_t,
    n) in kernel coordinates: y = C x + D w_{k−1} (:meth:`Recorder.flush`) with x = T z, C T
    the rows over z; the nonlinear ones are attitude channels of β and ω
    (:func:`~flexsat.dynamics.rigid_spacecraft.attitude_output`), the seven rows T[:7] z; the
    flexible plant's energy ½ ω_rᵀ J ω_r + ½ z_eᵀ Q_e z_e in z (:class:`~flexsat.sim.
    spacecraft_modal.SpacecraftModes`; equal to ½[ω; η̇]ᵀ𝓜[ω; η̇] + ½ηᵀKη of x = T z up to
    cond(T) · eps relative), O(n) per sample for a diagonal Q_e where the change back x = T z
    is O(n²)."""
    cb = Z.shape[0]
    c1 = c0 + cb
    Wp = np.empty_like(U)  # the input held before each sample
    Wp[:, 0] = 0.0
    np.add(U[:, :-1], Dist[:, :-1], out=Wp[:, 1:])
    T = None if pl.T is None else _of_block(pl.T, c0, c1)
    if rec.linear:
        CT = rec.CT if rec.CT.ndim == 2 else rec.CT[c0:c1]
        Yo = _rows(Z, CT if T is None else np.swapaxes(T, -1, -2) @ CT)
        Yo += _rows(Wp, rec.DT if rec.DT.ndim == 2 else rec.DT[c0:c1])
        col = 0
        for k in rec.linear:
            w = channel_width(plant, k)
            outs[k][c0:c1] = Yo[..., col] if w == 1 else Yo[..., col : col + w]
            col += w
    if rec.nonlinear:
        head = Z[..., :HEAD] if T is None else _rows(Z, np.swapaxes(T[:, :HEAD], -1, -2))
        for k in rec.nonlinear:
            outs[k][c0:c1] = attitude_output(k, head[..., :4], head[..., 4:7])
    if energy is None:
        return
    if T is None:  # the rigid body: its own energy of the states
        if plant.n_cases == 1:
            energy[c0:c1] = plant.energy(Z)
            return
        for i in range(cb):
            energy[c0 + i] = _case_plant(plant, c0 + i).energy(Z[i])
        return
    wr, ze = Z[..., 2:HEAD:2], Z[..., HEAD:]  # ω_r, the elastic coordinates
    kinetic = np.sum(wr * _rows(wr, _of_block(pl.J, c0, c1)), -1)
    assert pl.elastic_energy is not None  # a flexible plant (T is set with it)
    Qe = _of_block(pl.elastic_energy, c0, c1)
    if Qe.ndim == 2:  # diagonal: d (1 or cb, 2 n_e)
        elastic = np.sum(ze * ze * Qe[:, None], -1)
    else:
        elastic = np.sum(ze * _rows(ze, Qe), -1)
    energy[c0:c1] = 0.5 * (kinetic + elastic)


#: the channel kinds of :class:`~flexsat.sim.kernels_attitude.AttitudeMetrics` (``chan``) of
#: the nonlinear attitude channels
_ATTITUDE_CHANNELS = {"rate": 1, "euler123": 2, "mrp": 3}


def run_metrics(job: CompiledRun, law: LinearLaw | None) -> SimResult | None:
    """The channel metrics of :func:`~flexsat.sim.engine.simulate` (``metrics_only``) without
    any time history, or None where this path does not apply (the caller then runs
    :func:`run`, which also raises for a case that diverges).

    The metrics of a three-axis run (:func:`flexsat.sim.metrics.channel_metrics`) are, per
    recorded output channel, its largest norm and a scalar channel's last value; per input
    channel, the largest norm and the root mean square of the norm; and against the law's
    fixed target attitude, the final pointing error and the settling time. Each is a
    running maximum, a running sum, a value at the last sample or the last sample outside
    the band, so the kernel accumulates them in the loop
    (:class:`~flexsat.sim.kernels_attitude.AttitudeMetrics`) in place of the records: no
    history is held and no state is changed back x = T z. The loop is that of :func:`run`
    (the same operations, the same states bit for bit); the outputs are the rows C T z of
    the modal coordinates summed in the loop where :func:`run` sums them after it by a
    matrix product, and the sum of the squared input norms is a running sum where NumPy's
    mean sums pairwise, so the metrics agree with those of :func:`run` to round-off (the
    peaks of the rigid body's channels, its attitude and its pointing metrics bit for bit:
    the same formulas on the same states). A case's metrics do not depend on its batch.

    Applies where :func:`run` does, for a law whose target attitude, if any, is fixed
    (``beta_target``; a turning reference, ``target_at``, takes :func:`run`).
    """
    plant, controller, config, nc = job.plant, job.controller, job.config, job.nc
    if callable(getattr(controller, "target_at", None)):
        return None
    s = _setup(job, law)
    if s is None:
        return None
    pl, a = s.pl, s.a
    n, m, n_t = a.n, a.m, config.n_steps + 1
    rec = Recorder(plant, n_t, nc, (), {}, False, plant.n_cases != 1, allocate=False)
    head = 0 if pl.T is None else HEAD  # the flexible plant's rows of β and ω first
    chan: list[tuple[int, int, int]] = []
    names: list[tuple[str, bool]] = []  # (metric stem, scalar) per channel
    col = {}
    offset = head
    for k in rec.linear:
        col[k] = offset
        offset += channel_width(plant, k)
    recorded = set(plant.recorded)
    for c in plant.outputs:
        k = c.name
        if k not in recorded or k == "attitude":
            continue
        w = channel_width(plant, k)
        if k in col:
            chan.append((0, col[k], w))
        elif k in _ATTITUDE_CHANNELS:
            chan.append((_ATTITUDE_CHANNELS[k], 0, 3))
        else:
            return None
        names.append((k, w == 1))
    outputs = len(chan)
    for c in plant.inputs:
        sl = plant.input_slices[c.name]
        chan.append((4, sl.start, sl.stop - sl.start))
        names.append((c.name, False))
    # the output rows over the kernel coordinates and their feedthrough
    lead = max(
        1 if pl.T is None else pl.T.shape[0],
        rec.CT.shape[0] if rec.linear and rec.CT.ndim == 3 else 1,
    )
    rows = np.zeros((lead, offset, n))
    feed = np.zeros((lead, offset, m))
    if pl.T is not None:
        rows[:, :head] = pl.T[:, :head]
    if rec.linear:
        CT = rec.CT if rec.CT.ndim == 3 else rec.CT[None]
        DT = rec.DT if rec.DT.ndim == 3 else rec.DT[None]
        rows[:, head:] = (
            np.swapaxes(CT, -1, -2)
            if pl.T is None
            else np.swapaxes(np.swapaxes(pl.T, -1, -2) @ CT, -1, -2)
        )
        feed[:, head:] = np.swapaxes(DT, -1, -2)
    at, extra = _row_sources(a.Cm, rows)
    target_of = getattr(controller, "beta_target", None)
    pointing = target_of is not None and "attitude" in recorded
    target = _c(np.asarray(target_of, float).reshape(-1, 4)) if pointing else np.zeros((0, 4))
    if target.shape[0] not in (0, 1, nc):
        return None
    band = float(config.settling_band)
    q = len(chan)
    peak, final, sumsq = (np.zeros((nc, q)) for _ in range(3))
    beta_end = np.zeros((nc, 4))
    after = np.zeros(nc, np.int64)
    stop = np.full(nc, -1, dtype=np.int64)
    chan_a = np.array(chan, np.int64).reshape(-1, 3)
    size = block_size(nc, n_t, (a.width if a.noisy else 0) + a.law_values + 1)
    size = min(nc, -(-max(size, MIN_GROUPS * LANES) // LANES) * LANES)
    e3 = np.zeros((0, 0, 0))
    for c0 in range(0, nc, size):
        c1 = min(nc, c0 + size)
        red = AttitudeMetrics(
            n_t,
            _c(_cases(rows[:, extra], c0, c1)),
            at,
            _c(_cases(feed, c0, c1)) if feed.any() else np.zeros((1, offset, 0)),
            chan_a,
            _cases(target, c0, c1) if target.shape[0] else target,
            float(np.cos(band / 2)),
            band,
            peak[c0:c1],
            final[c0:c1],
            sumsq[c0:c1],
            beta_end[c0:c1],
            after[c0:c1],
        )
        records = AttitudeRecords(e3, e3, e3, e3, e3, stop[c0:c1])
        _kernel(c0, c1)(_block_loop(s, c0, c1, n_t), records, red)
        if (stop[c0:c1] >= 0).any():
            return None  # run() raises the divergence (or the Python loop the singular law)
    t = config.dt * np.arange(n_t, dtype=np.float64)
    units = {c.name: c.unit for c in plant.outputs + plant.inputs}
    metrics: dict[str, np.ndarray] = {}
    metric_units: dict[str, str] = {}
    for i, (k, scalar) in enumerate(names):
        metrics[f"peak_{k}"] = peak[:, i].copy()
        metric_units[f"peak_{k}"] = units.get(k, "")
        if i < outputs and scalar:
            metrics[f"final_{k}"] = final[:, i].copy()
            metric_units[f"final_{k}"] = units.get(k, "")
        elif i >= outputs:
            metrics[f"rms_{k}"] = np.sqrt(sumsq[:, i] / n_t)
            metric_units[f"rms_{k}"] = units.get(k, "")
    if pointing:
        e0 = np.abs(np.sum(beta_end * target, axis=-1)).clip(max=1.0)
        metrics["final_pointing_error_deg"] = np.degrees(2.0 * np.arccos(e0))
        metric_units["final_pointing_error_deg"] = "deg"
        metrics["pointing_settling_time_s"] = settled_at(t, after)
        metric_units["pointing_settling_time_s"] = "s"
    data = {k: (("case",), v, {"units": metric_units[k]}) for k, v in metrics.items()}
    ds = xr.Dataset(data, coords={"time": ("time", t, {"units": "s"}), "case": np.arange(nc)})
    ds.attrs.update(
        control_rate_Hz=config.control_rate,
        settling_band_rad=config.settling_band,
        substeps=job.substeps,
        engine="compiled",
        propagation="modal" if pl.T is not None else "rkmk4",
        histories="none",
    )
    return SimResult(ds, metrics)


def _row_sources(Cm: np.ndarray, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Where the kernel finds each output row (lead, r, n) among its row sums: ``at[i]`` the
    measurement row of Cm (lead', p, n) that is the same row in every case (its sum serves
    both), else p + its place among the ``extra`` rows summed after them."""
    p = Cm.shape[1]
    lead = max(Cm.shape[0], rows.shape[0])
    M = np.broadcast_to(Cm, (lead,) + Cm.shape[1:])
    R = np.broadcast_to(rows, (lead,) + rows.shape[1:])
    at = np.empty(rows.shape[1], np.int64)
    extra: list[int] = []
    for i in range(rows.shape[1]):
        same = [j for j in range(p) if np.array_equal(M[:, j], R[:, i])]
        if same:
            at[i] = same[0]
        else:
            at[i] = p + len(extra)
            extra.append(i)
    return at, np.array(extra, np.int64)
