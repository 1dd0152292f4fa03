"""Problems in a scenario: :class:`ScenarioError` and its :class:`Problem` records.

Every problem found while loading, validating or preparing a scenario is a record of the field
path and the rule (``runs['Law I'].gains.g1`` and ``must be >= 0``), read as one line
``runs['Law I'].gains.g1: must be >= 0``. The helpers here build the paths from pydantic's
error locations (:func:`pydantic_problem`) and from the field a runtime error names as data
(:attr:`flexsat.input_checks.FieldError.field`, :func:`locate`); no message is parsed for them.
Only the runtime messages of the few modules that do not raise a
:class:`~flexsat.input_checks.FieldError` yet are read as ``field: rule`` text
(:func:`_locate`; tests/test_field_errors.py lists those modules).
"""

from __future__ import annotations

import re
from collections.abc import Iterable
from typing import TYPE_CHECKING, get_args

from pydantic import BaseModel

from flexsat.input_checks import FieldError

if TYPE_CHECKING:
    from pydantic_core import ErrorDetails


class Problem(str):
    """One problem of a scenario: the field path and the rule it breaks, as data.

    It reads as the line users see, ``"path: rule"`` (``"scenario: rule"`` for the document
    itself), so that it prints and compares as that text. ``Problem(path, rule)`` builds one.

    Attributes
    ----------
    path : str
        Dotted field path, runs named by label (``runs['Law I'].gains.g1``); ``""`` for the
        scenario as a whole.
    rule : str
        The rule and the value given (``must be >= 0, got -1``).
    """

    path: str
    rule: str

    def __new__(cls, path: str, rule: str) -> Problem:
        self = super().__new__(cls, f"{path or 'scenario'}: {rule}")
        self.path, self.rule = path, rule
        return self

    def __reduce__(self) -> tuple[type[Problem], tuple[str, str]]:
        return type(self), (self.path, self.rule)


def _problem_of(item: object) -> Problem:
    """``item`` as a :class:`Problem`; a line written as ``"path: rule"`` is split there."""
    if isinstance(item, Problem):
        return item
    path, sep, rule = str(item).partition(": ")
    return Problem(path, rule) if sep and " " not in path else Problem("", str(item))


class ScenarioError(ValueError):
    """An invalid scenario.

    Parameters
    ----------
    problems : list of Problem or str
        One problem each (a ``str`` is read as ``"path: rule"``); the exception message lists
        them all.

    Attributes
    ----------
    problems : list of Problem
        The problems, each with its :attr:`Problem.path` and :attr:`Problem.rule`.
    """

    def __init__(self, problems: Iterable[str]) -> None:
        self.problems = [_problem_of(p) for p in problems]
        count = "1 problem" if len(self.problems) == 1 else f"{len(self.problems)} problems"
        super().__init__(
            f"invalid scenario ({count}):" + "".join(f"\n  {p}" for p in self.problems)
        )

    def __reduce__(self) -> tuple[type[ScenarioError], tuple[list[Problem]]]:
        return type(self), (self.problems,)


# -- messages ----------------------------------------------------------------------------------
_HEAD = re.compile(r"^([A-Za-z_][\w.]*): ")


def _head(message: str) -> str | None:
    """The field a ``"field: rule"`` message names, or None."""
    match = _HEAD.match(message)
    return match.group(1) if match else None


def _locate(path: str, message: str) -> Problem:
    """Prefix ``message`` with the field path ``path`` (``""`` is the scenario itself).

    A message that starts with a field name (``"g1: must be >= 0"``) gets the name appended to the
    path unless the path already ends with it. This reads the text of the runtime messages that
    carry no field as data: those of the modules that do not raise a
    :class:`~flexsat.input_checks.FieldError` yet (the allow-list of
    tests/test_field_errors.py); delete it with the last of them.
    """
    head = _head(message)
    if head is None:
        return Problem(path, message)
    rule = message[len(head) + 2 :]
    if path == head or path.endswith("." + head):
        return Problem(path, rule)
    if head.startswith(path + "."):  # the message already names the path from the root
        return Problem(head, rule)
    return Problem(f"{path}.{head}" if path else head, rule)


def locate(path: str, error: Exception) -> Problem:
    """The problem ``error`` raised for the value at field path ``path``.

    A :class:`~flexsat.input_checks.FieldError` (every refusal of an input below the scenarios,
    a :class:`~flexsat.units.UnitError` included) names its field as data: it is appended to
    ``path`` (unless ``path`` already ends with it). Any other error's message is placed by
    :func:`_locate`.
    """
    if isinstance(error, FieldError):
        field = error.field
        if path == field or path.endswith("." + field):
            return Problem(path, error.rule)
        if field.startswith(path + "."):  # the error already names the path from the root
            return Problem(field, error.rule)
        return Problem(f"{path}.{field}" if path else field, error.rule)
    return _locate(path, str(error))


def item_path(index: int, label: object) -> str:
    """Path element of list item ``index``; runs are named by their label."""
    return f"[{label!r}]" if isinstance(label, str) else f"[{index}]"


def _loc_path(loc: tuple[int | str, ...], data: object) -> str:
    """Dotted field path of a pydantic error location, runs named by their label in ``data``."""
    path, node = "", data
    for key in loc:
        if isinstance(key, int):
            node = node[key] if isinstance(node, list) and 0 <= key < len(node) else None
            path += item_path(key, node.get("label") if isinstance(node, dict) else None)
        else:
            path = f"{path}.{key}" if path else str(key)
            node = node.get(key) if isinstance(node, dict) else None
    return path


def _models_in(annotation: object) -> list[type[BaseModel]]:
    """The schema models inside a field annotation (``X | None``, ``list[X]``, ...)."""
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return [annotation]
    return [m for arg in get_args(annotation) for m in _models_in(arg)]


def _allowed_keys(loc: tuple[int | str, ...], root: type[BaseModel]) -> str:
    """The keys allowed beside the unknown key at ``loc`` of a ``root`` document."""
    model = root
    for key in loc[:-1]:
        # list indices and the keys of a mapping of models (channel names) stay at the model
        if isinstance(key, str) and key in model.model_fields:
            inner = _models_in(model.model_fields[key].annotation)
            if inner:
                model = inner[0]
    return ", ".join(model.model_fields)


def pydantic_problem(error: ErrorDetails, data: object, root: type[BaseModel]) -> Problem:
    """The problem of a pydantic error dict of a ``root`` document.

    The path is pydantic's location; a validator's own error (``ctx["error"]``) is placed by
    :func:`locate`, and pydantic's messages (``Input should be ...``) name no field of their own.
    """
    cause = error.get("ctx", {}).get("error")
    path = _loc_path(error["loc"], data)
    if error["type"] == "extra_forbidden":
        return Problem(path, f"unknown key (allowed: {_allowed_keys(error['loc'], root)})")
    if isinstance(cause, Exception):
        return locate(path, cause)
    return Problem(path, error["msg"])


__all__ = ["Problem", "ScenarioError", "item_path", "locate", "pydantic_problem"]
