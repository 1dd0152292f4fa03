"""Compiled closed-loop kernels: a sampled-data loop on plain arrays with a leading case axis.

One control period of the loop of :func:`flexsat.sim.engine.simulate`, fused into one compiled
function (numba) so that a maneuver costs a few microseconds per control step:

at each sample k (t_k = k dt), for each case c

1. impulses: x += Δx_k (instantaneous momentum changes, already mapped to state increments);
2. force at the sample, f_k = F(x_k) (the low-rank bearing friction below, 0 if none);
3. measurement y = C_m x + D_m w_{k−1} + D_mf f_k (w_{k−1} the input applied over the last
   period, the feedthrough of the acceleration into root loads);
4. sensor model per element i (that of :class:`flexsat.sim.channels.ChannelSensor`):
   v = y_i + bias_i + std_i · noise[c, k, slot_i]; v = q_i rint(v / q_i) if q_i > 0 (an
   encoder of quantum q, Junkins, Pollock & Rahman 1990 Att. 3: 0.01 deg); v = clip(v, ±sat_i);
5. optional causal FIR-derivative channel: y[dst] = Σ_j c_j v_src(t_{k−L+1+j}), the
   least-squares differentiating filter of
   :func:`flexsat.sim.sensors.least_squares_derivative_weights`, its history started full of
   the first sensed value (zero initial rate); it replaces element dst's sensor model;
6. law in the compiled-loop linear form (HELPERS.md, issue #10), e = y − y_ref[k]:
   u_cmd = u_ff[k] + C_k ξ + D_k e,  ξ ← A_k ξ + B_k e,  ξ_0 = K0 e_0 (LQG) or 0;
7. divergence check: the first sample where |x| or |u_cmd| exceeds ``bound`` or is not finite
   ends the case (``stop[c] = k``; the engine raises SimulationDiverged);
   records at the sample: the state x (when asked), the recorded output rows
   o = C_o x + D_o w_{k−1} + D_of f_k (like the measurement, without sensor effects) and the
   energy ½ xᵀ Q x: what a result needs, without the state history (O(n) and O(n²) per
   sample against O(n²) or O(n) per substep of the propagation);
8. actuator per input element: u = scale · clip(u_cmd, ±sat); random disturbance
   d = std · noise[c, k, slot]; applied input w = u + d, held over the period;
9. ``substeps`` steps of h = dt / substeps of x' = A x + B w + b_f N(x) with the exponential
   integrator of :mod:`flexsat.sim.integrators` (exact zero-order hold for the linear part,
   ETD2RK of Cox & Matthews 2002 Eq. 22 for the force):

       a = E x + P1u w + P1f N(x),   x ← a + P2f (N(a) − N(x)),

   N(x) = −c1 tanh(r / ε) − c2 r, r = C_r x (Junkins, Pollock & Rahman 1990,
   Att. 3 Eq. 23, regularised as in
   :class:`flexsat.sim.disturbances.BearingFriction`): a rank-1 force on one input channel.

The propagator E is either dense or block-diagonal with 2×2 blocks (``block_diagonal=True``:
the modal coordinates of :class:`flexsat.sim.integrators.ModalPropagator`, O(n) per step).

Shapes (n_t samples, C cases, n states, m inputs, p measurements, n_k law states). Every
plant, sensor, actuator and force array has a leading case axis of length 1 (shared) or C (per
case: a dispersion); the law arrays carry the (T, C) axes of the linear form.

Records and noise are case-major (C, n_t, ...), so each case's loop reads and writes
contiguous memory.

The step is written once, in :func:`_group`, for a group of W cases side by side (every
per-case quantity a row of W lanes, the lanes innermost), each phase above one function of
:mod:`flexsat.sim.kernel_phases` for any W. :func:`closed_loop` runs it with W = 1 and keeps
the history (:class:`Records`); :func:`closed_loop_reduced` with W = :data:`LANES` keeping
no history: the running reductions of the first output rows (a maneuver's peaks and last
sample outside a band) and the outputs and energy at chosen samples (the metrics of a sweep,
issue 13) (:class:`Reductions`). What is recorded at a sample is the only part that differs
(:func:`record_sample`, :func:`record_inputs`, chosen at compile time by the type of the
output record).

Each lane performs the same sequence of scalar operations whatever W, its group or its
neighbours, and whether the batch runs serially or in parallel (:func:`closed_loop_parallel`,
:func:`closed_loop_reduced_parallel`: groups spread over threads, no reductions across
cases): the records are bit-identical between serial and parallel, a batch and its cases run
alone, and the reductions equal the reductions of the records bit for bit. The noise enters
only through ``noise[c]``, so a case's result depends on its own stream only.

The kernels are plain numba functions on arrays: their parameters come as one record,
:class:`~flexsat.sim.kernel_arrays.Loop`, their outputs as
:class:`~flexsat.sim.kernel_arrays.Records` or :class:`~flexsat.sim.kernel_arrays.Reductions`
(:mod:`flexsat.sim.kernel_arrays`); :mod:`flexsat.sim.compiled` builds them from the plant, the
law and the channels. The formulas of a step's pieces (quantiser, saturation, actuator,
bearing friction: :mod:`flexsat.sim.step`) and of the maneuver metrics' per-sample terms
(:mod:`flexsat.sim.metrics`) are the plain functions the Python loop and the post-hoc metrics
run, compiled here.

The kernels use numba's numpy error model: no zero-division checks in the loop (the divisors
are a positive quantum, a positive smoothing speed and the FIR length, validated upstream).

numba's on-disk cache of a kernel is invalidated by a change of the file that defines it
only: after editing :mod:`flexsat.sim.kernel_phases`, :mod:`flexsat.sim.kernel_arrays`,
:mod:`flexsat.sim.step` or :mod:`flexsat.sim.metrics` alone, delete the cache (``__pycache__``
of this package or ``NUMBA_CACHE_DIR``), or the kernels run the code compiled before the edit.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numba import prange
from numba.extending import overload

from flexsat.sim.kernel_arrays import (
    ARGUMENTS,
    RECORDS,
    REDUCTIONS,
    Loop,
    Records,
    Reductions,
    allocate_records,
    cached_jit,
    case_index,
)
from flexsat.sim.kernel_phases import (
    actuate,
    apply_impulses,
    diverged,
    energy,
    fir_derivative,
    friction,
    lane_parameters,
    law,
    measure,
    output_rows,
    propagate,
    row_count,
    row_products,
)
from flexsat.sim.metrics import outside_term, past_term, peak_term

__all__ = [
    "ARGUMENTS",
    "LANES",
    "Loop",
    "Records",
    "Reductions",
    "RECORDS",
    "REDUCTIONS",
    "allocate_records",
    "closed_loop",
    "closed_loop_parallel",
    "closed_loop_reduced",
    "closed_loop_reduced_parallel",
    "lane_layout",
    "output_arrays",
    "record_inputs",
    "record_sample",
    "start_records",
]

#: cases per group of :func:`closed_loop_reduced`: the lanes of its vector operations (8:
#: :func:`flexsat.sim.kernel_phases.row_products` holds one register per lane)
LANES = 8


# ------------------------------------------------------------------------------------------
# what a run keeps: a history (Records, one case per group) or reductions (LANES per group).
# Each hook below is a stub numba replaces by the implementation for the output record's type
# (an overload, inlined): the step of _group is compiled once per kind of output. The hooks
# take the output arrays unpacked once before the time loop (output_arrays): an array taken
# out of a tuple inside the loop costs an atomic reference count increment and decrement per
# use (a third of a linear modal step).


def _reductions(sink: Any) -> bool:
    """The numba type of an output record is that of :class:`Reductions` (else: records)."""
    return getattr(sink, "instance_class", None) is Reductions


def lane_layout(sink: Records | Reductions, loop: Loop) -> tuple[int, int, int, bool]:
    """(W, n_t, r, energy): lanes per group, samples, output rows and whether the energy is
    computed, for the output record ``sink``."""
    raise NotImplementedError("compiled only (numba overload)")


def output_arrays(sink: Records | Reductions) -> tuple[np.ndarray, ...]:
    """The arrays of the output record as 11 (the fields of :class:`Reductions`; the 9 of
    :class:`Records` then ``stop`` twice more), named o0 .. o10 in the hooks."""
    raise NotImplementedError("compiled only (numba overload)")


def start_records(sink: Records | Reductions, cl: np.ndarray, W: int) -> None:
    """Initialise the outputs of the group's cases ``cl`` (stop = −1, empty reductions)."""
    raise NotImplementedError("compiled only (numba overload)")


