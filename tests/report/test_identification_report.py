"""Report of an identification scenario (flexsat.report.identification)."""

import base64
import json

import numpy as np
import pytest
import xarray as xr
import yaml

import flexsat.report.identification as rep
from flexsat.report import MANIFEST, write_report
from flexsat.report.identification import FIGURES, dataset
from flexsat.scenarios import load_scenario, run_scenario
from report_browser import assert_renders


@pytest.fixture(scope="module")
def result(identification_example):
    return run_scenario(load_scenario(yaml.safe_dump(identification_example(fast=True))))


def test_report_files_tables_and_netcdf_round_trip(result, tmp_path):
    out = write_report(result, tmp_path / "report")
    names = {p.name for p in out.iterdir()}
    assert names == {"identification.json", "results.nc", "index.html", MANIFEST} | {
        f for f, _ in FIGURES
    }
    summary = json.loads((out / "identification.json").read_text())
    assert summary["scalings"]["clamp verticals"]["a_priori"] == 1.15
    with xr.open_dataset(out / "results.nc", engine="h5netcdf") as ds:
        c = result.campaign
        assert np.array_equal(ds["era_hz"].values, c.modes["era_hz"])
        assert np.array_equal(
            ds["frf_measured_re"].values + 1j * ds["frf_measured_im"].values, c.frf_measured
        )
        assert ds["mac_updated"].shape == c.mac_updated.shape
        assert list(ds["substructure"].values) == list(c.substructures)
        assert ds["era_hz"].attrs["units"] == "Hz"
    page = (out / "index.html").read_text()
    for text in (
        "Natural frequencies",
        "Damping ratios",
        "Substructure stiffness scalings",
        "clamp verticals",
        "kind: identification",
        "Reaction-wheel torque constants",
    ):
        assert text in page
    # the figures inside the page (data: URIs of the PNG files still written beside it)
    for name in ("frf.png", "mac.png"):
        encoded = base64.b64encode((out / name).read_bytes()).decode()
        assert f'src="data:image/png;base64,{encoded}"' in page


def test_dataset_has_one_row_per_identified_mode(result):
    ds = dataset(result)
    assert ds.sizes["mode"] == len(result.campaign.modes["era_hz"])
    assert ds.sizes["frequency"] == result.campaign.frf_frequencies.size


def test_failed_report_leaves_nothing(result, tmp_path, monkeypatch):
    def broken(*_):
        raise RuntimeError("disk full")

    monkeypatch.setattr(rep, "_mac_figure", broken)
    with pytest.raises(RuntimeError):
        write_report(result, tmp_path / "report")
    assert list(tmp_path.iterdir()) == []


def test_report_of_measured_data_without_truth(result, tmp_path):
    """Measured data have no truth: its columns read "–" and the frequency plot compares with
    the ERA values; the dataset stores NaN."""
    import dataclasses

    n = len(result.campaign.modes["era_hz"])
    modes = {**result.campaign.modes, "true_hz": [None] * n, "true_damping": [None] * n}
    measured = dataclasses.replace(
        result, campaign=dataclasses.replace(result.campaign, modes=modes)
    )
    out = write_report(measured, tmp_path / "report")
    page = (out / "index.html").read_text()
    assert "<td>–</td>" in page
    assert np.all(np.isnan(dataset(measured)["true_hz"].values))


def test_the_page_reads_right_in_a_browser(result, tmp_path, browser):
    text = assert_renders(browser, write_report(result, tmp_path / "report") / "index.html")
    assert "Natural frequencies" in text
