"""Units of the reference problems' ``parameters:`` in a ``design`` scenario (issue 23).

A ``design`` document overrides fields of its reference problem (``parameters:``). Each value
is converted once, here, to the SI the problem's dataclass holds: a bare number is taken in the
field's SI unit, a unit string or a pint Quantity is converted (``hub_inertia: 50 ozf*in*s**2``),
a pair of bounds is a list of two quantities, a count must be an integer. An unknown field, a
wrong dimension, a boolean where a number goes or a fractional count is refused naming
``parameters.<field>`` (``parameters.hub_inertia: ...``). A problem without a unit table
(:data:`PARAMETER_UNITS`) takes its fields as given (SI numbers).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any

from flexsat import limits
from flexsat.input_checks import FieldError
from flexsat.limits import is_integral
from flexsat.units import to_si

__all__ = ["COUNT", "COUNT_LIMITS", "PARAMETER_UNITS", "reference_parameters"]

#: the unit of an integer count (in [1, its bound in :data:`COUNT_LIMITS`])
COUNT = "count"
#: the largest value of each count field (resource limits of :mod:`flexsat.limits`)
COUNT_LIMITS = {
    "elements": limits.MAX_ELEMENTS,
    "booms": 64,
    "elastic_modes": limits.MAX_MODES,
    "n_modes": limits.MAX_MODES,
    "peak_order": 64,
}
_PAIR_M = ("m", "m")

#: per reference problem (the names of flexsat.scenarios.design_problem.REFERENCE_PROBLEMS):
#: each field's SI unit, a tuple for a fixed-length list of quantities, :data:`COUNT`
PARAMETER_UNITS: dict[str, dict[str, str | tuple[str, ...]]] = {
    "hub_boom_codesign": {
        "length": "m",
        "elements": COUNT,
        "youngs_modulus": "Pa",
        "density": "kg/m**3",
        "hub_inertia": "kg*m**2",
        "booms": COUNT,
        "tip_mass": "kg",
        "damping": "",
        "elastic_modes": COUNT,
        "weights": ("1/(rad**2*s)", "s/rad**2", "1/(m**2*s)"),
        "control_weight": "1/(N**2*m**2*s)",
        "initial_angle": "rad",
        "mass_weight": "1/kg",
        "frequency_min_hz": "Hz",
        "thickness_bounds": _PAIR_M,
        "diameter_bounds": _PAIR_M,
        "start": _PAIR_M,
        "control_rate": "Hz",
        "maneuver_time": "s",
        "peak_order": COUNT,
        "settling_band": "rad",
        "settling_width": "",
    },
    "cantilever_tube": {
        "length": "m",
        "youngs_modulus": "Pa",
        "density": "kg/m**3",
        "omega_min": "rad/s",
        "thickness_bounds": _PAIR_M,
        "diameter_bounds": _PAIR_M,
    },
    "tamu_codesign": {
        "thickness_bounds": ("", ""),
        "g1_bounds": ("N*m/rad", "N*m/rad"),
        "g2_bounds": ("N*m*s/rad", "N*m*s/rad"),
        "alpha_bounds": ("", ""),
        "duration": "s",
        "n_modes": COUNT,
        "fd_step": "",
        "band_width": "",
        "friction_smoothing": "rad/s",
    },
    "agrawal_bang_ppf_codesign": {
        "n_modes": COUNT,
        "zeta_f": "",
        "control_weight": "m**2/(N**2*m**2)",
        "stiffness_margin": "",
        "effort_max": "N*m",
        "gain_fraction": "",
        "ratio_bounds": ("", ""),
        "start_gain": "N*m",
    },
}


def reference_parameters(problem: str, cls: type, parameters: Mapping[str, Any]) -> dict[str, Any]:
    """``parameters`` of reference problem ``problem`` (dataclass ``cls``) in SI.

    Raises
    ------
    FieldError
        ``parameters.<field>``: not a field of the problem, a wrong dimension, a boolean, a
        fractional count, a list of the wrong length.
    """
    fields = [f.name for f in dataclasses.fields(cls) if f.init and not f.name.startswith("_")]
    units = PARAMETER_UNITS.get(problem, {})
    out: dict[str, Any] = {}
    for key, value in parameters.items():
        path = f"parameters.{key}"
        if key not in fields:
            raise FieldError(path, f"not a parameter of {problem} ({', '.join(fields)})")
        unit = units.get(key)
        out[key] = value if unit is None else _convert(value, unit, path)
    return out


def _convert(value: Any, unit: str | tuple[str, ...], path: str) -> Any:
    if isinstance(unit, tuple):
        if isinstance(value, (str, bytes)) or not isinstance(value, (list, tuple)):
            raise FieldError(path, f"a list of {len(unit)} values, got {value!r}")
        if len(value) != len(unit):
            raise FieldError(path, f"must have {len(unit)} values, got {len(value)}")
        return tuple(_scalar(v, u, f"{path}[{i}]") for i, (v, u) in enumerate(zip(value, unit)))
    return _scalar(value, unit, path)


def _scalar(value: Any, unit: str, path: str) -> float | int:
    if isinstance(value, bool):
        raise FieldError(path, f"must be a number (with a unit where it has one), got {value!r}")
    if unit == COUNT:
        top = COUNT_LIMITS.get(path.rpartition(".")[2], limits.MAX_ELEMENTS)
        if not is_integral(value) or not 1 <= value <= top:
            raise FieldError(path, f"must be an integer in [1, {top}], got {value!r}")
        return int(value)
    return to_si(value, unit, path)