def record_sample(sink: Records | Reductions, *outputs_and_sample: Any) -> None:
    """Record sample k of each lane (arguments: :func:`_record_sample`): states,
    measurements, commands, force, output rows and energy (records), or the reductions'
    running maxima and snapshots (reductions)."""
    raise NotImplementedError("compiled only (numba overload)")


def record_inputs(sink: Records | Reductions, *outputs_and_inputs: Any) -> None:
    """Record the actuator outputs u and the disturbances d of sample k of each lane
    (arguments: :func:`_record_inputs`)."""
    raise NotImplementedError("compiled only (numba overload)")


def _history_layout(sink, loop):
    O = sink[6]
    r = O.shape[2] if O.shape[1] > 0 else 0
    return 1, sink[1].shape[1], r, sink[7].shape[1] > 0 and loop.Q.shape[0] > 0


def _reductions_layout(sink, loop):
    energy = sink.snapE.shape[1] > 0 and loop.Q.shape[0] > 0
    return LANES, loop.y_ref.shape[0], loop.Co.shape[1], energy


@overload(lane_layout, inline="always")
def _lane_layout(sink, loop):
    return _reductions_layout if _reductions(sink) else _history_layout


def _history_arrays(sink):
    X, Y, Ucmd, U, D, F, O, En, stop = sink
    return X, Y, Ucmd, U, D, F, O, En, stop, stop, stop


