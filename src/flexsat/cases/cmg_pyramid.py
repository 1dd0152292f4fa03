"""Gimbal runs of Vadali, Oh & Walker's single-gimbal CMG pyramid ("Preferred Gimbal Angles for
Single Gimbal CMGs", in Junkins, Pollock & Rahman 1990, Att. 13): torque steering
from a gimbal set until the first singular set, the back integration to preferred angles, and
the null-motion reorientation.

Each is the plant :class:`~flexsat.dynamics.gimbal_cluster.GimbalCluster` (σ̇ = u) under a law of
:mod:`flexsat.control.cmg_steering`, in the engine's continuous-law mode (the law at every stage
of DOP853, rtol 1e-10): the paper's steering is continuous. Each run is a
:func:`flexsat.sim.simulate` run of the triple :func:`steering_simulation` or
:func:`reorient_simulation` builds (what the ``kind: cmg`` scenario hands to the runner); torque
steering ends at the first singular set by the engine's stop condition
(:class:`flexsat.sim.StopCondition` on det(CCᵀ), which also finds a gain dip narrower than an
integrator step). One case per call; torques in rotor momenta h per second.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from flexsat.control.cmg_steering import NullMotionSteering, PseudoInverseSteering, TorqueHistory
from flexsat.dynamics import cmg
from flexsat.dynamics.cmg import PAPER_PERTURBATION, SKEW, GimbalRun
from flexsat.dynamics.gimbal_cluster import GimbalCluster
from flexsat.input_checks import FieldError, require_finite
from flexsat.sim import simulate
from flexsat.sim.config import SimConfig, StopCondition

if TYPE_CHECKING:
    import numpy.typing as npt
    import xarray as xr

    from flexsat.units import FloatArray

__all__ = [
    "gimbal_run",
    "gimbal_set",
    "integrate_gimbals",
    "preferred_angles",
    "reorient",
    "reorient_simulation",
    "steering_simulation",
]


def gimbal_set(sigma: npt.ArrayLike, n_units: int, field: str) -> FloatArray:
    """One gimbal set (n,), rad, checked by the kernels' rule; a boolean is not an angle."""
    if isinstance(sigma, (bool, np.bool_)) or (
        isinstance(sigma, (list, tuple, np.ndarray))
        and any(isinstance(v, (bool, np.bool_)) for v in np.asarray(sigma, object).ravel())
    ):
        raise FieldError(field, f"gimbal angles must be numbers, got {sigma!r}")
    sig = require_finite(sigma, field, "rad")
    if sig.ndim == 0 or sig.shape[-1] != n_units:
        raise FieldError(
            field, f"last axis must hold the {n_units} gimbal angles, got shape {sig.shape}"
        )
    if sig.ndim != 1:
        raise FieldError(field, f"one gimbal set (n,) per run, got shape {sig.shape}")
    return sig


def _reversed(torque: TorqueHistory) -> Callable[[float], FloatArray]:
    """The torque of a back integration run forward in s = −t: s ↦ −τ(−s) (σ' = −σ̇(−s), and
    the steering is linear in τ)."""
    if callable(torque):
        return lambda s: -require_finite(torque(-s), "torque")
    tq = -require_finite(torque, "torque")
    return lambda _s: tq


def steering_simulation(
    sigma0: npt.ArrayLike,
    torque: TorqueHistory,
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
) -> tuple[GimbalCluster, PseudoInverseSteering, SimConfig, dict[str, Any]]:
    """What :func:`integrate_gimbals` simulates: the gimbal cluster, the torque law, the
    configuration (continuous-law mode, recorded at ``n_out`` equally spaced times over
    |t_final|, the stop condition det(CCᵀ) <= ``threshold``) and the options of
    :func:`flexsat.sim.simulate` (what a ``kind: cmg`` steering run hands to the runner).

    A back integration (t_final < 0) runs forward in s = −t under the torque s ↦ −τ(−s)
    (:func:`gimbal_run` with ``direction=-1`` maps it back); null motion is forward only.

    Raises
    ------
    ValueError
        Naming the field: a bad gimbal set (or, stopping at singular sets, one that starts
        singular), torque, pyramid, weight, threshold, duration or sample count.
    """
    plant = GimbalCluster(n_units, skew)
    n, d = plant.n_units, plant.skew
    sig0 = gimbal_set(sigma0, n, "sigma0")
    tf = float(require_finite(t_final, "t_final", "s"))
    if tf == 0:
        raise FieldError("t_final", "must be nonzero (negative integrates backward)")
    if tf < 0 and null_target is not None:
        raise FieldError("null_target", "null motion runs forward only (t_final > 0)")
    thr = float(require_finite(threshold, "threshold"))
    if thr <= 0:
        raise FieldError("threshold", f"must be > 0, got {threshold!r}")
    if stop_at_singular and cmg.gain(sig0, d, n) <= thr:
        raise FieldError(
            "sigma0",
            "starts singular (det CCᵀ <= threshold); the pseudo-inverse "
            "cannot steer from it (use alpha > 0 and stop_at_singular=False)",
        )
    if isinstance(n_out, bool) or not isinstance(n_out, (int, np.integer)) or n_out < 2:
        raise FieldError("n_out", f"must be an integer >= 2, got {n_out!r}")
    law = PseudoInverseSteering(
        torque if tf > 0 else _reversed(torque),
        d,
        n,
        alpha,
        null_target,
        null_gain,
        null_alpha,
    )

    def gain_margin(_t: FloatArray, x: FloatArray) -> FloatArray:
        # x (k, n_cases, n): the lowest gain of the batch
        return np.asarray(cmg.gain(x, d, n), float).min(axis=-1) - thr

    stop = StopCondition(
        gain_margin,
        f"singular set (det CCᵀ <= {thr:g})",
        terminal=stop_at_singular,
        touches=True,
    )
    config = SimConfig(
        duration=abs(tf),
        control_rate=(n_out - 1) / abs(tf),
        substeps=1,
        law_mode="continuous",
        rtol=rtol,
        atol=atol,
        stop=stop,
    )
    return plant, law, config, {"initial_state": sig0, "record_states": True}


