"""The example of docs/conformance.md (a torsion pendulum and a rate damper) and the helpers
the tests of the conformance checks share (tests/testing/)."""

from __future__ import annotations

import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

DOC = Path(__file__).parents[1] / "docs" / "conformance.md"


def python_blocks() -> list[str]:
    """The page's Python blocks, in order."""
    return re.findall(r"```python\n(.*?)```", DOC.read_text(), re.S)


def documented_example() -> dict[str, Any]:
    """The namespace of the page's first block: TorsionPendulum, RateDamper, ..."""
    namespace: dict[str, Any] = {}
    exec(compile(python_blocks()[0], str(DOC), "exec"), namespace)
    return namespace


def assert_fails(check_name: str, run: Callable[..., Any], *args: Any) -> None:
    """``run(*args)`` fails the conformance check ``check_name``, saying so."""
    with pytest.raises(AssertionError, match=rf"fails {check_name}: "):
        run(*args)


def one_check(checks: list[Any], name: str) -> Any:
    """The check called ``name`` among ``checks``."""
    (check,) = [c for c in checks if c.name == name]
    return check
