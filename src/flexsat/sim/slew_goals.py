r"""Performance goals of a finite-time slew (EPS slew study c. 1989,
"Simulation Results").

The paper judges each closed-loop slew of the Earth Pointing Satellite against three goals:

1. the Euler-angle error is below **3 %** of the desired angle (1 rad per axis: 30 mrad) at
   **125 %** of the nominal maneuver time T;
2. the peak elastic displacement at the antenna rim is below **1/10 of the open-loop value** at
   125 % of T;
3. elastic displacements and control effort are kept small during the maneuver (reported, not a
   pass/fail goal: peak torques, peak torque perturbation, peak forces).

Goal 2 reads "at 125 % of the nominal time" a value of an oscillation; this module takes the
peak from 1.25 T to the end of the record (the vibration that remains at 1.25 T: its amplitude
rather than its phase at one instant, so a record should run on past 1.25 T by about a period
of the first mode) and reports the peak during the slew [0, T] beside it (the paper's "peak
deformations during the slew drop by 1.5–2×", Fig. 7).
A rim point's deflection is the Euclidean norm of its displacement components; the peak is over
every rim point.

All histories carry a leading case axis and SI units; the angle tolerance of an axis is the
fraction times the largest commanded angle (3 % of 1 rad for the paper's (1, 1, 1) rad slew).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from flexsat.input_checks import (
    FieldError,
    require_finite,
    require_positive,
    require_positive_scalar,
)
from flexsat.units import FloatArray

__all__ = ["SlewGoals", "euler_angle_error", "slew_goal_metrics"]


@dataclass(frozen=True)
class SlewGoals:
    """The goals' numbers (defaults: EPS slew study c. 1989 "Simulation Results")."""

    #: angle tolerance as a fraction of the commanded angle
    angle_fraction: float = 0.03
    #: evaluation time as a multiple of the nominal maneuver time
    evaluation: float = 1.25
    #: required open-loop / closed-loop ratio of the peak rim deflection from the evaluation time
    deflection_ratio: float = 10.0

    def __post_init__(self) -> None:
        for name in ("angle_fraction", "deflection_ratio"):
            require_positive_scalar(getattr(self, name), name)
        evaluation = require_finite(self.evaluation, "evaluation")
        if evaluation.ndim != 0:
            raise FieldError("evaluation", f"must be one number, got shape {evaluation.shape}")
        if not float(evaluation) >= 1.0:
            raise FieldError(
                "evaluation",
                f"must be >= 1 (a multiple of the maneuver time T), got {self.evaluation}",
            )


def euler_angle_error(angles: npt.ArrayLike, target: npt.ArrayLike) -> FloatArray:
    """Angle minus target, wrapped to [−π, π) (rad), broadcasting ``target`` (..., 3)."""
    e = np.asarray(angles, float) - np.asarray(target, float)
    return (e + np.pi) % (2 * np.pi) - np.pi


def _at(t: FloatArray, history: FloatArray, time: float) -> FloatArray:
    """History (cases, time, ...) linearly interpolated at one time inside the record."""
    k = int(np.clip(np.searchsorted(t, time, side="right") - 1, 0, len(t) - 2))
    w = (time - t[k]) / (t[k + 1] - t[k])
    return (1.0 - w) * history[:, k] + w * history[:, k + 1]


def _peak(t: FloatArray, deflection: FloatArray, start: float, stop: float) -> FloatArray:
    """Largest rim-point deflection norm over the samples in [start, stop], per case."""
    inside = (t >= start - 1e-9 * stop) & (t <= stop + 1e-9 * stop)
    if not inside.any():  # the record ends at the evaluation time: its last sample
        inside = t == t[-1]
    return np.linalg.norm(deflection[:, inside], axis=-1).max(axis=(1, 2))


