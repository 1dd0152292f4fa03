"""netCDF files written with Python's I/O (flexsat.netcdf): a full disk is an error, not a crash."""

import errno
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from flexsat.netcdf import write_netcdf


def test_full_device_is_an_os_error(tmp_path):
    """/dev/full fails every write with ENOSPC, as a full disk does: the netCDF bytes are written
    with Python's I/O, so this is an OSError (h5py writing there itself crashes the
    interpreter)."""
    ds = xr.Dataset({"theta": ("time", np.linspace(0.0, 1.0, 50), {"units": "rad"})})
    with pytest.raises(OSError) as info:
        write_netcdf(ds, Path("/dev/full"))
    assert info.value.errno == errno.ENOSPC
    write_netcdf(ds, tmp_path / "r.nc")
    with xr.open_dataset(tmp_path / "r.nc", engine="h5netcdf") as back:
        assert np.array_equal(back["theta"].values, ds["theta"].values)
        assert back["theta"].attrs["units"] == "rad"
