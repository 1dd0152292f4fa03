"""Design studies above the simulation engine: sweeps, Monte Carlo, optimisation (searches that
run the lower layers many times; nothing here imports the cases or scenarios).

The names below are imported from their modules on first use (the statistics load SALib, the
slew searches the simulation engine)."""

from flexsat.lazy import lazy_exports

_EXPORTS = {
    "ShapedSlew": "slew_shaping",
    "modal_cancelling_torque": "slew_shaping",
    "SlewEvaluation": "slew_weights",
    "SlewWeights": "slew_weights",
    "TuningResult": "slew_weights",
    "open_loop_deflection": "slew_weights",
    "slew_objective": "slew_weights",
    "slew_run_metrics": "slew_weights",
    "tune_slew_weights": "slew_weights",
    "DISTRIBUTIONS": "parameter_space",
    "GridAxis": "parameter_space",
    "GridSpace": "parameter_space",
    "LogNormal": "parameter_space",
    "Normal": "parameter_space",
    "ParameterSpace": "parameter_space",
    "SampleTable": "parameter_space",
    "SobolDesign": "parameter_space",
    "TruncatedNormal": "parameter_space",
    "Uniform": "parameter_space",
    "parameter_from_spec": "parameter_space",
    "require_si_unit": "parameter_space",
    "si_scalar": "parameter_space",
    "space_from_spec": "parameter_space",
    "DEFAULT_PERCENTILES": "monte_carlo_statistics",
    "INTERVAL_METHODS": "monte_carlo_statistics",
    "SAMPLE_METHODS": "monte_carlo_statistics",
    "Convergence": "monte_carlo_statistics",
    "MetricSummary": "monte_carlo_statistics",
    "ProbabilityEstimate": "monte_carlo_statistics",
    "Requirement": "monte_carlo_statistics",
    "SensitivityRanking": "monte_carlo_statistics",
    "SobolIndices": "monte_carlo_statistics",
    "checkpoints": "monte_carlo_statistics",
    "metric_summary": "monte_carlo_statistics",
    "monte_carlo_summary": "monte_carlo_statistics",
    "percentile_convergence": "monte_carlo_statistics",
    "percentile_interval": "monte_carlo_statistics",
    "probability_convergence": "monte_carlo_statistics",
    "probability_of_meeting": "monte_carlo_statistics",
    "proportion_interval": "monte_carlo_statistics",
    "requirement_from_spec": "monte_carlo_statistics",
    "sample_sensitivity": "monte_carlo_statistics",
    "sobol_indices": "monte_carlo_statistics",
    "maneuver_time_surface": "trade_surfaces",
    "residual_energy_surface": "trade_surfaces",
    "tracking_bound": "trade_surfaces",
    "tracking_bound_surface": "trade_surfaces",
}

__all__ = list(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