def _reductions_arrays(sink):
    return sink


@overload(output_arrays, inline="always")
def _output_arrays(sink):
    return _reductions_arrays if _reductions(sink) else _history_arrays


def _history_start(sink, cl, W):
    stop = sink[8]
    for l in range(W):
        stop[cl[l]] = -1


def _reductions_start(sink, cl, W):
    red, upeak, stop = sink.red, sink.upeak, sink.stop
    for l in range(W):
        c = cl[l]
        for j in range(red.shape[1]):
            red[c, j, 0] = 0.0  # max |s|
            red[c, j, 1] = -np.inf  # max dir · s
            red[c, j, 2] = 0.0  # last sample with |s| > band, + 1 (0: none)
        for i in range(upeak.shape[1]):
            upeak[c, i] = 0.0
        stop[c] = -1


@overload(start_records, inline="always")
def _start_records(sink, cl, W):
    return _reductions_start if _reductions(sink) else _history_start


def _history_sample(
    sink, o0, o1, o2, o3, o4, o5, o6, o7, o8, o9, o10, k, cl, x, y, ucmd, f, ov, Qv, qx, W
):
    """:func:`record_sample` of :class:`Records`: o0 .. o7 = X, Y, Ucmd, U, D, F, O, En."""
    n, p, m, p_rec = x.shape[0], y.shape[0], ucmd.shape[0], o1.shape[2]
    for l in range(W):
        c = cl[l]
        if o0.shape[1] > 0:
            for j in range(n):
                o0[c, k, j] = x[j, l]
        if o6.shape[1] > 0:
            for i in range(o6.shape[2]):
                o6[c, k, i] = ov[i, l]
        if o7.shape[1] > 0 and Qv.shape[0] > 0:
            o7[c, k] = energy(Qv, x, qx, l)
        for i in range(p_rec):
            o1[c, k, i] = y[p - p_rec + i, l]
        for i in range(m):
            o2[c, k, i] = ucmd[i, l]
        if o5.shape[1] > 0:
            o5[c, k] = f[l]


