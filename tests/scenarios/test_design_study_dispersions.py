"""The dispersions stage of a design study: the laws designed on the nominal fly on the
dispersed truth; the cases run through the batch machinery (independent of the chunking,
resumable, each equal to the case computed alone); a requirement change re-reads the store;
mistakes are named before any case runs. The example runs here with 6 cases (its 200 cut down,
an override of ``dispersions.cases``)."""

from __future__ import annotations

import json
import pickle
import re
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
import yaml

import flexsat.structures.fem as fem
from flexsat.control import QuaternionPD
from flexsat.design.batch_runner import BatchInterrupted, open_results, run_batch
from flexsat.report import write_report
from flexsat.scenarios import ScenarioError, load_scenario, run_scenario
from flexsat.scenarios.design_dispersions import (
    case_builder,
    dispersed_case,
    metric_names,
    sample_table,
)
from flexsat.scenarios.design_placement import spacecraft
from flexsat.scenarios.design_study import kept_modes, modal_model_of, run_metrics, stage_plan
from flexsat.sim import SimConfig, simulate

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "own_spacecraft_design_study.yaml"
#: the example's nominal values of its dispersed parameters, SI
NOMINAL = {
    "model.fe.materials.aluminium.E": 70e9,
    "model.fe.masses[1].mass": 1.0,
    "model.fe.masses[2].mass": 1.0,
    "modes.damping": 0.005,
}


def _data(tmp_path: Path, cases: int = 6, **dispersions) -> dict:
    """The example, cut down: ``cases`` cases, 6 s runs (the tests compare cases, they need no
    settled slew), its cache in ``tmp_path``."""
    data = yaml.safe_load(EXAMPLE.read_text(encoding="utf-8"))
    data["cache"] = str(tmp_path / "cache")
    data["simulation"]["duration"] = "6 s"
    data["dispersions"]["cases"] = cases
    data["dispersions"]["execution"] = {"chunk_size": 4}
    data["dispersions"].update(dispersions)
    return data


def _load(data: dict):
    return load_scenario(yaml.safe_dump(data, sort_keys=False))


def _nominal(scenario):
    """The nominal study's result without its dispersions."""
    data = yaml.safe_load(scenario.yaml_text)
    data.pop("dispersions")
    return run_scenario(_load(data))


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


def test_the_example_is_designed_and_monte_carlod_from_one_file(tmp_path):
    """The example (6 of its 200 cases) runs every stage and reports the dispersions: the
    semantics, the probabilities with their intervals and the percentiles."""
    data = yaml.safe_load(EXAMPLE.read_text(encoding="utf-8"))
    assert data["dispersions"]["cases"] == 200
    data["dispersions"]["cases"] = 6  # the override the module docstring states
    data["cache"] = str(tmp_path / "cache")
    scenario = _load(data)
    result = run_scenario(scenario)
    stages = [r.stage.name for r in result.records]
    assert stages == ["model", "modes", "placement", "law", "run", "dispersions"]
    d = result.dispersions
    assert set(d.metrics) == {
        "final_attitude_error_rad",
        "peak_torque_N_m",
        "peak_displacement_m",
        "final_displacement_m",
        "peak_force_N",
    }
    assert all(v.shape == (6,) and np.all(np.isfinite(v)) for v in d.metrics.values())
    for r in d.summary["requirements"]:  # Clopper-Pearson bounds hold the estimate
        assert r["n"] == 6 and r["low"] <= r["probability"] <= r["high"]
        met = d.metrics[r["metric"]] <= r["threshold"]
        assert r["successes"] == int(met.sum())
    out = tmp_path / "report"
    write_report(result, out)
    page = (out / "index.html").read_text(encoding="utf-8")
    assert "<h2>Dispersions</h2>" in page and "dispersed truth" in page
    assert "Requirements" in page and "final_attitude_error_rad" in page
    assert (out / "convergence.png").is_file()
    assert (out / "distribution_peak_displacement_m.png").is_file()
    saved = json.loads((out / "dispersions.json").read_text(encoding="utf-8"))
    assert saved["cases"] == 6 and saved["runs"] == ["PD return"]
    assert [r["probability"] for r in saved["requirements"]] == [
        r["probability"] for r in d.summary["requirements"]
    ]
    stored = xr.open_zarr(out / "dispersions.zarr", consolidated=False)
    peaks = stored["metric_peak_displacement_m"].values
    np.testing.assert_array_equal(peaks, d.metrics["peak_displacement_m"])


