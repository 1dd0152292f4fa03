"""Pieces of the xarray datasets that scenario results write (``results.nc``)."""

from __future__ import annotations

import numpy as np
import xarray as xr


def add_run_metrics(ds: xr.Dataset, records: list[dict]) -> None:
    """Add each metric of ``records`` (one dict per run: ``run`` its label, then metric: value)
    to ``ds`` as a variable over its ``run`` coordinate; a run without the metric, or with
    None, holds NaN."""
    labels = list(ds["run"].values)
    for record in records:
        for key, value in record.items():
            if key == "run":
                continue
            if key not in ds:
                ds[key] = ("run", np.full(len(labels), np.nan))
            ds[key].loc[record["run"]] = np.nan if value is None else float(value)


__all__ = ["add_run_metrics"]
