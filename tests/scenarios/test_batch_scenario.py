"""Sweep and Monte Carlo scenarios (kind: sweep / montecarlo): a maneuver scenario's Law II run
over a grid or a distribution, chunked on dask into a zarr store, with statistics, the seed 000
trade surfaces and a report; each mistake named before anything runs."""

import json
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from flexsat.report import write_report
from flexsat.scenarios import ScenarioError, load_scenario, run_scenario
from flexsat.sim import SimulationDiverged
from report_browser import assert_renders

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"

#: a short TAMU Law II slew: 2 modes, 4 s at 50 Hz
MANEUVER = """
name: short TAMU slew
case: tamu
case_overrides: {hub_inertia: "50 ozf*in*s**2"}
model: {n_modes: 2, stiffening: false}
maneuver: {angle: "40 deg"}
simulation: {duration: "6 s", control_rate: "50 Hz", settling_band: "0.5 deg", seed: 0}
actuator: {saturation: "400 ozf*in"}
runs:
  - {label: "Law I", law: lyapunov_regulator, gains: {g1: "600 ozf*in/rad", g2: "800 ozf*in*s/rad"}}
  - {label: "Law II", law: lyapunov_tracker, gains: {g1: "3000 ozf*in/rad", g2: "800 ozf*in*s/rad"},
     reference: {shape: smooth_bang_bang, alpha: 0.2, u_max: "400 ozf*in"}}
"""

SWEEP = """
kind: sweep
name: small trade grid
scenario: maneuver.yaml
run: Law II
parameters:
  alpha: {values: [0.0, 0.25]}
  u_max: {values: ["300 ozf*in", "400 ozf*in", "500 ozf*in"]}
execution: {chunk_size: 4}
store: store.zarr
"""

MONTECARLO = """
kind: montecarlo
name: small Monte Carlo
scenario: maneuver.yaml
run: Law II
parameters:
  hub_inertia: {distribution: normal, mean: "50 ozf*in*s**2", sd: "2 ozf*in*s**2"}
  tip_mass: {distribution: uniform, low: "0 kg", high: "0.01 kg"}
cases: 24
seed: 3
requirements:
  settling_time_s: {max: "6 s"}
  overshoot_deg: {max: "2 deg"}
execution: {chunk_size: 10}
store: mc.zarr
"""


def _write(folder: Path, name: str, text: str) -> Path:
    (folder / "maneuver.yaml").write_text(MANEUVER)
    path = folder / name
    path.write_text(text)
    return path


def test_a_sweep_runs_every_grid_point_and_maps_the_trade_surfaces(tmp_path):
    result = run_scenario(load_scenario(_write(tmp_path, "sweep.yaml", SWEEP)))
    ds = result.dataset()
    assert ds.sizes["case"] == 6 and bool(ds["done"].all())
    # the grid in order, first axis slowest; u_max in SI
    np.testing.assert_array_equal(ds["param_alpha"].values, [0, 0, 0, 0.25, 0.25, 0.25])
    np.testing.assert_allclose(
        ds["param_u_max"].values[:3] / 0.0070615518142, [300, 400, 500], rtol=1e-10
    )
    # seed 000 Att. 3 Eq. 16: T falls with u_max and rises with α (the paper's Fig. 5)
    T = result.surfaces["maneuver_time_s"]
    assert T.shape == (2, 3) and np.all(np.diff(T, axis=1) < 0) and np.all(T[1] > T[0])
    assert result.surfaces["residual_energy_J"].shape == (2, 3)
    assert result.chunks_run == 2 and result.chunks_skipped == 0
    # the same scenario again resumes: nothing to run, the same numbers
    again = run_scenario(load_scenario(tmp_path / "sweep.yaml"))
    assert again.chunks_run == 0 and again.chunks_skipped == 2
    for name in ds.data_vars:
        if name.startswith("metric_"):
            np.testing.assert_array_equal(again.dataset()[name].values, ds[name].values)


