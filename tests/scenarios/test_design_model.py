"""``kind: design`` with ``model:`` (flexsat.scenarios.design_model, issue 23 deliverable 1):
the example's optimum is checked against methods that share nothing with the analytic
gradients or the optimisers' KKT check, and bad documents are refused with their field paths.

Independent checks of examples/own_structure_design.yaml (minimum mass, f₁ >= 3 Hz,
f₂ − f₁ >= 0.5 Hz, four section dimensions):

1. Kuhn–Tucker by central differences of the plain FE model (``Assembly.modes`` and
   ``Structure.structural_mass`` only): at the optimum both constraints hold with equality and
   ∇m = λ₁ ∇f₁ + λ₂ ∇(f₂ − f₁) with λ >= 0, the least-squares residual ≤ 1e-6 ‖∇m‖. Step
   h = 1e-4 x: truncation h²|f'''|/6 ≈ 1e-8 relative, round-off ε_f |f| / h ≈ 1e-9.
2. A derivative-free optimiser (COBYLA) on the same plain model from the same start reaches
   the same design: its accuracy is set by its final trust radius (rhoend 1e-6 of the
   variables' millimetre scale), so designs agree to 1e-4 and masses to 1e-6 relative.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml
from scipy.optimize import minimize

from flexsat.scenarios.design_problem import ConfiguredProblem
from flexsat.scenarios.documents import load_scenario
from flexsat.scenarios.errors import ScenarioError
from flexsat.scenarios.runner import run_scenario

EXAMPLE = Path(__file__).parents[2] / "examples" / "own_structure_design.yaml"
F_MIN, SEPARATION = 3.0, 0.5  # the example's constraints, Hz


@pytest.fixture(scope="module")
def solved():
    scenario = load_scenario(EXAMPLE)
    return scenario, run_scenario(scenario)


def _plain(problem, x):
    """(f₁, f₂) in Hz and the mass of the FE model at x: modal solve, no derivatives."""
    structure = problem.structure(x)
    f = structure.assemble().modes(2).frequencies_hz
    return f[0], f[1], structure.structural_mass()


def test_both_optimisers_reach_a_kkt_point_with_both_constraints_active(solved):
    scenario, result = solved
    a, b = result.optima
    assert (a.method, b.method) == ("slsqp", "trust-constr")
    assert a.kkt.residual <= 1e-6 and b.kkt.residual <= 1e-6
    assert b.objective == pytest.approx(a.objective, rel=1e-6)
    np.testing.assert_allclose(b.x, a.x, rtol=1e-5)
    assert set(a.active) == {f"frequency_hz_1 >= {F_MIN:g}", f"separation_hz_1_2 >= {SEPARATION:g}"}
    assert all(v > 0 for v in a.multipliers.values())


def test_the_optimum_satisfies_kkt_by_central_differences_of_the_plain_model(solved):
    scenario, result = solved
    problem = result.configured.reference
    x = result.optima[0].x
    f1, f2, m = _plain(problem, x)
    assert f1 == pytest.approx(F_MIN, rel=1e-8)
    assert f2 - f1 == pytest.approx(SEPARATION, rel=1e-7)
    grads = np.zeros((3, x.size))
    for k in range(x.size):
        h = 1e-4 * x[k]
        e = np.zeros(x.size)
        e[k] = h
        grads[:, k] = (np.array(_plain(problem, x + e)) - np.array(_plain(problem, x - e))) / (
            2 * h
        )
    dm, active = grads[2], np.vstack([grads[0], grads[1] - grads[0]])
    lam, *_ = np.linalg.lstsq(active.T, dm, rcond=None)
    assert np.all(lam > 0)
    assert np.linalg.norm(active.T @ lam - dm) <= 1e-6 * np.linalg.norm(dm)
    # no bound is active: the optimum is interior in every dimension
    lower, upper = np.array([5e-3] * 4), np.array([60e-3] * 4)
    assert np.all((x - lower) > 1e-3) and np.all((upper - x) > 1e-3)


def test_a_derivative_free_optimiser_on_the_plain_model_finds_the_same_design(solved):
    scenario, result = solved
    problem = result.configured.reference
    memo: dict[bytes, tuple[float, float, float]] = {}

    def plain(z):
        key = z.tobytes()
        if key not in memo:
            memo[key] = _plain(problem, z * 1e-3)
        return memo[key]

    found = minimize(
        lambda z: plain(z)[2],
        problem.x0 * 1e3,
        method="COBYLA",
        constraints=[
            {"type": "ineq", "fun": lambda z: plain(z)[0] - F_MIN},
            {"type": "ineq", "fun": lambda z: plain(z)[1] - plain(z)[0] - SEPARATION},
        ],
        bounds=[(5.0, 60.0)] * 4,
        options={"rhobeg": 2.0, "tol": 1e-6, "maxiter": 3000},
    )
    best = result.optima[0]
    np.testing.assert_allclose(found.x * 1e-3, best.x, rtol=1e-4)
    assert found.fun == pytest.approx(best.objective, rel=1e-6)


def test_the_report_tracks_the_modes_against_the_start_design(solved):
    _, result = solved
    record = result.optimum_records()[0]
    assert record["mode_1_is_start_mode"] == 1 and record["mode_2_is_start_mode"] == 2
    assert record["mode_1_mac"] > 0.9 and record["mode_2_mac"] > 0.9
    assert record["frequency_hz_1"] == pytest.approx(F_MIN, rel=1e-8)
    assert result.report_case().startswith("your own")


# -- refusals ------------------------------------------------------------------------------------
BASE = yaml.safe_load(EXAMPLE.read_text())


def _changed(path: tuple, value) -> dict:
    import copy

    data = copy.deepcopy(BASE)
    node = data
    for key in path[:-1]:
        node = node[key]
    if value is _DELETE:
        del node[path[-1]]
    else:
        node[path[-1]] = value
    return data


_DELETE = object()


@pytest.mark.parametrize(
    ("path", "value", "field"),
    [
        (("variables", "root_width", "section"), "stem", "variables.root_width.section"),
        (("variables", "root_width", "property"), "thickness", "variables.root_width.property"),
        (("variables", "root_width", "lower"), _DELETE, "variables.root_width.lower"),
        (("variables", "root_width", "lower"), "5 kg", "variables.root_width.lower"),
        (("variables", "root_width", "start"), "90 mm", "variables.root_width.start"),
        (("variables", "root_width", "upper"), "1 mm", "variables.root_width.lower"),
        (
            ("variables", "tip"),
            {"lumped_mass": 3, "lower": 1, "upper": 2},
            "variables.tip.lumped_mass",
        ),
        (
            ("variables", "tip"),
            {"lumped_mass": 4, "property": "inertia", "lower": 1e-5, "upper": 2e-4},
            "variables.tip.axis",
        ),
        (("variables", "tip"), {"lower": 1, "upper": 2}, "variables.tip"),
        (
            ("variables", "root_width"),
            {"material": "steel", "property": "E", "lower": 1, "upper": 2},
            "variables.root_width.material",
        ),
        (
            ("variables", "root_width"),
            {"material": "aluminium", "section": "root", "lower": 1, "upper": 2},
            "variables.root_width",
        ),
        (("objective",), "frequency_hz_9", "objective"),
        (("objective",), "stiffness", "objective"),
        (("constraints", 1, "response"), "separation_hz_2_1", "constraints[1].response"),
        (("parameters",), {"hub_inertia": 1}, "parameters"),
        (("problem",), "cantilever_tube", "problem"),
        (("model",), {"file": "boom.nc"}, "model.file"),
        (("model", "fe", "sections", "root", "width"), "3 kg", "model.fe.sections.root.width"),
    ],
    ids=[
        "section",
        "property",
        "no-bound",
        "bound-unit",
        "start",
        "bounds",
        "mass-node",
        "inertia-axis",
        "what",
        "material",
        "two-parts",
        "mode-beyond",
        "response",
        "separation",
        "parameters",
        "both",
        "file",
        "model-unit",
    ],
)
def test_bad_documents_are_refused_with_their_field_path(path, value, field, tmp_path):
    doc = tmp_path / "design.yaml"
    doc.write_text(yaml.safe_dump(_changed(path, value), sort_keys=False))
    with pytest.raises(ScenarioError) as info:
        load_scenario(doc)
    fields = [p.path for p in info.value.problems]
    assert any(f.startswith(field) for f in fields), fields


def test_a_lumped_mass_variable_names_its_node_and_defaults_to_the_models_value(tmp_path):
    data = _changed(("variables", "tip"), {"lumped_mass": 4, "lower": "0.2 kg", "upper": "1 kg"})
    doc = tmp_path / "design.yaml"
    doc.write_text(yaml.safe_dump(data, sort_keys=False))
    configured = ConfiguredProblem.from_scenario(load_scenario(doc))
    (tip,) = [v for v in configured.reference.variables if v.name == "tip"]
    assert (tip.index, tip.property, tip.start) == (0, "mass", 0.5)
    (row,) = [v for v in configured.variables if v[0] == "tip"]
    assert row[1:4] == (0.5, 0.2, 1.0)


def test_a_material_variable_starts_at_the_models_modulus(tmp_path):
    data = _changed(
        ("variables", "modulus"),
        {"material": "aluminium", "property": "E", "lower": "60 GPa", "upper": "80 GPa"},
    )
    doc = tmp_path / "design.yaml"
    doc.write_text(yaml.safe_dump(data, sort_keys=False))
    configured = ConfiguredProblem.from_scenario(load_scenario(doc))
    (row,) = [v for v in configured.variables if v[0] == "modulus"]
    assert row[1:4] == (70e9, 60e9, 80e9) and row[5] == "Pa"
    r = configured.responses(np.array([v[1] for v in configured.variables]))
    assert r["frequency_hz_1"][1][-1] > 0  # a stiffer material raises the frequency