def _reductions_sample(
    sink, o0, o1, o2, o3, o4, o5, o6, o7, o8, o9, o10, k, cl, x, y, ucmd, f, ov, Qv, qx, W
):
    """:func:`record_sample` of :class:`Reductions`: o0 .. o10 = red_c, red_tab, red_t,
    red_dir, red_band, snap_k, red, upeak, snapO, snapE, stop."""
    for j in range(o6.shape[1]):
        tab = o1[j]
        band = o4[j]
        for l in range(W):
            c = cl[l]
            v = ov[j, l] - o0[case_index(o0.shape[0], c), j]
            if tab >= 0:
                v = v - o2[tab, case_index(o2.shape[1], k), case_index(o2.shape[2], c)]
            # running maxima of the metrics' per-sample terms (flexsat.sim.metrics)
            a = peak_term(v)
            if a > o6[c, j, 0]:
                o6[c, j, 0] = a
            a = past_term(v, o3[case_index(o3.shape[0], c)])
            if a > o6[c, j, 1]:
                o6[c, j, 1] = a
            a = outside_term(v, band, k)
            if a > o6[c, j, 2]:
                o6[c, j, 2] = a
    for i in range(o8.shape[1]):
        for l in range(W):
            c = cl[l]
            if o5[case_index(o5.shape[0], c), i] == k:
                for j in range(o8.shape[2]):
                    o8[c, i, j] = ov[j, l]
                if o9.shape[1] > 0 and Qv.shape[0] > 0:
                    o9[c, i] = energy(Qv, x, qx, l)


@overload(record_sample, inline="always")
def _record_sample(
    sink, o0, o1, o2, o3, o4, o5, o6, o7, o8, o9, o10, k, cl, x, y, ucmd, f, ov, Qv, qx, W
):
    return _reductions_sample if _reductions(sink) else _history_sample


def _history_inputs(sink, o0, o1, o2, o3, o4, o5, o6, o7, o8, o9, o10, k, cl, u, d, W):
    """:func:`record_inputs` of :class:`Records` (o3, o4 = U, D)."""
    for i in range(u.shape[0]):
        for l in range(W):
            o3[cl[l], k, i] = u[i, l]
            o4[cl[l], k, i] = d[i, l]


def _reductions_inputs(sink, o0, o1, o2, o3, o4, o5, o6, o7, o8, o9, o10, k, cl, u, d, W):
    """:func:`record_inputs` of :class:`Reductions` (o7 = upeak)."""
    for i in range(min(u.shape[0], o7.shape[1])):
        for l in range(W):
            a = peak_term(u[i, l])
            if a > o7[cl[l], i]:
                o7[cl[l], i] = a


@overload(record_inputs, inline="always")
def _record_inputs(sink, o0, o1, o2, o3, o4, o5, o6, o7, o8, o9, o10, k, cl, u, d, W):
    return _reductions_inputs if _reductions(sink) else _history_inputs


# ------------------------------------------------------------------------------------------
# the step


