"""Compiled closed-loop kernel: a sampled-data loop on plain arrays with a leading case axis.

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
contiguous memory; the law's arrays keep the (T, C) axes of the linear form.

Each case is computed by the same sequence of scalar operations whether the batch runs
serially or in parallel (:func:`closed_loop_parallel`, one case per thread, no reductions
across cases), so the results are bit-identical; the noise enters only through ``noise[c]``,
so a case's result depends on its own stream only.

:func:`closed_loop_reduced` runs the same step keeping no history: the running reductions of
the first output rows (a maneuver's peaks and last sample outside a band) and the outputs and
energy at chosen samples (the metrics of a sweep, issue 13). It takes the cases in groups of
:data:`LANES` side by side (every per-case quantity a row of lanes, the lanes innermost), each
lane performing the scalar operations of :func:`closed_loop` in the same order: its numbers
are those the history loop records, bit for bit, whatever the grouping.

The kernels are plain numba functions on arrays: their parameters come as one record,
:class:`Loop` (a named tuple of arrays and scalars, numba-typed field by field: the attribute
reads compile to the same loads as positional arguments), their outputs as :class:`Records`
or :class:`Reductions`; :mod:`flexsat.sim.compiled` builds them from the plant, the law and
the channels. The formulas of a step's pieces (quantiser, saturation, actuator, bearing
friction: :mod:`flexsat.sim.step`) and of the maneuver metrics' per-sample terms
(:mod:`flexsat.sim.metrics`) are the plain functions the Python loop and the post-hoc metrics
run, compiled here.

The kernels use numba's numpy error model: no zero-division checks in the loop (the divisors
are a positive quantum, a positive smoothing speed and the FIR length, validated upstream).
"""

from __future__ import annotations

import warnings
from typing import NamedTuple

import numpy as np
from numba import njit, prange

from flexsat.sim.metrics import outside_term, past_term, peak_term
from flexsat.sim.step import actuated, friction_torque, quantised, saturated

__all__ = [
    "ARGUMENTS",
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
]

_UNCACHED: list[str] = []


def _jit(**options):
    """``njit(cache=True, **options)``; where numba finds no writable cache directory (a
    read-only install without a writable home) it refuses to cache at decoration time, and
    the kernels are compiled in each process instead (a warning says so: a few seconds)."""

    def wrap(function):
        try:
            return njit(cache=True, **options)(function)
        except RuntimeError as exc:
            if _UNCACHED:  # one warning for the module
                return njit(**options)(function)
            _UNCACHED.append(function.__name__)
            warnings.warn(
                f"flexsat.sim.kernels: {exc}; compiling without the on-disk cache "
                "(set NUMBA_CACHE_DIR to a writable directory to keep it)",
                RuntimeWarning,
                stacklevel=2,
            )
            return njit(**options)(function)

    return wrap


class Loop(NamedTuple):
    """The parameters of a closed loop (shapes and meanings: :func:`closed_loop`)."""

    x0: np.ndarray
    E: np.ndarray
    block_diagonal: bool
    P1u: np.ndarray
    P1f: np.ndarray
    P2f: np.ndarray
    Cr: np.ndarray
    fric: np.ndarray
    substeps: int
    imp_k: np.ndarray
    imp_dx: np.ndarray
    Cm: np.ndarray
    Dm: np.ndarray
    Dmf: np.ndarray
    sensor: np.ndarray
    sensor_slot: np.ndarray
    fir_src: int
    fir_dst: int
    fir_w: np.ndarray
    Ak: np.ndarray
    Bk: np.ndarray
    Ck: np.ndarray
    Dk: np.ndarray
    y_ref: np.ndarray
    u_ff: np.ndarray
    K0: np.ndarray
    act: np.ndarray
    dist_std: np.ndarray
    dist_slot: np.ndarray
    noise: np.ndarray
    bound: float
    Co: np.ndarray
    Do: np.ndarray
    Dof: np.ndarray
    Q: np.ndarray


class Records(NamedTuple):
    """What :func:`closed_loop` records (:func:`allocate_records`)."""

    X: np.ndarray
    Y: np.ndarray
    Ucmd: np.ndarray
    U: np.ndarray
    D: np.ndarray
    F: np.ndarray
    O: np.ndarray
    En: np.ndarray
    stop: np.ndarray


class Reductions(NamedTuple):
    """The reductions of :func:`closed_loop_reduced`: their definitions (inputs), then the
    arrays it writes."""

    red_c: np.ndarray
    red_tab: np.ndarray
    red_t: np.ndarray
    red_dir: np.ndarray
    red_band: np.ndarray
    snap_k: np.ndarray
    red: np.ndarray
    upeak: np.ndarray
    snapO: np.ndarray
    snapE: np.ndarray
    stop: np.ndarray


