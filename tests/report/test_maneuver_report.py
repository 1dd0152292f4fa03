"""Report files of a scenario run (flexsat.report.maneuver)."""

from __future__ import annotations

import errno
import html
import json
import re
import shutil

import pytest
import xarray as xr
import yaml

import flexsat.report.maneuver as report
from flexsat.report import (
    MANIFEST,
    OutputError,
    format_metric,
    metric_rows,
    write_atomically,
    write_report,
)
from flexsat.report.maneuver import PLOTS
from flexsat.scenarios import default_scenario, load_scenario, run_scenario
from report_browser import assert_renders

METRICS = {
    "run",
    "settling_time_s",
    "overshoot_deg",
    "peak_torque_Nm",
    "residual_energy_J",
    "residual_energy_at_T_J",
    "peak_tip_deflection_m",
    "peak_rate_error_deg_s",
}
FILES = {"metrics.json", "results.nc", "index.html"}  # the figures are inside the page


def short_run(name: str):
    """Law I and Law II on a 3-mode model for 2 s."""
    data = yaml.safe_load(default_scenario().yaml_text)
    data["name"] = name
    data["model"]["n_modes"] = 3
    data["simulation"]["duration"] = "2 s"
    return run_scenario(load_scenario(yaml.safe_dump(data)))


@pytest.fixture(scope="module")
def result():
    return short_run("Short <test> & run")


@pytest.fixture(scope="module")
def earlier_report(tmp_path_factory):
    """The report of another run (another name), to be replaced."""
    return write_report(short_run("Earlier run"), tmp_path_factory.mktemp("earlier") / "report")


def snapshot(folder):
    return {p.name: p.read_bytes() for p in folder.iterdir()}


def test_metrics_json_has_one_object_per_run(result, tmp_path):
    out = write_report(result, tmp_path / "report")
    assert {p.name for p in out.iterdir()} == FILES | {MANIFEST}
    assert json.loads((out / MANIFEST).read_text()) == {"files": sorted(FILES)}
    records = json.loads((out / "metrics.json").read_text())
    assert [r["run"] for r in records] == ["Law I", "Law II"]
    for record in records:
        assert set(record) == METRICS
        assert record["peak_torque_Nm"] > 0
    assert records[0]["settling_time_s"] is None  # 2 s is too short to settle: null, not NaN


def test_results_nc_has_run_and_time_dims(result, tmp_path):
    out = write_report(result, tmp_path / "report")
    with xr.open_dataset(out / "results.nc", engine="h5netcdf") as ds:
        assert ds["theta"].dims == ("run", "time")
        assert list(ds["run"].values) == ["Law I", "Law II"]
        assert ds["theta"].attrs["units"] == "rad"
        assert ds["settling_time_s"].dims == ("run",)
        assert ds.sizes["time"] == 151  # 2 s at 75 Hz, both ends
        assert ds.attrs["case"] == "tamu"
        assert "Law II" in ds.attrs["scenario_yaml"]
        assert float(ds["time"][-1]) == pytest.approx(2.0)


def test_index_html_is_self_contained(result, tmp_path):
    page = (write_report(result, tmp_path / "report") / "index.html").read_text()
    assert "Short &lt;test&gt; &amp; run" in page
    assert html.escape(result.case_source) in page
    # the source stands alone (the seed files do not ship): the paper is cited, not a file name
    assert result.case_source.startswith("Junkins, Pollock & Rahman 1990") and ".txt" not in page
    for spec in PLOTS:  # interactive figures, drawn from the page's own data
        assert f'"text":"{spec.title}"' in page
    markup = re.sub(r"<script\b.*?</script>", "", page, flags=re.DOTALL)  # BokehJS aside
    assert "<img" not in markup
    assert "<th>Law I</th><th>Law II</th>" in page
    assert "<td>Settling time (s)</td>" in page  # readable metric names with units
    assert "smooth_bang_bang" in page  # the scenario echoed
    # nothing is loaded from elsewhere: no source or style sheet but the page's own
    assert not re.search(r"""<(script|link|img)\b[^>]*\b(src|href)=""", markup)
    assert not re.search(r"<script\b[^>]*\bsrc=", page)
    # the full citation of the paper, and the controller summary of both (linear) laws
    assert "Analytical and Experimental Research on Large Angle Maneuvers" in page
    assert page.count("Margins and norms of the sampled-data loop") == 2


def test_rewrite_replaces_the_whole_report(result, tmp_path):
    out = write_atomically(
        tmp_path / "report", lambda folder: (folder / "identification.json").write_text("{}")
    )
    write_report(result, out)
    assert {p.name for p in out.iterdir()} == FILES | {MANIFEST}  # nothing of the earlier left
    assert json.loads((out / "metrics.json").read_text())[0]["run"] == "Law I"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["report"]  # no temporary folder left


