"""Sweeps and Monte Carlo over any scenario, parameters by field path (flexsat.scenarios.
batch_cases): a case equals its document run alone, the store does not depend on the chunking
or the workers, an interrupted run resumes to the same store, and every mistake is named before
any case runs."""

from pathlib import Path

import numpy as np
import pytest
import yaml

from flexsat.design.batch_runner import open_results
from flexsat.scenarios import ScenarioError, load_scenario, run_scenario
from flexsat.scenarios.batch_cases import case_metrics, document_seeds

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"

#: a short noisy TAMU slew (2 modes, 3 s at 50 Hz, a random hub torque): cheap cases whose
#: results depend on their seeds
MANEUVER = """
name: short noisy TAMU slew
case: tamu
case_overrides: {hub_inertia: "50 ozf*in*s**2"}
model: {n_modes: 2, stiffening: false}
maneuver: {angle: "40 deg"}
simulation: {duration: "3 s", control_rate: "50 Hz", settling_band: "0.5 deg", seed: 0}
actuator: {saturation: "400 ozf*in"}
disturbances: {random_torque: "5 ozf*in"}
runs:
  - {label: "Law I", law: lyapunov_regulator, gains: {g1: "600 ozf*in/rad", g2: "800 ozf*in*s/rad"}}
  - {label: "Law II", law: lyapunov_tracker, gains: {g1: "3000 ozf*in/rad", g2: "800 ozf*in*s/rad"},
     reference: {shape: smooth_bang_bang, alpha: 0.2, u_max: "400 ozf*in"}}
"""

MONTECARLO = """
kind: montecarlo
name: Law I by field path
scenario: maneuver.yaml
run: Law I
parameters:
  case_overrides.hub_inertia: {distribution: normal, mean: "50 ozf*in*s**2", sd: "2 ozf*in*s**2"}
  runs['Law I'].gains.g1: {distribution: uniform, low: "500 ozf*in/rad", high: "700 ozf*in/rad"}
cases: 8
seed: 5
requirements:
  settling_time_s: {max: "3 s"}
execution: {chunk_size: 3}
store: mc.zarr
"""


def _write(folder: Path, text: str, name: str = "study.yaml", target: str = MANEUVER) -> Path:
    (folder / "maneuver.yaml").write_text(target)
    path = folder / name
    path.write_text(text)
    return path


def _values(store: Path) -> dict[str, np.ndarray]:
    ds = open_results(store)
    return {name: ds[name].values for name in ds.variables}


def _same(a: dict, b: dict) -> None:
    """Bit-identical stores: the same variables with the same bytes (NaN where NaN)."""
    assert sorted(a) == sorted(b)
    for name in a:
        assert np.array_equal(a[name], b[name], equal_nan=a[name].dtype.kind == "f"), name


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """The Monte Carlo in chunks of 3, in-process: (its folder, its result, its store)."""
    folder = tmp_path_factory.mktemp("documents")
    result = run_scenario(load_scenario(_write(folder, MONTECARLO)))
    return folder, result, _values(folder / "mc.zarr")


def test_every_case_equals_its_document_run_alone(reference, tmp_path):
    """Case i is the maneuver file with run Law I only, the two values written in their units
    and the case's seed in simulation.seed, run by itself: bit for bit. The document is
    written here by hand, not by the batch code."""
    _, result, store = reference
    assert result.chunks_run == 3 and store["done"].all()
    seeds = document_seeds(5, np.arange(8))
    assert np.array_equal(store["seed"], seeds) and len(set(seeds)) == 8
    from flexsat.units import si_factor

    ozf_in = si_factor("ozf*in")  # the factor the document's strings are read back with
    assert ozf_in == pytest.approx(0.0254 * 0.45359237 * 9.80665 / 16, rel=1e-15)
    inertia = store["param_case_overrides.hub_inertia"]
    gain = store["param_runs['Law I'].gains.g1"]
    assert 40 * ozf_in < inertia.min() and inertia.max() < 60 * ozf_in
    assert 500 * ozf_in <= gain.min() and gain.max() <= 700 * ozf_in
    for i in (0, 7):
        data = yaml.safe_load(MANEUVER)
        data["runs"] = [data["runs"][0]]
        data["case_overrides"]["hub_inertia"] = f"{float(inertia[i]) / ozf_in!r} ozf*in*s**2"
        data["runs"][0]["gains"]["g1"] = f"{float(gain[i]) / ozf_in!r} ozf*in/rad"
        data["simulation"]["seed"] = int(seeds[i])
        alone = run_scenario(load_scenario(yaml.safe_dump(data)))
        metrics = case_metrics(alone)
        assert metrics, "no metrics"
        for name, value in metrics.items():
            assert np.array_equal(store[f"metric_{name}"][i], value, equal_nan=True), (i, name)
    # the seed matters: case 7's document with another seed gives other numbers
    data["simulation"]["seed"] = int(seeds[7]) + 1
    other = case_metrics(run_scenario(load_scenario(yaml.safe_dump(data))))
    assert any(not np.array_equal(other[k], metrics[k], equal_nan=True) for k in metrics)
    assert result.summary["requirements"][0]["metric"] == "settling_time_s"


