"""Schema building blocks (flexsat.scenarios.fields): a quantity field stores its SI float and
refuses booleans, wrong dimensions and non-finite numbers; a count field takes integers and
integral floats within its bounds and refuses the rest, naming the field and the rule; unknown
keys are errors."""

from __future__ import annotations

import math
from typing import Annotated

import pytest
from pydantic import ValidationError

from flexsat.scenarios import count, quantity
from flexsat.scenarios.fields import SchemaSection, given_fields, in_unit, integer_in


class Probe(SchemaSection):
    length: quantity("m")
    rate: quantity("Hz", optional=True) = None
    ratio: quantity("", optional=True) = None
    modes: count(1, 10, optional=True) = None
    seed: count(0) = 0


def problem(**values) -> str:
    """The one problem of validating a Probe from ``values`` (its validator's own message)."""
    with pytest.raises(ValidationError) as info:
        Probe(**values)
    errors = info.value.errors()
    assert len(errors) == 1, errors
    cause = errors[0].get("ctx", {}).get("error")
    return str(cause) if cause is not None else errors[0]["msg"]


@pytest.mark.parametrize(
    "given, si",
    [
        (2.5, 2.5),  # a bare number is in the field's unit
        ("2.5", 2.5),
        ("1 ft", 0.3048),
        ("3 km", 3000.0),
    ],
)
def test_quantities_are_stored_in_si(given, si):
    assert Probe(length=given).length == pytest.approx(si, rel=1e-15)  # exact unit factors


def test_frequency_and_dimensionless_quantities():
    probe = Probe(length=1, rate="0.1 kHz", ratio="50 percent")
    assert probe.rate == pytest.approx(100.0) and probe.ratio == pytest.approx(0.5)
    assert Probe(length=1).rate is None  # optional: left out
    assert Probe(length=1, rate=None).rate is None


@pytest.mark.parametrize(
    "value, expected",
    [
        (True, "length: must be a number (with a unit where it has one), not a boolean"),
        ("2 kg", "length: incompatible units (kilogram given, m expected)"),
        (math.nan, "length: must be a finite number"),
        ("inf m", "length: must be a finite number"),
    ],
)
def test_quantities_refused(value, expected):
    assert problem(length=value).startswith(expected)


def test_a_required_quantity_is_required():
    assert problem() == "Field required"


@pytest.mark.parametrize("given, stored", [(1, 1), (10, 10), (1e1, 10), (4.0, 4), (None, None)])
def test_counts_take_integers_and_integral_floats(given, stored):
    modes = Probe(length=1, modes=given).modes
    assert modes == stored and type(modes) is type(stored)


@pytest.mark.parametrize("value", [0, 11, 2.5, "3", math.inf, math.nan, 1e300])
def test_counts_out_of_bounds_or_not_integers_are_refused(value):
    assert problem(length=1, modes=value) == (
        f"modes: must be an integer in [1, 10], got {value!r}"
    )


def test_a_boolean_count_is_refused():
    assert problem(length=1, modes=True) == "modes: must be an integer, not a boolean, got True"


def test_an_unbounded_count_has_a_lower_bound_only():
    assert Probe(length=1, seed=10**30).seed == 10**30  # an int of any size, compared exactly
    assert problem(length=1, seed=-1) == "seed: must be an integer >= 0, got -1"
    assert problem(length=1, seed=None) == "seed: must be an integer >= 0, got None"


def test_unknown_keys_are_errors_and_given_drops_what_was_left_out():
    with pytest.raises(ValidationError, match="Extra inputs are not permitted"):
        Probe(length=1, colour="red")
    assert given_fields(Probe(length="2 m", modes=3)) == {"length": 2.0, "modes": 3, "seed": 0}
    assert given_fields(Probe(length=1), exclude={"length", "seed"}) == {}


class SpelledProbe(SchemaSection):
    """Probe, declared as the modules mypy checks declare their fields."""

    length: Annotated[float, in_unit("m")]
    rate: Annotated[float | None, in_unit("Hz")] = None
    ratio: Annotated[float | None, in_unit("")] = None
    modes: Annotated[int | None, integer_in(1, 10, optional=True)] = None
    seed: Annotated[int, integer_in(0)] = 0


@pytest.mark.parametrize(
    "values",
    [
        {"length": "3 km"},
        {"length": 1, "rate": "0.1 kHz", "ratio": "50 percent"},
        {"length": 1, "modes": 1e1, "seed": 10**30},
        {"length": True},
        {"length": "2 kg"},
        {"length": math.nan},
        {"length": 1, "modes": 2.5},
        {"length": 1, "modes": None, "seed": None},
        {"length": 1, "colour": "red"},
        {},
    ],
)
def test_in_unit_and_integer_in_are_the_validators_of_quantity_and_count(values):
    """``Annotated[float, in_unit(u)]`` is ``quantity(u)`` and ``Annotated[int, integer_in(...)]``
    is ``count(...)``: the same stored values, the same problems, the same schema."""

    def outcome(model: type[SchemaSection]) -> object:
        try:
            return model(**values).model_dump()
        except ValidationError as exc:
            return [(e["loc"], e["msg"]) for e in exc.errors()]

    assert outcome(SpelledProbe) == outcome(Probe)
    spelled, original = SpelledProbe.model_json_schema(), Probe.model_json_schema()
    assert spelled["properties"] == original["properties"]
    assert spelled["required"] == original["required"]