def test_the_laws_are_designed_on_the_nominal_and_flown_on_the_truth(tmp_path):
    """A case with 30 % heavier tips: its metrics are those of the nominal PD gains on the
    spacecraft rebuilt from its values (computed here by hand), not those of a PD redesigned
    for it (the case's document run as a study of its own)."""
    scenario = _load(_data(tmp_path))
    nominal = _nominal(scenario)
    build = case_builder(
        scenario, stage_plan(scenario)["dispersions"], nominal.placement, nominal.laws
    )
    values = {**NOMINAL, "model.fe.masses[1].mass": 1.3, "model.fe.masses[2].mass": 1.3}
    metrics = build.case(values, 0, 0)

    case = build.cases.scenario(values, 0)
    truth = spacecraft(
        kept_modes(modal_model_of(case.model, case.folder), case.modes),
        case.placement,
        nominal.placement,
    )
    arrays = nominal.laws["PD"].arrays
    config = SimConfig(duration=case.simulation.duration, control_rate=case.simulation.control_rate)
    x0 = truth.state_from(euler123=case.runs[0].initial.euler123)
    by_hand = run_metrics(
        simulate(
            truth,
            QuaternionPD(Kp=arrays["Kp"], Kd=arrays["Kd"]),
            config,
            n_cases=1,
            initial_state=x0,
        )
    )
    for name, value in by_hand.items():
        assert metrics[name] == pytest.approx(value, rel=1e-12, abs=1e-15), name

    redesigned = run_scenario(case)  # the case alone, as a study: its PD designed on it
    assert not np.allclose(redesigned.laws["PD"].arrays["Kp"], arrays["Kp"], rtol=1e-6)
    assert redesigned.metrics_records()[0]["final_attitude_error_rad"] != pytest.approx(
        metrics["final_attitude_error_rad"], rel=1e-9
    )


def test_a_case_at_the_nominal_values_is_the_nominal_run(tmp_path):
    """The truth at the nominal values is the nominal spacecraft: the case's metrics are the
    nominal run's (the same modal solve and simulation, to round-off)."""
    scenario = _load(_data(tmp_path))
    nominal = _nominal(scenario)
    build = case_builder(
        scenario, stage_plan(scenario)["dispersions"], nominal.placement, nominal.laws
    )
    metrics = build.case(NOMINAL, 0, 0)
    (record,) = nominal.metrics_records()
    for name, value in metrics.items():
        assert value == pytest.approx(record[name], rel=1e-12, abs=1e-15), name


def test_cases_are_independent_of_chunking_and_equal_the_case_alone(tmp_path):
    """The store of chunks of 1 equals that of chunks of 7 and of 1,000 bit for bit, and each
    case equals :func:`dispersed_case` (its values sampled alone, its seed its own)."""
    scenario = _load(_data(tmp_path, cases=8))
    nominal = _nominal(scenario)
    stage = stage_plan(scenario)["dispersions"]
    build = case_builder(scenario, stage, nominal.placement, nominal.laws)
    table = sample_table(scenario.dispersions, {p.path: p.unit for p in build.cases.parameters})
    stores = {}
    for chunk in (1, 7, 1000):
        store = tmp_path / f"chunks-{chunk}.zarr"
        run_batch(build, table.values, store, extract=dict, chunk_size=chunk, setup_text=stage.key)
        ds = open_results(store)
        stores[chunk] = {k: ds[k].values for k in map(str, ds.data_vars) if k.startswith("metric_")}
    for chunk in (7, 1000):
        for name, values in stores[1].items():
            np.testing.assert_array_equal(stores[chunk][name], values, err_msg=name)
    # what process workers receive: the builder pickled, its chunk the same numbers
    shipped = pickle.loads(pickle.dumps(build))
    chunk = shipped.run_chunk(dict, {k: v[3:5] for k, v in table.values.items()}, 3, 0)
    for name, values in chunk.items():
        if name.startswith("metric_"):
            np.testing.assert_array_equal(values, stores[1][name][3:5], err_msg=name)
    for index in range(8):
        alone = dispersed_case(build, scenario.dispersions, index)
        for name, value in alone.items():
            assert stores[7][f"metric_{name}"][index] == value, (index, name)