#: the fields of :class:`Loop`, :class:`Records` and :class:`Reductions` in order
ARGUMENTS, RECORDS, REDUCTIONS = Loop._fields, Records._fields, Reductions._fields


@_jit(inline="always", error_model="numpy")
def _ci(arr_cases, c):
    """Index into a leading case axis of length 1 (shared) or C (per case)."""
    return 0 if arr_cases == 1 else c


@_jit(error_model="numpy")
def _dot(a, b):
    """Σ a_i b_i in four interleaved partial sums: a single chain of dependent additions is
    latency-bound (it was half the cost of a friction substep)."""
    n = a.shape[0]
    s0 = s1 = s2 = s3 = 0.0
    j = 0
    while j + 4 <= n:
        s0 += a[j] * b[j]
        s1 += a[j + 1] * b[j + 1]
        s2 += a[j + 2] * b[j + 2]
        s3 += a[j + 3] * b[j + 3]
        j += 4
    while j < n:
        s0 += a[j] * b[j]
        j += 1
    return (s0 + s1) + (s2 + s3)


@_jit(error_model="numpy")
def _force(x, cr, c1, c2, eps):
    """N(x) = −c1 tanh(r/ε) − c2 r with r = C_r x."""
    return friction_torque(_dot(cr, x), c1, c2, eps)


@_jit(error_model="numpy")
def _propagate(E, x, out, block_diagonal):
    """out = E x: dense (n, n), or 2×2 block-diagonal stored as (n, 2): O(n)."""
    n = x.shape[0]
    if block_diagonal:  # E[i] holds row i's two entries in its own 2×2 block
        for i in range(0, n, 2):
            x0, x1 = x[i], x[i + 1]
            out[i] = E[i, 0] * x0 + E[i, 1] * x1
            out[i + 1] = E[i + 1, 0] * x0 + E[i + 1, 1] * x1
    else:
        for i in range(n):
            s = 0.0
            for j in range(n):
                s += E[i, j] * x[j]
            out[i] = s


@_jit(inline="always", error_model="numpy")
def _rows(Mt, x, out):
    """out = Mtᵀ x, Mt (n, 8 g): eight rows at a time in registers, each summed in order."""
    for i0 in range(0, Mt.shape[1], 8):
        s0 = s1 = s2 = s3 = s4 = s5 = s6 = s7 = 0.0
        for j in range(x.shape[0]):
            xj = x[j]
            s0 += Mt[j, i0] * xj
            s1 += Mt[j, i0 + 1] * xj
            s2 += Mt[j, i0 + 2] * xj
            s3 += Mt[j, i0 + 3] * xj
            s4 += Mt[j, i0 + 4] * xj
            s5 += Mt[j, i0 + 5] * xj
            s6 += Mt[j, i0 + 6] * xj
            s7 += Mt[j, i0 + 7] * xj
        out[i0], out[i0 + 1], out[i0 + 2], out[i0 + 3] = s0, s1, s2, s3
        out[i0 + 4], out[i0 + 5], out[i0 + 6], out[i0 + 7] = s4, s5, s6, s7


@_jit(inline="always", error_model="numpy")
def _energy(Qc, x, qx):
    """½ xᵀ v, v = Q x accumulated column by column (Q symmetric: row j is column j):
    independent element-wise updates the compiler vectorises, where n dot products are each a
    chain of dependent additions (3× slower at n = 22)."""
    n = x.shape[0]
    for i in range(n):
        qx[i] = 0.0
    for j in range(n):
        xj = x[j]
        for i in range(n):
            qx[i] += Qc[j, i] * xj
    return 0.5 * _dot(x, qx)


