"""Overridable inputs of the case builders: one declarative spec, one reader.

Each builder lists its inputs as :class:`Param` (default as published, SI unit, rule) and calls
:func:`read_inputs` with its keyword overrides; checks that involve several inputs stay in the
builder. Every message starts with the field name, then the rule it breaks.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from flexsat import limits
from flexsat.input_checks import FieldError, require_count, require_nonneg, require_positive
from flexsat.units import to_si

_QUANTITY_RULES = {"positive": require_positive, "nonneg": require_nonneg}
_OTHER_RULES = ("count", "flag", "choice", "raw")


@dataclass(frozen=True)
class Param:
    """One overridable input of a case.

    Parameters
    ----------
    default : Any
        Value used when the input is not overridden, as written (a published string with units,
        a number in SI, a tuple, ...); it goes through the same rule as an override.
    unit : str
        SI unit of a quantity (``""``: dimensionless). A number is taken in this unit, a pint
        Quantity or a string such as ``"2 in"`` or ``"0.4 percent"`` is converted with
        :func:`flexsat.units.to_si` (a dimensionless unit is refused where a dimension is due).
    rule : str or callable
        ``"positive"`` (> 0) or ``"nonneg"`` (>= 0) for a quantity, returned as float;
        ``"count"`` a positive integer; ``"flag"`` a bool or the string "true"/"false";
        ``"choice"`` one of ``choices`` (strings compared stripped and lower-case); ``"raw"``
        the value unchanged (checked by the builder); or a parser ``rule(raw, name) -> value``
        that raises ValueError with a message starting with ``name``.
    choices : tuple of str
        The accepted strings of a ``"choice"``.
    optional : bool
        None is accepted (and kept) for an input solved or derived later by the case.
    limit : str
        For a ``"count"``: the :mod:`flexsat.limits` constant bounding it (``"MAX_ELEMENTS"``),
        read when the input is read.

    Raises
    ------
    ValueError
        For an unknown rule name, or a ``"choice"`` without choices.
    """

    default: Any
    unit: str = ""
    rule: str | Callable[[Any, str], Any] = "positive"
    choices: tuple[str, ...] = ()
    optional: bool = False
    limit: str = ""

    def __post_init__(self) -> None:
        if isinstance(self.rule, str) and self.rule not in (*_QUANTITY_RULES, *_OTHER_RULES):
            raise FieldError(
                "rule",
                f"must be one of {[*_QUANTITY_RULES, *_OTHER_RULES]} or a "
                f"callable, got {self.rule!r}",
            )
        if self.limit and not (self.rule == "count" and hasattr(limits, self.limit)):
            raise FieldError(
                "limit", f"must name a flexsat.limits constant of a 'count', got {self.limit!r}"
            )
        if self.rule == "choice" and not self.choices:
            raise FieldError("choices", "a 'choice' input needs at least one choice")

    def read(self, raw: Any, name: str) -> Any:
        """``raw`` (an override or the default) checked and converted by the rule."""
        if raw is None and self.optional:
            return None
        if callable(self.rule):
            return self.rule(raw, name)
        if self.rule == "raw":
            return raw
        if self.rule == "count":
            count = require_count(raw, name)
            if self.limit:
                limits.check_count(
                    count,
                    getattr(limits, self.limit),
                    name,
                    name,
                    f"a larger {name} takes more time and memory than one run is "
                    f"allowed (flexsat.limits.{self.limit})",
                )
            return count
        if self.rule == "flag":
            return _flag(raw, name)
        if self.rule == "choice":
            return _choice(raw, name, self.choices)
        return float(_QUANTITY_RULES[self.rule](to_si(raw, self.unit, name), name))


def _flag(raw: object, name: str) -> bool:
    if isinstance(raw, (bool, np.bool_)):
        return bool(raw)
    if isinstance(raw, str) and raw.strip().lower() in ("true", "false"):
        return raw.strip().lower() == "true"
    raise FieldError(name, f"must be true or false, got {raw!r}")


def _choice(raw: object, name: str, choices: tuple[str, ...]) -> str:
    if isinstance(raw, str) and raw.strip().lower() in choices:
        return raw.strip().lower()
    raise FieldError(name, f"must be one of {list(choices)}, got {raw!r}")


def read_inputs(
    builder: str, params: dict[str, Param], overrides: dict[str, Any]
) -> dict[str, Any]:
    """Read every input of a case: the override if given, else the default, by its rule.

    Parameters
    ----------
    builder : str
        Name of the case builder, for the unknown-name message.
    params : dict of str to Param
        The case's inputs, in the order they are read (and reported when broken).
    overrides : dict
        Keyword overrides given to the builder.

    Returns
    -------
    dict
        Every input by name, in the order of ``params``: quantities as SI floats, counts as
        int, flags as bool, choices as the lower-case string, None where optional and not given.

    Raises
    ------
    ValueError
        ``"<builder>: unknown parameter(s) [...]; known: [...]"`` for a name not in ``params``;
        else the first input breaking its rule, message starting with the input's name.

    Examples
    --------
    >>> read_inputs("demo", {"length": Param("2 in", "m"), "n": Param(3, rule="count")},
    ...             {"length": "30 cm"})
    {'length': 0.3, 'n': 3}
    """
    unknown = set(overrides) - set(params)
    if unknown:
        raise ValueError(
            f"{builder}: unknown parameter(s) {sorted(unknown)}; known: {sorted(params)}"
        )
    return {
        name: param.read(overrides.get(name, param.default), name) for name, param in params.items()
    }


__all__ = ["Param", "read_inputs"]
