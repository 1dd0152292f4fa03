"""The arguments of the compiled loops (:mod:`flexsat.sim.kernels`,
:mod:`flexsat.sim.kernels_attitude`) built from a run of :func:`flexsat.sim.engine.simulate`:
:class:`LoopArguments` (sensors, actuators, disturbances, impulses, each case's noise stream
from its own seed, the law's linear form, the propagators) and :func:`modal_form`, the rule for
propagating a plant in its modal coordinates.

They are the Python loop's arguments, built by the same functions so that they are the same
numbers (:mod:`flexsat.sim.compiled`, module docstring); split from :mod:`flexsat.sim.compiled`,
which runs the kernels on them.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from flexsat.sim.channels import input_impulses, noise_column, noise_columns
from flexsat.sim.instruments import stacked_output_matrices
from flexsat.sim.integrators import ExponentialStepper, ModalPropagator, modal_coordinates
from flexsat.sim.kernels import Loop, Records, closed_loop, closed_loop_parallel
from flexsat.sim.sensors import least_squares_derivative_weights

__all__ = [
    "MODAL_STATES",
    "MODAL_STEPS",
    "MODAL_STEPS_LARGE",
    "PARALLEL_CASES",
    "LoopArguments",
    "channel_width",
    "modal_form",
]

#: integrator steps of a run (cases × samples × substeps) from which a hybrid plant is
#: propagated in its modal coordinates: the eigen-decomposition (a few ms at 22 states, ~45 ms
#: at 202) and the change back to physical states after the loop (one n × n product per
#: sample) then cost less than the O(n²) dense substeps they replace. Measured crossover
#: (docs/performance.md): 22 states between 4,500 steps (modal 9.0 ms, dense 7.7) and 45,000
#: (17.6 against 21.3); 202 states below 4,500 (58.6 against 110) and above 1,125 (one linear
#: maneuver: the set-up dominates)
MODAL_STEPS = 20_000
#: above this many states the crossover is MODAL_STEPS_LARGE steps
MODAL_STATES, MODAL_STEPS_LARGE = 60, 2_000
#: cases from which a block runs on every core (below, the threads cost more than they save)
PARALLEL_CASES = 8


@dataclass(frozen=True)
class CompiledRun:
    """One run as :func:`~flexsat.sim.engine.simulate` hands it to a compiled path
    (:func:`flexsat.sim.compiled.run`, :func:`~flexsat.sim.compiled.run_reduced`,
    :func:`flexsat.sim.compiled_attitude.run`), SI throughout: the plant and law, the
    configuration, ``nc`` cases with their noise ``seeds``, the start state ``x0`` (and the
    hub angle ``theta0`` of a single-axis maneuver), the per-channel instruments, the integrator
    ``substeps``, the ``measured`` channels the law reads and those ``kept`` in the record."""

    plant: Any
    controller: Any
    config: Any
    nc: int
    seeds: np.ndarray
    x0: np.ndarray
    theta0: np.ndarray | None
    sensors: Mapping[str, Any]
    actuators: Mapping[str, Any]
    disturbances: Mapping[str, Any]
    substeps: int
    measured: Sequence[str]
    kept: Sequence[str]


def channel_width(plant, name: str) -> int:
    return next(c.size for c in plant.outputs if c.name == name)


def _c(a) -> np.ndarray:
    """A C-contiguous, writable float64 array: one compiled signature for every call."""
    return np.require(a, np.float64, ["C", "W"])


def _per_element(value, nc: int, width: int) -> np.ndarray:
    """A sensor or actuator field as (1 or n_cases, width): the Python loop's broadcasting
    of the value against the channel's (n_cases[, width]) history."""
    v = np.asarray(value, float)
    if v.ndim == 0:
        return np.full((1, width), float(v))
    shape = (nc,) if width == 1 else (nc, width)
    return np.broadcast_to(v, shape).reshape(nc, width)