@_jit(error_model="numpy")
def _case(c, loop, records):
    """Case c of :func:`closed_loop`."""
    (
        x0,
        E,
        block_diagonal,
        P1u,
        P1f,
        P2f,
        Cr,
        fric,
        substeps,
        imp_k,
        imp_dx,
        Cm,
        Dm,
        Dmf,
        sensor,
        sensor_slot,
        fir_src,
        fir_dst,
        fir_w,
        Ak,
        Bk,
        Ck,
        Dk,
        y_ref,
        u_ff,
        K0,
        act,
        dist_std,
        dist_slot,
        noise,
        bound,
        Co,
        Do,
        Dof,
        Q,
    ) = loop
    X, Y, Ucmd, U, D, F, O, En, stop = records
    n = x0.shape[1]
    m = P1u.shape[2]
    p = Cm.shape[1]
    p_rec = Y.shape[2]
    nk = Ak.shape[2]
    n_t = Y.shape[1]
    L = fir_w.shape[0]
    has_force = P1f.shape[0] > 0
    rec_x = X.shape[1] > 0
    r_out = O.shape[2] if O.shape[1] > 0 else 0
    rec_e = En.shape[1] > 0 and Q.shape[0] > 0
    rec_f = F.shape[1] > 0
    cp = _ci(E.shape[0], c)
    cu = _ci(P1u.shape[0], c)
    cm = _ci(Cm.shape[0], c)
    cs = _ci(sensor.shape[0], c)
    ca = _ci(act.shape[0], c)
    cd = _ci(dist_std.shape[0], c)
    # per-case views: two-index access in the loop
    Ec, P1uc, Cmc, Dmc, Dmfc = E[cp], P1u[cu], Cm[cm], Dm[cm], Dmf[cm]
    Coc, Doc, Dofc = np.zeros((0, n)), np.zeros((0, m)), np.zeros(0)
    if r_out > 0:
        co = _ci(Co.shape[0], c)
        Coc, Doc, Dofc = Co[co], Do[co], Dof[co]
    Qc = np.zeros((0, n))
    if rec_e:
        Qc = Q[_ci(Q.shape[0], c)]
    sens, actc, dstd = sensor[cs], act[ca], dist_std[cd]
    noisec, Yc = noise[c], Y[c]
    c1 = c2 = eps = 0.0
    p1f = p2f = cr = np.zeros(n)
    if has_force:
        cf = _ci(P1f.shape[0], c)
        cfr = _ci(fric.shape[0], c)
        p1f, p2f, cr = P1f[cf], P2f[cf], Cr[_ci(Cr.shape[0], c)]
        c1, c2, eps = fric[cfr, 0], fric[cfr, 1], fric[cfr, 2]

    # the measurement and output rows side by side, transposed and padded with zero rows to
    # groups of 8: Mt x accumulated over j = 0 .. n − 1 in eight registers per group (eight
    # independent chains of additions, where each row's dot product alone is one chain of
    # dependent additions), each row summed in the order j = 0 .. n − 1
    R = p + r_out
    R8 = (R + 7) // 8 * 8
    Mt = np.zeros((n, R8))
    for j in range(n):
        for i in range(p):
            Mt[j, i] = Cmc[i, j]
        for i in range(r_out):
            Mt[j, p + i] = Coc[i, j]
    acc = np.empty(R8)
    fused = block_diagonal and not has_force

    x = x0[c].copy()
    xa = np.empty(n)
    qx = np.empty(n)
    drive = np.empty(n)
    w = np.zeros(m)  # input applied over the previous period (none before the first sample)
    ucmd = np.empty(m)
    y = np.empty(p)
    e = np.empty(p)
    xi = np.zeros(nk)
    xi_new = np.empty(nk)
    hist = np.empty(max(L, 1))
    head = 0  # ring buffer: hist[head] is the oldest sample
    i_imp = 0
    n_imp = imp_k.shape[0]
    ci_imp = _ci(imp_dx.shape[1], c)

    for k in range(n_t):
        # 1. impulses (imp_k sorted ascending)
        while i_imp < n_imp and imp_k[i_imp] == k:
            for j in range(n):
                x[j] += imp_dx[i_imp, ci_imp, j]
            i_imp += 1
        # 2. force at the sample
        f = _force(x, cr, c1, c2, eps) if has_force else 0.0
        # 3.-4. measurement and sensors; the output rows' state part
        _rows(Mt, x, acc)
        for i in range(p):
            s = acc[i]
            for j in range(m):
                s += Dmc[i, j] * w[j]
            s += Dmfc[i] * f
            s += sens[i, 2]
            if sensor_slot[i] >= 0:
                s += sens[i, 1] * noisec[k, sensor_slot[i]]
            q = sens[i, 0]
            if q > 0.0:
                s = quantised(s, q)
            y[i] = saturated(s, sens[i, 3])
        # 5. FIR-derivative channel
        if fir_src >= 0:
            if k == 0:
                for j in range(L):
                    hist[j] = y[fir_src]
            else:
                hist[head] = y[fir_src]
                head = (head + 1) % L
            s = 0.0
            for j in range(L):
                s += fir_w[j] * hist[(head + j) % L]
            y[fir_dst] = s
        # 6. law
        tk = _ci(Ak.shape[0], k)
        ck = _ci(Ak.shape[1], c)
        tb = _ci(Bk.shape[0], k)
        cb = _ci(Bk.shape[1], c)
        tc = _ci(Ck.shape[0], k)
        cc = _ci(Ck.shape[1], c)
        td = _ci(Dk.shape[0], k)
        cdk = _ci(Dk.shape[1], c)
        cr_ = _ci(y_ref.shape[1], c)
        cf_ = _ci(u_ff.shape[1], c)
        for i in range(p):
            e[i] = y[i] - y_ref[k, cr_, i]
        if k == 0 and K0.shape[0] > 0:
            c0 = _ci(K0.shape[0], c)
            for i in range(nk):
                s = 0.0
                for j in range(p):
                    s += K0[c0, i, j] * e[j]
                xi[i] = s
        bad = False
        for i in range(m):
            s = u_ff[k, cf_, i]
            for j in range(nk):
                s += Ck[tc, cc, i, j] * xi[j]
            for j in range(p):
                s += Dk[td, cdk, i, j] * e[j]
            ucmd[i] = s
            Ucmd[c, k, i] = s
            if not abs(s) <= bound:
                bad = True
        if nk > 0:
            for i in range(nk):
                s = 0.0
                for j in range(nk):
                    s += Ak[tk, ck, i, j] * xi[j]
                for j in range(p):
                    s += Bk[tb, cb, i, j] * e[j]
                xi_new[i] = s
            xi[:] = xi_new
        # 7. divergence
        for j in range(n):
            if not abs(x[j]) <= bound:
                bad = True
        if rec_x:
            X[c, k, :] = x
        for i in range(r_out):  # o_i = C_o[i] x + D_of[i] f + D_o[i] w
            s = acc[p + i] + Dofc[i] * f
            for j in range(m):
                s += Doc[i, j] * w[j]
            O[c, k, i] = s
        if rec_e:
            En[c, k] = _energy(Qc, x, qx)
        for i in range(p_rec):
            Yc[k, i] = y[p - p_rec + i]
        if rec_f:
            F[c, k] = f
        if bad:
            stop[c] = k
            return
        # 8. actuator and disturbance
        for i in range(m):
            u = actuated(ucmd[i], actc[i, 0], actc[i, 1])
            d = dstd[i] * noisec[k, dist_slot[i]] if dist_slot[i] >= 0 else 0.0
            U[c, k, i] = u
            D[c, k, i] = d
            w[i] = u + d
        if k == n_t - 1:
            break
        # 9. propagation over the period with the held input
        for i in range(n):
            s = 0.0
            for j in range(m):
                s += P1uc[i, j] * w[j]
            drive[i] = s
        for _ in range(substeps):
            if fused:  # x ← E x + drive in one pass over the 2×2 blocks (same operations)
                for i in range(0, n, 2):
                    x0_, x1_ = x[i], x[i + 1]
                    x[i] = (Ec[i, 0] * x0_ + Ec[i, 1] * x1_) + drive[i]
                    x[i + 1] = (Ec[i + 1, 0] * x0_ + Ec[i + 1, 1] * x1_) + drive[i + 1]
                continue
            _propagate(Ec, x, xa, block_diagonal)
            if has_force:
                f0 = _force(x, cr, c1, c2, eps)
                for i in range(n):
                    xa[i] += drive[i] + p1f[i] * f0
                df = _force(xa, cr, c1, c2, eps) - f0
                for i in range(n):
                    x[i] = xa[i] + p2f[i] * df
            else:
                for i in range(n):
                    x[i] = xa[i] + drive[i]
    stop[c] = -1


