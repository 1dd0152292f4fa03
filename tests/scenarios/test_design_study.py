"""Design studies (kind: design_study): the example runs and reports every stage; the stage cache
is proven to skip the modal solve when a later stage changes and to redo everything when the
model changes; each law is what its design says; mistakes are named by their field."""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import control as ct
import flexsat.structures.fem as fem
from flexsat.report import write_report
from flexsat.scenarios import ScenarioError, load_scenario, run_scenario
from flexsat.scenarios.design_laws import design_state, law_controller, pd_gains
from flexsat.scenarios.design_study import stage_plan
from flexsat.sim import SimulationDiverged
from flexsat.structures.modal_model import RIGID_FREQUENCY
from scenario_mutations import VALUES, delete_at, key_paths, set_at

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "eps_design_stages.yaml"

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"

SMALL = {
    "kind": "design_study",
    "name": "small EPS study",
    "model": {"case": "eps", "n_modes": 8},
    "modes": {"n_modes": 6},
    "placement": {
        "torque_node": 95,
        "candidates": {"nodes": [69, 66, 60], "axes": ["x", "y"]},
        "number": 2,
        "outputs": [69],
    },
    "laws": [
        {"label": "PD", "type": "pd", "bandwidth": "0.3 rad/s"},
        {
            "label": "LQR",
            "type": "lqr",
            "modes": 4,
            "weights": {"attitude": 1e4, "rate": 1e4, "modes": 1, "torque": 1e-4, "force": 1e-2},
        },
    ],
    "simulation": {"duration": "2 s", "control_rate": "10 Hz"},
    "runs": [
        {"label": "PD run", "law": "PD", "initial": {"euler123": ["0.05 rad", 0, 0]}},
        {"label": "LQR run", "law": "LQR", "initial": {"euler123": ["0.05 rad", 0, 0]}},
    ],
}


def _study(tmp_path: Path, **changes) -> object:
    data = copy.deepcopy(SMALL)
    data["cache"] = str(tmp_path / "cache")
    for path, value in changes.items():
        node = data
        keys = path.split(".")
        for key in keys[:-1]:
            node = node[int(key)] if isinstance(node, list) else node[key]
        node[keys[-1]] = value
    return load_scenario(yaml.safe_dump(data, sort_keys=False))


@pytest.fixture
def solves(monkeypatch):
    """The number of finite-element modal solves (calls of ``Assembly.modes``)."""
    calls = []
    original = fem.Assembly.modes

    def counted(self, *args, **kwargs):
        calls.append(1)
        return original(self, *args, **kwargs)

    monkeypatch.setattr(fem.Assembly, "modes", counted)
    return calls


def _origins(result) -> dict[str, bool]:
    return {record.stage.label: record.cached for record in result.records}


def test_example_runs_and_reports_every_stage(tmp_path):
    data = yaml.safe_load(EXAMPLE.read_text())
    data["cache"] = str(tmp_path / "cache")
    scenario = load_scenario(yaml.safe_dump(data, sort_keys=False))
    result = run_scenario(scenario)
    labels = [r.stage.label for r in result.records]
    assert labels == ["model", "modes", "placement"] + [
        f"law {law.label!r}" for law in scenario.laws
    ] + [f"run {run.label!r}" for run in scenario.runs]
    assert not any(r.cached for r in result.records)
    assert len(result.placement.selection) == scenario.placement.number
    for record in result.records:
        if record.stage.name == "law":
            assert record.summary["max_pole_real_1_per_s"] < 0  # every design is stable
    for metrics in result.metrics_records():
        # 0.1 rad about each axis: every law brings the attitude back within 1 mrad in 30 s
        assert metrics["final_attitude_error_rad"] < 1e-3
    folder = tmp_path / "report"
    write_report(result, folder)
    page = (folder / "index.html").read_text()
    for label in labels:
        assert label.replace("'", "&#x27;") in page
    assert "computed" in page and "read from the stage cache" not in page
    ds = result.dataset()
    assert np.all(np.isfinite(ds["attitude"].values))


