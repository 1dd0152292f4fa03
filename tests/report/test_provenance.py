"""Provenance of a report (flexsat.report.provenance): the scenario's SHA-256 is the standard
one (a published test vector), the date follows SOURCE_DATE_EPOCH, and the provenance line is
the only line taken out to compare two pages."""

from __future__ import annotations

import pytest

from flexsat import __version__
from flexsat.report.provenance import (
    provenance,
    provenance_html,
    report_date,
    without_provenance,
)

#: SHA-256 of "abc" (FIPS 180-2, Appendix B.1)
ABC = "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"


def test_the_line_names_version_fingerprint_command_and_date(monkeypatch):
    monkeypatch.setenv("SOURCE_DATE_EPOCH", "86400")
    origin = provenance("abc", "flexsat run 'a b.yaml' -o out")
    assert origin.scenario_sha256 == ABC
    assert origin.written == "1970-01-02T00:00:00Z" and origin.version == __version__
    line = provenance_html(origin)
    assert line.count("\n") == 1 and line.startswith('<p class="provenance">')
    assert "flexsat run &#x27;a b.yaml&#x27; -o out" in line and ABC in line
    assert "Python API" in provenance("abc").command


def test_without_provenance_takes_out_that_line_only(monkeypatch):
    monkeypatch.setenv("SOURCE_DATE_EPOCH", "0")
    line = provenance_html(provenance("x: 1\n"))
    page = f"<h1>r</h1>\n{line}<p>body</p>\n"
    assert without_provenance(page) == "<h1>r</h1>\n<p>body</p>\n"


@pytest.mark.parametrize("bad", ["soon", "1.5", "1e99"])
def test_a_bad_source_date_epoch_is_named(monkeypatch, bad):
    monkeypatch.setenv("SOURCE_DATE_EPOCH", bad)
    with pytest.raises(ValueError, match="SOURCE_DATE_EPOCH: must be a whole number"):
        report_date()
