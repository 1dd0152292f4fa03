"""Input checks shared by every constructor: one clear message naming the field and the rule.

Each check takes the field's SI ``unit`` where the field is a physical quantity: a number is then
taken in that unit and a pint Quantity or a unit string is converted to it
(:func:`flexsat.units.to_si_array`); ``""`` declares a dimensionless field. Without a unit only
plain numbers are accepted: a Quantity is refused rather than stripped of its unit.

A refusal is a :class:`FieldError` (``str`` ``"field: rule"``, the field as data), defined in
:mod:`flexsat.units` beside :class:`~flexsat.units.UnitError`, which is one, and imported from
here by the layers above.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import numpy.typing as npt

# FieldError lives in flexsat.units (a UnitError is one; units cannot import this module) and
# is exported from here, where every layer takes its checks from
from flexsat.units import FieldError as FieldError
from flexsat.units import (
    FloatArray,
    FrequencyArray,
    QuantityArrayLike,
    UnitError,
    holds_quantity,
    to_si_array,
)


def _real(value: Any, field: str, noun: str) -> Any:
    """``value``, or its real part when it is complex with every imaginary part exactly 0.

    A nonzero imaginary part, which the float conversion would silently drop, is refused.
    """
    try:
        is_complex = np.iscomplexobj(value)
    except (TypeError, ValueError):
        return value  # not array-like: the float conversion gives the message
    if not is_complex:
        return value
    imag = np.abs(np.imag(value))
    if np.any(imag != 0):
        raise FieldError(
            field,
            f"must be a real {noun}, got a complex value (largest "
            f"|imaginary part| {np.max(imag):.3g}, which would be dropped)",
        )
    return np.real(value)


def _plain_numbers(value: object, field: str) -> None:
    """Refuse a Quantity where no unit is declared: ``np.asarray`` would drop its unit."""
    if isinstance(value, FrequencyArray):
        value.si("", field)  # refused, naming its unit
    if holds_quantity(value):
        raise UnitError(
            field,
            "takes a plain number here (no unit is declared for it), got a quantity with units "
            f"({str(value)[:80]}); convert it yourself, its unit is not dropped silently",
        )


def require_finite(value: QuantityArrayLike, field: str, unit: str | None = None) -> FloatArray:
    """``value`` as a finite float array, in SI when ``unit`` is given (see the module)."""
    if unit is not None:
        arr = to_si_array(value, unit, field)
    else:
        _plain_numbers(value, field)
        if isinstance(value, (str, bytes)):
            raise FieldError(
                field,
                f"must be a number in SI units, got the string {value!r} (quantities with "
                "units are converted at the boundary: flexsat.units.to_si)",
            )
        real = _real(value, field, "number")
        try:
            arr = np.asarray(real, dtype=float)
        except (TypeError, ValueError):
            raise FieldError(field, f"must be a number, got {value!r}") from None
    if not np.all(np.isfinite(arr)):
        raise FieldError(field, f"must be finite (no NaN or inf), got {value!r}")
    return arr


def require_positive(value: QuantityArrayLike, field: str, unit: str | None = None) -> FloatArray:
    """``value`` as a float array of numbers > 0, in SI when ``unit`` is given (see the module)."""
    arr = require_finite(value, field, unit)
    if np.any(arr <= 0):
        raise FieldError(field, f"must be > 0, got {value!r}")
    return arr


def require_positive_scalar(value: QuantityArrayLike, field: str, unit: str | None = None) -> float:
    """``value`` as one finite number > 0, in SI when ``unit`` is given (see the module)."""
    arr = require_positive(value, field, unit)
    if arr.ndim != 0:
        raise FieldError(field, f"must be one number, got shape {arr.shape}")
    return float(arr)


def require_nonneg(value: QuantityArrayLike, field: str, unit: str | None = None) -> FloatArray:
    """``value`` as a float array of numbers >= 0, in SI when ``unit`` is given (see the module)."""
    arr = require_finite(value, field, unit)
    if np.any(arr < 0):
        raise FieldError(field, f"must be >= 0, got {value!r}")
    return arr


#: the signature of the checks above, as :func:`set_si` calls them
Check = Callable[[Any, str, str], FloatArray]


def set_si(obj: object, name: str, check: Check, unit: str, field: str | None = None) -> None:
    """Replace attribute ``name`` of a frozen dataclass by ``check(value, field, unit)``, its
    value checked and converted to SI (a float for a scalar), so the object holds SI numbers
    whatever the caller passed (a number in SI, a pint Quantity or a unit string)."""
    arr = check(getattr(obj, name), field or name, unit)
    object.__setattr__(obj, name, float(arr) if arr.ndim == 0 else arr)


def require_scalar(value: QuantityArrayLike, field: str, unit: str | None = None) -> float:
    """``value`` as one finite number, in SI when ``unit`` is given (see the module)."""
    arr = require_finite(value, field, unit)
    if arr.ndim != 0:
        raise FieldError(field, f"must be one number, got shape {arr.shape}")
    return float(arr)


def require_count(value: npt.ArrayLike, field: str) -> int:
    """A positive integer (bools and fractional numbers refused)."""
    if isinstance(value, (bool, np.bool_)):
        raise FieldError(field, f"must be a positive integer, got {value!r}")
    number = require_scalar(value, field)
    if number != int(number) or number < 1:
        raise FieldError(field, f"must be a positive integer, got {value!r}")
    return int(number)


def require_numeric(value: npt.ArrayLike, field: str, noun: str = "array") -> FloatArray:
    """A finite numeric array (a copy); strings and non-numbers are refused, naming the field."""
    _plain_numbers(value, field)
    if isinstance(value, (str, bytes)):
        raise FieldError(field, f"must be a numeric {noun}, got the string {value!r}")
    real = _real(value, field, noun)
    try:
        arr = np.array(real, dtype=float)
    except (TypeError, ValueError):
        raise FieldError(field, f"must be a numeric {noun}, got {type(value).__name__}") from None
    if not np.all(np.isfinite(arr)):
        raise FieldError(
            field,
            f"must be finite (no NaN or inf), got shape {arr.shape} with "
            f"{int(np.sum(~np.isfinite(arr)))} non-finite entries",
        )
    return arr


def require_physical_inertia(J: FloatArray, field: str, definite: bool = True) -> FloatArray:
    r"""``J`` (..., 3, 3), kg·m², checked to be an inertia tensor some mass distribution has:
    symmetric (:math:`|I - I^T| \le 10^{-12}\max|I|`), positive definite (only semi-definite
    when not ``definite``: a point mass has no inertia), and with principal moments satisfying
    the triangle inequality :math:`I_a + I_b \ge I_c`, since
    :math:`I_a + I_b - I_c = 2\int r_c^2\,dm \ge 0` in principal axes (each moment
    :math:`I_a = \int (r_b^2 + r_c^2)\,dm`), allowed a round-off of :math:`10^{-12} I_c` (the
    flat-plate limit is an equality).

    Raises
    ------
    FieldError
        ``field``: the rule broken and the principal moments.
    """
    scale = np.abs(J).max(axis=(-2, -1))
    if np.any(np.abs(J - np.swapaxes(J, -1, -2)).max(axis=(-2, -1)) > 1e-12 * scale):
        raise FieldError(field, "must be symmetric (|I − Iᵀ| <= 1e-12 max|I|)")
    eig = np.linalg.eigvalsh(J)
    if definite and np.any(eig[..., 0] <= 0):
        raise FieldError(
            field,
            f"must be positive definite, smallest principal moment {eig[..., 0].min():.3g} kg·m²",
        )
    if not definite and np.any(eig[..., 0] < -1e-12 * scale):
        raise FieldError(
            field,
            "must be positive semi-definite, smallest principal moment "
            f"{eig[..., 0].min():.3g} kg·m²",
        )
    gap = eig[..., 0] + eig[..., 1] - eig[..., 2]
    if np.any(gap < -1e-12 * eig[..., 2]):
        k = np.unravel_index(np.argmin(gap / eig[..., 2]), gap.shape)
        raise FieldError(
            field,
            f"principal moments {np.round(eig[k], 6).tolist()} kg·m² "
            f"violate the triangle inequality I1 + I2 >= I3 (no mass distribution "
            f"has them)",
        )
    return J
