"""The EPS slew Monte Carlo (examples/eps_slew_montecarlo.yaml, seed 003's goals under a
dispersed truth plant and noisy sensors), run here with 6 cases in chunks of 3 instead of the
file's 1,000 (a case takes about 0.7 s once the design is kept; 1,000 would take 12 minutes of
one core): a case equals its document run alone, the probabilities and their intervals are
those of the stored goal verdicts, the report states them, and a dispersion that makes the
plant unphysical is refused by name before any case runs."""

import shutil
from pathlib import Path

import numpy as np
import pytest
import yaml
from scipy import stats

from flexsat.design.batch_runner import open_results
from flexsat.design.monte_carlo_statistics import proportion_interval
from flexsat.scenarios import ScenarioError, load_scenario, run_scenario, slew
from flexsat.scenarios.batch_cases import case_metrics, document_seeds

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
RUN = "tuned: torquers + forces"
CASES = 6


def _study(folder: Path, *changes: tuple[str, str]) -> Path:
    text = (EXAMPLES / "eps_slew_montecarlo.yaml").read_text()
    for old, new in (("cases: 1000", f"cases: {CASES}"), ("chunk_size: 25", "chunk_size: 3")):
        assert old in text
        text = text.replace(old, new)
    for old, new in changes:
        assert old in text, old
        text = text.replace(old, new)
    shutil.copy(EXAMPLES / "eps_slew_6s_flown.yaml", folder / "eps_slew_6s_flown.yaml")
    path = folder / "eps_slew_montecarlo.yaml"
    path.write_text(text + "store: study.zarr\n")
    return path


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    folder = tmp_path_factory.mktemp("eps_mc")
    result = run_scenario(load_scenario(_study(folder)))
    return folder, result, open_results(folder / "study.zarr")


def test_the_example_file_loads_as_written():
    study = load_scenario(EXAMPLES / "eps_slew_montecarlo.yaml")
    assert study.cases == 1000 and study.kind == "montecarlo" and study.store is None
    assert sorted(study.parameters) == [
        "sensors.rate.noise",
        "truth.damping",
        "truth.frequency_scale",
        "truth.inertia_scale[0]",
        "truth.inertia_scale[1]",
        "truth.inertia_scale[2]",
    ]


def test_a_case_equals_its_document_run_alone(study, monkeypatch):
    """Case i is eps_slew_6s_flown.yaml with the drawn factors, damping and gyro noise written
    in by hand here and the case's seed in simulation.seed, run alone with nothing kept from
    the batch (a fresh nominal maneuver and design): the same metrics, bit for bit."""
    folder, _, ds = study
    assert ds["done"].values.all()
    seeds = document_seeds(3, np.arange(CASES))
    assert np.array_equal(ds["seed"].values, seeds)
    monkeypatch.setattr(slew, "DESIGNS_KEPT", 0)
    for i in (0, CASES - 1):
        data = yaml.safe_load((folder / "eps_slew_6s_flown.yaml").read_text())
        truth = data["truth"]
        for k in range(3):
            truth["inertia_scale"][k] = float(ds[f"param_truth.inertia_scale[{k}]"].values[i])
        truth["frequency_scale"] = float(ds["param_truth.frequency_scale"].values[i])
        truth["damping"] = float(ds["param_truth.damping"].values[i])
        noise = float(ds["param_sensors.rate.noise"].values[i])
        data["sensors"]["rate"]["noise"] = f"{noise!r} rad/s"
        data["simulation"]["seed"] = int(seeds[i])
        alone = case_metrics(run_scenario(load_scenario(yaml.safe_dump(data))))
        assert sorted(alone) == sorted(
            str(k)[len("metric_") :] for k in ds.data_vars if str(k).startswith("metric_")
        )
        for name, value in alone.items():
            assert np.array_equal(ds[f"metric_{name}"].values[i], value, equal_nan=True), (i, name)


def test_the_draws_follow_the_distributions(study):
    """Uniform factors inside their bounds, the log-normal damping and noise positive, every
    case its own draw (the dispersion reaches the goal metrics)."""
    _, result, ds = study
    for k in range(3):
        factors = result.table[f"truth.inertia_scale[{k}]"]
        assert 0.95 <= factors.min() and factors.max() <= 1.05
    assert (0.9 <= result.table["truth.frequency_scale"]).all()
    assert (result.table["truth.frequency_scale"] <= 1.1).all()
    assert (result.table["truth.damping"] > 0).all()
    assert result.units["sensors.rate.noise"] == "rad/s"
    assert len(set(ds[f"metric_runs['{RUN}'].angle_error_mrad"].values)) == CASES


