"""Plug-ins through entry points (flexsat.plugins, docs/plugins.md): the example package in
tests/plugin_package adds a scenario kind, a plant, a law, a case and a check that the command
line uses like the built-in ones; a broken or colliding plug-in is named on stderr and breaks
no command.

The example package must be installed (``make test`` does it: ``pip install -e
tests/plugin_package``); the broken plug-ins are declared by a package written into a temporary
folder and put on the path of a fresh interpreter only, so that they never reach the other
tests.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import textwrap
from importlib.metadata import PackageNotFoundError, distribution
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

import flexsat
from flexsat.cli import app

SRC = Path(flexsat.__file__).resolve().parents[1]
PACKAGE = Path(__file__).resolve().parent / "plugin_package"
SCENARIO = PACKAGE / "scenarios" / "two_mass_bang_off_bang.yaml"
NOT_INSTALLED = (
    "the example plug-in package flexsat-example-plugin is not installed in this environment: "
    "run `pip install -e tests/plugin_package` (`make test` does it after the dev extras)"
)
runner = CliRunner()


@pytest.fixture(scope="module")
def example_plugin():
    try:
        return distribution("flexsat-example-plugin")
    except PackageNotFoundError:
        pytest.fail(NOT_INSTALLED)


def test_the_example_plugin_is_installed(example_plugin):
    groups = {(p.group, p.name) for p in example_plugin.entry_points}
    assert groups == {
        ("flexsat.kinds", "pulse_tuning"),
        ("flexsat.plants", "two_mass_spring"),
        ("flexsat.laws", "bang_off_bang"),
        ("flexsat.cases", "wie_bernstein"),
        ("flexsat.checks", "wie_bernstein"),
    }


def test_the_registries_merge_the_built_ins_with_the_plugins(example_plugin):
    from flexsat_example_plugin.check import ELASTIC_FREQUENCY
    from flexsat_example_plugin.law import BangOffBang
    from flexsat_example_plugin.plant import TwoMassSpring

    from flexsat.catalog import CASES, all_cases
    from flexsat.checks import plugin_checks
    from flexsat.plugins import broken_plugins
    from flexsat.scenarios.simulation_laws import BUILTIN_LAWS, simulation_laws
    from flexsat.scenarios.simulation_plants import simulation_cases, simulation_plants

    laws = simulation_laws()
    assert list(laws) == [*BUILTIN_LAWS, "bang_off_bang"] and laws["bang_off_bang"] is BangOffBang
    plants = simulation_plants()
    assert list(plants) == [*simulation_cases(), "two_mass_spring"]
    assert plants["two_mass_spring"] is TwoMassSpring
    cases = all_cases()
    assert list(cases) == [*CASES, "wie_bernstein"]
    assert cases["wie_bernstein"].builder().frequencies_hz(2)[1] == pytest.approx(
        math.sqrt(2) / (2 * math.pi), rel=1e-15
    )
    assert plugin_checks() == [ELASTIC_FREQUENCY]
    assert broken_plugins() == []


def _tail(ds, run: str) -> tuple[float, float, float, float]:
    end = ds.sel(run=run).isel(time=-1)
    return tuple(float(end[name]) for name in ("x1", "x2", "v1", "v2"))


def test_the_plugin_law_and_plant_run_by_name_from_a_scenario_file(example_plugin, tmp_path):
    """``flexsat run`` of tests/plugin_package/scenarios/two_mass_bang_off_bang.yaml.

    Analytic result (law.py, plant.py): the centre of mass moves d = F t1 (t1 + tc) / (m1 + m2)
    and the elastic mode (ω = 2π rad/s) is left with the amplitude
    A = 4 F |sin(ω t1 / 2) sin(ω (t1 + tc) / 2)| / (m1 ω²): zero for the tuned pulses
    (t1 = 1 s, one period), 1 / (2π²) m = 0.051 m for the mistuned ones (t1 = 0.75 s).
    The exponential integrator is exact for a force held over each sample, so what is left is
    round-off of 400 steps on metre-sized states (~1e-13 m); the bound is 1e-9 m.
    """
    import xarray as xr

    out = tmp_path / "out"
    result = runner.invoke(app, ["run", str(SCENARIO), "-o", str(out)])
    assert result.exit_code == 0, result.output
    omega, force, m = 2 * math.pi, 1.0, 1.0
    with xr.open_dataset(out / "results.nc", engine="h5netcdf") as ds:
        for run, t1, tc in (("tuned", 1.0, 0.5), ("mistuned", 0.75, 0.5)):
            x1, x2, v1, v2 = _tail(ds, run)
            d = force * t1 * (t1 + tc) / (2 * m)
            amplitude = 4 * force * abs(math.sin(omega * t1 / 2) * math.sin(omega * (t1 + tc) / 2))
            amplitude /= m * omega**2
            # centre of mass: at d, at rest
            assert abs((x1 + x2) / 2 - d) < 1e-9 and abs((v1 + v2) / 2) < 1e-9, run
            # elastic mode z = x1 - x2 (its velocity over ω: the same unit)
            assert abs(math.hypot(x1 - x2, (v1 - v2) / omega) - amplitude) < 1e-9, run
    assert amplitude > 0.05  # the mistuned run does vibrate: the test tells them apart


def test_the_plugin_kind_runs_from_its_scenario_file(example_plugin, tmp_path):
    """``flexsat run`` of tests/plugin_package/scenarios/pulse_tuning.yaml: a kind that flexsat
    does not know, found through its entry point. Its measured residual amplitude equals the
    closed form A = 4 F |sin(ω t1 / 2) sin(ω (t1 + tc) / 2)| / (m1 ω²) computed here (ω = 2π
    rad/s, F = 1 N, m1 = 1 kg, tc = 0.3 s) to the round-off bound of the previous test."""
    from flexsat.scenarios.kind import scenario_kinds

    assert scenario_kinds()["pulse_tuning"].__module__ == "flexsat_example_plugin.kind"
    out = tmp_path / "out"
    scenario = PACKAGE / "scenarios" / "pulse_tuning.yaml"
    result = runner.invoke(app, ["run", str(scenario), "-o", str(out)])
    assert result.exit_code == 0, result.output
    records = json.loads((out / "metrics.json").read_text())
    omega, tc = 2 * math.pi, 0.3
    for record, t1 in zip(records, (0.5, 0.75, 1.0)):
        expected = 4 * abs(math.sin(omega * t1 / 2) * math.sin(omega * (t1 + tc) / 2)) / omega**2
        assert abs(record["residual_amplitude_m"] - expected) < 1e-9, record
    assert records[0]["residual_amplitude_m"] > 0.05 and records[2]["residual_amplitude_m"] < 1e-9
    assert "Residual vibration" in (out / "index.html").read_text()


def test_the_plugin_law_batches_over_a_leading_case_axis(example_plugin):
    """Three forces in one call: three rest-to-rest moves d = F t1 (t1 + tc) / (m1 + m2) (the
    same analytic result and round-off bound as the scenario above)."""
    from flexsat_example_plugin.law import BangOffBang
    from flexsat_example_plugin.plant import TwoMassSpring

    from flexsat.sim import SimConfig, simulate

    plant = TwoMassSpring(1.0, 1.0, 2 * math.pi**2)
    config = SimConfig(duration=3.0, control_rate=100.0)
    forces = np.array([0.5, 1.0, -2.0])
    law = BangOffBang(forces, 1.0, 0.5, dt=config.dt)
    assert law.n_cases == 3
    ds = simulate(plant, law, config).dataset
    end = ds.isel(time=-1)
    np.testing.assert_allclose(end["x1"].values, forces * 1.0 * 1.5 / 2, rtol=0, atol=1e-9)
    np.testing.assert_allclose(end["x2"].values, forces * 1.0 * 1.5 / 2, rtol=0, atol=1e-9)
    np.testing.assert_allclose(end["v1"].values, 0.0, rtol=0, atol=1e-9)


def test_plugin_parameters_are_checked_with_field_paths(example_plugin):
    from flexsat.scenarios import ScenarioError, load_scenario, run_scenario

    base = SCENARIO.read_text()
    mistakes = [
        ('k: "19.739208802178716 N/m"', 'k: "-1 N/m"', "plant.k: must be > 0"),
        ('k: "19.739208802178716 N/m"', 'k: "1 kg"', "plant.k"),
        (
            'm2: "1 kg"',
            'm2: "1 kg", spring: 1',
            "plant.spring: not an option of plant 'two_mass_spring' (its options: m1, m2, k, c)",
        ),
        ("name: two_mass_spring", "name: three_mass", "plant.name: unknown plant 'three_mass'"),
        ('force: "1 N", pulse_width: "1 s"', 'pulse_width: "1 s"', "gains.force: required by"),
        (
            'pulse_width: "1 s", coast',
            'pulse_width: "1 s", kp: 3, coast',
            "runs['tuned'].gains.kp: not a gain of law 'bang_off_bang' (its gains: force, "
            "pulse_width, coast)",
        ),
        ('pulse_width: "1 s"', 'pulse_width: "1.005 s"', "runs['tuned'].gains.pulse_width: must"),
        ('pulse_width: "1 s"', 'pulse_width: "1 N"', "runs['tuned'].gains.pulse_width"),
        ("law: bang_off_bang\n    gains: {force", "law: bang\n    gains: {force", "law 'bang'"),
    ]
    for old, new, message in mistakes:
        text = base.replace(old, new, 1)
        assert text != base, old
        with pytest.raises(ScenarioError) as info:
            run_scenario(load_scenario(text))
        assert message in str(info.value), (message, str(info.value))


def test_the_plugin_case_is_listed_by_flexsat_cases(example_plugin):
    from flexsat_example_plugin.case import WieBernstein

    listed = json.loads(runner.invoke(app, ["cases", "--json"]).stdout)
    row = next(r for r in listed if r["case"] == "wie_bernstein")
    assert row["description"] == WieBernstein.description
    assert row["source"] == WieBernstein.source and row is listed[-1]
    table = runner.invoke(app, ["cases"], terminal_width=200)
    assert table.exit_code == 0 and "wie_bernstein" in table.stdout


def test_the_plugin_check_is_shown_and_passes_in_flexsat_validate(example_plugin):
    result = runner.invoke(app, ["validate", "--case", "wie_bernstein", "--json"])
    assert result.exit_code == 0, result.output
    (row,) = json.loads(result.stdout)
    assert row["case"] == "wie_bernstein" and row["quantity"] == "elastic mode ω, nominal plant"
    assert row["published"] == 1.414214 and row["status"] == "pass"
    assert abs(row["computed"] - math.sqrt(2)) < 1e-12  # eig of a 4 x 4: round-off only
    table = runner.invoke(app, ["validate", "--case", "wie_bernstein"], terminal_width=200)
    assert table.exit_code == 0
    assert "wie_bernstein" in table.stdout and "1.414214" in table.stdout
    assert "1 checks: 1 passed" in table.stdout


# -- broken plug-ins -----------------------------------------------------------------------------
#: entry points of a package that gets everything wrong, and what stderr must say of each
BROKEN = {
    "flexsat.cases": {
        "missing_case": (
            "flexsat_no_such_module:Case",
            "ModuleNotFoundError: No module named 'flexsat_no_such_module'",
        ),
        "tamu": (
            "flexsat_example_plugin.case:WieBernstein",
            "its name is taken by the built-in case 'tamu' (flexsat.cases.tamu:tamu)",
        ),
    },
    "flexsat.checks": {
        "broken_check": (
            "flexsat_example_plugin.check:NO_SUCH_CHECK",
            "AttributeError",
        ),
    },
    "flexsat.laws": {
        "not_a_law": (
            "flexsat_example_plugin.case:WieBernstein",
            "Parameters: a scenario component needs a pydantic BaseModel subclass",
        ),
    },
    "flexsat.plants": {
        "eps": (
            "flexsat_example_plugin.plant:TwoMassSpring",
            "its name is taken by the plant of the case 'eps'",
        ),
    },
}


@pytest.fixture(scope="module")
def broken_package(tmp_path_factory) -> dict[str, str]:
    """The environment of an interpreter that also sees the broken package's entry points."""
    folder = tmp_path_factory.mktemp("broken")
    info = folder / "flexsat_broken_example-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(
        "Metadata-Version: 2.1\nName: flexsat-broken-example\nVersion: 0.1\n"
    )
    (info / "entry_points.txt").write_text(
        "".join(
            f"[{group}]\n" + "".join(f"{name} = {target}\n" for name, (target, _) in items.items())
            for group, items in BROKEN.items()
        )
    )
    path = [str(SRC), os.environ.get("PYTHONPATH", ""), str(folder)]
    return {**os.environ, "PYTHONPATH": os.pathsep.join(p for p in path if p)}