@_jit(error_model="numpy")
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
        _case(c, loop, records)


@_jit(parallel=True, error_model="numpy")
def closed_loop_parallel(loop: Loop, records: Records) -> None:
    """:func:`closed_loop` with the cases spread over threads (same arguments, bit-identical
    results: each case runs the same scalar operations as in the serial loop)."""
    for c in prange(loop.x0.shape[0]):
        # prange's index is unsigned; the case index must stay a signed integer
        _case(np.int64(c), loop, records)


#: cases per group of :func:`closed_loop_reduced`: the lanes of its vector operations (8:
#: :func:`_rows8` holds one register per lane)
LANES = 8


@_jit(error_model="numpy")
def _lanes(c0, nl, loop, reductions):
    """Cases c0 .. c0 + nl − 1 (nl <= :data:`LANES`) of :func:`closed_loop_reduced` side by
    side: every per-case quantity is a row of :data:`LANES` lanes, the innermost loops run
    over the lanes (independent cases; the rows' sums in registers, :func:`_rows8`), and
    each lane performs the scalar operations of :func:`_case` in its order, so a case's
    numbers do not depend on its group or on ``nl``."""
    (
        x0,
        E,
        block_diagonal,
        P1u,
        P1f,
        P2f,
        Cr,
        fric,
        substeps,
        imp_k,
        imp_dx,
        Cm,
        Dm,
        Dmf,
        sensor,
        sensor_slot,
        fir_src,
        fir_dst,
        fir_w,
        Ak,
        Bk,
        Ck,
        Dk,
        y_ref,
        u_ff,
        K0,
        act,
        dist_std,
        dist_slot,
        noise,
        bound,
        Co,
        Do,
        Dof,
        Q,
    ) = loop
    (
        red_c,
        red_tab,
        red_t,
        red_dir,
        red_band,
        snap_k,
        red,
        upeak,
        snapO,
        snapE,
        stop,
    ) = reductions
    n = x0.shape[1]
    m = P1u.shape[2]
    p = Cm.shape[1]
    nk = Ak.shape[2]
    n_t = y_ref.shape[0]
    Lf = fir_w.shape[0]
    has_force = P1f.shape[0] > 0
    n_red = red.shape[1]
    n_snap = snapO.shape[1]
    r = Co.shape[1]
    snap_e = snapE.shape[1] > 0 and Q.shape[0] > 0
    R = p + r
    # lanes past the group's nl cases repeat its last case: the same numbers written twice
    cl = np.empty(LANES, np.int64)
    for l in range(LANES):
        cl[l] = c0 + min(l, nl - 1)
    # per-lane copies of the per-case arrays, lanes last
    Mt = np.empty((n, R, LANES))
    Ev = np.empty((n, E.shape[2], LANES))
    P1v = np.empty((n, m, LANES))
    Dmv = np.empty((p, m, LANES))
    Dmfv = np.empty((p, LANES))
    sensv = np.empty((p, 4, LANES))
    Dov = np.empty((r, m, LANES))
    Dofv = np.empty((r, LANES))
    actv = np.empty((m, 2, LANES))
    dstdv = np.empty((m, LANES))
    p1f = np.zeros((n, LANES))
    p2f = np.zeros((n, LANES))
    crv = np.zeros((n, LANES))
    c1 = np.zeros(LANES)
    c2 = np.zeros(LANES)
    eps = np.ones(LANES)
    redc = np.zeros((max(n_red, 1), LANES))
    rdir = np.zeros(LANES)
    ct = np.zeros(LANES, np.int64)
    cr_ = np.zeros(LANES, np.int64)
    cf_ = np.zeros(LANES, np.int64)
    ck = np.zeros(LANES, np.int64)
    cb = np.zeros(LANES, np.int64)
    cc = np.zeros(LANES, np.int64)
    cdk = np.zeros(LANES, np.int64)
    ci_imp = np.zeros(LANES, np.int64)
    snapc = np.zeros((max(n_snap, 1), LANES), np.int64)
    Qv = np.zeros((n, n, LANES)) if snap_e else np.zeros((0, 0, LANES))
    for l in range(LANES):
        c = cl[l]
        cp, cu, cm = _ci(E.shape[0], c), _ci(P1u.shape[0], c), _ci(Cm.shape[0], c)
        for j in range(n):
            for i in range(p):
                Mt[j, i, l] = Cm[cm, i, j]
            for i in range(r):
                Mt[j, p + i, l] = Co[_ci(Co.shape[0], c), i, j]
            for q in range(E.shape[2]):
                Ev[j, q, l] = E[cp, j, q]
            for i in range(m):
                P1v[j, i, l] = P1u[cu, j, i]
        for i in range(p):
            for j in range(m):
                Dmv[i, j, l] = Dm[cm, i, j]
            Dmfv[i, l] = Dmf[cm, i]
            for q in range(4):
                sensv[i, q, l] = sensor[_ci(sensor.shape[0], c), i, q]
        for i in range(r):
            co = _ci(Co.shape[0], c)
            for j in range(m):
                Dov[i, j, l] = Do[co, i, j]
            Dofv[i, l] = Dof[co, i]
        for i in range(m):
            actv[i, 0, l] = act[_ci(act.shape[0], c), i, 0]
            actv[i, 1, l] = act[_ci(act.shape[0], c), i, 1]
            dstdv[i, l] = dist_std[_ci(dist_std.shape[0], c), i]
        if has_force:
            cf, cfr = _ci(P1f.shape[0], c), _ci(fric.shape[0], c)
            for j in range(n):
                p1f[j, l] = P1f[cf, j]
                p2f[j, l] = P2f[cf, j]
                crv[j, l] = Cr[_ci(Cr.shape[0], c), j]
            c1[l], c2[l], eps[l] = fric[cfr, 0], fric[cfr, 1], fric[cfr, 2]
        if n_red > 0:
            for j in range(n_red):
                redc[j, l] = red_c[_ci(red_c.shape[0], c), j]
            rdir[l] = red_dir[_ci(red_dir.shape[0], c)]
        if red_t.shape[0] > 0:
            ct[l] = _ci(red_t.shape[2], c)
        for i in range(n_snap):
            snapc[i, l] = snap_k[_ci(snap_k.shape[0], c), i]
        if snap_e:
            cq = _ci(Q.shape[0], c)
            for j in range(n):
                for i in range(n):
                    Qv[j, i, l] = Q[cq, j, i]
        cr_[l], cf_[l] = _ci(y_ref.shape[1], c), _ci(u_ff.shape[1], c)
        ck[l], cb[l] = _ci(Ak.shape[1], c), _ci(Bk.shape[1], c)
        cc[l], cdk[l] = _ci(Ck.shape[1], c), _ci(Dk.shape[1], c)
        ci_imp[l] = _ci(imp_dx.shape[1], c)
        for j in range(n_red):
            red[c, j, 0] = 0.0  # max |s|
            red[c, j, 1] = -np.inf  # max dir · s
            red[c, j, 2] = 0.0  # last sample with |s| > band, + 1 (0: none)
        for i in range(upeak.shape[1]):
            upeak[c, i] = 0.0
        stop[c] = -1

    x = np.empty((n, LANES))
    for l in range(LANES):
        for j in range(n):
            x[j, l] = x0[cl[l], j]
    xa = np.empty((n, LANES))
    drive = np.empty((n, LANES))
    qx = np.empty((n, LANES))
    w = np.zeros((m, LANES))
    ucmd = np.empty((m, LANES))
    y = np.empty((p, LANES))
    e = np.empty((p, LANES))
    acc = np.empty((R, LANES))
    ov = np.empty((r, LANES))
    f = np.zeros(LANES)
    f0 = np.zeros(LANES)
    df = np.zeros(LANES)
    s = np.empty(LANES)
    d0 = np.empty(LANES)
    d1 = np.empty(LANES)
    d2 = np.empty(LANES)
    d3 = np.empty(LANES)
    xi = np.zeros((nk, LANES))
    xi_new = np.empty((nk, LANES))
    hist = np.empty((max(Lf, 1), LANES))
    bad = np.zeros(LANES, np.bool_)
    alive = np.ones(LANES, np.bool_)
    head = 0
    i_imp = 0
    n_imp = imp_k.shape[0]
    fused = block_diagonal and not has_force

    for k in range(n_t):
        # 1. impulses
        while i_imp < n_imp and imp_k[i_imp] == k:
            for j in range(n):
                for l in range(LANES):
                    x[j, l] += imp_dx[i_imp, ci_imp[l], j]
            i_imp += 1
        # 2. force at the sample (the four partial sums of _dot)
        if has_force:
            _force_lanes(x, crv, c1, c2, eps, f, d0, d1, d2, d3)
        # 3.-4. rows, measurement and sensors
        _rows8(Mt, x, acc)
        for i in range(p):
            for l in range(LANES):
                s[l] = acc[i, l]
            for j in range(m):
                for l in range(LANES):
                    s[l] += Dmv[i, j, l] * w[j, l]
            slot = sensor_slot[i]
            for l in range(LANES):
                v = s[l] + Dmfv[i, l] * f[l]
                v += sensv[i, 2, l]
                if slot >= 0:
                    v += sensv[i, 1, l] * noise[cl[l], k, slot]
                q = sensv[i, 0, l]
                if q > 0.0:
                    v = quantised(v, q)
                y[i, l] = saturated(v, sensv[i, 3, l])
        # 5. FIR-derivative channel (one ring buffer position for every lane)
        if fir_src >= 0:
            if k == 0:
                for j in range(Lf):
                    for l in range(LANES):
                        hist[j, l] = y[fir_src, l]
            else:
                for l in range(LANES):
                    hist[head, l] = y[fir_src, l]
                head = (head + 1) % Lf
            for l in range(LANES):
                s[l] = 0.0
            for j in range(Lf):
                hj = (head + j) % Lf
                for l in range(LANES):
                    s[l] += fir_w[j] * hist[hj, l]
            for l in range(LANES):
                y[fir_dst, l] = s[l]
        # 6. law
        tk, tb = _ci(Ak.shape[0], k), _ci(Bk.shape[0], k)
        tc, td = _ci(Ck.shape[0], k), _ci(Dk.shape[0], k)
        for i in range(p):
            for l in range(LANES):
                e[i, l] = y[i, l] - y_ref[k, cr_[l], i]
        if k == 0 and K0.shape[0] > 0:
            for i in range(nk):
                for l in range(LANES):
                    c0k = _ci(K0.shape[0], cl[l])
                    v = 0.0
                    for j in range(p):
                        v += K0[c0k, i, j] * e[j, l]
                    xi[i, l] = v
        for l in range(LANES):
            bad[l] = False
        for i in range(m):
            for l in range(LANES):
                v = u_ff[k, cf_[l], i]
                for j in range(nk):
                    v += Ck[tc, cc[l], i, j] * xi[j, l]
                for j in range(p):
                    v += Dk[td, cdk[l], i, j] * e[j, l]
                ucmd[i, l] = v
                if not abs(v) <= bound:
                    bad[l] = True
        if nk > 0:
            for i in range(nk):
                for l in range(LANES):
                    v = 0.0
                    for j in range(nk):
                        v += Ak[tk, ck[l], i, j] * xi[j, l]
                    for j in range(p):
                        v += Bk[tb, cb[l], i, j] * e[j, l]
                    xi_new[i, l] = v
            for i in range(nk):
                for l in range(LANES):
                    xi[i, l] = xi_new[i, l]
        # 7. divergence: a diverged lane is stopped there (its later numbers are not used)
        for j in range(n):
            for l in range(LANES):
                if not abs(x[j, l]) <= bound:
                    bad[l] = True
        for i in range(r):  # o_i = C_o[i] x + D_of[i] f + D_o[i] w
            for l in range(LANES):
                v = acc[p + i, l] + Dofv[i, l] * f[l]
                for j in range(m):
                    v += Dov[i, j, l] * w[j, l]
                ov[i, l] = v
        for j in range(n_red):
            tab = red_tab[j]
            band = red_band[j]
            for l in range(LANES):
                v = ov[j, l] - redc[j, l]
                if tab >= 0:
                    v = v - red_t[tab, _ci(red_t.shape[1], k), ct[l]]
                # running maxima of the metrics' per-sample terms (flexsat.sim.metrics)
                c = cl[l]
                a = peak_term(v)
                if a > red[c, j, 0]:
                    red[c, j, 0] = a
                a = past_term(v, rdir[l])
                if a > red[c, j, 1]:
                    red[c, j, 1] = a
                a = outside_term(v, band, k)
                if a > red[c, j, 2]:
                    red[c, j, 2] = a
        for i in range(n_snap):
            for l in range(LANES):
                if snapc[i, l] == k:
                    for j in range(r):
                        snapO[cl[l], i, j] = ov[j, l]
                    if snap_e:
                        snapE[cl[l], i] = _energy_lane(Qv, x, qx, l)
        for l in range(LANES):
            if bad[l] and alive[l]:
                stop[cl[l]] = k
                alive[l] = False
        if not alive.any():
            return
        # 8. actuator and disturbance
        for i in range(m):
            slot = dist_slot[i]
            for l in range(LANES):
                u = actuated(ucmd[i, l], actv[i, 0, l], actv[i, 1, l])
                d = dstdv[i, l] * noise[cl[l], k, slot] if slot >= 0 else 0.0
                if i < upeak.shape[1] and peak_term(u) > upeak[cl[l], i]:
                    upeak[cl[l], i] = peak_term(u)
                w[i, l] = u + d
        if k == n_t - 1:
            break
        # 9. propagation over the period with the held input
        for i in range(n):
            for l in range(LANES):
                drive[i, l] = 0.0
            for j in range(m):
                for l in range(LANES):
                    drive[i, l] += P1v[i, j, l] * w[j, l]
        for _ in range(substeps):
            if fused:
                for i in range(0, n, 2):
                    for l in range(LANES):
                        x0_, x1_ = x[i, l], x[i + 1, l]
                        x[i, l] = (Ev[i, 0, l] * x0_ + Ev[i, 1, l] * x1_) + drive[i, l]
                        x[i + 1, l] = (Ev[i + 1, 0, l] * x0_ + Ev[i + 1, 1, l] * x1_) + drive[
                            i + 1, l
                        ]
                continue
            _propagate_lanes(Ev, x, xa, block_diagonal)
            if has_force:
                _force_lanes(x, crv, c1, c2, eps, f0, d0, d1, d2, d3)
                for i in range(n):
                    for l in range(LANES):
                        xa[i, l] += drive[i, l] + p1f[i, l] * f0[l]
                _force_lanes(xa, crv, c1, c2, eps, df, d0, d1, d2, d3)
                for l in range(LANES):
                    df[l] = df[l] - f0[l]
                for i in range(n):
                    for l in range(LANES):
                        x[i, l] = xa[i, l] + p2f[i, l] * df[l]
            else:
                for i in range(n):
                    for l in range(LANES):
                        x[i, l] = xa[i, l] + drive[i, l]