def test_a_later_stage_change_does_not_redo_the_modal_solve(tmp_path, solves, monkeypatch):
    first = run_scenario(_study(tmp_path))
    assert len(solves) == 1
    assert not any(_origins(first).values())

    loads = []
    from flexsat.structures.modal_model import ModalModel

    load = ModalModel.load.__func__

    def counted_load(cls, path):
        loads.append(Path(path).parent.name.split("-")[0])
        return load(cls, path)

    monkeypatch.setattr(ModalModel, "load", classmethod(counted_load))
    again = run_scenario(_study(tmp_path))
    assert len(solves) == 1 and all(_origins(again).values())
    # the modes are in the cache: the model is not even read, its record is its summary
    assert loads == ["modes"]
    assert again.records[0].summary == first.records[0].summary
    for fresh, cached in zip(first.results, again.results):
        # a run read back is the run computed
        assert fresh.dataset.identical(cached.dataset)

    changed = run_scenario(_study(tmp_path, **{"laws.1.weights.torque": 1e-3}))
    assert len(solves) == 1  # no modal solve: the model stage is read from the cache
    assert _origins(changed) == {
        "model": True,
        "modes": True,
        "placement": True,
        "law 'PD'": True,
        "law 'LQR'": False,
        "run 'PD run'": True,
        "run 'LQR run'": False,
    }
    assert not np.array_equal(changed.laws["LQR"].arrays["K"], first.laws["LQR"].arrays["K"])
    np.testing.assert_array_equal(changed.laws["PD"].arrays["Kp"], first.laws["PD"].arrays["Kp"])


def test_a_model_change_redoes_every_stage(tmp_path, solves):
    run_scenario(_study(tmp_path))
    changed = run_scenario(_study(tmp_path, **{"model.options": {"tube_wall": "1.7 mm"}}))
    assert len(solves) == 2
    assert not any(_origins(changed).values())


def test_a_modes_change_keeps_the_model_only(tmp_path, solves):
    run_scenario(_study(tmp_path))
    changed = run_scenario(_study(tmp_path, **{"modes.damping": 0.01}))
    assert len(solves) == 1
    origins = _origins(changed)
    assert origins.pop("model") is True and not any(origins.values())


def test_a_model_file_gives_the_case_modes_and_its_content_is_fingerprinted(tmp_path):
    from flexsat.cases.eps import eps

    path = tmp_path / "eps.nc"
    eps().modal_model(8).save(path)
    from_case = run_scenario(_study(tmp_path / "a"))
    data = copy.deepcopy(SMALL)
    data["model"] = {"file": str(path)}
    data["cache"] = str(tmp_path / "b")
    scenario = load_scenario(yaml.safe_dump(data))
    from_file = run_scenario(scenario)
    np.testing.assert_array_equal(from_file.modes.frequencies, from_case.modes.frequencies)
    assert from_file.placement.selection == from_case.placement.selection
    before = stage_plan(scenario)["model"].key
    eps(damping=0.01).modal_model(8).save(path)  # same name, other content
    assert stage_plan(scenario)["model"].key != before


def test_an_inline_fe_model_is_the_simulation_scenarios_model(tmp_path):
    """``model: {fe: ...}`` of a design study is the simulation kind's section: the user's own
    spacecraft (examples/own_spacecraft_slew.yaml) gets the same modal model, bit for bit,
    and flows through placement, design and a run."""
    from flexsat.scenarios.models import ModelSection

    own = yaml.safe_load((EXAMPLES / "own_spacecraft_slew.yaml").read_text())["model"]
    data = copy.deepcopy(SMALL)
    data["model"] = own
    data["cache"] = str(tmp_path / "cache")
    data["placement"] = {
        "torque_node": 0,
        "candidates": {"nodes": [103, 105, 203, 205], "axes": ["y", "z"]},
        "number": 2,
        "outputs": [105],
    }
    data["laws"] = data["laws"][:1]  # the PD (the LQR's weights are the EPS's, 1000 kg·m²)
    data["runs"] = data["runs"][:1]
    result = run_scenario(load_scenario(yaml.safe_dump(data, sort_keys=False)))
    direct = ModelSection.model_validate(own).modal_model(tmp_path)
    kept = result.modes.frequencies
    kept = kept[kept > RIGID_FREQUENCY]
    assert kept.size == 6  # modes: {n_modes: 6}
    np.testing.assert_array_equal(kept, direct.elastic().frequencies[:6])
    assert len(result.placement.selection) == 2


