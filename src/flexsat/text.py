"""Display formatting shared by the command line and the reports."""

from __future__ import annotations

#: shown where a value does not exist (not settled, not measured, unknown truth)
MISSING = "–"


def format_optional(value: object, spec: str) -> str:
    """``format(value, spec)``, or :data:`MISSING` for None."""
    return MISSING if value is None else format(value, spec)


__all__ = ["MISSING", "format_optional"]