def test_the_probabilities_are_those_of_the_stored_verdicts(study):
    """Each requirement's successes are the cases whose stored metrics meet the goal (the
    verdicts recomputed from the angle error, 3 % of 1 rad, and the deflection ratio, 10:1),
    its interval the Clopper-Pearson interval (the beta quantiles, Clopper & Pearson 1934) of
    monte_carlo_statistics."""
    _, result, ds = study
    names = ("angle_error_mrad", "deflection_ratio_after", "angle_goal_met", "deflection_goal_met")
    metric = {name: ds[f"metric_runs['{RUN}'].{name}"].values for name in names}
    angle = metric["angle_error_mrad"] <= 30.0
    deflection = metric["deflection_ratio_after"] >= 10.0
    assert np.array_equal(metric["angle_goal_met"], angle.astype(float))
    assert np.array_equal(metric["deflection_goal_met"], deflection.astype(float))
    expected = {
        "angle_goal_met": angle.sum(),
        "deflection_goal_met": deflection.sum(),
        "goals_met": (angle & deflection).sum(),
    }
    requirements = {r["metric"]: r for r in result.summary["requirements"]}
    assert sorted(requirements) == sorted(f"runs['{RUN}'].{name}" for name in expected)
    for name, k in expected.items():
        r = requirements[f"runs['{RUN}'].{name}"]
        assert (r["successes"], r["n"]) == (k, CASES)
        assert r["probability"] == k / CASES
        assert (r["low"], r["high"]) == proportion_interval(int(k), CASES, 0.95)
        low = stats.beta.ppf(0.025, k, CASES - k + 1) if k > 0 else 0.0
        high = stats.beta.ppf(0.975, k + 1, CASES - k) if k < CASES else 1.0
        assert r["low"] == pytest.approx(low, abs=1e-12)
        assert r["high"] == pytest.approx(high, abs=1e-12)


def test_the_report_states_each_probability(study):
    folder, result, _ = study
    from flexsat.report import write_report

    page = (write_report(result, folder / "report") / "index.html").read_text()
    for r in result.summary["requirements"]:
        row = f"<td>{r['probability']:.4f}</td><td>[{r['low']:.4f}, {r['high']:.4f}]</td>"
        assert row in page, r["requirement"]


@pytest.mark.parametrize(
    "change, message",
    [
        (
            # the greatest principal moment up to 1.3 ×: the extreme draw breaks the triangle
            # inequality (the EPS's moments 1.45, 9.07, 9.13 × 1e4 kg m²)
            (
                "truth.inertia_scale[2]: {distribution: uniform, low: 0.95, high: 1.05}",
                "truth.inertia_scale[2]: {distribution: uniform, low: 0.95, high: 1.3}",
            ),
            # (named by the section's field: the three factors together make the inertia)
            r"parameters: case \d+ \(.*truth\.inertia_scale\[2\] = 1\.[12].*\): "
            r"truth\.inertia_scale: principal moments .* violate the triangle inequality",
        ),
        (
            # a normal factor with a wide spread draws non-positive frequency scales
            (
                "truth.frequency_scale: {distribution: uniform, low: 0.9, high: 1.1}",
                "truth.frequency_scale: {distribution: normal, mean: 1.0, sd: 10.0}",
            ),
            r"parameters\.truth\.frequency_scale: case \d+ \(.*\): .*must be a finite number "
            r"> 0",
        ),
        (
            ("truth.damping:", "truth.dampnig:"),
            r"parameters\.truth\.dampnig: case 0 .*truth\.dampnig: unknown key .*nearest fields: "
            r"truth\.damping",
        ),
    ],
)
def test_an_unphysical_dispersion_is_refused_before_any_case_runs(tmp_path, change, message):
    path = _study(tmp_path, change)
    with pytest.raises(ScenarioError, match=message):
        run_scenario(load_scenario(path))
    assert not (tmp_path / "study.zarr").exists()
