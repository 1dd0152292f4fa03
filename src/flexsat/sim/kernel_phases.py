"""The phases of one step of the compiled closed loop, each written once for a group of W cases.

Every per-case quantity of :func:`flexsat.sim.kernels.closed_loop` is held as a row of W lanes
(lanes last: ``x[j, l]`` is state j of the group's lane l), and each phase below is the one
definition of its formula for any W: the records kernel runs them with W = 1 (one case), the
reductions kernel with W = :data:`flexsat.sim.kernels.LANES` (independent cases side by side,
the innermost loops over the lanes). Each lane performs the same scalar operations in the same
order whatever W, so a case's numbers do not depend on its group: the bit-identity of the
records and the reductions rests on that. The step they make up, and its equations, are in
the module docstring of :mod:`flexsat.sim.kernels`.

The phases are numba functions inlined into the kernel (``inline="always"``): W is a constant
there, so the lane loops of W = 1 vanish. Only the products with a matrix of rows (the
measurement and output rows, the dense propagator) take a different loop order and layout per
W, to hold eight independent sums in registers (:func:`row_products`, :func:`rows_shape`);
each row is still summed in the order j = 0 .. n − 1.

Formulas shared with the Python loop of :func:`flexsat.sim.engine.simulate` (quantiser,
saturation, actuator, bearing friction) come from :mod:`flexsat.sim.step`, the maneuver
metrics' per-sample terms from :mod:`flexsat.sim.metrics`.
"""

from __future__ import annotations

import numpy as np

from flexsat.sim.kernel_arrays import Loop, cached_jit, case_index
from flexsat.sim.step import actuated, friction_torque, quantised, saturated

__all__ = [
    "actuate",
    "apply_impulses",
    "diverged",
    "energy",
    "fir_derivative",
    "friction",
    "lane_parameters",
    "law",
    "measure",
    "output_rows",
    "propagate",
    "row_count",
    "row_entry",
    "row_products",
    "rows_shape",
]

#: register blocking of :func:`row_products`: eight rows (W = 1) or eight lanes (W = 8)
BLOCK = 8

_inline = cached_jit(inline="always", error_model="numpy")


@_inline
def lane_parameters(
    loop: Loop, cl: np.ndarray, W: int, r: np.ndarray, energy_rows: bool
) -> tuple[np.ndarray, ...]:
    """The per-case arrays of the group's cases ``cl`` (W,) gathered lanes last.

    Returns (Mt, Et, P1v, Dmv, Dmfv, sensv, Dov, Dofv, actv, dstdv, p1f, p2f, crv, c1, c2,
    eps, Qv): Mt the p measurement rows then the first r output rows, Et the dense propagator
    (each a matrix of rows in the layout of :func:`row_products`, :func:`row_entry`) or the
    2×2 blocks (n, 2, W); Qv (n, n, W) with ``energy_rows``, else empty."""
    x0, E, block_diagonal, P1u, P1f, P2f, Cr, fric = loop[:8]
    Cm, Dm, Dmf, sensor = loop.Cm, loop.Dm, loop.Dmf, loop.sensor
    act, dist_std, Co, Do, Dof, Q = loop.act, loop.dist_std, loop.Co, loop.Do, loop.Dof, loop.Q
    n, m, p = x0.shape[1], P1u.shape[2], Cm.shape[1]
    Mt = np.zeros(rows_shape(p + r, n, W))
    Et = np.zeros((n, 2, W) if block_diagonal else rows_shape(n, n, W))
    P1v = np.empty((n, m, W))
    Dmv = np.empty((p, m, W))
    Dmfv = np.empty((p, W))
    sensv = np.empty((p, 4, W))
    Dov = np.empty((r, m, W))
    Dofv = np.empty((r, W))
    actv = np.empty((m, 2, W))
    dstdv = np.empty((m, W))
    has_force = P1f.shape[0] > 0
    p1f = np.zeros((n, W))
    p2f = np.zeros((n, W))
    crv = np.zeros((n, W))
    c1 = np.zeros(W)
    c2 = np.zeros(W)
    eps = np.ones(W)
    Qv = np.empty((n, n, W)) if energy_rows else np.empty((0, 0, W))
    for l in range(W):
        c = cl[l]
        cp, cu, cm = (
            case_index(E.shape[0], c),
            case_index(P1u.shape[0], c),
            case_index(Cm.shape[0], c),
        )
        co = case_index(Co.shape[0], c)
        for j in range(n):
            for i in range(p):
                a, b = row_entry(i, j, n, W)
                Mt[a, b, l] = Cm[cm, i, j]
            for i in range(r):
                a, b = row_entry(p + i, j, n, W)
                Mt[a, b, l] = Co[co, i, j]
            if block_diagonal:  # row j holds the two entries of its 2×2 block
                Et[j, 0, l] = E[cp, j, 0]
                Et[j, 1, l] = E[cp, j, 1]
            else:
                for i in range(n):
                    a, b = row_entry(i, j, n, W)
                    Et[a, b, l] = E[cp, i, j]
            for i in range(m):
                P1v[j, i, l] = P1u[cu, j, i]
        for i in range(p):
            for j in range(m):
                Dmv[i, j, l] = Dm[cm, i, j]
            Dmfv[i, l] = Dmf[cm, i]
            for q in range(4):
                sensv[i, q, l] = sensor[case_index(sensor.shape[0], c), i, q]
        for i in range(r):
            for j in range(m):
                Dov[i, j, l] = Do[co, i, j]
            Dofv[i, l] = Dof[co, i]
        ca, cd = case_index(act.shape[0], c), case_index(dist_std.shape[0], c)
        for i in range(m):
            actv[i, 0, l] = act[ca, i, 0]
            actv[i, 1, l] = act[ca, i, 1]
            dstdv[i, l] = dist_std[cd, i]
        if has_force:
            cf, cfr = case_index(P1f.shape[0], c), case_index(fric.shape[0], c)
            for j in range(n):
                p1f[j, l] = P1f[cf, j]
                p2f[j, l] = P2f[cf, j]
                crv[j, l] = Cr[case_index(Cr.shape[0], c), j]
            c1[l], c2[l], eps[l] = fric[cfr, 0], fric[cfr, 1], fric[cfr, 2]
        if energy_rows:
            cq = case_index(Q.shape[0], c)
            for j in range(n):
                for i in range(n):
                    Qv[j, i, l] = Q[cq, j, i]
    return Mt, Et, P1v, Dmv, Dmfv, sensv, Dov, Dofv, actv, dstdv, p1f, p2f, crv, c1, c2, eps, Qv


