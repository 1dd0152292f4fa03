"""``kind: design`` (issue 23 deliverables 1 and 4): a design problem as data — the optimum
from the document equals the one built by hand through the API, two optimisers agree, the front
is nondominated with every ε binding, the report writes metrics.json with the optimum, KKT
residual, active set and the front, and bad documents are refused with their field paths."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import yaml

from flexsat.design.pareto import FrontSetup, nondominated, solve_case
from flexsat.design.reference_problems import HubBoomCodesign
from flexsat.report.page import write_report
from flexsat.scenarios.documents import load_scenario
from flexsat.scenarios.errors import ScenarioError
from flexsat.scenarios.runner import run_scenario

EXAMPLE = Path(__file__).parents[2] / "examples" / "tamu_codesign_pareto.yaml"

DOC = {
    "kind": "design",
    "name": "hub-boom co-design",
    "problem": "hub_boom_codesign",
    "variables": {"t": {"start": "2 mm", "lower": "0.5 mm", "upper": "3 mm"}},
    "objective": "lq_cost",
    "constraints": [
        {"response": "frequency_hz", "min": "6 Hz"},
        {"response": "mass", "max": "300 g"},
    ],
    "optimizer": {"method": "slsqp", "compare": "trust-constr"},
}


def _load(doc: dict, tmp_path: Path):
    path = tmp_path / "design.yaml"
    path.write_text(yaml.safe_dump(doc))
    return load_scenario(path)


def test_the_example_validates():
    scenario = load_scenario(EXAMPLE)
    assert scenario.kind == "design" and scenario.pareto is not None
    assert scenario.pareto.points == 40


def test_the_optimum_equals_the_api_problem_and_two_optimisers_agree(tmp_path):
    result = run_scenario(_load(DOC, tmp_path))
    a, b = result.optima
    # the document's mass cap is the ε-constraint problem at ε = 0.3 kg built through the API
    direct = solve_case(FrontSetup(HubBoomCodesign(), "lq_cost", "mass"), 0.3, 0)
    assert a.objective == pytest.approx(direct.objective, rel=1e-12)
    np.testing.assert_allclose(a.x, direct.x, rtol=1e-12)
    assert a.kkt.residual <= 1e-6 and b.kkt.residual <= 1e-6
    assert b.objective == pytest.approx(a.objective, rel=1e-2)
    assert any(name.startswith("mass <=") for name in a.active)


def test_the_report_holds_optimum_kkt_active_set_and_the_front(tmp_path):
    doc = dict(DOC, optimizer={"method": "slsqp"})
    doc["pareto"] = {"secondary": "mass", "points": 3, "starts": 2, "store": "front.zarr"}
    result = run_scenario(_load(doc, tmp_path))
    out = write_report(result, tmp_path / "report")
    records = json.loads((out / "metrics.json").read_text())
    optimum = records[0]
    assert optimum["run"] == "optimum (slsqp)"
    assert optimum["kkt_residual"] <= 1e-6
    assert "mass <= 0.3" in optimum["active"]
    front = [r for r in records if r["run"].startswith("front ")]
    assert len(front) == 3
    f1 = np.array([r["primary"] for r in front])
    f2 = np.array([r["secondary"] for r in front])
    assert nondominated(f1, f2).all()
    assert all(r["epsilon_active"] == 1 and r["kkt_residual"] <= 1e-6 for r in front)
    assert np.all(f2 < 0.3)  # inside the document's mass budget
    assert (tmp_path / "front.zarr").is_dir()  # relative stores live beside the document
    page = (out / "index.html").read_text()
    assert "Pareto front" in page and "pareto_front.png" in page
    assert (out / "pareto_front.png").stat().st_size > 0


@pytest.mark.parametrize(
    ("change", "path"),
    [
        ({"problem": "truss"}, "problem"),
        ({"objective": "settling_time"}, "objective"),
        ({"variables": {"w": {"start": 1}}}, "variables.w"),
        ({"variables": {"t": {"lower": "3 mm", "upper": "1 mm"}}}, "variables.t.lower"),
        ({"variables": {"t": {"start": "2 kg"}}}, "variables.t.start"),
        ({"parameters": {"booms": 0}}, "parameters.booms"),
        ({"parameters": {"colour": 1}}, "parameters.colour"),
        ({"constraints": [{"response": "mass"}]}, "constraints"),
        ({"constraints": [{"response": "cost", "max": 1}]}, "constraints[0].response"),
        ({"pareto": {"secondary": "lq_cost"}}, "pareto.secondary"),
        ({"pareto": {"secondary": "mass", "points": 0}}, "pareto.points"),
        ({"optimizer": {"method": "simplex"}}, "optimizer.method"),
    ],
    ids=[
        "problem",
        "objective",
        "variable",
        "bounds",
        "unit",
        "parameter-rule",
        "parameter-name",
        "no-bound",
        "response",
        "secondary",
        "points",
        "method",
    ],
)
def test_bad_documents_are_refused_with_their_field_path(change, path, tmp_path):
    with pytest.raises(ScenarioError) as info:
        _load({**DOC, **change}, tmp_path)
    fields = [p.path for p in info.value.problems]
    assert any(f.startswith(path) for f in fields), fields


def test_workers_go_into_the_pareto_section_and_need_one(tmp_path):
    from flexsat.scenarios.design_problem import DesignKind

    kind = DesignKind()
    with_front = _load({**DOC, "pareto": {"secondary": "mass"}}, tmp_path)
    assert kind.with_execution(with_front, 2, None).pareto.workers == 2
    with pytest.raises(ScenarioError, match="pareto"):
        kind.with_execution(_load(DOC, tmp_path), 2, None)
    with pytest.raises(ScenarioError, match="not both"):
        kind.with_execution(with_front, 2, "tcp://127.0.0.1:1")


def test_the_cantilever_tube_document_reproduces_the_closed_form(tmp_path):
    """The closed-form optimum (reference_problems.cantilever_tube_optimum) to 1e-8: SLSQP ends
    on the two active constraints (wall bound and frequency floor), a vertex it solves to
    round-off."""
    from flexsat.design.reference_problems import CantileverTube, cantilever_tube_optimum

    doc = {
        "kind": "design",
        "name": "cantilever tube",
        "problem": "cantilever_tube",
        "objective": "mass",
        "constraints": [{"response": "omega", "min": "20 Hz"}],  # 2π·20 rad/s
    }
    (optimum,) = run_scenario(_load(doc, tmp_path)).optima
    exact = cantilever_tube_optimum(CantileverTube())
    assert optimum.objective == pytest.approx(exact["mass"], rel=1e-8)
    assert optimum.design["D"] == pytest.approx(exact["D"], rel=1e-8)
    assert optimum.kkt.residual <= 1e-6


def test_a_maneuver_response_is_an_objective(tmp_path):
    """The sampled slew's soft settling time as the objective (the reference computes its
    maneuver responses because the document names one): both optimisers reach the same
    optimum with KKT residual <= 1e-6 (wall at its lower bound; the diameter trades boom
    inertia against stiffness and the mass cap is inactive)."""
    doc = {
        "kind": "design",
        "name": "hub-boom co-design, settling",
        "problem": "hub_boom_codesign",
        "objective": "soft_settling",
        "constraints": [{"response": "mass", "max": "0.6 kg"}],
        "optimizer": {"method": "slsqp", "compare": "trust-constr"},
    }
    result = run_scenario(_load(doc, tmp_path))
    a, b = result.optima
    assert a.kkt.residual <= 1e-6 and b.kkt.residual <= 1e-6
    assert b.objective == pytest.approx(a.objective, rel=1e-2)
    assert a.active == ("t >= lower",)
    start = HubBoomCodesign(maneuver=True).responses(np.array([2e-3, 0.04]))["soft_settling"][0]
    assert a.objective < start


def test_maneuver_responses_validate_by_name(tmp_path):
    doc = dict(DOC, objective="settling")
    with pytest.raises(ScenarioError, match="soft_settling"):
        _load(doc, tmp_path)
