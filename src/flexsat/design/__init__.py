"""Design studies above the simulation engine: sweeps, Monte Carlo, optimisation (searches that
run the lower layers many times; nothing here imports the cases or scenarios)."""

from flexsat.design.slew_shaping import ShapedSlew, modal_cancelling_torque
from flexsat.design.slew_weights import (
    SlewEvaluation,
    SlewWeights,
    TuningResult,
    open_loop_deflection,
    slew_objective,
    slew_run_metrics,
    tune_slew_weights,
)

__all__ = ["ShapedSlew", "SlewEvaluation", "SlewWeights", "TuningResult",
           "modal_cancelling_torque", "open_loop_deflection", "slew_objective",
           "slew_run_metrics", "tune_slew_weights"]
