"""Problems in a scenario: :class:`ScenarioError` and its ``field.path: rule`` messages.

Every problem found while loading, validating or preparing a scenario becomes one line naming
the field (``runs['Law I'].gains.g1: must be >= 0``); the helpers here build those paths from
pydantic's error locations and from the ``field: rule`` messages of the runtime classes.
"""

from __future__ import annotations

import re
from typing import get_args

from pydantic import BaseModel


class ScenarioError(ValueError):
    """An invalid scenario.

    Parameters
    ----------
    problems : list of str
        One ``field.path: rule`` message per problem; the exception message lists them all.
    """

    def __init__(self, problems):
        self.problems = list(problems)
        count = "1 problem" if len(self.problems) == 1 else f"{len(self.problems)} problems"
        super().__init__(
            f"invalid scenario ({count}):" + "".join(f"\n  {p}" for p in self.problems)
        )


# -- messages ----------------------------------------------------------------------------------
_HEAD = re.compile(r"^([A-Za-z_][\w.]*): ")


def _head(message: str) -> str | None:
    """The field a ``"field: rule"`` message names, or None."""
    match = _HEAD.match(message)
    return match.group(1) if match else None


def _locate(path: str, message: str) -> str:
    """Prefix ``message`` with the field path ``path`` (``""`` is the scenario itself).

    A message that starts with a field name (``"g1: must be >= 0"``) gets the name appended to the
    path unless the path already ends with it.
    """
    head = _head(message)
    if head is None:
        return f"{path or 'scenario'}: {message}"
    if path == head or path.endswith("." + head):
        return path + message[len(head) :]
    return f"{path}.{message}" if path else message


def _item(index: int, label) -> str:
    """Path element of list item ``index``; runs are named by their label."""
    return f"[{label!r}]" if isinstance(label, str) else f"[{index}]"


def _loc_path(loc: tuple, data) -> str:
    """Dotted field path of a pydantic error location, runs named by their label in ``data``."""
    path, node = "", data
    for key in loc:
        if isinstance(key, int):
            node = node[key] if isinstance(node, list) and 0 <= key < len(node) else None
            path += _item(key, node.get("label") if isinstance(node, dict) else None)
        else:
            path = f"{path}.{key}" if path else str(key)
            node = node.get(key) if isinstance(node, dict) else None
    return path


def _models_in(annotation) -> list[type[BaseModel]]:
    """The schema models inside a field annotation (``X | None``, ``list[X]``, ...)."""
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return [annotation]
    return [m for arg in get_args(annotation) for m in _models_in(arg)]


def _allowed_keys(loc: tuple, root: type[BaseModel]) -> str:
    """The keys allowed beside the unknown key at ``loc`` of a ``root`` document."""
    model = root
    for key in loc[:-1]:
        # list indices and the keys of a mapping of models (channel names) stay at the model
        if isinstance(key, str) and key in model.model_fields:
            inner = _models_in(model.model_fields[key].annotation)
            if inner:
                model = inner[0]
    return ", ".join(model.model_fields)


def _problem(error: dict, data, root: type[BaseModel]) -> str:
    """One message line for a pydantic error dict of a ``root`` document."""
    cause = error.get("ctx", {}).get("error")
    if error["type"] == "extra_forbidden":
        message = f"unknown key (allowed: {_allowed_keys(error['loc'], root)})"
    else:
        message = str(cause) if isinstance(cause, Exception) else error["msg"]
    return _locate(_loc_path(error["loc"], data), message)


__all__ = ["ScenarioError"]
