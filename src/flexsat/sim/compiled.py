"""The compiled path of :func:`flexsat.sim.engine.simulate`: the run handed to the numba loop
of :mod:`flexsat.sim.kernels` when every piece of it has an array form.

Taken when (:func:`unsupported` names the first reason it is not)

* the plant is linear, x' = A x + B u (``nonlinear`` false, no own ``step``), apart from at most
  one input force: a :class:`~flexsat.sim.disturbances.BearingFriction` on a size-1 input driven
  by a size-1 linear output (rank 1, integrated by ETD2RK as in the Python loop);
* the law has a linear form (:meth:`~flexsat.control.base.Controller.linear_form`, HELPERS.md);
* every measured channel is linear (``output_matrices``), at most one is a least-squares
  derivative of a size-1 channel and that one has no sensor error of its own;
* no actuator has a rate limit or a bias (the kernel has neither);
* a dispersed plant's recorded outputs are linear.

The arguments are those of the Python loop, built by the same functions so that they are the
same numbers: the propagators of :class:`~flexsat.sim.integrators.ExponentialStepper`, the
impulse increments B J, the stacked output matrices, the least-squares weights, each case's
noise stream from its own seed (one draw of the whole run: the numbers the Python loop draws
chunk by chunk). Only the order of the sums in the matrix products differs, so the two paths
agree to round-off (a few ulps of the largest term per product, carried by the closed loop).

On the modal path (:func:`modal_form`) the kernel records what the result needs, at each
sample: the linear recorded outputs (``output_matrices``, y = C x + D w + D_f f_in, with C T
in the modal coordinates x = T z) as extra output rows, the energy ½ xᵀ Q x of a plant with an
``energy_matrix`` Q (Tᵀ Q T in modal coordinates) and, for a plant with ``momentum_row`` and
``total_inertia`` (the hub plants), the angular momentum h as one more row, whence the
vibration energy E − h² / (2 I_tot) as :meth:`~flexsat.dynamics.hybrid.HybridPlant.
vibration_energy` computes it. No state history, no change back from modal coordinates.
A dispersed hybrid plant (per-case M, K, D: :class:`~flexsat.dynamics.dispersed_hub.
DispersedHubAppendage`) takes this path with each case's own T, propagators, rows and Q
(arrays with a leading case axis, which the kernel reads per case).

Otherwise (dense propagation, states asked for, a nonlinear recorded output, an energy that is
not a quadratic form, a dispersed plant without per-case energy matrices) cases run in
blocks: each block's states are kept for the whole run, then its recorded outputs and
energies are computed from them in array products (as :class:`~flexsat.sim.recording.
Recorder` does per chunk of samples), and dropped; a block holds at most :data:`BLOCK_BYTES`.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from flexsat.dynamics.dispersion import DispersedPlant
from flexsat.sim.channels import input_impulses, noise_column, noise_columns
from flexsat.sim.disturbances import BearingFriction
from flexsat.sim.instruments import stacked_output_matrices
from flexsat.sim.integrators import ExponentialStepper, ModalPropagator, modal_coordinates
from flexsat.sim.kernels import (
    Loop,
    Records,
    Reductions,
    closed_loop,
    closed_loop_parallel,
    closed_loop_reduced,
    closed_loop_reduced_parallel,
)
from flexsat.sim.metrics import (
    METRIC_UNITS,
    maneuver_direction,
    metrics_from_reductions,
    reference_end_sample,
)
from flexsat.sim.recording import Recorder, SimResult
from flexsat.sim.sensors import least_squares_derivative_weights

#: states and noise of one block of cases, bytes: a few MB keeps them in cache-sized pieces
#: and small next to the recorded histories of a large batch
BLOCK_BYTES = 4_000_000
#: a block's states and noise, per case of the batch, in recorded histories' worth (one
#: history is n_t values): 1 keeps them below a tenth of the ~13 histories a case records
BLOCK_SHARE = 1
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


def _ideal(s) -> bool:
    return not (
        np.any(s.noise) or np.any(s.bias) or np.any(s.quantum) or np.any(np.isfinite(s.range))
    )


def unsupported(plant, controller, sensors, actuators, disturbances, measured) -> str | None:
    """Why the run cannot take the compiled loop (module docstring), or None when it can."""
    if getattr(plant, "step", None) is not None:
        return "the plant has its own integrator"
    if plant.nonlinear:
        return "the plant is nonlinear"
    if not own_linear_form(type(controller)):
        return f"{type(controller).__name__} has no linear form of its own commands"
    forced = {k: d for k, d in disturbances.items() if d.force is not None}
    if len(forced) > 1:
        return "more than one input force"
    for k, d in forced.items():
        if not isinstance(d.force, BearingFriction):
            return f"{k}: the input force is not a BearingFriction"
        if plant.input_slices[k].stop - plant.input_slices[k].start != 1:
            return f"{k}: friction on a channel wider than 1"
        mats = plant.output_matrices(d.force_output)
        if mats is None or np.shape(mats[0])[-2] != 1:
            return f"{d.force_output}: the friction's driving output is not a linear scalar"
        if getattr(plant, "integrator", "etd2rk") != "etd2rk":
            return "the plant asks for exp_rk4 with an input force"
    derived = [k for k in measured if k in sensors and sensors[k].derivative_of is not None]
    if len(derived) > 1:
        return "more than one derivative sensor"
    for k in derived:
        src = sensors[k].derivative_of
        if channel_width(plant, k) != 1 or channel_width(plant, src) != 1:
            return f"{k}: derivative sensor on a channel wider than 1"
        if not _ideal(sensors[k]):
            return f"{k}: derivative sensor with its own noise, bias, quantum or range"
    for k in list(measured) + [sensors[k].derivative_of for k in derived]:
        if k not in derived and plant.output_matrices(k) is None:
            return f"{k}: measured output is nonlinear"
    for k in controller.writes:
        a = actuators.get(k)
        if a is not None and (np.any(np.isfinite(a.rate_limit)) or np.any(a.bias)):
            return f"{k}: actuator rate limit or bias"
    if isinstance(plant, DispersedPlant) and any(
        plant.output_matrices(k) is None for k in plant.recorded
    ):
        return "a dispersed plant with a nonlinear recorded output"
    return None


def own_linear_form(cls) -> bool:
    """Whether ``cls`` defines its linear form no higher in its hierarchy than its
    ``__call__``: a subclass changing the commands, or a wrapper forwarding attributes to a
    law, does not inherit a linear form that no longer describes them."""

    def owner(name):
        return next((i for i, k in enumerate(cls.__mro__) if name in vars(k)), None)

    form, call = owner("linear_form"), owner("__call__")
    return form is not None and call is not None and form <= call


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

    The rule: a shared (not dispersed) plant whose coordinates are already decoupled modes
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
        plant,
        controller,
        config,
        nc,
        x0,
        sensors,
        actuators,
        disturbances,
        substeps,
        measured,
        kept,
        law,
        modal: bool = True,
        always_modal: bool = False,
        rows=None,
        propagate: bool = True,
    ):
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


def run(
    plant,
    controller,
    config,
    nc,
    seeds,
    x0,
    theta0,
    sensors,
    actuators,
    disturbances,
    substeps,
    measured,
    kept,
    record_states,
    law,
    always_modal: bool = False,
):
    """The run of :func:`~flexsat.sim.engine.simulate` on the compiled loop (module
    docstring); same result, same exceptions. ``always_modal``: in modal coordinates whenever
    the plant has them, whatever the batch size (:func:`modal_form`)."""
    a = LoopArguments(
        plant,
        controller,
        config,
        nc,
        x0,
        sensors,
        actuators,
        disturbances,
        substeps,
        measured,
        kept,
        law,
        always_modal=always_modal,
    )
    n_t, n, m = a.n_t, a.n, a.m
    batched = plant.n_cases != 1
    forced = a.forced
    rec = Recorder(
        plant,
        n_t,
        nc,
        kept,
        {k: d.force_name for k, d in forced.items()},
        record_states,
        batched,
        [k for k, d in disturbances.items() if np.any(d.random)],
        allocate=False,
    )
    Y, Ucmd, U, Dist = (np.empty((nc, n_t, w)) for w in (a.p_rec, m, m, m))
    F = np.empty((nc, n_t if forced else 0))  # no force: nothing to record
    stop = np.full(nc, -1, dtype=np.int64)
    X_all = np.empty((nc, n_t, n)) if record_states else None
    # in-kernel records on the modal path only: there the state record would need the change
    # back x = T z (an O(n²) product per sample) beside the outputs and energy, while the
    # kernel's propagation is O(n); on the dense path (O(n²) per substep already) the
    # post-loop BLAS products are cheaper than the kernel's scalar quadratic form per sample
    # (202 states, one maneuver: 32.9 against 36.4 µs/step)
    lean = a.lean and not record_states and a.T is not None
    # a block's temporaries: the states unless lean, the noise streams if any are drawn and
    # the copy of a per-case law (its arrays are read-only: block.law_cases)
    size = block_size(nc, n_t, (0 if lean else n) + (a.width if a.noisy else 0) + a.law_values)
    if lean:  # the kernel's records: the recorded outputs, h, the energy
        O = np.empty((nc, n_t, a.Co.shape[1]))
        energy = np.empty((nc, n_t)) if a.Q.shape[0] else None
    else:
        outs = {
            k: np.empty((nc, n_t) + ((w,) if w > 1 else ()))
            for k, w in zip(plant.recorded, a.widths)
        }
        energy = np.empty((nc, n_t)) if rec.has_energy else None
        vib = np.empty((nc, n_t)) if rec.has_vibration else None
    for c0 in range(0, nc, size):
        c1 = min(nc, c0 + size)
        if lean:
            a.block(
                c0,
                c1,
                seeds,
                n_t,
                np.empty((c1 - c0, 0, n)),
                Y[c0:c1],
                Ucmd[c0:c1],
                U[c0:c1],
                Dist[c0:c1],
                F[c0:c1],
                stop[c0:c1],
                O[c0:c1],
                None if energy is None else energy[c0:c1],
            )
            continue
        X = X_all[c0:c1] if X_all is not None else np.empty((c1 - c0, n_t, n))
        a.block(
            c0,
            c1,
            seeds,
            n_t,
            X,
            Y[c0:c1],
            Ucmd[c0:c1],
            U[c0:c1],
            Dist[c0:c1],
            F[c0:c1],
            stop[c0:c1],
        )
        if (stop[c0:c1] >= 0).any():
            continue
        if a.T is not None:  # back to the plant's coordinates, x = T z
            X[...] = X @ np.swapaxes(a.T if a.T.ndim == 2 else a.T[c0:c1], -1, -2)
        _outputs(rec, plant, a, c0, c1, X, U[c0:c1], Dist[c0:c1], F[c0:c1], outs, energy, vib)
    if (stop >= 0).any():
        if a.T is not None:  # the Python loop bounds the physical state: rerun it dense
            a = LoopArguments(
                plant,
                controller,
                config,
                nc,
                x0,
                sensors,
                actuators,
                disturbances,
                substeps,
                measured,
                kept,
                law,
                modal=False,
            )
            stop[:] = -1
            for c0 in range(0, nc, size):
                c1 = min(nc, c0 + size)
                a.block(
                    c0,
                    c1,
                    seeds,
                    n_t,
                    np.empty((c1 - c0, 0, n)),
                    Y[c0:c1],
                    Ucmd[c0:c1],
                    U[c0:c1],
                    Dist[c0:c1],
                    F[c0:c1],
                    stop[c0:c1],
                )
        raise _divergence(a, config, seeds, stop, Ucmd)
    if lean:
        outs, col = {}, 0
        for k, w in zip(plant.recorded, a.widths):
            outs[k] = O[..., col] if w == 1 else O[..., col : col + w]
            col += w
        vib = None
        if a.inertia is not None:  # E − h² / (2 I_tot) (HybridPlant.vibration_energy)
            vib = O[..., col]  # written over h, in place: no history more
            np.square(vib, out=vib)
            vib *= -0.5 / a.inertia
            vib += energy
    Dist += U  # the plant's input u + d, as the Python loop records it
    rec.commands, rec.applied, rec.disturbed = (np.swapaxes(v, 0, 1) for v in (Ucmd, U, Dist))
    if forced:
        if m == 1:
            rec.forces = np.swapaxes(F, 0, 1)[..., None]
        else:
            Ff = np.zeros((nc, n_t, m))
            Ff[..., a.force_col] = F
            rec.forces = np.swapaxes(Ff, 0, 1)
    for k in kept:
        sl = a.offsets[k]
        lo, hi = sl.start - a.rec_start, sl.stop - a.rec_start
        rec.measured[k] = np.swapaxes(Y[..., lo] if hi - lo == 1 else Y[..., lo:hi], 0, 1)
    rec.outputs = {k: np.swapaxes(v, 0, 1) for k, v in outs.items()}
    rec.energy = None if energy is None else energy.T
    rec.vibration = None if vib is None else vib.T
    rec.states = None if X_all is None else np.swapaxes(X_all, 0, 1)
    t = config.dt * np.arange(n_t)
    result = rec.dataset(t, controller, theta0, config, substeps, engine="compiled")
    result.dataset.attrs["propagation"] = "dense" if a.T is None else "modal"
    return result


def run_reduced(
    plant,
    controller,
    config,
    nc,
    seeds,
    x0,
    theta0,
    sensors,
    actuators,
    disturbances,
    substeps,
    measured,
    kept,
    law,
):
    """The maneuver metrics of :func:`~flexsat.sim.engine.simulate` (``metrics_only``) without
    any time history, or None where this path does not apply (the caller then runs
    :func:`run`).

    The single-axis maneuver metrics (:func:`flexsat.sim.metrics.maneuver_metrics`) read
    the histories of θ, θ', the torque, the tip deflection and the vibration energy; each is a
    running maximum, the last sample outside the settling band or a value at one sample, so
    the kernel (:func:`~flexsat.sim.kernels.closed_loop_reduced`) accumulates them in the
    loop: |θ − θ_f| > band, max d (θ − θ_f) (d the slew direction), max |θ' − θ'_ref|,
    max |tip|, max |u|, and the energy and angular momentum at the last sample and at the
    reference's end. The loop is that of :func:`run` (the same operations), its records
    replaced by these reductions: the metrics equal those of :func:`run` on the same
    propagation bit for bit. A shared hybrid plant is always propagated in its modal
    coordinates here (O(n) per substep), whatever the batch size, so that a case's metrics
    do not depend on the batch it runs in (one case alone takes the same path); so is a
    dispersed hybrid plant with per-case energy matrices, momentum rows and inertias
    (:class:`~flexsat.dynamics.dispersed_hub.DispersedHubAppendage`), in each case's own
    modal coordinates (:func:`modal_form`), which do not depend on the batch either.

    Applies to a plant whose recorded outputs include those above as linear outputs, with an
    energy matrix and a vibration energy (:class:`~flexsat.dynamics.hybrid.HybridPlant`),
    a size-1 torque input, a law with a reference (``reference_at``) and a start angle.
    A divergence, or the bound met in modal coordinates, returns None: :func:`run` then
    raises as the Python loop does.
    """
    from flexsat.sim.recording import reference_histories

    names = [c.name for c in plant.outputs]
    axis = plant.maneuver
    if axis is None or theta0 is None:
        return None
    # the histories the maneuver metrics read (:func:`flexsat.sim.metrics.maneuver_metrics`):
    # the outputs reduced in the loop, in this order, and the input
    reduced_outputs, reduced_input = (axis.angle, axis.rate, axis.deflection), axis.torque
    if (
        not all(
            k in plant.recorded and k in names and channel_width(plant, k) == 1
            for k in reduced_outputs
        )
        or plant.input_slices.get(reduced_input, slice(0, 2)).stop
        - plant.input_slices.get(reduced_input, slice(0, 2)).start
        != 1
    ):
        return None
    a = LoopArguments(
        plant,
        controller,
        config,
        nc,
        x0,
        sensors,
        actuators,
        disturbances,
        substeps,
        measured,
        kept,
        law,
        always_modal=True,
        rows=reduced_outputs,
    )
    n_t = a.n_t
    t = config.dt * np.arange(n_t)
    refs = reference_histories(controller, t, nc)
    if not a.lean or a.inertia is None or not a.Q.shape[0] or refs is None:
        return None
    target = np.broadcast_to(np.asarray(controller.target, float), (nc,))
    direction = maneuver_direction(np.broadcast_to(np.asarray(theta0, float), (nc,)), target)
    # θ − θ_f, θ' − θ'_ref (the reference's rate table), the tip deflection
    red_c = np.zeros((nc, 3))
    red_c[:, 0] = target
    red_tab = np.array([-1, 0, -1], dtype=np.int64)
    red_band = np.array([config.settling_band, np.inf, np.inf])
    rate_ref = np.ascontiguousarray(refs[1])  # (n_t, nc)
    ref = controller.reference
    k_end = np.full(nc, n_t - 1, dtype=np.int64)
    if ref is not None:
        ref_end = np.broadcast_to(np.asarray(ref.end_time, float), (nc,))
        k_end = reference_end_sample(t, ref_end)
    snap_k = np.ascontiguousarray(np.column_stack([np.full(nc, n_t - 1), k_end]), dtype=np.int64)
    m_u = plant.input_slices[reduced_input].start + 1
    red = np.empty((nc, 3, 3))
    upeak = np.empty((nc, m_u))
    snapO = np.empty((nc, 2, a.Co.shape[1]))
    snapE = np.empty((nc, 2))
    stop = np.full(nc, -1, dtype=np.int64)
    size = block_size(nc, n_t, (a.width if a.noisy else 0) + a.law_values + 1)
    for c0 in range(0, nc, size):
        c1 = min(nc, c0 + size)
        kernel = closed_loop_reduced_parallel if c1 - c0 >= PARALLEL_CASES else closed_loop_reduced
        kernel(
            a.inputs(c0, c1, seeds, n_t),
            Reductions(
                red_c[c0:c1],
                red_tab,
                np.ascontiguousarray(rate_ref[None, :, c0:c1]),
                direction[c0:c1].copy(),
                red_band,
                snap_k[c0:c1],
                red[c0:c1],
                upeak[c0:c1],
                snapO[c0:c1],
                snapE[c0:c1],
                stop[c0:c1],
            ),
        )
    if (stop >= 0).any():
        return None
    vib = snapO[..., -1]  # E − h² / (2 I_tot), as run() computes it
    np.square(vib, out=vib)
    vib *= -0.5 / a.inertia
    vib += snapE
    metrics = metrics_from_reductions(
        t,
        red[:, 0, 2],
        red[:, 0, 1],
        upeak[:, m_u - 1].copy(),
        vib[:, 0].copy(),
        red[:, 2, 0].copy(),
        red[:, 1, 0],
        vib[:, 1].copy() if ref is not None else None,
    )
    data = {k: (("case",), v, {"units": METRIC_UNITS[k]}) for k, v in metrics.items()}
    ds = xr.Dataset(data, coords={"time": ("time", t, {"units": "s"}), "case": np.arange(nc)})
    ds.attrs.update(
        control_rate_Hz=config.control_rate,
        settling_band_rad=config.settling_band,
        substeps=substeps,
        engine="compiled",
        propagation="dense" if a.T is None else "modal",
        histories="none",
    )
    return SimResult(ds, metrics)


def block_size(nc: int, n_t: int, values: float) -> int:
    """Cases per block: their states, noise and law copy (``values`` per sample) within
    :data:`BLOCK_BYTES` and within :data:`BLOCK_SHARE` of a case's recorded histories per
    case of the batch (a block's temporaries stay small next to what the run keeps)."""
    one = n_t * values * 8
    if one == 0:  # nothing kept per case: one block
        return nc
    budget = min(BLOCK_BYTES, BLOCK_SHARE * nc * n_t * 8)
    return max(1, min(nc, int(budget // one)))


def _outputs(rec, plant, a, c0, c1, X, U, Dist, F, outs, energy, vib):
    """Recorded outputs and energies of cases [c0, c1) from their states X (cb, n_t, n_x):
    y = C x + D w_{k−1} + D_f f_in, as :meth:`Recorder.flush` computes them."""
    cb, n_t = X.shape[:2]
    Wp = np.empty((cb, n_t, a.m))  # the input held before each sample
    Wp[:, 0] = 0.0
    np.add(U[:, :-1], Dist[:, :-1], out=Wp[:, 1:])
    Ff = None
    if a.forced:
        Ff = np.zeros((cb, n_t, a.m))
        Ff[..., a.force_col] = F

    def lin(V, MT):
        if MT.ndim == 2:
            return V @ MT
        return np.einsum("cti,cip->ctp", V, MT[c0:c1])

    if rec.linear:
        Yo = lin(X, rec.CT) + lin(Wp, rec.DT)
        if Ff is not None:
            Yo = Yo + lin(Ff, rec.DfT)
        col = 0
        for k in rec.linear:
            w = channel_width(plant, k)
            outs[k][c0:c1] = Yo[..., col] if w == 1 else Yo[..., col : col + w]
            col += w
    for k in rec.nonlinear:  # a shared plant (unsupported() keeps dispersed ones out)
        outs[k][c0:c1] = plant.output(k, X, Wp, Ff)
    if energy is None:
        return
    if isinstance(plant, DispersedPlant):
        for i in range(cb):
            sub = plant.plants[c0 + i]
            energy[c0 + i] = sub.energy(X[i])
            if vib is not None:
                vib[c0 + i] = sub.vibration_energy(X[i], energy[c0 + i])
        return
    energy[c0:c1] = plant.energy(X)
    if vib is not None:
        vib[c0:c1] = plant.vibration_energy(X, energy[c0:c1])


def _divergence(a, config, seeds, stop, Ucmd):
    """The :class:`~flexsat.sim.engine.SimulationDiverged` of the Python loop: at the first
    sample where any case diverged, the cases bad there and the state growth of the batch
    (the states around that sample recomputed by a run of the batch up to it)."""
    from flexsat.sim.engine import divergence_error

    k = int(stop[stop >= 0].min())
    nc, n, m = a.nc, a.n, a.m
    X = np.empty((nc, k + 1, n))
    rec = [np.empty((nc, k + 1, w)) for w in (a.p_rec, m, m, m)]
    F, st = np.empty((nc, k + 1)), np.full(nc, -1, dtype=np.int64)
    size = block_size(nc, k + 1, n + a.width)
    for c0 in range(0, nc, size):
        c1 = min(nc, c0 + size)
        a.block(c0, c1, seeds, k + 1, X[c0:c1], *(r[c0:c1] for r in rec), F[c0:c1], st[c0:c1])
    X = X[:, max(k - 1, 0) :]  # a dense run (run() reruns a modal one dense)
    prev = float(np.abs(X[:, 0]).max()) if k > 0 else 0.0
    return divergence_error(X[:, -1], Ucmd[:, k], config.dt * k, k, prev, config)