def test_pd_gains_give_the_rigid_bandwidth_and_damping(tmp_path):
    result = run_scenario(_study(tmp_path))
    plant = _plant(result)
    kp, kd = pd_gains(plant, 0.3, 0.7)
    for J, p, d in zip(np.diag(plant.inertia), kp, kd):
        # J θ'' + K_d θ' + K_p θ / 2 = 0 (β_v = θ/2): poles at ω_c with damping ζ
        poles = np.roots([J, d, p / 2])
        np.testing.assert_allclose(np.abs(poles), 0.3, rtol=1e-12)
        np.testing.assert_allclose(-poles.real / np.abs(poles), 0.7, rtol=1e-12)


def _plant(result):
    from flexsat.scenarios.design_placement import spacecraft

    return spacecraft(result.modes, result.scenario.placement, result.placement)


def test_the_lqr_gain_is_python_controls(tmp_path):
    result = run_scenario(_study(tmp_path))
    plant = _plant(result)
    A, B = design_state(plant.reduced(4))
    weights = result.scenario.laws[1].weights
    q = np.r_[[weights.attitude] * 3, [weights.rate] * 3, [weights.modes] * 8]
    r = np.r_[[weights.torque] * 3, [weights.force] * 2]
    K, _, _ = ct.lqr(A, B, np.diag(q), np.diag(r))
    got = result.laws["LQR"].arrays["K"]
    np.testing.assert_allclose(got, K, rtol=1e-6, atol=1e-9 * np.abs(K).max())


def test_the_lqr_law_applies_its_gain_to_the_design_modes_only(tmp_path):
    result = run_scenario(_study(tmp_path))
    plant = _plant(result)
    spec = result.scenario.laws[1]
    K = result.laws["LQR"].arrays["K"]
    law = law_controller(spec, result.laws["LQR"].arrays, plant, 0.1)
    rng = np.random.default_rng(3)
    x = rng.standard_normal(plant.nx)
    y = {c.name: plant.output(c.name, x[None]) for c in plant.outputs}
    u, _ = law(0.0, y, law.initial_state(1))
    n, nd = plant.n_modes, 4
    design_x = np.r_[x[1:7], x[7 : 7 + nd], x[7 + n : 7 + n + nd]]
    got = np.concatenate([np.ravel(u[c.name]) for c in plant.inputs])
    np.testing.assert_allclose(got, -K @ design_x, rtol=1e-12, atol=1e-12 * np.abs(K).max())


def test_the_pd_design_matrix_is_the_quaternion_pd_to_first_order(tmp_path):
    from flexsat.control import QuaternionPD
    from flexsat.dynamics.attitude import dcm_to_quaternion, euler123_to_dcm

    result = run_scenario(_study(tmp_path))
    arrays = result.laws["PD"].arrays
    law = QuaternionPD(Kp=arrays["Kp"], Kd=arrays["Kd"])
    angles, w = np.array([1e-6, -2e-6, 3e-6]), np.array([1e-4, 2e-4, -1e-4])
    beta = dcm_to_quaternion(euler123_to_dcm(angles))
    linear = -(arrays["Kp"] * beta[1:] + arrays["Kd"] * w)
    np.testing.assert_allclose(law.torque(beta, w), linear, rtol=1e-12)