def test_a_requirement_change_rereads_the_store_and_an_interrupted_run_resumes(tmp_path, solves):
    """Interrupted after its first chunk, the stage resumes from the store; then a changed
    threshold runs no case and no modal solve (the stage from the cache), only the statistics."""
    data = _data(tmp_path, cases=8)

    def stop(message: str) -> None:
        if message.startswith("dispersions: 4/8"):
            raise KeyboardInterrupt

    with pytest.raises(BatchInterrupted):
        run_scenario(_load(data), progress=stop)
    resumed = run_scenario(_load(data))
    assert (resumed.dispersions.chunks_skipped, resumed.dispersions.chunks_run) == (1, 1)
    fresh = run_scenario(_load(_data(tmp_path / "other", cases=8)))
    for name, values in fresh.dispersions.metrics.items():
        np.testing.assert_array_equal(resumed.dispersions.metrics[name], values)

    data["dispersions"]["requirements"]["peak_displacement_m"] = {"max": "0.2 mm"}
    before = len(solves)
    changed = run_scenario(_load(data))
    assert len(solves) == before  # no case, and the nominal stages from the cache
    assert changed.dispersions.chunks_run == 0
    assert changed.records[-1].cached
    (req,) = [
        r
        for r in changed.dispersions.summary["requirements"]
        if r["metric"] == "peak_displacement_m"
    ]
    assert req["threshold"] == pytest.approx(2e-4)
    assert req["successes"] == int(
        (changed.dispersions.metrics["peak_displacement_m"] <= 2e-4).sum()
    )


def test_a_runs_initial_state_and_the_duration_are_dispersed_into_the_case(tmp_path):
    """Paths into a run's initial state and the simulation reach the case's study, each value
    written in the unit its entry is given in."""
    data = _data(tmp_path)
    data["dispersions"]["parameters"] = {
        "runs['PD return'].initial.euler123[2]": {
            "distribution": "normal",
            "mean": "30 deg",
            "sd": "2 deg",
        },
        "simulation.duration": {"distribution": "uniform", "low": "4 s", "high": "5 s"},
    }
    scenario = _load(data)
    nominal = _nominal(scenario)
    build = case_builder(
        scenario, stage_plan(scenario)["dispersions"], nominal.placement, nominal.laws
    )
    units = {p.path: p.unit for p in build.cases.parameters}
    assert units == {"runs['PD return'].initial.euler123[2]": "rad", "simulation.duration": "s"}
    case = build.cases.scenario(
        {"runs['PD return'].initial.euler123[2]": 0.6, "simulation.duration": 4.5}, 0
    )
    assert case.simulation.duration == 4.5
    angle = case.runs[0].initial.euler123[2]
    assert angle.endswith(" deg") and float(angle.split()[0]) == pytest.approx(np.degrees(0.6))
    # the laws and placement in the case are the nominal ones
    assert case.laws == scenario.laws and case.placement == scenario.placement


def test_with_several_runs_each_metric_is_named_by_its_run(tmp_path):
    """Two runs flown: every metric under ``runs['label'].name`` (those
    :func:`metric_names` announces, which requirements are checked against), each run's the
    metrics of that run alone."""
    data = _data(tmp_path, cases=2)
    data["runs"].append({"label": "small", "law": "PD", "initial": {"euler123": [0, 0, "0.1 rad"]}})
    data["dispersions"]["requirements"] = {"runs['small'].peak_displacement_m": {"max": "1 mm"}}
    scenario = _load(data)
    result = run_scenario(scenario)
    names = metric_names(["PD return", "small"], forces=True)
    assert sorted(result.dispersions.metrics) == sorted(names)
    (requirement,) = result.dispersions.summary["requirements"]
    assert requirement["metric"] == "runs['small'].peak_displacement_m"
    data["dispersions"]["runs"] = ["small"]  # one run: its metrics under their own names
    with pytest.raises(ScenarioError, match="unknown metric"):
        _load(data)
    data["dispersions"]["requirements"] = {"peak_displacement_m": {"max": "1 mm"}}
    alone = run_scenario(_load(data)).dispersions.metrics["peak_displacement_m"]
    both = result.dispersions.metrics["runs['small'].peak_displacement_m"]
    np.testing.assert_array_equal(alone, both)


