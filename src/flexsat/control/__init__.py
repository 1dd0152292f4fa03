"""Control laws behind one interface (:class:`Controller`)."""

from flexsat.control.attitude_laws import GibbsLyapunovLaw, MRPLaw, QuaternionPD
from flexsat.control.base import Controller, SlewLaw
from flexsat.control.estimation import (
    RefinedEstimator,
    dkalman,
    kalman,
    refine_estimator,
    regulator_weighted_process_noise,
    truncate_gains,
)
from flexsat.control.force_decoupling import decoupled_input_map, moment_free_forces
from flexsat.control.frequency_shaped import (
    FrequencyShapedController,
    FrequencyShapedDesign,
    frequency_shaped_lqr,
)
from flexsat.control.generalized_plant import GeneralizedPlant, closed_loop, lqg_plant
from flexsat.control.h2_synthesis import H2Controller, H2Synthesis, h2syn
from flexsat.control.hac_lac import HacLacController, lac_plant, modal_damping
from flexsat.control.hinf_synthesis import (
    HinfController,
    HinfSynthesis,
    InfeasibleGamma,
    hinf_central,
    hinfsyn,
)
from flexsat.control.linear_form import LinearLaw, run_linear_law
from flexsat.control.lqg import LQGController
from flexsat.control.lqr import RiccatiSolution, dlqr, lqr
from flexsat.control.ltr import LTRController
from flexsat.control.lyapunov import LyapunovRegulator, LyapunovTracker, check_lyapunov_gains
from flexsat.control.mimo_lqg import AttitudeLQG
from flexsat.control.output_feedback import (
    FeedbackDesign,
    SymmetricOutputFeedback,
    design_minimum_sensitivity,
)
from flexsat.control.pd import PD
from flexsat.control.perturbation_feedback import (
    NominalTorque,
    PerturbationDesign,
    PerturbationFeedback,
    perturbation_design,
)
from flexsat.control.ppf import (
    PPFBank,
    PPFController,
    PPFModel,
    PPFProblem,
    PPFStability,
    initial_second_moment,
    ppf_closed_loop,
    ppf_compensator,
    ppf_cost_gradient,
    ppf_feedback,
    ppf_state_matrices,
    ppf_stiffness,
    ppf_stiffness_gradient,
    replicate_matrix,
)
from flexsat.control.ppf_optimization import (
    EigenvalueRestoration,
    PPFHomotopyResult,
    PPFHomotopyStep,
    ScipyPPFResult,
    optimize_ppf_gains,
    restore_eigenvalue_constraints,
    scipy_ppf_gains,
)
from flexsat.control.r_tuning import ModalLQR, RTuning, modal_lqr, tune_r
from flexsat.control.scheduled import ScheduledStateFeedback
from flexsat.control.state_space_compensator import StateSpaceCompensator
from flexsat.control.trajectory_linearization import TrajectoryLinearization, attitude_error

__all__ = [
    "AttitudeLQG",
    "Controller",
    "SlewLaw",
    "EigenvalueRestoration",
    "PPFHomotopyResult",
    "PPFHomotopyStep",
    "ScipyPPFResult",
    "optimize_ppf_gains",
    "restore_eigenvalue_constraints",
    "scipy_ppf_gains",
    "FeedbackDesign",
    "SymmetricOutputFeedback",
    "design_minimum_sensitivity",
    "FrequencyShapedController",
    "FrequencyShapedDesign",
    "GibbsLyapunovLaw",
    "LQGController",
    "LinearLaw",
    "LyapunovRegulator",
    "LyapunovTracker",
    "NominalTorque",
    "MRPLaw",
    "PD",
    "PPFBank",
    "PPFController",
    "PPFModel",
    "PPFProblem",
    "PPFStability",
    "PerturbationDesign",
    "PerturbationFeedback",
    "QuaternionPD",
    "RefinedEstimator",
    "RiccatiSolution",
    "ModalLQR",
    "RTuning",
    "modal_lqr",
    "tune_r",
    "ScheduledStateFeedback",
    "StateSpaceCompensator",
    "TrajectoryLinearization",
    "attitude_error",
    "check_lyapunov_gains",
    "decoupled_input_map",
    "dkalman",
    "dlqr",
    "frequency_shaped_lqr",
    "kalman",
    "lqr",
    "moment_free_forces",
    "initial_second_moment",
    "ppf_closed_loop",
    "ppf_compensator",
    "ppf_cost_gradient",
    "ppf_feedback",
    "ppf_state_matrices",
    "ppf_stiffness",
    "ppf_stiffness_gradient",
    "replicate_matrix",
    "perturbation_design",
    "refine_estimator",
    "regulator_weighted_process_noise",
    "run_linear_law",
    "truncate_gains",
    "GeneralizedPlant",
    "closed_loop",
    "lqg_plant",
    "H2Controller",
    "H2Synthesis",
    "h2syn",
    "HacLacController",
    "lac_plant",
    "modal_damping",
    "HinfController",
    "HinfSynthesis",
    "InfeasibleGamma",
    "hinf_central",
    "hinfsyn",
    "LTRController",
]
