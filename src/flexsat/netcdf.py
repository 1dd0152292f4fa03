"""Writing netCDF files without crashing on a full disk.

Used by the model files of :mod:`flexsat.structures` and by the reports of
:mod:`flexsat.report`, so it sits below both.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import xarray


def write_netcdf(dataset: xarray.Dataset, path: str | Path, **options: Any) -> None:
    """Write ``dataset`` (an ``xarray.Dataset``) to ``path`` as netCDF-4 (engine h5netcdf;
    ``options`` go to ``to_netcdf``, e.g. ``encoding``).

    The file is built in memory and written with Python's file I/O: HDF5 writing to a full disk
    crashes the interpreter (segmentation fault in h5py 3.16 when it closes the file), whereas a
    failed Python write raises ``OSError`` (ENOSPC).
    """
    Path(path).write_bytes(dataset.to_netcdf(engine="h5netcdf", **options))


__all__ = ["write_netcdf"]
