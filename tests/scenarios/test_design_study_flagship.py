"""The flagship design study (issue 22), ``examples/eps_design_study.yaml``, cut down to a few
cases: the EPS from its finite-element model through placement, the optimal slew with its
scheduled perturbation feedback, a run with sensor noise and a random torque, and dispersed
cases flown in compiled batches. Its results are checked against the same cases flown alone
(the batch path and the engine's own path for one plant), its stages against the cache."""

from __future__ import annotations

import pickle
from pathlib import Path

import numpy as np
import pytest
import yaml

from flexsat.design.batch_runner import open_results, run_batch
from flexsat.scenarios import load_scenario, run_scenario
from flexsat.scenarios.design_dispersions import case_builder, dispersed_case, sample_table
from flexsat.scenarios.design_flight import fly
from flexsat.scenarios.design_study import stage_plan

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "eps_design_study.yaml"
CASES = 10


def _data(cache: Path, cases: int = CASES) -> dict:
    data = yaml.safe_load(EXAMPLE.read_text(encoding="utf-8"))
    data["cache"] = str(cache)
    data["dispersions"]["cases"] = cases
    data["dispersions"]["execution"] = {"chunk_size": 4}  # in-process: no worker processes
    return data


def _load(data: dict):
    return load_scenario(yaml.safe_dump(data, sort_keys=False))


@pytest.fixture(scope="module")
def flagship(tmp_path_factory):
    """The cut-down flagship run once from an empty cache, and its cache folder."""
    cache = tmp_path_factory.mktemp("flagship") / "cache"
    return run_scenario(_load(_data(cache))), cache


def test_the_example_is_the_issue_s_flagship():
    """10,000 cases of the EPS slew under the perturbation feedback, dispersed in the truth
    only (each case a lane of a compiled batch), with sensor noise and a random torque."""
    scenario = load_scenario(EXAMPLE.read_text(encoding="utf-8"))
    assert scenario.model.case == "eps"
    assert scenario.dispersions.cases == 10_000
    assert [law.type for law in scenario.laws] == ["perturbation"]
    assert all(p.startswith("truth.") for p in scenario.dispersions.parameters)
    assert scenario.sensors and scenario.disturbances["torque"].random is not None


def test_every_stage_runs_and_the_metrics_are_finite(flagship):
    result, _ = flagship
    assert [r.cached for r in result.records] == [False] * len(result.records)
    dispersed = result.dispersions
    assert dispersed.chunks_run == 3 and dispersed.chunks_skipped == 0
    for name, values in dispersed.metrics.items():
        assert values.shape == (CASES,) and np.isfinite(values).all(), name
    # the dispersions change the flight: the cases differ from one another
    assert np.ptp(dispersed.metrics["peak_displacement_m"]) > 0
    for r in dispersed.summary["requirements"]:
        assert 0 <= r["low"] <= r["probability"] <= r["high"] <= 1
        assert r["n"] == CASES


def test_a_second_run_reads_every_stage_from_the_cache(flagship, monkeypatch):
    """Nothing is recomputed: no modal solve, no law design, no simulation, no case."""
    import flexsat.scenarios.design_study as design_study

    result, cache = flagship
    monkeypatch.setattr(design_study, "modal_model_of", _refuse)
    monkeypatch.setattr(design_study, "design_law", _refuse)
    again = run_scenario(_load(_data(cache)))
    assert all(r.cached for r in again.records)
    assert again.dispersions.chunks_run == 0
    for name, values in result.dispersions.metrics.items():
        np.testing.assert_array_equal(again.dispersions.metrics[name], values)


def _refuse(*args, **kwargs):
    raise AssertionError("a cached stage was recomputed")


def _builder(result):
    scenario = result.scenario
    return scenario, case_builder(
        scenario, stage_plan(scenario)["dispersions"], result.placement, result.laws
    )


