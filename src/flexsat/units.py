"""Unit handling at the boundary: everything inside flexsat is SI.

Published values are entered as published (oz-in-s, lbf, deg) and converted here with pint, so
the conversion factor is never typed by hand. Every public input that carries a physical number
goes through :func:`to_si_array` (arrays) or :func:`to_si` (scalars), the one boundary helper:
a plain number or array is already SI and passes through unchanged (only checked to be real), a
pint Quantity or a unit string is converted to the field's SI unit, and anything else is a
:class:`UnitError` naming the field.

pint is imported on first need only, when a Quantity or a unit string is actually given (or
:data:`ureg` / :data:`Q_` is asked for): a run fed SI numbers never loads it, and the layers
below ``cases`` and ``scenarios`` import no pint of their own (tests/test_units_lazy.py).
"""

from __future__ import annotations

import functools
import math
import sys
from collections.abc import Callable
from tokenize import NUMBER, TokenInfo
from typing import TYPE_CHECKING, Any, TypeAlias

import numpy as np
import numpy.typing as npt

if TYPE_CHECKING:
    import pint

# the aliases are strings so that pint is imported only by the type checker
#: a pint quantity of any magnitude (a float or an array)
Quantity: TypeAlias = "pint.Quantity[Any]"
#: a scalar physical input at the boundary: a number in the field's unit, a unit string such as
#: ``"400 ozf*in"`` or a pint Quantity (converted by :func:`to_si`)
QuantityLike: TypeAlias = "float | str | pint.Quantity[Any]"
#: an array physical input at the boundary: anything :func:`to_si_array` reads -- a number, an
#: array or nested list in the field's unit, a unit string, a Quantity (scalar or array), or a
#: list mixing them
QuantityArrayLike: TypeAlias = "npt.ArrayLike | pint.Quantity[Any]"
#: a float array in SI units, what every check and conversion here returns
FloatArray: TypeAlias = npt.NDArray[np.float64]

#: longest unit expression read; published values are short, and the bound keeps the parse (and
#: every message quoting the text) small
MAX_EXPRESSION_LENGTH = 200
#: largest |exponent| of a unit after a power; real units stay below 10, and the bound keeps the
#: exact (integer) conversion factors pint computes for such powers small
MAX_UNIT_EXPONENT = 100


@functools.cache
def _registry() -> tuple[Any, Any]:
    """pint and the one unit registry, loaded on first use (about 0.3 s of import)."""
    import pint

    return pint, pint.UnitRegistry()


def __getattr__(name: str) -> Any:
    """``ureg`` (the unit registry) and ``Q_`` (its Quantity class), loaded on first access."""
    if name == "ureg":
        return _registry()[1]
    if name == "Q_":
        return _registry()[1].Quantity
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def _is_quantity(value: object) -> bool:
    """A pint Quantity; without pint loaded no Quantity can exist, so pint is not imported."""
    pint = sys.modules.get("pint")
    return pint is not None and isinstance(value, pint.Quantity)


class FieldError(ValueError):
    """A value refused by the rule of one named input: ``str(exc)`` is ``"field: rule"``.

    The field travels as data (:attr:`field`), so that a caller that knows where the value came
    from (a scenario, which names it ``runs['Law I'].gains.g1``) can place the problem without
    reading the message.

    Parameters
    ----------
    field : str
        The input as the refusing function names it (its parameter, ``"gains.k"``, ...).
    rule : str
        The rule it breaks and the value given (``"must be > 0, got -1"``).
    """

    def __init__(self, field: str, rule: str) -> None:
        self.field, self.rule = field, rule
        super().__init__(f"{field}: {rule}")

    def __reduce__(self) -> tuple[type[FieldError], tuple[str, str]]:
        # picklable across processes (dask workers) with its field
        return type(self), (self.field, self.rule)


class UnitError(FieldError):
    """A quantity of field ``field`` has the wrong dimensionality or cannot be parsed."""


#: the two units of a frequency that pint cannot tell apart (it calls the radian dimensionless)
FREQUENCY_UNITS = ("Hz", "rad/s")


