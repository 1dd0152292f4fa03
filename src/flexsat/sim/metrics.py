"""Closed-loop maneuver metrics, vectorized over the case axis.

The single-axis maneuver metrics are each the maximum over the samples k of one per-sample
term of a signal s_k (:func:`peak_term`, :func:`past_term`, :func:`outside_term`), or a value at
one sample (:func:`reference_end_sample`), then finished by :func:`metrics_from_reductions`.
Both ways of computing them use these functions: :func:`maneuver_metrics` on the recorded
histories (the maximum over the time axis), and the metrics-only kernel
(:func:`flexsat.sim.kernels.closed_loop_reduced`) in the loop (a running maximum, the terms
compiled by numba), so the two give the same numbers bit for bit (a maximum is exact).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any, overload

import numpy as np
import numpy.typing as npt
from numba.extending import register_jitable

from flexsat.analysis.settling import settled_at, settling_time

if TYPE_CHECKING:
    from flexsat.sim.step import Values
    from flexsat.units import FloatArray

# a per-sample term of two or more arguments has two overloads, all floats -> float (the compiled
# kernel) and any array -> array (the recorded histories): the ignore on the first is safe for the
# reason given at flexsat.sim.step.Values (floats pick the first overload)

METRIC_UNITS = {
    "settling_time_s": "s",
    "overshoot_deg": "deg",
    "peak_torque_Nm": "N m",
    "residual_energy_J": "J",
    "residual_energy_at_T_J": "J",
    "peak_tip_deflection_m": "m",
    "peak_rate_error_deg_s": "deg/s",
}


@overload
def peak_term(s: float) -> float: ...


@overload
def peak_term(s: FloatArray) -> FloatArray: ...


@register_jitable
def peak_term(s: Values) -> Values:
    """|s|: its maximum over the samples is a peak (tip deflection, rate error, torque)."""
    return np.abs(s)


@overload
def past_term(s: float, direction: float) -> float: ...  # type: ignore[overload-overlap]


@overload
def past_term(s: Values, direction: Values) -> FloatArray: ...


@register_jitable
def past_term(s: Values, direction: Values) -> Values:
    """d · s, d = ±1 the slew direction: its maximum over the samples of s = θ − θ_f is the
    largest excursion past the target (the overshoot where positive)."""
    return direction * s


@overload
def outside_term(s: float, band: float, k: float) -> float: ...  # type: ignore[overload-overlap]


@overload
def outside_term(
    s: Values, band: Values, k: FloatArray | npt.NDArray[np.integer[Any]] | float
) -> FloatArray: ...


@register_jitable
def outside_term(
    s: Values, band: Values, k: FloatArray | npt.NDArray[np.integer[Any]] | float
) -> Values:
    """k + 1 where |s_k| > band, else 0: its maximum over the samples is 1 + the last sample
    outside the band (0 if none; n_t if the last sample is outside: not settled)."""
    # numpy's stubs type an integer array + 1.0 as floating[Any]; at run time it is float64
    return (k + 1.0) * (np.abs(s) > band)  # type: ignore[return-value]


def maneuver_direction(theta0: np.ndarray, target: np.ndarray) -> np.ndarray:
    """The slew direction d = sign(θ_f − θ_0), +1 for no slew."""
    direction = np.sign(target - theta0)
    return np.where(direction == 0, 1.0, direction)


def reference_end_sample(t: np.ndarray, reference_end: np.ndarray) -> np.ndarray:
    """The sample at the end T of the reference (the first t_k >= T − 1e-12 s, at most the
    last): where ``residual_energy_at_T_J`` is read."""
    return np.minimum(np.searchsorted(t, reference_end - 1e-12), len(t) - 1)


def metrics_from_reductions(
    t: np.ndarray,
    last_outside: np.ndarray,
    past: np.ndarray,
    peak_torque: np.ndarray,
    residual_energy: np.ndarray,
    peak_tip_deflection: np.ndarray,
    peak_rate_error: np.ndarray,
    residual_energy_at_T: np.ndarray | None,
) -> dict[str, np.ndarray]:
    """The single-axis maneuver metrics (SI, angles in deg) of a batch from the maxima of
    their per-sample terms (module docstring), each (n_cases,): ``last_outside`` of
    θ − θ_f, ``past`` of d (θ − θ_f), the peaks of |u|, |tip| and |θ' − θ'_ref|, and the
    vibration energies at the last sample and at the end of the reference (None: the law has
    no reference, NaN)."""
    return {
        "settling_time_s": settled_at(t, last_outside),
        "overshoot_deg": np.degrees(np.maximum(past, 0.0)),
        "peak_torque_Nm": peak_torque,
        "residual_energy_J": residual_energy,
        "peak_tip_deflection_m": peak_tip_deflection,
        "peak_rate_error_deg_s": np.degrees(peak_rate_error),
        "residual_energy_at_T_J": (
            np.full(len(last_outside), np.nan)
            if residual_energy_at_T is None
            else residual_energy_at_T
        ),
    }


def maneuver_metrics(
    t: np.ndarray,
    theta: np.ndarray,
    theta_dot: np.ndarray,
    theta_dot_ref: np.ndarray,
    torque: np.ndarray,
    tip_deflection: np.ndarray,
    vibration_energy: np.ndarray,
    theta0: np.ndarray,
    target: np.ndarray,
    reference_end: np.ndarray | None,
    band: float,
) -> dict[str, np.ndarray]:
    """Metrics of a batch of maneuvers; every history has shape (n_cases, n_t), SI units.

    overshoot: largest excursion past the target in the direction of the maneuver.
    residual energy: vibration energy (elastic modes of the free vehicle) at the end of the run
    and at the end T of the reference (NaN when the law has no reference). Each the maximum
    over the time axis of its per-sample term (module docstring).
    """
    k = np.arange(len(t))
    direction = maneuver_direction(theta0, target)
    error = theta - target[:, None]
    at_T = None
    if reference_end is not None:
        at_T = vibration_energy[np.arange(theta.shape[0]), reference_end_sample(t, reference_end)]
    return metrics_from_reductions(
        t,
        outside_term(error, band, k).max(axis=1),
        past_term(error, direction[:, None]).max(axis=1),
        peak_term(torque).max(axis=1),
        vibration_energy[:, -1],
        peak_term(tip_deflection).max(axis=1),
        peak_term(theta_dot - theta_dot_ref).max(axis=1),
        at_T,
    )


def channel_metrics(
    histories: Mapping[str, FloatArray],
    units: Mapping[str, str],
    outputs: Sequence[str],
    inputs: Sequence[str],
    t: FloatArray,
    attitude_target: npt.ArrayLike | None = None,
    band: float | None = None,
) -> tuple[dict[str, FloatArray], dict[str, str]]:
    """Summary metrics of any plant's run, from its recorded (case, time[, component]) histories.

    For each recorded output channel: ``peak_<name>`` (largest magnitude, the Euclidean norm of
    a vector channel) and, for a scalar one, ``final_<name>``; for each input channel:
    ``peak_<name>`` and ``rms_<name>`` over the run. A three-axis run whose law has a target
    attitude (``attitude_target``, Euler parameters (..., 4)) adds ``final_pointing_error_deg``
    (the principal angle 2 arccos|β_e0| of the error quaternion at the end),
    and ``pointing_settling_time_s`` (first time after which that angle stays within ``band``,
    rad; NaN if it never does).

    Returns
    -------
    (dict, dict)
        Metrics (n_cases,) by name, and their units.
    """
    metrics: dict[str, FloatArray] = {}
    metric_units: dict[str, str] = {}

    def norm(a: FloatArray) -> FloatArray:
        return np.abs(a) if a.ndim == 2 else np.linalg.norm(a, axis=-1)

    for name in outputs:
        if name not in histories or name == "attitude":
            continue
        h = histories[name]
        metrics[f"peak_{name}"] = norm(h).max(axis=1)
        metric_units[f"peak_{name}"] = units.get(name, "")
        if h.ndim == 2:
            metrics[f"final_{name}"] = h[:, -1]
            metric_units[f"final_{name}"] = units.get(name, "")
    for name in inputs:
        if name not in histories:
            continue
        mag = norm(histories[name])
        metrics[f"peak_{name}"] = mag.max(axis=1)
        metrics[f"rms_{name}"] = np.sqrt(np.mean(mag**2, axis=1))
        metric_units[f"peak_{name}"] = metric_units[f"rms_{name}"] = units.get(name, "")
    if attitude_target is not None and "attitude" in histories:
        beta = histories["attitude"]
        target = np.asarray(attitude_target, float)
        if target.ndim < 3:  # one attitude per case (or for all), the same at every time
            target = target.reshape(-1, 1, 4)
        # scalar part of the error quaternion β_t* ⊗ β: the inner product of the two
        e0 = np.abs(np.sum(beta * target, axis=-1)).clip(max=1.0)
        angle = 2.0 * np.arccos(e0)
        metrics["final_pointing_error_deg"] = np.degrees(angle[:, -1])
        metric_units["final_pointing_error_deg"] = "deg"
        if band is not None:
            metrics["pointing_settling_time_s"] = settling_time(t, angle, band)
            metric_units["pointing_settling_time_s"] = "s"
    return metrics, metric_units
