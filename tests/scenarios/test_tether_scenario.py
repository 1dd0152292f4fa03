"""Tether scenarios (kind: tether, issue 14): Vadali & Kim's retrieval as a scenario file; the
example reruns controllers 1 and 2 and the rate law with the published numbers (V10-V13, V15);
the sampled integrator (the simulation core, commands held) approaches the continuous one; and
each mistake is reported as ``field.path: rule`` before anything runs."""

from pathlib import Path

import numpy as np
import pytest

from flexsat.scenarios import ScenarioError, TetherScenario, load_scenario, run_scenario

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "tether_retrieval.yaml"

SMALL = """
kind: tether
name: small tether
system: {mass: 22.7 kg, length: 20 km, altitude: 220 km}
initial: {length: 20 km, pitch: 5 deg, roll: 5 deg}
simulation: {orbits: 2, samples_per_orbit: 500, integrator: continuous}
runs:
  - label: coupled
    law: coupled
    gains: {K1: 1.0, K2: 0.0, K3: 3.0, K4: 2.0}
    final_length: 200 m
  - label: rate
    law: rate
    gains: {K1: 0.25, K2: 0.01, K3: 1.0}
    final_length: 0.2 km
"""


@pytest.fixture(scope="module")
def example():
    return run_scenario(load_scenario(EXAMPLE))


def test_the_example_reproduces_the_published_retrievals(example):
    rows = {r["run"]: r for r in example.metrics_records()}
    assert len(rows) == 6
    c1, c2, c2k3 = (
        rows["controller 1 (Figs. 2-3)"],
        rows["controller 2, K4 = 2 (Figs. 4-5)"],
        rows["controller 2, K4 = 3"],
    )
    # V10: T̂(0) = 3.96 ("4"), settled in 1.55 orbits ("nearly two")
    assert c1["initial_tension"] == pytest.approx(4.0, abs=0.05)
    assert 1.4 < c1["settling_orbits"] < 2.0
    # V11, V12 (the bands of tests/control/test_tether_laws.py)
    assert c2["thrust_index_2_orbits"] == pytest.approx(0.24, abs=0.01)
    assert c2["max_pitch_deg"] == pytest.approx(29.3, abs=0.2)
    assert c2k3["thrust_index_2_orbits"] == pytest.approx(0.258, abs=0.002)
    # V13: over the top with K1 = 1, 21.9° with K1 = 0.9
    assert rows["controller 2 to 20 m, K1 = 1.0 (Fig. 6)"]["max_pitch_deg"] > 180
    assert rows["controller 2 to 20 m, K1 = 0.9 (Fig. 7)"]["max_pitch_deg"] == pytest.approx(
        21.9, abs=0.1
    )
    # V15: 5.83 m/s, not the printed 30
    rate = rows["rate law (Fig. 8)"]
    assert rate["initial_rate_m_s"] == pytest.approx(5.83, abs=0.005)
    assert rate["initial_tension"] is None and c1["initial_rate_m_s"] is None
    # the final lengths in metres: λf L = 200 m and 20 m
    assert c2["final_length_m"] == pytest.approx(200, rel=0.01)


def test_sampled_runs_approach_the_continuous_ones():
    # The simulation core with the commands held 500 and 2000 times an orbit: the max pitch
    # error falls more than 4× (first-order hold error, tests/control/test_tether_laws.py)
    spec = load_scenario(SMALL)
    continuous = run_scenario(spec).metrics_records()
    errors = []
    for n in (500, 2000):
        sim = spec.simulation.model_copy(update={"integrator": "sampled", "samples_per_orbit": n})
        sampled = run_scenario(spec.model_copy(update={"simulation": sim})).metrics_records()
        errors.append(abs(sampled[0]["max_pitch_deg"] - continuous[0]["max_pitch_deg"]))
        # the rate law's commanded rate is exact at the first sample either way
        assert sampled[1]["initial_rate_m_s"] == pytest.approx(
            continuous[1]["initial_rate_m_s"], rel=1e-12
        )
    assert errors[1] < errors[0] / 4


def test_units_are_converted_and_the_orbit_rate_may_be_given():
    spec = load_scenario(SMALL.replace("altitude: 220 km", "orbit_rate: 0.07068 rad/min"))
    assert isinstance(spec, TetherScenario)
    assert spec.system.scales().orbit_rate == pytest.approx(0.07068 / 60)
    assert spec.initial.pitch == pytest.approx(np.radians(5))
    assert spec.runs[1].final_length == pytest.approx(200.0)


