"""Simulation scenarios (kind: simulation): every example runs, and each mistake is reported
as ``field.path: rule`` before anything runs."""

from pathlib import Path

import numpy as np
import pytest

from flexsat.scenarios import ScenarioError, load_scenario, run_scenario, simulation_cases

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
SIMULATION_EXAMPLES = sorted(
    p for p in EXAMPLES.glob("*.yaml") if "kind: simulation" in p.read_text()
)

BASE = """
kind: simulation
name: test
case: eps
plant: {model: rigid}
initial: {euler123: ["10 deg", 0, 0]}
simulation: {duration: "2 s", control_rate: "10 Hz"}
runs:
  - {label: a, law: mrp_pd, gains: {K: "100 N*m", P: "1000 N*m*s/rad"}}
"""


def test_every_case_with_a_plant_ships_an_example():
    named = {load_scenario(p).case for p in SIMULATION_EXAMPLES}
    assert set(simulation_cases()) <= named, set(simulation_cases()) - named


@pytest.mark.parametrize("path", SIMULATION_EXAMPLES, ids=lambda p: p.stem)
def test_example_runs(path):
    result = run_scenario(load_scenario(path))
    ds = result.dataset()
    assert list(ds.run.values) == [run.label for run in result.scenario.runs]
    for name, var in ds.data_vars.items():
        assert np.all(np.isfinite(var.values)) or name.endswith("settling_time_s"), name


def test_the_rigid_slew_reaches_the_papers_attitude():
    """examples/eps_rigid_gibbs_slew.yaml: both laws end within 0.01° of (1, 1, 1) rad."""
    result = run_scenario(load_scenario(EXAMPLES / "eps_rigid_gibbs_slew.yaml"))
    for row in result.metrics_records():
        assert row["final_pointing_error_deg"] < 0.01, row


@pytest.mark.parametrize(
    "law, gains",
    [
        ("gibbs_lyapunov", '{k: "1000 N*m*s/rad", A: "50 N*m"}'),
        ("quaternion_pd", '{Kp: "100 N*m", Kd: "1000 N*m*s/rad"}'),
    ],
)
def test_every_attitude_law_builds_from_its_gains(law, gains):
    """Each attitude law of the table takes the gain names of its class and turns the
    spacecraft toward the target."""
    text = BASE.replace(
        'law: mrp_pd, gains: {K: "100 N*m", P: "1000 N*m*s/rad"}', f"law: {law}, gains: {gains}"
    )
    result = run_scenario(load_scenario(text))
    assert result.metrics_records()[0]["final_pointing_error_deg"] < 10.0


@pytest.mark.parametrize(
    "change, message",
    [
        (
            ("plant: {model: rigid}", "plant: {model: rigid, stiffness: 3}"),
            "plant.stiffness: not an option of the eps plant",
        ),
        (("plant: {model: rigid}", "plant: {model: wobbly}"), "plant.model: must be 'flexible'"),
        (
            ('initial: {euler123: ["10 deg", 0, 0]}', "initial: {spin: 1}"),
            "initial.spin: not an initial value of RigidSpacecraft",
        ),
        (
            ('initial: {euler123: ["10 deg", 0, 0]}', 'initial: {euler123: ["10 s", 0, 0]}'),
            "initial.euler123",
        ),
        (
            ("runs:", "sensors: {gyro: {noise: 1e-5}}\nruns:"),
            "sensors.gyro: the eps plant has no output channel 'gyro'",
        ),
        (
            ("runs:", 'actuators: {torque: {saturation: "-1 N*m"}}\nruns:'),
            "actuators.torque.saturation",
        ),
        (
            ('gains: {K: "100 N*m", P: "1000 N*m*s/rad"}', 'gains: {K: "100 N*m"}'),
            "gains.P: required by law 'mrp_pd'",
        ),
        (
            ('gains: {K: "100 N*m", P: "1000 N*m*s/rad"}', 'gains: {K: "100 N*m", kp: 1, P: 1}'),
            "gains.kp: not a gain of law 'mrp_pd'",
        ),
        (('gains: {K: "100 N*m", P: "1000 N*m*s/rad"}', 'gains: {K: "100 s", P: 1}'), "K"),
        (
            (
                'law: mrp_pd, gains: {K: "100 N*m", P: "1000 N*m*s/rad"}',
                "law: lqr, gains: {state_weights: 1}, target: {euler123: [1, 1, 1]}",
            ),
            "target: law 'lqr' takes no target",
        ),
        (("case: eps", "case: tamu"), "case: 'tamu' builds no plant to simulate"),
    ],
)
def test_mistakes_name_the_field(change, message):
    text = BASE.replace(*change)
    assert text != BASE
    with pytest.raises(ScenarioError, match=message.replace("(", r"\(").replace(")", r"\)")):
        run_scenario(load_scenario(text))


def test_report_has_a_figure_per_recorded_channel(tmp_path):
    from flexsat.report import write_report

    result = run_scenario(load_scenario(BASE))
    folder = write_report(result, tmp_path / "out")
    html = (folder / "index.html").read_text()
    plots = {p.title: p for p in result.plots(result.dataset())}
    for name in ("attitude", "rate", "torque"):
        # an interactive figure per channel, every run's every component a curve of it
        assert f'"text":"{name}"' in html
        width = result.dataset()[name].isel(run=0, time=0).size
        assert len(plots[name].curves) == width * len(result.labels)
    assert "Final pointing error (deg)" in html  # the metric's readable name, not its key
    assert not list(folder.glob("*.png"))


def test_open_loop_runs_on_a_plant_with_vector_channels():
    """The open loop reads the plant's first output and writes every input whatever their
    widths (the rigid EPS: a 4-wide attitude, a 3-wide torque); at rest it stays at rest."""
    text = BASE.replace(
        'law: mrp_pd, gains: {K: "100 N*m", P: "1000 N*m*s/rad"}', "law: open_loop"
    ).replace('initial: {euler123: ["10 deg", 0, 0]}\n', "")
    result = run_scenario(load_scenario(text))
    assert np.all(result.dataset()["torque"].values == 0)