@pytest.mark.parametrize("chunking", ["chunk_size: 1", "chunk_size: 7", "chunk_size: 8"])
def test_the_store_does_not_depend_on_the_chunk_size(reference, tmp_path, chunking):
    _, _, store = reference
    text = MONTECARLO.replace("chunk_size: 3", chunking)
    run_scenario(load_scenario(_write(tmp_path, text)))
    _same(_values(tmp_path / "mc.zarr"), store)


def test_the_store_does_not_depend_on_the_worker_count(reference, tmp_path):
    _, _, store = reference
    text = MONTECARLO.replace("chunk_size: 3}", "chunk_size: 3, workers: 2}")
    run_scenario(load_scenario(_write(tmp_path, text)))
    _same(_values(tmp_path / "mc.zarr"), store)


def test_an_interrupted_run_resumes_to_the_same_store(reference, tmp_path):
    """Stopped (as by Ctrl-C) after its first chunk, the store keeps that chunk; the same
    scenario again runs the two others only and equals the uninterrupted store."""
    from flexsat.design.batch_runner import BatchInterrupted

    _, _, store = reference
    path = _write(tmp_path, MONTECARLO)
    calls = []

    def stop(message):
        calls.append(message)
        if len(calls) == 2:
            raise KeyboardInterrupt

    with pytest.raises(BatchInterrupted, match="3 of 8 cases are done"):
        run_scenario(load_scenario(path), progress=stop)
    assert open_results(tmp_path / "mc.zarr")["done"].values.sum() == 3
    again = run_scenario(load_scenario(path))
    assert (again.chunks_skipped, again.chunks_run) == (1, 2)
    _same(_values(tmp_path / "mc.zarr"), store)


def test_the_report_names_the_paths_and_the_run(reference):
    folder, result, _ = reference
    from flexsat.report import write_report

    out = write_report(result, folder / "report")
    page = (out / "index.html").read_text()
    assert "8 cases of run <b>Law I</b>" in page
    assert "runs[&#x27;Law I&#x27;].gains.g1" in page
    assert result.report_case() == "tamu"


@pytest.mark.parametrize(
    "change, message",
    [
        (
            ("case_overrides.hub_inertia:", "case_overrides.hub_inertai:"),
            r"parameters\.case_overrides\.hub_inertai: case 0 .*unknown parameter\(s\) "
            r"\['hub_inertai'\]; known: .*'hub_inertia'",
        ),
        (
            ("case_overrides.hub_inertia:", "simulation.durations:"),
            r"parameters\.simulation\.durations: case 0 .* simulation\.durations: unknown key "
            r"\(allowed: duration, .*\); nearest fields: simulation\.duration",
        ),
        (
            ("runs['Law I'].gains.g1:", "runs['Law 1'].gains.g1:"),
            r"runs\['Law 1'\].gains.g1 is not a field of the scenario \(step 2, 'Law 1', is "
            r"not found\); nearest: runs\['Law I'\].gains.g1",
        ),
        (
            ("runs['Law I'].gains.g1:", "runs['Law I'].gains:"),
            r"holds a mapping; a parameter sets one number",
        ),
        (
            ("runs['Law I'].gains.g1:", "runs[Law I].gains.g1:"),
            r"at character 5, a bracket holds an index",
        ),
        (
            ('low: "500 ozf*in/rad", high: "700 ozf*in/rad"', 'low: "5 s", high: "7 s"'),
            r"values in s \(\[time\]\) where the scenario's runs\['Law I'\].gains.g1 is "
            r"'600 ozf\*in/rad'",
        ),
        (
            (
                'distribution: normal, mean: "50 ozf*in*s**2", sd: "2 ozf*in*s**2"',
                'distribution: uniform, low: "-60 ozf*in*s**2", high: "-50 ozf*in*s**2"',
            ),
            r"parameters\.case_overrides\.hub_inertia: case \d+ \(case_overrides.hub_inertia "
            r"= -[\d.e+-]+ ozf\*in\*s\*\*2, .*\): .*hub_inertia.*must be > 0",
        ),
        (("run: Law I", "run: Law III"), r"run: 'Law III' is not a run of the scenario"),
    ],
)
def test_mistakes_are_named_before_any_case_runs(tmp_path, change, message):
    """A mistyped key or label, a mapping, a bad bracket, a unit of another dimension, a
    draw that makes the plant unphysical (a negative hub inertia: refused where the kind builds
    the plant, at an extreme draw) and an unknown run: refused by name, no store made."""
    old, new = change
    assert old in MONTECARLO
    path = _write(tmp_path, MONTECARLO.replace(old, new))
    with pytest.raises(ScenarioError, match=message):
        run_scenario(load_scenario(path))
    assert not (tmp_path / "mc.zarr").exists()


