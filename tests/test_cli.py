"""Command line (flexsat.cli) through typer's CliRunner."""

from __future__ import annotations

import errno
import json
import os
from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

from flexsat.cli import app, parse_settings, parse_value
from flexsat.scenarios import default_scenario
from flexsat.units import to_si

runner = CliRunner()


def write_scenario(path, **simulation) -> str:
    """A short Law I / Law II scenario file (3 modes, 2 s) with ``simulation`` changes."""
    data = yaml.safe_load(default_scenario().yaml_text)
    data["model"]["n_modes"] = 3
    data["simulation"].update({"duration": "2 s", **simulation})
    path.write_text(yaml.safe_dump(data))
    return str(path)


def test_cases_lists_every_case_with_its_source():
    """Sources are cited by authors and year, never by the developers' seed file names; the
    built-in cases come first, then the plug-ins' (tests/test_example_plugin.py)."""
    from flexsat.cases import CASES
    from flexsat.catalog import all_cases
    from flexsat.references import cite

    result = runner.invoke(app, ["cases", "--json"])
    assert result.exit_code == 0
    listed = {row["case"]: row for row in json.loads(result.stdout)}
    assert list(listed) == list(all_cases()) and list(listed)[: len(CASES)] == list(CASES)
    for info in CASES.values():
        assert listed[info.name]["source"] == cite(info.source)
        assert ".txt" not in listed[info.name]["source"]
    assert listed["tamu"]["source"].startswith("Junkins, Pollock & Rahman 1990, Att. 3")
    assert "Large Angle Maneuvers of Flexible Structures" in listed["tamu"]["references"][0]
    table = runner.invoke(app, ["cases"])
    assert table.exit_code == 0 and "flexsat cases" in table.stdout
    assert ".txt" not in table.stdout and "Bainum & Reddy 1979:" in table.stdout


def test_modes_json():
    result = runner.invoke(
        app,
        [
            "modes",
            "tamu",
            "--modes",
            "3",
            "--json",
            "--set",
            "n_modes=4",
            "--set",
            "hub_inertia=30 ozf*in*s**2",
        ],
    )
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    assert len(data["frequencies_hz"]) == len(data["constrained_hz"]) == 3
    assert data["frequencies_hz"] == sorted(data["frequencies_hz"])
    # a light hub: each hub-free frequency lies above the clamped one
    assert all(f > c for f, c in zip(data["frequencies_hz"], data["constrained_hz"]))
    # the 4-mode model's first frequency is within 0.1 % of the exact one, and above it
    exact, model = data["exact_unconstrained_hz"][0], data["frequencies_hz"][0]
    assert exact <= model < 1.001 * exact
    budget = data["inertia_budget_kg_m2"]
    assert budget["hub"] == pytest.approx(to_si("30 ozf*in*s**2", "kg*m**2"))
    assert budget["total_model"] == pytest.approx(
        budget["hub"] + budget["beams"] + budget["tip_masses"]
    )


def test_modes_table():
    result = runner.invoke(app, ["modes", "tamu", "-n", "2", "--set", "n_modes=2"])
    assert result.exit_code == 0, result.output
    assert "hub clamped" in result.stdout and "published_total" in result.stdout


@pytest.mark.parametrize(
    "args, expected",
    [
        (["modes", "tamu", "--set", "hub_inertia=-1"], "hub_inertia: must be > 0"),
        (["modes", "tamu", "--set", "hub_inertia"], "--set: expected NAME=VALUE"),
        (["modes", "tamu", "-n", "12"], "n_modes: the model has 10 modes"),
        (["modes", "nope"], "case: unknown case 'nope'"),
    ],
)
def test_modes_errors_exit_2(args, expected):
    result = runner.invoke(app, args)
    assert result.exit_code == 2
    assert expected in result.stderr


def test_set_values():
    assert parse_value("3") == 3 and isinstance(parse_value("3"), int)
    assert parse_value("1e-3") == 1e-3
    assert parse_value("False") is False
    assert parse_value("30 ozf*in*s**2") == "30 ozf*in*s**2"
    assert parse_settings(["a=1", "b = 2 deg"]) == {"a": 1, "b": "2 deg"}


