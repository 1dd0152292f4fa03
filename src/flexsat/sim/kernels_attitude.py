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
   case), records (state, measurements, commands);
5. actuator and random disturbance (:func:`flexsat.sim.kernel_phases.actuate`);
6. ``substeps`` steps of h = dt / substeps with the input held:

   * rigid (``kind`` 0): the RKMK4 step of :func:`flexsat.dynamics.rigid_body.rkmk4_step`
     (Munthe-Kaas 1999) on (β, ω) with Euler's equations I ω' = u − ω × I ω, then β scaled to
     unit norm (the engine's ``plant.normalize`` after the plant's own step);
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
from flexsat.sim.spacecraft_modal import HEAD

__all__ = [
    "ATTITUDE_LAWS",
    "AttitudeLoop",
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


@_inline
def _gather(loop, cl, W):
    """The per-case arrays of the lanes ``cl``, lanes last."""
    n, m, p = loop.x0.shape[1], loop.P1u.shape[2], loop.Cm.shape[1]
    modal = loop.kind == 1
    nm = n if modal else 0
    own = modal and loop.E.shape[0] > 1  # each lane its own E2, E, F (a dispersed plant)
    no = n if own else 0
    Mt = np.zeros(rows_shape(p, n, W))
    Dmv = np.empty((p, m, W))
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
    return Mt, Dmv, sensv, J, Jinv, E2, E, Q1u, P1u, F, R, gains, target, w_ref, actv, dstdv


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
def _dexpinv(t0, t1, t2, w0, w1, w2):
    """θ̇ of the rotation-vector kinematics (:func:`flexsat.dynamics.rigid_body.dexpinv`)."""
    a2 = t0 * t0 + t1 * t1 + t2 * t2
    if a2 < 0.02 * 0.02:
        c = 1.0 / 12 + a2 / 720 + a2 * a2 / 30240
    else:
        x = np.sqrt(a2) / 2
        c = (1 - x / np.tan(x)) / a2
    s0, s1, s2 = t1 * w2 - t2 * w1, t2 * w0 - t0 * w2, t0 * w1 - t1 * w0
    return (
        w0 + 0.5 * s0 + c * (t1 * s2 - t2 * s1),
        w1 + 0.5 * s1 + c * (t2 * s0 - t0 * s2),
        w2 + 0.5 * s2 + c * (t0 * s1 - t1 * s0),
    )


@_inline
def _euler(J, Jinv, l, w0, w1, w2, u0, u1, u2):
    """ω' = I⁻¹ (u − ω × I ω) of lane l."""
    h0 = J[0, 0, l] * w0 + J[0, 1, l] * w1 + J[0, 2, l] * w2
    h1 = J[1, 0, l] * w0 + J[1, 1, l] * w1 + J[1, 2, l] * w2
    h2 = J[2, 0, l] * w0 + J[2, 1, l] * w1 + J[2, 2, l] * w2
    v0 = u0 - (w1 * h2 - w2 * h1)
    v1 = u1 - (w2 * h0 - w0 * h2)
    v2 = u2 - (w0 * h1 - w1 * h0)
    return (
        Jinv[0, 0, l] * v0 + Jinv[0, 1, l] * v1 + Jinv[0, 2, l] * v2,
        Jinv[1, 0, l] * v0 + Jinv[1, 1, l] * v1 + Jinv[1, 2, l] * v2,
        Jinv[2, 0, l] * v0 + Jinv[2, 1, l] * v1 + Jinv[2, 2, l] * v2,
    )


@_inline
def rigid_steps(
    x: np.ndarray,
    w: np.ndarray,
    J: np.ndarray,
    Jinv: np.ndarray,
    h: float,
    substeps: int,
    W: int,
) -> None:
    """Phase 6, rigid: ``substeps`` RKMK4 steps of (β, ω) = x[0:7] per lane with the torque
    w[0:3] held, β scaled to unit norm after each (module docstring)."""
    for _ in range(substeps):
        for l in range(W):
            u0, u1, u2 = w[0, l], w[1, l], w[2, l]
            a0, a1, a2 = x[4, l], x[5, l], x[6, l]
            k1t = (a0, a1, a2)
            k1w = _euler(J, Jinv, l, a0, a1, a2, u0, u1, u2)
            b = 0.5 * h
            ws = (a0 + b * k1w[0], a1 + b * k1w[1], a2 + b * k1w[2])
            k2t = _dexpinv(b * k1t[0], b * k1t[1], b * k1t[2], ws[0], ws[1], ws[2])
            k2w = _euler(J, Jinv, l, ws[0], ws[1], ws[2], u0, u1, u2)
            ws = (a0 + b * k2w[0], a1 + b * k2w[1], a2 + b * k2w[2])
            k3t = _dexpinv(b * k2t[0], b * k2t[1], b * k2t[2], ws[0], ws[1], ws[2])
            k3w = _euler(J, Jinv, l, ws[0], ws[1], ws[2], u0, u1, u2)
            ws = (a0 + h * k3w[0], a1 + h * k3w[1], a2 + h * k3w[2])
            k4t = _dexpinv(h * k3t[0], h * k3t[1], h * k3t[2], ws[0], ws[1], ws[2])
            k4w = _euler(J, Jinv, l, ws[0], ws[1], ws[2], u0, u1, u2)
            g = h / 6
            t0 = g * (k1t[0] + 2 * k2t[0] + 2 * k3t[0] + k4t[0])
            t1 = g * (k1t[1] + 2 * k2t[1] + 2 * k3t[1] + k4t[1])
            t2 = g * (k1t[2] + 2 * k2t[2] + 2 * k3t[2] + k4t[2])
            x[4, l] = a0 + g * (k1w[0] + 2 * k2w[0] + 2 * k3w[0] + k4w[0])
            x[5, l] = a1 + g * (k1w[1] + 2 * k2w[1] + 2 * k3w[1] + k4w[1])
            x[6, l] = a2 + g * (k1w[2] + 2 * k2w[2] + 2 * k3w[2] + k4w[2])
            # exp(θ) (rigid_body._exp: ½ sinc(|θ| / 2π) = sin(|θ|/2) / |θ|), then exp(θ) ⊗ β
            nt = np.sqrt(t0 * t0 + t1 * t1 + t2 * t2)
            q0 = np.cos(nt / 2)
            s = 0.5 * np.sinc(nt / (2 * np.pi))
            q1, q2, q3 = t0 * s, t1 * s, t2 * s
            p0, p1, p2, p3 = x[0, l], x[1, l], x[2, l], x[3, l]
            r0 = q0 * p0 - (q1 * p1 + q2 * p2 + q3 * p3)
            r1 = q0 * p1 + p0 * q1 - (q2 * p3 - q3 * p2)
            r2 = q0 * p2 + p0 * q2 - (q3 * p1 - q1 * p3)
            r3 = q0 * p3 + p0 * q3 - (q1 * p2 - q2 * p1)
            norm = np.sqrt(r0 * r0 + r1 * r1 + r2 * r2 + r3 * r3)
            x[0, l], x[1, l], x[2, l], x[3, l] = r0 / norm, r1 / norm, r2 / norm, r3 / norm


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
    n, m = z.shape[0], w.shape[0]
    hd, fd, a, b, full, fx = work[0], work[1], work[2], work[3], work[4], work[5]
    fa, fb, fc = work[6, :7], work[7, :7], work[8, :7]
    for i in range(n):
        for l in range(W):
            s, t = 0.0, 0.0
            for j in range(m):
                s += Q1u[i, j, l] * w[j, l]
                t += P1u[i, j, l] * w[j, l]
            hd[i, l], fd[i, l] = s, t
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
def _group(c0, nl, loop, rec, W):
    """Cases c0 .. c0 + nl − 1 as W = :data:`LANES` lanes (the lanes past nl repeat the last
    case): the step of the module docstring.

    W is an argument, not the constant, on purpose: with a known trip count of 8 LLVM unrolls
    the loops over the lanes and then cannot pack them into vectors (it cannot prove the
    arrays apart); with a trip count known only at run time it vectorises them across the
    lanes behind a run-time overlap check (measured: the flexible step of a shared plant 1.26
    -> 0.87 µs per lane-substep, ``benchmarks/bench_attitude.py --step``). The same
    operations in the same order either way (no fast-math): the numbers do not change."""
    X, Y, Ucmd, U, D, stop = rec
    n_t, n = Y.shape[1], loop.x0.shape[1]
    m, p, nk = loop.P1u.shape[2], loop.Cm.shape[1], loop.Ak.shape[2]
    p_rec = Y.shape[2]
    cl = np.empty(W, np.int64)
    for l in range(W):
        cl[l] = c0 + min(l, nl - 1)
    Mt, Dmv, sensv, J, Jinv, E2, E, Q1u, P1u, F, R, gains, target, w_ref, actv, dstdv = _gather(
        loop, cl, W
    )
    x = np.empty((n, W))
    for l in range(W):
        stop[cl[l]] = -1
        for j in range(n):
            x[j, l] = loop.x0[cl[l], j]
    work = np.empty((9, n, W))
    g = np.empty((7, W))
    acc6 = np.empty((8, W))  # row sums of R (padded to a block of 8 for W = 1)
    acc = np.empty((row_count(Mt, n), W))
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
        for i in range(m):
            for l in range(W):
                U[cl[l], k, i] = u[i, l]
                D[cl[l], k, i] = d[i, l]
        if k == n_t - 1:
            break
        if loop.kind == 0:
            rigid_steps(x, w, J, Jinv, loop.h, loop.substeps, W)
        elif loop.E.shape[0] == 1:  # a shared plant: the one E2, E, F, R of every lane
            modal_steps(
                x,
                w,
                loop.E2[0],
                loop.E[0],
                Q1u,
                P1u,
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


@cached_jit(error_model="numpy")
def attitude_loop(loop: AttitudeLoop, records: AttitudeRecords) -> None:
    """Run the three-axis loop for every case, in groups of :data:`LANES` (module
    docstring)."""
    nc = loop.x0.shape[0]
    for g in range((nc + LANES - 1) // LANES):
        c0 = g * LANES
        _group(c0, min(LANES, nc - c0), loop, records, LANES)


@cached_jit(parallel=True, error_model="numpy")
def attitude_loop_parallel(loop: AttitudeLoop, records: AttitudeRecords) -> None:
    """:func:`attitude_loop` with the groups spread over threads (bit-identical)."""
    nc = loop.x0.shape[0]
    for g in prange((nc + LANES - 1) // LANES):
        c0 = np.int64(g) * LANES
        _group(c0, min(LANES, nc - c0), loop, records, LANES)
