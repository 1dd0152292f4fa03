r"""A sampled LQ loop run on the engine, and the adjoint gradients of its maneuver metrics.

The plant :math:`\dot x = A x + B u` (a :class:`~flexsat.dynamics.state_space.StateSpacePlant`)
runs under :class:`~flexsat.control.scheduled.ScheduledStateFeedback` with one constant gain,
u_k = −K(x_k − r), sampled every h with a zero-order hold, through :func:`flexsat.sim.simulate`
(the engine propagates a linear plant exactly: x_{k+1} = Φx_k + Γu_k with Φ, Γ from one block
exponential; :func:`run_loop` returns its record). K is the discrete LQR gain of the ZOH model
(Φ, Γ) with weights (Q_d, R_d) (:func:`flexsat.control.lqr.dlqr`).

A metric J of the record (:mod:`flexsat.analysis.sampled_sensitivity`: terminal energy,
terminal error, smooth peak, soft settling) is differentiated with respect to
(A, B, Q_d, R_d, x₀, r) by the discrete adjoint (:func:`loop_gradient`): one backward sweep
(:func:`~flexsat.analysis.sampled_sensitivity.loop_adjoint`), one Stein solve for the gain
(:func:`~flexsat.analysis.sampled_sensitivity.dlqr_gain_adjoint`) and one Fréchet derivative
of the block exponential (:func:`~flexsat.analysis.sampled_sensitivity.zoh_adjoint`),
whatever the number of design parameters; a caller chains the result with its ∂A/∂p, ∂B/∂p
stacks (:func:`flexsat.analysis.riccati_sensitivity.chain_gradient`). References: Y. Cao,
S. Li, L. Petzold and R. Serban, "Adjoint sensitivity analysis for differential-algebraic
equations: the adjoint DAE system and its numerical solution", SIAM J. Scientific Computing
24(3), 2003; A. H. Al-Mohy and N. J. Higham, "Computing the Fréchet derivative of the matrix
exponential, with an application to condition number estimation", SIAM J. Matrix Analysis and
Applications 30(4), 2009.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from flexsat.analysis.sampled_sensitivity import (
    MetricValue,
    dlqr_gain_adjoint,
    loop_adjoint,
    zoh_adjoint,
    zoh_maps,
)
from flexsat.control.lqr import dlqr
from flexsat.control.scheduled import ScheduledStateFeedback
from flexsat.dynamics.state_space import StateSpacePlant
from flexsat.input_checks import FieldError, require_count, require_finite, require_positive
from flexsat.sim.config import SimConfig
from flexsat.sim.engine import simulate
from flexsat.units import FloatArray

if TYPE_CHECKING:
    import numpy.typing as npt

__all__ = ["LoopGradient", "SampledLQLoop", "loop_gradient", "run_loop", "sampled_lq_loop"]


def run_loop(
    A: FloatArray,
    B: FloatArray,
    K: FloatArray,
    h: float,
    n_steps: int,
    x0: FloatArray,
    r: FloatArray | None = None,
) -> tuple[FloatArray, FloatArray]:
    """The engine's record of u_k = −K(x_k − r) on ẋ = Ax + Bu: X (N + 1, n), U (N, m).

    U holds the commands held over [t_k, t_{k+1}), k < N (the engine also records the command
    at t_N, which acts after the maneuver and is dropped).
    """
    n, m = B.shape
    plant = StateSpacePlant(A, B, np.zeros((1, n)), np.zeros((1, m)))
    ref = np.zeros((1, n)) if r is None else np.asarray(r, float).reshape(1, n)
    law = ScheduledStateFeedback([0.0], K[None], "state", "u", state_reference=ref)
    config = SimConfig(duration=n_steps * h, control_rate=1.0 / h)
    if config.n_steps != n_steps:
        raise FieldError("n_steps", f"the engine made {config.n_steps} steps of {h:g} s")
    ds = simulate(plant, law, config, n_cases=1, initial_state=x0, record_states=True).dataset
    X = np.asarray(ds["state"].values[0], float)
    U = np.asarray(ds["u"].values[0], float).reshape(n_steps + 1, m)[:n_steps]
    return X, U


@dataclass(frozen=True)
class SampledLQLoop:
    """A sampled discrete-LQR loop and its engine record (:func:`sampled_lq_loop`).

    Attributes
    ----------
    A, B, Q, R : the continuous plant and the discrete weights (Q_d, R_d)
    h : sample period, s;  x0, r : initial state and state reference
    phi, gamma : ZOH maps;  S, K : discrete Riccati solution and gain
    X, U : the engine's record, (N + 1, n) and (N, m)
    """

    A: FloatArray
    B: FloatArray
    Q: FloatArray
    R: FloatArray
    h: float
    x0: FloatArray
    r: FloatArray
    phi: FloatArray
    gamma: FloatArray
    S: FloatArray
    K: FloatArray
    X: FloatArray
    U: FloatArray


def sampled_lq_loop(
    A: npt.ArrayLike,
    B: npt.ArrayLike,
    Q: npt.ArrayLike,
    R: npt.ArrayLike,
    h: npt.ArrayLike,
    n_steps: npt.ArrayLike,
    x0: npt.ArrayLike,
    r: npt.ArrayLike | None = None,
) -> SampledLQLoop:
    """Design the discrete LQR gain of the ZOH model and run the loop on the engine.

    Parameters
    ----------
    A, B : (n, n), (n, m) continuous plant (SI)
    Q, R : (n, n), (m, m) discrete weights of Σ x_kᵀQx_k + u_kᵀRu_k
    h : float, sample period, s;  n_steps : int, N (maneuver time T = N h)
    x0 : (n,) initial state;  r : (n,) state reference (default 0)

    Raises
    ------
    FieldError
        Misshapen or non-finite input, h <= 0, N < 1; ValueError from the Riccati solver
        (not stabilisable, weights not definite).
    """
    phi, gamma = zoh_maps(A, B, h)
    Af, Bf = require_finite(A, "A"), require_finite(B, "B")
    hf = float(require_positive(h, "h", "s"))
    N = require_count(n_steps, "n_steps")
    n, m = Bf.shape
    Qf, Rf = require_finite(Q, "Q"), require_finite(R, "R").reshape(m, m)
    x0f = require_finite(x0, "x0")
    rf = np.zeros(n) if r is None else require_finite(r, "r")
    for name, arr, shape in (("Q", Qf, (n, n)), ("x0", x0f, (n,)), ("r", rf, (n,))):
        if arr.shape != shape:
            raise FieldError(name, f"must have shape {shape}, got {arr.shape}")
    K, S, _ = dlqr(phi, gamma, Qf, Rf)
    K, S = np.asarray(K, float), np.asarray(S, float)
    X, U = run_loop(Af, Bf, K, hf, N, x0f, rf)
    return SampledLQLoop(Af, Bf, Qf, Rf, hf, x0f, rf, phi, gamma, S, K, X, U)


@dataclass(frozen=True)
class LoopGradient:
    """∂J/∂A (n, n), ∂J/∂B (n, m), ∂J/∂Q_d, ∂J/∂R_d, ∂J/∂x₀, ∂J/∂r of a metric of the loop."""

    dA: FloatArray
    dB: FloatArray
    dQ: FloatArray
    dR: FloatArray
    dx0: FloatArray
    dr: FloatArray


def loop_gradient(loop: SampledLQLoop, metric: MetricValue) -> LoopGradient:
    """The adjoint gradient of ``metric`` (evaluated on ``loop.X``, ``loop.U``) with respect to
    the loop's data (module docstring): sweep, Stein solve, one Fréchet derivative."""
    if metric.dX.shape != loop.X.shape or metric.dU.shape != loop.U.shape:
        raise FieldError("metric", "its partials do not match the loop's record")
    adj = loop_adjoint(loop.phi, loop.gamma, loop.K, loop.X, loop.U, metric.dX, metric.dU, loop.r)
    gain = dlqr_gain_adjoint(loop.phi, loop.gamma, loop.R, loop.S, loop.K, adj.dK)
    dA, dB = zoh_adjoint(loop.A, loop.B, loop.h, adj.dphi + gain.dphi, adj.dgamma + gain.dgamma)
    return LoopGradient(dA, dB, gain.dQ, gain.dR, adj.dx0, adj.dr)
