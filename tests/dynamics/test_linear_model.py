"""A plant's linear part as a labelled python-control StateSpace (flexsat.dynamics.linear_model)."""

from __future__ import annotations

import numpy as np
import pytest

from flexsat.cases.tamu import tamu
from flexsat.dynamics import RigidSpacecraft
from flexsat.dynamics.dispersion import stack_plants
from flexsat.dynamics.linear_model import plant_state_space
from flexsat.input_checks import FieldError


@pytest.fixture(scope="module")
def hub():
    """The TAMU hub with its appendages: a linear HubAppendage, 22 states, one torque."""
    return tamu().model()


def test_the_state_space_is_the_plant_s_linear_part_and_output_matrices(hub):
    """A, B are linear_part() and the rows of C, D each chosen output's matrices, in the order
    asked; copied, not computed, so equal bit for bit."""
    P = plant_state_space(hub, outputs=["tip_deflection", "theta"])
    A, B = hub.linear_part()
    assert np.array_equal(P.A, A) and np.array_equal(P.B, B)
    for row, out in enumerate(["tip_deflection", "theta"]):
        C, D, _ = hub.output_matrices(out)
        assert np.array_equal(P.C[row], np.ravel(C)) and np.array_equal(P.D[row], np.ravel(D))


def test_signals_are_labelled_as_python_control_names_them(hub):
    """Every linear output but "state" by default; one-wide channels by name; states x[i]."""
    P = plant_state_space(hub)
    linear = [c.name for c in hub.outputs if c.name != "state" and hub.output_matrices(c.name)]
    assert P.output_labels == linear and P.input_labels == ["torque"]
    assert P.state_labels == [f"x[{i}]" for i in range(hub.nx)]
    assert P.name == "HubAppendage"
    assert plant_state_space(hub, name="tamu").name == "tamu"


def test_a_nonlinear_plant_is_refused_naming_the_way_to_linearise_it():
    # RigidSpacecraft is nonlinear: refused by name, with the way to linearise it
    with pytest.raises(FieldError, match="plant: RigidSpacecraft is nonlinear.*linearize_attitude"):
        plant_state_space(RigidSpacecraft(np.eye(3)))


def test_a_dispersed_batch_and_a_non_plant_are_refused_by_name(hub):
    with pytest.raises(FieldError, match="plant: DispersedHubAppendage is a dispersed batch"):
        plant_state_space(stack_plants([hub, hub]))
    with pytest.raises(FieldError, match="plant: must be a flexsat Plant"):
        plant_state_space("hub")  # type: ignore[arg-type]
    with pytest.raises(FieldError, match="states: give 22 distinct labels"):
        plant_state_space(hub, states=["a"] * 22)
