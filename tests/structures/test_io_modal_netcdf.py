"""A modal model's netCDF file: the round trip is bitwise, every variable carries a unit
that pint parses, and foreign or future files are refused naming ``path``."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr
from test_modal_model import synthetic, tower, vars_of

from flexsat.structures.io_modal_netcdf import UNITS, modal_model_dataset
from flexsat.structures.modal_model import FORMAT_VERSION, ModalModel
from flexsat.units import ureg


def test_every_variable_has_its_unit():
    ds = modal_model_dataset(synthetic())
    assert set(ds.data_vars) == set(UNITS)
    assert all(ds[name].attrs["units"] == unit for name, unit in UNITS.items())


def test_save_load_round_trip_is_exact(tmp_path):
    modes, _, _ = tower()
    model = ModalModel.from_fe(
        modes, damping=np.linspace(0.001, 0.02, 18), reference=(0.1, 0.2, -0.3)
    )
    path = tmp_path / "tower.nc"
    model.save(path)
    back = ModalModel.load(path)
    for name, value in vars_of(model).items():
        got = getattr(back, name)
        if isinstance(value, str):
            assert got == value
        else:  # bitwise
            assert got.dtype == value.dtype and got.shape == value.shape
            assert got.tobytes() == value.tobytes(), name
    with open(path, "rb") as fh:
        assert fh.read(8) == b"\x89HDF\r\n\x1a\n"  # netCDF-4/HDF5, not a pickle
    ds = xr.open_dataset(path, engine="h5netcdf")
    try:
        assert ds.attrs["flexsat_modal_model_version"] == FORMAT_VERSION
        assert {"mode", "node", "axis"} <= set(ds.sizes)
        assert ds.sizes["mode"] == 18 and ds.sizes["node"] == 9
        for name, var in ds.variables.items():
            assert "units" in var.attrs, name
            ureg.Quantity(1.0, var.attrs["units"])  # parses
        assert ureg.Quantity(1.0, ds["rotation_shapes"].units).dimensionality == (
            ureg.Quantity(1.0, "kg**-0.5/m").dimensionality
        )
    finally:
        ds.close()


def test_load_refuses_foreign_files(tmp_path):
    path = tmp_path / "other.nc"
    xr.Dataset({"a": ("x", np.arange(3.0))}).to_netcdf(path, engine="h5netcdf")
    with pytest.raises(ValueError, match="^path: not a flexsat modal model"):
        ModalModel.load(path)
    synthetic().save(path)
    ds = xr.load_dataset(path, engine="h5netcdf")
    ds.attrs["flexsat_modal_model_version"] = FORMAT_VERSION + 1
    ds.to_netcdf(tmp_path / "future.nc", engine="h5netcdf")
    with pytest.raises(ValueError, match="not supported"):
        ModalModel.load(tmp_path / "future.nc")
