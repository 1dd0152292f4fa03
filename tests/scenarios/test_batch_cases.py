"""The case documents of a batch (flexsat.scenarios.batch_cases): seeds, units, parameters."""

from __future__ import annotations

import numpy as np
import pytest
from pydantic import BaseModel

from flexsat.design.batch_seeds import case_seeds
from flexsat.input_checks import FieldError
from flexsat.limits import MAX_SEED
from flexsat.scenarios.batch_cases import (
    DocumentParameter,
    document_parameter,
    document_seeds,
    is_document_path,
    noise_seed_path,
    written_unit,
)
from flexsat.units import to_si

EPS = np.finfo(float).eps


def test_document_seeds_are_the_high_32_bits_of_the_case_seeds():
    """s_i >> 31 of a 63-bit seed: in the scenario seed range [0, 2³²), the case's alone (the
    same in any chunk), and distinct for 1,000 cases (collision chance ~ n²/2³³ ≈ 1e-4)."""
    idx = np.arange(1000)
    seeds = document_seeds(11, idx)
    assert seeds.tolist() == (case_seeds(11, idx) >> 31).tolist()
    assert seeds.min() >= 0 and seeds.max() <= MAX_SEED
    assert document_seeds(11, idx[500:510]).tolist() == seeds[500:510].tolist()
    assert np.unique(seeds).size == 1000


def test_a_value_goes_into_the_document_in_its_written_unit_and_reads_back_as_si():
    """52.3 ozf·in·s² written as a quantity string (repr of the float: exact round trip) and
    read back by the units boundary: the SI value to the product's round-off (a few ε)."""
    parameter = DocumentParameter("hub.inertia", "kg*m**2", "ozf*in*s**2")
    si = to_si("52.3 ozf*in*s**2", "kg*m**2")
    text = parameter.value(si)
    assert text.endswith(" ozf*in*s**2") and float(text.split()[0]) == pytest.approx(52.3)
    assert to_si(text, "kg*m**2") == pytest.approx(si, rel=4 * EPS)
    assert DocumentParameter("gain", "", None).value(2.5) == 2.5


def test_the_written_unit_is_the_first_quantity_and_hz_stays_hz():
    """A cyclic frequency keeps Hz as its SI unit (pint's base 1/s would not tell it from
    rad/s); plain numbers have no unit."""
    assert written_unit({"values": [1.0, "3 Hz"]}, "f") == ("Hz", "Hz")
    assert written_unit({"low": "2 rad/s", "high": "3 Hz"}, "w") == ("rad/s", "rad/s")
    assert written_unit({"mean": 1.0, "sd": 0.1}, "k") is None
    assert written_unit({"values": ["20 percent"]}, "p") == ("%", "")


def test_a_parameter_of_another_dimension_or_off_the_document_is_refused_by_path():
    data = {"hub": {"inertia": "2 kg*m**2", "name": "hub"}, "gain": 3.0}
    with pytest.raises(FieldError, match=r"parameters\.hub\.inertia: values in s .* dimension"):
        document_parameter("hub.inertia", {"values": ["1 s"]}, data)
    with pytest.raises(FieldError, match=r"parameters\.hub\.name: .*not a number or a quantity"):
        document_parameter("hub.name", {"values": [1.0]}, data)
    with pytest.raises(FieldError, match=r"parameters\.rotor\.mass"):
        document_parameter("rotor.mass", {"values": [1.0]}, data)
    # an absent last key is an optional field left out: accepted (the kind's schema judges it)
    assert document_parameter("hub.mass", {"values": ["1 kg"]}, data).unit == "kg"
    # a plain-number entry on a quantity field: SI, labelled with the field's base unit
    assert document_parameter("hub.inertia", {"values": [1.0]}, data) == DocumentParameter(
        "hub.inertia", "kg*m**2", None
    )


def test_the_seed_field_of_a_kind_and_what_counts_as_a_path():
    class Simulation(BaseModel):
        seed: int = 0

    class WithSimulation(BaseModel):
        simulation: Simulation | None = None

    class TopLevel(BaseModel):
        seed: int = 0

    class Deterministic(BaseModel):
        name: str = ""

    assert noise_seed_path(WithSimulation) == "simulation.seed"
    assert noise_seed_path(TopLevel) == "seed"
    assert noise_seed_path(Deterministic) is None
    assert is_document_path("ppf.zeta_f") and is_document_path("runs[0]")
    assert not is_document_path("g1")