def test_without_a_model_dispersion_the_cases_reuse_the_nominal_solve(tmp_path, monkeypatch):
    """Dispersing the damping and the duration only: the model section is made a ModalModel
    once in all (the nominal's; a built-in case has no other cache), and each case's metrics
    are those of the case making its own."""
    import flexsat.scenarios.design_study as design_study

    calls = []
    original = design_study.modal_model_of

    def counted(*args, **kwargs):
        calls.append(1)
        return original(*args, **kwargs)

    monkeypatch.setattr(design_study, "modal_model_of", counted)
    data = _data(tmp_path, cases=4)
    data["dispersions"]["parameters"] = {
        "modes.damping": {"distribution": "lognormal", "median": 0.005, "gsd": 1.5},
        "simulation.duration": {"distribution": "uniform", "low": "4 s", "high": "6 s"},
    }
    scenario = _load(data)
    result = run_scenario(scenario)
    assert len(calls) == 1
    own = case_builder(
        scenario, stage_plan(scenario)["dispersions"], result.placement, result.laws, None
    )
    assert own.model is None
    for index in range(4):
        alone = dispersed_case(own, scenario.dispersions, index)
        for name, value in alone.items():
            assert result.dispersions.metrics[name][index] == value, (index, name)
    assert len(calls) == 5  # the builder without the nominal model made each case's


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (
            {
                "parameters": {
                    "laws[0].bandwidth": {"distribution": "normal", "mean": 0.4, "sd": 0.01}
                }
            },
            "parameters.laws[0].bandwidth: a dispersion varies the truth",
        ),
        (
            {
                "parameters": {
                    "simulation.control_rate": {
                        "distribution": "uniform",
                        "low": "19 Hz",
                        "high": "21 Hz",
                    }
                }
            },
            "not a dispersion: the laws are designed and sampled at the nominal control rate",
        ),
        ({"parameters": {"modes.damping": {"values": [0.004, 0.006]}}}, "not grid axes"),
        ({"runs": ["nope"]}, "dispersions.runs: 'nope' is not a run of the study"),
        (
            {"requirements": {"settling_time_s": {"max": "8 s"}}},
            "dispersions.requirements.settling_time_s: unknown metric",
        ),
        (
            {"requirements": {"peak_displacement_m": {"max": "8 s"}}},
            "dispersions.requirements.peak_displacement_m",
        ),
    ],
)
def test_section_mistakes_are_named(tmp_path, change, message):
    data = _data(tmp_path)
    data["dispersions"].update(change)
    with pytest.raises(ScenarioError, match=re.escape(message)):
        _load(data)


def test_a_mistyped_path_and_an_unphysical_tail_are_refused_before_any_case_runs(tmp_path, solves):
    data = _data(tmp_path)
    data["dispersions"]["parameters"] = {
        "model.fe.materials.aluminum.E": {"distribution": "normal", "mean": "70 GPa", "sd": "1 GPa"}
    }
    with pytest.raises(ScenarioError, match="aluminium"):
        run_scenario(_load(data))
    data["dispersions"]["parameters"] = {
        "model.fe.materials.aluminium.E": {
            "distribution": "normal",
            "mean": "70 GPa",
            "sd": "60 GPa",
        }
    }
    data["dispersions"]["cases"] = 40
    scenario = _load(data)
    with pytest.raises(
        ScenarioError, match=r"parameters\.model\.fe\.materials\.aluminium\.E: case \d+"
    ) as info:
        run_scenario(scenario)
    assert "E" in str(info.value)
    key = stage_plan(scenario)["dispersions"].key
    # refused before any case ran: no store was made
    assert not (Path(scenario.cache_folder) / f"dispersions-{key[:20]}.zarr").exists()
