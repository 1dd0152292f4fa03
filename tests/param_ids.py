"""Test ids that are the same in every process: pytest-xdist workers must collect identical
ids, and ``repr`` of a function or object carries its memory address."""

from __future__ import annotations

import re

_ADDRESS = re.compile(r" at 0x[0-9a-fA-F]+")


def stable_id(value: object) -> str:
    """``repr(value)`` without memory addresses (``<function _unit>``)."""
    return _ADDRESS.sub("", repr(value))