@cached_jit(error_model="numpy")
def _group(c0, nl, loop, sink):
    """Cases c0 .. c0 + nl − 1 of the loop, side by side as W lanes (:func:`lane_layout`; nl
    <= W, the lanes past nl repeat the last case: the same numbers written twice): the step
    of the module docstring, phase by phase (:mod:`flexsat.sim.kernel_phases`)."""
    W, n_t, r, with_energy = lane_layout(sink, loop)
    n, m, p, nk = loop.x0.shape[1], loop.P1u.shape[2], loop.Cm.shape[1], loop.Ak.shape[2]
    fir_src, fir_dst, fir_w = loop.fir_src, loop.fir_dst, loop.fir_w
    imp_k, imp_dx, sensor_slot, noise = loop.imp_k, loop.imp_dx, loop.sensor_slot, loop.noise
    Ak, Bk, Ck, Dk, y_ref, u_ff, K0 = (
        loop.Ak,
        loop.Bk,
        loop.Ck,
        loop.Dk,
        loop.y_ref,
        loop.u_ff,
        loop.K0,
    )
    bound, dist_slot, substeps = loop.bound, loop.dist_slot, loop.substeps
    block_diagonal, has_force = loop.block_diagonal, loop.P1f.shape[0] > 0
    cl = np.empty(W, np.int64)
    for l in range(W):
        cl[l] = c0 + min(l, nl - 1)
    (Mt, Et, P1v, Dmv, Dmfv, sensv, Dov, Dofv, actv, dstdv, p1f, p2f, crv, c1, c2, eps, Qv) = (
        lane_parameters(loop, cl, W, r, with_energy)
    )
    start_records(sink, cl, W)
    o0, o1, o2, o3, o4, o5, o6, o7, o8, o9, o10 = output_arrays(sink)
    stop = o10
    x = np.empty((n, W))
    for l in range(W):
        for j in range(n):
            x[j, l] = loop.x0[cl[l], j]
    xa = np.empty((n if block_diagonal else row_count(Et, n), W))
    drive = np.empty((n, W))
    qx = np.empty((n, W))
    w = np.zeros((m, W))  # input applied over the previous period (none before the first sample)
    ucmd = np.empty((m, W))
    u = np.empty((m, W))
    d = np.empty((m, W))
    y = np.empty((p, W))
    e = np.empty((p, W))
    acc = np.empty((row_count(Mt, n), W))
    ov = np.empty((r, W))
    f = np.zeros(W)
    f0 = np.zeros(W)
    df = np.zeros(W)
    s0, s1, s2, s3 = np.empty(W), np.empty(W), np.empty(W), np.empty(W)
    xi = np.zeros((nk, W))
    xi_new = np.empty((nk, W))
    hist = np.empty((max(fir_w.shape[0], 1), W))
    bad = np.zeros(W, np.bool_)
    alive = np.ones(W, np.bool_)
    head = 0  # ring buffer: hist[head] is the oldest sample
    i_imp = 0
    for k in range(n_t):
        # 1. impulses
        i_imp = apply_impulses(x, imp_k, imp_dx, i_imp, k, cl, W)
        # 2. force at the sample
        if has_force:
            friction(x, n, crv, c1, c2, eps, f, s0, s1, s2, s3, W)
        # 3.-4. measurement and sensors; the output rows' state part
        row_products(Mt, x, acc, W)
        measure(acc, w, f, Dmv, Dmfv, sensv, sensor_slot, noise, cl, k, y, W)
        # 5. FIR-derivative channel
        if fir_src >= 0:
            head = fir_derivative(y, hist, head, k, fir_src, fir_dst, fir_w, W)
        # 6. law
        law(Ak, Bk, Ck, Dk, y_ref, u_ff, K0, bound, k, y, e, xi, xi_new, ucmd, bad, cl, W)
        # 7. divergence, records at the sample; a diverged lane is stopped there (its later
        # numbers are not used)
        diverged(x, bound, bad, W)
        output_rows(acc, p, w, f, Dov, Dofv, ov, W)
        record_sample(
            sink, o0, o1, o2, o3, o4, o5, o6, o7, o8, o9, o10, k, cl, x, y, ucmd, f, ov, Qv, qx, W
        )
        # 8. actuator and disturbance (recorded only for a lane still running)
        actuate(ucmd, actv, dstdv, dist_slot, noise, cl, k, u, d, w, W)
        running = False
        for l in range(W):
            if bad[l] and alive[l]:
                stop[cl[l]] = k
                alive[l] = False
            running = running or alive[l]
        if not running:
            break
        record_inputs(sink, o0, o1, o2, o3, o4, o5, o6, o7, o8, o9, o10, k, cl, u, d, W)
        if k == n_t - 1:
            break
        # 9. propagation over the period with the held input
        propagate(
            block_diagonal,
            has_force,
            substeps,
            x,
            xa,
            drive,
            w,
            P1v,
            Et,
            p1f,
            p2f,
            crv,
            c1,
            c2,
            eps,
            f0,
            df,
            s0,
            s1,
            s2,
            s3,
            W,
        )


# ------------------------------------------------------------------------------------------
# the drivers


