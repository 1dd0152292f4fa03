"""The metric variables of scenario result datasets (flexsat.scenarios.datasets)."""

import numpy as np
import xarray as xr

from flexsat.scenarios.datasets import add_run_metrics


def test_metrics_become_variables_over_the_runs_nan_where_missing():
    ds = xr.Dataset(coords={"run": ["a", "b"]})
    add_run_metrics(ds, [{"run": "a", "peak": 2.0, "mean": None}, {"run": "b", "peak": 3}])
    assert ds["peak"].values.tolist() == [2.0, 3.0]
    assert np.isnan(ds["mean"].values).all()  # None and a missing entry
