"""Pieces of the xarray datasets that scenario results write (``results.nc``), and the result
of the kinds whose runs are simulations (:class:`SimulatedRuns`)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
import xarray as xr

from flexsat.report.json_data import NULL_REASONS
from flexsat.report.page import ReportedResult

if TYPE_CHECKING:
    from flexsat.sim import SimResult


def add_run_metrics(ds: xr.Dataset, records: list[dict[str, Any]]) -> None:
    """Add each metric of ``records`` (one dict per run: ``run`` its label, then metric: value)
    to ``ds`` as a variable over its ``run`` coordinate; a run without the metric, or with
    None, holds NaN (a record's ``null_reasons`` say why in ``metrics.json``; they are no
    metric)."""
    labels = list(ds["run"].values)
    for record in records:
        for key, value in record.items():
            if key in ("run", NULL_REASONS):
                continue
            if key not in ds:
                ds[key] = ("run", np.full(len(labels), np.nan))
            ds[key].loc[record["run"]] = np.nan if value is None else float(value)


@dataclass(frozen=True)
class SimulatedRuns(ReportedResult):
    """Runs that are one simulation each (:class:`flexsat.sim.SimResult`), in one dataset.

    Attributes
    ----------
    scenario
        The document.
    labels : tuple of str
        Run labels, in the scenario's order.
    results : tuple of SimResult
        One single-case result per run (every run uses the same noise seed).
    case_source : str
        Where the case's data come from (:attr:`flexsat.cases.CaseInfo.source`).
    """

    scenario: Any
    labels: tuple[str, ...]
    results: tuple[SimResult, ...]
    case_source: str

    def metrics_records(self) -> list[dict[str, Any]]:
        """One JSON-ready dict per run: ``"run"`` (the label) and the metrics (NaN -> None)."""
        return [
            row
            for label, result in zip(self.labels, self.results)
            for row in result.metrics_records([label])
        ]

    def dataset(self) -> xr.Dataset:
        """All runs in one dataset, dims (run, time[, component]); ``run`` holds the labels.

        Attributes: ``scenario_name``, ``case``, ``case_source``, ``scenario_yaml`` and those of
        the simulation (``control_rate_Hz``, ``settling_band_rad``).
        """
        ds = concat_runs(self.results, self.labels)
        ds.attrs.update(
            scenario_name=self.scenario.name,
            case=self.scenario.case,
            case_source=self.case_source,
            scenario_yaml=self.scenario.yaml_text,
        )
        return ds


def concat_runs(results: Sequence[SimResult], labels: Sequence[str]) -> xr.Dataset:
    """The single-case datasets of ``results`` along a new dimension ``run`` (``labels``)."""
    runs = [r.dataset.isel(case=0, drop=True) for r in results]
    ds = xr.concat(
        runs,
        dim="run",
        data_vars="all",
        coords="minimal",
        compat="override",
        join="exact",
        combine_attrs="override",
    )
    return ds.assign_coords(run=("run", list(labels)))


__all__ = ["SimulatedRuns", "add_run_metrics", "concat_runs"]