class FrequencyArray(np.ndarray):
    """Frequencies that carry their unit, cyclic ``"Hz"`` or angular ``"rad/s"``.

    Hz and rad/s differ by 2π and share a dimension, so a plain array cannot say which it holds
    (ERA's frequencies in Hz fed to a model update that expects rad/s scaled its stiffness by
    1/(2π)² with no error). An identification result hands its frequencies out as this array;
    the boundary helper (:func:`to_si_array`) passes it only where its own unit is declared and
    refuses it, naming the field, anywhere else (another frequency unit, any other quantity, or
    a field that declares no unit). Indexing and slicing keep the unit; arithmetic returns a
    plain array, which is a number the caller has converted and vouches for.
    """

    unit: str | None

    def __new__(cls, values: npt.ArrayLike, unit: str) -> FrequencyArray:
        """The frequencies ``values`` in ``unit``.

        Parameters
        ----------
        values : array_like
            The frequencies.
        unit : {"Hz", "rad/s"}
        """
        if unit not in FREQUENCY_UNITS:
            raise FieldError("unit", f"must be one of {list(FREQUENCY_UNITS)}, got {unit!r}")
        arr = np.array(values, dtype=float).view(cls)
        arr.unit = unit
        return arr

    def __array_finalize__(self, obj: object) -> None:
        self.unit = getattr(obj, "unit", None)

    def __array_ufunc__(self, ufunc: Any, method: str, *inputs: Any, **kwargs: Any) -> Any:
        plain = [x.view(np.ndarray) if isinstance(x, FrequencyArray) else x for x in inputs]
        if "out" in kwargs:
            kwargs["out"] = tuple(
                x.view(np.ndarray) if isinstance(x, FrequencyArray) else x for x in kwargs["out"]
            )
        return getattr(ufunc, method)(*plain, **kwargs)

    def __reduce__(self) -> tuple[type[FrequencyArray], tuple[np.ndarray, str | None]]:
        return FrequencyArray, (self.view(np.ndarray), self.unit)

    def __repr__(self) -> str:
        return f"FrequencyArray({self.view(np.ndarray).tolist()!r}, unit={self.unit!r})"

    def to(self, unit: str) -> FrequencyArray:
        """The same frequencies in ``unit`` (ω = 2π f)."""
        if unit not in FREQUENCY_UNITS:
            raise FieldError("unit", f"must be one of {list(FREQUENCY_UNITS)}, got {unit!r}")
        values = self.view(np.ndarray)
        if unit != self.unit:
            values = values * (2 * math.pi) if unit == "rad/s" else values / (2 * math.pi)
        return FrequencyArray(values, unit)

    def si(self, unit: str, field: str) -> np.ndarray:
        """The plain values where the field declares ``unit``; refused (naming the field) unless
        ``unit`` is this array's own unit."""
        if unit != self.unit:
            hint = f"; convert explicitly, e.g. .to({unit!r})" if unit in FREQUENCY_UNITS else ""
            raise UnitError(
                field,
                f"frequencies in {self.unit} given where "
                f"{unit or 'a plain number'} is expected{hint}",
            )
        return np.array(self.view(np.ndarray), dtype=float)


def _angular(q: Quantity) -> bool:
    """Whether ``q`` is an angle or an angular rate: its root units hold the radian (rad/s, deg/s,
    rpm = revolution/min, ...)."""
    return dict(q.to_root_units().unit_items()).get("radian", 0) != 0


def _cyclic_to_angular(q: Quantity, unit: str) -> Quantity:
    """pint treats the radian as dimensionless, so it would turn 1 Hz into 1 rad/s, and 60 rpm
    (2π rad/s) into 2π Hz. A cyclic frequency asked for in angular units, or an angular rate
    asked for in cyclic ones, is converted with its 2π here."""
    Q_ = _registry()[1].Quantity
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
    return _registry()[1].Quantity(1.0, text)


def _bounded_power(base: Any, exponent: Any) -> Any:
    """``base ** exponent`` with a finite float exponent and unit exponents kept in bounds."""
    if _is_quantity(exponent):
        exponent = exponent.to("").magnitude
    exponent = float(exponent)
    if not math.isfinite(exponent):
        raise ValueError(f"the exponent {exponent} is not finite")
    if _is_quantity(base):
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
            field, f"a quantity must be at most {MAX_EXPRESSION_LENGTH} characters, got {len(text)}"
        )
    if not text.strip():
        raise UnitError(field, "empty string; give a number or a quantity such as '2 m'")
    pint, ureg = _registry()
    from pint.pint_eval import build_eval_tree, tokenizer
    from pint.util import string_preprocessor

    try:
        expression = text
        for preprocess in ureg.preprocessors:
            expression = preprocess(expression)
        tree = build_eval_tree(tokenizer(string_preprocessor(expression)))
        value = tree.evaluate(_number_or_unit, _OPERATORS)
        return value if isinstance(value, pint.Quantity) else ureg.Quantity(value)
    except Exception as exc:  # noqa: BLE001 - pint's parser raises a version-dependent mix
        # (TokenError, DefinitionSyntaxError, UndefinedUnitError, ZeroDivisionError,
        # OverflowError, DimensionalityError, AssertionError, ...) for malformed text
        raise UnitError(
            field, f"cannot read {text!r} as a quantity ({type(exc).__name__}: {exc})"
        ) from None


