"""Plug-ins: kinds, plants, laws, cases and checks that other packages add through entry points.

A package extends flexsat by declaring entry points in its ``pyproject.toml``, one group per
extension point, each naming one object::

    [project.entry-points."flexsat.laws"]
    bang_off = "my_package.laws:BangOff"

The groups are :data:`GROUPS`. :func:`entry_point_objects` loads a group once per process; a
plug-in that cannot be loaded (a missing module, an import error, a missing attribute, an object
the group's ``accept`` rule refuses) is kept out and reported by name through
:func:`broken_plugins`, never raised: a broken plug-in must not break the command line or the
other plug-ins.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from importlib.metadata import entry_points
from typing import Any

#: the extension points: scenario kinds, plants, control laws, published cases, published checks
GROUPS = ("flexsat.kinds", "flexsat.plants", "flexsat.laws", "flexsat.cases", "flexsat.checks")


@dataclass(frozen=True)
class BrokenPlugin:
    """A plug-in that could not be loaded.

    Attributes
    ----------
    group : str
        Its entry-point group (one of :data:`GROUPS`).
    name : str
        Its entry-point name.
    target : str
        What it points at (``module:attribute``).
    reason : str
        Why it was left out (the exception's type and message, or the rule it breaks).
    """

    group: str
    name: str
    target: str
    reason: str

    def __str__(self) -> str:
        return (
            f"plug-in {self.name!r} ({self.group} = {self.target!r}) was not loaded: {self.reason}"
        )


_BROKEN: dict[tuple[str, str], BrokenPlugin] = {}


@functools.cache
def _load_group(group: str) -> dict[str, Any]:
    loaded: dict[str, Any] = {}
    for point in sorted(entry_points(group=group), key=lambda p: p.name):
        try:
            loaded[point.name] = point.load()
        except Exception as exc:  # noqa: BLE001 -- any failure of foreign code is reported
            _BROKEN[(group, point.name)] = BrokenPlugin(
                group, point.name, point.value, f"{type(exc).__name__}: {exc}"
            )
    return loaded


def entry_point_objects(
    group: str,
    accept: Callable[[str, Any], str | None] | None = None,
    reserved: Mapping[str, str] | None = None,
) -> dict[str, Any]:
    """The objects the installed packages declare in entry-point ``group``, by entry-point name.

    Parameters
    ----------
    group : str
        One of :data:`GROUPS`.
    accept : callable, optional
        ``accept(name, obj)`` returns None for an acceptable object, or the rule it breaks (for
        example "not a Plant subclass"); a refused object is reported like a failed import.
    reserved : mapping of str to str, optional
        The built-in names of the extension point, each with what it is (``"the built-in case
        'tamu' (flexsat.cases.tamu:tamu)"``): a plug-in of one of these names is refused and
        reported naming both, so that a package never silently replaces a built-in.

    Raises
    ------
    ValueError
        For a group that is not one of :data:`GROUPS`.
    """
    if group not in GROUPS:
        from flexsat.input_checks import FieldError  # numpy: loaded for the refusal only

        raise FieldError("group", f"must be one of {', '.join(GROUPS)}, got {group!r}")
    reserved = reserved or {}
    objects: dict[str, Any] = {}
    for name, obj in _load_group(group).items():
        rule: str | None
        if name in reserved:
            rule = f"its name is taken by {reserved[name]}; rename the entry point"
        else:
            try:
                rule = accept(name, obj) if accept is not None else None
            except Exception as exc:  # noqa: BLE001 -- an object that breaks the rule's checks
                rule = f"{type(exc).__name__}: {exc}"
        if rule is None:
            objects[name] = obj
        else:
            target = next((p.value for p in entry_points(group=group) if p.name == name), "?")
            _BROKEN[(group, name)] = BrokenPlugin(group, name, target, rule)
    return objects


def broken_plugins() -> list[BrokenPlugin]:
    """Every plug-in left out so far in this process (load every group first to see all)."""
    return [_BROKEN[key] for key in sorted(_BROKEN)]


__all__ = ["GROUPS", "BrokenPlugin", "broken_plugins", "entry_point_objects"]
