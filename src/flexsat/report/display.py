"""Readable names and units of report metrics: one table for every scenario kind.

The data files keep the machine names (``settling_time_s``, ``peak_torque_Nm``): stable keys a
script reads. A report page shows a person :func:`metric_label` of a name instead, e.g.
``Settling time (s)``. A name listed in :data:`METRICS` gets its entry there (a name and a unit
written out, and what it means where the words alone would not say); any other name is read by
the rules every kind's names follow:

- the unit is the name's suffix (:data:`UNIT_SUFFIXES`, the longest that matches:
  ``_deg_s`` is deg/s, ``_Nm`` is N m, ``_arcsec``, ``_Hz``, ``_s``, ...) or, failing that, the
  unit the dataset gives the metric (``units`` attribute), else none (a ratio, a count, a
  verdict);
- the words are the rest with underscores as spaces, abbreviations upper-case (``rms``,
  ``nees``, ``era``: :data:`ABBREVIATIONS`) and the first letter capitalised.

Deliberately free of numpy: the console and the page both read it.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class MetricName:
    """How a metric is shown: ``name`` (words), ``unit`` ("" for none) and, where the words
    need it, ``note`` (a sentence on what it measures)."""

    name: str
    unit: str = ""
    note: str = ""

    @property
    def label(self) -> str:
        """``name (unit)``, or ``name`` alone without a unit."""
        return f"{self.name} ({self.unit})" if self.unit else self.name


#: the named metrics of the built-in kinds (those the suffix rules would read less well)
METRICS: dict[str, MetricName] = {
    # maneuver and simulation runs (flexsat.sim.metrics)
    "settling_time_s": MetricName("Settling time", "s", "last exit from the settling band"),
    "overshoot_deg": MetricName("Overshoot", "deg", "past the commanded hub angle"),
    "peak_torque_Nm": MetricName("Peak torque", "N m"),
    "residual_energy_J": MetricName(
        "Residual vibration energy", "J", "appendage energy at the end of the run"
    ),
    "residual_energy_at_T_J": MetricName(
        "Vibration energy at T", "J", "appendage energy at the end of the maneuver time T"
    ),
    "peak_tip_deflection_m": MetricName("Peak tip deflection", "m"),
    "peak_rate_error_deg_s": MetricName("Peak rate error", "deg/s", "against the reference"),
    "final_pointing_error_deg": MetricName("Final pointing error", "deg"),
    "pointing_settling_time_s": MetricName("Pointing settling time", "s"),
    # slew (EPS slew study c. 1989)
    "angle_error_mrad": MetricName("Euler-angle error at 1.25 T", "mrad"),
    "angle_goal_met": MetricName("Angle goal met"),
    "deflection_goal_met": MetricName("Deflection goal met"),
    "deflection_ratio_after": MetricName("Rim deflection open/closed from 1.25 T"),
    "deflection_ratio_slew": MetricName("Rim deflection open/closed during the slew"),
    "peak_rim_deflection_after_m": MetricName("Peak rim deflection from 1.25 T", "m"),
    "peak_torque_perturbation_Nm": MetricName("Peak torque perturbation", "N m"),
    "peak_force_N": MetricName("Peak force", "N"),
    # control moment gyroscopes: momenta in units of one rotor's momentum h
    "envelope_h": MetricName("Momentum envelope along the demand", "h", "h: one rotor's momentum"),
    "final_momentum_h": MetricName("Final momentum", "h", "h: one rotor's momentum"),
    "final_momentum_along_demand_h": MetricName("Final momentum along the demand", "h"),
    "peak_momentum_h": MetricName("Peak momentum", "h", "h: one rotor's momentum"),
    "peak_momentum_ft_lb_s": MetricName("Peak momentum", "ft lb s"),
    "min_gain": MetricName("Least steering gain", "", "the singularity measure of the cluster"),
    "final_gain": MetricName("Final steering gain"),
    # star tracker
    "nees_mean": MetricName("Mean NEES", "", "normalised estimation error squared"),
    "accepted_rate": MetricName("Accepted fraction"),
    "identification_rate": MetricName("Identified fraction"),
    # identification
    "true_hz": MetricName("True frequency", "Hz"),
    "era_hz": MetricName("ERA frequency", "Hz"),
    "a_priori_hz": MetricName("A priori frequency", "Hz"),
    "updated_hz": MetricName("Updated frequency", "Hz"),
}

#: unit suffixes of metric names, longest first, and the unit each stands for
UNIT_SUFFIXES: tuple[tuple[str, str], ...] = tuple(
    sorted(
        {
            "_ft_lb_s": "ft lb s",
            "_deg_s": "deg/s",
            "_rad_s": "rad/s",
            "_arcsec": "arcsec",
            "_mrad": "mrad",
            "_deg": "deg",
            "_rad": "rad",
            "_Nm": "N m",
            "_Hz": "Hz",
            "_hz": "Hz",
            "_mm": "mm",
            "_kg": "kg",
            "_J": "J",
            "_N": "N",
            "_W": "W",
            "_m": "m",
            "_s": "s",
        }.items(),
        key=lambda item: -len(item[0]),
    )
)

#: words shown upper-case
ABBREVIATIONS = frozenset({"rms", "nees", "era", "okid", "mac", "lqg", "lqr", "ppf", "cmg", "dc"})


def _words(stem: str) -> str:
    words = [w.upper() if w in ABBREVIATIONS else w for w in stem.split("_") if w]
    text = " ".join(words) or stem
    return text[:1].upper() + text[1:]


def metric_name(name: str, unit: str | None = None) -> MetricName:
    """How the metric ``name`` is shown (module docstring); ``unit`` is the dataset's unit of
    it, used when the name has no unit suffix."""
    if name in METRICS:
        return METRICS[name]
    for suffix, shown in UNIT_SUFFIXES:
        if name.endswith(suffix) and len(name) > len(suffix):
            return MetricName(_words(name[: -len(suffix)]), shown)
    return MetricName(_words(name), unit or "")


def metric_label(name: str, unit: str | None = None) -> str:
    """``Name (unit)`` of the metric ``name`` (:func:`metric_name`)."""
    return metric_name(name, unit).label


__all__ = [
    "ABBREVIATIONS",
    "METRICS",
    "UNIT_SUFFIXES",
    "MetricName",
    "metric_label",
    "metric_name",
]
