r"""Compiled closed loop of a three-axis spacecraft (rigid or flexible) with the cases in lanes.

The sampled-data loop of :func:`flexsat.sim.engine.simulate` for
:class:`~flexsat.dynamics.rigid_spacecraft.RigidSpacecraft` and
:class:`~flexsat.dynamics.flexible_spacecraft.FlexibleSpacecraft` plants (and batches of
them), as the hub kernels of :mod:`flexsat.sim.kernels` run it for linear plants: at each
sample k, for each case,

1. impulses z += Δz_k;
2. measurement y = C_m z + D_m w_{k−1} and the sensor model per element (bias, noise,
   quantiser, saturation: :func:`flexsat.sim.kernel_phases.measure`);
3. the law: its linear form (:func:`flexsat.sim.kernel_phases.law`) or an attitude law of
   :mod:`flexsat.control.attitude_laws` on the measured attitude β_m = y[0:4] and rate
   ω_m = y[4:7], with the error quaternion e = β_m ⊗ β_t* (Schaub & Junkins Eq. 3.105):

   * MRP PD (Schaub & Junkins §8.3 Eq. 8.16): u = −K σ − P ω, σ = e_v / (1 + e_0) on the
     short rotation (e_0 >= 0);
   * quaternion PD (Wie, Weiss & Arapostathis 1989): u = −K_p e_v − K_d (ω − ω_ref), e_0 >= 0;
   * Gibbs Lyapunov law (Junkins, Pollock & Rahman 1990, Att. 3 Eq. 4):
     u = −[k ω + A q (1 + qᵀq)], q = e_v / e_0 (a lane with |e_0| below the singular
     tolerance stops: the engine then reruns the Python loop, which refuses it by name);

4. divergence check of the state and command (|·| beyond ``bound`` or not finite stops the
   case), records (state, measurements, commands), or in their place the channel metrics
   accumulated sample by sample (:class:`AttitudeMetrics`: running peaks of the outputs'
   norms, last values, sums of squares of the inputs' norms, the pointing error's last
   sample outside the band; no history);
5. actuator and random disturbance (:func:`flexsat.sim.kernel_phases.actuate`);
6. ``substeps`` steps of h = dt / substeps with the input held:

   * rigid (``kind`` 0): the RKMK4 step of :func:`flexsat.dynamics.rigid_body.rkmk4_step`
     (Munthe-Kaas 1999) on (β, ω) with Euler's equations I ω' = u − ω × I ω, then β scaled to
     unit norm (the engine's ``plant.normalize`` after the plant's own step); each stage one
     pass over the lanes (vectorised), the coefficients of dexpinv and of exp(θ) by their
     series for small angles, decided per lane, libm's tan, cos and sinc only for a lane
     beyond them (:func:`flexsat.sim.kernels_rigid.rigid_steps`);
   * flexible (``kind`` 1): Krogstad's fourth-order exponential Runge-Kutta scheme
     (J. Comput. Phys. 203, 2005, Eq. 20; :class:`flexsat.sim.integrators.ExpRK4Stepper`) in
     the modal coordinates z of :func:`flexsat.sim.spacecraft_modal.spacecraft_modal_form`:
     the linear part is block-diagonal there (β0 a 1×1 block, the three rigid rotations and
     the elastic modes 2×2 blocks: O(n) per step), and the force
     f(z) = [Ω(ω)β − (0, ω/2), −ω × h] (the plant's ``nonlinear_force``) is evaluated from
     β, ω read off z by the rows R and h = J ω_r, ω_r the rigid-rotation rates of z (exact:
     h = J ω + Δᵀ η̇ and ω_r = ω + J⁻¹ Δᵀ η̇). The force columns of β act on the first seven
     coordinates only (exact zeros elsewhere), those of ω on all.

The cases run in groups of :data:`flexsat.sim.kernels.LANES` lanes (the lanes innermost; the
lanes past the batch repeat its last case). A shared plant's propagators (E2, E, F, R: one
set, leading axis 1) are read by every lane from the one copy, each entry broadcast over the
lanes (:func:`coefficient`, :func:`lane_rows`); a dispersed plant's are gathered per lane. The
sums are the same either way, in the same order. Each lane performs the same scalar operations
whatever its group or neighbours, serially or in parallel, so a case's records are bit for
bit those of the case run alone.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import prange
from numba.extending import overload

from flexsat.sim.kernel_arrays import cached_jit, case_index
from flexsat.sim.kernel_phases import (
    actuate,
    apply_impulses,
    law,
    measure,
    row_count,
    row_entry,
    row_products,
    rows_shape,
)
from flexsat.sim.kernels_rigid import rigid_steps
from flexsat.sim.spacecraft_modal import HEAD

__all__ = [
    "ATTITUDE_LAWS",
    "AttitudeLoop",
    "AttitudeMetrics",
    "AttitudeRecords",
    "attitude_loop",
    "attitude_loop_parallel",
]

#: cases side by side in a group (the lanes of the vector operations)
LANES = 8
#: the law codes of :class:`AttitudeLoop` ``law_kind``: 0 the linear form, then these laws
ATTITUDE_LAWS = {"MRPLaw": 1, "QuaternionPD": 2, "GibbsLyapunovLaw": 3}

_inline = cached_jit(inline="always", error_model="numpy")


def coefficient(A: np.ndarray, i: int, j: int, l: int) -> float:
    """Entry (i, j) of lane l of a propagator matrix: ``A[i, j, l]`` of the lanes' own copies
    (lanes last, a dispersed plant) or ``A[i, j]`` of the one matrix all lanes share (a
    shared plant: read once per row and broadcast over the lanes, where the lanes' copies of
    the EPS's F alone fill 217 kB of cache per group). Compiled per array rank
    (:func:`_coefficient`); the same number either way."""
    return A[i, j, l] if A.ndim == 3 else A[i, j]


@overload(coefficient)
def _coefficient(A, i, j, l):
    if A.ndim == 3:
        return lambda A, i, j, l: A[i, j, l]
    return lambda A, i, j, l: A[i, j]


def lane_rows(R: np.ndarray, z: np.ndarray, out: np.ndarray, W: int) -> None:
    """out[i] = Σ_j R[i, j] z[j] per lane, summed in the order j = 0 .. n − 1: R in the
    lanes' layout of :func:`~flexsat.sim.kernel_phases.row_products` (three axes), or the one
    (rows, n) matrix all lanes share (two axes: each entry read once and broadcast over the
    lanes, the lanes' sums side by side). The same sums either way (:func:`_lane_rows`)."""
    if R.ndim == 3:
        row_products(R, z, out, W)
        return
    for i in range(R.shape[0]):
        out[i] = R[i] @ z


@overload(lane_rows)
def _lane_rows(R, z, out, W):
    if R.ndim == 3:
        return lambda R, z, out, W: row_products(R, z, out, W)

    def shared(R, z, out, W):  # the eight lanes' sums in registers (W = LANES = 8)
        n = z.shape[0]
        for i in range(R.shape[0]):
            a0 = a1 = a2 = a3 = a4 = a5 = a6 = a7 = 0.0
            for j in range(n):
                r = R[i, j]
                a0 += r * z[j, 0]
                a1 += r * z[j, 1]
                a2 += r * z[j, 2]
                a3 += r * z[j, 3]
                a4 += r * z[j, 4]
                a5 += r * z[j, 5]
                a6 += r * z[j, 6]
                a7 += r * z[j, 7]
            out[i, 0], out[i, 1], out[i, 2], out[i, 3] = a0, a1, a2, a3
            out[i, 4], out[i, 5], out[i, 6], out[i, 7] = a4, a5, a6, a7

    return shared


def input_products(
    Q1u: np.ndarray, P1u: np.ndarray, w: np.ndarray, hd: np.ndarray, fd: np.ndarray, W: int
) -> None:
    """hd = Q1u w, fd = P1u w per lane, each sum in the order j = 0 .. m − 1 from 0: Q1u, P1u
    the lanes' own copies (n, m, W) or the one (n, m) pair all lanes share (each entry read
    once and broadcast over the lanes, the eight lanes' sums in registers). The same sums
    either way (:func:`_input_products`)."""
    for i in range(hd.shape[0]):
        for l in range(W):
            s, t = 0.0, 0.0
            for j in range(w.shape[0]):
                s += coefficient(Q1u, i, j, l) * w[j, l]
                t += coefficient(P1u, i, j, l) * w[j, l]
            hd[i, l], fd[i, l] = s, t


@overload(input_products)
def _input_products(Q1u, P1u, w, hd, fd, W):
    if Q1u.ndim == 3:

        def own(Q1u, P1u, w, hd, fd, W):
            for i in range(hd.shape[0]):
                for l in range(W):
                    s, t = 0.0, 0.0
                    for j in range(w.shape[0]):
                        s += Q1u[i, j, l] * w[j, l]
                        t += P1u[i, j, l] * w[j, l]
                    hd[i, l], fd[i, l] = s, t

        return own

    def shared(Q1u, P1u, w, hd, fd, W):  # W = LANES = 8
        for i in range(hd.shape[0]):
            a0 = a1 = a2 = a3 = a4 = a5 = a6 = a7 = 0.0
            b0 = b1 = b2 = b3 = b4 = b5 = b6 = b7 = 0.0
            for j in range(w.shape[0]):
                q, r = Q1u[i, j], P1u[i, j]
                a0 += q * w[j, 0]
                a1 += q * w[j, 1]
                a2 += q * w[j, 2]
                a3 += q * w[j, 3]
                a4 += q * w[j, 4]
                a5 += q * w[j, 5]
                a6 += q * w[j, 6]
                a7 += q * w[j, 7]
                b0 += r * w[j, 0]
                b1 += r * w[j, 1]
                b2 += r * w[j, 2]
                b3 += r * w[j, 3]
                b4 += r * w[j, 4]
                b5 += r * w[j, 5]
                b6 += r * w[j, 6]
                b7 += r * w[j, 7]
            hd[i, 0], hd[i, 1], hd[i, 2], hd[i, 3] = a0, a1, a2, a3
            hd[i, 4], hd[i, 5], hd[i, 6], hd[i, 7] = a4, a5, a6, a7
            fd[i, 0], fd[i, 1], fd[i, 2], fd[i, 3] = b0, b1, b2, b3
            fd[i, 4], fd[i, 5], fd[i, 6], fd[i, 7] = b4, b5, b6, b7

    return shared


class AttitudeLoop(NamedTuple):
    """The parameters of the three-axis loop (module docstring). Leading axes of length 1
    (shared) or C (per case) unless stated.

    x0 (C, n) initial state (kernel coordinates); kind 0 rigid, 1 modal; substeps; h step (s);
    J, Jinv (Cj, 3, 3) inertia and inverse; E2, E (Cp, n, 2) e^{hA/2}, e^{hA} by 2×2 blocks
    (row 0: β0, [1, 0]); Q1u, P1u (Cp, n, m) input integrals at h/2 and h; F (Cp, 5, n, 7)
    Q1f, Q2f, P1f, P2f, P3f of :class:`~flexsat.sim.integrators.ExpRK4Stepper` in z;
    R (Cp, 6, n) β_v and ω from z; imp_k (ni,), imp_dx (ni, Ci, n) impulses; Cm, Dm (Cm, p, n),
    (Cm, p, m) measurement; sensor (Cs, p, 4), sensor_slot (p,); law_kind; the linear form
    Ak .. K0 (:class:`~flexsat.sim.kernel_arrays.Loop`); gains (Cg, 7) [scalar gain, three
    rate or attitude gains, three rate gains], target (Cg, 4), w_ref (Cg, 3); act (Ca, m, 2),
    dist_std (Cd, m), dist_slot (m,), noise (C, n_t, slots), bound, singular (the Gibbs law's
    tolerance on |e_0|).
    """

    x0: np.ndarray
    kind: int
    substeps: int
    h: float
    J: np.ndarray
    Jinv: np.ndarray
    E2: np.ndarray
    E: np.ndarray
    Q1u: np.ndarray
    P1u: np.ndarray
    F: np.ndarray
    R: np.ndarray
    imp_k: np.ndarray
    imp_dx: np.ndarray
    Cm: np.ndarray
    Dm: np.ndarray
    sensor: np.ndarray
    sensor_slot: np.ndarray
    law_kind: int
    Ak: np.ndarray
    Bk: np.ndarray
    Ck: np.ndarray
    Dk: np.ndarray
    y_ref: np.ndarray
    u_ff: np.ndarray
    K0: np.ndarray
    gains: np.ndarray
    target: np.ndarray
    w_ref: np.ndarray
    act: np.ndarray
    dist_std: np.ndarray
    dist_slot: np.ndarray
    noise: np.ndarray
    bound: float
    singular: float


class AttitudeRecords(NamedTuple):
    """What :func:`attitude_loop` writes, case-major: X (C, n_t, n) the states in kernel
    coordinates, Y (C, n_t, p_rec) the last p_rec measurements, Ucmd, U, D (C, n_t, m)
    commands, actuator outputs, disturbances, stop (C,) −1 or the sample where the case
    stopped (diverged, or a singular Gibbs error)."""

    X: np.ndarray
    Y: np.ndarray
    Ucmd: np.ndarray
    U: np.ndarray
    D: np.ndarray
    stop: np.ndarray


class AttitudeMetrics(NamedTuple):
    """The channel metrics accumulated in the loop in place of the records (``n_t`` > 0; 0:
    the records of :class:`AttitudeRecords`, the other arrays unused).

    n_t samples; the output rows over the kernel coordinates (the flexible plant's first seven
    the rows T[:7] of β and ω, then the linear outputs' rows): row i is the measurement row
    at[i] (< p) where that is the same row, else row at[i] − p of Ot (Co, r, n), summed after
    the measurement rows; Do (Co, rows, m) their feedthrough of the input held before the
    sample (no columns: zero); chan (q, 3) [kind, lo, width] per channel: kind 0 the linear
    output rows lo .. lo + width − 1, 1 the rate ω, 2 the 1-2-3 Euler angles
    of β, 3 the MRP of β, 4 the actuator outputs u[lo : lo + width]; target (Ct, 4) the law's
    target attitude (Ct = 0: none); cos_band cos(band / 2), band the settling band (rad).
    Outputs per case: peak (C, q) the largest norm over the samples (|v| of a scalar),
    final (C, q) a scalar channel's last value, sumsq (C, q) the sum of the squared norms,
    beta_end (C, 4) β at the last sample, after (C,) the index just after the last sample
    whose pointing error 2 arccos|e_0| exceeds the band (0 when none does)."""

    n_t: int
    Ot: np.ndarray
    at: np.ndarray
    Do: np.ndarray
    chan: np.ndarray
    target: np.ndarray
    cos_band: float
    band: float
    peak: np.ndarray
    final: np.ndarray
    sumsq: np.ndarray
    beta_end: np.ndarray
    after: np.ndarray


@_inline
def _gather(loop, red, cl, W):
    """The per-case arrays of the lanes ``cl``, lanes last; the measurement rows followed by
    the output rows ``red.Ot`` (none on the records path) in one matrix of rows."""
    n, m, p = loop.x0.shape[1], loop.P1u.shape[2], loop.Cm.shape[1]
    r = red.Ot.shape[1] if red.n_t > 0 else 0
    modal = loop.kind == 1
    nm = n if modal else 0
    own = modal and loop.E.shape[0] > 1  # each lane its own E2, E, F (a dispersed plant)
    no = n if own else 0
    Mt = np.zeros(rows_shape(p + r, n, W))
    Dmv = np.empty((p, m, W))
    rf = red.Do.shape[1] if red.n_t > 0 else 0  # the output rows' feedthrough
    mf = red.Do.shape[2] if red.n_t > 0 else 0  # no columns: no feedthrough
    Dov = np.empty((rf, mf, W))
    sensv = np.empty((p, 4, W))
    J = np.empty((3, 3, W))
    Jinv = np.empty((3, 3, W))
    E2 = np.empty((no, 2, W))
    E = np.empty((no, 2, W))
    Q1u = np.empty((nm, m, W))
    P1u = np.empty((nm, m, W))
    F = np.empty((5, no, 7, W))
    R = np.zeros(rows_shape(6, no, W))
    gains = np.empty((7, W))
    target = np.empty((4, W))
    w_ref = np.empty((3, W))
    actv = np.empty((m, 2, W))
    dstdv = np.empty((m, W))
    for l in range(W):
        c = cl[l]
        cm, cj = case_index(loop.Cm.shape[0], c), case_index(loop.J.shape[0], c)
        cs = case_index(loop.sensor.shape[0], c)
        for j in range(n):
            for i in range(p):
                a, b = row_entry(i, j, n, W)
                Mt[a, b, l] = loop.Cm[cm, i, j]
        if r > 0:
            co = case_index(red.Ot.shape[0], c)
            for j in range(n):
                for i in range(r):
                    a, b = row_entry(p + i, j, n, W)
                    Mt[a, b, l] = red.Ot[co, i, j]
        if rf > 0 and mf > 0:
            cf = case_index(red.Do.shape[0], c)
            for i in range(rf):
                for j in range(mf):
                    Dov[i, j, l] = red.Do[cf, i, j]
        for i in range(p):
            for j in range(m):
                Dmv[i, j, l] = loop.Dm[cm, i, j]
            for q in range(4):
                sensv[i, q, l] = loop.sensor[cs, i, q]
        for i in range(3):
            for j in range(3):
                J[i, j, l] = loop.J[cj, i, j]
                Jinv[i, j, l] = loop.Jinv[cj, i, j]
        if modal:
            cp = case_index(loop.E.shape[0], c)
            for i in range(n):
                for j in range(m):
                    Q1u[i, j, l] = loop.Q1u[cp, i, j]
                    P1u[i, j, l] = loop.P1u[cp, i, j]
                if own:
                    for s in range(6):
                        a, b = row_entry(s, i, n, W)
                        R[a, b, l] = loop.R[cp, s, i]
                    for j in range(2):
                        E2[i, j, l] = loop.E2[cp, i, j]
                        E[i, j, l] = loop.E[cp, i, j]
                    for s in range(5):
                        for j in range(7):
                            F[s, i, j, l] = loop.F[cp, s, i, j]
        cg = case_index(loop.gains.shape[0], c)
        for i in range(7):
            gains[i, l] = loop.gains[cg, i]
        for i in range(4):
            target[i, l] = loop.target[case_index(loop.target.shape[0], c), i]
        for i in range(3):
            w_ref[i, l] = loop.w_ref[case_index(loop.w_ref.shape[0], c), i]
        ca, cd = case_index(loop.act.shape[0], c), case_index(loop.dist_std.shape[0], c)
        for i in range(m):
            actv[i, 0, l] = loop.act[ca, i, 0]
            actv[i, 1, l] = loop.act[ca, i, 1]
            dstdv[i, l] = loop.dist_std[cd, i]
    return Mt, Dmv, Dov, sensv, J, Jinv, E2, E, Q1u, P1u, F, R, gains, target, w_ref, actv, dstdv


@_inline
def attitude_law(
    kind: int,
    y: np.ndarray,
    gains: np.ndarray,
    target: np.ndarray,
    w_ref: np.ndarray,
    singular: float,
    ucmd: np.ndarray,
    bad: np.ndarray,
    W: int,
) -> None:
    """Phase 3 for an attitude law (module docstring) on y[0:4] (β) and y[4:7] (ω) per lane;
    bad[l] set for a singular Gibbs error."""
    for l in range(W):
        b0, b1, b2, b3 = y[0, l], y[1, l], y[2, l], y[3, l]
        r0, r1, r2, r3 = target[0, l], target[1, l], target[2, l], target[3, l]
        # e = β ⊗ r* (attitude_laws._error)
        e0 = b0 * r0 + (b1 * r1 + b2 * r2 + b3 * r3)
        e1 = (r0 * b1 - b0 * r1) + (b2 * r3 - b3 * r2)
        e2 = (r0 * b2 - b0 * r2) + (b3 * r1 - b1 * r3)
        e3 = (r0 * b3 - b0 * r3) + (b1 * r2 - b2 * r1)
        w0, w1, w2 = y[4, l], y[5, l], y[6, l]
        if kind == 3:
            bad[l] = not abs(e0) >= singular
            g = 1.0 / e0 if not bad[l] else 0.0
            q0, q1, q2 = e1 * g, e2 * g, e3 * g
            s = gains[0, l] * (1.0 + (q0 * q0 + q1 * q1 + q2 * q2))
            ucmd[0, l] = -(gains[1, l] * w0 + s * q0)
            ucmd[1, l] = -(gains[2, l] * w1 + s * q1)
            ucmd[2, l] = -(gains[3, l] * w2 + s * q2)
            continue
        if e0 < 0.0:  # the short rotation
            e0, e1, e2, e3 = -e0, -e1, -e2, -e3
        if kind == 1:
            g = gains[0, l] / (1.0 + e0)
            ucmd[0, l] = -(g * e1 + gains[1, l] * w0)
            ucmd[1, l] = -(g * e2 + gains[2, l] * w1)
            ucmd[2, l] = -(g * e3 + gains[3, l] * w2)
        else:
            ucmd[0, l] = -(gains[1, l] * e1 + gains[4, l] * (w0 - w_ref[0, l]))
            ucmd[1, l] = -(gains[2, l] * e2 + gains[5, l] * (w1 - w_ref[1, l]))
            ucmd[2, l] = -(gains[3, l] * e3 + gains[6, l] * (w2 - w_ref[2, l]))


@_inline
def reduce_outputs(kind, x, acc, w, Dov, red, tgt, hv, pk, fin, after, k, W):
    """The channel metrics of sample k per lane (:class:`AttitudeMetrics`): the outputs'
    norms' running peaks and last values, the pointing error's last sample outside the band.
    β, ω (copied to ``hv`` (7, W)) are x[0:7] (rigid) or the first seven output rows
    (modal); output row i is ``acc[red.at[i]]`` (a measurement row where one is the same
    row, else one of the rows ``red.Ot`` summed after them); a linear channel is its rows
    plus the feedthrough of w, the input held before the sample (as the recorder's outputs;
    ``Dov`` has no columns when it is zero). A vector channel's squares are summed in
    NumPy's order of ``norm(axis=-1)``."""
    for i in range(7):
        for l in range(W):
            hv[i, l] = acc[red.at[i], l] if kind == 1 else x[i, l]
    for q in range(red.chan.shape[0]):
        ck, lo, width = red.chan[q, 0], red.chan[q, 1], red.chan[q, 2]
        if ck == 0 and width == 1:  # a scalar linear channel, lanes innermost
            row = red.at[lo]
            for l in range(W):
                v = acc[row, l]
                for j in range(Dov.shape[1]):
                    v += Dov[lo, j, l] * w[j, l]
                fin[q, l] = v
                nv = abs(v)
                if k == 0 or nv > pk[q, l]:
                    pk[q, l] = nv
        elif ck == 0:
            for l in range(W):
                s = 0.0
                for i in range(width):
                    v = acc[red.at[lo + i], l]
                    for j in range(Dov.shape[1]):
                        v += Dov[lo + i, j, l] * w[j, l]
                    s = v * v if i == 0 else s + v * v
                nv = np.sqrt(s)
                if k == 0 or nv > pk[q, l]:
                    pk[q, l] = nv
        elif ck == 1:
            for l in range(W):
                v0, v1, v2 = hv[4, l], hv[5, l], hv[6, l]
                nv = np.sqrt((v0 * v0 + v1 * v1) + v2 * v2)
                if k == 0 or nv > pk[q, l]:
                    pk[q, l] = nv
        elif ck == 2 or ck == 3:
            for l in range(W):
                b0, b1, b2, b3 = hv[0, l], hv[1, l], hv[2, l], hv[3, l]
                if ck == 2:  # rigid_spacecraft.attitude_output("euler123"): dcm(β), Table B.1
                    c00 = b0 * b0 + b1 * b1 - b2 * b2 - b3 * b3
                    c10 = 2 * (b1 * b2 - b0 * b3)
                    c20 = 2 * (b1 * b3 + b0 * b2)
                    c21 = 2 * (b2 * b3 - b0 * b1)
                    c22 = b0 * b0 - b1 * b1 - b2 * b2 + b3 * b3
                    v0 = np.arctan2(-c21, c22)
                    v1 = np.arctan2(c20, np.hypot(c00, c10))
                    v2 = np.arctan2(-c10, c00)
                else:  # "mrp": β_v / (1 + β0) with β0 >= 0
                    if b0 < 0:
                        b0, b1, b2, b3 = -b0, -b1, -b2, -b3
                    v0, v1, v2 = b1 / (1 + b0), b2 / (1 + b0), b3 / (1 + b0)
                nv = np.sqrt((v0 * v0 + v1 * v1) + v2 * v2)
                if k == 0 or nv > pk[q, l]:
                    pk[q, l] = nv
    if tgt.shape[0] == 0:
        return
    for l in range(W):
        b0, b1, b2, b3 = hv[0, l], hv[1, l], hv[2, l], hv[3, l]
        # |β · β_t| (metrics.channel_metrics), 2 arccos of it against the band; arccos only
        # where e0 is within 1e-12 of cos(band / 2) (elsewhere the comparison decides)
        e0 = abs(((b0 * tgt[0, l] + b1 * tgt[1, l]) + b2 * tgt[2, l]) + b3 * tgt[3, l])
        if e0 < red.cos_band - 1e-12:
            out = True
        elif e0 > red.cos_band + 1e-12:
            out = False
        else:
            out = 2.0 * np.arccos(min(e0, 1.0)) > red.band
        if out:
            after[l] = k + 1


@_inline
def reduce_inputs(red, u, pk, ss, k, W):
    """The actuator outputs' norms' running peaks and sums of squares at sample k."""
    for q in range(red.chan.shape[0]):
        if red.chan[q, 0] != 4:
            continue
        lo, width = red.chan[q, 1], red.chan[q, 2]
        for l in range(W):
            if width == 1:
                nv = abs(u[lo, l])
            else:
                s = u[lo, l] * u[lo, l]
                for i in range(1, width):
                    s += u[lo + i, l] * u[lo + i, l]
                nv = np.sqrt(s)
            if k == 0 or nv > pk[q, l]:
                pk[q, l] = nv
            ss[q, l] = nv * nv if k == 0 else ss[q, l] + nv * nv


@_inline
def modal_force(
    z: np.ndarray, R: np.ndarray, J: np.ndarray, f: np.ndarray, acc: np.ndarray, W: int
) -> None:
    """f(z) (7, W) of the flexible plant (module docstring): β_v, ω by the rows R
    (:func:`lane_rows`), h = J ω_r with ω_r = z[2], z[4], z[6]; ``acc`` scratch of the row
    sums."""
    lane_rows(R, z, acc, W)
    for l in range(W):
        a0, a1, a2 = acc[0, l], acc[1, l], acc[2, l]
        b0, w0, w1, w2 = z[0, l], acc[3, l], acc[4, l], acc[5, l]
        r0, r1, r2 = z[2, l], z[4, l], z[6, l]
        h0 = J[0, 0, l] * r0 + J[0, 1, l] * r1 + J[0, 2, l] * r2
        h1 = J[1, 0, l] * r0 + J[1, 1, l] * r1 + J[1, 2, l] * r2
        h2 = J[2, 0, l] * r0 + J[2, 1, l] * r1 + J[2, 2, l] * r2
        # Ω(ω) β − (0, ω/2) (rigid_spacecraft.omega: the ½ included)
        f[0, l] = -0.5 * (w0 * a0 + w1 * a1 + w2 * a2)
        f[1, l] = 0.5 * (w0 * b0 + w2 * a1 - w1 * a2) - 0.5 * w0
        f[2, l] = 0.5 * (w1 * b0 - w2 * a0 + w0 * a2) - 0.5 * w1
        f[3, l] = 0.5 * (w2 * b0 + w1 * a0 - w0 * a1) - 0.5 * w2
        f[4, l] = -(w1 * h2 - w2 * h1)
        f[5, l] = -(w2 * h0 - w0 * h2)
        f[6, l] = -(w0 * h1 - w1 * h0)


@_inline
def _linear_stage(out, E, z, base, Fs, g, W):
    """out = e^{τA} z + base + F_s g per lane, in one pass: e^{τA} by its 2×2 blocks (row 0,
    β0, unchanged by the linear part), the force columns of β on the first
    :data:`~flexsat.sim.spacecraft_modal.HEAD` rows, those of ω on all."""
    n = z.shape[0]
    for l in range(W):
        out[0, l] = z[0, l] + base[0, l]
    for i in range(1, n, 2):
        for l in range(W):
            z0, z1 = z[i, l], z[i + 1, l]
            out[i, l] = (coefficient(E, i, 0, l) * z0 + coefficient(E, i, 1, l) * z1) + base[i, l]
            out[i + 1, l] = (
                coefficient(E, i + 1, 0, l) * z0 + coefficient(E, i + 1, 1, l) * z1
            ) + base[i + 1, l]
    _add_force(out, Fs, g, W)


@_inline
def _force_stage(out, base, Fs, g, W):
    """out = base + F_s g per lane (:func:`_linear_stage` without the linear part)."""
    n = out.shape[0]
    for i in range(n):
        for l in range(W):
            out[i, l] = base[i, l] + (
                (coefficient(Fs, i, 4, l) * g[4, l] + coefficient(Fs, i, 5, l) * g[5, l])
                + coefficient(Fs, i, 6, l) * g[6, l]
            )
    for i in range(HEAD):
        for j in range(4):
            for l in range(W):
                out[i, l] += coefficient(Fs, i, j, l) * g[j, l]


@_inline
def _add_force(out, Fs, g, W):
    """out += F_s g per lane: the β columns on the first
    :data:`~flexsat.sim.spacecraft_modal.HEAD` rows, ω's on all."""
    n = out.shape[0]
    for i in range(HEAD):
        for j in range(4):
            for l in range(W):
                out[i, l] += coefficient(Fs, i, j, l) * g[j, l]
    for i in range(n):
        for l in range(W):
            out[i, l] += (
                coefficient(Fs, i, 4, l) * g[4, l] + coefficient(Fs, i, 5, l) * g[5, l]
            ) + coefficient(Fs, i, 6, l) * g[6, l]


@_inline
def modal_steps(
    z: np.ndarray,
    w: np.ndarray,
    E2: np.ndarray,
    E: np.ndarray,
    Q1u: np.ndarray,
    P1u: np.ndarray,
    F: np.ndarray,
    R: np.ndarray,
    J: np.ndarray,
    substeps: int,
    work: np.ndarray,
    g: np.ndarray,
    acc: np.ndarray,
    W: int,
) -> None:
    """Phase 6, flexible: ``substeps`` steps of Krogstad's scheme (module docstring) with w
    held: a = e^{hA/2} z + Q1u w + Q1f f(z), b = a + Q2f (f(a) − f(z)),
    c = e^{hA} z + P1u w + P1f f(z) + P2f 2 (f(b) − f(z)),
    z ← e^{hA} z + P1u w + P1f f(z) + P2f (−3 f(z) + 2 f(a) + 2 f(b) − f(c))
    + P3f 4 (f(z) − f(a) − f(b) + f(c)). Scratch: ``work`` (9, n, W) (n >= 7: rows 5 .. 8
    hold the forces), ``g`` (7, W), ``acc`` (8, W)."""
    hd, fd, a, b, full, fx = work[0], work[1], work[2], work[3], work[4], work[5]
    fa, fb, fc = work[6, :7], work[7, :7], work[8, :7]
    input_products(Q1u, P1u, w, hd, fd, W)
    f0 = fx[:7]
    for _ in range(substeps):
        modal_force(z, R, J, f0, acc, W)
        _linear_stage(a, E2, z, hd, F[0], f0, W)
        modal_force(a, R, J, fa, acc, W)
        for j in range(7):
            for l in range(W):
                g[j, l] = fa[j, l] - f0[j, l]
        _force_stage(b, a, F[1], g, W)
        modal_force(b, R, J, fb, acc, W)
        _linear_stage(full, E, z, fd, F[2], f0, W)
        for j in range(7):
            for l in range(W):
                g[j, l] = 2.0 * (fb[j, l] - f0[j, l])
        _force_stage(b, full, F[3], g, W)  # c, in b's place (b is not read again)
        modal_force(b, R, J, fc, acc, W)
        for j in range(7):
            for l in range(W):
                g[j, l] = -3.0 * f0[j, l] + 2.0 * fa[j, l] + 2.0 * fb[j, l] - fc[j, l]
        _force_stage(z, full, F[3], g, W)
        for j in range(7):
            for l in range(W):
                g[j, l] = 4.0 * (f0[j, l] - fa[j, l] - fb[j, l] + fc[j, l])
        _add_force(z, F[4], g, W)


@cached_jit(error_model="numpy")
def _group(c0, nl, loop, rec, red, W):
    """Cases c0 .. c0 + nl − 1 as W = :data:`LANES` lanes (the lanes past nl repeat the last
    case): the step of the module docstring.

    W is an argument, not the constant, on purpose: with a known trip count of 8 LLVM unrolls
    the loops over the lanes and then cannot pack them into vectors (it cannot prove the
    arrays apart); with a trip count known only at run time it vectorises them across the
    lanes behind a run-time overlap check (measured: the flexible step of a shared plant 1.26
    -> 0.87 µs per lane-substep, ``benchmarks/bench_attitude.py --step``). The same
    operations in the same order either way (no fast-math): the numbers do not change."""
    X, Y, Ucmd, U, D, stop = rec
    metrics = red.n_t > 0  # the channel metrics in place of the records
    n_t, n = red.n_t if metrics else Y.shape[1], loop.x0.shape[1]
    m, p, nk = loop.P1u.shape[2], loop.Cm.shape[1], loop.Ak.shape[2]
    p_rec = Y.shape[2]
    cl = np.empty(W, np.int64)
    for l in range(W):
        cl[l] = c0 + min(l, nl - 1)
    (Mt, Dmv, Dov, sensv, J, Jinv, E2, E, Q1u, P1u, F, R, gains, target, w_ref, actv, dstdv) = (
        _gather(loop, red, cl, W)
    )
    nq = red.chan.shape[0] if metrics else 0
    pk = np.zeros((nq, W))
    fin = np.zeros((nq, W))
    ss = np.zeros((nq, W))
    after = np.zeros(W, np.int64)
    hv = np.empty((7, W))  # β, ω of the sample
    tgt = np.empty((4, W if metrics and red.target.shape[0] > 0 else 0))
    for l in range(tgt.shape[1]):
        for i in range(4):
            tgt[i, l] = red.target[case_index(red.target.shape[0], cl[l]), i]
    x = np.empty((n, W))
    for l in range(W):
        stop[cl[l]] = -1
        for j in range(n):
            x[j, l] = loop.x0[cl[l], j]
    work = np.empty((9, n, W))
    rs = np.empty((32, W))  # the rigid step's stages
    g = np.empty((7, W))
    acc6 = np.empty((8, W))  # row sums of R (padded to a block of 8 for W = 1)
    acc = np.empty((row_count(Mt, n), W))
    # one matrix of rows all lanes share (measurement and output rows of a shared plant):
    # each entry read once and broadcast over the lanes (:func:`lane_rows`), the same sums as
    # the lanes' own copies Mt
    r_out = red.Ot.shape[1] if metrics else 0
    one = loop.Cm.shape[0] == 1 and (r_out == 0 or red.Ot.shape[0] == 1) and W == LANES
    Ms = np.empty((p + r_out if one else 0, n))
    for j in range(Ms.shape[1] if one else 0):
        for i in range(p):
            Ms[i, j] = loop.Cm[0, i, j]
        for i in range(r_out):
            Ms[p + i, j] = red.Ot[0, i, j]
    w = np.zeros((m, W))
    ucmd = np.zeros((m, W))  # an attitude law commands the torque only: 0 on the rest
    u = np.empty((m, W))
    d = np.empty((m, W))
    y = np.empty((p, W))
    e = np.empty((p, W))
    f = np.zeros(W)  # no input force: its feedthrough Dmfv is zero
    Dmfv = np.zeros((p, W))
    xi = np.zeros((nk, W))
    xi_new = np.empty((nk, W))
    bad = np.zeros(W, np.bool_)
    alive = np.ones(W, np.bool_)
    i_imp = 0
    for k in range(n_t):
        i_imp = apply_impulses(x, loop.imp_k, loop.imp_dx, i_imp, k, cl, W)
        if one:
            lane_rows(Ms, x, acc, W)
        else:
            row_products(Mt, x, acc, W)
        measure(acc, w, f, Dmv, Dmfv, sensv, loop.sensor_slot, loop.noise, cl, k, y, W)
        if loop.law_kind == 0:
            law(
                loop.Ak,
                loop.Bk,
                loop.Ck,
                loop.Dk,
                loop.y_ref,
                loop.u_ff,
                loop.K0,
                loop.bound,
                k,
                y,
                e,
                xi,
                xi_new,
                ucmd,
                bad,
                cl,
                W,
            )
        else:
            attitude_law(loop.law_kind, y, gains, target, w_ref, loop.singular, ucmd, bad, W)
            for l in range(W):
                for i in range(3):
                    if not abs(ucmd[i, l]) <= loop.bound:
                        bad[l] = True
        for j in range(n):
            for l in range(W):
                if not abs(x[j, l]) <= loop.bound:
                    bad[l] = True
        if metrics:
            reduce_outputs(loop.kind, x, acc, w, Dov, red, tgt, hv, pk, fin, after, k, W)
        else:
            for l in range(W):
                c = cl[l]
                for j in range(n):
                    X[c, k, j] = x[j, l]
                for i in range(p_rec):
                    Y[c, k, i] = y[p - p_rec + i, l]
                for i in range(m):
                    Ucmd[c, k, i] = ucmd[i, l]
        actuate(ucmd, actv, dstdv, loop.dist_slot, loop.noise, cl, k, u, d, w, W)
        running = False
        for l in range(W):
            if bad[l] and alive[l]:
                stop[cl[l]] = k
                alive[l] = False
            running = running or alive[l]
        if not running:
            break
        if metrics:
            reduce_inputs(red, u, pk, ss, k, W)
        else:
            for i in range(m):
                for l in range(W):
                    U[cl[l], k, i] = u[i, l]
                    D[cl[l], k, i] = d[i, l]
        if k == n_t - 1:
            break
        if loop.kind == 0:
            rigid_steps(x, w, J, Jinv, loop.h, loop.substeps, rs, W)
        elif loop.E.shape[0] == 1:  # a shared plant: the one E2, E, F, R of every lane
            modal_steps(
                x,
                w,
                loop.E2[0],
                loop.E[0],
                loop.Q1u[0],
                loop.P1u[0],
                loop.F[0],
                loop.R[0],
                J,
                loop.substeps,
                work,
                g,
                acc6,
                W,
            )
        else:
            modal_steps(x, w, E2, E, Q1u, P1u, F, R, J, loop.substeps, work, g, acc6, W)
    if metrics:
        for l in range(W):
            c = cl[l]
            for q in range(nq):
                red.peak[c, q] = pk[q, l]
                red.final[c, q] = fin[q, l]
                red.sumsq[c, q] = ss[q, l]
            for i in range(4):
                red.beta_end[c, i] = hv[i, l]
            red.after[c] = after[l]


@cached_jit(error_model="numpy")
def attitude_loop(loop: AttitudeLoop, records: AttitudeRecords, metrics: AttitudeMetrics) -> None:
    """Run the three-axis loop for every case, in groups of :data:`LANES` (module
    docstring): the records, or with ``metrics.n_t`` > 0 the channel metrics alone."""
    nc = loop.x0.shape[0]
    for g in range((nc + LANES - 1) // LANES):
        c0 = g * LANES
        _group(c0, min(LANES, nc - c0), loop, records, metrics, LANES)


@cached_jit(parallel=True, error_model="numpy")
def attitude_loop_parallel(
    loop: AttitudeLoop, records: AttitudeRecords, metrics: AttitudeMetrics
) -> None:
    """:func:`attitude_loop` with the groups spread over threads (bit-identical)."""
    nc = loop.x0.shape[0]
    for g in prange((nc + LANES - 1) // LANES):
        c0 = np.int64(g) * LANES
        _group(c0, min(LANES, nc - c0), loop, records, metrics, LANES)
