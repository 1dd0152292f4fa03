"""The compiled path of :func:`flexsat.sim.engine.simulate`: the run handed to the numba loop
of :mod:`flexsat.sim.kernels` when every piece of it has an array form.

Taken when (:func:`unsupported` names the first reason it is not)

* the plant is linear, x' = A x + B u (``nonlinear`` false, no own ``step``), apart from at most
  one input force: a :class:`~flexsat.sim.disturbances.BearingFriction` on a size-1 input driven
  by a size-1 linear output (rank 1, integrated by ETD2RK as in the Python loop);
* the law has a linear form (:meth:`~flexsat.control.base.Controller.linear_form`, HELPERS.md);
  through hardware (:class:`~flexsat.sim.hardware.HardwareLaw`) without a wheel speed limit or a
  fractional delay;
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
from flexsat.sim.compiled_arguments import (
    MODAL_STATES,
    MODAL_STEPS,
    MODAL_STEPS_LARGE,
    PARALLEL_CASES,
    CompiledRun,
    LoopArguments,
    channel_width,
    modal_form,
)
from flexsat.sim.disturbances import BearingFriction
from flexsat.sim.kernels import (
    Reductions,
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

__all__ = [
    "BLOCK_BYTES",
    "BLOCK_SHARE",
    "MODAL_STATES",
    "MODAL_STEPS",
    "MODAL_STEPS_LARGE",
    "PARALLEL_CASES",
    "LoopArguments",
    "block_size",
    "channel_width",
    "modal_form",
    "own_linear_form",
    "run",
    "run_reduced",
    "unsupported",
]

#: states and noise of one block of cases, bytes: a few MB keeps them in cache-sized pieces
#: and small next to the recorded histories of a large batch
BLOCK_BYTES = 4_000_000
#: a block's states and noise, per case of the batch, in recorded histories' worth (one
#: history is n_t values): 1 keeps them below a tenth of the ~13 histories a case records
BLOCK_SHARE = 1


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
    hardware = getattr(controller, "compiled_reason", None)  # a law run through hardware
    if isinstance(hardware, str):
        return hardware
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


def run(job: CompiledRun, record_states, law, always_modal: bool = False, dense: bool = False):
    """The run of :func:`~flexsat.sim.engine.simulate` on the compiled loop (module
    docstring); same result, same exceptions. ``always_modal``: in modal coordinates whenever
    the plant has them, whatever the batch size (:func:`modal_form`); ``dense``: never."""
    plant, controller, config = job.plant, job.controller, job.config
    nc, seeds, theta0 = job.nc, job.seeds, job.theta0
    disturbances, substeps, kept = job.disturbances, job.substeps, job.kept
    a = (
        LoopArguments(job, law, modal=False)
        if dense
        else LoopArguments(job, law, always_modal=always_modal)
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
        if a.T is not None:
            # the Python loop bounds the physical state, not the modal coordinates: flown dense,
            # the run either finishes (the modal bound was passed where x was not) or raises the
            # divergence the Python loop would
            return run(job, record_states, law, dense=True)
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


def run_reduced(job: CompiledRun, law):
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
    plant, controller, config = job.plant, job.controller, job.config
    nc, seeds, theta0 = job.nc, job.seeds, job.theta0
    substeps = job.substeps
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
        job,
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
