"""Tether report (kind: tether): metrics.json and results.nc hold every run's measures and
histories in SI; index.html sets the published numbers of Vadali & Kim beside the measured ones
for the runs that repeat a paper example, and only for those; the four figures are written; a
folder holding other files is refused and left unchanged."""

import json

import numpy as np
import pytest
import xarray as xr

from flexsat.report import write_report
from flexsat.report.publish import OutputError
from flexsat.report.tether import FIGURES, paper_example
from flexsat.scenarios import load_scenario, run_scenario
from report_browser import assert_renders

TEXT = """
kind: tether
name: report test
system: {mass: 22.7 kg, length: 20 km, altitude: 220 km}
initial: {length: 20 km, pitch: 5 deg, roll: 5 deg}
simulation: {orbits: 2, samples_per_orbit: 400}
runs:
  - {label: c2, law: coupled, gains: {K1: 1.0, K2: 0.0, K3: 3.0, K4: 2.0}, final_length: 200 m}
  - {label: c2 stiff, law: coupled, gains: {K1: 2.0, K2: 0.0, K3: 3.0, K4: 2.0},
     final_length: 200 m}
  - {label: rate law, law: rate, gains: {K1: 0.25, K2: 0.01, K3: 1.0}, final_length: 200 m}
"""


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    result = run_scenario(load_scenario(TEXT))
    return result, write_report(result, tmp_path_factory.mktemp("tether") / "report")


def test_files_hold_the_measures_and_histories(report):
    result, out = report
    records = json.loads((out / "metrics.json").read_text())
    assert [r["run"] for r in records] == ["c2", "c2 stiff", "rate law"]
    assert records[0]["thrust_index_2_orbits"] == pytest.approx(0.2369, abs=5e-4)
    assert records[2]["initial_tension"] is None
    with xr.open_dataset(out / "results.nc", engine="h5netcdf") as ds:
        assert ds["length"].attrs["units"] == "m"
        assert ds["length"].sel(run="c2").values[0] == pytest.approx(2e4)
        assert ds["orbits"].values[-1] == pytest.approx(2.0)
        assert ds["time"].values[-1] == pytest.approx(2 * result.scales.period)
        assert np.isnan(ds["tension"].sel(run="rate law").values).all()
        assert np.isnan(ds["reel_rate"].sel(run="c2").values).all()
        # T(0) = 3.99 mΩ²L in newtons
        assert ds["tension"].sel(run="c2").values[0] == pytest.approx(3.99 * 0.630, abs=0.005)
        assert str(ds["law"].sel(run="rate law").values) == "rate"
    for name in FIGURES:
        assert (out / name).stat().st_size > 10_000


def test_page_compares_only_the_paper_examples(report):
    result, out = report
    page = (out / "index.html").read_text()
    assert "V11 (Figs. 4-5)" in page and "Tether Rate Control Law&#x27;, Fig. 8)" in page
    assert "128.4" in page and "29.3" in page  # published V11 numbers
    examples = [paper_example(spec, result.scenario) for spec in result.scenario.runs]
    assert [e and e.key for e in examples] == ["V11", None, "V15"]
    # another start is not the paper's example
    moved = load_scenario(TEXT.replace("pitch: 5 deg", "pitch: 6 deg"))
    assert paper_example(moved.runs[0], moved) is None


def test_a_folder_with_other_files_is_refused(report, tmp_path):
    result, _ = report
    (tmp_path / "notes.txt").write_text("mine")
    with pytest.raises(OutputError):
        write_report(result, tmp_path)
    assert (tmp_path / "notes.txt").read_text() == "mine"


def test_the_page_reads_right_in_a_browser(report, browser):
    _, out = report
    assert "Vadali" in assert_renders(browser, out / "index.html")
