"""The example studies over field paths, each run here with fewer cases (the files state the
full counts): the PPF gain sweep, the tether gain sweep, the space-station CMG Monte Carlo and
the NPS PD Monte Carlo. Where a grid point holds the target's own values, that case equals the
target's run alone, bit for bit."""

import shutil
from pathlib import Path

import numpy as np
import pytest
import yaml

from flexsat.design.batch_runner import open_results
from flexsat.scenarios import load_scenario, run_scenario
from flexsat.scenarios.batch_cases import case_metrics

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def _study(tmp_path: Path, name: str, *changes: tuple[str, str]) -> Path:
    """The example ``name`` and its target copied to ``tmp_path``, with ``changes`` (fewer
    cases) and a store of its own."""
    text = (EXAMPLES / name).read_text()
    for old, new in changes:
        assert old in text, old
        text = text.replace(old, new)
    target = yaml.safe_load(text)["scenario"]
    shutil.copy(EXAMPLES / target, tmp_path / target)
    path = tmp_path / name
    path.write_text(text + "store: study.zarr\n")
    return path


def _run_alone(target: Path, run: str) -> dict[str, float]:
    """The metrics of the target's run ``run`` alone (the file with its other runs removed)."""
    data = yaml.safe_load(target.read_text())
    data["runs"] = [r for r in data["runs"] if r["label"] == run]
    return case_metrics(run_scenario(load_scenario(yaml.safe_dump(data))))


def _case(tmp_path: Path, index: int) -> dict[str, float]:
    ds = open_results(tmp_path / "study.zarr")
    return {
        str(k)[len("metric_") :]: ds[k].values[index]
        for k in ds.data_vars
        if str(k).startswith("metric_")
    }


def _assert_equal(case: dict, alone: dict) -> None:
    assert sorted(case) == sorted(alone)
    for name, value in alone.items():
        assert np.array_equal(case[name], value, equal_nan=True), name


def test_the_ppf_gain_sweep(tmp_path):
    """The initial gains and the first-mode weight of run 1a, the file as written (6 cases):
    the point (100, 100) is the published run itself; a heavier first-mode weight raises the
    cost at the initial gains."""
    path = _study(tmp_path, "agrawal_bang_ppf_sweep.yaml")
    result = run_scenario(load_scenario(path))
    assert result.scenario.sampling == "grid" and len(result.table["ppf.initial_gains"]) == 6
    # grid order: the first axis slowest, case 2 = (initial gains 100, w1 100)
    _assert_equal(_case(tmp_path, 2), _run_alone(tmp_path / "agrawal_bang_ppf.yaml", "1a paper"))
    j_init = open_results(tmp_path / "study.zarr")["metric_J_init"].values
    assert (j_init[1::2] > j_init[0::2]).all()  # w1 = 500 against 100, at each initial gain


def test_the_tether_gain_sweep(tmp_path):
    """K1 and K4 of controller 2: the point (1.0, 2.0) is the run of Figs. 4-5 itself."""
    path = _study(
        tmp_path,
        "tether_gain_sweep.yaml",
        ("{values: [0.8, 0.9, 1.0, 1.1]}", "{values: [0.9, 1.0]}"),
        ("{values: [1.5, 2.0, 3.0]}", "{values: [2.0]}"),
    )
    result = run_scenario(load_scenario(path))
    assert len(result.table) == 2 and result.chunks_run == 1
    _assert_equal(
        _case(tmp_path, 1),
        _run_alone(tmp_path / "tether_retrieval.yaml", "controller 2, K4 = 2 (Figs. 4-5)"),
    )
    assert _case(tmp_path, 0) != _case(tmp_path, 1)


def test_the_space_station_cmg_monte_carlo(tmp_path):
    """The three principal moments dispersed: each case redoes the LQR design and both loops;
    the requirements' probabilities come with their confidence bounds."""
    path = _study(
        tmp_path,
        "space_station_cmg_montecarlo.yaml",
        ("cases: 100", "cases: 3"),
        ("chunk_size: 10", "chunk_size: 2"),
    )
    result = run_scenario(load_scenario(path))
    moments = np.stack([result.table[f"station.inertia[{k}]"] for k in range(3)])
    assert moments.shape == (3, 3) and len(np.unique(moments)) == 9
    assert result.units["station.inertia[0]"] == "kg*m**2"
    peak = open_results(tmp_path / "study.zarr")["metric_peak_momentum_h"].values
    assert np.isfinite(peak).all() and len(set(peak)) == 3  # the inertia changes the demand
    reqs = {r["metric"]: r for r in result.summary["requirements"]}
    assert sorted(reqs) == ["peak_momentum_h", "singular"]
    for r in reqs.values():
        assert 0 <= r["low"] <= r["probability"] <= r["high"] <= 1


def test_the_nps_pd_monte_carlo(tmp_path):
    """Poles and gyro noise dispersed, each case with its own noise seed in simulation.seed:
    the probability of settling within 30 s and the parameters' ranking."""
    path = _study(
        tmp_path,
        "nps_pd_montecarlo.yaml",
        ("cases: 200", "cases: 6"),
        ("chunk_size: 50", "chunk_size: 4"),
    )
    result = run_scenario(load_scenario(path))
    ds = open_results(tmp_path / "study.zarr")
    assert ds["done"].values.all() and len(set(ds["seed"].values)) == 6
    frequency = result.table["runs['PD step'].poles.natural_frequency"]
    assert result.units["runs['PD step'].poles.natural_frequency"] == "Hz"
    assert 0.04 < frequency.min() and frequency.max() < 0.08  # Hz, as written
    assert [r["metric"] for r in result.summary["requirements"]] == [
        "settling_time_s",
        "overshoot_deg",
    ]
    assert np.isfinite(ds["metric_settling_time_s"].values).all()


@pytest.mark.parametrize(
    "name",
    [
        "agrawal_bang_ppf_sweep.yaml",
        "tether_gain_sweep.yaml",
        "space_station_cmg_montecarlo.yaml",
        "nps_pd_montecarlo.yaml",
    ],
)
def test_the_example_files_load_as_written(name):
    study = load_scenario(EXAMPLES / name)
    assert study.kind in ("sweep", "montecarlo") and study.store is None


def test_a_sweep_over_the_modulus_of_an_inline_finite_element_model(tmp_path):
    """A path into a model: section (the user's own spacecraft, examples/own_spacecraft_slew.
    yaml): each case rebuilds the FE model and its modes; the point at the file's own 70 GPa
    equals the scenario run alone, a stiffer boom rings less at its tip."""
    shutil.copy(EXAMPLES / "own_spacecraft_slew.yaml", tmp_path / "own_spacecraft_slew.yaml")
    path = tmp_path / "sweep.yaml"
    path.write_text(
        "kind: sweep\nname: boom modulus\nscenario: own_spacecraft_slew.yaml\n"
        'parameters:\n  model.fe.materials.aluminium.E: {values: ["70 GPa", "140 GPa"]}\n'
        "store: study.zarr\n"
    )
    result = run_scenario(load_scenario(path))
    assert result.units["model.fe.materials.aluminium.E"] == "kg/m/s**2"  # Pa in base units
    _assert_equal(_case(tmp_path, 0), _run_alone(tmp_path / "own_spacecraft_slew.yaml", "MRP PD"))
    soft, stiff = (_case(tmp_path, i)["peak_displacement_105Z"] for i in (0, 1))
    assert stiff < soft
