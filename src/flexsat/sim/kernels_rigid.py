r"""The rigid body's RKMK4 step of the three-axis kernel (:mod:`flexsat.sim.kernels_attitude`)
with the cases in lanes, vectorised across the lanes.

The step is that of :func:`flexsat.dynamics.rigid_body.rkmk4_step` (Munthe-Kaas, "High order
Runge-Kutta methods on manifolds", Applied Numerical Mathematics 29, 1999): four stages of
the rotation-vector kinematics θ̇ = dexp⁻¹_θ(ω) = ω + ½ θ × ω + c(θ) θ × (θ × ω),
c(θ) = (1 − x / tan x) / |θ|², x = |θ| / 2 (Iserles, Munthe-Kaas, Nørsett & Zanna, "Lie-group
methods", Acta Numerica 9, 2000, §3), with Euler's equations I ω̇ = u − ω × I ω, then
β ← exp(θ) ⊗ β, exp(θ) = (cos x, sin x θ / |θ|), scaled to unit norm.

Each stage is one pass over the lanes without a branch or a libm call, so the compiler packs
the lanes into vector operations; the two transcendental coefficients are evaluated between
the passes, for every lane by a series or polynomial of its own angle (c(θ) by its series
1/12 + a²/720 + a⁴/30240, a = |θ|, for |θ| < :data:`SERIES_ANGLE`, as the Python step; cos x
and sin x / x by their Taylor polynomials to x⁸ for x < :data:`EXP_HALF_ANGLE`), and by libm's
tan, cos and sinc, lane by lane, only for a lane beyond them. A lane's numbers depend on its own
state only: a case is the same alone and in a batch. No fast-math.
"""

from __future__ import annotations

import numpy as np

from flexsat.sim.kernel_arrays import cached_jit

__all__ = [
    "EXP_HALF_ANGLE",
    "SERIES_ANGLE",
    "dexpinv_with",
    "euler_rates",
    "exp_coefficients",
    "rigid_steps",
    "series_coefficient",
]

_inline = cached_jit(inline="always", error_model="numpy")


@_inline
def euler_rates(J, Jinv, l, w0, w1, w2, u0, u1, u2):
    """ω' = I⁻¹ (u − ω × I ω) of lane l (J, Jinv (3, 3, W))."""
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


#: the rotation angle below which dexpinv's coefficient is its series (rigid_body.dexpinv)
SERIES_ANGLE = 0.02
#: half the rotation angle of a step below which exp(θ) takes the polynomials of
#: :func:`exp_coefficients` (their truncation below 3e-17 relative) in place of cos and sinc
EXP_HALF_ANGLE = 0.1


@_inline
def series_coefficient(t, c, W):
    """dexpinv's coefficient c(θ) = (1 − x / tan x) / |θ|², x = |θ| / 2, of the lanes'
    θ = t[0:3] (3, W) into c (W,): the series 1/12 + a²/720 + a⁴/30240 (|θ| <
    :data:`SERIES_ANGLE`) for every lane in one pass the compiler vectorises, then the
    closed form, lane by lane, for the lanes beyond it (libm's tan: no vector form). Each
    lane's formula depends on its own θ only: the same number alone and in a batch."""
    big = 0
    for l in range(W):
        a2 = t[0, l] * t[0, l] + t[1, l] * t[1, l] + t[2, l] * t[2, l]
        c[l] = 1.0 / 12 + a2 / 720 + a2 * a2 / 30240
        big += 1 if a2 >= SERIES_ANGLE * SERIES_ANGLE else 0
    if big == 0:
        return
    for l in range(W):
        a2 = t[0, l] * t[0, l] + t[1, l] * t[1, l] + t[2, l] * t[2, l]
        if a2 >= SERIES_ANGLE * SERIES_ANGLE:
            x = np.sqrt(a2) / 2
            c[l] = (1 - x / np.tan(x)) / a2


@_inline
def dexpinv_with(t0, t1, t2, w0, w1, w2, c):
    """θ̇ of the rotation-vector kinematics (:func:`flexsat.dynamics.rigid_body.dexpinv`)
    with its coefficient c (:func:`series_coefficient`)."""
    s0, s1, s2 = t1 * w2 - t2 * w1, t2 * w0 - t0 * w2, t0 * w1 - t1 * w0
    return (
        w0 + 0.5 * s0 + c * (t1 * s2 - t2 * s1),
        w1 + 0.5 * s1 + c * (t2 * s0 - t0 * s2),
        w2 + 0.5 * s2 + c * (t0 * s1 - t1 * s0),
    )