def test_flexsat_run_dispatches_kind_tether(tmp_path):
    from typer.testing import CliRunner

    from flexsat.cli import app

    path = tmp_path / "tether.yaml"
    path.write_text(SMALL)
    out = tmp_path / "report"
    result = CliRunner().invoke(app, ["run", str(path), "-o", str(out)])
    assert result.exit_code == 0, result.output
    assert "thrust_index" in result.output
    assert (out / "index.html").is_file() and (out / "libration.png").is_file()


@pytest.mark.parametrize(
    "change, message",
    [
        (("mass: 22.7 kg", "mass: 0 kg"), "system.mass: must be > 0"),
        (("mass: 22.7 kg", "mass: 22.7 m"), "system.mass"),
        (("length: 20 km, alt", "length: -20 km, alt"), "system.length: must be > 0"),
        (("altitude: 220 km", "altitude: -220 km"), "system.altitude: must be >= 0"),
        (("altitude: 220 km", "altitude: 220 km, orbit_rate: 0.001"), "not both"),
        (
            ("{mass: 22.7 kg, length: 20 km, altitude: 220 km}", "{mass: 22.7 kg, length: 20 km}"),
            "system.altitude: give the orbit's altitude or its orbit_rate",
        ),
        (("initial: {length: 20 km", "initial: {length: 0 km"), "initial.length: must be > 0"),
        (("pitch: 5 deg", "pitch: 5 kg"), "initial.pitch"),
        (("orbits: 2", "orbits: 0"), "simulation.orbits"),
        (("samples_per_orbit: 500", "samples_per_orbit: 5"), "simulation.samples_per_orbit"),
        (("integrator: continuous", "integrator: euler"), "simulation.integrator"),
        (("law: coupled", "law: fuzzy"), r"runs\['coupled'\].law"),
        (
            ("K3: 3.0, K4: 2.0", "K3: 3.0"),
            r"runs\['coupled'\].gains: law 'coupled' takes K1, K2, "
            r"K3, K4; missing K4",
        ),
        (
            ("{K1: 0.25, K2: 0.01, K3: 1.0}", "{K1: 0.25, K2: 0.01, K3: 1.0, K5: 1}"),
            r"runs\['rate'\].gains: .*unknown K5",
        ),
        (
            ("K1: 1.0, K2: 0.0, K3: 3.0, K4", "K1: 0.0, K2: 0.0, K3: 3.0, K4"),
            r"runs\['coupled'\].gains: K1 must be finite and > 0",
        ),
        (("K4: 2.0", "K4: -2.0"), r"runs\['coupled'\].gains: K4 must be finite and >= 0"),
        (
            ("final_length: 200 m", "final_length: -200 m"),
            r"runs\['coupled'\].final_length: must "
            r"be > 0",
        ),
        (("final_length: 0.2 km", "final_length: 0.2 kg"), r"runs\['rate'\].final_length"),
        (
            ("final_length: 200 m", "final_length: 200 m\n    printed_sign: true"),
            r"runs\['coupled'\].printed_sign: only the decoupled law",
        ),
        (("roll: 5 deg}", "roll: 5 deg, length_rate: 1 m/s}"), "initial.length_rate: a rate-law"),
        (("label: rate", "label: coupled"), "runs: duplicate label 'coupled'"),
        (("name: small tether", "name: small tether\ncolour: red"), "colour: unknown key"),
    ],
)
def test_bad_input_is_reported_by_field(change, message):
    with pytest.raises(ScenarioError, match=message):
        load_scenario(SMALL.replace(*change))


def test_a_collapsing_tether_is_named_by_its_run():
    # Without angular momentum (pitch rate −Ω: not turning inertially; no roll) nothing holds
    # the subsatellite off the centre: thrown inward at 5 km/s (212 LΩ) it reaches 1e-4 L
    # before the law can brake it. (With the orbit's angular momentum the centrifugal barrier
    # stops it first, at λ ~ 1/|λ'|.)
    text = SMALL[: SMALL.index("  - label: rate")].replace(
        "pitch: 5 deg, roll: 5 deg}",
        "pitch: 0 deg, roll: 0 deg, pitch_rate: -0.070678 rad/min, length_rate: -5 km/s}",
    )
    with pytest.raises(
        ScenarioError,
        match=r"runs\['coupled'\].length: the tether collapsed "
        r"\(length below 0.0001 L\) at t = 4\.03 s",
    ):
        run_scenario(load_scenario(text))
    # a final length at or below that threshold is refused before the run
    with pytest.raises(
        ScenarioError,
        match=r"runs\['rate'\].final_length: 1 mm is below the "
        r"collapse threshold",
    ):
        run_scenario(load_scenario(SMALL.replace("final_length: 0.2 km", "final_length: 1 mm")))