def _flexsat(env: dict[str, str], *args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "flexsat", *args],
        capture_output=True,
        text=True,
        env={**env, "COLUMNS": "200"},
        timeout=300,
    )


def _reported(stderr: str, group: str, name: str) -> bool:
    target, reason = BROKEN[group][name]
    line = f"warning: plug-in {name!r} ({group} = {target!r}) was not loaded: "
    return any(line in row and reason in row for row in stderr.splitlines())


def test_broken_plugins_are_named_and_flexsat_cases_still_works(example_plugin, broken_package):
    done = _flexsat(broken_package, "cases", "--json")
    assert done.returncode == 0, done.stderr
    listed = [row["case"] for row in json.loads(done.stdout)]
    assert listed.count("tamu") == 1 and "wie_bernstein" in listed
    assert "missing_case" not in listed
    for name in ("missing_case", "tamu"):
        assert _reported(done.stderr, "flexsat.cases", name), done.stderr


def test_broken_plugins_are_named_and_flexsat_validate_still_works(example_plugin, broken_package):
    done = _flexsat(broken_package, "validate", "--case", "wie_bernstein")
    assert done.returncode == 0, done.stderr
    assert "1 checks: 1 passed" in done.stdout
    assert _reported(done.stderr, "flexsat.checks", "broken_check"), done.stderr