@cached_jit(error_model="numpy")
def closed_loop(loop: Loop, records: Records) -> None:
    """Run the closed loop for every case, serially (see the module docstring).

    Parameters
    ----------
    loop : Loop                 the loop's parameters, the fields below
    records : Records           the arrays written, the fields after ``Q`` below

    Notes
    -----
    The fields of ``loop`` and ``records``:

        x0 : (C, n)                 initial states
        E : (Cp, n, n) or (Cp, n, 2)
                                    e^{hA}, h = dt / substeps; with ``block_diagonal`` (n even)
                                    row i holds the two entries of its 2×2 diagonal block
                                    (:attr:`flexsat.sim.integrators.ModalPropagator.E`)
        P1u : (Cp, n, m)            h φ1(hA) B (input integral of the held input)
        P1f, P2f, Cr : (Cf, n)      h φ1(hA) b_f, h φ2(hA) b_f and the rate output of the force;
                                    leading length 0 for no force
        fric : (Cfr, 3)             [c1, c2, ε] of N(x)
        substeps : int
        imp_k : (ni,) int64         sample of each impulse, ascending
        imp_dx : (ni, Ci, n)        state increment of each impulse
        Cm, Dm, Dmf : (Cm, p, n), (Cm, p, m), (Cm, p)   measurement matrices
        sensor : (Cs, p, 4)         [quantum, noise std, bias, saturation] per measurement
        sensor_slot : (p,) int64    noise slot per measurement (−1: none)
        fir_src, fir_dst : int      FIR-derivative source and destination element (fir_src < 0:
                                    none); fir_w (L,) weights, oldest sample first
        Ak, Bk, Ck, Dk, y_ref, u_ff, K0
                                    the law's linear form; K0 (C0, nk, p), C0 = 0 for none
        act : (Ca, m, 2)            [saturation, scale] per input
        dist_std : (Cd, m), dist_slot : (m,) int64   random disturbance per input
        noise : (C, n_t, n_slots)   standard normals, case-major (one contiguous stream per case)
        bound : float               divergence bound on |x| and |u_cmd|
        Co, Do, Dof : (Co, r, n), (Co, r, m), (Co, r)
                                    recorded output rows (no sensor effects)
        Q : (Cq, n, n)              energy matrix, symmetric (leading length 0: none)
                                    (Co and Cq are 1 or C; read only when O, En have samples)
        X : (C, n_t or 0, n)        recorded states (time length 0: not recorded)
        Y : (C, n_t, p_rec), Ucmd, U, D : (C, n_t, m), F : (C, n_t or 0)
                                    recorded measurements (the last p_rec <= p of them),
                                    commands, actuator outputs,
                                    disturbances and force (time length 0: not recorded) at
                                    each sample; case-major, so a
                                    case's loop writes contiguous memory (the time-major layout
                                    costs a cache miss per record and sample: 3× slower in a
                                    batch of 1,000)
        O : (C, n_t or 0, r)        recorded outputs o (time length 0: none)
        En : (C, n_t or 0)          energy ½ xᵀ Q x (time length 0: none)
        stop : (C,) int64           written: −1, or the first diverged sample (its X, Y, Ucmd and
                                    F are recorded; U, D there and every later row are not)
    """
    for c in range(loop.x0.shape[0]):
        _group(c, 1, loop, records)


@cached_jit(parallel=True, error_model="numpy")
def closed_loop_parallel(loop: Loop, records: Records) -> None:
    """:func:`closed_loop` with the cases spread over threads (same arguments, bit-identical
    results: each case runs the same scalar operations as in the serial loop)."""
    for c in prange(loop.x0.shape[0]):
        # prange's index is unsigned; the case index must stay a signed integer
        _group(np.int64(c), 1, loop, records)


@cached_jit(error_model="numpy")
def closed_loop_reduced(loop: Loop, reductions: Reductions) -> None:
    """:func:`closed_loop` keeping no history: per case, the reductions of the first
    R output rows o_j (C_o, D_o, D_of), s_j = o_j − red_c[c, j] − red_t[red_tab[j], k, c]
    (the table term only where red_tab[j] >= 0), over every sample k:

        red[c, j] = (max_k |s_j|, max_k red_dir[c] · s_j, 1 + the last k with |s_j| >
                     red_band[j], 0 if none),

    upeak[c, i] = max_k |u_i| (the actuator output of the first upeak.shape[1] inputs), and
    at the samples snap_k[c] (Cs = 1 or C, S) every output row snapO[c, s] and the energy
    snapE[c, s] (S = 0 in snapE: none); red_t (n_tab, 1 or n_t, 1 or C). The cases run in
    groups of :data:`LANES`, each lane the operations of :func:`closed_loop` in the same
    order: the same bits as its records give, whatever the grouping."""
    nc = loop.x0.shape[0]
    for g in range((nc + LANES - 1) // LANES):
        c0 = g * LANES
        _group(c0, min(LANES, nc - c0), loop, reductions)


@cached_jit(parallel=True, error_model="numpy")
def closed_loop_reduced_parallel(loop: Loop, reductions: Reductions) -> None:
    """:func:`closed_loop_reduced` with the groups spread over threads (bit-identical)."""
    nc = loop.x0.shape[0]
    for g in prange((nc + LANES - 1) // LANES):
        c0 = np.int64(g) * LANES
        _group(c0, min(LANES, nc - c0), loop, reductions)
