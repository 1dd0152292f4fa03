"""Schema building blocks shared by every scenario kind: quantities with units, bounded
counts and the base models (unknown keys are errors; a document remembers its text and folder;
a buildable section checks its runtime object's own rules)."""

from __future__ import annotations

import types
from collections.abc import Callable, Iterable, Mapping, Sequence
from pathlib import Path
from typing import Annotated, Any, Self, Union, get_args, get_origin

import yaml
from pydantic import (
    BaseModel,
    BeforeValidator,
    ConfigDict,
    PrivateAttr,
    ValidationInfo,
    field_validator,
    model_validator,
)

from flexsat.input_checks import FieldError
from flexsat.limits import is_integral
from flexsat.units import to_si


# -- quantities --------------------------------------------------------------------------------
# A field is declared ``Annotated[float, in_unit("m")]`` in the modules checked by mypy (a call
# is no type to it); ``quantity("m")`` builds the same type for a plug-in's schema.
def quantity_converter(
    unit: str, positive: bool = False
) -> Callable[[Any, ValidationInfo], float | None]:
    """Before-validator converting a quantity to SI (None passes through for optional fields)."""

    def convert(value: Any, info: ValidationInfo) -> float | None:
        if value is None:
            return None
        field = info.field_name or ""  # always set for a field validator
        if isinstance(value, bool):  # a plug-in's model need not be a SchemaSection
            raise _boolean_refusal(field, value, "")
        si = to_si(value, unit, field)
        if positive and not si > 0:
            raise FieldError(field, f"must be > 0, got {value!r}")
        return si

    return convert


def in_unit(unit: str, positive: bool = False) -> BeforeValidator:
    """The validator of a quantity field, ``Annotated[float, in_unit(unit)]`` (or
    ``Annotated[float | None, in_unit(unit)]`` for an optional one): the value converted from
    ``unit`` to its SI float (parameters of :func:`quantity`)."""
    return BeforeValidator(quantity_converter(unit, positive))


def quantity(unit: str, optional: bool = False, positive: bool = False) -> Any:
    """Field type of a quantity in ``unit``, stored as its SI float.

    Parameters
    ----------
    unit : str
        Expected unit; a bare number is taken in it, ``""`` is dimensionless.
    optional : bool
        Accept ``None`` (the key left out).
    positive : bool
        Refuse zero and negative values.

    Returns
    -------
    typing.Annotated
        ``Annotated[float, in_unit(unit, positive)]`` (``float | None`` when ``optional``):
        a type for pydantic, built at run time, so a module checked by mypy spells it out.
    """
    return Annotated[float | None if optional else float, in_unit(unit, positive)]


def integer_in(
    minimum: int = 1, maximum: int | None = None, optional: bool = False
) -> BeforeValidator:
    """The validator of a count field, ``Annotated[int, integer_in(minimum, maximum)]`` (or
    ``Annotated[int | None, integer_in(minimum, maximum, optional=True)]``): parameters of
    :func:`count`."""
    rule = (
        f"an integer in [{minimum}, {maximum}]"
        if maximum is not None
        else f"an integer >= {minimum}"
    )

    def check(value: Any, info: ValidationInfo) -> int | None:
        if value is None and optional:
            return None
        if not is_integral(value) or value < minimum or (maximum is not None and value > maximum):
            raise FieldError(info.field_name or "", f"must be {rule}, got {value!r}")
        return int(value)

    return BeforeValidator(check)


def count(minimum: int = 1, maximum: int | None = None, optional: bool = False) -> Any:
    """Field type of an integer in [minimum, maximum]; a float with an integral value (``1e3``)
    is accepted, bools and fractions are not.

    Parameters
    ----------
    minimum, maximum : int
        Inclusive bounds (``maximum`` None: no upper bound).
    optional : bool
        Accept ``None`` (the key left out).

    Returns
    -------
    typing.Annotated
        ``Annotated[int, integer_in(minimum, maximum)]`` (``int | None`` when ``optional``),
        built at run time like :func:`quantity`.
    """
    return Annotated[int | None if optional else int, integer_in(minimum, maximum, optional)]


def given_fields(section: BaseModel, exclude: Iterable[str] = ()) -> dict[str, Any]:
    """The fields of ``section`` that were set (not None), as keyword arguments."""
    return section.model_dump(exclude_none=True, exclude=set(exclude))