def test_run_writes_the_report(tmp_path):
    out = tmp_path / "out"
    result = runner.invoke(app, ["run", write_scenario(tmp_path / "s.yaml"), "-o", str(out)])
    assert result.exit_code == 0, result.output
    assert "Law II" in result.stdout and "peak_torque_Nm" in result.stdout
    # progress on stderr (a line per step off a terminal): one step per run
    assert "[2/2] running Law II ..." in result.stderr and "done (2/2 steps)" in result.stderr
    assert {"metrics.json", "results.nc", "index.html"} <= {p.name for p in out.iterdir()}
    # the provenance line names the command as typed (the program without its folder)
    page = (out / "index.html").read_text()
    assert f"-o {out}</code>" in page and "s.yaml" in page
    records = json.loads((out / "metrics.json").read_text())
    assert [r["run"] for r in records] == ["Law I", "Law II"]
    assert {"settling_time_s", "overshoot_deg", "peak_torque_Nm", "residual_energy_J"} <= set(
        records[0]
    )


def test_bad_scenario_exits_2_and_writes_nothing(tmp_path):
    out = tmp_path / "out"
    path = write_scenario(tmp_path / "s.yaml", integration_step="20 ms")
    result = runner.invoke(app, ["run", path, "-o", str(out)])
    assert result.exit_code == 2
    assert "simulation.integration_step: must be smaller than the control period" in result.stderr
    assert not out.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.yaml"]


def test_missing_scenario_file_exits_2(tmp_path):
    result = runner.invoke(app, ["run", str(tmp_path / "none.yaml"), "-o", str(tmp_path / "o")])
    assert result.exit_code == 2
    assert "cannot read" in result.stderr


def test_run_identification_scenario_prints_modes_and_writes_report(
    tmp_path, identification_example
):
    path = tmp_path / "id.yaml"
    path.write_text(yaml.safe_dump(identification_example(fast=True)))
    out = tmp_path / "out"
    result = runner.invoke(app, ["run", str(path), "-o", str(out)])
    assert result.exit_code == 0, result.output
    assert "identified modes" in result.stdout and "clamp verticals" in result.stdout
    # progress: three simulated tests, then four identification steps, all announced
    assert "[1/7] running hammer test ..." in result.stderr
    assert "[7/7] running model update ..." in result.stderr and "(7/7 steps)" in result.stderr
    assert {"index.html", "frf.png", "mac.png", "results.nc"} <= {p.name for p in out.iterdir()}


def test_run_recorded_identification_scenario(tmp_path, recorded_scenario):
    """Measured tests (UFF 58) in, report out: the truth columns read "–"."""
    path = recorded_scenario(tmp_path)
    out = tmp_path / "out"
    result = runner.invoke(app, ["run", str(path), "-o", str(out)])
    assert result.exit_code == 0, result.output
    # progress on stderr: the campaign's four identification steps, all announced, and no
    # simulated test (the tests are recorded)
    assert "[1/4] running hammer test: ERA ..." in result.stderr
    assert "done (4/4 steps)" in result.stderr
    assert "of nominal" in result.stdout
    assert "<td>–</td>" in (out / "index.html").read_text()


def unwrapped(text: str) -> str:
    """``text`` as printed before rich wrapped it to the terminal width (its line breaks fall at
    a space it keeps, or inside a word too long for a line)."""
    return text.rstrip("\n").replace("\n", "")


def _probe_raises(monkeypatch, code):
    """Creating the probe file in the output folder's parent raises OSError(code), as on a
    read-only (EROFS) or full (ENOSPC) file system (tests run as root, whom chmod does not
    stop)."""
    real = os.open

    def guarded(path, flags, *args, **kwargs):
        if ".probe-" in os.fspath(path):
            raise OSError(code, os.strerror(code), os.fspath(path))
        return real(path, flags, *args, **kwargs)

    monkeypatch.setattr(os, "open", guarded)


@pytest.mark.parametrize(
    "code, reason",
    [
        (errno.EROFS, "Read-only file system"),
        (errno.ENOSPC, "No space left on device"),
        (errno.EDQUOT, "Disk quota exceeded"),
    ],
)
def test_run_refuses_an_unwritable_out_before_simulating(tmp_path, monkeypatch, code, reason):
    _probe_raises(monkeypatch, code)
    out = tmp_path / "out"
    result = runner.invoke(app, ["run", write_scenario(tmp_path / "s.yaml"), "-o", str(out)])
    assert result.exit_code == 2, result.output
    message = unwrapped(result.stderr)
    assert message.startswith(f"--out: cannot write the report to '{out}': {reason}")
    assert "running" not in result.stdout + result.stderr  # nothing simulated
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.yaml"]


