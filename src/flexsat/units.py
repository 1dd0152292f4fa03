"""Unit handling at the boundary: everything inside flexsat is SI.

Published values are entered as published (oz-in-s, lbf, deg) and converted here with pint, so
the conversion factor is never typed by hand.
"""

from __future__ import annotations

import math

import pint

ureg = pint.UnitRegistry()
Q_ = ureg.Quantity


class UnitError(ValueError):
    """A quantity has the wrong dimensionality or cannot be parsed."""


def _cyclic_to_angular(q: pint.Quantity, unit: str) -> pint.Quantity:
    """pint treats the radian as dimensionless, so it would turn 1 Hz into 1 rad/s. A cyclic
    frequency asked for in angular units (and back) is converted with its 2π here."""
    given_cyclic = "hertz" in str(q.units)
    want_angular = "radian" in str(Q_(1, unit).units) and "hertz" not in str(Q_(1, unit).units)
    if given_cyclic and want_angular:
        return Q_(2 * math.pi * q.to("Hz").magnitude, "rad/s")
    if "radian" in str(q.units) and "hertz" in str(Q_(1, unit).units):
        return Q_(q.to("rad/s").magnitude / (2 * math.pi), "Hz")
    return q


def to_si(value, unit: str, field: str = "value") -> float:
    """Convert ``value`` to the SI magnitude of ``unit``'s dimension.

    Parameters
    ----------
    value : float, str or pint.Quantity
        A bare number is taken to be already in ``unit``; a string such as ``"400 ozf*in"`` or a
        Quantity is converted.
    unit : str
        The expected unit, e.g. ``"N*m"``; the result is in the SI base units of its dimension.
    field : str
        Name used in error messages.

    Raises
    ------
    UnitError
        If the value cannot be parsed, is not finite or has incompatible dimensions.
    """
    try:
        q = Q_(value) if isinstance(value, str) else value
        if not isinstance(q, pint.Quantity):
            q = Q_(float(q), unit)
        elif q.dimensionless and not Q_(1, unit).dimensionless:
            q = Q_(q.magnitude, unit)
        q = _cyclic_to_angular(q, unit)
        mag = float(q.to(unit).magnitude)
    except pint.DimensionalityError as exc:
        raise UnitError(f"{field}: incompatible units ({exc.units1} given, {unit} expected)") from exc
    except (pint.UndefinedUnitError, ValueError, TypeError, AttributeError) as exc:
        raise UnitError(f"{field}: cannot read {value!r} as a quantity in {unit} ({exc})") from exc
    si = float(Q_(mag, unit).to_base_units().magnitude)
    if not math.isfinite(si):
        raise UnitError(f"{field}: must be a finite number, got {value!r}")
    return si
