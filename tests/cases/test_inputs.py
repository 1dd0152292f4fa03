"""read_inputs / Param: the shared override reader of the case builders."""

import numpy as np
import pytest

from flexsat.cases.inputs import Param, read_inputs


def read(param: Param, *value):
    """The value of a single input named ``x``: the default, or ``value`` as an override."""
    return read_inputs("demo", {"x": param}, {"x": value[0]} if value else {})["x"]


def test_unknown_names_are_refused_with_the_known_list():
    params = {"length": Param("1 m", "m"), "n": Param(2, rule="count")}
    with pytest.raises(ValueError) as info:
        read_inputs("demo", params, {"lenght": 2.0, "m": 1, "n": 3})
    assert str(info.value) == "demo: unknown parameter(s) ['lenght', 'm']; known: ['length', 'n']"


def test_every_input_is_returned_in_spec_order_with_defaults_through_the_rule():
    params = {"b": Param("2 in", "m"), "a": Param(3, rule="count"), "c": Param(False, rule="flag")}
    values = read_inputs("demo", params, {"a": 5.0})
    assert list(values) == ["b", "a", "c"]
    assert values == {"b": pytest.approx(0.0508), "a": 5, "c": False}
    assert type(values["a"]) is int


def test_quantities_numbers_are_si_and_strings_are_converted():
    assert read(Param("1 m", "m"), 2) == 2.0
    assert read(Param("1 m", "m"), "25 mm") == pytest.approx(0.025)
    assert read(Param("5 ozf*in", "N*m")) == pytest.approx(0.035306, rel=1e-4)
    assert type(read(Param("1 m", "m"), np.float32(2))) is float
    with pytest.raises(ValueError, match=r"^x: incompatible units"):
        read(Param("1 m", "m"), "3 kg")
    with pytest.raises(ValueError, match=r"^x: must be a finite number"):
        read(Param("1 m", "m"), float("nan"))


def test_dimensionless_numbers_are_checked_and_strings_converted():
    assert read(Param(0.5), 0.25) == 0.25
    assert read(Param("0.4 percent")) == pytest.approx(0.004)
    with pytest.raises(ValueError, match=r"^x: must be a finite number, got nan"):
        read(Param(0.5), float("nan"))
    with pytest.raises(ValueError, match=r"^x: incompatible units"):
        read(Param(0.5), "3 m")


def test_positive_and_nonneg_rules():
    with pytest.raises(ValueError, match=r"^x: must be > 0, got 0.0$"):
        read(Param("1 m", "m"), 0)
    with pytest.raises(ValueError, match=r"^x: must be > 0, got -1.0$"):
        read(Param(1.0), -1)
    assert read(Param("1 m", "m", "nonneg"), 0) == 0.0
    assert read(Param(1.0, rule="nonneg"), "0 percent") == 0.0
    with pytest.raises(ValueError, match=r"^x: must be >= 0, got -0.001$"):
        read(Param("1 m", "m", "nonneg"), "-1 mm")


def test_count_rule():
    assert read(Param(3, rule="count"), 4.0) == 4
    with pytest.raises(ValueError, match=r"^x: must be a positive integer, got 2.5"):
        read(Param(3, rule="count"), 2.5)
    with pytest.raises(ValueError, match=r"^x: must be a positive integer, got True"):
        read(Param(3, rule="count"), True)
    with pytest.raises(ValueError, match=r"^x: must be a positive integer, got 0"):
        read(Param(3, rule="count"), 0)


def test_flag_rule_takes_bools_and_true_false_strings():
    flag = Param(False, rule="flag")
    assert read(flag, True) is True
    assert read(flag, np.bool_(True)) is True
    assert read(flag, " TRUE ") is True
    assert read(flag, "false") is False
    for bad in ("yes", 1, None):
        with pytest.raises(ValueError, match=r"^x: must be true or false, got"):
            read(flag, bad)


def test_choice_rule():
    choice = Param("cantilevered", rule="choice", choices=("cantilevered", "total"))
    assert read(choice) == "cantilevered"
    assert read(choice, " Total ") == "total"
    for bad in ("hub", 1, None):
        with pytest.raises(
            ValueError, match=r"^x: must be one of \['cantilevered', 'total'\], got"
        ):
            read(choice, bad)


def test_raw_rule_returns_the_value_unchanged():
    patches = [(1, "0 m"), (2, 0)]
    assert read(Param((), rule="raw"), patches) is patches
    assert read(Param(None, rule="raw")) is None


def test_callable_rule_parses_the_default_and_overrides():
    calls = []

    def parse(raw, name):
        calls.append((raw, name))
        if raw == "bad":
            raise ValueError(f"{name}: must not be bad")
        return raw * 2

    assert read(Param(3, rule=parse)) == 6
    assert read(Param(3, rule=parse), "ab") == "abab"
    assert calls == [(3, "x"), ("ab", "x")]
    with pytest.raises(ValueError, match=r"^x: must not be bad$"):
        read(Param(3, rule=parse), "bad")


def test_optional_inputs_accept_none_others_refuse_it():
    assert read(Param(None, "kg", optional=True)) is None
    assert read(Param("1 kg", "kg", optional=True), None) is None
    assert read(Param(None, "kg", optional=True), "2 kg") == 2.0
    assert read(Param(None, rule="count", optional=True), 2) == 2
    with pytest.raises(ValueError, match=r"^x: must be a positive integer, got 0"):
        read(Param(None, rule="count", optional=True), 0)
    with pytest.raises(ValueError, match=r"^x: cannot read None"):
        read(Param("1 kg", "kg"), None)


def test_first_broken_input_in_spec_order_is_reported():
    params = {"a": Param(1.0), "b": Param(1.0)}
    with pytest.raises(ValueError, match=r"^a: must be > 0"):
        read_inputs("demo", params, {"b": -1, "a": -1})


def test_bad_specs_are_refused():
    with pytest.raises(ValueError, match=r"^rule: must be one of .*, got 'positiv'"):
        Param(1.0, rule="positiv")
    with pytest.raises(ValueError, match=r"^choices: a 'choice' input needs"):
        Param("a", rule="choice")


def test_a_count_with_a_limit_is_refused_above_it_before_anything_is_built():
    """A mesh or mode count beyond flexsat.limits is refused naming the input and the limit
    (n_elements = 1e9 would otherwise allocate the mesh and hang)."""
    from flexsat import limits

    spec = {"n_elements": Param(20, rule="count", limit="MAX_ELEMENTS")}
    assert (
        read_inputs("test", spec, {"n_elements": limits.MAX_ELEMENTS})["n_elements"]
        == limits.MAX_ELEMENTS
    )
    with pytest.raises(
        ValueError,
        match=r"^n_elements: n_elements = 1e\+09, above the limit "
        r"1,000 \(flexsat.limits\); a larger n_elements takes",
    ):
        read_inputs("test", spec, {"n_elements": 10**9})
    with pytest.raises(ValueError, match=r"^limit: must name a flexsat.limits constant"):
        Param(20, rule="count", limit="MAX_NOTHING")


@pytest.mark.parametrize(
    "case, name",
    [
        ("cantilever_beam", "n_elements"),
        ("nafems_fv2", "elements_per_arm"),
        ("nps", "n_elements"),
        ("nps", "n_modes"),
        ("agrawal_bang", "n_modes"),
    ],
)
def test_case_mesh_and_mode_counts_are_bounded(case, name):
    from flexsat.cases import get_case

    with pytest.raises(ValueError, match=rf"^{name}: {name} = 1e\+09, above the limit"):
        get_case(case).builder(**{name: 10**9})