@pytest.mark.parametrize(
    "text, message",
    [
        (
            MONTECARLO.replace("case_overrides.hub_inertia:", "hub_inertia:"),
            r"field paths \(runs\['Law I'\].gains.g1\) and Law II parameter names "
            r"\(hub_inertia\) cannot be mixed",
        ),
        (
            MONTECARLO.replace("cases: 8", "cases: 8\nhistories: [theta]"),
            "histories: a batch over a scenario document's field paths keeps metrics only",
        ),
        (
            MONTECARLO.replace(
                'low: "500 ozf*in/rad", high: "700 ozf*in/rad"', "low: .nan, high: 1"
            ),
            r"parameters.runs\['Law I'\].gains.g1.low: .*finite",
        ),
    ],
)
def test_schema_mistakes_are_named_when_the_study_is_read(tmp_path, text, message):
    with pytest.raises(ScenarioError, match=message):
        load_scenario(_write(tmp_path, text))


def test_a_batch_of_batches_is_refused_by_name(tmp_path):
    inner = _write(tmp_path, MONTECARLO, "inner.yaml")
    outer = MONTECARLO.replace("scenario: maneuver.yaml", f"scenario: {inner.name}").replace(
        "runs['Law I'].gains.g1:", "execution.chunk_size:"
    )
    with pytest.raises(ScenarioError, match="a montecarlo scenario is a batch itself"):
        run_scenario(load_scenario(_write(tmp_path, outer, "outer.yaml")))


def test_a_case_diverging_on_a_worker_is_named_by_its_case(tmp_path):
    """A rate gain of 1e5 N m s/rad at 50 Hz with the torque unbounded: g2 dt / J >> 2, the
    sampled loop of the last grid point is unstable. The divergence is raised on the worker
    and arrives with its type, its run's path and the sweep's case number (the last of the four,
    alone in its chunk: case 3)."""
    from flexsat.sim import SimulationDiverged

    text = """
kind: sweep
name: unstable corner
scenario: maneuver.yaml
run: Law I
parameters:
  runs['Law I'].gains.g2: {values: ["800 ozf*in*s/rad", "1e5 N*m*s/rad"]}
  actuator.saturation: {values: ["400 ozf*in", "1e9 N*m"]}
execution: {chunk_size: 1}
store: unstable.zarr
"""
    with pytest.raises(SimulationDiverged) as err:
        run_scenario(load_scenario(_write(tmp_path, text)))
    assert err.value.cases == (3,) and "in case(s) 3:" in str(err.value)
    assert str(err.value).startswith("runs['Law I']: ")
    assert open_results(tmp_path / "unstable.zarr")["done"].values.tolist() == [1, 1, 1, 0]


def test_the_law_ii_fast_path_runs_no_scenario_per_case(tmp_path, monkeypatch):
    """Parameters by name still take the compiled Law II path, one batched call per chunk."""
    from flexsat.scenarios.batch_cases import DocumentCases

    def refuse(*args, **kwargs):
        raise AssertionError("a case ran through the scenario runner")

    monkeypatch.setattr(DocumentCases, "run_chunk", refuse)
    text = """
kind: sweep
name: fast path
scenario: maneuver.yaml
run: Law II
parameters:
  alpha: {values: [0.1, 0.2]}
store: fast.zarr
"""
    result = run_scenario(load_scenario(_write(tmp_path, text)))
    assert result.chunks_run == 1 and "metric_settling_time_s" in result.dataset()