def test_a_sweep_varies_the_actuator_and_sensors_given_in_units(tmp_path):
    """Sensor/actuator parameters are scenario parameters with units: a sweep over the torque
    limit (oz-in) and the encoder resolution (deg) stores them in SI, and a lower limit is a
    lower peak torque (the limit is reached by the 400 oz-in reference)."""
    text = SWEEP.replace(
        """  alpha: {values: [0.0, 0.25]}
  u_max: {values: ["300 ozf*in", "400 ozf*in", "500 ozf*in"]}""",
        """  saturation: {low: "300 ozf*in", high: "500 ozf*in", n: 3}
  encoder_resolution: {values: ["0 deg", "0.01 deg"]}""",
    )
    result = run_scenario(load_scenario(_write(tmp_path, "hardware.yaml", text)))
    ds = result.dataset()
    assert ds.sizes["case"] == 6 and bool(ds["done"].all())
    oz_in = 0.0070615518142  # N m per ozf*in
    np.testing.assert_allclose(
        ds["param_saturation"].values / oz_in, [300, 300, 400, 400, 500, 500], rtol=1e-10
    )
    np.testing.assert_allclose(
        np.degrees(ds["param_encoder_resolution"].values), [0, 0.01] * 3, rtol=1e-10
    )
    peak = ds["metric_peak_torque_Nm"].values
    assert np.all(np.diff(peak[::2]) > 0) and peak[0] <= ds["param_saturation"].values[0]


def test_a_monte_carlo_estimates_its_requirements_and_writes_its_report(tmp_path, browser):
    result = run_scenario(load_scenario(_write(tmp_path, "mc.yaml", MONTECARLO)))
    reqs = {r["metric"]: r for r in result.summary["requirements"]}
    settle = reqs["settling_time_s"]
    met = np.sum(result.dataset()["metric_settling_time_s"].values <= 6.0)
    assert settle["successes"] == met and settle["n"] == 24
    assert settle["low"] <= settle["probability"] <= settle["high"]
    assert reqs["overshoot_deg"]["threshold"] == pytest.approx(2.0)  # compared in degrees
    assert set(result.sensitivity) <= {
        k[len("metric_") :] for k in result.dataset().data_vars if k.startswith("metric_")
    }
    out = write_report(result, tmp_path / "report")
    for name in (
        "index.html",
        "summary.json",
        "convergence.png",
        "distribution_settling_time_s.png",
    ):
        assert (out / name).exists(), name
    summary = json.loads((out / "summary.json").read_text())
    assert summary["cases"] == 24 and summary["kind"] == "montecarlo"
    with xr.open_zarr(out / "results.zarr", consolidated=False) as saved:
        assert saved.sizes["case"] == 24
    assert "settling_time_s &lt;= 6" in (out / "index.html").read_text()
    assert "settling_time_s <= 6" in assert_renders(browser, out / "index.html")
    rows = result.metrics_records()
    assert any(r["run"].startswith("P(settling_time_s") for r in rows)


@pytest.mark.parametrize(
    "change, message",
    [
        (("hub_inertia: {", "spin_rate: {"), r"parameters.spin_rate: unknown parameter; known:"),
        (('sd: "2 ozf*in*s**2"', 'sd: "-2 ozf*in*s**2"'), r"parameters.hub_inertia.sd"),
        (("distribution: normal", "distribution: cauchy"), "unknown distribution 'cauchy'"),
        (('mean: "50 ozf*in*s**2"', 'mean: "50 kg"'), r"parameters.hub_inertia.mean"),
        (("cases: 24\n", ""), "cases: required with sampling 'random'"),
        (
            ("settling_time_s: {max", "settling_time: {max"),
            "requirements.settling_time: unknown metric",
        ),
        (
            ("execution: {chunk_size: 10}", "execution: {workers: 2, scheduler: 'tcp://x:1'}"),
            "give workers .* or scheduler .*, not both",
        ),
        (("kind: montecarlo", "kind: sweep"), r"requirements: belong to a montecarlo"),
        # a distribution written as a list or a mapping, a bound as a list: refused by name
        # (they used to reach a dict lookup: TypeError: unhashable type)
        (
            ("distribution: normal", "distribution: [normal]"),
            r"parameters.hub_inertia.distribution: must be a distribution name",
        ),
        (
            ("distribution: uniform", "distribution: {uniform: 1}"),
            r"parameters.tip_mass.distribution: must be a distribution name",
        ),
        (('low: "0 kg"', 'low: ["0 kg"]'), r"parameters.tip_mass.low: must be one number"),
    ],
)
def test_schema_mistakes_are_named(tmp_path, change, message):
    old, new = change
    assert old in MONTECARLO
    path = _write(tmp_path, "mc.yaml", MONTECARLO.replace(old, new))
    with pytest.raises(ScenarioError, match=message):
        load_scenario(path)