@_jit(inline="always", error_model="numpy")
def _rows8(Mt, x, acc):
    """acc[i] = Σ_j Mt[j, i] x[j] for the 8 lanes, each lane's sum in order j = 0 .. n − 1 in
    its own register (eight independent chains of additions)."""
    n, R = Mt.shape[0], Mt.shape[1]
    for i in range(R):
        a0 = a1 = a2 = a3 = a4 = a5 = a6 = a7 = 0.0
        for j in range(n):
            a0 += Mt[j, i, 0] * x[j, 0]
            a1 += Mt[j, i, 1] * x[j, 1]
            a2 += Mt[j, i, 2] * x[j, 2]
            a3 += Mt[j, i, 3] * x[j, 3]
            a4 += Mt[j, i, 4] * x[j, 4]
            a5 += Mt[j, i, 5] * x[j, 5]
            a6 += Mt[j, i, 6] * x[j, 6]
            a7 += Mt[j, i, 7] * x[j, 7]
        acc[i, 0], acc[i, 1], acc[i, 2], acc[i, 3] = a0, a1, a2, a3
        acc[i, 4], acc[i, 5], acc[i, 6], acc[i, 7] = a4, a5, a6, a7


@_jit(inline="always", error_model="numpy")
def _force_lanes(x, crv, c1, c2, eps, out, s0, s1, s2, s3):
    """out = N(x) per lane, r = C_r x in the four partial sums of :func:`_dot`."""
    n, nl = x.shape
    for l in range(nl):
        s0[l] = s1[l] = s2[l] = s3[l] = 0.0
    j = 0
    while j + 4 <= n:
        for l in range(nl):
            s0[l] += crv[j, l] * x[j, l]
            s1[l] += crv[j + 1, l] * x[j + 1, l]
            s2[l] += crv[j + 2, l] * x[j + 2, l]
            s3[l] += crv[j + 3, l] * x[j + 3, l]
        j += 4
    while j < n:
        for l in range(nl):
            s0[l] += crv[j, l] * x[j, l]
        j += 1
    for l in range(nl):
        out[l] = friction_torque((s0[l] + s1[l]) + (s2[l] + s3[l]), c1[l], c2[l], eps[l])


