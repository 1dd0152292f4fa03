"""Field paths into scenario documents (flexsat.scenarios.document_paths): keys, indices and
labels read and written, every other path refused with the nearest ones."""

import pytest

from flexsat.input_checks import FieldError
from flexsat.scenarios.document_paths import (
    leaf_paths,
    nearest_paths,
    parse_path,
    read_value,
    with_values,
)

DOCUMENT = {
    "plant": {"tip_mass": "0.1 kg", "inertia": ["1 kg*m**2", "2 kg*m**2", "2.5 kg*m**2"]},
    "model": {
        "fe": {
            "materials": [
                {"name": "al", "E": "70 GPa"},
                {"name": "Al 6061", "E": "68.9 GPa"},
            ],
            "sections": {"tube": {"A": "1 cm**2"}},
        }
    },
    "runs": [
        {"label": "PD", "gains": {"K": "7200 N*m"}},
        {"label": "LQR", "weights": [1.0, 2.0]},
    ],
    "simulation": {"duration": "60 s"},
}


@pytest.mark.parametrize(
    "text, steps",
    [
        ("plant.tip_mass", ("plant", "tip_mass")),
        ("plant.inertia[2]", ("plant", "inertia", 2)),
        ("runs['PD'].gains.K", ("runs", "PD", "gains", "K")),
        ('runs["PD"].gains.K', ("runs", "PD", "gains", "K")),
        ("model.fe.materials['Al 6061'].E", ("model", "fe", "materials", "Al 6061", "E")),
        ("runs['it\\'s'].x", ("runs", "it's", "x")),
        ("runs[ -1 ].weights", ("runs", -1, "weights")),
    ],
)
def test_paths_parse_into_their_steps(text, steps):
    assert parse_path(text) == steps


@pytest.mark.parametrize(
    "text, value",
    [
        ("plant.tip_mass", "0.1 kg"),
        ("plant.inertia[2]", "2.5 kg*m**2"),
        ("plant.inertia[-1]", "2.5 kg*m**2"),
        ("runs['PD'].gains.K", "7200 N*m"),
        ("runs.PD.gains.K", "7200 N*m"),  # a label that is a name may follow a dot
        ("runs[1].weights[0]", 1.0),
        ("runs['LQR'].weights[1]", 2.0),
        ("model.fe.materials.al.E", "70 GPa"),  # a list item by its name
        ("model.fe.materials['Al 6061'].E", "68.9 GPa"),
        ("model.fe.sections.tube.A", "1 cm**2"),
        ("simulation.seed", None),  # an absent last key: the kind's schema decides
    ],
)
def test_values_are_read_by_key_index_label_and_name(text, value):
    assert read_value(DOCUMENT, text) == value


def test_values_are_written_into_a_copy():
    out = with_values(
        DOCUMENT,
        {
            "runs['PD'].gains.K": "7000 N*m",
            "plant.inertia[0]": "1.5 kg*m**2",
            "model.fe.materials.al.E": "71 GPa",
            "simulation.seed": 3,
        },
    )
    assert out["runs"][0]["gains"]["K"] == "7000 N*m"
    assert out["plant"]["inertia"] == ["1.5 kg*m**2", "2 kg*m**2", "2.5 kg*m**2"]
    assert out["model"]["fe"]["materials"][0]["E"] == "71 GPa"
    assert out["simulation"] == {"duration": "60 s", "seed": 3}
    # the original is untouched
    assert DOCUMENT["runs"][0]["gains"]["K"] == "7200 N*m"
    assert DOCUMENT["plant"]["inertia"][0] == "1 kg*m**2"
    assert "seed" not in DOCUMENT["simulation"]


@pytest.mark.parametrize(
    "text, message",
    [
        (
            "runs['PID'].gains.K",
            r"runs\['PID'\].gains.K is not a field of the scenario \(step 2, 'PID', is not "
            r"found\); nearest: runs\['PD'\].gains.K",
        ),
        ("plant.inertia[3]", r"step 3, 3, is not found"),
        ("plnt.tip_mass", r"nearest: plant.tip_mass"),
        ("runs['PD'].gain.K", r"step 3, 'gain', is not found.*nearest: runs\['PD'\].gains.K"),
        ("plant", "holds a mapping; a parameter sets one number"),
        ("plant.inertia", "holds a list; a parameter sets one number"),
        ("runs[PD].x", "at character 5, a bracket holds an index"),
        ("plant..tip_mass", "at character 7, expected a name"),
        ("plant tip_mass", "at character 6, expected '.' or '\\[' between steps"),
        ("2plant", "at character 1, expected a name"),
        ("", "a field path such as plant.tip_mass"),
    ],
)
def test_bad_paths_are_refused_by_name(text, message):
    with pytest.raises(FieldError, match=message) as err:
        read_value(DOCUMENT, text, "parameters.x")
    assert err.value.field == "parameters.x"


def test_the_paths_of_a_document_name_labelled_items_by_label():
    paths = list(leaf_paths(DOCUMENT))
    assert "runs['PD'].gains.K" in paths and "runs['LQR'].weights[1]" in paths
    assert "model.fe.materials['al'].E" in paths and "plant.inertia[0]" in paths
    assert "runs['PD'].label" not in paths
    assert len(paths) == 11  # the labels and names are not among them
    assert nearest_paths("runs['PD'].gains.k", DOCUMENT)[0] == "runs['PD'].gains.K"