def integrate_gimbals(
    sigma0: npt.ArrayLike,
    torque: TorqueHistory,
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
    det(CCᵀ) falls to ``threshold``: :func:`flexsat.sim.simulate` on
    :func:`steering_simulation`.

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
        Sampled at ``n_out`` equally spaced times over [0, t_final]; stopped at a singular
        set, the samples before it and the stop itself (the exact end point).
    """
    plant, law, config, options = steering_simulation(
        sigma0,
        torque,
        t_final,
        skew,
        n_units,
        alpha,
        threshold,
        rtol,
        atol,
        n_out,
        null_target,
        null_gain,
        null_alpha,
        stop_at_singular,
    )
    direction = 1.0 if float(require_finite(t_final, "t_final", "s")) > 0 else -1.0
    return gimbal_run(plant, simulate(plant, law, config, **options).dataset, direction)


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
        raise FieldError("direction", f"must have 3 components, got shape {u.shape}")
    if perturbation is None:
        if n != 4:
            raise FieldError(
                "perturbation",
                f"required for n_units = {n} (the paper's offset is for the 4-unit pyramid)",
            )
        perturbation = PAPER_PERTURBATION
    dp = require_finite(perturbation, "perturbation", "rad")
    if dp.shape != (n,) or not np.any(dp):
        raise FieldError(
            "perturbation",
            f"must be a nonzero offset of shape ({n},), got {np.shape(perturbation)}",
        )
    _, sig_sat = cmg.envelope(u, d, n)  # normalises u and rejects u = 0
    u = u / np.linalg.norm(u)
    start = sig_sat + dp
    t_back = float(u @ cmg.momentum(start, d, n))
    if t_back <= 0:
        raise FieldError("perturbation", "moves the start set off the saturated side (uᵀh <= 0)")
    run = integrate_gimbals(start, -u, -t_back, d, n, threshold=threshold, rtol=rtol, atol=atol)
    if run.singular:
        raise FieldError(
            "perturbation",
            f"the back integration along {u} met a singularity at "
            f"t = {run.t[-1]:.6g} s; try another offset",
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
    sig0 = gimbal_set(sigma0, n, "sigma0")
    gimbal_set(sigma_target, n, "sigma_target")
    law = NullMotionSteering(sigma_target, gain_k, d, n, alpha)
    tf = float(require_finite(t_final, "t_final", "s"))
    if tf <= 0:
        raise FieldError("t_final", f"must be > 0, got {t_final!r}")
    if isinstance(n_out, bool) or not isinstance(n_out, (int, np.integer)) or n_out < 2:
        raise FieldError("n_out", f"must be an integer >= 2, got {n_out!r}")
    config = SimConfig(
        duration=tf,
        control_rate=(n_out - 1) / tf,
        substeps=1,
        law_mode="continuous",
        rtol=rtol,
        atol=atol,
    )
    return plant, law, config, {"initial_state": sig0, "record_states": True}


def gimbal_run(plant: GimbalCluster, dataset: xr.Dataset, direction: float = 1.0) -> GimbalRun:
    """The recorded run of :func:`steering_simulation` or :func:`reorient_simulation`
    (``dataset`` of its :class:`~flexsat.sim.recording.SimResult`, one case) as a
    :class:`GimbalRun`, times multiplied by ``direction`` (−1: a back integration run in
    reversed time); ``singular`` when the run's stop condition (det(CCᵀ) <= threshold) held
    (never for the null motion, which runs through singular sets)."""
    t = direction * dataset["time"].values
    sig = dataset["state"].values[0]
    d, n = plant.skew, plant.n_units
    singular = bool(np.isfinite(dataset.attrs.get("stop_time", np.nan)))
    return GimbalRun(t, sig, cmg.momentum(sig, d, n), cmg.gain(sig, d, n), singular)


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