def test_identical_monte_carlo_runs_write_identical_summaries_and_pages(tmp_path):
    # the wall time and the resumed-chunk counts vary between identical runs: they stay out of
    # the files a user compares (a second run in the same folder resumes from the store); the
    # page's provenance line (its date) is the one line that differs
    from flexsat.report.provenance import without_provenance

    pages = []
    for name in ("first", "second"):
        folder = tmp_path / name
        folder.mkdir()
        result = run_scenario(load_scenario(_write(folder, "mc.yaml", MONTECARLO)))
        out = write_report(result, folder / "report")
        page = without_provenance((out / "index.html").read_text())
        pages.append(((out / "summary.json").read_text(), page))
    again = run_scenario(load_scenario(tmp_path / "first" / "mc.yaml"))
    assert again.chunks_run == 0
    out = write_report(again, tmp_path / "first" / "report")
    page = without_provenance((out / "index.html").read_text())
    pages.append(((out / "summary.json").read_text(), page))
    assert pages[0][0] == pages[1][0] == pages[2][0]
    assert pages[0][1] == pages[1][1] == pages[2][1]


@pytest.mark.parametrize(
    "change, message",
    [
        (
            ("run: Law II", "run: Law I"),
            "uses LyapunovRegulator; a batch varies a Control Law II run",
        ),
        (("run: Law II", "run: Law III"), r"run: 'Law III' is not a run of the scenario"),
        (("scenario: maneuver.yaml", "scenario: missing.yaml"), "scenario: cannot read"),
    ],
)
def test_mistakes_found_before_any_case_runs(tmp_path, change, message):
    old, new = change
    path = _write(tmp_path, "sweep.yaml", SWEEP.replace(old, new))
    with pytest.raises(ScenarioError, match=message):
        run_scenario(load_scenario(path))
    assert not (tmp_path / "store.zarr").exists()


def test_a_law_ii_run_tracking_another_shape_is_refused_by_name(tmp_path):
    """The case builder remakes the reference from (alpha, u_max): a smooth bang-bang. A
    bang_bang reference (which has no alpha) was an AttributeError; it is now named."""
    path = _write(tmp_path, "sweep.yaml", SWEEP)
    (tmp_path / "maneuver.yaml").write_text(
        MANEUVER.replace("shape: smooth_bang_bang, alpha: 0.2", "shape: bang_bang")
    )
    with pytest.raises(ScenarioError, match="run: 'Law II' tracks a BangBang reference; a batch"):
        run_scenario(load_scenario(path))
    assert not (tmp_path / "store.zarr").exists()


@pytest.mark.parametrize(
    "text, message",
    [
        (MONTECARLO.replace("cases: 24", "cases: 2000000"), r"cases: the sample has 2,000,000"),
        (
            SWEEP.replace(
                "alpha: {values: [0.0, 0.25]}", "alpha: {low: 0.0, high: 0.25, n: 400}"
            ).replace(
                'u_max: {values: ["300 ozf*in", "400 ozf*in", "500 ozf*in"]}',
                'u_max: {low: "300 ozf*in", high: "500 ozf*in", n: 400}',
            ),
            r"parameters: the grid of 400 × 400 has 160,000 cases",
        ),
        (
            SWEEP.replace(
                "alpha: {values: [0.0, 0.25]}", "alpha: {low: 0.0, high: 0.25, n: 1000000000}"
            ),
            r"^invalid scenario \(1 problem\):\n  parameters\.alpha\.n: grid points on one axis",
        ),
    ],
)
def test_a_study_beyond_the_case_limit_is_refused_before_its_table(
    tmp_path, monkeypatch, text, message
):
    # counted from the sizes given and the axes' lengths: no table, no linspace of 1e9 points
    from flexsat.design import parameter_space

    def no_table(*args, **kwargs):
        raise AssertionError("the table was built")

    for name in ("table", "sample", "latin_hypercube", "sobol_sequence", "sobol_design"):
        for cls in (parameter_space.GridSpace, parameter_space.ParameterSpace):
            if hasattr(cls, name):
                monkeypatch.setattr(cls, name, no_table)
    path = _write(tmp_path, "study.yaml", text)
    with pytest.raises(ScenarioError, match=message) as err:
        load_scenario(path)
    assert "MAX_CASES" in str(err.value) or "flexsat.limits" in str(err.value)


