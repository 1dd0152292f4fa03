"""`flexsat validate` through typer's CliRunner (cheap cases and injected fake checks)."""

from __future__ import annotations

import json

import pytest
from rich.console import Console
from typer.testing import CliRunner

import flexsat.checks as checks_module
from flexsat import cli
from flexsat.checks import COLUMNS, Check, Discrepancy
from flexsat.cli import app

runner = CliRunner()


def _raise():
    raise RuntimeError("solver did not converge")


FAKES = [
    Check(
        "fake_ok",
        "a passing number",
        "seed 000_7bfdb62d2eacc22a.txt, L1",
        1.0,
        "Hz",
        lambda: 1.0 + 1e-6,
        rtol=1e-3,
    ),
    Check(
        "fake_bad",
        "a failing number",
        "seed 000_7bfdb62d2eacc22a.txt, L2",
        1.0,
        "Hz",
        lambda: 2.0,
        rtol=1e-3,
        note="a documented deviation",
    ),
    Check(
        "fake_bad",
        "a crashing number",
        "seed 000_7bfdb62d2eacc22a.txt, L3",
        1.0,
        "Hz",
        _raise,
        rtol=1e-3,
    ),
]
#: a printed 1.0 that the paper's own inputs give as 1.5: an erratum, explained
ERRATUM = Check(
    "fake_erratum",
    "a misprinted number",
    "seed 002_c3272b32d7cac32e.txt, L4",
    1.0,
    "Hz",
    lambda: 1.5,
    rtol=1e-3,
    discrepancy=Discrepancy(1.5, "Bainum & Reddy 1979 misprint 1.5 as 1.0"),
)


@pytest.fixture
def erratum(monkeypatch):
    monkeypatch.setattr(checks_module, "all_checks", lambda: [FAKES[0], ERRATUM])


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
    assert "10 checks: 10 passed, 0 discrepancies (explained), 0 failed" in out
    # sources cited by authors and year, the full reference below the table; no seed file
    flat = " ".join(out.split())  # narrow consoles wrap
    assert "Hailey, Sortun & Agrawal c. 1992, 'Experimental Setup'" in flat  # where in the paper
    assert "Experimental Verification of Attitude Control Techniques" in flat
    assert ".txt" not in out and "../shared" not in out
    assert "the unpublished EI is solved to give this frequency" in flat  # the fitted 0.14 Hz


def test_a_failing_check_exits_1_and_is_shown(fakes):
    result = runner.invoke(app, ["validate"])
    assert result.exit_code == 1
    out = result.stdout
    assert "FAIL" in out and "ERROR" in out and "pass" in out
    flat = " ".join(out.split())
    assert "the computation raised: RuntimeError: solver did not converge" in flat
    assert "a documented deviation" in flat  # the failing check's note, in its explanation
    assert "no erratum or model deviation explains it" in flat
    assert "3 checks: 1 passed, 0 discrepancies (explained), 2 failed" in out


def test_a_failing_check_exits_1_in_json_too(fakes):
    result = runner.invoke(app, ["validate", "--json"])
    assert result.exit_code == 1
    rows = json.loads(result.stdout)
    assert [r["status"] for r in rows] == ["pass", "fail", "error"]
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


def test_a_discrepancy_exits_0_and_1_with_strict(erratum):
    """A documented erratum does not fail the gate; --strict makes it fail."""
    result = runner.invoke(app, ["validate"])
    assert result.exit_code == 0, result.output
    assert "discrepancy" in result.stdout and "misprint 1.5 as 1.0" in result.stdout
    assert "2 checks: 1 passed, 1 discrepancies (explained), 0 failed" in result.stdout
    strict = runner.invoke(app, ["validate", "--strict"])
    assert strict.exit_code == 1
    assert runner.invoke(app, ["validate", "--strict", "--case", "fake_ok"]).exit_code == 0


def test_json_carries_status_explanation_and_references(erratum):
    result = runner.invoke(app, ["validate", "--json"])
    assert result.exit_code == 0, result.output
    ok, odd = json.loads(result.stdout)
    assert (ok["status"], ok["explanation"], ok["passed"]) == ("pass", None, True)
    assert (odd["status"], odd["passed"], odd["discrepancy_value"]) == ("discrepancy", False, 1.5)
    assert odd["explanation"] == "Bainum & Reddy 1979 misprint 1.5 as 1.0"
    assert odd["source"] == "Bainum & Reddy 1979, L4"
    assert "NASA CR-158684" in odd["references"][0]
    assert odd["stale"] is False
    assert runner.invoke(app, ["validate", "--json", "--strict"]).exit_code == 1


def test_every_non_pass_row_of_the_real_registry_is_explained_and_none_fails():
    """The gate a user relies on: on this machine the whole registry has no failure, and every
    row that is not a plain pass says why, naming the paper rather than a seed file."""
    result = runner.invoke(app, ["validate", "--json"])
    assert result.exit_code == 0, result.output
    rows = json.loads(result.stdout)
    assert {r["status"] for r in rows} <= {"pass", "discrepancy"}
    assert not [r["quantity"] for r in rows if r["stale"]]  # every explanation still applies
    odd = [r for r in rows if r["status"] != "pass"]
    assert len(odd) >= 1
    for row in rows:
        assert ".txt" not in row["source"] and "../shared" not in json.dumps(row)
    for row in odd:
        assert row["explanation"] and row["references"], row["quantity"]
        assert "docs/" not in row["explanation"] and "notes §" not in row["explanation"]
    strict = runner.invoke(app, ["validate", "--strict"])
    assert strict.exit_code == 1