def _fill(target: np.ndarray, index: tuple, rows: np.ndarray) -> np.ndarray:
    """``target`` (1 or C, ...) with ``rows`` (1 or C, width) written at ``index`` (the
    indices after the case axis), its case axis grown to C when the rows are per case."""
    if rows.shape[0] > target.shape[0]:
        target = np.repeat(target, rows.shape[0], axis=0)
    target[(slice(None),) + index] = rows
    return target


def _pad_law(law, p: int, reads: list[int], order: list[int], m: int):
    """The law's arrays with its columns placed on the measured elements ``reads`` (zero
    columns for the others) and its rows on the plant's inputs ``order``."""

    def cols(a):
        if a.shape[-1] == p and reads == list(range(p)):
            return a
        out = np.zeros(a.shape[:-1] + (p,))
        out[..., reads] = a
        return out

    def rows(a, axis):
        if len(order) == m and order == list(range(m)):
            return a
        out = np.zeros(a.shape[:axis] + (m,) + a.shape[axis + 1 :])
        idx = [slice(None)] * a.ndim
        idx[axis] = order
        out[tuple(idx)] = a
        return out

    if law is None:  # no linear form: empty arrays of the right ranks
        return (
            np.zeros((1, 1, 0, 0)),
            np.zeros((1, 1, 0, p)),
            np.zeros((1, 1, m, 0)),
            np.zeros((1, 1, m, p)),
            np.zeros((1, 1, p)),
            np.zeros((1, 1, m)),
            np.zeros((0, 0, p)),
        )
    K0 = np.zeros((0, law.Ak.shape[-1], p)) if law.K0 is None else cols(law.K0)
    return (
        law.Ak,
        cols(law.Bk),
        rows(law.Ck, 2),
        rows(cols(law.Dk), 2),
        cols(law.y_ref),
        rows(law.u_ff, 2),
        K0,
    )


def modal_form(plant, steps: int):
    """(T, T⁻¹, ω, ζ) with x = T z, z in 2×2-block modal coordinates, where propagating z
    pays (O(n) per substep, :class:`~flexsat.sim.integrators.ModalPropagator`), else None.

    The rule: a plant with its own ``modal_form()`` (a
    :class:`~flexsat.sim.hardware.HardwarePlant`) under the step rule below, a shared (not
    dispersed) plant whose coordinates are already decoupled modes
    (``modal_blocks``: T is a permutation, no set-up), or a hybrid plant (``mass_matrix``,
    ``stiffness_matrix``, ``damping_matrix``) over at least :data:`MODAL_STEPS` integrator
    steps (cases × samples × substeps; :data:`MODAL_STEPS_LARGE` above
    :data:`MODAL_STATES` states), through its :func:`~flexsat.sim.integrators.
    modal_coordinates` (with non-proportional damping exact to cond(T) · eps: ~1e-10
    relative at 202 states, where the dense step is exact to round-off). A dispersed hybrid
    plant (:class:`~flexsat.dynamics.dispersed_hub.DispersedHubAppendage`: its matrices with a
    leading case axis) under the same rule gets each case's own (T, T⁻¹, ω, ζ), stacked on a
    leading case axis; each case's are computed alone, so they do not depend on the batch.
    """
    hybrid = all(hasattr(plant, k) for k in ("mass_matrix", "stiffness_matrix", "damping_matrix"))
    few = steps < (MODAL_STEPS_LARGE if plant.nx > MODAL_STATES else MODAL_STEPS)
    own = getattr(plant, "modal_form", None)
    if callable(own):  # a plant that forms its own (a plant with hardware states appended)
        return None if few else own()
    if plant.n_cases != 1:  # a dispersed hybrid plant: each case's own, stacked
        if few or not hybrid:
            return None
        try:
            return modal_coordinates(
                plant.mass_matrix, plant.stiffness_matrix, plant.damping_matrix
            )
        except (ValueError, np.linalg.LinAlgError):
            return None
    blocks = getattr(plant, "modal_blocks", None)
    if blocks is not None:
        k = blocks.frequencies.size
        T = np.zeros((2 * k, 2 * k))
        T[np.arange(k), 2 * np.arange(k)] = 1.0  # x = [q; q'] <- z = (q_0, q_0', q_1, ...)
        T[k + np.arange(k), 2 * np.arange(k) + 1] = 1.0
        return T, T.T.copy(), blocks.frequencies, blocks.damping
    if few or not hybrid:
        return None
    try:
        return modal_coordinates(plant.mass_matrix, plant.stiffness_matrix, plant.damping_matrix)
    except (ValueError, np.linalg.LinAlgError):  # overdamped or damped rigid modes: dense
        return None


