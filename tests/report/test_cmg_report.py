"""CMG reports (issue 14): the two example scenarios run through ``flexsat run`` and leave the
metrics, the netCDF results, the figures and a page with the V1–V8 table (published against
computed) or the station's V9 table."""

import json
from pathlib import Path

import pytest
import xarray as xr
from typer.testing import CliRunner

from flexsat.cli import app
from report_browser import assert_renders

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


@pytest.fixture(scope="module")
def reports(tmp_path_factory):
    out = {}
    for name in ("cmg_preferred_angles", "space_station_cmg"):
        folder = tmp_path_factory.mktemp(name) / "report"
        result = CliRunner().invoke(app, ["run", str(EXAMPLES / f"{name}.yaml"), "-o", str(folder)])
        assert result.exit_code == 0, result.output
        out[name] = (folder, result.output)
    return out


def test_preferred_angles_report_has_the_v1_to_v8_table_and_figures(reports):
    folder, output = reports["cmg_preferred_angles"]
    assert "metrics" in output  # the metrics table on the console
    page = (folder / "index.html").read_text(encoding="utf-8")
    for v in ("V1", "V2", "V3", "V4", "V5", "V6", "V7", "V8"):
        assert f"<td>{v}</td>" in page
    assert "1.1854" in page and "3.1545" in page  # published V1, V2 beside the computed ones
    assert (folder / "gimbals.png").is_file() and (folder / "envelope.png").is_file()
    records = json.loads((folder / "metrics.json").read_text())
    by_run = {r["run"]: r for r in records}
    assert by_run["x, zero gimbals (V3)"]["internal"] is True
    assert by_run["x, preferred set (V4)"]["internal"] is False
    ds = xr.open_dataset(folder / "results.nc", engine="h5netcdf")
    assert set(ds["run"].values) == set(by_run)
    assert ds["gimbal_angles"].attrs["units"] == "rad"


def test_station_report_has_the_v9_contrast_and_the_histories(reports):
    folder, _ = reports["space_station_cmg"]
    page = (folder / "index.html").read_text(encoding="utf-8")
    assert "AERO1" in page and "about 720 seconds" in page
    records = {r["run"]: r for r in json.loads((folder / "metrics.json").read_text())}
    assert records["sigma(0) = 0"]["singular"] is True
    assert records["[45, -45, 45, -45]"]["singular"] is False
    assert records["preferred"]["singular"] is False
    ds = xr.open_dataset(folder / "results.nc", engine="h5netcdf")
    assert ds["attitude"].dims == ("time", "axis")
    assert ds["cmg_momentum"].attrs["units"] == "N*m*s"
    assert (folder / "station.png").is_file() and (folder / "gimbals.png").is_file()


@pytest.mark.parametrize("name", ["cmg_preferred_angles", "space_station_cmg"])
def test_the_pages_read_right_in_a_browser(reports, name, browser):
    folder, _ = reports[name]
    assert_renders(browser, folder / "index.html")
