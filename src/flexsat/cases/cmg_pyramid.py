"""Gimbal runs of Vadali, Oh & Walker's single-gimbal CMG pyramid ("Preferred Gimbal Angles for
Single Gimbal CMGs", in Junkins, Pollock & Rahman 1990, L4533-L4830): torque steering
from a gimbal set until the first singular set, the back integration to preferred angles, and
the null-motion reorientation.

Each is the plant :class:`~flexsat.dynamics.gimbal_cluster.GimbalCluster` (σ̇ = u) under a law of
:mod:`flexsat.control.cmg_steering`, in the engine's continuous-law mode (the law at every stage
of DOP853, rtol 1e-10): the paper's steering is continuous. The reorientation is a
:func:`flexsat.sim.simulate` run of the triple :func:`reorient_simulation` builds (what the
``kind: cmg`` scenario hands to the runner). Torque steering stops at the first singular set, a
terminal condition and dense output :func:`~flexsat.sim.simulate` does not offer, so it calls
the mode's integrator :func:`flexsat.sim.continuous.run` directly. One case per call; torques
in rotor momenta h per second.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np
from scipy.optimize import brentq, minimize_scalar

from flexsat.control.cmg_steering import NullMotionSteering, PseudoInverseSteering
from flexsat.dynamics import cmg
from flexsat.dynamics.cmg import PAPER_PERTURBATION, SKEW, GimbalRun
from flexsat.dynamics.gimbal_cluster import GimbalCluster
from flexsat.input_checks import require_finite
from flexsat.sim import continuous, simulate
from flexsat.sim.config import SimConfig

if TYPE_CHECKING:
    import numpy.typing as npt
    import xarray as xr

__all__ = [
    "gimbal_run",
    "integrate_gimbals",
    "preferred_angles",
    "reorient",
    "reorient_simulation",
]


def _gimbal_set(sigma, n_units: int, field: str) -> np.ndarray:
    """One gimbal set (n,), rad, checked by the kernels' rule."""
    sig = require_finite(sigma, field, "rad")
    if sig.ndim == 0 or sig.shape[-1] != n_units:
        raise ValueError(
            f"sigma: last axis must hold the {n_units} gimbal angles, got shape {sig.shape}"
        )
    if sig.ndim != 1:
        raise ValueError(f"{field}: one gimbal set (n,) per run, got shape {sig.shape}")
    return sig


def integrate_gimbals(
    sigma0: npt.ArrayLike,
    torque: npt.ArrayLike | Callable[[float], npt.ArrayLike],
    t_final: float | str,
    skew: float | str = SKEW,
    n_units: int = 4,
    alpha: float = 0.0,
    threshold: float = 1e-6,
    rtol: float = 1e-10,
    atol: float = 1e-12,
    n_out: int = 201,
    null_target: npt.ArrayLike | None = None,
    null_gain: float = 1.0,
    null_alpha: float = 0.0,
    stop_at_singular: bool = True,
) -> GimbalRun:
    """Steer σ̇ = Cᵀ(CCᵀ + αI)⁻¹(−torque(t)) from σ0 (§8.3), forward (t_final > 0) or
    backward (t_final < 0: the preferred-angle back integration), stopping when the gain
    det(CCᵀ) falls to ``threshold`` (the engine's terminal stop condition).

    Parameters
    ----------
    torque : array_like ``(3,)`` or callable
        Torque on the spacecraft: a constant, or a function ``t -> (3,)`` of the time in s (the
        time-varying demands of §8.3, e.g. Kurokawa's Tx = 0.2 sin 4πt, V6). A callable is
        checked at t = 0 and wherever the integrator evaluates it.
    null_target : array_like ``(n,)``, optional
        Run null motion towards this set beside the torque law
        (:func:`flexsat.dynamics.cmg.steering_with_null_motion`, gain ``null_gain`` 1/s,
        projector weight ``null_alpha``); None: the torque law alone.
    stop_at_singular : bool
        Stop at the gain ``threshold`` (default). False runs to ``t_final`` whatever the gain
        (for the SR inverse, α > 0, which passes singular sets; ``singular`` then says whether
        the gain fell to the threshold on the way).

    Returns
    -------
    GimbalRun
        Sampled at ``n_out`` equally spaced times up to the end, or up to the singular stop.
    """
    law = PseudoInverseSteering(torque, skew, n_units, alpha, null_target, null_gain, null_alpha)
    plant = GimbalCluster(n_units, skew)
    n, d = plant.n_units, plant.skew
    sig0 = _gimbal_set(sigma0, n, "sigma0")
    tf = float(require_finite(t_final, "t_final", "s"))
    if tf == 0:
        raise ValueError("t_final: must be nonzero (negative integrates backward)")
    thr = float(require_finite(threshold, "threshold"))
    if thr <= 0:
        raise ValueError(f"threshold: must be > 0, got {threshold!r}")
    if stop_at_singular and cmg.gain(sig0, d, n) <= thr:
        raise ValueError(
            "sigma0: starts singular (det CCᵀ <= threshold); the pseudo-inverse "
            "cannot steer from it (use alpha > 0 and stop_at_singular=False)"
        )

    def below_threshold(_t, x):
        return cmg.gain(x[0], d, n) - thr

    run = continuous.run(
        plant,
        law,
        [0.0, tf],
        sig0,
        rtol,
        atol,
        stop=below_threshold if stop_at_singular else None,
    )

    def sigma_at(t):
        return run.solution(t)[..., 0, :]

    t_end, singular = run.t_end, run.stopped
    if stop_at_singular:
        dip = _first_dip(sigma_at, run.steps, d, n, thr)
        if dip is not None and abs(dip) < abs(t_end):
            t_end, singular = dip, True
    else:  # the gain on the dense output, 8 points a step: did it touch the threshold?
        grid = np.linspace(run.steps[:-1], run.steps[1:], 9).T.ravel()
        singular = bool(np.min(cmg.gain(sigma_at(grid), d, n)) <= thr)
    t = np.linspace(0.0, t_end, n_out)
    sig = sigma_at(t)
    if t_end == run.t_end:
        sig[-1] = run.x_end[0]  # the stop's exact end point
    return GimbalRun(t, sig, cmg.momentum(sig, d, n), cmg.gain(sig, d, n), bool(singular))


