"""Field paths into a scenario document: parsing, reading, writing, and the paths there are.

A batch over any kind (:mod:`flexsat.scenarios.batch_cases`) names what it varies by the field
path of the value in the target scenario, written as problems name fields
(:class:`~flexsat.scenarios.errors.Problem`)::

    plant.tip_mass                      a mapping's key
    station.inertia[2]                  a list's item by its index
    runs['PD'].gains.K                  a list's item by its label
    model.fe.materials.al.E             a key, or the item labelled (or named) 'al' of a list
    model.fe.materials['Al 6061'].E     any text in quotes: a key or a label

A step is a name (``[A-Za-z_][A-Za-z0-9_]*``) after a dot, or a bracket holding an integer or a
quoted string. On a mapping a name or a quoted string is the key; on a list an integer is the
index and a name or a quoted string the item whose ``label`` (else ``name``, else ``id``) it
is. The last key of a path may be absent from its mapping (a field the scenario leaves at its
default); the kind's schema then decides whether the field exists. Everything else must exist:
a path that does not is refused naming the first step that fails, with the nearest paths of
the document (:func:`difflib.get_close_matches`).
"""

from __future__ import annotations

import copy
import difflib
import re
from collections.abc import Iterator, Mapping
from typing import Any

from flexsat.input_checks import FieldError

#: the keys that name an item of a list of mappings, in the order they are tried
ITEM_KEYS = ("label", "name", "id")

Step = str | int

_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_BRACKET = re.compile(r"\[\s*(?:(-?\d+)|'((?:[^'\\]|\\.)*)'|\"((?:[^\"\\]|\\.)*)\")\s*\]")


def parse_path(text: object, field: str = "parameters") -> tuple[Step, ...]:
    """The steps of the path ``text`` (module docstring).

    Raises
    ------
    FieldError
        ``field``: the character where the path stops making sense.
    """
    if not isinstance(text, str) or not text.strip():
        raise FieldError(field, f"a field path such as plant.tip_mass, got {text!r}")
    steps: list[Step] = []
    at = 0
    while at < len(text):
        if text[at] == "[":
            match = _BRACKET.match(text, at)
            if match is None:
                raise FieldError(
                    field,
                    f"{text}: at character {at + 1}, a bracket holds an index ([0]) or a "
                    "quoted key or label (['PD'])",
                )
            index, single, double = match.groups()
            if index is not None:
                steps.append(int(index))
            else:
                quoted = single if single is not None else double
                steps.append(re.sub(r"\\(.)", r"\1", quoted))
            at = match.end()
            continue
        if steps:
            if text[at] != ".":
                raise FieldError(
                    field, f"{text}: at character {at + 1}, expected '.' or '[' between steps"
                )
            at += 1
        match = _NAME.match(text, at)
        if match is None:
            raise FieldError(
                field,
                f"{text}: at character {at + 1}, expected a name (letters, digits, _) or a bracket",
            )
        steps.append(match.group())
        at = match.end()
    return tuple(steps)


def _item_key(item: object) -> str | None:
    """The key (of :data:`ITEM_KEYS`) that names a list item, if it is a mapping with one."""
    if isinstance(item, Mapping):
        for key in ITEM_KEYS:
            if isinstance(item.get(key), str):
                return key
    return None


def _item_name(item: object) -> str | None:
    """The label (or name, or id) of a list item, if it is a mapping that has one."""
    key = _item_key(item)
    return None if key is None else item[key]  # type: ignore[index]  # a mapping: _item_key


def _key_step(prefix: str, key: object) -> str:
    """``prefix`` followed by the mapping key ``key``: after a dot if it is a name, else in
    brackets."""
    if isinstance(key, str) and _NAME.fullmatch(key):
        return f"{prefix}.{key}" if prefix else key
    return f"{prefix}[{key!r}]"


def leaf_paths(data: object, prefix: str = "") -> Iterator[str]:
    """The path of every value of ``data`` that is not a mapping or a list, as text (list items
    named by their label where they have one, as problems name them: ``runs['PD'].gains.K``;
    the label itself is the item's name, not a value to vary, and is left out)."""
    if isinstance(data, Mapping):
        for key, value in data.items():
            yield from leaf_paths(value, _key_step(prefix, key))
    elif isinstance(data, list):
        for index, item in enumerate(data):
            key = _item_key(item)
            if key is None:
                yield from leaf_paths(item, f"{prefix}[{index}]")
                continue
            named = f"{prefix}[{item[key]!r}]"
            for inner, value in item.items():
                if inner != key:
                    yield from leaf_paths(value, _key_step(named, inner))
    elif prefix:
        yield prefix


def nearest_paths(text: str, data: object, n: int = 3) -> list[str]:
    """The ``n`` paths of ``data`` closest to ``text`` (difflib's ratio, at least 0.5)."""
    return difflib.get_close_matches(text, list(leaf_paths(data)), n=n, cutoff=0.5)


def _child(node: object, step: Step) -> tuple[bool, Any]:
    """(found, the child) of ``node`` at ``step``."""
    if isinstance(node, Mapping):
        return (step in node, node.get(step))
    if isinstance(node, list):
        if isinstance(step, int):
            inside = -len(node) <= step < len(node)
            return inside, node[step] if inside else None
        for item in node:
            if _item_name(item) == step:
                return True, item
    return False, None


def _unknown(
    text: str, steps: tuple[Step, ...], failed: int, data: object, field: str
) -> FieldError:
    near = nearest_paths(text, data)
    hint = f"; nearest: {', '.join(near)}" if near else ""
    return FieldError(
        field,
        f"{text} is not a field of the scenario (step {failed + 1}, {steps[failed]!r}, "
        f"is not found){hint}",
    )


def read_value(data: object, text: str, field: str = "parameters") -> Any:
    """The value at the path ``text`` (None for a last key absent from its mapping).

    Raises
    ------
    FieldError
        ``field``: the path does not lead into the document (the nearest paths named).
    """
    steps = parse_path(text, field)
    node = data
    for depth, step in enumerate(steps):
        found, child = _child(node, step)
        last = depth == len(steps) - 1
        if not found and not (last and isinstance(node, Mapping) and isinstance(step, str)):
            raise _unknown(text, steps, depth, data, field)
        node = child
    if isinstance(node, (Mapping, list)):
        raise FieldError(
            field,
            f"{text} holds a {'mapping' if isinstance(node, Mapping) else 'list'}"
            "; a parameter sets one number (name one of its entries)",
        )
    return node


def with_values(data: Mapping[str, Any], values: Mapping[str, Any]) -> dict[str, Any]:
    """A deep copy of ``data`` with each path of ``values`` set to its value (each path read by
    :func:`read_value` first: it leads into the document)."""
    out = copy.deepcopy(dict(data))
    for text, value in values.items():
        steps = parse_path(text)
        node: Any = out
        for step in steps[:-1]:
            node = _child(node, step)[1]
        node[steps[-1]] = value  # a list's index or a mapping's key (read_value's rule)
    return out


__all__ = [
    "ITEM_KEYS",
    "Step",
    "leaf_paths",
    "nearest_paths",
    "parse_path",
    "read_value",
    "with_values",
]