@_inline
def exp_coefficients(t, q0, s, W):
    """exp(θ) = (cos(|θ|/2), s θ), s = sin(|θ|/2) / |θ| (rigid_body._exp), of the lanes'
    θ = t[0:3]: for x = |θ|/2 < :data:`EXP_HALF_ANGLE` the Taylor polynomials
    cos x = 1 − x²/2 + x⁴/24 − x⁶/720 + x⁸/40320 and s = ½ (1 − x²/6 + x⁴/120 − x⁶/5040 +
    x⁸/362880) (truncation below x¹⁰/10! < 3e-17), every lane in one vectorised pass; libm's
    cos and sinc, lane by lane, for the lanes beyond (each lane by its own angle)."""
    big = 0
    for l in range(W):
        nt = np.sqrt(t[0, l] * t[0, l] + t[1, l] * t[1, l] + t[2, l] * t[2, l])
        x = nt / 2
        x2 = x * x
        q0[l] = 1.0 + x2 * (-1.0 / 2 + x2 * (1.0 / 24 + x2 * (-1.0 / 720 + x2 * (1.0 / 40320))))
        s[l] = 0.5 * (
            1.0 + x2 * (-1.0 / 6 + x2 * (1.0 / 120 + x2 * (-1.0 / 5040 + x2 * (1.0 / 362880))))
        )
        big += 1 if x >= EXP_HALF_ANGLE else 0
    if big == 0:
        return
    for l in range(W):
        nt = np.sqrt(t[0, l] * t[0, l] + t[1, l] * t[1, l] + t[2, l] * t[2, l])
        if nt / 2 >= EXP_HALF_ANGLE:
            q0[l] = np.cos(nt / 2)
            s[l] = 0.5 * np.sinc(nt / (2 * np.pi))


@_inline
def rigid_steps(
    x: np.ndarray,
    w: np.ndarray,
    J: np.ndarray,
    Jinv: np.ndarray,
    h: float,
    substeps: int,
    S: np.ndarray,
    W: int,
) -> None:
    """Phase 6, rigid: ``substeps`` RKMK4 steps of (β, ω) = x[0:7] per lane with the torque
    w[0:3] held, β scaled to unit norm after each (module docstring). Each stage is one pass
    over the lanes without a branch or a libm call (vectorised across the lanes), the
    coefficients of dexpinv and exp between them (:func:`series_coefficient`,
    :func:`exp_coefficients`); scratch S (32, W): k1w .. k4w, k2t .. k4t, θ, ω_s, c, q0, s."""
    b = 0.5 * h
    g = h / 6
    th, ws, c, q0, sc = S[21:24], S[24:27], S[27], S[28], S[29]
    for _ in range(substeps):
        for l in range(W):
            a0, a1, a2 = x[4, l], x[5, l], x[6, l]
            k1w = euler_rates(J, Jinv, l, a0, a1, a2, w[0, l], w[1, l], w[2, l])
            S[0, l], S[1, l], S[2, l] = k1w
            ws[0, l], ws[1, l], ws[2, l] = a0 + b * k1w[0], a1 + b * k1w[1], a2 + b * k1w[2]
            th[0, l], th[1, l], th[2, l] = b * a0, b * a1, b * a2  # b k1t, k1t = ω
        for stage in range(3):  # k2, k3, k4
            series_coefficient(th, c, W)
            kw, kt = 3 + 6 * stage, 6 + 6 * stage
            for l in range(W):
                a0, a1, a2 = x[4, l], x[5, l], x[6, l]
                v0, v1, v2 = ws[0, l], ws[1, l], ws[2, l]
                t = dexpinv_with(th[0, l], th[1, l], th[2, l], v0, v1, v2, c[l])
                k = euler_rates(J, Jinv, l, v0, v1, v2, w[0, l], w[1, l], w[2, l])
                S[kt, l], S[kt + 1, l], S[kt + 2, l] = t
                S[kw, l], S[kw + 1, l], S[kw + 2, l] = k
                f = b if stage == 0 else h
                ws[0, l], ws[1, l], ws[2, l] = a0 + f * k[0], a1 + f * k[1], a2 + f * k[2]
                th[0, l], th[1, l], th[2, l] = f * t[0], f * t[1], f * t[2]
        # S rows: 0-2 k1w, 3-5 k2w, 6-8 k2t, 9-11 k3w, 12-14 k3t, 15-17 k4w, 18-20 k4t
        for l in range(W):
            a0, a1, a2 = x[4, l], x[5, l], x[6, l]
            th[0, l] = g * (a0 + 2 * S[6, l] + 2 * S[12, l] + S[18, l])
            th[1, l] = g * (a1 + 2 * S[7, l] + 2 * S[13, l] + S[19, l])
            th[2, l] = g * (a2 + 2 * S[8, l] + 2 * S[14, l] + S[20, l])
            x[4, l] = a0 + g * (S[0, l] + 2 * S[3, l] + 2 * S[9, l] + S[15, l])
            x[5, l] = a1 + g * (S[1, l] + 2 * S[4, l] + 2 * S[10, l] + S[16, l])
            x[6, l] = a2 + g * (S[2, l] + 2 * S[5, l] + 2 * S[11, l] + S[17, l])
        exp_coefficients(th, q0, sc, W)
        for l in range(W):  # exp(θ) ⊗ β, scaled to unit norm
            r0_, s_ = q0[l], sc[l]
            q1, q2, q3 = th[0, l] * s_, th[1, l] * s_, th[2, l] * s_
            p0, p1, p2, p3 = x[0, l], x[1, l], x[2, l], x[3, l]
            r0 = r0_ * p0 - (q1 * p1 + q2 * p2 + q3 * p3)
            r1 = r0_ * p1 + p0 * q1 - (q2 * p3 - q3 * p2)
            r2 = r0_ * p2 + p0 * q2 - (q3 * p1 - q1 * p3)
            r3 = r0_ * p3 + p0 * q3 - (q1 * p2 - q2 * p1)
            norm = np.sqrt(r0 * r0 + r1 * r1 + r2 * r2 + r3 * r3)
            x[0, l], x[1, l], x[2, l], x[3, l] = r0 / norm, r1 / norm, r2 / norm, r3 / norm