def test_a_scenario_of_another_kind_is_refused(tmp_path):
    path = _write(
        tmp_path,
        "sweep.yaml",
        SWEEP.replace("scenario: maneuver.yaml", f"scenario: {EXAMPLES / 'eps_slew_6s.yaml'}"),
    )
    with pytest.raises(
        ScenarioError, match="is a slew scenario; a batch of Law II parameters varies a maneuver"
    ):
        run_scenario(load_scenario(path))


def test_the_examples_are_valid():
    for name in ("tamu_trade_surfaces.yaml", "tamu_montecarlo.yaml"):
        spec = load_scenario(EXAMPLES / name)
        assert spec.kind in ("sweep", "montecarlo")


def test_the_command_line_runs_a_sweep_on_two_local_workers_and_refuses_them_elsewhere(tmp_path):
    from typer.testing import CliRunner

    from flexsat.cli import app

    runner = CliRunner()
    path = _write(tmp_path, "sweep.yaml", SWEEP)
    result = runner.invoke(app, ["run", str(path), "-o", str(tmp_path / "out"), "--workers", "2"])
    assert result.exit_code == 0, result.output
    assert (tmp_path / "out" / "results.zarr").exists()
    # the workers do not change the results: the in-process run finds the store complete
    again = run_scenario(load_scenario(path))
    assert again.chunks_run == 0
    refused = runner.invoke(
        app,
        ["run", str(tmp_path / "maneuver.yaml"), "-o", str(tmp_path / "out2"), "--workers", "2"],
    )
    assert refused.exit_code == 2
    assert "--workers/--scheduler: a maneuver scenario runs in this process" in refused.stderr


def test_a_saltelli_sweep_ranks_the_parameters_by_their_sobol_indices(tmp_path):
    # the peak torque of a Law II slew follows its reference's peak u_max and hardly α (the
    # tracking feedback adds little): Sobol' ranks u_max first with the larger total index;
    # n_base (d + 2) cases ran
    text = SWEEP.replace(
        """  alpha: {values: [0.0, 0.25]}
  u_max: {values: ["300 ozf*in", "400 ozf*in", "500 ozf*in"]}""",
        """  alpha: {low: 0.0, high: 0.25}
  u_max: {low: "300 ozf*in", high: "500 ozf*in"}
sampling: saltelli
cases: 8""",
    ).replace("execution: {chunk_size: 4}", "execution: {chunk_size: 16}")
    result = run_scenario(load_scenario(_write(tmp_path, "saltelli.yaml", text)))
    assert result.dataset().sizes["case"] == 8 * (2 + 2)
    peak = result.sensitivity["peak_torque_Nm"]
    assert peak["method"] == "sobol" and peak["ranking"][0] == "u_max"
    assert peak["indices"]["u_max"]["ST"] > peak["indices"]["alpha"]["ST"]
    out = write_report(result, tmp_path / "report")
    assert "S_T" in (out / "index.html").read_text()
    with pytest.raises(ScenarioError, match="cases: the Saltelli design takes a power of 2"):
        load_scenario(_write(tmp_path, "bad.yaml", text.replace("cases: 8", "cases: 6")))


