"""The one JSON conversion of report data (``metrics.json``, ``summary.json``,
``identification.json``): numpy values made plain, a non-finite number made ``null`` with its
reason stated beside it, and a writer that refuses a NaN token outright.

JSON (RFC 8259 §6) has no NaN or Infinity: ``json.dumps`` writes the tokens ``NaN``/``Infinity``
by default, which strict readers (a browser's ``JSON.parse``, jq, most languages' parsers)
refuse. Here a non-finite float becomes ``null`` and the mapping that holds it gains (or
extends) a ``null_reasons`` entry ``{key: reason}``: a "no data" result is stated as such, not
silently dropped. A kind that knows why a value is missing states it itself (its own
``null_reasons`` entry is kept); otherwise the reason names the number (``"not a number
(NaN)"``, ``"+infinity"``). :func:`dumps` then serialises with ``allow_nan=False``, so that a
non-finite number that escaped the conversion is an error, never an invalid file.
"""

from __future__ import annotations

import json
import math
from typing import Any

import numpy as np

#: the key of a mapping that says why some of its values are null
NULL_REASONS = "null_reasons"


def _reason(value: float) -> str:
    if math.isnan(value):
        return "not a number (NaN): no data"
    return "+infinity" if value > 0 else "-infinity"


def _finite(value: Any) -> tuple[Any, str | None]:
    """``value`` JSON-ready, and why it (or an element of it) became null, if it did."""
    if isinstance(value, dict):
        return json_ready(value), None
    if isinstance(value, np.ndarray):
        value = value.tolist()
    if isinstance(value, (list, tuple)):
        items, reasons = [], []
        for index, item in enumerate(value):
            clean, why = _finite(item)
            items.append(clean)
            if why is not None:
                reasons.append(f"[{index}] {why}")
        return items, ("; ".join(reasons) if reasons else None)
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None, _reason(value)
    return value, None


def json_ready(value: Any) -> Any:
    """A JSON-ready copy of ``value`` (mappings, sequences, numpy arrays and scalars, numbers,
    strings, None): keys as strings, numpy values plain, every non-finite float ``null`` with
    its reason in the enclosing mapping's :data:`NULL_REASONS` (module docstring).

    A top-level non-finite scalar or one inside lists only becomes ``null`` without a place to
    state why; report data are mappings (records, summaries), where it always has one.
    """
    if not isinstance(value, dict):
        return _finite(value)[0]
    out: dict[str, Any] = {}
    reasons: dict[str, str] = {}
    for key, item in value.items():
        if key == NULL_REASONS:
            continue
        out[str(key)], why = _finite(item)
        if why is not None:
            reasons[str(key)] = why
    stated = value.get(NULL_REASONS) or {}
    reasons.update({str(k): str(v) for k, v in stated.items()})  # the kind's own reasons win
    if reasons:
        out[NULL_REASONS] = reasons
    return out


def dumps(value: Any) -> str:
    """``value`` as indented, strictly valid JSON text (:func:`json_ready`, then
    ``allow_nan=False``), with a final newline.

    Raises
    ------
    ValueError
        If a non-finite number is left (cannot happen after :func:`json_ready`; the check
        makes an invalid file impossible rather than unlikely).
    """
    return json.dumps(json_ready(value), indent=2, allow_nan=False) + "\n"


__all__ = ["NULL_REASONS", "dumps", "json_ready"]