def test_broken_plugins_are_named_and_flexsat_run_still_works(
    example_plugin, broken_package, tmp_path
):
    done = _flexsat(broken_package, "run", str(SCENARIO), "-o", str(tmp_path / "out"))
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "out" / "index.html").is_file()
    assert _reported(done.stderr, "flexsat.laws", "not_a_law"), done.stderr
    assert _reported(done.stderr, "flexsat.plants", "eps"), done.stderr
    # the built-in eps plant is the one a scenario still gets
    from flexsat.scenarios import load_scenario

    eps = textwrap.dedent("""
        kind: simulation
        name: rigid EPS at rest
        case: eps
        plant: {model: rigid}
        simulation: {duration: "1 s", control_rate: "10 Hz"}
        runs: [{label: a, law: open_loop}]
    """)
    (tmp_path / "eps.yaml").write_text(eps)
    done = _flexsat(broken_package, "run", str(tmp_path / "eps.yaml"), "-o", str(tmp_path / "e"))
    assert done.returncode == 0, done.stderr
    assert load_scenario(eps).plant[0] == "eps"


def test_light_commands_stay_light_with_the_plugins(example_plugin, broken_package):
    """``flexsat cases`` reads the flexsat.cases group only, whose modules import nothing
    numerical (tests/test_cli_startup.py measures the same without plug-ins)."""
    heavy = ("numpy", "scipy", "flexsat.scenarios", "flexsat.checks", "flexsat.cases")
    code = (
        "import sys\nfrom flexsat.cli import app\n"
        "try:\n    app(['cases'], prog_name='flexsat')\nexcept SystemExit:\n    pass\n"
        f"print(sorted(m for m in {heavy!r} if m in sys.modules))"
    )
    done = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        env=broken_package,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip().splitlines()[-1] == "[]", done.stdout


def test_a_law_that_builds_no_controller_is_refused(example_plugin, monkeypatch):
    """The registry checks the protocol's shape; the runner checks what from_scenario gives."""
    from flexsat_example_plugin.law import BangOffBang

    import flexsat.scenarios.simulation as simulation
    from flexsat.scenarios import ScenarioError, load_scenario, run_scenario

    class Sloppy(BangOffBang):
        @classmethod
        def from_scenario(cls, parameters, context):
            return np.zeros(3)

    laws = {**simulation.simulation_laws(), "bang_off_bang": Sloppy}
    monkeypatch.setattr(simulation, "simulation_laws", lambda: laws)
    with pytest.raises(ScenarioError, match="law 'bang_off_bang' built a ndarray, not a"):
        run_scenario(load_scenario(SCENARIO))
