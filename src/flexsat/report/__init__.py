"""Reports: the files a run leaves behind, written whole or not at all.

:mod:`flexsat.report.publish` writes a report folder atomically (and checks it can be written
before any work); :mod:`flexsat.report.maneuver` and :mod:`flexsat.report.identification` write
the report of each scenario kind (JSON, netCDF, PNG plots, ``index.html``).

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
    "PLOTS": "maneuver",
    "STYLE": "maneuver",
    "format_metric": "maneuver",
    "metric_rows": "maneuver",
    "write_report": "maneuver",
    "MAX_FIGURES": "simulation",
    "write_simulation_report": "simulation",
    "GOAL_COLUMNS": "slew",
    "write_slew_report": "slew",
    "write_ppf_report": "ppf",
    "write_star_tracker_report": "star_tracker",
    "write_tether_report": "tether",
    "write_cmg_report": "cmg",
    "write_batch_report": "batch",
    "FIGURES": "identification",
    "write_identification_report": "identification",
}

__all__ = list(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
