"""Report of a star-tracker scenario (flexsat.report.star_tracker): files, table, netCDF."""

import json

import numpy as np
import pytest
import xarray as xr

from flexsat.report import MANIFEST, write_report
from flexsat.scenarios import ScenarioError, load_scenario, run_scenario
from report_browser import assert_renders

SMALL = """
kind: star_tracker
name: report star tracker
cameras:
  - {centroid_noise: 0.1}
  - {centroid_noise: 0.1, mounting: ["0 deg", "90 deg", "0 deg"]}
runs:
  - {label: clean, attitudes: 20, seed: 1}
  - {label: "false + missing", attitudes: 20, seed: 2, false_stars: 2, missing_fraction: 0.2}
"""


@pytest.fixture(scope="module")
def result():
    return run_scenario(load_scenario(SMALL))


def test_report_files_table_and_netcdf_round_trip(result, tmp_path):
    out = write_report(result, tmp_path / "report")
    names = {p.name for p in out.iterdir()}
    assert names == {
        "metrics.json",
        "results.nc",
        "index.html",
        "errors.png",
        "sky_1.png",
        "sky_2.png",
        MANIFEST,
    }
    records = json.loads((out / "metrics.json").read_text())
    assert [r["run"] for r in records] == ["clean", "false + missing"]
    assert all(r["wrong_accepted"] == 0 for r in records)
    with xr.open_dataset(out / "results.nc", engine="h5netcdf") as ds:
        r = result.runs[1]
        np.testing.assert_allclose(ds["error"].values[1] * np.pi / 648000, r.errors)
        assert ds["error"].attrs["units"] == "arcsec"
        status = ds["example_status"].values[1]
        # the example frame's two false stars per camera are shown as such, none matched wrong
        assert np.sum(status == -1) == 2 * len(result.tracker.cameras)
        assert not np.any(status == 2)
        assert ds.attrs["tolerance_arcsec"] == pytest.approx(5.0)
    page = (out / "index.html").read_text()
    for text in (
        "Identification",
        "wrong accepted",
        "σ_QUEST",
        "errors.png",
        "sky_2.png",
        "kind: star_tracker",
        "false + missing",
    ):
        assert text in page


def test_report_of_a_run_with_nothing_identified_states_no_data(tmp_path):
    # cameras limited to m = 4.4 on the synthetic sky (463 stars: a 12° field holds 1.6 on
    # average; the 4 stars of 3 triplets in both fields with probability 0.6 %): identification is
    # possible (the run is not refused) but none of the 20 attitudes gets it; the metrics of
    # the errors are null with the reason, and metrics.json is strict JSON
    spec = load_scenario(
        SMALL.replace("centroid_noise: 0.1", "centroid_noise: 0.1, magnitude_limit: 4.4")
    )
    result = run_scenario(spec)
    rec = result.metrics_records()[0]
    assert rec["accepted_rate"] == 0.0 and rec["wrong_accepted"] == 0
    out = write_report(result, tmp_path / "r")
    assert (out / "errors.png").is_file()
    text = (out / "metrics.json").read_text()
    written = json.loads(text, parse_constant=lambda token: pytest.fail(f"{token} in JSON"))
    for run in written:
        assert run["mean_stars"] is None and run["error_std_x_arcsec"] is None
        assert "none of the 20 attitudes" in run["null_reasons"]["error_std_x_arcsec"]
        assert set(run["null_reasons"]) == {k for k, v in run.items() if v is None}


def test_a_sky_the_cameras_cannot_identify_in_is_refused_before_the_run():
    # m = 2: ~30 stars, 0.1 in a field on average; 3 in both fields for about 1e-8 of the
    # attitudes: 20 attitudes would report no data
    spec = load_scenario(
        SMALL.replace("centroid_noise: 0.1", "centroid_noise: 0.1, magnitude_limit: 2.0")
    )
    with pytest.raises(ScenarioError) as info:
        run_scenario(spec)
    assert [p.path for p in info.value.problems] == ["cameras"]
    assert "could only report no data" in info.value.problems[0].rule


def test_the_page_reads_right_in_a_browser(result, tmp_path, browser):
    text = assert_renders(browser, write_report(result, tmp_path / "report") / "index.html")
    assert "false + missing" in text
