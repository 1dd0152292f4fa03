"""Closed-loop maneuver metrics, vectorized over the case axis."""

from __future__ import annotations

import numpy as np

from flexsat.analysis.settling import settling_time

METRIC_UNITS = {
    "settling_time_s": "s",
    "overshoot_deg": "deg",
    "peak_torque_Nm": "N m",
    "residual_energy_J": "J",
    "residual_energy_at_T_J": "J",
    "peak_tip_deflection_m": "m",
    "peak_rate_error_deg_s": "deg/s",
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
    and at the end T of the reference (NaN when the law has no reference).
    """
    direction = np.sign(target - theta0)
    direction = np.where(direction == 0, 1.0, direction)
    past = direction[:, None] * (theta - target[:, None])
    out = {
        "settling_time_s": settling_time(t, theta - target[:, None], band),
        "overshoot_deg": np.degrees(np.maximum(past.max(axis=1), 0.0)),
        "peak_torque_Nm": np.abs(torque).max(axis=1),
        "residual_energy_J": vibration_energy[:, -1],
        "peak_tip_deflection_m": np.abs(tip_deflection).max(axis=1),
        "peak_rate_error_deg_s": np.degrees(np.abs(theta_dot - theta_dot_ref).max(axis=1)),
    }
    if reference_end is None:
        out["residual_energy_at_T_J"] = np.full(theta.shape[0], np.nan)
    else:
        k = np.minimum(np.searchsorted(t, reference_end - 1e-12), len(t) - 1)
        out["residual_energy_at_T_J"] = vibration_energy[np.arange(theta.shape[0]), k]
    return out


def channel_metrics(
    histories: dict,
    units: dict,
    outputs,
    inputs,
    t: np.ndarray,
    attitude_target=None,
    band: float | None = None,
) -> tuple[dict[str, np.ndarray], dict[str, str]]:
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
    metrics, metric_units = {}, {}

    def norm(a):
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
        target = np.asarray(attitude_target, float).reshape(-1, 1, 4)
        # scalar part of the error quaternion β_t* ⊗ β: the inner product of the two
        e0 = np.abs(np.sum(beta * target, axis=-1)).clip(max=1.0)
        angle = 2.0 * np.arccos(e0)
        metrics["final_pointing_error_deg"] = np.degrees(angle[:, -1])
        metric_units["final_pointing_error_deg"] = "deg"
        if band is not None:
            metrics["pointing_settling_time_s"] = settling_time(t, angle, band)
            metric_units["pointing_settling_time_s"] = "s"
    return metrics, metric_units