def test_cases_equal_the_case_alone_in_any_chunking(flagship, tmp_path):
    """The store in chunks of 1, 7 and 1,000 and each case flown alone (its values sampled
    alone, its own seed) are the same numbers bit for bit: a case is one lane of the kernel,
    its noise from its own seed."""
    result, _ = flagship
    scenario, build = _builder(result)
    assert build.direct
    table = sample_table(scenario.dispersions, {p.path: p.unit for p in build.cases.parameters})
    stored = result.dispersions.metrics
    for chunk in (1, 7, 1000):
        store = tmp_path / f"chunks-{chunk}.zarr"
        run_batch(
            build,
            table.values,
            store,
            extract=dict,
            base_seed=scenario.dispersions.seed,
            chunk_size=chunk,
            setup_text="x",
        )
        ds = open_results(store)
        for name, values in stored.items():
            np.testing.assert_array_equal(ds[f"metric_{name}"].values, values, err_msg=name)
    shipped = pickle.loads(pickle.dumps(build))  # what a worker process receives
    for index in (0, 3, CASES - 1):
        alone = dispersed_case(shipped, scenario.dispersions, index)
        for name, value in alone.items():
            assert stored[name][index] == value, (index, name)


def test_a_case_is_its_document_flown_alone_by_the_engine(flagship):
    """A direct case (the nominal spacecraft with its truth departures, in a dispersed batch)
    against its case document flown alone (:func:`fly`: the plant rebuilt from the document, a
    plain spacecraft, the engine's own choice of loop). The two paths differ in the order of
    the sums only (shared against per-case propagators, the law's linear form built per run);
    the slew's closed loop carries the round-off: 1e-9 of each metric."""
    result, _ = flagship
    scenario, build = _builder(result)
    table = sample_table(scenario.dispersions, {p.path: p.unit for p in build.cases.parameters})
    seeds = result.dispersions
    from flexsat.scenarios.batch_cases import document_seeds

    for index in (1, 6):
        values = {p: float(table.values[p][index]) for p in build.parameter_names}
        seed = int(document_seeds(scenario.dispersions.seed, np.array([index]))[0])
        case = build.cases.scenario(values, seed)
        assert case.truth.frequency_scale != 1.0  # the values are written into the document
        alone = fly(case, list(build.runs), result.placement, build.laws)
        for name, value in alone.items():
            assert seeds.metrics[name][index] == pytest.approx(value, rel=1e-9), name


def test_the_noise_reaches_the_flight(flagship):
    """The nominal document flown with its sensors and random torque, and without them: the
    noise changes the final attitude error (each draw from the case's seed)."""
    result, _ = flagship
    scenario, build = _builder(result)
    data = yaml.safe_load(scenario.yaml_text)
    data.pop("dispersions")
    noisy = fly(_load(data), ["slew"], result.placement, build.laws)
    data.pop("sensors")
    data.pop("disturbances")
    quiet = fly(_load(data), ["slew"], result.placement, build.laws)
    assert noisy["final_attitude_error_rad"] != quiet["final_attitude_error_rad"]
    # the nominal run of the study flies the same document: its metrics are the noisy ones
    (record,) = result.metrics_records()
    for name, value in noisy.items():
        assert record[name] == pytest.approx(value, rel=1e-12), name


def test_an_interrupted_monte_carlo_resumes_where_it_stopped(flagship, tmp_path):
    """Stopped after its first chunk (4 of 10 cases), the stage resumes from its store: the
    chunk done is read back, the two others run, and the numbers are those of the whole run."""
    from flexsat.design.batch_runner import BatchInterrupted

    result, cache = flagship
    data = _data(cache)
    data["dispersions"]["store"] = str(tmp_path / "resumed.zarr")

    def stop(message: str) -> None:
        if message.startswith("dispersions: 4/10"):
            raise KeyboardInterrupt

    with pytest.raises(BatchInterrupted):
        run_scenario(_load(data), progress=stop)
    resumed = run_scenario(_load(data))
    assert (resumed.dispersions.chunks_skipped, resumed.dispersions.chunks_run) == (1, 2)
    for name, values in result.dispersions.metrics.items():
        np.testing.assert_array_equal(resumed.dispersions.metrics[name], values, err_msg=name)