def test_ppf_stage_designs_a_stable_bank_and_refuses_an_unstable_one(tmp_path):
    ppf = {
        "label": "PPF",
        "type": "ppf",
        "tuned_modes": 2,
        "gains": 20,
        "attitude": {"bandwidth": "0.3 rad/s"},
    }
    data = copy.deepcopy(SMALL)
    data["cache"] = str(tmp_path)
    data["laws"].append(ppf)
    data["runs"].append({"label": "PPF run", "law": "PPF"})
    result = run_scenario(load_scenario(yaml.safe_dump(data)))
    arrays = result.laws["PPF"].arrays
    assert arrays["gains"].shape == (4,)  # 2 actuators × 2 tuned modes
    np.testing.assert_array_equal(
        arrays["omega_f"], np.tile(result.modes.elastic().frequencies[:2], (2, 1))
    )
    assert arrays["stiffness_eigenvalues"][0] > 0
    data["laws"][-1]["gains"] = 1e6
    with pytest.raises(ScenarioError, match=r"laws\['PPF'\]\.gains: the PPF loop is unstable"):
        run_scenario(load_scenario(yaml.safe_dump(data)))


def test_kim_junkins_placement_is_the_search_result(tmp_path):
    from flexsat.analysis.placement import actuator_candidates, exhaustive, kim_junkins_score

    result = run_scenario(
        _study(
            tmp_path,
            **{"placement.criterion": "kim_junkins", "placement.search": "exhaustive"},
        )
    )
    elastic = result.modes.elastic()
    vectors = actuator_candidates(elastic, [69, 66, 60], ["x", "y"])
    rows = elastic.displacement_output(69, ["x", "y", "z"]).T
    best = exhaustive(list(vectors), 2, kim_junkins_score(elastic, vectors, Cq=rows))
    assert result.placement.selection == best.selection
    assert result.placement.criterion_value == pytest.approx(best.score, rel=1e-12)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"runs.0.law": "LQG"}, r"runs\['PD run'\]\.law: 'LQG' is not a law of the study"),
        ({"placement.number": 7}, r"placement\.number: at most the 6 candidates"),
        ({"placement.candidates.nodes": [69, 69]}, r"placement\.candidates\.nodes: must be dist"),
        ({"model.file": "x.nc"}, r"model\.file: applies to a model of your own, not to a case"),
        ({"model": {}}, r"model: give exactly one of file"),
        ({"model": {"file": "x.nc", "n_modes": 8}}, r"model\.options: .* apply to a case"),
        ({"model.case": "tamu"}, r"model\.case: 'tamu' has no free-free finite-element model"),
        ({"laws.0.bandwidth": "-1 rad/s"}, r"laws\['PD'\]\.bandwidth: must be > 0"),
        ({"laws.0.gains": 1}, r"laws\['PD'\]\.gains: not a field of a pd law"),
        ({"laws.1.weights": None}, r"laws\['LQR'\]\.weights: required by a lqr law"),
    ],
)
def test_document_mistakes_are_named_by_their_field(tmp_path, change, message):
    with pytest.raises(ScenarioError, match=message):
        _study(tmp_path, **change)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"placement.candidates.nodes": [69, 999]}, r"placement\.candidates\.nodes: node 999"),
        ({"modes.n_modes": 9}, r"modes\.n_modes: at most the model's 8 elastic modes"),
        ({"modes.damping": [0.1, 0.2]}, r"modes\.damping: one ratio or one per kept"),
        ({"laws.1.modes": 7}, r"laws\['LQR'\]\.modes: at most the 6 elastic modes"),
        ({"laws.1.weights.torque": 1e-20}, r"laws\['LQR'\]\.weights\.(torque|attitude|rate)"),
        ({"model.options": {"tube_wall": "1 m"}}, r"model\.options\.tube_wall: must be <="),
        ({"runs.0.initial": {"euler123": [1, 2]}}, r"runs\['PD run'\]\.initial"),
        ({"model.options": {"damping": float("nan")}}, r"model\.options\.damping: must be"),
        ({"laws.1.weights.rate": float("nan")}, r"laws\['LQR'\]\.weights\.rate"),
    ],
)
def test_stage_refusals_are_named_by_their_field(tmp_path, change, message):
    with pytest.raises(ScenarioError, match=message):
        run_scenario(_study(tmp_path, **change))


