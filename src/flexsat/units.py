"""Unit handling at the boundary: everything inside flexsat is SI.

Published values are entered as published (oz-in-s, lbf, deg) and converted here with pint, so
the conversion factor is never typed by hand. Every public input that carries a physical number
goes through :func:`to_si_array` (arrays) or :func:`to_si` (scalars): a float is taken in the
field's unit, a pint Quantity or a unit string is converted, and anything else is a
:class:`UnitError` naming the field.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from tokenize import NUMBER, TokenInfo
from typing import Any, TypeAlias

import numpy as np
import numpy.typing as npt
import pint
from pint.pint_eval import build_eval_tree, tokenizer
from pint.util import string_preprocessor

ureg: pint.UnitRegistry[Any] = pint.UnitRegistry()
Q_ = ureg.Quantity

#: a pint quantity of any magnitude (a float or an array)
Quantity: TypeAlias = pint.Quantity[Any]
#: a scalar physical input at the boundary: a number in the field's unit, a unit string such as
#: ``"400 ozf*in"`` or a pint Quantity (converted by :func:`to_si`)
QuantityLike: TypeAlias = float | str | Quantity
#: an array physical input at the boundary: anything :func:`to_si_array` reads -- a number, an
#: array or nested list in the field's unit, a unit string, a Quantity (scalar or array), or a
#: list mixing them
QuantityArrayLike: TypeAlias = npt.ArrayLike | Quantity
#: a float array in SI units, what every check and conversion here returns
FloatArray: TypeAlias = npt.NDArray[np.float64]

#: longest unit expression read; published values are short, and the bound keeps the parse (and
#: every message quoting the text) small
MAX_EXPRESSION_LENGTH = 200
#: largest |exponent| of a unit after a power; real units stay below 10, and the bound keeps the
#: exact (integer) conversion factors pint computes for such powers small
MAX_UNIT_EXPONENT = 100


class UnitError(ValueError):
    """A quantity has the wrong dimensionality or cannot be parsed."""


def _angular(q: Quantity) -> bool:
    """Whether ``q`` is an angle or an angular rate: its root units hold the radian (rad/s, deg/s,
    rpm = revolution/min, ...)."""
    return dict(q.to_root_units().unit_items()).get("radian", 0) != 0


def _cyclic_to_angular(q: Quantity, unit: str) -> Quantity:
    """pint treats the radian as dimensionless, so it would turn 1 Hz into 1 rad/s, and 60 rpm
    (2π rad/s) into 2π Hz. A cyclic frequency asked for in angular units, or an angular rate
    asked for in cyclic ones, is converted with its 2π here."""
    wanted = Q_(1, unit)
    want_cyclic = "hertz" in str(wanted.units)
    given_cyclic = "hertz" in str(q.units)
    if given_cyclic and _angular(wanted):
        return Q_(2 * math.pi * q.to("Hz").magnitude, "rad/s")
    if want_cyclic and _angular(q):
        return Q_(q.to("rad/s").magnitude / (2 * math.pi), "Hz")
    return q


def _number_or_unit(token: TokenInfo) -> float | Quantity:
    """A leaf of a unit expression: numbers become floats (pint keeps integers as Python ints,
    whose powers are unbounded: ``10**10**10`` would build a ten-billion-digit number), names
    become unit quantities."""
    text = token.string
    if token.type == NUMBER:
        return float(text)
    if text.lower() in ("inf", "infinity", "nan"):
        return float(text)
    return Q_(1.0, text)


def _bounded_power(base: Any, exponent: Any) -> Any:
    """``base ** exponent`` with a finite float exponent and unit exponents kept in bounds."""
    if isinstance(exponent, pint.Quantity):
        exponent = exponent.to("").magnitude
    exponent = float(exponent)
    if not math.isfinite(exponent):
        raise ValueError(f"the exponent {exponent} is not finite")
    if isinstance(base, pint.Quantity):
        worst = max((abs(complex(p)) for _, p in base.unit_items()), default=0.0) * abs(exponent)
        if worst > MAX_UNIT_EXPONENT:
            raise ValueError(f"a unit raised to the power {worst:g}; at most {MAX_UNIT_EXPONENT}")
    return base**exponent


_OPERATORS: dict[str, Callable[[Any, Any], Any]] = {
    "**": _bounded_power,
    "*": lambda a, b: a * b,
    "": lambda a, b: a * b,  # implicit product, "2 m"
    "/": lambda a, b: a / b,
    "+": lambda a, b: a + b,
    "-": lambda a, b: a - b,
}


def parse_quantity(text: str, field: str = "value") -> Quantity:
    """Read a unit expression such as ``"400 ozf*in"`` with bounded cost.

    pint's own parser evaluates integer literals as Python ints, so ``"10**10**10 s"`` hangs and
    exhausts memory. Here the text is bounded in length, every number is a float (an out-of-range
    power overflows at once) and a power may not raise a unit beyond ``MAX_UNIT_EXPONENT``, so
    every step costs O(1) and the whole parse O(length).

    Raises
    ------
    UnitError
        ``"<field>: ..."`` for text that is empty, too long or not a quantity.
    """
    if len(text) > MAX_EXPRESSION_LENGTH:
        raise UnitError(
            f"{field}: a quantity must be at most {MAX_EXPRESSION_LENGTH} characters, "
            f"got {len(text)}"
        )
    if not text.strip():
        raise UnitError(f"{field}: empty string; give a number or a quantity such as '2 m'")
    try:
        expression = text
        for preprocess in ureg.preprocessors:
            expression = preprocess(expression)
        tree = build_eval_tree(tokenizer(string_preprocessor(expression)))
        value = tree.evaluate(_number_or_unit, _OPERATORS)
        return value if isinstance(value, pint.Quantity) else Q_(value)
    except Exception as exc:  # noqa: BLE001 - pint's parser raises a version-dependent mix
        # (TokenError, DefinitionSyntaxError, UndefinedUnitError, ZeroDivisionError,
        # OverflowError, DimensionalityError, AssertionError, ...) for malformed text
        raise UnitError(
            f"{field}: cannot read {text!r} as a quantity ({type(exc).__name__}: {exc})"
        ) from None


def holds_quantity(value: object, strings: bool = False) -> bool:
    """A pint Quantity, or a list or tuple with one anywhere inside (or a string, if
    ``strings``): a value whose units would be lost by ``np.asarray(value, float)``."""
    kinds = (pint.Quantity, str) if strings else pint.Quantity
    if isinstance(value, kinds):
        return True
    return isinstance(value, (list, tuple)) and any(holds_quantity(v, strings) for v in value)


@functools.lru_cache(maxsize=256)
def _si_factor(unit: str) -> float:
    """Factor from ``unit`` to the SI base units of its dimension (1 for an SI unit)."""
    return float(Q_(1.0, unit).to_base_units().magnitude)


def to_si_array(value: QuantityArrayLike, unit: str, field: str = "value") -> FloatArray:
    """Convert ``value`` to a float array in the SI base units of ``unit``'s dimension.

    Parameters
    ----------
    value : float, array_like, str or pint.Quantity
        A number or an array without units is taken to be in ``unit``; a string such as
        ``"400 ozf*in"`` (or ``"3"``, a number in ``unit``) or a Quantity (scalar or array) is
        converted; a list may mix them. A dimensionless quantity with units (``"15 deg"``,
        ``"100 percent"``) is accepted only where ``unit`` is dimensionless too (rad counts as
        dimensionless, so ``"40 deg"`` reads as an angle). Cyclic and angular frequencies
        (Hz, rad/s) convert with their 2π.
    unit : str
        The field's unit, e.g. ``"N*m"`` (``""``: dimensionless).
    field : str
        Name used in error messages.

    Returns
    -------
    ndarray
        Float array of the shape of ``value``; not checked for finiteness (callers apply their
        rule, e.g. :func:`flexsat.input_checks.require_finite`).

    Raises
    ------
    UnitError
        If the value cannot be read or has an incompatible dimension.
    """
    if isinstance(value, (list, tuple)) and holds_quantity(value, strings=True):
        items = [to_si_array(v, unit, field) for v in value]
        if any(item.shape != items[0].shape for item in items):
            raise UnitError(f"{field}: the items of {_shown(value)} differ in shape")
        return np.array(items)
    q = parse_quantity(value, field) if isinstance(value, str) else value
    if not isinstance(q, pint.Quantity) or q.units == ureg.dimensionless:
        arr = _real(q.magnitude if isinstance(q, pint.Quantity) else q, value, unit, field)
        factor = _si_factor(unit)
        return arr if factor == 1.0 else arr * factor
    try:
        q = _cyclic_to_angular(q, unit)
        magnitude = q.to(unit).magnitude
    except pint.DimensionalityError as exc:
        raise UnitError(
            f"{field}: incompatible units ({exc.units1} given, {unit or 'dimensionless'} expected)"
        ) from None
    except (pint.PintError, ValueError, TypeError, AttributeError, ArithmeticError) as exc:
        raise UnitError(
            f"{field}: cannot read {_shown(value)} as a quantity in "
            f"{unit or 'dimensionless'} ({exc})"
        ) from None
    return _real(magnitude, value, unit, field) * _si_factor(unit)


def _real(magnitude: Any, value: object, unit: str, field: str) -> FloatArray:
    """``magnitude`` as a float array; None, complex numbers and non-numbers are refused (numpy
    would read None as NaN and drop an imaginary part with only a warning)."""
    try:
        if magnitude is not None and not np.iscomplexobj(magnitude):
            return np.asarray(magnitude, dtype=float)
    except (TypeError, ValueError):
        pass
    raise UnitError(
        f"{field}: cannot read {_shown(value)} as a real number or a quantity in "
        f"{unit or 'dimensionless'} units"
    )


def _shown(value: object) -> str:
    """A short repr for messages (a megabyte of input is not echoed back)."""
    text = repr(value)
    return text if len(text) <= 80 else text[:77] + "..."


def to_si(value: QuantityArrayLike, unit: str, field: str = "value") -> float:
    """Convert a scalar ``value`` to the SI magnitude of ``unit``'s dimension.

    Parameters
    ----------
    value : float, str or pint.Quantity
        A bare number (or a string holding only one, ``"3"``) is taken to be in ``unit``; a
        string such as ``"400 ozf*in"`` or a Quantity is converted (see :func:`to_si_array`).
    unit : str
        The expected unit, e.g. ``"N*m"``; the result is in the SI base units of its dimension.
    field : str
        Name used in error messages.

    Raises
    ------
    UnitError
        If the value cannot be parsed, is not a single finite number or has incompatible
        dimensions.
    """
    arr = to_si_array(value, unit, field)
    if arr.size != 1:
        raise UnitError(f"{field}: must be a single number, got {_shown(value)}")
    si = float(arr.reshape(()))
    if not math.isfinite(si):
        raise UnitError(f"{field}: must be a finite number, got {_shown(value)}")
    return si
