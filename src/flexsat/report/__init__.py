"""Reports: the files a run leaves behind, written whole or not at all.

:mod:`flexsat.report.publish` writes a report folder atomically (and checks it can be written
before any work); :func:`flexsat.report.page.write_report` writes the report of a result of any
scenario kind (JSON, netCDF and one self-contained ``index.html`` that opens offline, its
figures inside it) through the result's protocol (:class:`~flexsat.report.page.ReportedResult`);
:mod:`~flexsat.report.interactive` draws the interactive figures, :mod:`~flexsat.report.display`
names the metrics, :mod:`~flexsat.report.provenance` dates and fingerprints the page and
:mod:`~flexsat.report.controller_summary` sums up the linear laws; the other modules describe
the figures and the page sections of one kind each.

The names below are imported from their modules on first use: the command line checks the
output folder before it loads matplotlib or xarray.
"""

from flexsat.lazy import lazy_exports

_EXPORTS = {
    "LOCK_TIMEOUT_S": "publish",
    "MANIFEST": "publish",
    "OutputError": "publish",
    "check_output_folder": "publish",
    "write_atomically": "publish",
    "STYLE": "page",
    "ReportedResult": "page",
    "ResultTable": "page",
    "format_metric": "page",
    "metric_rows": "page",
    "write_report": "page",
}

__all__ = list(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