@_jit(inline="always", error_model="numpy")
def _propagate_lanes(Ev, x, out, block_diagonal):
    """out = E x per lane (:func:`_propagate`)."""
    n, nl = x.shape
    if block_diagonal:
        for i in range(0, n, 2):
            for l in range(nl):
                x0, x1 = x[i, l], x[i + 1, l]
                out[i, l] = Ev[i, 0, l] * x0 + Ev[i, 1, l] * x1
                out[i + 1, l] = Ev[i + 1, 0, l] * x0 + Ev[i + 1, 1, l] * x1
    else:
        for i in range(n):
            for l in range(nl):
                out[i, l] = 0.0
            for j in range(n):
                for l in range(nl):
                    out[i, l] += Ev[i, j, l] * x[j, l]


@_jit(inline="always", error_model="numpy")
def _energy_lane(Qv, x, qx, l):
    """:func:`_energy` of lane l."""
    n = x.shape[0]
    for i in range(n):
        qx[i, l] = 0.0
    for j in range(n):
        xj = x[j, l]
        for i in range(n):
            qx[i, l] += Qv[j, i, l] * xj
    s0 = s1 = s2 = s3 = 0.0
    j = 0
    while j + 4 <= n:
        s0 += x[j, l] * qx[j, l]
        s1 += x[j + 1, l] * qx[j + 1, l]
        s2 += x[j + 2, l] * qx[j + 2, l]
        s3 += x[j + 3, l] * qx[j + 3, l]
        j += 4
    while j < n:
        s0 += x[j, l] * qx[j, l]
        j += 1
    return 0.5 * ((s0 + s1) + (s2 + s3))