def holds_quantity(value: object, strings: bool = False) -> bool:
    """A pint Quantity or a :class:`FrequencyArray`, or a list or tuple with one anywhere inside
    (or a string, if ``strings``): a value whose units would be lost by
    ``np.asarray(value, float)``."""
    if _is_quantity(value) or isinstance(value, FrequencyArray):
        return True
    if strings and isinstance(value, str):
        return True
    return isinstance(value, (list, tuple)) and any(holds_quantity(v, strings) for v in value)


@functools.lru_cache(maxsize=256)
def si_factor(unit: str) -> float:
    """Factor from ``unit`` to the SI base units of its dimension (1 for an SI unit)."""
    return float(_registry()[1].Quantity(1.0, unit).to_base_units().magnitude)


def to_si_array(value: QuantityArrayLike, unit: str, field: str = "value") -> FloatArray:
    """``value`` as a float array in SI: the one boundary helper (see the module).

    Parameters
    ----------
    value : float, array_like, str or pint.Quantity
        A number or an array without units is SI already and is returned as a float array,
        unconverted (pint is not loaded). A string such as ``"400 ozf*in"`` (or ``"3"``, a
        number in ``unit``) or a Quantity (scalar or array) is converted; a list may mix them.
        A dimensionless quantity with units (``"15 deg"``, ``"100 percent"``) is accepted only
        where ``unit`` is dimensionless too (rad counts as dimensionless, so ``"40 deg"`` reads
        as an angle). Cyclic and angular frequencies (Hz, rad/s) convert with their 2π.
    unit : str
        The field's SI unit, e.g. ``"N*m"`` (``""``: dimensionless); a coherent SI unit, so a
        plain number needs no factor (tests/test_units_lazy.py checks every unit declared in
        the sources).
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
            raise UnitError(field, f"the items of {_shown(value)} differ in shape")
        return np.array(items)
    if isinstance(value, FrequencyArray):
        return value.si(unit, field)
    if not isinstance(value, str) and not _is_quantity(value):
        return _real(value, value, unit, field)  # a plain number: SI, passed through
    pint, ureg = _registry()
    q: Quantity = parse_quantity(value, field) if isinstance(value, str) else value  # type: ignore[assignment]
    if q.units == ureg.dimensionless:
        return _real(q.magnitude, value, unit, field) * si_factor(unit)
    try:
        q = _cyclic_to_angular(q, unit)
        magnitude = q.to(unit).magnitude
    except pint.DimensionalityError as exc:
        raise UnitError(
            field, f"incompatible units ({exc.units1} given, {unit or 'dimensionless'} expected)"
        ) from None
    except (pint.PintError, ValueError, TypeError, AttributeError, ArithmeticError) as exc:
        raise UnitError(
            field, f"cannot read {_shown(value)} as a quantity in {unit or 'dimensionless'} ({exc})"
        ) from None
    return _real(magnitude, value, unit, field) * si_factor(unit)


def _real(magnitude: Any, value: object, unit: str, field: str) -> FloatArray:
    """``magnitude`` as a float array; None, complex numbers and non-numbers are refused (numpy
    would read None as NaN and drop an imaginary part with only a warning)."""
    try:
        if magnitude is not None and not np.iscomplexobj(magnitude):
            return np.asarray(magnitude, dtype=float)
    except (TypeError, ValueError):
        pass
    raise UnitError(
        field,
        f"cannot read {_shown(value)} as a real number or a quantity in "
        f"{unit or 'dimensionless'} units",
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
        raise UnitError(field, f"must be a single number, got {_shown(value)}")
    si = float(arr.reshape(()))
    if not math.isfinite(si):
        raise UnitError(field, f"must be a finite number, got {_shown(value)}")
    return si