# -- booleans where numbers are expected --------------------------------------------------------
def _members(annotation: Any) -> list[Any]:
    """The types a field annotation admits: ``Annotated`` metadata dropped, a union split, None
    left out."""
    while get_origin(annotation) is Annotated:
        annotation = get_args(annotation)[0]
    if get_origin(annotation) in (Union, types.UnionType):
        return [m for arg in get_args(annotation) if arg is not type(None) for m in _members(arg)]
    return [annotation]


def _boolean_for_a_number(annotation: Any, value: Any) -> tuple[str, bool] | None:
    """Where ``value`` holds a boolean that ``annotation`` would take as a number (pydantic's lax
    mode reads ``true`` as 1): ``""`` for the value itself, ``"[2]"`` or ``"['k']"`` inside a
    list or mapping of numbers, and whether an integer is expected there; None when it holds
    none there."""
    members = _members(annotation)
    if isinstance(value, bool):
        numeric = any(m in (int, float) for m in members)
        if numeric and bool not in members and Any not in members:
            return "", float not in members
        return None
    containers = [(get_origin(m), get_args(m)) for m in members]
    if isinstance(value, (list, tuple)):
        for origin, args in containers:
            if origin in (list, tuple, Sequence) and args:
                fixed = origin is tuple and Ellipsis not in args and len(args) == len(value)
                for i, item in enumerate(value):
                    found = _boolean_for_a_number(args[i] if fixed else args[0], item)
                    if found is not None:
                        return f"[{i}]{found[0]}", found[1]
    if isinstance(value, dict):
        for origin, args in containers:
            if origin in (dict, Mapping) and len(args) == 2:
                for key, item in value.items():
                    found = _boolean_for_a_number(args[1], item)
                    if found is not None:
                        return f"[{key!r}]{found[0]}", found[1]
    return None


def _boolean_refusal(field: str, value: Any, where: str, integer: bool = False) -> FieldError:
    """The refusal of a boolean given where field ``field`` takes a number (an ``integer``;
    ``where``: the item of a list or mapping that holds it, ``""`` for the value itself)."""
    number = "an integer" if integer else "a number (with a unit where it has one)"
    return FieldError(
        field,
        f"must be {number}, not a boolean"
        + (f" (the item {where})" if where else f", got {value!r}"),
    )


# -- schema ------------------------------------------------------------------------------------
class SchemaSection(BaseModel):
    """Base of every schema model: unknown keys are errors, and so is a boolean where a number
    is expected (the one place where they are refused for every kind)."""

    model_config = ConfigDict(extra="forbid")

    @field_validator("*", mode="before")
    @classmethod
    def _no_boolean_for_a_number(cls, value: Any, info: ValidationInfo) -> Any:
        """Refuse ``true``/``false`` where the field takes a number or a quantity: pydantic's lax
        mode would read it as 1 or 0 (a YAML ``true`` given as a gimbal angle ran as 1 rad)."""
        field = info.field_name or ""  # always set for a field validator
        found = _boolean_for_a_number(cls.model_fields[field].annotation, value)
        if found is not None:
            raise _boolean_refusal(field, value, *found)
        return value


class Document(SchemaSection):
    """Base of a scenario kind's document (:attr:`flexsat.scenarios.kind.ScenarioKind.document`):
    unknown keys are errors; it remembers the text and the folder it was loaded from."""

    _source: str | None = PrivateAttr(default=None)
    _folder: Path | None = PrivateAttr(default=None)

    @property
    def folder(self) -> Path:
        """The folder of the scenario file (relative paths in it start there), else the
        working directory."""
        return self._folder if self._folder is not None else Path.cwd()

    @property
    def yaml_text(self) -> str:
        """The scenario as YAML: the text it was loaded from, else a dump (SI numbers)."""
        if self._source is not None:
            return self._source
        return yaml.safe_dump(self.model_dump(exclude_none=True), sort_keys=False)


class BuildableSection(SchemaSection):
    """A section that maps onto a runtime object; building it checks the runtime's own rules."""

    def build(self) -> Any:
        """The runtime object of this section (its constructor checks its own rules)."""
        raise NotImplementedError

    @model_validator(mode="after")
    def _buildable(self) -> Self:
        self.build()
        return self


def check_unique_labels(runs: Iterable[Any]) -> None:
    """Refuse two runs with one label: reports, datasets and error paths name runs by label."""
    labels = [run.label for run in runs]
    for label in labels:
        if labels.count(label) > 1:
            raise FieldError("runs", f"duplicate label {label!r}; each run needs its own label")


__all__ = ["Document", "check_unique_labels", "count", "in_unit", "integer_in", "quantity"]
