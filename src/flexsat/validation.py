"""Input checks shared by every constructor: one clear message naming the field and the rule."""

from __future__ import annotations

import numpy as np


def require_finite(value, field: str) -> np.ndarray:
    arr = np.asarray(value, dtype=float)
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