def _first_dip(sigma_at, steps, skew, n, thr):
    """The earliest time the gain touches ``thr`` between the integrator's steps, or None.

    The stop condition sees only sign changes at the integrator's steps. Where the commanded ḣ
    stays normal to the singular direction the pseudo-inverse passes *through* a singularity
    with finite rates, and det(CCᵀ) (a product of squared singular values) only touches zero: a
    dip narrower than a step (e.g. a z torque from [45, −45, 45, −45]°, §8.3) that the stop
    misses. So scan the dense output, 8 points a step, and refine every sampled local minimum.
    """
    grid = np.concatenate(
        [np.linspace(t0, t1, 9)[:-1] for t0, t1 in zip(steps[:-1], steps[1:])] + [steps[-1:]]
    )

    def excess(t):
        return cmg.gain(sigma_at(t), skew, n) - thr

    vals = excess(grid)
    for j in range(1, grid.size):
        if vals[j] <= 0:
            return brentq(excess, grid[j - 1], grid[j], xtol=1e-14)
        if j + 1 < grid.size and vals[j] <= vals[j - 1] and vals[j] <= vals[j + 1]:
            lo, hi = sorted((grid[j - 1], grid[j + 1]))
            res = minimize_scalar(
                excess,
                bounds=(lo, hi),
                method="bounded",
                options={"xatol": 1e-12 * max(1.0, abs(hi))},
            )
            if res.fun <= 0:
                return brentq(excess, grid[j - 1], res.x, xtol=1e-14)
    return None


def preferred_angles(
    direction: npt.ArrayLike,
    skew: float | str = SKEW,
    n_units: int = 4,
    perturbation: npt.ArrayLike | None = None,
    threshold: float = 1e-6,
    rtol: float = 1e-10,
    atol: float = 1e-12,
) -> np.ndarray:
    """Preferred initial gimbal angles for a momentum demand along u, by back integration from
    near saturation (Vadali, Oh & Walker; the paper's back-integration study).

    Start at the saturation set along u (:func:`flexsat.dynamics.cmg.envelope`), moved by
    ``perturbation`` off that external singularity (where the pseudo-inverse has no solution
    and the perturbation picks the branch), and steer backward under the unit demand ḣ = u
    (torque −u) for the time t = uᵀh(σ_start) that removes the momentum along u. The end set
    holds h ≈ 0 (the perturbation's small momentum normal to u is untouched) and, run forward
    under the same demand, retraces the path to the envelope along u without an internal
    singularity.

    Parameters
    ----------
    direction : array_like ``(3,)``
        Nonzero demand direction u (normalised here).
    perturbation : array_like ``(n,)``, optional
        Offset from the saturation set, rad or strings with units. Default: the paper's
        [1, −3, 0, −1]° (V4) for n = 4; required for other n.
    threshold : float
        Gain det(CCᵀ) at which the back integration counts as singular (then ValueError).

    Returns
    -------
    ndarray ``(n,)``
        The preferred σ(0), rad, wrapped to (−π, π].
    """
    plant = GimbalCluster(n_units, skew)  # checks both
    n, d = plant.n_units, plant.skew
    u = require_finite(direction, "direction")
    if u.shape != (3,):
        raise ValueError(f"direction: must have 3 components, got shape {u.shape}")
    if perturbation is None:
        if n != 4:
            raise ValueError(
                f"perturbation: required for n_units = {n} (the paper's offset "
                "is for the 4-unit pyramid)"
            )
        perturbation = PAPER_PERTURBATION
    dp = require_finite(perturbation, "perturbation", "rad")
    if dp.shape != (n,) or not np.any(dp):
        raise ValueError(
            f"perturbation: must be a nonzero offset of shape ({n},), got {np.shape(perturbation)}"
        )
    _, sig_sat = cmg.envelope(u, d, n)  # normalises u and rejects u = 0
    u = u / np.linalg.norm(u)
    start = sig_sat + dp
    t_back = float(u @ cmg.momentum(start, d, n))
    if t_back <= 0:
        raise ValueError("perturbation: moves the start set off the saturated side (uᵀh <= 0)")
    run = integrate_gimbals(start, -u, -t_back, d, n, threshold=threshold, rtol=rtol, atol=atol)
    if run.singular:
        raise ValueError(
            f"perturbation: the back integration along {u} met a singularity at "
            f"t = {run.t[-1]:.6g} s; try another offset"
        )
    return np.angle(np.exp(1j * run.sigma[-1]))