def test_run_refuses_a_file_as_out(tmp_path):
    (tmp_path / "taken").write_text("x")
    for out in (tmp_path / "taken", tmp_path / "taken" / "out"):
        result = runner.invoke(app, ["run", "-o", str(out)])
        assert result.exit_code == 2, result.output
        message = unwrapped(result.stderr)
        assert message.startswith("--out: ") and "is a file, not a folder" in message
        assert "running" not in result.stdout + result.stderr


def test_run_disk_full_while_publishing_exits_2_and_keeps_the_earlier_report(
    tmp_path, fail_opening
):
    out = tmp_path / "out"
    path = write_scenario(tmp_path / "s.yaml")
    assert runner.invoke(app, ["run", path, "-o", str(out)]).exit_code == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    fail_opening("results.nc")
    result = runner.invoke(
        app, ["run", write_scenario(tmp_path / "s.yaml", duration="1 s"), "-o", str(out)]
    )
    assert result.exit_code == 2, result.output
    assert "Law II" in result.stdout  # simulated, then the write failed
    message = unwrapped(result.stderr).split("done (2/2 steps)")[-1]  # after the progress lines
    assert message.startswith(f"--out: cannot write the report to '{out}': No space left on device")
    assert "free some space or choose another folder" in message
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out", "s.yaml"]


@pytest.mark.skipif(not os.path.isdir("/proc/self"), reason="needs Linux's /proc")
def test_run_refuses_a_location_where_nothing_can_be_created():
    """procfs refuses every new file, for root too: a real unwritable location."""
    result = runner.invoke(app, ["run", "-o", "/proc/flexsat-report"])
    assert result.exit_code == 2, result.output
    assert unwrapped(result.stderr).startswith(
        "--out: cannot write the report to '/proc/flexsat-report': "
    )
    assert "running" not in result.stdout + result.stderr


def test_modes_refuses_more_modes_than_the_limit():
    result = runner.invoke(app, ["modes", "tamu", "--modes", "1000000"])
    assert result.exit_code == 2
    assert unwrapped(result.stderr).startswith(
        "--modes: modes asked for = 1e+06, above the limit 100 (flexsat.limits)"
    )


def test_the_metrics_table_puts_the_longer_list_down_the_rows():
    """A few runs: a column per run. A batch's many summary rows (a row per metric and per
    requirement, a few statistics each): a column per statistic, so the table fits a terminal."""
    from rich.console import Console

    from flexsat.cli import _result_table
    from flexsat.report.page import metrics_table

    def shown(records):
        console = Console(width=100, record=True)
        console.print(_result_table(metrics_table(records)))
        return console.export_text().splitlines()

    runs = [
        {"run": "Law I", "overshoot_deg": 1.5, "settling_time_s": 3.0},
        {"run": "Law II", "overshoot_deg": 0.5, "settling_time_s": 2.0},
    ]
    header = next(line for line in shown(runs) if "Law II" in line)
    assert "metric" in header and "Law I" in header
    batch = [{"run": f"metric_{i}", "p5": 1.0, "median": 2.0, "p95": 3.0} for i in range(5)]
    lines = shown(batch)
    assert any("p5" in line and "median" in line and "p95" in line for line in lines)
    assert sum(line.count("metric_") for line in lines) == 5  # one row each


def test_workers_are_asked_of_the_kind(tmp_path):
    """--workers/--scheduler: a kind that runs no batch refuses them (naming the kinds that
    take them); a batch kind refuses both at once; nothing runs either way."""
    done = runner.invoke(app, ["run", "--workers", "2", "--out", str(tmp_path / "a")])
    assert done.exit_code == 2
    assert (
        "--workers/--scheduler: a maneuver scenario runs in this process; they apply to the "
        "kinds design, montecarlo, sweep"
    ) in unwrapped(done.stderr)
    batch = Path(__file__).parents[1] / "examples" / "tamu_montecarlo.yaml"
    done = runner.invoke(
        app,
        ["run", str(batch), "--workers", "2", "--scheduler", "tcp://localhost:1"]
        + ["--out", str(tmp_path / "b")],
    )
    assert done.exit_code == 2
    assert "--workers/--scheduler: give one (a local cluster or an existing one), not both" in (
        done.stderr
    )
    assert not (tmp_path / "a").exists() and not (tmp_path / "b").exists()