def test_without_a_run_every_run_is_a_case_and_its_metrics_are_named_by_run(tmp_path):
    """No ``run:``: a case runs both laws; each metric is named by its run, a requirement reads
    one run's metric (its unit: the engine's settling time, in s)."""
    text = (
        MONTECARLO.replace("run: Law I\n", "")
        .replace("cases: 8", "cases: 2")
        .replace("settling_time_s: {max:", "runs['Law II'].settling_time_s: {max:")
    )
    result = run_scenario(load_scenario(_write(tmp_path, text)))
    ds = open_results(tmp_path / "mc.zarr")
    names = {str(k) for k in ds.data_vars if str(k).startswith("metric_")}
    assert "metric_runs['Law I'].settling_time_s" in names
    assert "metric_runs['Law II'].settling_time_s" in names
    assert not {n for n in names if not n.startswith("metric_runs[")}
    (requirement,) = result.summary["requirements"]
    assert requirement["metric"] == "runs['Law II'].settling_time_s"
    assert requirement["threshold"] == 3.0
    assert "every run" in result.sections(result.dataset(), [])


def test_a_requirement_on_a_metric_the_kind_does_not_report_is_named(tmp_path):
    text = MONTECARLO.replace('settling_time_s: {max: "3 s"}', "settle_time: {max: 3}")
    with pytest.raises(ValueError, match=r"requirements.settle_time: unknown metric; the run's"):
        run_scenario(load_scenario(_write(tmp_path, text)))


def test_cyclic_and_angular_frequencies_keep_their_two_pi():
    """Values in Hz and rad/s for one parameter: the table holds Hz (its SI unit here), the
    rad/s value divided by 2π, and each goes into the document in Hz."""
    import math

    from flexsat.design.parameter_space import space_from_spec
    from flexsat.scenarios.batch_cases import document_parameter

    path = "runs['PD step'].poles.natural_frequency"
    entry = {"values": ["0.06 Hz", "0.4 rad/s"]}
    data = yaml.safe_load((EXAMPLES / "nps_pd_slews.yaml").read_text())
    parameter = document_parameter(path, entry, data)
    assert (parameter.unit, parameter.written) == ("Hz", "Hz")
    values = space_from_spec({path: entry}, {path: parameter.unit}).table().values[path]
    assert values[0] == 0.06 and values[1] == pytest.approx(0.4 / (2 * math.pi), rel=1e-15)
    assert parameter.value(values[1]) == f"{0.4 / (2 * math.pi)!r} Hz"
    rad_s = document_parameter(path, {"values": ["0.4 rad/s", "0.06 Hz"]}, data)
    assert rad_s.unit == "rad/s"
    table = space_from_spec({path: entry}, {path: rad_s.unit}).table().values[path]
    assert table[0] == pytest.approx(0.06 * 2 * math.pi, rel=1e-15) and table[1] == 0.4


def test_a_negative_stiffness_in_a_distribution_s_tail_is_refused_before_any_case_runs(tmp_path):
    """The appendage modulus, normal about 70 GPa with a 60 GPa sd: the schema takes any number
    (the override goes to the case builder), the extreme draw's plan refuses it, naming the
    parameter, the case (the least draw) and the rule; no store is made."""
    text = """
kind: montecarlo
name: negative stiffness in the tail
scenario: maneuver.yaml
run: Law I
parameters:
  case_overrides.modulus: {distribution: normal, mean: "70 GPa", sd: "60 GPa"}
cases: 50
seed: 1
store: neg.zarr
"""
    path = _write(tmp_path, text)
    study = load_scenario(path)
    from flexsat.design.parameter_space import space_from_spec

    draws = space_from_spec(study.parameters, {"case_overrides.modulus": "Pa"}).sample(50, 1)
    least = int(np.argmin(draws.values["case_overrides.modulus"]))
    assert draws.values["case_overrides.modulus"][least] < 0
    with pytest.raises(
        ScenarioError,
        match=rf"parameters\.case_overrides\.modulus: case {least} \(case_overrides\.modulus = "
        r"-[\d.]+ GPa\): case_overrides\.modulus: must be > 0",
    ):
        run_scenario(study)
    assert not (tmp_path / "neg.zarr").exists()


def test_a_study_over_field_paths_runs_ten_cases_a_chunk_unless_told(tmp_path):
    """Its cases take seconds each: 10 a chunk by default (the fast path keeps 1,000), a
    chunk size given is kept."""
    from flexsat.scenarios.batch_cases import DOCUMENT_CHUNK_SIZE

    plain = MONTECARLO.replace("execution: {chunk_size: 3}\n", "")
    assert load_scenario(_write(tmp_path, plain)).execution.chunk_size == DOCUMENT_CHUNK_SIZE == 10
    assert load_scenario(_write(tmp_path, MONTECARLO)).execution.chunk_size == 3
    fast = "kind: sweep\nname: f\nscenario: maneuver.yaml\nrun: Law II\n"
    fast += "parameters: {alpha: {values: [0.1, 0.2]}}\n"
    assert load_scenario(_write(tmp_path, fast)).execution.chunk_size == 1000
