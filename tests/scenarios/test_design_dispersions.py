"""The dispersions section of a design study (flexsat.scenarios.design_dispersions): what may be
dispersed, which runs fly, the metrics and their requirements in SI."""

from __future__ import annotations

import re

import pytest

from flexsat.input_checks import FieldError
from flexsat.scenarios.batch_cases import DOCUMENT_CHUNK_SIZE
from flexsat.scenarios.design_dispersions import (
    METRIC_UNITS,
    DispersionsSpec,
    disperses_model,
    metric_names,
)

MODULUS = {"distribution": "normal", "mean": "70 GPa", "sd": "1.75 GPa"}
DAMPING = {"distribution": "lognormal", "median": 0.005, "gsd": 1.5}


def _spec(parameters=None, **changes) -> DispersionsSpec:
    """The section validated as a study reads it (a refusal: pydantic's ValueError)."""
    data = {"parameters": parameters or {"modes.damping": DAMPING}, "cases": 20, **changes}
    return DispersionsSpec.model_validate(data)


@pytest.mark.parametrize(
    "path, message",
    [
        ("laws[0].bandwidth", "a dispersion varies the truth"),
        ("placement.number", "a dispersion varies the truth"),
        ("runs[0].duration", "of a run, only its initial state"),
        ("simulation.control_rate", "not a dispersion: the laws are designed and sampled"),
        ("simulation.seed", "not a dispersion: each case's noise seed"),
        ("damping", "a dispersion varies the truth"),  # not a path at all
    ],
)
def test_only_the_truth_may_be_dispersed(path, message):
    """The design (laws, placement) stays nominal; control rate and seed are not dispersions."""
    with pytest.raises(ValueError, match=re.escape(f"parameters.{path}") + ".*" + message):
        _spec({path: DAMPING})


def test_the_truth_sections_are_accepted_and_say_whether_each_case_solves_its_structure():
    both = _spec({"model.fe.materials.aluminium.E": MODULUS, "runs[0].initial.rate[0]": DAMPING})
    assert disperses_model(both)
    assert not disperses_model(_spec({"modes.damping": DAMPING}))


def test_grid_axes_are_refused_and_the_chunk_defaults_to_the_document_batches():
    with pytest.raises(ValueError, match="parameters: dispersions are distributions"):
        _spec({"modes.damping": {"values": [0.001, 0.01]}})
    assert _spec().execution.chunk_size == DOCUMENT_CHUNK_SIZE
    assert _spec(execution={"chunk_size": 3}).execution.chunk_size == 3


def test_the_runs_flown_keep_the_study_s_order_and_unknown_ones_are_named():
    labels = ["slew", "hold", "step"]
    assert _spec().flown(labels) == labels
    assert _spec(runs=["step", "slew"]).flown(labels) == ["slew", "step"]
    with pytest.raises(FieldError, match="dispersions.runs: 'spin' is not a run of the study"):
        _spec(runs=["spin"]).flown(labels)


def test_metric_names_for_one_run_and_for_several():
    assert metric_names(["slew"], forces=True) == list(METRIC_UNITS)
    assert "peak_force_N" not in metric_names(["slew"], forces=False)
    two = metric_names(["slew", "hold"], forces=False)
    assert two[0] == "runs['slew'].final_attitude_error_rad"
    assert len(two) == 2 * (len(METRIC_UNITS) - 1)


def test_requirements_are_taken_in_the_metric_s_si_unit():
    """1 mrad → 1e-3 rad and 5 mm → 5e-3 m (exact decimal factors, to a few ε); a metric the
    runs do not produce is refused by its path."""
    spec = _spec(
        requirements={
            "final_attitude_error_rad": {"max": "1 mrad"},
            "peak_displacement_m": {"max": "5 mm"},
        }
    )
    reqs = spec.requirement_list(metric_names(["slew"], forces=False))
    assert [(r.metric, r.relation) for r in reqs] == [
        ("final_attitude_error_rad", "<="),
        ("peak_displacement_m", "<="),
    ]
    assert reqs[0].threshold == pytest.approx(1e-3, rel=1e-15)
    assert reqs[1].threshold == pytest.approx(5e-3, rel=1e-15)
    bad = _spec(requirements={"peak_force_N": {"max": "1 N"}})
    with pytest.raises(FieldError, match="dispersions.requirements.peak_force_N: unknown metric"):
        bad.requirement_list(metric_names(["slew"], forces=False))