def test_ctrl_c_on_the_command_line_keeps_the_finished_cases_and_the_same_command_resumes(tmp_path):
    """SIGINT to the ``flexsat run`` process itself, after some chunks have finished: it exits 130
    saying how many cases the store keeps; the same command then completes the store, which
    equals an uninterrupted run's case for case (nothing missing, nothing twice)."""
    import signal
    import subprocess
    import sys

    grid = SWEEP.replace("execution: {chunk_size: 4}", "execution: {chunk_size: 1}").replace(
        '["300 ozf*in", "400 ozf*in", "500 ozf*in"]',
        '["300 ozf*in", "350 ozf*in", "400 ozf*in", "450 ozf*in", "500 ozf*in", "550 ozf*in"]',
    )
    path = _write(tmp_path, "sweep.yaml", grid)
    command = [sys.executable, "-m", "flexsat.cli", "run", str(path), "-o", str(tmp_path / "out")]
    # a shell or CI runner may start us with SIGINT ignored, which a child would inherit
    run = subprocess.Popen(
        command,
        stderr=subprocess.PIPE,
        stdout=subprocess.DEVNULL,
        text=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    for line in run.stderr:  # one progress line per chunk (stderr is not a terminal)
        if line.startswith("[4/"):  # 3 of the 12 one-case chunks are in the store
            run.send_signal(signal.SIGINT)
            break
    err = run.stderr.read()
    assert run.wait(timeout=60) == 130, err
    assert "Traceback" not in err
    kept = int(err.split("interrupted: ")[1].split(" of 12 cases")[0])
    assert 3 <= kept < 12
    store = tmp_path / "store.zarr"
    assert xr.open_zarr(store, consolidated=False)["done"].values.sum() == kept
    assert not (tmp_path / "out").exists()

    again = subprocess.run(command, capture_output=True, text=True, timeout=120)
    assert again.returncode == 0, again.stderr
    resumed = xr.open_zarr(store, consolidated=False).load()
    assert resumed["done"].values.all()
    whole = load_scenario(path).model_copy(update={"store": str(tmp_path / "whole.zarr")})
    whole._source, whole._folder = load_scenario(path)._source, tmp_path
    reference = run_scenario(whole).dataset().load()
    for name in reference.data_vars:
        np.testing.assert_array_equal(resumed[name].values, reference[name].values, name)


def test_the_default_store_is_named_after_the_run_s_fingerprint(tmp_path, monkeypatch):
    """Without ``store:``, the store sits in the temporary folder under the run's fingerprint:
    the same run resumes it, and the same scenario text run by a flexsat that fills stores
    differently (here: another store layout) gets a store of its own instead of an error
    about a store it must refuse (what a fresh clone met with a store left by an older
    version)."""
    import tempfile

    import flexsat.design.batch_runner as runner

    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path / "tmp"))
    (tmp_path / "tmp").mkdir()
    path = _write(tmp_path, "sweep.yaml", SWEEP.replace("store: store.zarr\n", ""))
    first = run_scenario(load_scenario(path))
    assert first.store.parent == tmp_path / "tmp" and first.chunks_run == 2
    assert run_scenario(load_scenario(path)).chunks_run == 0  # resumed: nothing to do
    monkeypatch.setattr(runner, "STORE_LAYOUT", runner.STORE_LAYOUT + "-next")
    other = run_scenario(load_scenario(path))
    assert other.store != first.store and other.chunks_run == 2


def test_a_diverged_case_is_a_divergence_named_by_its_case_in_the_sweep(tmp_path):
    # a rate gain of 1e5 N m s/rad at 50 Hz with the torque unbounded: g2 dt / J >> 2, the
    # sampled loop is unstable; the last of the four cases, alone in its chunk, is case 3
    text = (
        SWEEP.replace(
            "alpha: {values: [0.0, 0.25]}", 'g2: {values: ["800 ozf*in*s/rad", "1e5 N*m*s/rad"]}'
        )
        .replace(
            'u_max: {values: ["300 ozf*in", "400 ozf*in", "500 ozf*in"]}',
            'saturation: {values: ["400 ozf*in", "1e9 N*m"]}',
        )
        .replace("chunk_size: 4", "chunk_size: 1")
    )
    with pytest.raises(SimulationDiverged) as err:
        run_scenario(load_scenario(_write(tmp_path, "sweep.yaml", text)))
    assert err.value.cases == (3,) and "in case(s) 3:" in str(err.value)
