"""`flexsat validate` through typer's CliRunner (cheap cases and injected fake checks)."""

from __future__ import annotations

import json

import pytest
from rich.console import Console
from typer.testing import CliRunner

import flexsat.checks as checks_module
from flexsat.checks import COLUMNS, Check
from flexsat import cli
from flexsat.cli import app

runner = CliRunner()


def _raise():
    raise RuntimeError("solver did not converge")


FAKES = [
    Check("fake_ok", "a passing number", "seed 000_7bfdb62d2eacc22a.txt, L1", 1.0, "Hz",
          lambda: 1.0 + 1e-6, rtol=1e-3),
    Check("fake_bad", "a failing number", "seed 000_7bfdb62d2eacc22a.txt, L2", 1.0, "Hz",
          lambda: 2.0, rtol=1e-3, note="a documented deviation"),
    Check("fake_bad", "a crashing number", "seed 000_7bfdb62d2eacc22a.txt, L3", 1.0, "Hz",
          _raise, rtol=1e-3),
]


@pytest.fixture
def fakes(monkeypatch):
    monkeypatch.setattr(checks_module, "all_checks", lambda: list(FAKES))


def test_json_of_a_passing_case_exits_0():
    result = runner.invoke(app, ["validate", "--json", "--case", "exact_beam"])
    assert result.exit_code == 0, result.output
    rows = json.loads(result.stdout)
    assert len(rows) == 5
    for row in rows:
        assert set(COLUMNS) <= set(row)
        assert row["case"] == "exact_beam" and row["passed"] is True
        assert row["computed"] == pytest.approx(row["published"], rel=1e-9)
        assert "Blevins" in row["source"]


@pytest.mark.parametrize("width", [80, 200])
def test_table_of_passing_cases_exits_0(monkeypatch, width):
    """Narrow consoles stack each source under its quantity; wide ones give it a column."""
    monkeypatch.setattr(cli, "console", Console(width=width))
    result = runner.invoke(app, ["validate", "--case", "exact_beam", "--case", "nps"])
    assert result.exit_code == 0, result.output
    out = result.stdout
    assert "flexsat validate" in out and "exact_beam" in out and "nps" in out
    assert ("  case  " in out) is (width >= cli._WIDE_TABLE)
    assert "9 checks: 9 passed, 0 failed" in out
    assert "seed 001: ../shared/seeds/001_79dfdfba94ed8e0d.txt" in out  # abbreviation legend
    assert "EI solved to give it" in out  # the note of the fitted 0.14 Hz
    assert "seed 001_79dfdfba94ed8e0d.txt" not in out


def test_a_failing_check_exits_1_and_is_shown(fakes):
    result = runner.invoke(app, ["validate"])
    assert result.exit_code == 1
    out = result.stdout
    assert "FAIL" in out and "error" in out and "pass" in out
    assert "RuntimeError: solver did not converge" in out
    assert "a documented deviation" in out
    assert "3 checks: 1 passed, 2 failed" in out


def test_a_failing_check_exits_1_in_json_too(fakes):
    result = runner.invoke(app, ["validate", "--json"])
    assert result.exit_code == 1
    rows = json.loads(result.stdout)
    assert [r["status"] for r in rows] == ["pass", "FAIL", "error"]
    assert rows[1]["computed"] == 2.0 and rows[1]["relative_error"] == pytest.approx(1.0)
    assert rows[2]["computed"] is None and "did not converge" in rows[2]["error"]


def test_selecting_the_passing_case_exits_0(fakes):
    result = runner.invoke(app, ["validate", "--case", "fake_ok", "--json"])
    assert result.exit_code == 0, result.output
    assert [r["quantity"] for r in json.loads(result.stdout)] == ["a passing number"]


def test_unknown_case_is_a_usage_error(fakes):
    result = runner.invoke(app, ["validate", "--case", "hst"])
    assert result.exit_code == 2
    assert "case: no checks for 'hst'; known: ['fake_ok', 'fake_bad']" in result.stderr