def slew_goal_metrics(
    t: npt.ArrayLike,
    duration: float,
    euler123: npt.ArrayLike,
    target: npt.ArrayLike,
    deflection: npt.ArrayLike,
    deflection_open: npt.ArrayLike,
    torque: npt.ArrayLike | None = None,
    torque_nominal: npt.ArrayLike | None = None,
    forces: npt.ArrayLike | None = None,
    goals: SlewGoals = SlewGoals(),
) -> tuple[dict[str, npt.NDArray[Any]], dict[str, str]]:
    """The goals of a batch of slews (module docstring).

    Parameters
    ----------
    t : (n_t,) array
        Sample times, s; must reach ``goals.evaluation × duration``.
    duration : float
        Nominal maneuver time T, s.
    euler123 : (n_cases, n_t, 3) array
        1-2-3 Euler angles of the body, rad.
    target : (3,) array
        Commanded 1-2-3 angles, rad.
    deflection, deflection_open : (n_cases, n_t, n_points, 3) arrays
        Elastic displacements of the rim points (body axes, m), closed loop and open loop (the
        nominal torque alone; one open-loop case is broadcast to every case).
    torque, torque_nominal : (n_cases, n_t, 3) arrays, optional
        Applied torque and the nominal one, N m (peaks of both and of their difference).
    forces : (n_cases, n_t, n_forces) array, optional
        Point forces, N.
    goals : SlewGoals

    Returns
    -------
    (dict, dict)
        Metrics (n_cases,) by name, and their units; the goal verdicts are booleans
        ``angle_goal_met``, ``deflection_goal_met`` and ``goals_met`` (both).
    """
    t = require_finite(t, "t", "s")
    T = float(require_positive(duration, "duration", "s"))
    t_eval = goals.evaluation * T
    if t.ndim != 1 or len(t) < 2 or t[0] > 0.0 or t[-1] < t_eval * (1 - 1e-9):
        raise FieldError(
            "t",
            f"the record must span [0, {t_eval:g}] s ({goals.evaluation:g} T) "
            f"to evaluate the goals, got [{t[0]:g}, {t[-1]:g}] s",
        )
    angles = np.asarray(euler123, float)
    target = np.asarray(target, float)
    defl = np.asarray(deflection, float)
    defl_open = np.broadcast_to(np.asarray(deflection_open, float), defl.shape)
    tolerance = goals.angle_fraction * float(np.max(np.abs(target)))
    if tolerance <= 0.0:
        raise FieldError("target", "a slew of zero angle has no angle goal (3 % of 0 rad)")

    error = np.abs(euler_angle_error(_at(t, angles, min(t_eval, t[-1])), target))
    slew = _peak(t, defl, 0.0, T)
    after = _peak(t, defl, t_eval, t[-1])
    slew_open = _peak(t, defl_open, 0.0, T)
    after_open = _peak(t, defl_open, t_eval, t[-1])
    with np.errstate(divide="ignore"):
        ratio = np.where(after > 0, after_open / after, np.inf)
        ratio_slew = np.where(slew > 0, slew_open / slew, np.inf)
    metrics: dict[str, npt.NDArray[Any]] = {
        "angle_error_mrad": 1e3 * error.max(axis=-1),
        "angle_tolerance_mrad": np.full(len(error), 1e3 * tolerance),
        "angle_goal_met": error.max(axis=-1) <= tolerance,
        "peak_rim_deflection_slew_m": slew,
        "peak_rim_deflection_after_m": after,
        "open_loop_rim_deflection_after_m": after_open,
        "deflection_ratio_after": ratio,
        "deflection_ratio_slew": ratio_slew,
        "deflection_goal_met": ratio >= goals.deflection_ratio,
    }
    # both goals at once: what a Monte Carlo's probability of success counts
    metrics["goals_met"] = metrics["angle_goal_met"] & metrics["deflection_goal_met"]
    for axis, name in enumerate("xyz"):
        metrics[f"angle_error_{name}_mrad"] = 1e3 * error[:, axis]
    units = {k: "mrad" for k in metrics if k.endswith("_mrad")}
    units.update({k: "m" for k in metrics if k.endswith("_m")})
    if torque is not None:
        tau = np.asarray(torque, float)
        for axis, name in enumerate("xyz"):
            metrics[f"peak_torque_{name}_Nm"] = np.abs(tau[..., axis]).max(axis=1)
        if torque_nominal is not None:
            delta = tau - np.asarray(torque_nominal, float)
            metrics["peak_torque_perturbation_Nm"] = np.abs(delta).max(axis=(1, 2))
    if forces is not None and np.size(forces):
        metrics["peak_force_N"] = np.abs(np.asarray(forces, float)).max(axis=(1, 2))
    units.update({k: "N m" for k in metrics if k.endswith("_Nm")})
    units.update({k: "N" for k in metrics if k.endswith("_N")})
    return metrics, units