def test_a_missing_model_file_is_named(tmp_path):
    data = copy.deepcopy(SMALL)
    data["model"] = {"file": "missing.nc"}
    with pytest.raises(ScenarioError, match=r"model\.file: no such file"):
        run_scenario(load_scenario(yaml.safe_dump(data)))


SLEW_LAW = {
    "label": "slew",
    "type": "perturbation",
    "maneuver": {
        "target": {"euler123": ["0.2 rad", "0.1 rad", "-0.1 rad"]},
        "duration": "10 s",
        "break_frequency": "2.5 rad/s",
    },
    "modes": 3,
    "linearization_points": 5,
    "break_frequency": "2.5 rad/s",
    "weights": {"attitude": 1000, "rate": 1000, "modes": 1, "torque": 50, "force": 1e-3},
}


def _slew_study(tmp_path: Path, **changes):
    data = copy.deepcopy(SMALL)
    data["cache"] = str(tmp_path / "cache")
    data["laws"] = [copy.deepcopy(SLEW_LAW)]
    data["runs"] = [{"label": "slew run", "law": "slew"}]
    data["simulation"] = {"duration": "12.5 s", "control_rate": "20 Hz"}
    for key, value in changes.items():
        data[key] = value
    return load_scenario(yaml.safe_dump(data, sort_keys=False))


def test_a_perturbation_law_rebuilt_from_its_tables_is_the_designed_law(tmp_path):
    from flexsat.control import PerturbationFeedback, perturbation_design
    from flexsat.design.slew_weights import SlewWeights
    from flexsat.maneuvers import three_axis_slew
    from flexsat.scenarios.simulation import target_quaternion

    study = _slew_study(tmp_path)
    result = run_scenario(study)
    plant = _plant(result)
    spec = study.laws[0]
    nominal = three_axis_slew(
        plant.inertia, target_quaternion(spec.maneuver.target), 10.0, 2.5, 0.0, Q=np.zeros((3, 3))
    )
    forces = [c.name for c in plant.inputs if c.name != "torque"]
    q, d = SlewWeights(**spec.weights.model_dump()).diagonals(3, len(forces))
    design = perturbation_design(
        plant.reduced(3), nominal, np.diag(q), np.diag(d), 2.5, 0.0, 5, forces=forces
    )
    original = design.controller(0.05, "constant", plant=plant)
    stored = result.laws["slew"].arrays  # read back from the stage's netCDF
    rebuilt = law_controller(spec, stored, plant, 0.05)
    assert isinstance(rebuilt, PerturbationFeedback) and rebuilt.design is None
    rng = np.random.default_rng(5)
    state_a, state_b = original.initial_state(2), rebuilt.initial_state(2)
    for k in range(0, 260, 7):
        x = rng.standard_normal((2, plant.nx)) * 0.1
        x[:, :4] /= np.linalg.norm(x[:, :4], axis=1, keepdims=True)
        y = {c.name: plant.output(c.name, x) for c in plant.outputs}
        u_a, state_a = original(k * 0.05, y, state_a)
        u_b, state_b = rebuilt(k * 0.05, y, state_b)
        assert u_a.keys() == u_b.keys()
        for name in u_a:
            np.testing.assert_array_equal(u_b[name], u_a[name])
    # the slew reaches its target: within 3 % of the angle at 1.25 T (the EPS study's goal)
    angle = 2 * np.arccos(target_quaternion(spec.maneuver.target)[0])
    assert result.metrics_records()[0]["final_attitude_error_rad"] < 0.03 * angle