class LoopArguments:
    """The kernel's arguments for a whole batch (each sliced per block by :meth:`block`).

    ``propagate`` False: no propagator (the three-axis loop of
    :mod:`flexsat.sim.compiled_attitude` builds its own; ``E`` and ``P1u`` are then empty);
    ``law`` None: a law without a linear form (an attitude law of that loop), whose arrays are
    then empty (no law state, no column)."""

    def __init__(
        self,
        job: CompiledRun,
        law,
        modal: bool = True,
        always_modal: bool = False,
        rows=None,
        propagate: bool = True,
    ):
        plant, controller, config, nc, x0 = job.plant, job.controller, job.config, job.nc, job.x0
        sensors, actuators, disturbances = job.sensors, job.actuators, job.disturbances
        substeps, measured, kept = job.substeps, job.measured, job.kept
        dt, n_t = config.dt, config.n_steps + 1
        self.nc, self.n_t = nc, n_t
        A, B = plant.linear_part()
        m, slices = plant.n_inputs, plant.input_slices
        forced = {k: d for k, d in disturbances.items() if d.force is not None}
        self.forced = forced
        Bf = None
        if forced:
            ((k, d),) = forced.items()
            j = slices[k].start
            Bf = B[..., :, j : j + 1]
        n = plant.nx
        modal = (
            modal_form(plant, np.inf if always_modal else nc * (n_t - 1) * substeps)
            if modal
            else None
        )
        self.T = None if modal is None else modal[0]
        Tinv = None if modal is None else modal[1]
        if not propagate:
            self.E, self.P1u = np.zeros((1, 0, 2)), np.zeros((1, 0, m))
        elif modal is not None and modal[0].ndim == 3:  # a dispersed plant: per case
            st = ModalPropagator.build(
                modal[2], modal[3], Tinv @ B, dt, substeps, None if Bf is None else Tinv @ Bf
            )
            self.E, self.P1u = _c(st.E), _c(st.P1u)
            if forced:
                self.P1f, self.P2f = _c(st.P1f[..., 0]), _c(st.P2f[..., 0])
        elif modal is not None:
            st = ModalPropagator.build(
                modal[2], modal[3], Tinv @ B, dt, substeps, None if Bf is None else Tinv @ Bf
            )
            self.E, self.P1u = _c(st.E[None]), _c(st.P1u[None])
            if forced:
                self.P1f, self.P2f = _c(st.P1f.T), _c(st.P2f.T)
        else:
            st = ExponentialStepper.build(A, B, Bf, dt, substeps)
            self.E = _c(np.swapaxes(st.Et, -1, -2).reshape(-1, n, n))
            self.P1u = _c(np.swapaxes(st.P1u, -1, -2).reshape(-1, n, m))
            if forced:
                self.P1f = _c(st.P1f.reshape(-1, n))
                self.P2f = _c(st.P2f.reshape(-1, n))
        if forced:
            Cr = np.asarray(plant.output_matrices(d.force_output)[0]).reshape(-1, n)
            self.Cr = _c(Cr if self.T is None else (Cr[:, None, :] @ self.T)[:, 0])
            f = d.force
            self.fric = _c(
                np.array(np.broadcast_arrays(f.coulomb, f.viscous, f.smoothing), float).T.reshape(
                    -1, 3
                )
            )
            self.force_col = j
        else:
            self.P1f = self.P2f = self.Cr = np.zeros((0, n))
            self.fric = np.zeros((0, 3))
            self.force_col = None
        self.substeps = int(substeps)
        # impulses: Δx = J B (the Python loop's ``impulses[k] @ Bt``), ascending samples
        Bt = np.swapaxes(B, -1, -2)
        imp = input_impulses(disturbances, slices, m, n_t, dt)
        keys = sorted(imp)
        self.imp_k = np.array(keys, dtype=np.int64)
        self.imp_dx = _c(
            np.stack(
                [np.broadcast_to(imp[i] @ Bt, (B.shape[0] if B.ndim == 3 else 1, n)) for i in keys]
            )
            if keys
            else np.zeros((0, 1, n))
        )
        # measured elements: what the law reads (its columns, in its order: no copy of its
        # arrays), the sources of a derivative sensor, then the recorded ones it does not
        # read; the kernel keeps the tail from the first recorded element on
        derived = [k for k in measured if k in sensors and sensors[k].derivative_of is not None]
        names = list(controller.reads)
        names += [
            sensors[k].derivative_of for k in derived if sensors[k].derivative_of not in names
        ]
        names += [k for k in kept if k not in names]
        self.offsets, off = {}, 0
        for k in names:
            self.offsets[k] = slice(off, off + channel_width(plant, k))
            off += channel_width(plant, k)
        p = off
        direct = [k for k in names if k not in derived]
        mats = {k: plant.output_matrices(k) for k in direct}
        C, D, Df = stacked_output_matrices([mats[k] for k in direct], m)
        lead = (C.shape[0],) if C.ndim == 3 else (1,)
        Cm, Dm, Dmf = np.zeros(lead + (p, n)), np.zeros(lead + (p, m)), np.zeros(lead + (p,))
        row = 0
        for k in direct:
            sl, w = self.offsets[k], channel_width(plant, k)
            Cm[:, sl] = C[..., row : row + w, :]
            Dm[:, sl] = D[..., row : row + w, :]
            if forced:
                Dmf[:, sl] = Df[..., row : row + w, self.force_col]
            row += w
        self.Cm = _c(Cm if self.T is None else Cm @ self.T)
        self.Dm, self.Dmf = _c(Dm), _c(Dmf)
        columns = noise_columns(plant)
        sens = np.zeros((1, p, 4))
        sens[..., 3] = np.inf
        slot = np.full(p, -1, dtype=np.int64)
        for k in direct:
            s = sensors.get(k)
            if s is None:
                continue
            sl, w = self.offsets[k], channel_width(plant, k)
            for i, field in enumerate(("quantum", "noise", "bias", "range")):
                sens = _fill(sens, (sl, i), _per_element(getattr(s, field), nc, w))
            if np.any(s.noise):
                col = noise_column(columns, k, "its sensor noise", plant)
                slot[sl] = np.arange(w) + (col if isinstance(col, int) else col.start)
        self.sensor, self.sensor_slot = _c(sens), slot
        if derived:
            s = sensors[derived[0]]
            self.fir_src = self.offsets[s.derivative_of].start
            self.fir_dst = self.offsets[derived[0]].start
            self.fir_w = _c(least_squares_derivative_weights(s.window, s.order, dt))
        else:
            self.fir_src = self.fir_dst = -1
            self.fir_w = np.zeros(0)
        # the law, its rows on the plant's inputs
        order = [j for k in controller.writes for j in range(slices[k].start, slices[k].stop)]
        reads = [
            i for k in controller.reads for i in range(self.offsets[k].start, self.offsets[k].stop)
        ]
        self.law = _pad_law(law, p, reads, order, m)  # read-only: copied block by block
        # per-case values of the law per sample: what a block's copy of it holds per case
        self.law_values = (
            sum(a.size / a.shape[1] for a in self.law[:6] if a.shape[1] == nc > 1) / n_t
        )
        self.rec_start = min((self.offsets[k].start for k in kept), default=p)
        self.p_rec = p - self.rec_start
        act = np.zeros((1, m, 2))
        act[..., 0], act[..., 1] = np.inf, 1.0
        for k in controller.writes:
            a = actuators.get(k)
            if a is not None:
                w = slices[k].stop - slices[k].start
                act = _fill(act, (slices[k], 0), _per_element(a.saturation, nc, w))
                act = _fill(act, (slices[k], 1), _per_element(a.scale, nc, w))
        self.act = _c(act)
        dstd, dslot = np.zeros((1, m)), np.full(m, -1, dtype=np.int64)
        for k, d in disturbances.items():
            if np.any(d.random):
                sl = slices[k]
                w = sl.stop - sl.start
                dstd = _fill(dstd, (sl,), _per_element(d.random, nc, w))
                col = noise_column(columns, k, "its random disturbance", plant)
                dslot[sl] = np.arange(w) + (col if isinstance(col, int) else col.start)
        self.dist_std, self.dist_slot = _c(dstd), dslot
        self.width = sum(s.stop - s.start for s in columns.values())
        self.noisy = bool((slot >= 0).any() or (dslot >= 0).any())
        # case by case: a case's modal start must not depend on its batch (see Co below)
        self.x0 = _c(
            x0
            if Tinv is None
            else np.array([x @ (Tinv if Tinv.ndim == 2 else Tinv[c]).T for c, x in enumerate(x0)])
        )
        if Tinv is not None and Tinv.ndim == 2:
            self.imp_dx = _c(self.imp_dx @ Tinv.T)
        elif Tinv is not None:  # per case: each case's increments in its own coordinates
            imp = np.broadcast_to(self.imp_dx, (self.imp_dx.shape[0], nc, n))
            self.imp_dx = _c(np.stack([imp[:, c] @ Tinv[c].T for c in range(nc)], axis=1))
        self.p, self.m, self.n = p, m, n
        self._recorded_rows(plant, forced, rows)

    def _recorded_rows(self, plant, forced, names=None):
        """The kernel's records in place of the states (module docstring): ``lean`` when
        every recorded output is linear and the energies (if any) are quadratic forms; its
        output rows (Co, Do, Dof: the recorded outputs, or ``names``, then h) and energy
        matrix Q."""
        n, m = self.n, self.m
        names = list(plant.recorded if names is None else names)
        mats = [plant.output_matrices(k) for k in names]
        probe = np.zeros((plant.n_cases, n))
        energy = plant.energy(probe) is not None
        vibration = energy and hasattr(plant, "vibration_energy")
        Q = plant.energy_matrix if energy else None
        h = (getattr(plant, "momentum_row", None), getattr(plant, "total_inertia", None))
        self.lean = (
            all(mt is not None for mt in mats)
            and (not energy or Q is not None)
            and (not vibration or all(v is not None for v in h))
        )
        self.Co, self.Do = np.zeros((1, 0, n)), np.zeros((1, 0, m))
        self.Dof, self.Q = np.zeros((1, 0)), np.zeros((0, n, n))
        self.widths = [channel_width(plant, k) for k in names]
        # per case for a dispersed plant: (n_cases, 1) against the (n_cases, samples) rows
        self.inertia = np.asarray(h[1], float)[..., None] if vibration else None
        if not self.lean:
            return
        rows = list(mats) + (
            [(np.asarray(h[0])[..., None, :], np.zeros((1, m)), None)] if vibration else []
        )
        if rows:
            C, D, Df = stacked_output_matrices(rows, m)
            lead = (C.shape[0],) if C.ndim == 3 else (1,)
            C, D = C.reshape(lead + C.shape[-2:]), D.reshape(lead + D.shape[-2:])
            Dof = Df[..., self.force_col] if forced else np.zeros(D.shape[:-1])
            if self.T is not None:
                # row by row: a BLAS product's summation order may depend on the matrix's
                # shape (OpenBLAS Haswell kernels), and a row must have the same bits whichever
                # rows are stacked with it, so that run_reduced's rows equal run's
                T = self.T if self.T.ndim == 3 else self.T[None]
                C = np.array(
                    [
                        [row @ T[min(c, len(T) - 1)] for row in case_rows]
                        for c, case_rows in enumerate(np.broadcast_to(C, (len(T),) + C.shape[1:]))
                    ]
                )
            self.Co = _c(C)
            self.Do, self.Dof = _c(D), _c(np.broadcast_to(Dof, D.shape[:-1]))
        if energy:
            Q = np.asarray(Q, float)
            Q = Q if self.T is None else np.swapaxes(self.T, -1, -2) @ Q @ self.T
            self.Q = _c(Q.reshape((-1, n, n)))

    def block(self, c0: int, c1: int, seeds, n_t: int, X, Y, Ucmd, U, D, F, stop, O=None, En=None):
        """Run the kernel on cases [c0, c1) over the first ``n_t`` samples into the given
        records (case-major views; O, En None: no output rows, no energy)."""
        kernel = closed_loop_parallel if c1 - c0 >= PARALLEL_CASES else closed_loop
        cb_ = c1 - c0
        O = np.empty((cb_, 0, 0)) if O is None else O
        En = np.empty((cb_, 0)) if En is None else En
        kernel(self.inputs(c0, c1, seeds, n_t), Records(X, Y, Ucmd, U, D, F, O, En, stop))

    def inputs(self, c0: int, c1: int, seeds, n_t: int) -> Loop:
        """The kernel's parameters (:class:`~flexsat.sim.kernels.Loop`) for cases
        [c0, c1) over ``n_t`` samples: the noise streams drawn, the per-case arrays sliced."""

        def cases(a, axis=0):  # a per-case array's block, a shared one as is
            if a.shape[axis] == 1:
                return a
            idx = [slice(None)] * a.ndim
            idx[axis] = slice(c0, c1)
            return _c(a[tuple(idx)])

        def law_cases(a):  # the law's (read-only) arrays: a writable copy of the block
            return np.array(a[:, c0:c1] if a.shape[1] != 1 else a, dtype=np.float64, order="C")

        cb = c1 - c0
        if self.noisy:  # each case's stream from its own seed, as the Python loop draws it
            noise = np.empty((cb, n_t, self.width))
            for i in range(cb):
                noise[i] = np.random.default_rng(int(seeds[c0 + i])).standard_normal(
                    (n_t, self.width)
                )
        else:
            noise = np.zeros((cb, 0, 0))
        Ak, Bk, Ck, Dk, y_ref, u_ff, K0 = self.law
        from flexsat.sim.engine import DIVERGENCE_BOUND

        return Loop(
            self.x0[c0:c1],
            cases(self.E),
            self.T is not None,
            cases(self.P1u),
            cases(self.P1f),
            cases(self.P2f),
            cases(self.Cr),
            cases(self.fric),
            self.substeps,
            self.imp_k,
            cases(self.imp_dx, 1),
            cases(self.Cm),
            cases(self.Dm),
            cases(self.Dmf),
            cases(self.sensor),
            self.sensor_slot,
            self.fir_src,
            self.fir_dst,
            self.fir_w,
            law_cases(Ak),
            law_cases(Bk),
            law_cases(Ck),
            law_cases(Dk),
            law_cases(y_ref),
            law_cases(u_ff),
            np.array(K0 if K0.shape[0] <= 1 else K0[c0:c1], order="C"),
            cases(self.act),
            cases(self.dist_std),
            self.dist_slot,
            noise,
            DIVERGENCE_BOUND,
            cases(self.Co),
            cases(self.Do),
            cases(self.Dof),
            cases(self.Q),
        )