def reorient_simulation(
    sigma0: npt.ArrayLike,
    sigma_target: npt.ArrayLike,
    t_final: float | str,
    gain_k: float = 1.0,
    skew: float | str = SKEW,
    n_units: int = 4,
    alpha: float = 1e-3,
    rtol: float = 1e-10,
    atol: float = 1e-12,
    n_out: int = 201,
) -> tuple[GimbalCluster, NullMotionSteering, SimConfig, dict[str, Any]]:
    """What :func:`reorient` simulates: the plant, the law, the configuration and the options
    of :func:`flexsat.sim.simulate` (continuous-law mode, the law at every stage of DOP853,
    recorded at ``n_out`` equally spaced times over ``t_final``).

    Raises
    ------
    ValueError
        Naming the field: a bad gimbal set, pyramid, gain, weight, duration or sample count.
    """
    plant = GimbalCluster(n_units, skew)
    n, d = plant.n_units, plant.skew
    sig0 = _gimbal_set(sigma0, n, "sigma0")
    _gimbal_set(sigma_target, n, "sigma_target")
    law = NullMotionSteering(sigma_target, gain_k, d, n, alpha)
    tf = float(require_finite(t_final, "t_final", "s"))
    if tf <= 0:
        raise ValueError(f"t_final: must be > 0, got {t_final!r}")
    if isinstance(n_out, bool) or not isinstance(n_out, (int, np.integer)) or n_out < 2:
        raise ValueError(f"n_out: must be an integer >= 2, got {n_out!r}")
    config = SimConfig(
        duration=tf,
        control_rate=(n_out - 1) / tf,
        substeps=1,
        law_mode="continuous",
        rtol=rtol,
        atol=atol,
    )
    return plant, law, config, {"initial_state": sig0, "record_states": True}


def gimbal_run(plant: GimbalCluster, dataset: xr.Dataset) -> GimbalRun:
    """The recorded run of :func:`reorient_simulation` (``dataset`` of its
    :class:`~flexsat.sim.recording.SimResult`, one case) as a :class:`GimbalRun`
    (``singular`` False: the null motion runs through singular sets)."""
    t = dataset["time"].values
    sig = dataset["state"].values[0]
    d, n = plant.skew, plant.n_units
    return GimbalRun(t, sig, cmg.momentum(sig, d, n), cmg.gain(sig, d, n), False)


def reorient(
    sigma0: npt.ArrayLike,
    sigma_target: npt.ArrayLike,
    t_final: float | str,
    gain_k: float = 1.0,
    skew: float | str = SKEW,
    n_units: int = 4,
    alpha: float = 1e-3,
    rtol: float = 1e-10,
    atol: float = 1e-12,
    n_out: int = 201,
) -> GimbalRun:
    """Null-motion gimbal reorientation σ̇ = τ d, d = k(σ_f − σ) (§8.5 Eq. 13–17;
    :class:`~flexsat.control.cmg_steering.NullMotionSteering`), run by
    :func:`flexsat.sim.simulate` on :func:`reorient_simulation`.

    V = ½|σ_f − σ|² falls as V' = −k(σ_f − σ)ᵀτ(σ_f − σ) <= 0 (Eq. 16); α > 0 (the paper's
    ≈ 0.001) carries the motion through singular sets, where the rates go to zero (§8.5).
    One case per call; returns the run sampled at ``n_out`` times (``singular`` is False).
    """
    plant, law, config, options = reorient_simulation(
        sigma0, sigma_target, t_final, gain_k, skew, n_units, alpha, rtol, atol, n_out
    )
    return gimbal_run(plant, simulate(plant, law, config, **options).dataset)