@_inline
def apply_impulses(
    x: np.ndarray, imp_k: np.ndarray, imp_dx: np.ndarray, i_imp: int, k: int, cl: np.ndarray, W: int
) -> int:
    """Phase 1: x += Δx of the impulses due at sample k (``imp_k`` ascending from ``i_imp``);
    returns the index of the next impulse."""
    while i_imp < imp_k.shape[0] and imp_k[i_imp] == k:
        for j in range(x.shape[0]):
            for l in range(W):
                x[j, l] += imp_dx[i_imp, case_index(imp_dx.shape[1], cl[l]), j]
        i_imp += 1
    return i_imp


@_inline
def friction(
    x: np.ndarray,
    n: int,
    crv: np.ndarray,
    c1: np.ndarray,
    c2: np.ndarray,
    eps: np.ndarray,
    out: np.ndarray,
    s0: np.ndarray,
    s1: np.ndarray,
    s2: np.ndarray,
    s3: np.ndarray,
    W: int,
) -> None:
    """Phases 2 and 9: out = N(x) = −c1 tanh(r/ε) − c2 r per lane, r = C_r x in four
    interleaved partial sums (s0 .. s3 (W,) scratch): a single chain of dependent additions is
    latency-bound (it was half the cost of a friction substep); x (>= n, W)."""
    if W == 1:  # the partial sums in registers (in memory, a store-load latency per term)
        a0 = a1 = a2 = a3 = 0.0
        j = 0
        while j + 4 <= n:
            a0 += crv[j, 0] * x[j, 0]
            a1 += crv[j + 1, 0] * x[j + 1, 0]
            a2 += crv[j + 2, 0] * x[j + 2, 0]
            a3 += crv[j + 3, 0] * x[j + 3, 0]
            j += 4
        while j < n:
            a0 += crv[j, 0] * x[j, 0]
            j += 1
        s0[0], s1[0], s2[0], s3[0] = a0, a1, a2, a3
    else:  # the lanes innermost: one vector operation per term
        for l in range(W):
            s0[l] = s1[l] = s2[l] = s3[l] = 0.0
        j = 0
        while j + 4 <= n:
            for l in range(W):
                s0[l] += crv[j, l] * x[j, l]
                s1[l] += crv[j + 1, l] * x[j + 1, l]
                s2[l] += crv[j + 2, l] * x[j + 2, l]
                s3[l] += crv[j + 3, l] * x[j + 3, l]
            j += 4
        while j < n:
            for l in range(W):
                s0[l] += crv[j, l] * x[j, l]
            j += 1
    for l in range(W):
        out[l] = friction_torque((s0[l] + s1[l]) + (s2[l] + s3[l]), c1[l], c2[l], eps[l])