def test_folder_with_other_files_is_refused_untouched(result, tmp_path):
    out = tmp_path / "report"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    (out / "metrics.json").write_text("stale")
    with pytest.raises(OutputError, match="holds notes.txt, not files of a flexsat report"):
        write_report(result, out)
    assert snapshot(out) == {"notes.txt": b"mine", "metrics.json": b"stale"}
    assert sorted(p.name for p in tmp_path.iterdir()) == ["report"]


@pytest.mark.parametrize("name", ["metrics.json", "results.nc", "index.html", MANIFEST])
def test_disk_full_at_each_file_keeps_the_complete_earlier_report(
    result, earlier_report, tmp_path, fail_opening, name
):
    out = tmp_path / "report"
    shutil.copytree(earlier_report, out)
    before = snapshot(out)
    fail_opening(name, errno.ENOSPC)
    with pytest.raises(OutputError, match="No space left on device"):
        write_report(result, out)
    assert snapshot(out) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["report"]


def test_failure_leaves_no_partial_report(result, tmp_path, monkeypatch):
    def broken(*args):
        raise RuntimeError("plot failed")

    monkeypatch.setattr(report, "_plot", broken)
    with pytest.raises(RuntimeError):
        write_report(result, tmp_path / "report")
    assert list(tmp_path.iterdir()) == []


def test_metric_formatting():
    assert format_metric(None) == "n/a"
    assert format_metric(0.000123456) == "0.0001235"
    rows = metric_rows([{"run": "a", "x_s": 1.0}, {"run": "b", "x_s": None}])
    assert rows == [("x_s", ["1", "n/a"])]


def test_the_page_reads_right_in_a_browser(result, tmp_path, browser):
    text = assert_renders(browser, write_report(result, tmp_path / "report") / "index.html")
    assert "Law II" in text


#: JavaScript: [run tag, visible] of every line renderer tagged with a run, in document order
RENDERERS = """[...Bokeh.documents[0].all_models]
    .filter(m => m.tags && m.tags.length && String(m.tags[0]).startsWith("run:"))
    .map(m => [m.tags[0], m.visible])"""


def test_the_report_opens_offline_alone_and_toggles_runs(result, tmp_path, browser):
    """Issue 24's acceptance: index.html copied alone to an empty folder, opened with the
    network off, draws its figures without a script error or a request, and the run toggles
    hide a run in every figure and show it again."""
    from report_browser import open_offline

    out = write_report(result, tmp_path / "report")
    page, refused, text = open_offline(browser, out / "index.html", tmp_path / "alone")
    try:
        assert refused == []
        assert "Settling time (s)" in text and "Controller summary" in text
        assert page.locator("canvas").count() >= len(PLOTS)
        before = page.evaluate(f"() => {RENDERERS}")
        # each figure has a line of each run (with its reference where the figure has one)
        assert sum(tag == "run:Law II" for tag, _ in before) >= len(PLOTS)
        assert all(visible for _, visible in before)
        boxes = page.locator("input[type=checkbox]")
        assert boxes.count() == 2
        boxes.nth(1).click()  # Law II off
        page.wait_for_function(
            f"() => {RENDERERS}.every(([tag, shown]) => shown === (tag !== 'run:Law II'))"
        )
        boxes.nth(1).click()  # and on again
        page.wait_for_function(f"() => {RENDERERS}.every(([tag, shown]) => shown)")
    finally:
        page.context.close()


def test_identical_runs_write_identical_files_but_the_provenance_line(tmp_path, monkeypatch):
    """Two runs of the same scenario: every file of the report the same byte for byte, except
    the page's provenance line (its date); with SOURCE_DATE_EPOCH set, the page too."""
    from flexsat.report.provenance import without_provenance

    first = snapshot(write_report(short_run("Same"), tmp_path / "a"))
    second = snapshot(write_report(short_run("Same"), tmp_path / "b"))
    assert first.keys() == second.keys()
    for name in first.keys() - {"index.html"}:
        assert first[name] == second[name], name
    pages = [without_provenance(f["index.html"].decode()) for f in (first, second)]
    assert pages[0] == pages[1]
    monkeypatch.setenv("SOURCE_DATE_EPOCH", "1700000000")
    result = short_run("Same")
    again = [write_report(result, tmp_path / n).joinpath("index.html").read_bytes() for n in "cd"]
    assert again[0] == again[1] and b"written 2023-11-14T22:13:20Z" in again[0]