@_jit(error_model="numpy")
def closed_loop_reduced(loop: Loop, reductions: Reductions) -> None:
    """:func:`closed_loop` keeping no history: per case, the reductions of the first
    R output rows o_j (C_o, D_o, D_of), s_j = o_j − red_c[c, j] − red_t[red_tab[j], k, c]
    (the table term only where red_tab[j] >= 0), over every sample k:

        red[c, j] = (max_k |s_j|, max_k red_dir[c] · s_j, 1 + the last k with |s_j| >
                     red_band[j], 0 if none),

    upeak[c, i] = max_k |u_i| (the actuator output of the first upeak.shape[1] inputs), and
    at the samples snap_k[c] (Cs = 1 or C, S) every output row snapO[c, s] and the energy
    snapE[c, s] (S = 0 in snapE: none); red_t (n_tab, 1 or n_t, 1 or C). The cases run in
    groups of :data:`LANES` (:func:`_lanes`), each lane the operations of :func:`closed_loop`
    in the same order: the same bits as its records give, whatever the grouping."""
    nc = loop.x0.shape[0]
    for g in range((nc + LANES - 1) // LANES):
        c0 = g * LANES
        _lanes(c0, min(LANES, nc - c0), loop, reductions)


@_jit(parallel=True, error_model="numpy")
def closed_loop_reduced_parallel(loop: Loop, reductions: Reductions) -> None:
    """:func:`closed_loop_reduced` with the groups spread over threads (bit-identical)."""
    nc = loop.x0.shape[0]
    for g in prange((nc + LANES - 1) // LANES):
        c0 = np.int64(g) * LANES
        _lanes(c0, min(LANES, nc - c0), loop, reductions)


def allocate_records(
    n_t: int,
    n_cases: int,
    n: int,
    m: int,
    p: int,
    record_states: bool,
    r: int = 0,
    energy: bool = False,
):
    """Output arrays (X, Y, Ucmd, U, D, F, O, En, stop) of the kernels, case-major; X has
    time length 0 when the states are not recorded, O when there are no output rows (r = 0),
    En without ``energy``."""
    X = np.empty((n_cases, n_t if record_states else 0, n))
    return (
        X,
        np.empty((n_cases, n_t, p)),
        np.empty((n_cases, n_t, m)),
        np.empty((n_cases, n_t, m)),
        np.empty((n_cases, n_t, m)),
        np.empty((n_cases, n_t)),
        np.empty((n_cases, n_t if r else 0, r)),
        np.empty((n_cases, n_t if energy else 0)),
        np.full(n_cases, -1, dtype=np.int64),
    )
