"""flexsat.design.describe: a described feature keeps its values, units and labels, turns into
plain data and back, refuses bad values by name; describe is optional; poles are ordered so two
designs line up; each reference problem's description agrees with its own responses."""

from __future__ import annotations

import json

import numpy as np
import pytest

from flexsat.cases.tamu_codesign import PUBLISHED_LAW_II, TamuCodesign
from flexsat.design.describe import DesignFeature, describe_design, sorted_poles
from flexsat.design.reference_problems import CantileverTube, HubBoomCodesign
from flexsat.input_checks import FieldError


def test_a_feature_keeps_its_values_and_becomes_plain_data():
    real = DesignFeature("structure", np.array([1.5, 2.5]), "Hz", note="FE")
    assert real.labels == ("1", "2") and not real.is_complex
    assert json.loads(json.dumps(real.as_data())) == {
        "discipline": "structure",
        "unit": "Hz",
        "labels": ["1", "2"],
        "note": "FE",
        "values": [1.5, 2.5],
    }
    poles = DesignFeature("control", np.array([-1 + 2j, -1 - 2j]), "1/s", labels=("a", "b"))
    data = poles.as_data()
    back = np.array(data["real"]) + 1j * np.array(data["imag"])
    np.testing.assert_array_equal(back, poles.values)
    scalar = DesignFeature("control", 3, "N*m/rad")  # type: ignore[arg-type]
    assert scalar.values.shape == (1,) and scalar.values.dtype == float


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"discipline": "optics", "values": np.ones(1)}, "discipline"),
        ({"discipline": "structure", "values": np.array([1.0, np.nan])}, "values"),
        ({"discipline": "structure", "values": np.ones((2, 2))}, "values"),
        ({"discipline": "structure", "values": np.array(["a"])}, "values"),
        ({"discipline": "structure", "values": np.ones(2), "labels": ("a",)}, "labels"),
    ],
    ids=["discipline", "nan", "2-d", "text", "labels"],
)
def test_bad_features_are_refused_by_name(kwargs, field):
    with pytest.raises(FieldError) as info:
        DesignFeature(**kwargs)
    assert info.value.field == field


def test_describe_is_optional_and_its_result_is_checked():
    class Silent:
        def responses(self, x):
            return {}

    assert describe_design(Silent(), [1.0]) == {}

    class Wrong:
        def describe(self, x):
            return {"frequency": 3.0}

    with pytest.raises(FieldError, match="Wrong.describe"):
        describe_design(Wrong(), [1.0])


def test_poles_are_ordered_by_frequency_with_conjugates_together():
    p = np.array([-3 - 40j, -0.5 + 0j, -3 + 40j, -1 - 2j, -2 + 0j, -1 + 2j])
    assert list(sorted_poles(p)) == [-2, -0.5, -1 + 2j, -1 - 2j, -3 + 40j, -3 - 40j]
    rng = np.random.default_rng(1)
    np.testing.assert_array_equal(sorted_poles(rng.permutation(p)), sorted_poles(p))


def test_each_reference_problems_description_agrees_with_its_responses():
    x = np.array([1e-3, 30e-3])
    hub = HubBoomCodesign()
    d = hub.describe(x)
    assert d["elastic frequencies"].values[0] == pytest.approx(
        hub.responses(x)["frequency_hz"][0], rel=1e-14
    )
    assert d["elastic frequencies"].values.size == hub.elastic_modes
    assert d["LQ gain"].values.size == 2 * (hub.elastic_modes + 1)
    assert np.all(d["closed-loop poles"].values.real < 0)  # the LQ loop is stable
    tube = CantileverTube()
    omega = tube.responses(x)["omega"][0]
    assert tube.describe(x)["first bending frequency"].values[0] == pytest.approx(
        omega / (2 * np.pi), rel=1e-15
    )
    tamu = TamuCodesign()
    first = tamu.describe(np.array(PUBLISHED_LAW_II))["appendage frequencies"].values[0]
    assert first == pytest.approx(tamu.first_frequency_hz(np.array([1.0]))[0], rel=1e-14)
    # the published appendage's first clamped frequency (docs/design_optimization.md: 0.75 Hz)
    assert first == pytest.approx(0.75, abs=0.005)