def test_a_perturbation_law_depends_on_the_control_rate(tmp_path):
    slow = stage_plan(_slew_study(tmp_path))
    faster = {"duration": "12.5 s", "control_rate": "40 Hz"}
    fast = stage_plan(_slew_study(tmp_path, simulation=faster))
    assert slow["model"].key == fast["model"].key
    assert slow["placement"].key == fast["placement"].key
    assert slow["laws['slew']"].key != fast["laws['slew']"].key


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (
            {"runs": [{"label": "r", "law": "slew", "initial": {"euler123": [0.1, 0, 0]}}]},
            r"runs\['r'\]\.initial: law 'slew' flies its maneuver from rest",
        ),
        (
            {"simulation": {"duration": "3 s", "control_rate": "20 Hz"}},
            r"simulation\.duration: must cover the maneuver of law 'slew' \(10 s\)",
        ),
        (
            {"simulation": {"duration": "12.5 s", "control_rate": "0.5 Hz"}},
            r"laws\['slew'\]\.maneuver\.break_frequency: must be at most the control's Nyquist",
        ),
    ],
)
def test_perturbation_mistakes_are_named(tmp_path, change, message):
    with pytest.raises(ScenarioError, match=message):
        _slew_study(tmp_path, **change)


@st.composite
def _mutated_studies(draw) -> dict:
    data = copy.deepcopy(SMALL)
    for _ in range(draw(st.integers(1, 2))):
        paths = key_paths(data)
        path = draw(st.sampled_from(paths))
        action = draw(st.sampled_from(["set", "set", "delete"]))
        if action == "set":
            set_at(data, path, draw(VALUES))
        else:
            delete_at(data, path)
    return data


@settings(
    max_examples=60,
    deadline=None,
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)
@given(_mutated_studies())
def test_a_mutated_study_is_refused_by_name_or_runs_finite(tmp_path_factory, data):
    """Any mutation of a small study ends in a ScenarioError naming its field, a
    SimulationDiverged, or finite run metrics; no other exception escapes a stage."""
    data["cache"] = str(tmp_path_factory.getbasetemp() / "mutations-cache")
    try:
        result = run_scenario(load_scenario(yaml.safe_dump(data, sort_keys=False)))
    except ScenarioError as exc:
        assert all(":" in problem for problem in exc.problems)
        return
    except SimulationDiverged:
        return
    for record in result.metrics_records():
        assert all(np.isfinite(v) for k, v in record.items() if k != "run")


def test_a_file_that_is_no_modal_model_is_named(tmp_path):
    (tmp_path / "junk.nc").write_bytes(b"not a netCDF file")
    data = copy.deepcopy(SMALL)
    data["model"] = {"file": "junk.nc"}
    data["cache"] = str(tmp_path / "cache")
    path = tmp_path / "study.yaml"
    path.write_text(yaml.safe_dump(data))
    with pytest.raises(ScenarioError, match=r"model\.file: cannot read junk\.nc as a netcdf"):
        run_scenario(load_scenario(path))


def test_h2_placement_is_the_eps_studys_ranking(tmp_path):
    # the same candidates, disturbance and outputs as the EPS placement study of
    # flexsat.cases.eps_placement: the stage's choice is that ranking's top 5
    from flexsat.cases.eps_placement import (
        EPS_CANDIDATE_NODES,
        EPS_DISTURBANCE_NODE,
        EPS_OUTPUT_NODES,
        eps_h2_ranking,
    )

    data = copy.deepcopy(SMALL)
    data["cache"] = str(tmp_path)
    data["model"] = {"case": "eps", "n_modes": 20}
    data["modes"] = {}
    data["placement"] = {
        "torque_node": 95,
        "candidates": {"nodes": list(EPS_CANDIDATE_NODES)},
        "number": 5,
        "disturbance_node": EPS_DISTURBANCE_NODE,
        "outputs": list(EPS_OUTPUT_NODES),
    }
    data["laws"], data["runs"] = data["laws"][:1], data["runs"][:1]
    result = run_scenario(load_scenario(yaml.safe_dump(data)))
    ranking = eps_h2_ranking(n_modes=20)
    assert result.placement.selection == ranking.top(5)
    assert result.placement.criterion_value == pytest.approx(
        sum(ranking.scores[k] for k in ranking.top(5)), rel=1e-12
    )
