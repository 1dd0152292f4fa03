"""Input checks shared by every constructor: one clear message naming the field and the rule."""

from __future__ import annotations

import numpy as np


def _real(value, field: str, noun: str):
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
        raise ValueError(f"{field}: must be a real {noun}, got a complex value (largest "
                         f"|imaginary part| {np.max(imag):.3g}, which would be dropped)")
    return np.real(value)


def require_finite(value, field: str) -> np.ndarray:
    if isinstance(value, (str, bytes)):
        raise ValueError(
            f"{field}: must be a number in SI units, got the string {value!r} (quantities with "
            "units are converted at the boundary: flexsat.units.to_si)"
        )
    real = _real(value, field, "number")
    try:
        arr = np.asarray(real, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{field}: must be a number, got {value!r}") from None
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{field}: must be finite (no NaN or inf), got {value!r}")
    return arr


def require_positive(value, field: str) -> np.ndarray:
    arr = require_finite(value, field)
    if np.any(arr <= 0):
        raise ValueError(f"{field}: must be > 0, got {value!r}")
    return arr


def require_nonneg(value, field: str) -> np.ndarray:
    arr = require_finite(value, field)
    if np.any(arr < 0):
        raise ValueError(f"{field}: must be >= 0, got {value!r}")
    return arr


def require_count(value, field: str) -> int:
    """A positive integer (bools and fractional numbers refused)."""
    if isinstance(value, bool):
        raise ValueError(f"{field}: must be a positive integer, got {value!r}")
    number = float(require_finite(value, field))
    if number != int(number) or number < 1:
        raise ValueError(f"{field}: must be a positive integer, got {value!r}")
    return int(number)


def require_numeric(value, field: str, noun: str = "array") -> np.ndarray:
    """A finite numeric array (a copy); strings and non-numbers are refused, naming the field."""
    if isinstance(value, (str, bytes)):
        raise ValueError(f"{field}: must be a numeric {noun}, got the string {value!r}")
    real = _real(value, field, noun)
    try:
        arr = np.array(real, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{field}: must be a numeric {noun}, got {type(value).__name__}") from None
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{field}: must be finite (no NaN or inf), got shape {arr.shape} with "
                         f"{int(np.sum(~np.isfinite(arr)))} non-finite entries")
    return arr