@_inline
def rows_shape(R: int, n: int, W: int) -> tuple[int, int, int]:
    """Shape of a matrix of R rows of length n in the layout of :func:`row_products`:
    (n, R, W) for W > 1 (entry (i, j) of lane l at [j, i, l]); for W = 1 the rows in groups
    of :data:`BLOCK` (padded with zero rows), each group a block (n, BLOCK): (g n, BLOCK, 1),
    entry (i, j) at [(i // BLOCK) n + j, i % BLOCK, 0] (:func:`row_entry`)."""
    if W == 1:
        return (R + BLOCK - 1) // BLOCK * n, BLOCK, W
    return n, R, W


@_inline
def row_entry(i: int, j: int, n: int, W: int) -> tuple[int, int]:
    """The first two indices of entry (i, j) (row i, column j) in the layout of
    :func:`rows_shape`."""
    if W == 1:
        return i // BLOCK * n + j, i % BLOCK
    return j, i


@_inline
def row_count(M: np.ndarray, n: int) -> int:
    """Rows of a matrix M in the layout of :func:`rows_shape` (padded for W = 1)."""
    return M.shape[0] // n * M.shape[1]


@_inline
def row_products(Mt: np.ndarray, x: np.ndarray, out: np.ndarray, W: int) -> None:
    """out[i] = Σ_j M[i, j] x[j] per lane, M in the layout of :func:`rows_shape`, each row
    summed in the order j = 0 .. n − 1.

    Eight independent chains of additions in registers, where one row's sum alone is a chain
    of dependent additions: eight rows of the one lane for W = 1 (a block of Mt: the eight
    entries of column j side by side, read from one pointer), the eight lanes of one row for
    W = 8."""
    n = x.shape[0]
    if W == 1:
        for g in range(Mt.shape[0] // n):
            s0 = s1 = s2 = s3 = s4 = s5 = s6 = s7 = 0.0
            for j in range(n):
                xj = x[j, 0]
                jg = g * n + j
                s0 += Mt[jg, 0, 0] * xj
                s1 += Mt[jg, 1, 0] * xj
                s2 += Mt[jg, 2, 0] * xj
                s3 += Mt[jg, 3, 0] * xj
                s4 += Mt[jg, 4, 0] * xj
                s5 += Mt[jg, 5, 0] * xj
                s6 += Mt[jg, 6, 0] * xj
                s7 += Mt[jg, 7, 0] * xj
            i0 = g * BLOCK
            out[i0, 0], out[i0 + 1, 0], out[i0 + 2, 0], out[i0 + 3, 0] = s0, s1, s2, s3
            out[i0 + 4, 0], out[i0 + 5, 0], out[i0 + 6, 0], out[i0 + 7, 0] = s4, s5, s6, s7
    else:
        for i in range(Mt.shape[1]):
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
            out[i, 0], out[i, 1], out[i, 2], out[i, 3] = a0, a1, a2, a3
            out[i, 4], out[i, 5], out[i, 6], out[i, 7] = a4, a5, a6, a7


@_inline
def measure(
    acc: np.ndarray,
    w: np.ndarray,
    f: np.ndarray,
    Dmv: np.ndarray,
    Dmfv: np.ndarray,
    sensv: np.ndarray,
    sensor_slot: np.ndarray,
    noise: np.ndarray,
    cl: np.ndarray,
    k: int,
    y: np.ndarray,
    W: int,
) -> None:
    """Phases 3-4: y_i = sensor(C_m[i] x + D_m[i] w + D_mf[i] f) per lane, C_m x in ``acc``:
    bias, noise std · noise[c, k, slot], quantiser, saturation (:mod:`flexsat.sim.step`)."""
    for i in range(Dmv.shape[0]):
        slot = sensor_slot[i]
        for l in range(W):
            v = acc[i, l]
            for j in range(Dmv.shape[1]):
                v += Dmv[i, j, l] * w[j, l]
            v += Dmfv[i, l] * f[l]
            v += sensv[i, 2, l]
            if slot >= 0:
                v += sensv[i, 1, l] * noise[cl[l], k, slot]
            q = sensv[i, 0, l]
            if q > 0.0:
                v = quantised(v, q)
            y[i, l] = saturated(v, sensv[i, 3, l])


@_inline
def fir_derivative(
    y: np.ndarray,
    hist: np.ndarray,
    head: int,
    k: int,
    src: int,
    dst: int,
    fir_w: np.ndarray,
    W: int,
) -> int:
    """Phase 5: y[dst] = Σ_j c_j v_src(t_{k−L+1+j}) per lane, the ring buffer ``hist`` (L, W)
    started full of the first sample; returns the new ``head`` (its oldest sample)."""
    L = fir_w.shape[0]
    if k == 0:
        for j in range(L):
            for l in range(W):
                hist[j, l] = y[src, l]
    else:
        for l in range(W):
            hist[head, l] = y[src, l]
        head = (head + 1) % L
    for l in range(W):
        v = 0.0
        for j in range(L):
            v += fir_w[j] * hist[(head + j) % L, l]
        y[dst, l] = v
    return head


@_inline
def law(
    Ak: np.ndarray,
    Bk: np.ndarray,
    Ck: np.ndarray,
    Dk: np.ndarray,
    y_ref: np.ndarray,
    u_ff: np.ndarray,
    K0: np.ndarray,
    bound: float,
    k: int,
    y: np.ndarray,
    e: np.ndarray,
    xi: np.ndarray,
    xi_new: np.ndarray,
    ucmd: np.ndarray,
    bad: np.ndarray,
    cl: np.ndarray,
    W: int,
) -> None:
    """Phase 6, the law's linear form per lane, e = y − y_ref[k]: ξ_0 = K0 e_0 (K0 given),
    u_cmd = u_ff[k] + C_k ξ + D_k e, ξ ← A_k ξ + B_k e; bad[l] = a command beyond the bound
    or not finite."""
    p, m, nk = y.shape[0], ucmd.shape[0], xi.shape[0]
    tk, tb = case_index(Ak.shape[0], k), case_index(Bk.shape[0], k)
    tc, td = case_index(Ck.shape[0], k), case_index(Dk.shape[0], k)
    for l in range(W):
        c = cl[l]
        cy = case_index(y_ref.shape[1], c)
        for i in range(p):
            e[i, l] = y[i, l] - y_ref[k, cy, i]
        if k == 0 and K0.shape[0] > 0:
            c0 = case_index(K0.shape[0], c)
            for i in range(nk):
                v = 0.0
                for j in range(p):
                    v += K0[c0, i, j] * e[j, l]
                xi[i, l] = v
        bad[l] = False
        cf, cc, cd = (
            case_index(u_ff.shape[1], c),
            case_index(Ck.shape[1], c),
            case_index(Dk.shape[1], c),
        )
        for i in range(m):
            v = u_ff[k, cf, i]
            for j in range(nk):
                v += Ck[tc, cc, i, j] * xi[j, l]
            for j in range(p):
                v += Dk[td, cd, i, j] * e[j, l]
            ucmd[i, l] = v
            if not abs(v) <= bound:
                bad[l] = True
        ca, cb = case_index(Ak.shape[1], c), case_index(Bk.shape[1], c)
        for i in range(nk):
            v = 0.0
            for j in range(nk):
                v += Ak[tk, ca, i, j] * xi[j, l]
            for j in range(p):
                v += Bk[tb, cb, i, j] * e[j, l]
            xi_new[i, l] = v
        for i in range(nk):
            xi[i, l] = xi_new[i, l]


@_inline
def diverged(x: np.ndarray, bound: float, bad: np.ndarray, W: int) -> None:
    """Phase 7: bad[l] |= some |x_j| beyond ``bound`` or not finite."""
    for j in range(x.shape[0]):
        for l in range(W):
            if not abs(x[j, l]) <= bound:
                bad[l] = True


@_inline
def output_rows(
    acc: np.ndarray,
    p: int,
    w: np.ndarray,
    f: np.ndarray,
    Dov: np.ndarray,
    Dofv: np.ndarray,
    out: np.ndarray,
    W: int,
) -> None:
    """The recorded outputs o_i = C_o[i] x + D_of[i] f + D_o[i] w per lane, C_o x in
    ``acc[p:]``."""
    for i in range(Dov.shape[0]):
        for l in range(W):
            v = acc[p + i, l] + Dofv[i, l] * f[l]
            for j in range(Dov.shape[1]):
                v += Dov[i, j, l] * w[j, l]
            out[i, l] = v


@_inline
def energy(Qv: np.ndarray, x: np.ndarray, qx: np.ndarray, l: int) -> float:
    """½ xᵀ Q x of lane l, v = Q x accumulated column by column (Q symmetric: row j is column
    j; independent element-wise updates the compiler vectorises, where n dot products are each
    a chain of dependent additions: 3× slower at n = 22), then xᵀ v in four partial sums."""
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


@_inline
def actuate(
    ucmd: np.ndarray,
    actv: np.ndarray,
    dstdv: np.ndarray,
    dist_slot: np.ndarray,
    noise: np.ndarray,
    cl: np.ndarray,
    k: int,
    u: np.ndarray,
    d: np.ndarray,
    w: np.ndarray,
    W: int,
) -> None:
    """Phase 8: u = scale · clip(u_cmd, ±sat), d = std · noise[c, k, slot] (0 without a
    slot), the applied input w = u + d per element and lane."""
    for i in range(ucmd.shape[0]):
        slot = dist_slot[i]
        for l in range(W):
            u[i, l] = actuated(ucmd[i, l], actv[i, 0, l], actv[i, 1, l])
            d[i, l] = dstdv[i, l] * noise[cl[l], k, slot] if slot >= 0 else 0.0
            w[i, l] = u[i, l] + d[i, l]


@_inline
def propagate(
    block_diagonal: bool,
    has_force: bool,
    substeps: int,
    x: np.ndarray,
    xa: np.ndarray,
    drive: np.ndarray,
    w: np.ndarray,
    P1v: np.ndarray,
    Et: np.ndarray,
    p1f: np.ndarray,
    p2f: np.ndarray,
    crv: np.ndarray,
    c1: np.ndarray,
    c2: np.ndarray,
    eps: np.ndarray,
    f0: np.ndarray,
    df: np.ndarray,
    s0: np.ndarray,
    s1: np.ndarray,
    s2: np.ndarray,
    s3: np.ndarray,
    W: int,
) -> None:
    """Phase 9: ``substeps`` steps of x' = A x + B w + b_f N(x) with w held, the exponential
    integrator a = E x + P1u w + P1f N(x), x ← a + P2f (N(a) − N(x)) (ETD2RK, Cox & Matthews
    2002 Eq. 22; the exact zero-order hold without a force). E x is dense (:func:`row_products`
    on Et = Eᵀ) or 2×2 block-diagonal; s0 .. s3 (W,) scratch of :func:`friction`."""
    n, m = x.shape[0], w.shape[0]
    if W == 1:  # the sum in a register (in memory: a store and a load per term)
        for i in range(n):
            s = 0.0
            for j in range(m):
                s += P1v[i, j, 0] * w[j, 0]
            drive[i, 0] = s
    else:  # the lanes innermost: one vector operation per term
        for i in range(n):
            for l in range(W):
                drive[i, l] = 0.0
            for j in range(m):
                for l in range(W):
                    drive[i, l] += P1v[i, j, l] * w[j, l]
    fused = block_diagonal and not has_force
    for _ in range(substeps):
        if fused:  # x ← E x + drive in one pass over the 2×2 blocks (the same operations)
            for i in range(0, n, 2):
                for l in range(W):
                    x0, x1 = x[i, l], x[i + 1, l]
                    x[i, l] = (Et[i, 0, l] * x0 + Et[i, 1, l] * x1) + drive[i, l]
                    x[i + 1, l] = (Et[i + 1, 0, l] * x0 + Et[i + 1, 1, l] * x1) + drive[i + 1, l]
            continue
        if block_diagonal:
            for i in range(0, n, 2):
                for l in range(W):
                    x0, x1 = x[i, l], x[i + 1, l]
                    xa[i, l] = Et[i, 0, l] * x0 + Et[i, 1, l] * x1
                    xa[i + 1, l] = Et[i + 1, 0, l] * x0 + Et[i + 1, 1, l] * x1
        else:
            row_products(Et, x, xa, W)
        if has_force:
            friction(x, n, crv, c1, c2, eps, f0, s0, s1, s2, s3, W)
            for i in range(n):
                for l in range(W):
                    xa[i, l] += drive[i, l] + p1f[i, l] * f0[l]
            friction(xa, n, crv, c1, c2, eps, df, s0, s1, s2, s3, W)
            for l in range(W):
                df[l] = df[l] - f0[l]
            for i in range(n):
                for l in range(W):
                    x[i, l] = xa[i, l] + p2f[i, l] * df[l]
        else:
            for i in range(n):
                for l in range(W):
                    x[i, l] = xa[i, l] + drive[i, l]
