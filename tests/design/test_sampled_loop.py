"""Claims about the engine-run sampled LQ loop and its adjoint gradients (``design.sampled_loop``).

1. The engine's record (:func:`flexsat.sim.simulate`, a StateSpacePlant under a constant-gain
   ScheduledStateFeedback) is the ZOH recursion x_{k+1} = Φx_k + Γu_k with Φ, Γ from
   :func:`~flexsat.analysis.sampled_sensitivity.zoh_maps`, to round-off: each step adds at most
   a few ε (‖Φ‖‖x‖ + ‖Γ‖‖u‖) and the stable closed loop does not amplify it, so over N steps the
   difference is ≤ c N ε max‖x‖ (c = 8 allowed; measured ≲ 1e-14 relative on 1000 steps).
2. loop_gradient (sweep + Stein solve + one Fréchet derivative) against five-point central
   differences of the whole pipeline (DARE, engine run, metric) along random directions, step
   δ = 1e-3 (T ‖A‖ ≈ 7, so |J⁽⁵⁾| ≲ 1e4 |J|): truncation δ⁴|J⁽⁵⁾|/30 ≲ 1e-9 |J|, round-off
   ≈ 1.5 ε_J |J|/δ with ε_J ≈ 1e-13 (the DARE's relative accuracy on these 6-state problems)
   i.e. ≲ 2e-10 |J|; the
   bound is the issue-23 acceptance 1e-6 relative to max(|dJ|, 1e-3|J|).
"""

from __future__ import annotations

import numpy as np
import pytest

from flexsat.analysis.sampled_sensitivity import (
    smooth_peak,
    soft_settling,
    terminal_energy,
    terminal_error,
    zoh_maps,
)
from flexsat.design.sampled_loop import loop_gradient, sampled_lq_loop
from flexsat.input_checks import FieldError

ACCEPT = 1e-6


def central(f, h):
    return (-f(2 * h) + 8 * f(h) - 8 * f(-h) + f(-2 * h)) / (12.0 * h)


def modal_plant(modes=20, seed=0):
    """A lightly damped modal plant (2·modes states, one input), 1–60 rad/s."""
    rng = np.random.default_rng(seed)
    w = np.linspace(1.0, 60.0, modes)
    A = np.block([[np.zeros((modes, modes)), np.eye(modes)], [-np.diag(w**2), -np.diag(0.02 * w)]])
    B = np.concatenate([np.zeros(modes), rng.standard_normal(modes)])[:, None]
    return A, B


def test_engine_record_is_the_zoh_recursion():
    """40 states, 1000 steps at 100 Hz: the engine's record equals the Φ, Γ recursion."""
    A, B = modal_plant()
    n = A.shape[0]
    h, N = 0.01, 1000
    loop = sampled_lq_loop(A, B, np.eye(n), np.eye(1), h, N, np.full(n, 0.1))
    phi, gamma = zoh_maps(A, B, h)
    X = np.empty_like(loop.X)
    X[0] = loop.x0
    U = np.empty_like(loop.U)
    for k in range(N):
        U[k] = -loop.K @ (X[k] - loop.r)
        X[k + 1] = phi @ X[k] + gamma @ U[k]
    scale = np.abs(X).max()
    bound = 8 * N * np.finfo(float).eps * scale
    assert np.abs(loop.X - X).max() <= bound
    assert np.abs(loop.U - U).max() <= 8 * N * np.finfo(float).eps * np.abs(U).max()


def small_loop(seed=2, n=6, m=2, N=50, h=0.05):
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    B = rng.standard_normal((n, m))
    G = rng.standard_normal((n, n))
    Q = G @ G.T + np.eye(n)
    R = np.eye(m) * 0.5
    return rng, dict(
        A=A, B=B, Q=Q, R=R, h=h, n_steps=N, x0=rng.standard_normal(n), r=rng.standard_normal(n)
    )


def metric(loop, which):
    X, U = loop.X, loop.U
    n = X.shape[1]
    c = np.linspace(1.0, -0.5, n)
    if which == "energy":
        return terminal_energy(X, U, np.diag(np.linspace(1.0, 3.0, n)))
    if which == "error":
        return terminal_error(X, U, c, 0.2)
    if which == "peak":
        return smooth_peak(X, U, 16)
    return soft_settling(X, U, c, 0.4, 0.5, 0.2, loop.h)


@pytest.mark.numerics
@pytest.mark.parametrize("which", ["energy", "error", "peak", "settling"])
def test_loop_gradient_matches_differences(which):
    """∂J/∂(A, B, Q_d, R_d, x₀, r) through the DARE gain and the engine run."""
    rng, base = small_loop()
    loop = sampled_lq_loop(**base)
    mv = metric(loop, which)
    g = loop_gradient(loop, mv)
    grads = {"A": g.dA, "B": g.dB, "Q": g.dQ, "R": g.dR, "x0": g.dx0, "r": g.dr}
    for name, G in grads.items():
        D = rng.standard_normal(np.shape(base[name]))
        if name in ("Q", "R"):
            D = 0.1 * (D + D.T)

        def f(s, name=name, D=D):
            args = dict(base)
            args[name] = base[name] + s * D
            return metric(sampled_lq_loop(**args), which).value

        fd = central(f, 1e-3)
        an = float(np.sum(G * D))
        assert abs(an - fd) <= ACCEPT * max(abs(fd), 1e-3 * abs(mv.value)), name


def test_bad_input_named():
    _, base = small_loop()
    for field, value in (("Q", np.eye(3)), ("x0", np.zeros(2)), ("h", 0.0), ("n_steps", 0)):
        args = dict(base)
        args[field] = value
        with pytest.raises(FieldError) as info:
            sampled_lq_loop(**args)
        assert info.value.field == field
    loop = sampled_lq_loop(**base)
    with pytest.raises(FieldError) as info:  # partials of another record
        loop_gradient(loop, terminal_energy(loop.X[:-1], loop.U[:-1], np.eye(6)))
    assert info.value.field == "metric"
